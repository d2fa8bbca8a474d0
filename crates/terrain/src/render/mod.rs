//! The wgpu renderer. It draws a [`World`] into any texture view (a window's surface or an
//! off-screen texture) in one of two looks ([`crate::settings::Look`]): the course's (sky, land
//! and their mirror images under translucent water, exactly as the course drew them) or the
//! modern one (sun light, shadows, fog, and water that reflects and refracts). Each pass is a
//! handful of draw calls, whatever the heightmap's size.

mod course;
mod draw_path;
mod frame;
mod gpu;
mod grid;
mod land;
mod light_map;
mod lighting;
mod memory;
mod modern;
mod pipeline;
mod reflection;
mod sea;
mod shadow;
mod sky;
mod surface;
mod texture;
#[cfg(test)]
mod uniform_branches;
mod uniforms;
mod water;

pub use course::MESH_MAX_SIDE;
pub use draw_path::LandDrawPath;
pub use frame::{FrameStats, FrameView};
pub use gpu::{Backend, Gpu, GpuError};
pub use lighting::SHADOW_MAP_SIZE;
pub use surface::{Acquired, PresentSurface};
pub use texture::TEXTURE_FORMAT;

use course::CourseLook;
use draw_path::DrawSupport;
use grid::GridTerrain;
use modern::ModernLook;
use pipeline::PassContext;
use texture::DepthBuffer;

use crate::config::SceneConfig;
use crate::settings::{Look, Settings};
use crate::world::World;

/// Why the renderer could not be built or could not draw.
#[derive(Debug, thiserror::Error)]
pub enum RenderError {
    /// An image is larger than the GPU's textures may be (or empty).
    #[error("the {what} is {width}x{height}; this GPU's textures may be at most {max}x{max}")]
    TextureSize {
        /// Which image.
        what: String,
        /// Its width.
        width: u32,
        /// Its height.
        height: u32,
        /// The GPU's largest texture side.
        max: u32,
    },
    /// The terrain mesh does not fit in one GPU buffer.
    #[error("a {columns}x{rows} heightmap needs a {bytes}-byte buffer; this GPU allows at most {max} bytes")]
    MeshSize {
        /// Heightmap columns.
        columns: u32,
        /// Heightmap rows.
        rows: u32,
        /// Bytes needed.
        bytes: u64,
        /// The GPU's largest buffer.
        max: u64,
    },
    /// A frame size the GPU cannot render.
    #[error("cannot render a {width}x{height} image: sides must be between 1 and {max} pixels on this GPU")]
    FrameSize {
        /// Requested width.
        width: u32,
        /// Requested height.
        height: u32,
        /// The GPU's largest texture side.
        max: u32,
    },
    /// The GPU failed.
    #[error(transparent)]
    Gpu(#[from] GpuError),
}

/// Everything on the GPU needed to draw one world: pipelines, meshes, textures and the depth
/// buffer, for the looks used so far.
#[derive(Debug)]
pub struct Renderer {
    config: SceneConfig,
    /// What the frame is cleared to ([`frame::clear_colour`]).
    clear: wgpu::Color,
    settings: Settings,
    target_format: wgpu::TextureFormat,
    frame_layout: wgpu::BindGroupLayout,
    /// Uniforms of the direct pass (index 0), the mirrored pass (1) and the sun's view (2).
    frame_buffers: [wgpu::Buffer; 3],
    frame_groups: [wgpu::BindGroup; 3],
    /// What the GPU offers the static mesh's draws.
    draw_support: DrawSupport,
    /// How the static mesh's draws are asked to be made ([`Renderer::set_land_draw_path`]).
    land_draw_path: LandDrawPath,
    /// The heightmap as a GPU grid (the modern look, and the course's on large maps).
    grid: Option<GridTerrain>,
    course: Option<CourseLook>,
    modern: Option<ModernLook>,
    depth: Option<DepthBuffer>,
    stats: FrameStats,
    /// How many of the look's draws a frame makes ([`Renderer::set_draw_limit`]).
    draw_limit: Option<usize>,
}

/// The draws a frame of `look` makes, in order (see [`Renderer::set_draw_limit`]).
pub fn draw_names(look: Look) -> &'static [&'static str] {
    match look {
        Look::Course => &course::DRAWS,
        Look::Modern => &modern::DRAWS,
    }
}

