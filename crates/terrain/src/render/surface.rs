//! A surface frames are presented to: a native window's, or a web page's canvas.

use super::{Gpu, GpuError};

/// A configured surface and its size in pixels.
#[derive(Debug)]
pub struct PresentSurface {
    surface: wgpu::Surface<'static>,
    config: wgpu::SurfaceConfiguration,
}

/// What [`PresentSurface::acquire`] got.
#[derive(Debug)]
pub enum Acquired {
    /// A frame to draw into and present.
    Frame(wgpu::SurfaceTexture),
    /// No frame this time (the window is hidden, or the surface was just set up again).
    Skip,
}

impl PresentSurface {
    /// Configures `surface` for frames of `size` pixels: a format the renderer draws into
    /// without sRGB encoding (as off-screen and as the course's OpenGL: the textures' stored
    /// values go to the screen as they are), viewed as its non-sRGB form. `None` when the
    /// adapter cannot present to it.
    pub fn new(
        gpu: &Gpu,
        surface: wgpu::Surface<'static>,
        size: (u32, u32),
        present_mode: wgpu::PresentMode,
    ) -> Option<Self> {
        let capabilities = surface.get_capabilities(&gpu.adapter);
        let format = capabilities
            .formats
            .iter()
            .copied()
            .find(|format| !format.is_srgb())
            .or(capabilities.formats.first().copied())?;
        let view_format = format.remove_srgb_suffix();
        let config = wgpu::SurfaceConfiguration {
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
            format,
            color_space: wgpu::SurfaceColorSpace::default(),
            width: size.0.max(1),
            height: size.1.max(1),
            present_mode,
            desired_maximum_frame_latency: 2,
            alpha_mode: capabilities.alpha_modes.first().copied().unwrap_or(wgpu::CompositeAlphaMode::Auto),
            view_formats: if view_format == format { Vec::new() } else { vec![view_format] },
        };
        surface.configure(&gpu.device, &config);
        Some(Self { surface, config })
    }

    /// The format to draw in (the surface's, without sRGB encoding).
    pub fn view_format(&self) -> wgpu::TextureFormat {
        self.config.format.remove_srgb_suffix()
    }

    /// The size in pixels.
    pub fn size(&self) -> (u32, u32) {
        (self.config.width, self.config.height)
    }

    /// Follows the window's new size (sizes of 0, a minimised window, are ignored).
    pub fn resize(&mut self, gpu: &Gpu, (width, height): (u32, u32)) {
        if width > 0 && height > 0 {
            self.config.width = width;
            self.config.height = height;
            self.surface.configure(&gpu.device, &self.config);
        }
    }

    /// The next frame to draw into; a surface gone out of date is set up again (and this frame
    /// skipped). An error when the device refuses the surface.
    pub fn acquire(&self, gpu: &Gpu) -> Result<Acquired, GpuError> {
        match self.surface.get_current_texture() {
            wgpu::CurrentSurfaceTexture::Success(frame) | wgpu::CurrentSurfaceTexture::Suboptimal(frame) => {
                Ok(Acquired::Frame(frame))
            }
            wgpu::CurrentSurfaceTexture::Timeout | wgpu::CurrentSurfaceTexture::Occluded => {
                Ok(Acquired::Skip)
            }
            wgpu::CurrentSurfaceTexture::Outdated | wgpu::CurrentSurfaceTexture::Lost => {
                self.surface.configure(&gpu.device, &self.config);
                Ok(Acquired::Skip)
            }
            wgpu::CurrentSurfaceTexture::Validation => Err(gpu.check().err().unwrap_or_else(|| {
                GpuError::Reported { messages: vec!["the surface's next frame could not be acquired".into()] }
            })),
        }
    }

    /// A view of `frame` for drawing in [`Self::view_format`].
    pub fn view(&self, frame: &wgpu::SurfaceTexture) -> wgpu::TextureView {
        frame.texture.create_view(&wgpu::TextureViewDescriptor {
            format: Some(self.view_format()),
            ..Default::default()
        })
    }
}
