//! The page's app: winit on the canvas `#terrain`, feeding the fly camera with the window's
//! controls ([`terrain::controls`]) and drawing with the engine's renderer, the tuning panel
//! (F1) over it. The GPU opens asynchronously (a page cannot block) and the world arrives from
//! the worker; until both are there the canvas stays blank and the page shows progress.

use std::cell::RefCell;
use std::path::Path;
use std::rc::Rc;
use std::sync::Arc;

use std::cell::Cell;

use terrain::camera::{CameraPose, FlyCamera, MotionSettings};
use terrain::controls::{self, Action};
use terrain::headless::OffscreenTarget;
use terrain::overlay::Overlay;
use terrain::panel::{Panel, PanelRequests};
use terrain::render::{Acquired, Backend, FrameView, Gpu, PresentSurface, Renderer};
use terrain::settings::ViewSettings;
use terrain::world::World;
use terrain::world::heightfield::height_under;
use terrain::{SceneConfig, Settings};
use wasm_bindgen::JsCast;
use web_time::{Duration, Instant};
use winit::application::ApplicationHandler;
use winit::event::{DeviceEvent, DeviceId, ElementState, KeyEvent, MouseButton, WindowEvent};
use winit::event_loop::{ActiveEventLoop, ControlFlow};
use winit::keyboard::PhysicalKey;
use winit::platform::web::WindowAttributesExtWebSys;
use winit::window::{CursorGrabMode, Fullscreen, Window, WindowId};

use super::{answer_captures, fail, fail_with_status, page, report, take_capture_requests, take_delivered};
use crate::address::{BrowserApi, PageOptions};

/// Where the panel's Save and Load keep the settings: the browser's storage for this site.
const SETTINGS_KEY: &str = "rayterra-terrain-settings";
/// What the panel shows as the settings' place.
const SETTINGS_PLACE: &str = "this browser's storage for the page";

/// The GPU and the canvas's surface, once open.
struct Opened {
    gpu: Gpu,
    surface: wgpu::Surface<'static>,
}

/// Why the GPU did not open: the message, and what the status line says instead of the API.
struct NotOpened {
    message: String,
    status: &'static str,
}

/// Drawing into the canvas.
struct Drawing {
    gpu: Gpu,
    surface: PresentSurface,
    overlay: Overlay,
    /// The renderer of the world being drawn (none before the first world arrives).
    renderer: Option<Renderer>,
}

/// A frame being read back for [`super::capture`].
struct Capture {
    target: OffscreenTarget,
    /// Set when the read-back buffer is mapped (or failed to be).
    mapped: Rc<Cell<Option<Result<(), String>>>>,
    requests: Vec<(js_sys::Function, js_sys::Function)>,
}

/// The page's app.
pub(super) struct PageApp {
    options: PageOptions,
    config: SceneConfig,
    settings: Settings,
    camera: FlyCamera,
    panel: Panel,
    panel_open: bool,
    mouse_captured: bool,
    /// Whether the browser has granted the pointer lock asked for (see [`Self::redraw`]).
    lock_seen: bool,
    window: Option<Arc<Window>>,
    /// Filled by the task that opens the GPU.
    opening: Rc<RefCell<Option<Result<Opened, NotOpened>>>>,
    drawing: Option<Drawing>,
    capture: Option<Capture>,
    world: Option<World>,
    started: Instant,
    last_frame: Option<Instant>,
    last_frame_end: Option<Instant>,
    frames: u64,
    stopped: bool,
}

impl PageApp {
    pub(super) fn new(options: PageOptions) -> Self {
        let camera = FlyCamera::new(options.pose, options.field_of_view_degrees, MotionSettings::default());
        let settings = Settings { look: options.look, ..Settings::default() };
        Self {
            options,
            config: SceneConfig::default(),
            settings,
            camera,
            panel: Panel::default(),
            panel_open: false,
            mouse_captured: false,
            lock_seen: false,
            window: None,
            opening: Rc::new(RefCell::new(None)),
            drawing: None,
            capture: None,
            world: None,
            started: Instant::now(),
            last_frame: None,
            last_frame_end: None,
            frames: 0,
            stopped: false,
        }
    }