/// Counts a frame's draws against [`Renderer::set_draw_limit`].
#[derive(Debug, Clone, Copy)]
struct DrawBudget(Option<usize>);

impl DrawBudget {
    /// Whether the next draw is made (and counts it).
    fn take(&mut self) -> bool {
        match &mut self.0 {
            None => true,
            Some(0) => false,
            Some(left) => {
                *left -= 1;
                true
            }
        }
    }
}

/// GPU memory a renderer holds, in bytes, by what it is for.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct GpuMemory {
    /// The heightmap's texture (the grid: 2 bytes a sample) and its patch mesh.
    pub heights: u64,
    /// The course look's static mesh (maps up to [`MESH_MAX_SIDE`]).
    pub mesh: u64,
    /// The modern look's light map (with its mip levels).
    pub light_map: u64,
    /// Colour, detail and sky textures, wave maps, the shadow map and the reflection.
    pub textures: u64,
    /// The frame's depth buffer.
    pub depth: u64,
}

impl GpuMemory {
    /// All of it.
    pub fn total(&self) -> u64 {
        self.heights + self.mesh + self.light_map + self.textures + self.depth
    }

    /// What the terrain's geometry and light cost per height sample (`samples` of them), in
    /// bytes: the height texture, the mesh and the light map.
    pub fn bytes_per_sample(&self, samples: u64) -> f64 {
        (self.heights + self.mesh + self.light_map) as f64 / samples.max(1) as f64
    }
}

