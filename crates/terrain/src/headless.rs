//! Rendering off-screen: one frame into a texture, read back as an image. No window or display
//! is needed, so this runs on servers and in tests (on a software GPU such as Mesa's lavapipe).

#[cfg(not(target_arch = "wasm32"))]
use std::sync::mpsc;

use image::RgbaImage;

#[cfg(not(target_arch = "wasm32"))]
use crate::config::SceneConfig;
#[cfg(not(target_arch = "wasm32"))]
use crate::render::{FrameView, Renderer, TEXTURE_FORMAT};
use crate::render::{Gpu, GpuError, RenderError};
#[cfg(not(target_arch = "wasm32"))]
use crate::settings::Settings;
#[cfg(not(target_arch = "wasm32"))]
use crate::world::World;

/// Checks that `width` x `height` can be rendered on `gpu`: both sides between 1 and the GPU's
/// largest texture side.
pub fn check_frame_size(gpu: &Gpu, width: u32, height: u32) -> Result<(), RenderError> {
    let max = gpu.device.limits().max_texture_dimension_2d;
    if (1..=max).contains(&width) && (1..=max).contains(&height) {
        Ok(())
    } else {
        Err(RenderError::FrameSize { width, height, max })
    }
}

/// An off-screen colour target and the buffer its pixels are read back through.
#[derive(Debug)]
pub struct OffscreenTarget {
    texture: wgpu::Texture,
    view: wgpu::TextureView,
    readback: wgpu::Buffer,
    size: (u32, u32),
    padded_row_bytes: u32,
}

impl OffscreenTarget {
    /// A `width` x `height` target of `format` (8-bit RGBA or BGRA).
    pub fn new(gpu: &Gpu, format: wgpu::TextureFormat, width: u32, height: u32) -> Result<Self, RenderError> {
        check_frame_size(gpu, width, height)?;
        let row_bytes = 4 * width;
        let align = wgpu::COPY_BYTES_PER_ROW_ALIGNMENT;
        let padded_row_bytes = row_bytes.div_ceil(align) * align;
        // Per pixel: the target, its read-back buffer, the image read back on the CPU (4 bytes
        // each), the depth buffer (4), the reflection and its depth (up to 8), and the
        // rasteriser's own copies on a software GPU (about 4).
        gpu.reserve("off-screen frame", 28 * u64::from(width) * u64::from(height))?;
        let (texture, readback) = gpu.scoped("off-screen frame", || {
            let texture = gpu.device.create_texture(&wgpu::TextureDescriptor {
                label: Some("off-screen target"),
                size: wgpu::Extent3d { width, height, depth_or_array_layers: 1 },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format,
                usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
                view_formats: &[],
            });
            let readback = gpu.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("readback"),
                size: u64::from(padded_row_bytes) * u64::from(height),
                usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
                mapped_at_creation: false,
            });
            (texture, readback)
        })?;
        gpu.check()?;
        Ok(Self {
            view: texture.create_view(&wgpu::TextureViewDescriptor::default()),
            texture,
            readback,
            size: (width, height),
            padded_row_bytes,
        })
    }

    /// The target's size in pixels.
    pub fn size(&self) -> (u32, u32) {
        self.size
    }

    /// The view to draw into.
    pub fn view(&self) -> &wgpu::TextureView {
        &self.view
    }

    /// Copies the target's pixels back to the CPU, as RGBA, after all submitted work.
    #[cfg(not(target_arch = "wasm32"))]
    pub fn read(&self, gpu: &Gpu) -> Result<RgbaImage, RenderError> {
        let (sender, receiver) = mpsc::channel();
        self.request_read(gpu, move |result| {
            let _ = sender.send(result);
        });
        gpu.finish()?;
        receiver
            .recv()
            .map_err(|error| GpuError::Readback(error.to_string()))?
            .map_err(|error| GpuError::Readback(error.to_string()))?;
        self.mapped_image()
    }

    /// Copies the target's pixels into the read-back buffer after all submitted work, and asks
    /// for it to be mapped: `mapped` is called when it is (then [`Self::mapped_image`]). What a
    /// page does, which cannot wait for the GPU.
    pub fn request_read(
        &self,
        gpu: &Gpu,
        mapped: impl FnOnce(Result<(), wgpu::BufferAsyncError>) + wgpu::WasmNotSend + 'static,
    ) {
        let height = self.size.1;
        let mut encoder =
            gpu.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("readback") });
        encoder.copy_texture_to_buffer(
            self.texture.as_image_copy(),
            wgpu::TexelCopyBufferInfo {
                buffer: &self.readback,
                layout: wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(self.padded_row_bytes),
                    rows_per_image: Some(height),
                },
            },
            self.texture.size(),
        );
        gpu.queue.submit([encoder.finish()]);
        self.readback.map_async(wgpu::MapMode::Read, .., mapped);
    }

    /// The pixels of the mapped read-back buffer, as RGBA; unmaps it.
    pub fn mapped_image(&self) -> Result<RgbaImage, RenderError> {
        let (width, height) = self.size;
        let mut pixels = Vec::new();
        pixels.try_reserve_exact(4 * width as usize * height as usize).map_err(|_| {
            GpuError::OutOfMemory {
                what: format!("{width}x{height} image read back from the GPU"),
                message: "the system refused the allocation".into(),
            }
        })?;
        {
            let mapped =
                self.readback.get_mapped_range(..).map_err(|error| GpuError::Readback(error.to_string()))?;
            for row in mapped.chunks(self.padded_row_bytes as usize) {
                pixels.extend_from_slice(&row[..4 * width as usize]);
            }
        }
        self.readback.unmap();
        if matches!(
            self.texture.format(),
            wgpu::TextureFormat::Bgra8Unorm | wgpu::TextureFormat::Bgra8UnormSrgb
        ) {
            for pixel in pixels.chunks_exact_mut(4) {
                pixel.swap(0, 2);
            }
        }
        RgbaImage::from_raw(width, height, pixels)
            .ok_or_else(|| GpuError::Readback("the image read back has the wrong size".into()).into())
    }
}