    fn stop(&mut self, message: String) {
        self.stopped = true;
        fail(message);
    }

    /// Takes the GPU once the opening task has it, and configures the canvas.
    fn take_gpu(&mut self) {
        if self.drawing.is_some() {
            return;
        }
        let Some(opened) = self.opening.borrow_mut().take() else { return };
        let opened = match opened {
            Ok(opened) => opened,
            Err(NotOpened { message, status }) => {
                self.stopped = true;
                fail_with_status(message, status);
                return;
            }
        };
        let (Some(window), Opened { gpu, surface }) = (self.window.clone(), opened) else { return };
        let size = window.inner_size();
        let present = wgpu::PresentMode::AutoVsync;
        let Some(surface) = PresentSurface::new(&gpu, surface, (size.width, size.height), present) else {
            self.stop(format!("{} cannot draw into the page's canvas", gpu.describe()));
            return;
        };
        let info = gpu.adapter.get_info();
        let api = if info.backend == wgpu::Backend::BrowserWebGpu { "WebGPU" } else { "WebGL2" };
        // Browsers often keep the adapter's name to themselves (WebGPU does).
        let shown = if info.name.is_empty() { api.to_string() } else { format!("{api}: {}", info.name) };
        page::set_text("api", &shown);
        report(|state| {
            state.api = Some(api);
            state.adapter = Some(gpu.describe());
        });
        let overlay = Overlay::new(&window, &gpu, surface.view_format());
        self.drawing = Some(Drawing { gpu, surface, overlay, renderer: None });
    }

    /// Takes a world the worker delivered, with its scene, and makes its renderer when the GPU
    /// is open. The first world keeps the address's camera; a later one (a file) puts the
    /// camera at its own start, which for elevation data suits the data's heights.
    fn take_world(&mut self) {
        if let Some(super::Delivered { world, config, description }) = take_delivered() {
            page::set_text("world", &description);
            let elevation =
                world.elevation.clone().map(|info| (info, world.heightmap.columns(), world.heightmap.rows()));
            if self.world.is_some() {
                let start = config.camera_start;
                let ground = |x, z| height_under(&world.heightmap, &config, x, z);
                let position = config.camera_limits().clamp(start.position, ground);
                let pose = CameraPose::new(position, start.yaw_degrees, start.pitch_degrees);
                self.camera =
                    FlyCamera::new(pose, self.camera.field_of_view_degrees(), MotionSettings::default());
            }
            report(|state| {
                state.world = Some(description);
                state.scene = Some(config.clone());
                state.elevation = elevation;
            });
            self.config = config;
            self.world = Some(world);
            if let Some(drawing) = &mut self.drawing {
                drawing.renderer = None;
            }
        }
        let (Some(drawing), Some(world)) = (&mut self.drawing, &self.world) else { return };
        if drawing.renderer.is_none() {
            let format = drawing.surface.view_format();
            match Renderer::new(&drawing.gpu, world, &self.config, &self.settings, format) {
                Ok(renderer) => drawing.renderer = Some(renderer),
                Err(error) => self.stop(format!("the world cannot be drawn: {error}")),
            }
        }
    }

    fn view(&self) -> FrameView {
        let running = if self.options.paused { 0.0 } else { self.started.elapsed().as_secs_f64() };
        FrameView {
            pose: self.camera.pose(),
            field_of_view_degrees: self.camera.field_of_view_degrees(),
            time_seconds: self.options.start_time_seconds + running,
        }
    }

