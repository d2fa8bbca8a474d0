//! The preview window: winit's event loop on the main thread, the image drawn by wgpu with
//! `display.wgsl` (zoom, pan, exposure, sRGB), the terrain engine's fly camera moving the scene's
//! camera, and the keys of [`KEYS`].

use std::path::PathBuf;
use std::sync::Arc;
use std::time::{Duration, Instant};

use bytemuck::{Pod, Zeroable};
use raytracer::image_io::{Image, write_image};
use terrain::camera::{FlyCamera, Limits, Motion};
use terrain::headless::OffscreenTarget;
use terrain::render::{Acquired, Backend, Gpu, PresentSurface};
use winit::application::ApplicationHandler;
use winit::dpi::PhysicalSize;
use winit::event::{ElementState, KeyEvent, MouseButton, MouseScrollDelta, WindowEvent};
use winit::event_loop::{ActiveEventLoop, ControlFlow, EventLoop};
use winit::keyboard::{KeyCode, PhysicalKey};
use winit::window::{Window, WindowId};

use super::Shared;
use super::fly::{fly_camera, pose_of};
use super::pose::pose_note;
use super::pose::{Pose, PoseSyntax};
use super::view::View;

/// The keys and the mouse, as the docs list them.
pub const KEYS: &[(&str, &str)] = &[
    ("W, A, Left, Right", "fly forward, left, right (Shift: faster)"),
    ("Up, Down", "fly up, down (world z)"),
    ("right button + mouse", "look around; with it held, S and D fly back and right"),
    ("S", "write the image so far (NAME.so-far.EXT)"),
    ("D", "show the denoised image or the noisy one (with --denoise)"),
    ("P", "print the camera's pose as scene-file lines"),
    ("E, Shift+E", "exposure one stop up, down"),
    ("wheel", "zoom about the cursor (1:1 and beyond)"),
    ("left button drag", "pan"),
    ("F, 1", "fit the window, 1:1 pixels"),
    ("Esc", "close the window (the render goes on to its end)"),
];

/// The window's message that the worker has something new.
#[derive(Clone, Copy, Debug)]
pub struct Wake;

/// What the window needs to know.
#[derive(Clone, Debug)]
pub struct Setup {
    /// The scene's name, for the title.
    pub title: String,
    /// The image size in pixels.
    pub image: (u32, u32),
    /// Where `S` writes the image so far.
    pub save_as: PathBuf,
    /// Whether 8-bit output is sRGB-encoded (`--gamma`), for `S`.
    pub gamma: bool,
    /// Where every shown image is written, for tests ([`super::DUMP_FRAMES_ENV`]).
    pub dump_dir: Option<PathBuf>,
    /// The camera's pose at start (the scene file's).
    pub pose: Pose,
    /// The fly camera's top speed, in scene units a second.
    pub speed: f32,
    /// The syntax `P` prints the pose in.
    pub syntax: PoseSyntax,
    /// Whether `--denoise` found OIDN.
    pub can_denoise: bool,
    /// Print nothing but the pose, warnings and errors (`--quiet`).
    pub quiet: bool,
}

/// The controls as aligned lines, for the terminal.
pub fn controls() -> String {
    let width = KEYS.iter().map(|(keys, _)| keys.len()).max().unwrap_or(0);
    KEYS.iter().map(|(keys, what)| format!("  {keys:<width$}  {what}")).collect::<Vec<_>>().join("\n")
}

/// How the window closed.
#[derive(Clone, Copy, Debug)]
pub struct End {
    /// The camera's pose then.
    pub pose: Pose,
}

/// The event loop, or why there is none (no display).
pub fn event_loop() -> Result<EventLoop<Wake>, String> {
    EventLoop::<Wake>::with_user_event().build().map_err(|e| e.to_string())
}

