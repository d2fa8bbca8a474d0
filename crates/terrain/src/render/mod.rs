//! The wgpu renderer. It draws a [`World`] into any texture view (a window's surface or an
//! off-screen texture) in the course's order: sky, mirrored sky, terrain, mirrored terrain, then
//! the translucent water. Each of these is one draw call, whatever the heightmap's size.

mod frame;
mod gpu;
mod land;
mod pipeline;
mod sky;
mod texture;
mod uniforms;
mod water;

pub use frame::FrameView;
pub use gpu::{Backend, Gpu, GpuError};
pub use texture::TEXTURE_FORMAT;

use land::LandPass;
use sky::SkyPass;
use texture::DepthBuffer;
use water::WaterPass;

use crate::config::SceneConfig;
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
/// buffer.
#[derive(Debug)]
pub struct Renderer {
    config: SceneConfig,
    target_format: wgpu::TextureFormat,
    /// Uniforms of the direct pass (index 0) and the mirrored pass (index 1).
    frame_buffers: [wgpu::Buffer; 2],
    frame_groups: [wgpu::BindGroup; 2],
    sky: SkyPass,
    land: LandPass,
    water: WaterPass,
    depth: Option<DepthBuffer>,
}

impl Renderer {
    /// Uploads `world` laid out with `config`, for drawing into targets of `target_format`.
    /// Reports GPU errors (e.g. out of memory) as errors, not panics.
    pub fn new(
        gpu: &Gpu,
        world: &World,
        config: &SceneConfig,
        target_format: wgpu::TextureFormat,
    ) -> Result<Self, RenderError> {
        let device = &gpu.device;
        let frame_layout = uniforms::frame_layout(device);
        let frame_buffers = [0, 1].map(|_| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("frame uniforms"),
                size: size_of::<uniforms::FrameUniforms>() as u64,
                usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            })
        });
        let frame_groups = [0, 1].map(|i| {
            device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some(if i == 0 { "frame" } else { "frame (mirrored)" }),
                layout: &frame_layout,
                entries: &[wgpu::BindGroupEntry {
                    binding: 0,
                    resource: frame_buffers[i].as_entire_binding(),
                }],
            })
        });
        let context =
            pipeline::PassContext { device, queue: &gpu.queue, frame_layout: &frame_layout, target_format };
        let multi_draw =
            gpu.adapter.get_downlevel_capabilities().flags.contains(wgpu::DownlevelFlags::INDIRECT_EXECUTION);
        let sky = SkyPass::new(&context, &world.sky, config)?;
        let land = LandPass::new(&context, world, config, multi_draw)?;
        let water = WaterPass::new(&context, &world.water, config)?;
        gpu.check()?;
        Ok(Self {
            config: config.clone(),
            target_format,
            frame_buffers,
            frame_groups,
            sky,
            land,
            water,
            depth: None,
        })
    }

    /// The colour format this renderer draws into.
    pub fn target_format(&self) -> wgpu::TextureFormat {
        self.target_format
    }

    /// Triangles of terrain the last frame drew in its direct and mirrored passes.
    pub fn terrain_triangles(&self) -> [u64; 2] {
        self.land.triangles_chosen()
    }

    /// The scene configuration the world was laid out with.
    pub fn config(&self) -> &SceneConfig {
        &self.config
    }
}