    fn redraw(&mut self) {
        if self.stopped {
            return;
        }
        self.take_gpu();
        self.take_world();
        // The lock arrives a little after it is asked for; once it has come, its loss means the
        // browser let the pointer go (Esc, or the tab lost focus).
        let locked = page::pointer_locked();
        if self.mouse_captured && self.lock_seen && !locked {
            self.set_mouse_captured(false);
            self.camera.release_all();
        }
        self.lock_seen = self.mouse_captured && locked;
        let now = Instant::now();
        // Long stalls (a hidden tab) do not turn into a leap of the camera.
        let step = self.last_frame.map_or(Duration::ZERO, |last| now - last).min(Duration::from_millis(250));
        self.last_frame = Some(now);
        let limits = self.config.camera_limits();
        let config = &self.config;
        match &self.world {
            Some(world) => self
                .camera
                .update(step.as_secs_f32(), &limits, |x, z| height_under(&world.heightmap, config, x, z)),
            None => self.camera.update(step.as_secs_f32(), &limits, |_, _| None),
        }
        // A running day moves the sun; the renderer follows the settings (`follow_panel`).
        self.settings.sky.run(step.as_secs_f32());
        let view = self.view();
        let Some(window) = self.window.clone() else { return };
        let Some(drawing) = &mut self.drawing else { return };
        let Some(renderer) = &mut drawing.renderer else { return };
        let frame = match drawing.surface.acquire(&drawing.gpu) {
            Ok(Acquired::Frame(frame)) => frame,
            Ok(Acquired::Skip) => return,
            Err(error) => {
                self.stop(error.to_string());
                return;
            }
        };
        let target = drawing.surface.view(&frame);
        let size = drawing.surface.size();
        renderer.draw(&drawing.gpu, &target, size, &view);
        let mut requests = PanelRequests::default();
        if self.panel_open {
            let (panel, settings) = (&mut self.panel, &mut self.settings);
            let wireframe = drawing.gpu.has_wireframe();
            drawing.overlay.run(&window, size, |ctx| {
                requests = panel.show(ctx, settings, Path::new(SETTINGS_PLACE), wireframe);
            });
            drawing.overlay.paint(&drawing.gpu, &target, size);
        }
        window.pre_present_notify();
        drawing.gpu.queue.present(frame);
        if let Err(error) = drawing.gpu.check() {
            self.stop(error.to_string());
            return;
        }
        self.capture(&view, size);
        self.frames += 1;
        let end = Instant::now();
        if let Some(previous) = self.last_frame_end {
            self.panel.record_frame((end - previous).as_secs_f32() * 1000.0);
        }
        self.last_frame_end = Some(end);
        self.follow_panel(requests);
        self.report_frame();
    }

    /// Starts reading a frame back for waiting [`super::capture`] calls, and answers them once
    /// it is read.
    fn capture(&mut self, view: &FrameView, size: (u32, u32)) {
        let Some(drawing) = &mut self.drawing else { return };
        // Map callbacks run when the device is polled (WebGL) or when the browser answers (WebGPU).
        let _ = drawing.gpu.device.poll(wgpu::PollType::Poll);
        if let Some(capture) = &self.capture
            && let Some(mapped) = capture.mapped.take()
        {
            let Some(Capture { target, requests, .. }) = self.capture.take() else { return };
            let image = mapped.and_then(|()| target.mapped_image().map_err(|error| error.to_string()));
            answer_captures(requests, image);
        }
        if self.capture.is_some() {
            return;
        }
        let Some(renderer) = &mut drawing.renderer else { return };
        let requests = take_capture_requests();
        if requests.is_empty() {
            return;
        }
        let target = match OffscreenTarget::new(&drawing.gpu, renderer.target_format(), size.0, size.1) {
            Ok(target) => target,
            Err(error) => {
                answer_captures(requests, Err(error.to_string()));
                return;
            }
        };
        renderer.draw(&drawing.gpu, target.view(), size, view);
        let mapped = Rc::new(Cell::new(None));
        let sink = Rc::clone(&mapped);
        target.request_read(&drawing.gpu, move |result| {
            sink.set(Some(result.map_err(|error| error.to_string())))
        });
        self.capture = Some(Capture { target, mapped, requests });
    }

