//! Building the render pipelines: every drawn thing has a direct and a mirrored variant, which
//! differ only in the winding of front faces (a mirror image turns counter-clockwise triangles
//! clockwise).

use super::texture::DEPTH_FORMAT;

/// Concatenates the shared `frame.wgsl` prelude and shader files' sources.
macro_rules! shader_source {
    ($($file:literal),+) => {
        concat!(include_str!("frame.wgsl") $(, "\n", include_str!($file))+)
    };
}
pub(crate) use shader_source;

/// What differs between the pipelines of the things drawn.
pub struct PipelineSpec<'a> {
    /// Debug label.
    pub label: &'a str,
    /// WGSL source.
    pub source: &'a str,
    /// Layouts of the thing's own bind groups (group 1, 2...; group 0 is the frame's).
    pub layouts: &'a [&'a wgpu::BindGroupLayout],
    /// The vertex stage's entry point.
    pub vertex_entry: &'a str,
    /// The fragment stage's entry point (`None`: depth only, no colour target).
    pub fragment_entry: Option<&'a str>,
    /// The vertex buffers.
    pub buffers: &'a [wgpu::VertexBufferLayout<'a>],
    /// How vertices make triangles.
    pub topology: wgpu::PrimitiveTopology,
    /// Index format of an indexed strip (its restart index is the format's maximum).
    pub strip_index_format: Option<wgpu::IndexFormat>,
    /// Alpha blending (the course's water) rather than opaque drawing.
    pub blend: bool,
    /// Filled triangles, or their edges (wireframe).
    pub polygon_mode: wgpu::PolygonMode,
    /// Depth bias (the shadow map's).
    pub depth_bias: wgpu::DepthBiasState,
    /// Whether the pass has a depth buffer to test against.
    pub depth: bool,
    /// Values of the shader's `override` constants, by name (booleans as 0 or 1).
    pub constants: &'a [(&'a str, f64)],
}

impl<'a> PipelineSpec<'a> {
    /// An opaque triangle list drawn with `vs_main` and `fs_main`, filled.
    pub fn new(
        label: &'a str,
        source: &'a str,
        layouts: &'a [&'a wgpu::BindGroupLayout],
        buffers: &'a [wgpu::VertexBufferLayout<'a>],
    ) -> Self {
        Self {
            label,
            source,
            layouts,
            vertex_entry: "vs_main",
            fragment_entry: Some("fs_main"),
            buffers,
            topology: wgpu::PrimitiveTopology::TriangleList,
            strip_index_format: None,
            blend: false,
            polygon_mode: wgpu::PolygonMode::Fill,
            depth_bias: wgpu::DepthBiasState::default(),
            depth: true,
            constants: &[],
        }
    }
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
    let module = context.device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some(spec.label),
        source: wgpu::ShaderSource::Wgsl(spec.source.into()),
    });
    PipelinePair {
        direct: build(context, spec, &module, wgpu::FrontFace::Ccw, spec.label),
        mirrored: build(context, spec, &module, wgpu::FrontFace::Cw, &format!("{} (mirrored)", spec.label)),
    }
}

/// Builds one pipeline of `spec`: for the world as it is, or (`mirrored`) for its mirror image.
pub fn pipeline(context: &PassContext<'_>, spec: &PipelineSpec<'_>, mirrored: bool) -> wgpu::RenderPipeline {
    let module = context.device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some(spec.label),
        source: wgpu::ShaderSource::Wgsl(spec.source.into()),
    });
    let front_face = if mirrored { wgpu::FrontFace::Cw } else { wgpu::FrontFace::Ccw };
    build(context, spec, &module, front_face, spec.label)
}