/// Runs the window until it is closed. An error when it could not be opened.
pub fn run(event_loop: EventLoop<Wake>, shared: &Shared, setup: &Setup) -> Result<End, String> {
    event_loop.set_control_flow(ControlFlow::Wait);
    let mut app = App {
        shared,
        setup,
        running: None,
        error: None,
        camera: fly_camera(&setup.pose, setup.speed),
        pose: setup.pose,
        moved: false,
        view: None,
        cursor: [0.0; 2],
        drag: None,
        looking: None,
        shift: false,
        shown: None,
        last_step: Instant::now(),
        dumped: 0,
        capture_pending: false,
        title: String::new(),
    };
    event_loop.run_app(&mut app).map_err(|e| e.to_string())?;
    match app.error {
        Some(error) => Err(error),
        None => Ok(End { pose: app.pose }),
    }
}

/// The image on screen.
struct Shown {
    width: u32,
    height: u32,
    pixels: Arc<Vec<[f32; 3]>>,
    status: String,
    finished: bool,
    denoised: bool,
    serial: u64,
}

/// The GPU side of the open window.
struct Running {
    window: Arc<Window>,
    gpu: Gpu,
    surface: PresentSurface,
    pipeline: wgpu::RenderPipeline,
    layout: wgpu::BindGroupLayout,
    uniforms: wgpu::Buffer,
    /// The image's texture and its bind group, for images of its size.
    texture: Option<(wgpu::Texture, wgpu::BindGroup, (u32, u32))>,
}

/// The uniforms of `display.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct ViewUniforms {
    zoom: f32,
    exposure: f32,
    offset: [f32; 2],
    size: [f32; 2],
    pad: [f32; 2],
}

struct App<'a> {
    shared: &'a Shared,
    setup: &'a Setup,
    running: Option<Running>,
    error: Option<String>,
    camera: FlyCamera,
    /// The pose last sent to the worker (the scene's until the camera moves).
    pose: Pose,
    moved: bool,
    view: Option<View>,
    cursor: [f64; 2],
    /// Where a pan started (left button held).
    drag: Option<[f64; 2]>,
    /// Where a look started (right button held).
    looking: Option<[f64; 2]>,
    shift: bool,
    shown: Option<Shown>,
    last_step: Instant,
    dumped: u32,
    /// Whether the next picture drawn is to be captured (with the test folder).
    capture_pending: bool,
    title: String,
}