    fn report_frame(&self) {
        let pose = self.camera.pose();
        let camera =
            [pose.position.x, pose.position.y, pose.position.z, pose.yaw_degrees, pose.pitch_degrees];
        let frames = self.frames;
        report(|state| {
            state.frames = frames;
            state.camera = camera;
        });
        if frames % 15 == 1 {
            page::set_text(
                "camera",
                &format!(
                    "camera {:.2}, {:.2}, {:.2}; yaw {:.0}, pitch {:.0}",
                    camera[0], camera[1], camera[2], camera[3], camera[4]
                ),
            );
        }
    }

    /// Applies settings the panel changed, and its Save and Load (to the browser's storage).
    fn follow_panel(&mut self, requests: PanelRequests) {
        if requests.save {
            self.settings.view = Some(ViewSettings::from(&self.view()));
            let message = match page::store(SETTINGS_KEY, &self.settings.to_toml()) {
                Ok(()) => "saved, with the camera, in this browser".to_string(),
                Err(message) => message,
            };
            self.panel.set_message(message);
        }
        if requests.load {
            let loaded = page::stored(SETTINGS_KEY)
                .ok_or_else(|| "nothing saved in this browser yet".to_string())
                .and_then(|text| {
                    Settings::from_toml(&text, Path::new(SETTINGS_PLACE)).map_err(|error| error.to_string())
                });
            match loaded {
                Ok(settings) => {
                    if let Some(view) = &settings.view {
                        self.camera = view.camera();
                    }
                    self.settings = settings;
                    self.panel.set_message("loaded".into());
                }
                Err(message) => self.panel.set_message(message),
            }
        }
        let (Some(drawing), Some(world)) = (&mut self.drawing, &self.world) else { return };
        if let Some(renderer) = &mut drawing.renderer
            && renderer.settings() != &self.settings
            && let Err(error) = renderer.apply(&drawing.gpu, world, &self.settings)
        {
            self.panel.set_message(error.to_string());
        }
    }

    /// Turns mouse look on (`captured`: the canvas asks for the pointer lock) or off.
    fn set_mouse_captured(&mut self, captured: bool) {
        let Some(window) = &self.window else { return };
        if captured {
            // The browser grants the lock only in answer to a click or a key; where it refuses,
            // the pointer stays free and the camera does not turn.
            self.mouse_captured = window.set_cursor_grab(CursorGrabMode::Locked).is_ok();
        } else {
            let _ = window.set_cursor_grab(CursorGrabMode::None);
            self.mouse_captured = false;
        }
    }

    fn key(&mut self, event: &KeyEvent) {
        let PhysicalKey::Code(code) = event.physical_key else { return };
        let Some(action) = controls::action_for(code) else { return };
        let pressed = event.state == ElementState::Pressed;
        match action {
            Action::Move(motion) => self.camera.set_held(motion, pressed),
            Action::Boost => self.camera.set_boost(pressed),
            _ if !pressed || event.repeat => {}
            // A page does not close itself: Esc frees the mouse (the browser's own meaning).
            Action::Quit => self.set_mouse_captured(false),
            Action::ToggleMouse if self.panel_open => {}
            Action::ToggleMouse => self.set_mouse_captured(!self.mouse_captured),
            Action::TogglePanel => {
                self.panel_open = !self.panel_open;
                if self.panel_open {
                    self.set_mouse_captured(false);
                } else if let Some(drawing) = &mut self.drawing {
                    drawing.overlay.clear();
                }
            }
            Action::ToggleDay => self.settings.sky.day_runs = !self.settings.sky.day_runs,
            // The browser takes screenshots of pages itself.
            Action::Screenshot => {}
            Action::FullScreen => {
                if let Some(window) = &self.window {
                    let full = window.fullscreen().is_some();
                    window.set_fullscreen((!full).then_some(Fullscreen::Borderless(None)));
                }
            }
        }
    }
}

