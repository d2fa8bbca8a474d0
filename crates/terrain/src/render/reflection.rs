//! The modern look's reflection: the mirrored world (land and sky) rendered from the camera into
//! a texture at a fraction of the frame's size, which the water samples (distorted by its
//! waves).

use super::texture::DepthBuffer;

/// Format of the reflection texture.
pub const REFLECTION_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8Unorm;

/// The reflection's colour and depth targets.
#[derive(Debug)]
pub struct ReflectionTarget {
    view: wgpu::TextureView,
    depth: DepthBuffer,
    size: (u32, u32),
}

impl ReflectionTarget {
    /// Targets of `size` pixels (each side at least 1).
    pub fn new(device: &wgpu::Device, size: (u32, u32)) -> Self {
        let size = (size.0.max(1), size.1.max(1));
        let texture = device.create_texture(&wgpu::TextureDescriptor {
            label: Some("reflection"),
            size: wgpu::Extent3d { width: size.0, height: size.1, depth_or_array_layers: 1 },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: REFLECTION_FORMAT,
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING,
            view_formats: &[],
        });
        Self {
            view: texture.create_view(&wgpu::TextureViewDescriptor::default()),
            depth: DepthBuffer::new(device, size),
            size,
        }
    }

    /// The size of the reflection for a frame of `frame` pixels at `scale`.
    pub fn size_for(frame: (u32, u32), scale: f32) -> (u32, u32) {
        let side = |pixels: u32| ((pixels as f32 * scale).round() as u32).max(1);
        (side(frame.0), side(frame.1))
    }

    /// The size in pixels.
    pub fn size(&self) -> (u32, u32) {
        self.size
    }

    /// The colour texture (to sample, and to draw into).
    pub fn view(&self) -> &wgpu::TextureView {
        &self.view
    }

    /// GPU memory, in bytes (colour and depth).
    pub fn gpu_bytes(&self) -> u64 {
        u64::from(self.size.0) * u64::from(self.size.1) * 8
    }

    /// Begins the pass drawing into the reflection, cleared.
    pub fn begin<'a>(&'a self, encoder: &'a mut wgpu::CommandEncoder) -> wgpu::RenderPass<'a> {
        encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("reflection"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: &self.view,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(wgpu::Color::BLACK),
                    store: wgpu::StoreOp::Store,
                },
            })],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: self.depth.view(),
                depth_ops: Some(wgpu::Operations {
                    load: wgpu::LoadOp::Clear(1.0),
                    store: wgpu::StoreOp::Discard,
                }),
                stencil_ops: None,
            }),
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_follow_the_frame() {
        assert_eq!(ReflectionTarget::size_for((1280, 720), 0.5), (640, 360));
        assert_eq!(ReflectionTarget::size_for((1280, 720), 0.25), (320, 180));
        assert_eq!(ReflectionTarget::size_for((3, 1), 0.25), (1, 1));
    }
}
