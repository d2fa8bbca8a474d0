//! One frame: the passes in the course's order, into any colour target.

use super::uniforms::FrameUniforms;
use super::{DepthBuffer, Renderer};
use glam::Mat4;

use crate::camera::{CameraPose, Frustum, Lens};
use crate::world::mesh::LodView;

/// Largest on-screen error, in pixels, that the terrain's level of detail may introduce: two
/// pixels of vertical shift, which does not show as the camera moves.
pub const LOD_ERROR_PIXELS: f32 = 2.0;

/// What a frame shows: where the camera is, its field of view, and the time (which moves the
/// water).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FrameView {
    /// The camera's pose.
    pub pose: CameraPose,
    /// Vertical field of view in degrees.
    pub field_of_view_degrees: f32,
    /// Seconds since the scene started.
    pub time_seconds: f64,
}

impl FrameView {
    /// World-to-clip matrix for a target of aspect width / height, with `near` and `far`
    /// clipping distances in world units.
    pub fn view_projection(&self, aspect: f32, near: f32, far: f32) -> Mat4 {
        let lens = Lens { field_of_view_degrees: self.field_of_view_degrees, near, far };
        lens.projection(aspect) * self.pose.view_matrix()
    }
}

impl Renderer {
    /// Draws `view` into `target` (of this renderer's format and `size` pixels) and submits the
    /// work. Drawing order: sky, mirrored sky, terrain, mirrored terrain, water. GPU errors are
    /// collected by the [`super::Gpu`]; check them with [`super::Gpu::check`].
    pub fn draw(&mut self, gpu: &super::Gpu, target: &wgpu::TextureView, size: (u32, u32), view: &FrameView) {
        let config = &self.config;
        let aspect = size.0.max(1) as f32 / size.1.max(1) as f32;
        let view_projection = view.view_projection(aspect, config.near, config.far);
        let water_offset = config.water_offset(view.time_seconds);
        let frustum = Frustum::from_view_projection(view_projection);
        let lod = |mirrored| LodView {
            eye: view.pose.position,
            frustum,
            pixels_per_unit: size.1.max(1) as f32
                / (2.0 * (view.field_of_view_degrees.to_radians() / 2.0).tan()),
            max_error_pixels: LOD_ERROR_PIXELS,
            mirrored,
        };
        self.land.prepare(&gpu.queue, [&lod(false), &lod(true)]);
        for (mirrored, buffer) in [false, true].into_iter().zip(&self.frame_buffers) {
            let uniforms = FrameUniforms::new(view_projection, mirrored, water_offset);
            gpu.queue.write_buffer(buffer, 0, bytemuck::bytes_of(&uniforms));
        }
        if self.depth.as_ref().map(DepthBuffer::size) != Some(size) {
            self.depth = Some(DepthBuffer::new(&gpu.device, size));
        }
        let Some(depth) = &self.depth else { return };
        let mut encoder =
            gpu.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("frame") });
        {
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("scene"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: target,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color::BLACK),
                        store: wgpu::StoreOp::Store,
                    },
                })],
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: depth.view(),
                    depth_ops: Some(wgpu::Operations {
                        load: wgpu::LoadOp::Clear(1.0),
                        store: wgpu::StoreOp::Discard,
                    }),
                    stencil_ops: None,
                }),
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            let [direct, mirrored] = &self.frame_groups;
            self.sky.draw(&mut pass, direct, false);
            self.sky.draw(&mut pass, mirrored, true);
            self.land.draw(&mut pass, direct, false);
            self.land.draw(&mut pass, mirrored, true);
            self.water.draw(&mut pass, direct);
        }
        gpu.queue.submit([encoder.finish()]);
    }
}