impl App<'_> {
    fn open(&mut self, event_loop: &ActiveEventLoop) -> Result<Running, String> {
        let (w, h) = self.setup.image;
        // At 1:1 where it fits a common screen, else scaled down to fit.
        let fit = (1600.0 / f64::from(w)).min(1000.0 / f64::from(h)).min(1.0);
        let size =
            PhysicalSize::new(((f64::from(w) * fit) as u32).max(64), ((f64::from(h) * fit) as u32).max(64));
        let attributes = Window::default_attributes().with_title("rayterra preview").with_inner_size(size);
        let window = Arc::new(event_loop.create_window(attributes).map_err(|e| e.to_string())?);
        let instance = Gpu::instance(Backend::Auto, Some(Box::new(event_loop.owned_display_handle())));
        let surface = instance.create_surface(Arc::clone(&window)).map_err(|e| e.to_string())?;
        let gpu = Gpu::open(instance, Backend::Auto, Some(&surface)).map_err(|e| e.to_string())?;
        let inner = window.inner_size();
        let surface =
            PresentSurface::new(&gpu, surface, (inner.width, inner.height), wgpu::PresentMode::AutoVsync)
                .ok_or_else(|| format!("{} cannot present to this window", gpu.describe()))?;
        let device = &gpu.device;
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("preview"),
            source: wgpu::ShaderSource::Wgsl(include_str!("display.wgsl").into()),
        });
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("preview"),
            entries: &[
                wgpu::BindGroupLayoutEntry {
                    binding: 0,
                    visibility: wgpu::ShaderStages::FRAGMENT,
                    ty: wgpu::BindingType::Buffer {
                        ty: wgpu::BufferBindingType::Uniform,
                        has_dynamic_offset: false,
                        min_binding_size: None,
                    },
                    count: None,
                },
                wgpu::BindGroupLayoutEntry {
                    binding: 1,
                    visibility: wgpu::ShaderStages::FRAGMENT,
                    ty: wgpu::BindingType::Texture {
                        sample_type: wgpu::TextureSampleType::Float { filterable: false },
                        view_dimension: wgpu::TextureViewDimension::D2,
                        multisampled: false,
                    },
                    count: None,
                },
            ],
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("preview"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("preview"),
            layout: Some(&pipeline_layout),
            vertex: wgpu::VertexState {
                module: &module,
                entry_point: Some("vs_main"),
                compilation_options: wgpu::PipelineCompilationOptions::default(),
                buffers: &[],
            },
            primitive: wgpu::PrimitiveState::default(),
            depth_stencil: None,
            multisample: wgpu::MultisampleState::default(),
            fragment: Some(wgpu::FragmentState {
                module: &module,
                entry_point: Some("fs_main"),
                compilation_options: wgpu::PipelineCompilationOptions::default(),
                targets: &[Some(wgpu::ColorTargetState {
                    format: surface.view_format(),
                    blend: None,
                    write_mask: wgpu::ColorWrites::ALL,
                })],
            }),
            multiview_mask: None,
            cache: None,
        });
        let uniforms = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("preview view"),
            size: size_of::<ViewUniforms>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        gpu.check().map_err(|e| e.to_string())?;
        Ok(Running { window, gpu, surface, pipeline, layout, uniforms, texture: None })
    }

    /// Takes the worker's latest image (or its denoised image) if it is not the one shown.
    fn follow_worker(&mut self, event_loop: &ActiveEventLoop) {
        let state = self.shared.lock();
        if state.worker_failed {
            // Its error is printed by the worker.
            drop(state);
            event_loop.exit();
            return;
        }
        let Some(frame) = &state.frame else { return };
        let denoised = state.denoised.as_ref().filter(|(n, _)| state.show_denoised && *n == frame.serial);
        let pixels = denoised.map_or(&frame.pixels, |(_, p)| p);
        let is_denoised = denoised.is_some();
        if self.shown.as_ref().is_some_and(|s| s.serial == frame.serial && s.denoised == is_denoised) {
            return;
        }
        let shown = Shown {
            width: frame.width,
            height: frame.height,
            pixels: Arc::clone(pixels),
            status: frame.status.clone(),
            finished: frame.finished,
            denoised: is_denoised,
            serial: frame.serial,
        };
        drop(state);
        self.upload(&shown);
        self.dump(&shown);
        self.capture_pending = self.setup.dump_dir.is_some();
        self.shown = Some(shown);
        self.redraw();
    }

    /// Puts `shown` into the texture (made again when the size changed).
    fn upload(&mut self, shown: &Shown) {
        let Some(running) = &mut self.running else { return };
        let size = (shown.width, shown.height);
        if running.texture.as_ref().is_none_or(|(_, _, s)| *s != size) {
            let texture = running.gpu.device.create_texture(&wgpu::TextureDescriptor {
                label: Some("preview image"),
                size: wgpu::Extent3d { width: size.0, height: size.1, depth_or_array_layers: 1 },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format: wgpu::TextureFormat::Rgba32Float,
                usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
                view_formats: &[],
            });
            let view = texture.create_view(&wgpu::TextureViewDescriptor::default());
            let group = running.gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("preview"),
                layout: &running.layout,
                entries: &[
                    wgpu::BindGroupEntry { binding: 0, resource: running.uniforms.as_entire_binding() },
                    wgpu::BindGroupEntry { binding: 1, resource: wgpu::BindingResource::TextureView(&view) },
                ],
            });
            running.texture = Some((texture, group, size));
        }
        let Some((texture, _, _)) = &running.texture else { return };
        let texels: Vec<[f32; 4]> = shown.pixels.iter().map(|&[r, g, b]| [r, g, b, 1.0]).collect();
        running.gpu.queue.write_texture(
            wgpu::TexelCopyTextureInfo {
                texture,
                mip_level: 0,
                origin: wgpu::Origin3d::ZERO,
                aspect: wgpu::TextureAspect::All,
            },
            bytemuck::cast_slice(&texels),
            wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(16 * size.0),
                rows_per_image: Some(size.1),
            },
            wgpu::Extent3d { width: size.0, height: size.1, depth_or_array_layers: 1 },
        );
        if self.view.is_none() {
            let inner = running.window.inner_size();
            self.view = Some(View::fit(size, (inner.width, inner.height)));
        }
    }

    /// Writes the image shown to the test folder, if there is one.
    fn dump(&mut self, shown: &Shown) {
        let Some(dir) = &self.setup.dump_dir else { return };
        self.dumped += 1;
        let path = dir.join(format!("frame-{:05}.exr", self.dumped));
        let image = Image::new(shown.width, shown.height, shown.pixels.to_vec());
        if let Err(e) = write_image(&image, &path, false) {
            errln!("warning: cannot write the preview's frame {}: {e}", path.display());
        }
    }

    fn redraw(&self) {
        if let Some(running) = &self.running {
            running.window.request_redraw();
        }
    }

    fn draw(&mut self) -> Result<(), String> {
        let Some(running) = &self.running else { return Ok(()) };
        if running.texture.is_none() || self.view.is_none() {
            return Ok(());
        }
        let frame = match running.surface.acquire(&running.gpu).map_err(|e| e.to_string())? {
            Acquired::Frame(frame) => frame,
            Acquired::Skip => {
                running.window.request_redraw();
                return Ok(());
            }
        };
        let target = running.surface.view(&frame);
        self.paint(&target);
        running.window.pre_present_notify();
        running.gpu.queue.present(frame);
        running.gpu.check().map_err(|e| e.to_string())?;
        if self.capture_pending {
            self.capture_pending = false;
            self.capture();
        }
        Ok(())
    }

    /// Draws the image into `target` (a view in the surface's format, of the window's size).
    fn paint(&self, target: &wgpu::TextureView) {
        let (Some(running), Some(view)) = (&self.running, &self.view) else { return };
        let Some((_, group, size)) = &running.texture else { return };
        let uniforms = ViewUniforms {
            zoom: view.zoom as f32,
            exposure: view.exposure_scale(),
            offset: [view.offset[0] as f32, view.offset[1] as f32],
            size: [size.0 as f32, size.1 as f32],
            pad: [0.0; 2],
        };
        running.gpu.queue.write_buffer(&running.uniforms, 0, bytemuck::bytes_of(&uniforms));
        let mut encoder = running
            .gpu
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("preview") });
        {
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("preview"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: target,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color::BLACK),
                        store: wgpu::StoreOp::Store,
                    },
                })],
                depth_stencil_attachment: None,
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            pass.set_pipeline(&running.pipeline);
            pass.set_bind_group(0, group, &[]);
            pass.draw(0..3, 0..1);
        }
        running.gpu.queue.submit([encoder.finish()]);
    }

    /// Draws the window's picture again off-screen and writes it beside the dumped frame, as
    /// `screen-NNNNN.png` (what the window shows, pixel for pixel).
    fn capture(&self) {
        let (Some(running), Some(dir)) = (&self.running, &self.setup.dump_dir) else { return };
        let (width, height) = running.surface.size();
        let path = dir.join(format!("screen-{:05}.png", self.dumped));
        let result = OffscreenTarget::new(&running.gpu, running.surface.view_format(), width, height)
            .map_err(|e| e.to_string())
            .and_then(|target| {
                self.paint(target.view());
                target.read(&running.gpu).map_err(|e| e.to_string())
            })
            .and_then(|image| image.save(&path).map_err(|e| e.to_string()));
        if let Err(e) = result {
            errln!("warning: cannot write the preview's picture {}: {e}", path.display());
        }
    }

    /// The title: the scene, what the image is, the exposure and the pixel under the cursor.
    fn update_title(&mut self) {
        let Some(running) = &self.running else { return };
        let mut title = format!("rayterra preview - {}", self.setup.title);
        if let Some(shown) = &self.shown {
            title += &format!(" - {}", shown.status);
            if shown.denoised {
                title += " (denoised)";
            }
        }
        if let Some(view) = &self.view {
            if view.exposure_stops != 0 {
                title += &format!(" - exposure {:+}", view.exposure_stops);
            }
            if let Some(shown) = &self.shown
                && let Some((x, y)) = view.pixel_at(self.cursor, (shown.width, shown.height))
            {
                let [r, g, b] = shown.pixels[(y * shown.width + x) as usize];
                title += &format!(" - ({x}, {y}) = {r:.4} {g:.4} {b:.4}");
            }
        }
        if title != self.title {
            running.window.set_title(&title);
            self.title = title;
        }
    }

    fn key(&mut self, event_loop: &ActiveEventLoop, event: &KeyEvent) {
        let PhysicalKey::Code(code) = event.physical_key else { return };
        let pressed = event.state == ElementState::Pressed;
        let flying = self.looking.is_some();
        let motion = match code {
            KeyCode::KeyW => Some(Motion::Forward),
            KeyCode::KeyA | KeyCode::ArrowLeft => Some(Motion::Left),
            KeyCode::ArrowRight => Some(Motion::Right),
            KeyCode::ArrowUp => Some(Motion::Up),
            KeyCode::ArrowDown => Some(Motion::Down),
            // With the right button held, S and D fly; released, they always stop.
            KeyCode::KeyS if flying || !pressed => Some(Motion::Back),
            KeyCode::KeyD if flying || !pressed => Some(Motion::Right),
            _ => None,
        };
        if let Some(motion) = motion {
            self.camera.set_held(motion, pressed);
            self.last_step = Instant::now();
            return;
        }
        match code {
            KeyCode::ShiftLeft | KeyCode::ShiftRight => {
                self.shift = pressed;
                self.camera.set_boost(pressed);
            }
            _ if !pressed || event.repeat => {}
            KeyCode::Escape => event_loop.exit(),
            KeyCode::KeyP => outln!("{}", pose_note(&self.pose, self.setup.syntax, &self.setup.title, "now")),
            KeyCode::KeyS => self.save(),
            KeyCode::KeyD => self.toggle_denoised(),
            KeyCode::KeyE => {
                let shift = self.shift;
                if let Some(view) = &mut self.view {
                    view.step_exposure(!shift);
                }
                self.redraw();
            }
            KeyCode::KeyF => {
                if let (Some(running), Some(shown)) = (&self.running, &self.shown) {
                    let inner = running.window.inner_size();
                    let exposure = self.view.map_or(0, |v| v.exposure_stops);
                    let mut view = View::fit((shown.width, shown.height), (inner.width, inner.height));
                    view.exposure_stops = exposure;
                    self.view = Some(view);
                }
                self.redraw();
            }
            KeyCode::Digit1 => {
                if let Some(view) = &mut self.view {
                    let lines = -view.zoom.ln() / super::view::ZOOM_PER_LINE.ln();
                    view.zoom_at(self.cursor, lines);
                    // Rounding may miss 1:1 by a hair.
                    view.zoom = 1.0;
                    view.offset = [view.offset[0].round(), view.offset[1].round()];
                }
                self.redraw();
            }
            _ => {}
        }
        self.update_title();
    }

    /// `S`: writes the image shown (what the render has so far) beside the output.
    fn save(&self) {
        let Some(shown) = &self.shown else {
            errln!("note: nothing rendered yet to write");
            return;
        };
        let path = &self.setup.save_as;
        let image = Image::new(shown.width, shown.height, shown.pixels.to_vec());
        match write_image(&image, path, self.setup.gamma) {
            Ok(()) => {
                let what =
                    if shown.finished { "the finished render" } else { "the render so far, unfinished" };
                let denoised = if shown.denoised { ", denoised" } else { "" };
                outln!("wrote {}: {what} ({}{denoised})", path.display(), shown.status);
            }
            Err(e) => errln!("warning: cannot write {}: {e}", path.display()),
        }
    }

    /// `D`: the denoised image or the noisy one.
    fn toggle_denoised(&mut self) {
        if !self.setup.can_denoise {
            errln!("note: D shows the denoised image of a render started with --denoise");
            return;
        }
        self.shared.update(|s| s.show_denoised = !s.show_denoised);
        let on = self.shared.lock().show_denoised;
        outln!("preview: {}", if on { "denoised image (once a pass is done)" } else { "noisy image" });
    }

    /// Moves the fly camera by the time since the last step; a new pose goes to the worker.
    fn fly(&mut self) -> bool {
        let now = Instant::now();
        let step = (now - self.last_step).min(Duration::from_millis(250));
        self.last_step = now;
        self.camera.update(step.as_secs_f32(), &Limits::NONE, |_, _| None);
        let moving = self.camera.velocity().length() > 1e-6 * self.setup.speed
            || self.camera.target_velocity() != glam::Vec3::ZERO;
        self.send_pose();
        moving
    }

    /// Sends the fly camera's pose to the worker if it is not the last one sent.
    fn send_pose(&mut self) {
        let pose = pose_of(&self.camera, self.setup.pose.up);
        let last = if self.moved {
            self.pose
        } else {
            pose_of(&fly_camera(&self.setup.pose, self.setup.speed), self.setup.pose.up)
        };
        if pose != last {
            self.moved = true;
            self.pose = pose;
            self.shared.update(|s| s.pose = Some(pose));
        }
    }
}