/// A renderer drawing into an off-screen target of a fixed size (it waits for the GPU: not in
/// a browser).
#[cfg(not(target_arch = "wasm32"))]
#[derive(Debug)]
pub struct HeadlessRenderer {
    renderer: Renderer,
    target: OffscreenTarget,
}

#[cfg(not(target_arch = "wasm32"))]
impl HeadlessRenderer {
    /// Uploads `world` (laid out with `config`) for the look of `settings` and creates a
    /// `width` x `height` target.
    pub fn new(
        gpu: &Gpu,
        world: &World,
        config: &SceneConfig,
        settings: &Settings,
        width: u32,
        height: u32,
    ) -> Result<Self, RenderError> {
        check_frame_size(gpu, width, height)?;
        Ok(Self {
            renderer: Renderer::new(gpu, world, config, settings, TEXTURE_FORMAT)?,
            target: OffscreenTarget::new(gpu, TEXTURE_FORMAT, width, height)?,
        })
    }

    /// The renderer (e.g. for statistics of the last frame).
    pub fn renderer(&self) -> &Renderer {
        &self.renderer
    }

    /// The renderer, e.g. to change its settings.
    pub fn renderer_mut(&mut self) -> &mut Renderer {
        &mut self.renderer
    }

    /// Draws `view` and waits for the GPU to finish, without reading the image back (what a
    /// frame costs on screen).
    pub fn draw(&mut self, gpu: &Gpu, view: &FrameView) -> Result<(), RenderError> {
        self.renderer.draw(gpu, self.target.view(), self.target.size(), view);
        gpu.finish()?;
        Ok(())
    }

    /// Draws `view` and returns the image.
    pub fn render(&mut self, gpu: &Gpu, view: &FrameView) -> Result<RgbaImage, RenderError> {
        self.renderer.draw(gpu, self.target.view(), self.target.size(), view);
        gpu.check()?;
        self.target.read(gpu)
    }
}

/// Renders one frame of `world` off-screen on `gpu` with `settings`: the whole headless path in
/// one call.
#[cfg(not(target_arch = "wasm32"))]
pub fn render_image(
    gpu: &Gpu,
    world: &World,
    config: &SceneConfig,
    settings: &Settings,
    (width, height): (u32, u32),
    view: &FrameView,
) -> Result<RgbaImage, RenderError> {
    HeadlessRenderer::new(gpu, world, config, settings, width, height)?.render(gpu, view)
}
