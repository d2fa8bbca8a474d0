//! One frame: the passes in the course's order, into any colour target.

use super::uniforms::FrameUniforms;
use super::{DepthBuffer, Renderer};
use crate::camera::CameraPose;

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

impl Renderer {
    /// Draws `view` into `target` (of this renderer's format and `size` pixels) and submits the
    /// work. Drawing order: sky, mirrored sky, terrain, mirrored terrain, water. GPU errors are
    /// collected by the [`super::Gpu`]; check them with [`super::Gpu::check`].
    pub fn draw(
        &mut self,
        gpu: &super::Gpu,
        target: &wgpu::TextureView,
        size: (u32, u32),
        view: &FrameView,
    ) {
        let config = &self.config;
        let lens = crate::camera::Lens {
            field_of_view_degrees: view.field_of_view_degrees,
            near: config.near,
            far: config.far,
        };
        let aspect = size.0.max(1) as f32 / size.1.max(1) as f32;
        let view_projection = lens.projection(aspect) * view.pose.view_matrix();
        let water_offset = config.water_offset(view.time_seconds);
        for (mirrored, buffer) in [false, true].into_iter().zip(&self.frame_buffers) {
            let uniforms = FrameUniforms::new(view_projection, mirrored, water_offset);
            gpu.queue
                .write_buffer(buffer, 0, bytemuck::bytes_of(&uniforms));
        }
        if self.depth.as_ref().map(DepthBuffer::size) != Some(size) {
            self.depth = Some(DepthBuffer::new(&gpu.device, size));
        }
        let Some(depth) = &self.depth else { return };
        let mut encoder = gpu
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("frame"),
            });
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
