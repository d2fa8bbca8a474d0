//! The course's look: the sky box and its mirror image, the land and its mirror image, and the
//! translucent water drifting over them. Maps up to [`MESH_MAX_SIDE`] samples a side draw their
//! land as the static mesh (today's picture, bit for bit); larger ones as the GPU grid, with the
//! same shading.

use super::draw_path::{DrawSupport, LandDrawPath};
use super::grid::{GridPass, GridTerrain, upload_view};
use super::land::LandPass;
use super::pipeline::{PassContext, PipelinePair, PipelineSpec, pipelines, shader_source};
use super::sky::{SkyFaces, SkyPass};
use super::water::WaterPass;
use super::{DrawBudget, RenderError, Renderer};
use crate::config::SceneConfig;
use crate::world::World;

/// The course look's land on maps too large for its mesh (the grid): the WGSL source its
/// pipeline is built from.
pub(super) const GRID_SHADER: &str = shader_source!("heights.wgsl", "grid.wgsl", "grid_course.wgsl");

/// The course look's draws, in the order a frame makes them.
pub(super) const DRAWS: [&str; 5] = ["land", "mirrored land", "sky", "mirrored sky", "water"];

/// Largest heightmap side drawn as the static mesh in the course's look. Its memory grows with
/// the map (about 40 bytes a sample); larger maps use the grid, whose picture differs from the
/// mesh's by the rounding of its 16-bit heights and its levels of detail.
pub const MESH_MAX_SIDE: u32 = 2049;

/// The course look's GPU resources.
#[derive(Debug)]
pub struct CourseLook {
    sky: SkyPass,
    water: WaterPass,
    land: CourseLand,
    /// GPU memory of the static mesh and of the look's textures, in bytes.
    gpu_bytes: (u64, u64),
}

/// How the course look draws its land.
#[derive(Debug)]
enum CourseLand {
    /// The static mesh, cut at the waterline.
    Mesh(Box<LandPass>),
    /// The GPU grid (its resources are the renderer's), with these pipelines and group.
    Grid {
        pipelines: PipelinePair,
        wireframe: Option<PipelinePair>,
        layout: wgpu::BindGroupLayout,
        group: wgpu::BindGroup,
    },
}

impl CourseLook {
    /// Uploads what the course look needs of `world`; `grid` is the renderer's grid when the map
    /// is larger than [`MESH_MAX_SIDE`], else the mesh is drawn by `draws` (what the GPU offers,
    /// and the path asked for).
    pub fn new(
        context: &PassContext<'_>,
        world: &World,
        config: &SceneConfig,
        draws: (DrawSupport, LandDrawPath),
        grid: Option<&GridTerrain>,
    ) -> Result<Self, RenderError> {
        let faces = SkyFaces::new(context, &world.sky)?;
        let sky = SkyPass::new(context, &faces, config);
        let water = WaterPass::new(context, &world.water, config)?;
        let mut gpu_bytes = (0, faces.bytes + world.water.as_raw().len() as u64 * 4 / 3);
        let land = match grid {
            None => {
                let land = LandPass::new(context, world, config, draws.0, draws.1)?;
                gpu_bytes = (land.gpu_bytes().0, gpu_bytes.1 + land.gpu_bytes().1);
                CourseLand::Mesh(Box::new(land))
            }
            Some(grid) => {
                let colour = upload_view(context, "colour map", &world.colour_map)?;
                let detail = upload_view(context, "detail map", &world.detail_map)?;
                gpu_bytes.1 +=
                    (world.colour_map.as_raw().len() + world.detail_map.as_raw().len()) as u64 * 4 / 3;
                // The course's shading has no light map: the detail map stands in for it.
                let (layout, group) =
                    grid.land_group(context.device, "land (course)", &colour, &detail, &detail);
                let pipelines = grid_pipelines(context, &layout, wgpu::PolygonMode::Fill);
                CourseLand::Grid { pipelines, wireframe: None, layout, group }
            }
        };
        Ok(Self { sky, water, land, gpu_bytes })
    }

    /// GPU memory of the look's own resources (not the shared grid), in bytes: the static mesh
    /// (0 with the grid) and the textures.
    pub fn gpu_bytes(&self) -> (u64, u64) {
        self.gpu_bytes
    }

    /// Draws the land's edges (`on`) or its faces, where the GPU can.
    pub fn set_wireframe(&mut self, context: &PassContext<'_>, on: bool) {
        match &mut self.land {
            CourseLand::Mesh(land) => land.set_wireframe(context, on),
            CourseLand::Grid { wireframe, layout, .. } => {
                let able = context.device.features().contains(wgpu::Features::POLYGON_MODE_LINE);
                if on && able && wireframe.is_none() {
                    *wireframe = Some(grid_pipelines(context, layout, wgpu::PolygonMode::Line));
                }
                if !on {
                    *wireframe = None;
                }
            }
        }
    }

    /// The mesh's land, to choose its chunks.
    pub fn mesh(&mut self) -> Option<&mut LandPass> {
        match &mut self.land {
            CourseLand::Mesh(land) => Some(land),
            CourseLand::Grid { .. } => None,
        }
    }
}

/// The course shading of the grid, direct and mirrored.
fn grid_pipelines(
    context: &PassContext<'_>,
    layout: &wgpu::BindGroupLayout,
    polygon_mode: wgpu::PolygonMode,
) -> PipelinePair {
    let buffers = GridTerrain::buffer_layouts();
    let layouts = [layout];
    pipelines(
        context,
        &PipelineSpec {
            polygon_mode,
            ..PipelineSpec::new("land (course, grid)", GRID_SHADER, &layouts, &buffers)
        },
    )
}

impl Renderer {
    /// Draws the course's look into `target`: the land and its mirror image first (nearest first,
    /// so the depth test skips shading what they hide), then the sky and its mirror image, then
    /// the water blended over all. Opaque, depth-tested drawing keeps the nearest fragment
    /// whatever the order, so the picture is the course's (sky, mirrored sky, land, mirrored land,
    /// water).
    pub(super) fn draw_course(&mut self, encoder: &mut wgpu::CommandEncoder, target: &wgpu::TextureView) {
        let (Some(course), Some(depth)) = (&self.course, &self.depth) else { return };
        let mut pass = super::frame::begin_pass(encoder, "scene", target, depth.view(), self.clear);
        let [direct, mirrored, _] = &self.frame_groups;
        let mut budget = DrawBudget(self.draw_limit);
        match &course.land {
            CourseLand::Mesh(land) => {
                for (frame, mirrored_pass) in [(direct, false), (mirrored, true)] {
                    if budget.take() {
                        land.draw(&mut pass, frame, mirrored_pass);
                    }
                }
            }
            CourseLand::Grid { pipelines, wireframe, group, .. } => {
                if let Some(grid) = &self.grid {
                    let pipelines = wireframe.as_ref().unwrap_or(pipelines);
                    for (mirrored_pass, frame, which) in
                        [(false, direct, GridPass::Direct), (true, mirrored, GridPass::Mirrored)]
                    {
                        if budget.take() {
                            pass.set_pipeline(pipelines.get(mirrored_pass));
                            pass.set_bind_group(0, frame, &[]);
                            pass.set_bind_group(1, group, &[]);
                            grid.draw(&mut pass, which);
                        }
                    }
                }
            }
        }
        for (frame, mirrored_pass) in [(direct, false), (mirrored, true)] {
            if budget.take() {
                course.sky.draw(&mut pass, frame, mirrored_pass);
            }
        }
        if budget.take() && self.config.sea {
            course.water.draw(&mut pass, direct);
        }
    }
}
