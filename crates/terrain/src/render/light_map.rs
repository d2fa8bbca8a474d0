//! The light map: the sun's light on the ground (with the land's shadows) and how much of the sky
//! it faces, per heightmap sample, with a full mip chain (`bake.wgsl`). It is drawn again only
//! when the sun moves or shadows are switched, and then every pixel of land, its reflection and
//! the sea floor read their light from one texel.

use bytemuck::{Pod, Zeroable};
use glam::Vec3;
use wgpu::util::DeviceExt;

use super::grid::GridTerrain;
use super::pipeline::{Binding, PassContext, PipelineSpec, bind_group, pipeline, shader_source};

/// The light map's program: the WGSL source its pipeline is built from.
pub(super) const SHADER: &str = shader_source!("lighting.wgsl", "heights.wgsl", "bake.wgsl");

/// Format of the light map: the sun's light (r) and the sky's (g).
pub const LIGHT_MAP_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rg8Unorm;

/// Largest side of the light map, in texels: maps up to 4097 samples a side get a texel per
/// sample; larger ones a texel per 2 x 2 (or more) samples, whose light is computed from the
/// full-resolution heights across them (8193 x 8193 samples: 45 MB instead of 179 MB).
pub const LIGHT_MAP_MAX_SIDE: u32 = 4097;

/// The WGSL struct `Bake`.
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable)]
struct BakeUniforms {
    span: u32,
    shadows: u32,
    padding: [u32; 2],
}

/// The light map and what draws it.
#[derive(Debug)]
pub struct LightMap {
    view: wgpu::TextureView,
    /// Heightmap samples a texel of level 0 spans.
    span: u32,
    levels: Vec<Level>,
    pipeline: wgpu::RenderPipeline,
    /// The sun and shadow switch the map was drawn for.
    drawn_for: Option<(Vec3, bool)>,
    bytes: u64,
}

/// One mip level: its view to draw into, its uniforms, and its group 1 (the grid's uniforms and
/// heights, then these uniforms).
#[derive(Debug)]
struct Level {
    view: wgpu::TextureView,
    uniforms: wgpu::Buffer,
    group: wgpu::BindGroup,
}

impl LightMap {
    /// A light map for `grid`, drawn with the lighting of `lighting_layout` (group 2).
    pub fn new(
        context: &PassContext<'_>,
        grid: &GridTerrain,
        lighting_layout: &wgpu::BindGroupLayout,
    ) -> Self {
        let device = context.device;
        let (samples_x, samples_z) = grid.samples();
        // Samples a texel of level 0 spans.
        let mut span = 1u32;
        while samples_x.max(samples_z).div_ceil(span) > LIGHT_MAP_MAX_SIDE {
            span *= 2;
        }
        let (columns, rows) = (samples_x.div_ceil(span), samples_z.div_ceil(span));
        let mip_level_count = columns.max(rows).ilog2() + 1;
        let texture = device.create_texture(&wgpu::TextureDescriptor {
            label: Some("light map"),
            size: wgpu::Extent3d { width: columns, height: rows, depth_or_array_layers: 1 },
            mip_level_count,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: LIGHT_MAP_FORMAT,
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING,
            view_formats: &[],
        });
        let mut bytes = 0;
        let mut layout = None;
        let levels = (0..mip_level_count)
            .map(|level| {
                let (width, height) = ((columns >> level).max(1), (rows >> level).max(1));
                bytes += u64::from(width) * u64::from(height) * 2;
                let uniforms = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                    label: Some("light map level"),
                    contents: bytemuck::bytes_of(&BakeUniforms {
                        span: span << level,
                        shadows: 0,
                        padding: [0; 2],
                    }),
                    usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                });
                let (level_layout, group) = bind_group(
                    device,
                    "light map level",
                    &[
                        Binding::Uniform(grid.uniforms()),
                        Binding::UintTexture(grid.heights()),
                        Binding::Uniform(&uniforms),
                    ],
                );
                layout.get_or_insert(level_layout);
                let view = texture.create_view(&wgpu::TextureViewDescriptor {
                    base_mip_level: level,
                    mip_level_count: Some(1),
                    ..Default::default()
                });
                Level { view, uniforms, group }
            })
            .collect();
        let Some(level_layout) = layout else { unreachable!("a texture has at least one mip level") };
        let layouts = [&level_layout, lighting_layout];
        let bake_context = PassContext { target_format: LIGHT_MAP_FORMAT, ..*context };
        let spec = PipelineSpec {
            vertex_entry: "vs_bake",
            fragment_entry: Some("fs_bake"),
            depth: false,
            ..PipelineSpec::new("light map", SHADER, &layouts, &[])
        };
        Self {
            view: texture.create_view(&wgpu::TextureViewDescriptor::default()),
            span,
            levels,
            pipeline: pipeline(&bake_context, &spec, false),
            drawn_for: None,
            bytes,
        }
    }

    /// The light map, to sample.
    pub fn view(&self) -> &wgpu::TextureView {
        &self.view
    }

    /// GPU memory, in bytes.
    pub fn gpu_bytes(&self) -> u64 {
        self.bytes
    }

    /// Whether the map must be drawn again for `sun` with `shadows`.
    pub fn stale(&self, sun: Vec3, shadows: bool) -> bool {
        self.drawn_for != Some((sun, shadows))
    }

    /// Notes that the map is being drawn for `sun` with `shadows` and uploads the switch.
    pub fn prepare(&mut self, queue: &wgpu::Queue, sun: Vec3, shadows: bool) {
        for (level, entry) in self.levels.iter().enumerate() {
            let uniforms =
                BakeUniforms { span: self.span << level, shadows: u32::from(shadows), padding: [0; 2] };
            queue.write_buffer(&entry.uniforms, 0, bytemuck::bytes_of(&uniforms));
        }
        self.drawn_for = Some((sun, shadows));
    }

    /// Draws every level (after the shadow map), with any `frame` uniforms (unused) and the
    /// lighting's `lighting_group`.
    pub fn draw(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        frame: &wgpu::BindGroup,
        lighting_group: &wgpu::BindGroup,
    ) {
        for level in &self.levels {
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("light map"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: &level.view,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color::BLACK),
                        store: wgpu::StoreOp::Store,
                    },
                })],
                depth_stencil_attachment: None,
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            pass.set_pipeline(&self.pipeline);
            pass.set_bind_group(0, frame, &[]);
            pass.set_bind_group(1, &level.group, &[]);
            pass.set_bind_group(2, lighting_group, &[]);
            pass.draw(0..3, 0..1);
        }
    }
}