fn build(
    context: &PassContext<'_>,
    spec: &PipelineSpec<'_>,
    module: &wgpu::ShaderModule,
    front_face: wgpu::FrontFace,
    label: &str,
) -> wgpu::RenderPipeline {
    let device = context.device;
    let groups: Vec<Option<&wgpu::BindGroupLayout>> =
        std::iter::once(context.frame_layout).chain(spec.layouts.iter().copied()).map(Some).collect();
    let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some(spec.label),
        bind_group_layouts: &groups,
        immediate_size: 0,
    });
    let buffers: Vec<Option<wgpu::VertexBufferLayout<'_>>> = spec.buffers.iter().cloned().map(Some).collect();
    let targets = [Some(wgpu::ColorTargetState {
        format: context.target_format,
        blend: Some(if spec.blend { wgpu::BlendState::ALPHA_BLENDING } else { wgpu::BlendState::REPLACE }),
        write_mask: wgpu::ColorWrites::ALL,
    })];
    device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some(label),
        layout: Some(&layout),
        vertex: wgpu::VertexState {
            module,
            entry_point: Some(spec.vertex_entry),
            compilation_options: wgpu::PipelineCompilationOptions {
                constants: spec.constants,
                ..Default::default()
            },
            buffers: &buffers,
        },
        primitive: wgpu::PrimitiveState {
            topology: spec.topology,
            strip_index_format: spec.strip_index_format,
            front_face,
            cull_mode: Some(wgpu::Face::Back),
            polygon_mode: spec.polygon_mode,
            ..Default::default()
        },
        depth_stencil: spec.depth.then_some(wgpu::DepthStencilState {
            format: DEPTH_FORMAT,
            // Translucent water is drawn last, tested against but not hiding what is behind.
            depth_write_enabled: Some(!spec.blend),
            depth_compare: Some(wgpu::CompareFunction::Less),
            stencil: wgpu::StencilState::default(),
            bias: spec.depth_bias,
        }),
        multisample: wgpu::MultisampleState::default(),
        fragment: spec.fragment_entry.map(|entry| wgpu::FragmentState {
            module,
            entry_point: Some(entry),
            compilation_options: wgpu::PipelineCompilationOptions {
                constants: spec.constants,
                ..Default::default()
            },
            targets: &targets,
        }),
        multiview_mask: None,
        cache: None,
    })
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
    /// A filterable 2-D texture seen by both stages.
    Texture(&'a wgpu::TextureView),
    /// A filterable 2-D texture array seen by both stages.
    TextureArray(&'a wgpu::TextureView),
    /// A filtering sampler seen by both stages.
    Sampler(&'a wgpu::Sampler),
    /// An unsigned-integer 2-D texture (the heights) seen by both stages.
    UintTexture(&'a wgpu::TextureView),
    /// A depth texture (the shadow map) seen by the fragment stage.
    DepthTexture(&'a wgpu::TextureView),
    /// A comparison sampler seen by the fragment stage.
    ComparisonSampler(&'a wgpu::Sampler),
}

/// The bind group of `bindings` (bound at 0, 1, 2... in order) with an existing `layout` made for
/// bindings of the same kinds.
pub fn bind_group_for(
    device: &wgpu::Device,
    label: &str,
    layout: &wgpu::BindGroupLayout,
    bindings: &[Binding<'_>],
) -> wgpu::BindGroup {
    let entries: Vec<wgpu::BindGroupEntry<'_>> = bindings
        .iter()
        .enumerate()
        .map(|(binding, resource)| wgpu::BindGroupEntry {
            binding: binding as u32,
            resource: resource.resource(),
        })
        .collect();
    device.create_bind_group(&wgpu::BindGroupDescriptor { label: Some(label), layout, entries: &entries })
}

impl Binding<'_> {
    fn resource(&self) -> wgpu::BindingResource<'_> {
        match self {
            Binding::Uniform(buffer) => buffer.as_entire_binding(),
            Binding::Texture(view)
            | Binding::TextureArray(view)
            | Binding::UintTexture(view)
            | Binding::DepthTexture(view) => wgpu::BindingResource::TextureView(view),
            Binding::Sampler(sampler) | Binding::ComparisonSampler(sampler) => {
                wgpu::BindingResource::Sampler(sampler)
            }
        }
    }
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
                    wgpu::ShaderStages::VERTEX_FRAGMENT,
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
                    wgpu::ShaderStages::VERTEX_FRAGMENT,
                    wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Filtering),
                ),
                Binding::UintTexture(_) => (
                    wgpu::ShaderStages::VERTEX_FRAGMENT,
                    wgpu::BindingType::Texture {
                        sample_type: wgpu::TextureSampleType::Uint,
                        view_dimension: wgpu::TextureViewDimension::D2,
                        multisampled: false,
                    },
                ),
                Binding::DepthTexture(_) => (
                    wgpu::ShaderStages::FRAGMENT,
                    wgpu::BindingType::Texture {
                        sample_type: wgpu::TextureSampleType::Depth,
                        view_dimension: wgpu::TextureViewDimension::D2,
                        multisampled: false,
                    },
                ),
                Binding::ComparisonSampler(_) => (
                    wgpu::ShaderStages::FRAGMENT,
                    wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Comparison),
                ),
            };
            wgpu::BindGroupLayoutEntry { binding: binding as u32, visibility, ty, count: None }
        })
        .collect();
    let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some(label),
        entries: &layout_entries,
    });
    let group = bind_group_for(device, label, &layout, bindings);
    (layout, group)
}