/// Opens the GPU on `window`'s canvas: WebGPU where the browser has it (and `api` allows),
/// WebGL2 otherwise.
async fn open_gpu(window: Arc<Window>, api: BrowserApi) -> Result<Opened, NotOpened> {
    let mut descriptor = wgpu::InstanceDescriptor::new_without_display_handle();
    descriptor.backends = match api {
        BrowserApi::Auto => wgpu::Backends::BROWSER_WEBGPU | wgpu::Backends::GL,
        BrowserApi::WebGl => wgpu::Backends::GL,
    };
    let instance = wgpu::util::new_instance_with_webgpu_detection(descriptor).await;
    let wanted = match api {
        BrowserApi::Auto => "neither WebGPU nor WebGL2",
        BrowserApi::WebGl => "no WebGL2 (the address's `api=webgl` leaves WebGPU out)",
    };
    let neither = |reason: String| NotOpened {
        message: format!(
            "This browser offers {wanted} to the page ({reason}), so the terrain cannot be drawn. \
             Try a current Chrome, Edge, Firefox or Safari with hardware acceleration turned on."
        ),
        status: "no WebGPU or WebGL2",
    };
    let surface = instance.create_surface(window).map_err(|error| neither(error.to_string()))?;
    let gpu =
        Gpu::open_async(instance, Backend::Auto, Some(&surface)).await.map_err(|error| match error {
            terrain::render::GpuError::NoAdapter { reason, .. } => neither(reason),
            other => NotOpened { message: other.to_string(), status: "the GPU did not open (see below)" },
        })?;
    Ok(Opened { gpu, surface })
}

impl ApplicationHandler for PageApp {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if self.window.is_some() {
            return;
        }
        event_loop.set_control_flow(ControlFlow::Wait);
        let canvas = web_sys::window()
            .and_then(|window| window.document())
            .and_then(|document| document.get_element_by_id("terrain"))
            .and_then(|element| element.dyn_into::<web_sys::HtmlCanvasElement>().ok());
        let Some(canvas) = canvas else {
            self.stop("the page has no canvas with id `terrain`".into());
            return;
        };
        let attributes = Window::default_attributes()
            .with_canvas(Some(canvas))
            .with_prevent_default(true)
            .with_focusable(true);
        let window = match event_loop.create_window(attributes) {
            Ok(window) => Arc::new(window),
            Err(error) => {
                self.stop(format!("cannot draw on the page: {error}"));
                return;
            }
        };
        window.focus_window();
        let (slot, api, opening) = (Rc::clone(&self.opening), self.options.api, Arc::clone(&window));
        wasm_bindgen_futures::spawn_local(async move {
            let opened = open_gpu(opening, api).await;
            *slot.borrow_mut() = Some(opened);
        });
        window.request_redraw();
        self.window = Some(window);
    }

    fn window_event(&mut self, _event_loop: &ActiveEventLoop, _id: WindowId, event: WindowEvent) {
        if self.panel_open
            && let (Some(drawing), Some(window)) = (&mut self.drawing, &self.window)
            && drawing.overlay.takes(window, &event)
        {
            return;
        }
        match event {
            WindowEvent::Resized(size) => {
                if let Some(drawing) = &mut self.drawing {
                    drawing.surface.resize(&drawing.gpu, (size.width, size.height));
                }
            }
            WindowEvent::Focused(false) => {
                self.camera.release_all();
                self.set_mouse_captured(false);
            }
            WindowEvent::KeyboardInput { event, .. } => self.key(&event),
            WindowEvent::MouseInput { state: ElementState::Pressed, button: MouseButton::Left, .. }
                if !self.mouse_captured && !self.panel_open =>
            {
                self.set_mouse_captured(true)
            }
            WindowEvent::MouseWheel { delta, .. } => self.camera.zoom(controls::scroll_lines(delta)),
            WindowEvent::RedrawRequested => {
                self.redraw();
                if let Some(window) = &self.window {
                    window.request_redraw();
                }
            }
            _ => {}
        }
    }

    fn device_event(&mut self, _event_loop: &ActiveEventLoop, _id: DeviceId, event: DeviceEvent) {
        if let DeviceEvent::MouseMotion { delta } = event
            && self.mouse_captured
        {
            self.camera.turn(delta.0, delta.1);
        }
    }
}
