//! The modern look's water: one plane at y = 0 over the sky box's floor, shaded by `sea.wgsl`
//! (reflection, refraction of the sea floor, Fresnel, glint, foam, fog).

use wgpu::util::DeviceExt;

use super::RenderError;
use super::grid::GridTerrain;
use super::pipeline::{
    Binding, PassContext, PipelineSpec, bind_group, bind_group_for, pipeline, shader_source,
};
use super::texture::{sampler, upload};
use crate::config::SceneConfig;
use crate::world::procedural::{WAVE_MAP_SIZE, wave_map};

/// The modern look's water: the WGSL source its pipeline is built from.
pub(super) const SHADER: &str = shader_source!("lighting.wgsl", "heights.wgsl", "sea.wgsl");

/// Seeds of the two wave maps (the same for every world).
const WAVE_SEEDS: [u32; 2] = [11, 12];

/// Noise features across each wave map: broad swell, then finer ripples.
const WAVE_CELLS: [f64; 2] = [3.0, 5.0];

/// The water's GPU resources.
#[derive(Debug)]
pub struct SeaPass {
    pipeline: wgpu::RenderPipeline,
    layout: wgpu::BindGroupLayout,
    vertices: wgpu::Buffer,
    indices: wgpu::Buffer,
    index_count: u32,
    wave_maps: [wgpu::TextureView; 2],
    /// A 1x1 texture bound when there is no reflection.
    no_reflection: wgpu::TextureView,
    bind_group: wgpu::BindGroup,
    lighting: wgpu::BindGroup,
    bytes: u64,
}

impl SeaPass {
    /// Builds the water of `config` over `grid`'s sea floor (coloured by `colour`, lit by
    /// `light`), lit by `lighting` (group 2 and its layout).
    pub fn new(
        context: &PassContext<'_>,
        config: &SceneConfig,
        grid: &GridTerrain,
        (colour, light): (&wgpu::TextureView, &wgpu::TextureView),
        lighting: (&wgpu::BindGroupLayout, &wgpu::BindGroup),
    ) -> Result<Self, RenderError> {
        let device = context.device;
        let upload_map = |i: usize| -> Result<wgpu::TextureView, RenderError> {
            let map = wave_map(WAVE_SEEDS[i], WAVE_MAP_SIZE, WAVE_CELLS[i]);
            let texture = upload(device, context.queue, "wave map", &[&map])?;
            Ok(texture.create_view(&wgpu::TextureViewDescriptor::default()))
        };
        let wave_maps = [upload_map(0)?, upload_map(1)?];
        let blank = image::RgbaImage::from_pixel(1, 1, image::Rgba([0, 0, 0, 255]));
        let no_reflection = upload(device, context.queue, "no reflection", &[&blank])?
            .create_view(&wgpu::TextureViewDescriptor::default());
        let (layout, bind_group) = bind_group(
            device,
            "sea",
            &bindings(
                grid,
                &wave_maps,
                (colour, light),
                &no_reflection,
                &sampler(device, true),
                &sampler(device, false),
            ),
        );
        let attributes = wgpu::vertex_attr_array![0 => Float32x3];
        let buffers = [wgpu::VertexBufferLayout {
            array_stride: size_of::<[f32; 3]>() as u64,
            step_mode: wgpu::VertexStepMode::Vertex,
            attributes: &attributes,
        }];
        let layouts = [&layout, lighting.0];
        let spec = PipelineSpec::new("sea", SHADER, &layouts, &buffers);
        let (positions, indices) = sea_mesh(config);
        Ok(Self {
            pipeline: pipeline(context, &spec, false),
            layout,
            vertices: device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("sea vertices"),
                contents: bytemuck::cast_slice(&positions),
                usage: wgpu::BufferUsages::VERTEX,
            }),
            indices: device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("sea indices"),
                contents: bytemuck::cast_slice(&indices),
                usage: wgpu::BufferUsages::INDEX,
            }),
            index_count: indices.len() as u32,
            wave_maps,
            no_reflection,
            bind_group,
            lighting: lighting.1.clone(),
            bytes: 2 * u64::from(WAVE_MAP_SIZE * WAVE_MAP_SIZE) * 4 * 4 / 3,
        })
    }

    /// Binds the `reflection` (`None`: no reflection of the land) with the grid's heights and
    /// the sea floor's `colour` and `light` maps.
    pub fn bind(
        &mut self,
        device: &wgpu::Device,
        grid: &GridTerrain,
        (colour, light): (&wgpu::TextureView, &wgpu::TextureView),
        reflection: Option<&wgpu::TextureView>,
    ) {
        let reflection = reflection.unwrap_or(&self.no_reflection);
        let (wrap, clamp) = (sampler(device, true), sampler(device, false));
        let entries = bindings(grid, &self.wave_maps, (colour, light), reflection, &wrap, &clamp);
        self.bind_group = bind_group_for(device, "sea", &self.layout, &entries);
    }

    /// GPU memory of the wave maps, in bytes.
    pub fn gpu_bytes(&self) -> u64 {
        self.bytes
    }

    /// Draws the water in one draw call.
    pub fn draw(&self, pass: &mut wgpu::RenderPass<'_>, frame: &wgpu::BindGroup) {
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, frame, &[]);
        pass.set_bind_group(1, &self.bind_group, &[]);
        pass.set_bind_group(2, &self.lighting, &[]);
        pass.set_vertex_buffer(0, self.vertices.slice(..));
        pass.set_index_buffer(self.indices.slice(..), wgpu::IndexFormat::Uint16);
        pass.draw_indexed(0..self.index_count, 0, 0..1);
    }
}

