//! Building the render pipelines: every drawn thing has a direct and a mirrored variant, which
//! differ only in the winding of front faces (a mirror image turns counter-clockwise triangles
//! clockwise).

use super::texture::DEPTH_FORMAT;

/// Concatenates the shared `frame.wgsl` prelude and a shader file's source.
macro_rules! shader_source {
    ($file:literal) => {
        concat!(include_str!("frame.wgsl"), "\n", include_str!($file))
    };
}
pub(crate) use shader_source;

/// What differs between the pipelines of the things drawn.
pub struct PipelineSpec<'a> {
    /// Debug label.
    pub label: &'a str,
    /// WGSL source with `vs_main` and `fs_main`.
    pub source: &'a str,
    /// Bind group layouts: group 0 is the frame's, group 1 the thing's own.
    pub bind_group_layouts: &'a [&'a wgpu::BindGroupLayout],
    /// The single vertex buffer's layout.
    pub vertex_layout: wgpu::VertexBufferLayout<'a>,
    /// How vertices make triangles.
    pub topology: wgpu::PrimitiveTopology,
    /// Index format of an indexed strip (its restart index is the format's maximum).
    pub strip_index_format: Option<wgpu::IndexFormat>,
    /// Alpha blending (the water) rather than opaque drawing.
    pub blend: bool,
    /// Format of the colour target.
    pub target_format: wgpu::TextureFormat,
}

/// The direct and mirrored pipelines of one thing.
#[derive(Debug)]
pub struct PipelinePair {
    /// Draws the world as it is.
    pub direct: wgpu::RenderPipeline,
    /// Draws its mirror image in y = 0.
    pub mirrored: wgpu::RenderPipeline,
}

impl PipelinePair {
    /// The pipeline for the direct (`mirrored = false`) or mirrored pass.
    pub fn get(&self, mirrored: bool) -> &wgpu::RenderPipeline {
        if mirrored {
            &self.mirrored
        } else {
            &self.direct
        }
    }
}

/// Builds both pipelines of `spec`.
pub fn pipelines(device: &wgpu::Device, spec: &PipelineSpec<'_>) -> PipelinePair {
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some(spec.label),
        source: wgpu::ShaderSource::Wgsl(spec.source.into()),
    });
    let layouts: Vec<Option<&wgpu::BindGroupLayout>> = spec
        .bind_group_layouts
        .iter()
        .map(|&layout| Some(layout))
        .collect();
    let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some(spec.label),
        bind_group_layouts: &layouts,
        immediate_size: 0,
    });
    let build = |front_face: wgpu::FrontFace, label: &str| {
        device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some(label),
            layout: Some(&layout),
            vertex: wgpu::VertexState {
                module: &module,
                entry_point: Some("vs_main"),
                compilation_options: wgpu::PipelineCompilationOptions::default(),
                buffers: &[Some(spec.vertex_layout.clone())],
            },
            primitive: wgpu::PrimitiveState {
                topology: spec.topology,
                strip_index_format: spec.strip_index_format,
                front_face,
                cull_mode: Some(wgpu::Face::Back),
                ..Default::default()
            },
            depth_stencil: Some(wgpu::DepthStencilState {
                format: DEPTH_FORMAT,
                // Translucent water is drawn last, tested against but not hiding what is behind.
                depth_write_enabled: Some(!spec.blend),
                depth_compare: Some(wgpu::CompareFunction::Less),
                stencil: wgpu::StencilState::default(),
                bias: wgpu::DepthBiasState::default(),
            }),
            multisample: wgpu::MultisampleState::default(),
            fragment: Some(wgpu::FragmentState {
                module: &module,
                entry_point: Some("fs_main"),
                compilation_options: wgpu::PipelineCompilationOptions::default(),
                targets: &[Some(wgpu::ColorTargetState {
                    format: spec.target_format,
                    blend: Some(if spec.blend {
                        wgpu::BlendState::ALPHA_BLENDING
                    } else {
                        wgpu::BlendState::REPLACE
                    }),
                    write_mask: wgpu::ColorWrites::ALL,
                })],
            }),
            multiview_mask: None,
            cache: None,
        })
    };
    PipelinePair {
        direct: build(wgpu::FrontFace::Ccw, spec.label),
        mirrored: build(wgpu::FrontFace::Cw, &format!("{} (mirrored)", spec.label)),
    }
}

/// A bind group layout entry for a uniform buffer at `binding`, seen by both stages.
pub fn uniform_entry(binding: u32) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::VERTEX_FRAGMENT,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Uniform,
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    }
}

/// A bind group layout entry for a filterable float texture (2-D, or a 2-D array) at `binding`.
pub fn texture_entry(binding: u32, array: bool) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::FRAGMENT,
        ty: wgpu::BindingType::Texture {
            sample_type: wgpu::TextureSampleType::Float { filterable: true },
            view_dimension: if array {
                wgpu::TextureViewDimension::D2Array
            } else {
                wgpu::TextureViewDimension::D2
            },
            multisampled: false,
        },
        count: None,
    }
}

/// A bind group layout entry for a filtering sampler at `binding`.
pub fn sampler_entry(binding: u32) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::FRAGMENT,
        ty: wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Filtering),
        count: None,
    }
}
