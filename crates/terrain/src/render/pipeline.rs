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
    /// Layout of the thing's own bind group (group 1; group 0 is the frame's).
    pub layout: &'a wgpu::BindGroupLayout,
    /// Bytes from one vertex to the next in the single vertex buffer.
    pub vertex_stride: u64,
    /// The vertex attributes.
    pub attributes: &'a [wgpu::VertexAttribute],
    /// How vertices make triangles.
    pub topology: wgpu::PrimitiveTopology,
    /// Index format of an indexed strip (its restart index is the format's maximum).
    pub strip_index_format: Option<wgpu::IndexFormat>,
    /// Alpha blending (the water) rather than opaque drawing.
    pub blend: bool,
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
        if mirrored { &self.mirrored } else { &self.direct }
    }
}

/// Builds both pipelines of `spec`.
pub fn pipelines(context: &PassContext<'_>, spec: &PipelineSpec<'_>) -> PipelinePair {
    let device = context.device;
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some(spec.label),
        source: wgpu::ShaderSource::Wgsl(spec.source.into()),
    });
    let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some(spec.label),
        bind_group_layouts: &[Some(context.frame_layout), Some(spec.layout)],
        immediate_size: 0,
    });
    let vertex_layout = wgpu::VertexBufferLayout {
        array_stride: spec.vertex_stride,
        step_mode: wgpu::VertexStepMode::Vertex,
        attributes: spec.attributes,
    };
    let build = |front_face: wgpu::FrontFace, label: &str| {
        device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some(label),
            layout: Some(&layout),
            vertex: wgpu::VertexState {
                module: &module,
                entry_point: Some("vs_main"),
                compilation_options: wgpu::PipelineCompilationOptions::default(),
                buffers: &[Some(vertex_layout.clone())],
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
                    format: context.target_format,
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

/// What a pass needs from the renderer to build its resources.
pub struct PassContext<'a> {
    /// The device.
    pub device: &'a wgpu::Device,
    /// Its queue, for uploads.
    pub queue: &'a wgpu::Queue,
    /// Layout of the frame uniforms (group 0).
    pub frame_layout: &'a wgpu::BindGroupLayout,
    /// Format of the colour target.
    pub target_format: wgpu::TextureFormat,
}

/// A resource bound to a pass's own group (group 1).
pub enum Binding<'a> {
    /// A uniform buffer, seen by both stages.
    Uniform(&'a wgpu::Buffer),
    /// A filterable 2-D texture seen by the fragment stage.
    Texture(&'a wgpu::TextureView),
    /// A filterable 2-D texture array seen by the fragment stage.
    TextureArray(&'a wgpu::TextureView),
    /// A filtering sampler seen by the fragment stage.
    Sampler(&'a wgpu::Sampler),
}

/// The layout and the bind group of `bindings`, bound at 0, 1, 2... in order.
pub fn bind_group(
    device: &wgpu::Device,
    label: &str,
    bindings: &[Binding<'_>],
) -> (wgpu::BindGroupLayout, wgpu::BindGroup) {
    let layout_entries: Vec<wgpu::BindGroupLayoutEntry> = bindings
        .iter()
        .enumerate()
        .map(|(binding, resource)| {
            let (visibility, ty) = match resource {
                Binding::Uniform(_) => (
                    wgpu::ShaderStages::VERTEX_FRAGMENT,
                    wgpu::BindingType::Buffer {
                        ty: wgpu::BufferBindingType::Uniform,
                        has_dynamic_offset: false,
                        min_binding_size: None,
                    },
                ),
                Binding::Texture(_) | Binding::TextureArray(_) => (
                    wgpu::ShaderStages::FRAGMENT,
                    wgpu::BindingType::Texture {
                        sample_type: wgpu::TextureSampleType::Float { filterable: true },
                        view_dimension: if matches!(resource, Binding::TextureArray(_)) {
                            wgpu::TextureViewDimension::D2Array
                        } else {
                            wgpu::TextureViewDimension::D2
                        },
                        multisampled: false,
                    },
                ),
                Binding::Sampler(_) => (
                    wgpu::ShaderStages::FRAGMENT,
                    wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Filtering),
                ),
            };
            wgpu::BindGroupLayoutEntry { binding: binding as u32, visibility, ty, count: None }
        })
        .collect();
    let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some(label),
        entries: &layout_entries,
    });
    let entries: Vec<wgpu::BindGroupEntry<'_>> = bindings
        .iter()
        .enumerate()
        .map(|(binding, resource)| wgpu::BindGroupEntry {
            binding: binding as u32,
            resource: match resource {
                Binding::Uniform(buffer) => buffer.as_entire_binding(),
                Binding::Texture(view) | Binding::TextureArray(view) => {
                    wgpu::BindingResource::TextureView(view)
                }
                Binding::Sampler(sampler) => wgpu::BindingResource::Sampler(sampler),
            },
        })
        .collect();
    let group = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some(label),
        layout: &layout,
        entries: &entries,
    });
    (layout, group)
}