/// Cells of the water's grid along each side: fine enough for its per-vertex fog and horizon
/// colour (the cells near the camera, where they are largest on screen, have no fog).
const SEA_CELLS: u16 = 48;

/// How far the water reaches beyond the sky box's walls, in world units: a skirt of one cell
/// around the grid, hidden behind the walls. The water's edge meets each wall's bottom edge in
/// T-junctions (many vertices against one edge), where rounding can leave pixels that neither
/// covers, which showed the black the frame is cleared to; beyond the walls, the skirt fills
/// them (issue 31). Well within the far plane.
const SKIRT: f32 = 20.0;

/// The water plane over the sky box's floor as a grid of `SEA_CELLS` x `SEA_CELLS` cells, with a
/// skirt of [`SKIRT`] units beyond the walls all around, counter-clockwise seen from above. The
/// grid's own vertices are where they would be without the skirt.
fn sea_mesh(config: &SceneConfig) -> (Vec<[f32; 3]>, Vec<u16>) {
    let (hx, hz) = (config.sky_box_size.x / 2.0, config.sky_box_size.z / 2.0);
    let n = SEA_CELLS;
    // The lines of the grid along one side: the skirt's, then the box's, then the skirt's.
    let lines = |half: f32| -> Vec<f32> {
        let inside = (0..=n).map(|j| -half + 2.0 * half * (f32::from(j) / f32::from(n)));
        std::iter::once(-half - SKIRT).chain(inside).chain(std::iter::once(half + SKIRT)).collect()
    };
    let (xs, zs) = (lines(hx), lines(hz));
    let m = n + 2;
    let mut positions = Vec::with_capacity(usize::from((m + 1) * (m + 1)));
    for &z in &zs {
        for &x in &xs {
            positions.push([x, 0.0, z]);
        }
    }
    let at = |i: u16, j: u16| i * (m + 1) + j;
    let mut indices = Vec::with_capacity(usize::from(m * m) * 6);
    for i in 0..m {
        for j in 0..m {
            let (a, b, c, d) = (at(i, j), at(i + 1, j), at(i, j + 1), at(i + 1, j + 1));
            indices.extend([a, b, c, c, b, d]);
        }
    }
    (positions, indices)
}

/// The water's group 1: the grid's uniforms and heights, the sea floor's colour map, the wave
/// maps, the reflection, the samplers and the light map (as `sea.wgsl` binds them).
fn bindings<'a>(
    grid: &'a GridTerrain,
    wave_maps: &'a [wgpu::TextureView; 2],
    (colour, light): (&'a wgpu::TextureView, &'a wgpu::TextureView),
    reflection: &'a wgpu::TextureView,
    wrap: &'a wgpu::Sampler,
    clamp: &'a wgpu::Sampler,
) -> [Binding<'a>; 9] {
    [
        Binding::Uniform(grid.uniforms()),
        Binding::UintTexture(grid.heights()),
        Binding::Texture(colour),
        Binding::Texture(&wave_maps[0]),
        Binding::Texture(&wave_maps[1]),
        Binding::Texture(reflection),
        Binding::Sampler(wrap),
        Binding::Sampler(clamp),
        Binding::Texture(light),
    ]
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::*;

    #[test]
    fn the_sea_covers_the_floor_facing_up() {
        let config = SceneConfig::default();
        let (positions, indices) = sea_mesh(&config);
        let p = |i: u16| Vec3::from_array(positions[usize::from(i)]);
        let mut area = 0.0;
        for t in indices.chunks(3) {
            let normal = (p(t[1]) - p(t[0])).cross(p(t[2]) - p(t[0]));
            assert!(normal.y > 0.0);
            area += normal.y / 2.0;
        }
        let skirted = (200.0 + 2.0 * SKIRT) * (280.0 + 2.0 * SKIRT);
        assert!((area - skirted).abs() < 56.0, "{area}");
    }

    /// Issue 31, defect 10: the water reaches beyond the walls, and its vertices inside the box
    /// are where the plain grid puts them (the picture inside the box does not move).
    #[test]
    fn the_sea_reaches_beyond_the_walls_with_its_grid_in_place() {
        let config = SceneConfig::default();
        let (positions, _) = sea_mesh(&config);
        let (hx, hz) = (config.sky_box_size.x / 2.0, config.sky_box_size.z / 2.0);
        let max_x = positions.iter().map(|p| p[0]).fold(f32::MIN, f32::max);
        let max_z = positions.iter().map(|p| p[2]).fold(f32::MIN, f32::max);
        assert!(max_x > hx && max_z > hz);
        // From any corner of the box, the far corner of the skirt is within the far plane.
        assert!(glam::Vec2::new(max_x + hx, max_z + hz).length() < config.far);
        let n = SEA_CELLS;
        for i in 0..=n {
            for j in 0..=n {
                let (u, v) = (f32::from(j) / f32::from(n), f32::from(i) / f32::from(n));
                let plain = [-hx + 2.0 * hx * u, 0.0, -hz + 2.0 * hz * v];
                assert!(positions.contains(&plain), "{plain:?}");
            }
        }
    }
}
