//! An overlay for the window and the web page: egui (its context, its winit input state and its
//! wgpu renderer), drawn over the frame. Its last shapes are kept, so a screenshot shows what the
//! window shows.

use std::sync::Arc;

use winit::window::Window;

use crate::render::Gpu;

/// The last frame's shapes, in physical pixels of a target of the given size.
struct Painted {
    jobs: Vec<egui::ClippedPrimitive>,
    screen: egui_wgpu::ScreenDescriptor,
}

/// egui over the frames of a window (native or a web page's canvas).
pub struct Overlay {
    ctx: egui::Context,
    state: egui_winit::State,
    renderer: egui_wgpu::Renderer,
    last: Option<Painted>,
    /// Texture changes to upload before the next paint, and textures to free after it.
    pending_textures: Vec<(egui::TextureId, egui::epaint::ImageDelta)>,
    freed: Vec<egui::TextureId>,
}

impl Overlay {
    /// egui for `window`, drawing into targets of `format`.
    pub fn new(window: &Arc<Window>, gpu: &Gpu, format: wgpu::TextureFormat) -> Self {
        let ctx = egui::Context::default();
        let max_side = gpu.device.limits().max_texture_dimension_2d as usize;
        let state = egui_winit::State::new(
            ctx.clone(),
            egui::ViewportId::ROOT,
            window.as_ref(),
            Some(window.scale_factor() as f32),
            None,
            Some(max_side),
        );
        let renderer = egui_wgpu::Renderer::new(&gpu.device, format, egui_wgpu::RendererOptions::default());
        Self { ctx, state, renderer, last: None, pending_textures: Vec::new(), freed: Vec::new() }
    }

    /// Passes a window event to egui; whether egui used it (then the scene should not).
    pub fn on_window_event(&mut self, window: &Window, event: &winit::event::WindowEvent) -> bool {
        self.state.on_window_event(window, event).consumed
    }

    /// Passes a window event to egui while the panel is open; whether the event is the
    /// panel's (then the scene should not see it): typing, clicks and scrolls on the panel.
    /// F1 (the panel), F12 (a screenshot) and Esc are always the scene's.
    pub fn takes(&mut self, window: &Window, event: &winit::event::WindowEvent) -> bool {
        use winit::event::WindowEvent;
        use winit::keyboard::{KeyCode, PhysicalKey};
        let used = self.on_window_event(window, event);
        match event {
            WindowEvent::KeyboardInput { event: key, .. } => {
                let ours = matches!(
                    key.physical_key,
                    PhysicalKey::Code(KeyCode::F1 | KeyCode::F12 | KeyCode::Escape)
                );
                !ours && (used || self.wants_keyboard())
            }
            WindowEvent::MouseInput { .. } | WindowEvent::MouseWheel { .. } => used || self.wants_pointer(),
            _ => false,
        }
    }

    /// Whether the pointer is over the panel (a click there is not for the scene).
    pub fn wants_pointer(&self) -> bool {
        self.ctx.egui_wants_pointer_input() || self.ctx.is_pointer_over_egui()
    }

    /// Whether a text field has the keyboard (keys are not for the camera).
    pub fn wants_keyboard(&self) -> bool {
        self.ctx.egui_wants_keyboard_input()
    }

    /// Runs the interface for one frame and keeps its shapes for [`Self::paint`].
    pub fn run(&mut self, window: &Window, size: (u32, u32), ui: impl FnMut(&egui::Context)) {
        let input = self.state.take_egui_input(window);
        let mut ui = ui;
        let mut output = self.ctx.run_pass(input, |ctx| ui(ctx));
        // Texture changes are uploaded at the next paint (and frees applied after it).
        for (id, deltas) in std::mem::take(&mut output.textures_delta.set) {
            self.pending_textures.extend(deltas.into_iter().map(|delta| (id, delta)));
        }
        self.freed.extend(std::mem::take(&mut output.textures_delta.free));
        self.state.handle_platform_output(window, std::mem::take(&mut output.platform_output));
        let pixels_per_point = output.pixels_per_point;
        let jobs = self.ctx.tessellate(std::mem::take(&mut output.shapes), pixels_per_point);
        self.last = Some(Painted {
            jobs,
            screen: egui_wgpu::ScreenDescriptor { size_in_pixels: [size.0, size.1], pixels_per_point },
        });
    }

    /// Draws the last frame's shapes over `target` (of `size` pixels), if it has any.
    pub fn paint(&mut self, gpu: &Gpu, target: &wgpu::TextureView, size: (u32, u32)) {
        for (id, delta) in self.pending_textures.drain(..) {
            self.renderer.update_texture(&gpu.device, &gpu.queue, id, &delta);
        }
        let Some(painted) = &mut self.last else { return };
        painted.screen.size_in_pixels = [size.0, size.1];
        let mut encoder =
            gpu.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("panel") });
        let extra = self.renderer.update_buffers(
            &gpu.device,
            &gpu.queue,
            &mut encoder,
            &painted.jobs,
            &painted.screen,
        );
        {
            let pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("panel"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: target,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations { load: wgpu::LoadOp::Load, store: wgpu::StoreOp::Store },
                })],
                depth_stencil_attachment: None,
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            self.renderer.render(&mut pass.forget_lifetime(), &painted.jobs, &painted.screen);
        }
        gpu.queue.submit(extra.into_iter().chain([encoder.finish()]));
        for id in self.freed.drain(..) {
            self.renderer.free_texture(&id);
        }
    }

    /// Forgets the last frame's shapes (the panel was closed).
    pub fn clear(&mut self) {
        self.last = None;
    }
}