impl Renderer {
    /// Uploads `world` laid out with `config` for the look `settings` asks for, to draw into
    /// targets of `target_format`. Reports GPU errors (e.g. out of memory) as errors, not panics.
    pub fn new(
        gpu: &Gpu,
        world: &World,
        config: &SceneConfig,
        settings: &Settings,
        target_format: wgpu::TextureFormat,
    ) -> Result<Self, RenderError> {
        let device = &gpu.device;
        let frame_layout = uniforms::frame_layout(device);
        let frame_buffers = [0, 1, 2].map(|_| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("frame uniforms"),
                size: size_of::<uniforms::FrameUniforms>() as u64,
                usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            })
        });
        let frame_groups = [0, 1, 2].map(|i| {
            device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some(["frame", "frame (mirrored)", "frame (sun)"][i]),
                layout: &frame_layout,
                entries: &[wgpu::BindGroupEntry {
                    binding: 0,
                    resource: frame_buffers[i].as_entire_binding(),
                }],
            })
        });
        let mut renderer = Self {
            config: config.clone(),
            settings: settings.clone(),
            target_format,
            frame_layout,
            frame_buffers,
            frame_groups,
            draw_support: DrawSupport::of(&gpu.adapter),
            land_draw_path: LandDrawPath::default(),
            grid: None,
            course: None,
            modern: None,
            depth: None,
            stats: FrameStats::default(),
            draw_limit: None,
            clear: frame::clear_colour(config, world),
        };
        renderer.apply(gpu, world, settings)?;
        Ok(renderer)
    }

    /// Switches to `settings`, uploading what a look used for the first time needs of `world`
    /// (the world the renderer was made with).
    pub fn apply(&mut self, gpu: &Gpu, world: &World, settings: &Settings) -> Result<(), RenderError> {
        let context = PassContext {
            device: &gpu.device,
            queue: &gpu.queue,
            frame_layout: &self.frame_layout,
            target_format: self.target_format,
        };
        let side = world.heightmap.columns().max(world.heightmap.rows());
        let samples = u64::from(world.heightmap.columns()) * u64::from(world.heightmap.rows());
        let needs_grid = settings.look == Look::Modern || side > MESH_MAX_SIDE;
        if needs_grid && self.grid.is_none() {
            // The height texture (2 bytes a sample) and the level-of-detail tree's bounds.
            gpu.reserve("heightmap on the GPU", samples * 2 + samples / 4)?;
            let grid = gpu.scoped("heightmap on the GPU", || {
                GridTerrain::new(&context, &world.heightmap, &self.config)
            })??;
            self.grid = Some(grid);
        }
        match settings.look {
            Look::Course if self.course.is_none() => {
                let grid = (side > MESH_MAX_SIDE).then_some(self.grid.as_ref()).flatten();
                if grid.is_none() {
                    // The static mesh: positions (12 bytes) and indices (2 bytes, about 6 a
                    // sample) at every level of detail (a third more), and its build on the CPU.
                    gpu.reserve("terrain mesh", samples * (12 + 12) * 4 / 3 * 2)?;
                }
                let course = gpu.scoped("course look's terrain and textures", || {
                    CourseLook::new(
                        &context,
                        world,
                        &self.config,
                        (self.draw_support, self.land_draw_path),
                        grid,
                    )
                })??;
                self.course = Some(course);
            }
            Look::Modern if self.modern.is_none() => {
                if let Some(grid) = &self.grid {
                    let modern = gpu
                        .scoped("modern look's light map, shadow map, reflection and textures", || {
                            ModernLook::new(&context, world, &self.config, grid, settings.ground.materials)
                        })??;
                    self.modern = Some(modern);
                }
            }
            _ => {}
        }
        let wireframe = settings.terrain.wireframe;
        if let Some(course) = &mut self.course {
            course.set_wireframe(&context, wireframe);
        }
        if let Some(modern) = &mut self.modern {
            modern.set_land(&context, wireframe, settings.ground.materials);
        }
        self.settings = settings.clone();
        gpu.check()?;
        Ok(())
    }

    /// Leaves out of the course look's mirrored pass the land's chunks that the land itself hides
    /// (`on`, the default), or draws them all, to measure what that saves: the picture is the
    /// same bit for bit either way. Only the static mesh (maps up to [`MESH_MAX_SIDE`]) culls.
    pub fn set_cull_hidden_reflection(&mut self, on: bool) {
        if let Some(land) = self.course.as_mut().and_then(CourseLook::mesh) {
            land.set_cull_hidden_reflection(on);
        }
    }

    /// Draws the course look's static mesh (maps up to [`MESH_MAX_SIDE`]) by `path` from the
    /// next frame on, or by the next path down where the GPU lacks it (also for a mesh made
    /// later). The picture is the same bit for bit on every path; this is for tests and
    /// measurements. Returns the path the current mesh takes, `None` while there is none.
    pub fn set_land_draw_path(&mut self, path: LandDrawPath) -> Option<LandDrawPath> {
        self.land_draw_path = path;
        self.course.as_mut().and_then(CourseLook::mesh).map(|land| land.set_draw_path(path))
    }

    /// Makes frames draw only the first `limit` of their look's draws ([`draw_names`] lists
    /// them in order), or all of them (`None`, the default): adding one draw after another
    /// measures what each adds to a frame. What the sun's move redraws (the modern look's shadow
    /// and light maps) is always drawn.
    pub fn set_draw_limit(&mut self, limit: Option<usize>) {
        self.draw_limit = limit;
    }

    /// The settings the renderer draws with.
    pub fn settings(&self) -> &Settings {
        &self.settings
    }

    /// The colour format this renderer draws into.
    pub fn target_format(&self) -> wgpu::TextureFormat {
        self.target_format
    }

    /// What the last frame drew.
    pub fn stats(&self) -> FrameStats {
        self.stats
    }

    /// Triangles of terrain the last frame drew in its direct and mirrored passes.
    pub fn terrain_triangles(&self) -> [u64; 2] {
        self.stats.terrain_triangles
    }

    /// GPU memory held for the looks used so far.
    pub fn gpu_memory(&self) -> GpuMemory {
        let (mesh, course) = self.course.as_ref().map_or((0, 0), CourseLook::gpu_bytes);
        let (light_map, modern) = self.modern.as_ref().map_or((0, 0), ModernLook::gpu_bytes);
        GpuMemory {
            heights: self.grid.as_ref().map_or(0, GridTerrain::gpu_bytes),
            mesh,
            light_map,
            textures: course + modern,
            depth: self.depth.as_ref().map_or(0, |d| u64::from(d.size().0) * u64::from(d.size().1) * 4),
        }
    }

    /// CPU memory the renderer keeps (the grid's level-of-detail tree), in bytes.
    pub fn cpu_bytes(&self) -> usize {
        self.grid.as_ref().map_or(0, GridTerrain::tree_bytes)
    }

    /// The scene configuration the world was laid out with.
    pub fn config(&self) -> &SceneConfig {
        &self.config
    }
}