impl ApplicationHandler<Wake> for App<'_> {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if self.running.is_some() {
            return;
        }
        match self.open(event_loop) {
            Ok(running) => {
                if !self.setup.quiet {
                    outln!("preview on {}; the keys:\n{}", running.gpu.describe(), controls());
                }
                self.running = Some(running);
                self.follow_worker(event_loop);
                self.update_title();
            }
            Err(error) => {
                self.error = Some(error);
                event_loop.exit();
            }
        }
    }

    fn user_event(&mut self, event_loop: &ActiveEventLoop, _: Wake) {
        self.follow_worker(event_loop);
        self.update_title();
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _id: WindowId, event: WindowEvent) {
        match event {
            WindowEvent::CloseRequested => event_loop.exit(),
            WindowEvent::Resized(size) => {
                if let Some(running) = &mut self.running {
                    running.surface.resize(&running.gpu, (size.width, size.height));
                }
                self.redraw();
            }
            WindowEvent::Focused(false) => self.camera.release_all(),
            // Keys winit makes up for what was held when the focus came are not presses.
            WindowEvent::KeyboardInput { event, is_synthetic: false, .. } => self.key(event_loop, &event),
            WindowEvent::ModifiersChanged(modifiers) => self.shift = modifiers.state().shift_key(),
            WindowEvent::MouseWheel { delta, .. } => {
                let lines = match delta {
                    MouseScrollDelta::LineDelta(_, y) => f64::from(y),
                    MouseScrollDelta::PixelDelta(p) => p.y / 40.0,
                };
                if let Some(view) = &mut self.view {
                    view.zoom_at(self.cursor, lines);
                }
                self.redraw();
                self.update_title();
            }
            WindowEvent::MouseInput { state, button, .. } => {
                let pressed = state == ElementState::Pressed;
                match button {
                    MouseButton::Left => self.drag = pressed.then_some(self.cursor),
                    MouseButton::Right => {
                        self.looking = pressed.then_some(self.cursor);
                        if !pressed {
                            self.camera.set_held(Motion::Back, false);
                        }
                    }
                    _ => {}
                }
            }
            WindowEvent::CursorMoved { position, .. } => {
                let cursor = [position.x, position.y];
                if let Some(start) = self.drag {
                    if let Some(view) = &mut self.view {
                        view.pan([cursor[0] - start[0], cursor[1] - start[1]]);
                    }
                    self.drag = Some(cursor);
                    self.redraw();
                }
                if let Some(start) = self.looking {
                    self.camera.turn(cursor[0] - start[0], cursor[1] - start[1]);
                    self.looking = Some(cursor);
                    self.send_pose();
                }
                self.cursor = cursor;
                self.update_title();
            }
            WindowEvent::RedrawRequested => {
                if let Err(error) = self.draw() {
                    self.error = Some(error);
                    event_loop.exit();
                }
            }
            _ => {}
        }
    }

    fn about_to_wait(&mut self, event_loop: &ActiveEventLoop) {
        if self.fly() {
            event_loop.set_control_flow(ControlFlow::WaitUntil(Instant::now() + Duration::from_millis(16)));
        } else {
            event_loop.set_control_flow(ControlFlow::Wait);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_docs_list_every_key() {
        let docs = include_str!("../../../../docs/preview.md");
        for (keys, what) in KEYS {
            assert!(docs.contains(&format!("| {keys} | {what} |")), "docs/preview.md lacks `{keys}`");
        }
        assert_eq!(controls().lines().count(), KEYS.len());
    }
}
