//! One frame: the camera's uniforms, the choice of what to draw, then the look's passes, into
//! any colour target.

use glam::Mat4;

use super::Renderer;
use super::grid::GridPass;
use super::reflection::ReflectionTarget;
use super::texture::DepthBuffer;
use super::uniforms::FrameUniforms;
use crate::camera::{CameraPose, Frustum, Lens};
use crate::settings::{Look, ViewSettings};
use crate::world::mesh::LodView;
use crate::world::quadtree::TreeView;

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

impl From<&FrameView> for ViewSettings {
    /// The view's camera and time, as the settings file keeps them.
    fn from(view: &FrameView) -> Self {
        ViewSettings {
            position: view.pose.position.to_array(),
            yaw_degrees: view.pose.yaw_degrees,
            pitch_degrees: view.pose.pitch_degrees,
            field_of_view_degrees: view.field_of_view_degrees,
            time_seconds: view.time_seconds,
        }
    }
}

impl FrameView {
    /// World-to-clip matrix for a target of aspect width / height, with `near` and `far`
    /// clipping distances in world units.
    pub fn view_projection(&self, aspect: f32, near: f32, far: f32) -> Mat4 {
        let lens = Lens { field_of_view_degrees: self.field_of_view_degrees, near, far };
        lens.projection(aspect) * self.pose.view_matrix()
    }

    /// Pixels covered by one world unit seen face-on at a distance of one unit, for a target
    /// `height` pixels high.
    pub fn pixels_per_unit(&self, height: u32) -> f32 {
        height.max(1) as f32 / (2.0 * (self.field_of_view_degrees.to_radians() / 2.0).tan())
    }
}

/// What the last frame drew.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct FrameStats {
    /// Triangles of terrain in the direct and the mirrored (or reflected) pass, skirts included.
    pub terrain_triangles: [u64; 2],
    /// Whether the shadow map was drawn again (the sun moved).
    pub shadow_map_drawn: bool,
}

/// Begins the frame's pass into `target` and `depth`, both cleared (`target` to `clear`).
pub(super) fn begin_pass<'a>(
    encoder: &'a mut wgpu::CommandEncoder,
    label: &str,
    target: &'a wgpu::TextureView,
    depth: &'a wgpu::TextureView,
    clear: wgpu::Color,
) -> wgpu::RenderPass<'a> {
    encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
        label: Some(label),
        color_attachments: &[Some(wgpu::RenderPassColorAttachment {
            view: target,
            depth_slice: None,
            resolve_target: None,
            ops: wgpu::Operations { load: wgpu::LoadOp::Clear(clear), store: wgpu::StoreOp::Store },
        })],
        depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
            view: depth,
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

impl Renderer {
    /// Draws `view` into `target` (of this renderer's format and `size` pixels) in the look of
    /// its settings, and submits the work. GPU errors are collected by the [`super::Gpu`]; check
    /// them with [`super::Gpu::check`].
    pub fn draw(&mut self, gpu: &super::Gpu, target: &wgpu::TextureView, size: (u32, u32), view: &FrameView) {
        let config = &self.config;
        let aspect = size.0.max(1) as f32 / size.1.max(1) as f32;
        let view_projection = view.view_projection(aspect, config.near, config.far);
        let water_offset = config.water_offset(view.time_seconds);
        let frustum = Frustum::from_view_projection(view_projection);
        let eye = view.pose.position;
        for (mirrored, buffer) in [false, true].into_iter().zip(&self.frame_buffers) {
            let uniforms = FrameUniforms::new(view_projection, mirrored, water_offset, eye);
            gpu.queue.write_buffer(buffer, 0, bytemuck::bytes_of(&uniforms));
        }
        let max_error_pixels = self.settings.terrain.lod_error_pixels;
        let pixels_per_unit = view.pixels_per_unit(size.1);
        // The mirrored pass of the modern look draws into the smaller reflection.
        let mirrored_scale = match self.settings.look {
            Look::Course => 1.0,
            Look::Modern => self.settings.water.reflection.scale(),
        };
        let mut stats = FrameStats::default();
        if let Some(land) =
            self.course.as_mut().filter(|_| self.settings.look == Look::Course).and_then(|c| c.mesh())
        {
            // The near plane's corners are the furthest points it clips away.
            let half_height = (view.field_of_view_degrees.to_radians() / 2.0).tan();
            let near_reach = config.near * (1.0 + half_height * half_height * (1.0 + aspect * aspect)).sqrt();
            let lod = |mirrored| LodView {
                eye,
                frustum,
                view_projection,
                pixels_per_unit,
                max_error_pixels,
                mirrored,
                near_reach,
            };
            land.prepare(&gpu.queue, [&lod(false), &lod(true)]);
            stats.terrain_triangles = land.triangles_chosen();
        } else if let Some(grid) = &mut self.grid {
            let tree_view = |mirrored: bool, scale: f32| TreeView {
                eye,
                frustum,
                pixels_per_unit: pixels_per_unit * scale,
                max_error_pixels,
                mirrored,
                orthographic: false,
            };
            grid.prepare(&gpu.device, &gpu.queue, GridPass::Direct, &tree_view(false, 1.0));
            stats.terrain_triangles[0] = grid.triangles(GridPass::Direct);
            if mirrored_scale > 0.0 {
                let scale = if self.settings.look == Look::Modern {
                    ReflectionTarget::size_for(size, mirrored_scale).1 as f32 / size.1.max(1) as f32
                } else {
                    1.0
                };
                grid.prepare(&gpu.device, &gpu.queue, GridPass::Mirrored, &tree_view(true, scale));
                stats.terrain_triangles[1] = grid.triangles(GridPass::Mirrored);
            }
        }
        let shadow = self.settings.look == Look::Modern && self.prepare_modern(gpu, size, view.time_seconds);
        stats.shadow_map_drawn = shadow;
        self.stats = stats;
        if self.depth.as_ref().map(DepthBuffer::size) != Some(size) {
            self.depth = Some(DepthBuffer::new(&gpu.device, size));
        }
        let mut encoder =
            gpu.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("frame") });
        match self.settings.look {
            Look::Course => self.draw_course(&mut encoder, target),
            Look::Modern => self.draw_modern(&mut encoder, target, shadow),
        }
        gpu.queue.submit([encoder.finish()]);
    }
}

/// What the frame is cleared to: black (hidden by the sky and the sea) where there is a sea;
/// without one, the sky's colour at the horizon (the mean of the sky walls' bottom rows), which
/// then shows below the horizon beyond the land's edges.
pub(super) fn clear_colour(config: &crate::config::SceneConfig, world: &crate::world::World) -> wgpu::Color {
    if config.sea {
        return wgpu::Color::BLACK;
    }
    let sky = world.clear_sky();
    let mut sum = [0.0f64; 3];
    let mut count = 0.0;
    for wall in &sky.sides {
        if wall.height() == 0 {
            continue;
        }
        let y = wall.height() - 1;
        for x in 0..wall.width() {
            let pixel = wall.get_pixel(x, y).0;
            for (total, &channel) in sum.iter_mut().zip(&pixel[..3]) {
                *total += srgb_to_linear(f64::from(channel) / 255.0);
            }
            count += 1.0;
        }
    }
    if count == 0.0 {
        return wgpu::Color::BLACK;
    }
    wgpu::Color { r: sum[0] / count, g: sum[1] / count, b: sum[2] / count, a: 1.0 }
}

pub(super) fn srgb_to_linear(value: f64) -> f64 {
    if value <= 0.04045 { value / 12.92 } else { ((value + 0.055) / 1.055).powf(2.4) }
}
