//! The interactive window: a winit event loop feeding the fly camera and drawing with the same
//! renderer as the off-screen path, with the tuning panel ([`crate::panel`], egui) over it.
//!
//! The keys are in [`controls::BINDINGS`]; the mouse looks around while captured, the scroll
//! wheel zooms. While the panel is open the mouse is free for it, and Tab moves between its
//! widgets.

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::{Duration, Instant};

use winit::application::ApplicationHandler;
use winit::dpi::PhysicalSize;
use winit::event::{DeviceEvent, DeviceId, ElementState, KeyEvent, MouseButton, WindowEvent};
use winit::event_loop::{ActiveEventLoop, ControlFlow, EventLoop};
use winit::keyboard::PhysicalKey;
use winit::window::{CursorGrabMode, Fullscreen, Window, WindowId};

use crate::camera::{CameraPose, FlyCamera, MotionSettings};
use crate::config::SceneConfig;
use crate::controls::{self, Action};
use crate::headless::OffscreenTarget;
use crate::output::{SaveError, save_image};
use crate::overlay::Overlay;
use crate::panel::{Panel, PanelRequests};
use crate::render::{
    Acquired, Backend, FrameView, Gpu, GpuError, GpuMemory, PresentSurface, RenderError, Renderer,
};
use crate::settings::{Settings, ViewSettings};
use crate::world::World;
use crate::world::heightfield::height_under;

/// How to open the window.
#[derive(Debug, Clone, PartialEq)]
pub struct WindowOptions {
    /// Graphics backend.
    pub backend: Backend,
    /// Initial inner size in physical pixels.
    pub size: (u32, u32),
    /// Where the camera starts.
    pub pose: CameraPose,
    /// Initial vertical field of view in degrees.
    pub field_of_view_degrees: f32,
    /// Scene time at start, in seconds (the water's clock then runs in real time).
    pub start_time_seconds: f64,
    /// Quit after drawing this many frames (`None`: run until the user quits).
    pub max_frames: Option<u64>,
    /// Wait for the display's refresh between frames.
    pub vsync: bool,
    /// Folder where screenshots are saved.
    pub screenshot_dir: PathBuf,
    /// How the frames look, at start.
    pub settings: Settings,
    /// Where the panel saves (and loads) the settings.
    pub settings_path: PathBuf,
}

/// Something the user should hear about while the window runs.
#[derive(Debug, Clone, PartialEq)]
pub enum Notice {
    /// The GPU is ready; the adapter's description.
    Adapter(String),
    /// A screenshot was saved to this file.
    ScreenshotSaved(PathBuf),
    /// A screenshot could not be saved; why.
    ScreenshotFailed(String),
    /// The mouse was captured for looking around (`true`) or released (`false`).
    MouseCaptured(bool),
    /// What the renderer holds on the GPU, and its level-of-detail tree on the CPU (bytes).
    GpuMemory {
        /// GPU memory.
        memory: GpuMemory,
        /// CPU memory of the tree.
        tree_bytes: usize,
    },
    /// The panel saved the settings to this file.
    SettingsSaved(PathBuf),
    /// The panel could not save or load the settings; why.
    SettingsFailed(String),
}

/// How a window session went.
#[derive(Debug, Clone, PartialEq)]
pub struct WindowSummary {
    /// Frames drawn.
    pub frames: u64,
    /// Where the camera was when the window closed.
    pub pose: CameraPose,
    /// The vertical field of view when the window closed, in degrees.
    pub field_of_view_degrees: f32,
    /// Wall-clock time from the start of the first frame to the end of the last, in seconds
    /// (setting up the window and the GPU is not counted).
    pub seconds: f64,
    /// The settings when the window closed (the panel may have changed them).
    pub settings: Settings,
}

/// Why the window could not run.
#[derive(Debug, thiserror::Error)]
pub enum WindowError {
    /// There is no display to open a window on.
    #[error("no display to open a window on ({0})")]
    NoDisplay(String),
    /// The windowing system failed.
    #[error("the window system failed: {0}")]
    System(String),
    /// The GPU could not present to the window.
    #[error("the GPU cannot draw into the window: {0}")]
    Surface(String),
    /// Setting up or drawing with the GPU failed.
    #[error(transparent)]
    Render(#[from] RenderError),
}

impl From<GpuError> for WindowError {
    fn from(error: GpuError) -> Self {
        WindowError::Render(error.into())
    }
}

/// Whether a display server seems to be available (on Linux and BSD: `DISPLAY`,
/// `WAYLAND_DISPLAY` or `WAYLAND_SOCKET` is set; elsewhere always).
pub fn display_available() -> bool {
    if cfg!(all(unix, not(target_os = "macos"), not(target_os = "ios"), not(target_os = "android"))) {
        ["DISPLAY", "WAYLAND_DISPLAY", "WAYLAND_SOCKET"]
            .iter()
            .any(|name| std::env::var_os(name).is_some_and(|value| !value.is_empty()))
    } else {
        true
    }
}

/// Opens a window on `world` and runs until the user quits (or `max_frames` frames are drawn).
/// `notice` hears about the adapter, screenshots and the mouse.
pub fn run(
    world: &World,
    config: &SceneConfig,
    options: WindowOptions,
    notice: &mut dyn FnMut(Notice),
) -> Result<WindowSummary, WindowError> {
    if !display_available() {
        return Err(WindowError::NoDisplay("neither DISPLAY nor WAYLAND_DISPLAY is set".into()));
    }
    let event_loop = EventLoop::new().map_err(|error| match error {
        winit::error::EventLoopError::Os(os) => WindowError::NoDisplay(os.to_string()),
        other => WindowError::System(other.to_string()),
    })?;
    event_loop.set_control_flow(ControlFlow::Poll);
    let camera = FlyCamera::new(options.pose, options.field_of_view_degrees, MotionSettings::default());
    let settings = options.settings.clone();
    let mut app = App {
        settings,
        panel: Panel::default(),
        panel_open: false,
        world,
        config,
        options,
        notice,
        camera,
        running: None,
        error: None,
        started: Instant::now(),
        last_frame: None,
        first_frame: None,
        last_frame_end: None,
        frames: 0,
        mouse_captured: false,
        capture_on_focus: false,
        title_frames: 0,
        title_since: Instant::now(),
        screenshots_taken: 0,
    };
    event_loop.run_app(&mut app).map_err(|error| WindowError::System(error.to_string()))?;
    match app.error {
        Some(error) => Err(error),
        None => Ok(WindowSummary {
            frames: app.frames,
            pose: app.camera.pose(),
            field_of_view_degrees: app.camera.field_of_view_degrees(),
            seconds: app
                .first_frame
                .zip(app.last_frame_end)
                .map_or(0.0, |(first, last)| (last - first).as_secs_f64()),
            settings: app.settings,
        }),
    }
}

/// What exists once the window is open.
struct Running {
    window: Arc<Window>,
    surface: PresentSurface,
    gpu: Gpu,
    renderer: Renderer,
    gui: Overlay,
}

struct App<'a> {
    /// The settings the panel edits (the renderer follows them).
    settings: Settings,
    panel: Panel,
    panel_open: bool,
    world: &'a World,
    config: &'a SceneConfig,
    options: WindowOptions,
    notice: &'a mut dyn FnMut(Notice),
    camera: FlyCamera,
    running: Option<Running>,
    error: Option<WindowError>,
    started: Instant,
    last_frame: Option<Instant>,
    first_frame: Option<Instant>,
    last_frame_end: Option<Instant>,
    frames: u64,
    mouse_captured: bool,
    /// Whether to capture the mouse when the window gets the focus back.
    capture_on_focus: bool,
    title_frames: u32,
    title_since: Instant,
    screenshots_taken: u32,
}

const TITLE: &str = "rayterra terrain";

impl App<'_> {
    fn fail(&mut self, event_loop: &ActiveEventLoop, error: WindowError) {
        self.error.get_or_insert(error);
        event_loop.exit();
    }

    fn open(&mut self, event_loop: &ActiveEventLoop) -> Result<Running, WindowError> {
        let (width, height) = self.options.size;
        let attributes =
            Window::default_attributes().with_title(TITLE).with_inner_size(PhysicalSize::new(width, height));
        let window = Arc::new(
            event_loop.create_window(attributes).map_err(|error| WindowError::System(error.to_string()))?,
        );
        let instance = Gpu::instance(self.options.backend, Some(Box::new(event_loop.owned_display_handle())));
        let surface = instance
            .create_surface(Arc::clone(&window))
            .map_err(|error| WindowError::Surface(error.to_string()))?;
        let gpu = Gpu::open(instance, self.options.backend, Some(&surface))?;
        (self.notice)(Notice::Adapter(gpu.describe()));
        let present_mode =
            if self.options.vsync { wgpu::PresentMode::AutoVsync } else { wgpu::PresentMode::AutoNoVsync };
        let size = window.inner_size();
        let surface = PresentSurface::new(&gpu, surface, (size.width, size.height), present_mode)
            .ok_or_else(|| {
                WindowError::Surface(format!("{} cannot present to this window", gpu.describe()))
            })?;
        let view_format = surface.view_format();
        let renderer = Renderer::new(&gpu, self.world, self.config, &self.settings, view_format)?;
        (self.notice)(Notice::GpuMemory { memory: renderer.gpu_memory(), tree_bytes: renderer.cpu_bytes() });
        let gui = Overlay::new(&window, &gpu, view_format);
        Ok(Running { window, surface, gpu, renderer, gui })
    }

    /// Turns mouse look on (`captured`) or off. Grabbing and hiding the cursor is best effort:
    /// where the windowing system refuses, the mouse still turns the view.
    fn set_mouse_captured(&mut self, captured: bool) {
        let Some(running) = &self.running else {
            return;
        };
        let window = &running.window;
        let grabbed = captured
            && window
                .set_cursor_grab(CursorGrabMode::Locked)
                .or_else(|_| window.set_cursor_grab(CursorGrabMode::Confined))
                .is_ok();
        if !captured {
            let _ = window.set_cursor_grab(CursorGrabMode::None);
        }
        window.set_cursor_visible(!grabbed);
        if captured != self.mouse_captured {
            self.mouse_captured = captured;
            (self.notice)(Notice::MouseCaptured(captured));
        }
    }

    fn key(&mut self, event_loop: &ActiveEventLoop, event: &KeyEvent) {
        let PhysicalKey::Code(code) = event.physical_key else {
            return;
        };
        let Some(action) = controls::action_for(code) else {
            return;
        };
        let pressed = event.state == ElementState::Pressed;
        match action {
            Action::Move(motion) => self.camera.set_held(motion, pressed),
            Action::Boost => self.camera.set_boost(pressed),
            // The others happen once per press.
            _ if !pressed || event.repeat => {}
            Action::Quit => event_loop.exit(),
            // With the panel open the mouse is the panel's, and Tab moves between its widgets.
            Action::ToggleMouse if self.panel_open => {}
            Action::ToggleMouse => self.set_mouse_captured(!self.mouse_captured),
            Action::TogglePanel => self.toggle_panel(),
            Action::ToggleDay => self.settings.sky.day_runs = !self.settings.sky.day_runs,
            Action::Screenshot => self.screenshot(),
            Action::FullScreen => {
                if let Some(running) = &self.running {
                    let full = running.window.fullscreen().is_some();
                    running.window.set_fullscreen((!full).then_some(Fullscreen::Borderless(None)));
                }
            }
        }
    }

    fn toggle_panel(&mut self) {
        self.panel_open = !self.panel_open;
        if self.panel_open {
            self.capture_on_focus = false;
            self.set_mouse_captured(false);
        } else if let Some(running) = &mut self.running {
            running.gui.clear();
        }
    }

    /// Applies settings the panel changed, and its Save and Load.
    fn follow_panel(&mut self, requests: PanelRequests) {
        if requests.save {
            self.settings.view = Some(ViewSettings::from(&self.view()));
            match self.settings.save(&self.options.settings_path) {
                Ok(()) => {
                    self.panel.set_message(format!(
                        "saved, with the camera ({})",
                        self.options.settings_path.display()
                    ));
                    (self.notice)(Notice::SettingsSaved(self.options.settings_path.clone()));
                }
                Err(error) => {
                    self.panel.set_message(error.to_string());
                    (self.notice)(Notice::SettingsFailed(error.to_string()));
                }
            }
        }
        if requests.load {
            match Settings::load(&self.options.settings_path) {
                Ok(settings) => {
                    if let Some(view) = &settings.view {
                        self.camera = view.camera();
                    }
                    self.settings = settings;
                    self.panel.set_message("loaded".into());
                }
                Err(error) => {
                    self.panel.set_message(error.to_string());
                    (self.notice)(Notice::SettingsFailed(error.to_string()));
                }
            }
        }
        let Some(running) = &mut self.running else { return };
        if running.renderer.settings() != &self.settings
            && let Err(error) = running.renderer.apply(&running.gpu, self.world, &self.settings)
        {
            self.panel.set_message(error.to_string());
        }
    }

    fn view(&self) -> FrameView {
        FrameView {
            pose: self.camera.pose(),
            field_of_view_degrees: self.camera.field_of_view_degrees(),
            time_seconds: self.options.start_time_seconds + self.started.elapsed().as_secs_f64(),
        }
    }

    fn screenshot(&mut self) {
        let view = self.view();
        let Some(running) = &mut self.running else {
            return;
        };
        let size = running.surface.size();
        let result = (|| -> Result<PathBuf, String> {
            let target = OffscreenTarget::new(&running.gpu, running.renderer.target_format(), size.0, size.1)
                .map_err(|error| error.to_string())?;
            running.renderer.draw(&running.gpu, target.view(), size, &view);
            // What the window shows: the panel too, when it is open.
            running.gui.paint(&running.gpu, target.view(), size);
            let image = target.read(&running.gpu).map_err(|error| error.to_string())?;
            let path = free_screenshot_path(&self.options.screenshot_dir, self.screenshots_taken);
            save_image(&image.into(), &path, image::ImageFormat::Png)
                .map_err(|error: SaveError| error.to_string())?;
            Ok(path)
        })();
        match result {
            Ok(path) => {
                self.screenshots_taken += 1;
                (self.notice)(Notice::ScreenshotSaved(path));
            }
            Err(message) => (self.notice)(Notice::ScreenshotFailed(message)),
        }
    }

    fn redraw(&mut self, event_loop: &ActiveEventLoop) {
        let now = Instant::now();
        // Long stalls (a window drag, a breakpoint) do not turn into a leap of the camera.
        let step = self.last_frame.map_or(Duration::ZERO, |last| now - last).min(Duration::from_millis(250));
        self.last_frame = Some(now);
        self.first_frame.get_or_insert(now);
        let limits = self.config.camera_limits();
        // One query a frame, read from the heightmap itself: no full-resolution copy of the
        // heights (268 MB at 8193 samples a side) is kept for it.
        let (heightmap, config) = (&self.world.heightmap, self.config);
        self.camera.update(step.as_secs_f32(), &limits, |x, z| height_under(heightmap, config, x, z));
        // A running day moves the sun; the renderer follows the settings below.
        self.settings.sky.run(step.as_secs_f32());
        let view = self.view();
        let Some(running) = &mut self.running else {
            return;
        };
        let frame = match running.surface.acquire(&running.gpu) {
            Ok(Acquired::Frame(frame)) => frame,
            Ok(Acquired::Skip) => return,
            Err(error) => {
                self.fail(event_loop, error.into());
                return;
            }
        };
        let target = running.surface.view(&frame);
        let size = running.surface.size();
        running.renderer.draw(&running.gpu, &target, size, &view);
        let mut requests = PanelRequests::default();
        if self.panel_open {
            let (panel, settings) = (&mut self.panel, &mut self.settings);
            let file = self.options.settings_path.as_path();
            let wireframe = running.gpu.has_wireframe();
            running
                .gui
                .run(&running.window, size, |ctx| requests = panel.show(ctx, settings, file, wireframe));
            running.gui.paint(&running.gpu, &target, size);
        }
        running.window.pre_present_notify();
        running.gpu.queue.present(frame);
        if let Err(error) = running.gpu.check() {
            self.fail(event_loop, error.into());
            return;
        }
        self.frames += 1;
        let end = Instant::now();
        if let Some(previous) = self.last_frame_end {
            self.panel.record_frame((end - previous).as_secs_f32() * 1000.0);
        }
        self.last_frame_end = Some(end);
        self.update_title();
        self.follow_panel(requests);
        if self.options.max_frames.is_some_and(|max| self.frames >= max) {
            event_loop.exit();
        }
    }

    fn update_title(&mut self) {
        self.title_frames += 1;
        let elapsed = self.title_since.elapsed();
        if elapsed < Duration::from_millis(500) {
            return;
        }
        if let Some(running) = &self.running {
            let milliseconds = elapsed.as_secs_f64() * 1000.0 / f64::from(self.title_frames);
            let hint =
                if self.mouse_captured { "Tab releases the mouse" } else { "click or Tab to look around" };
            running.window.set_title(&format!(
                "{TITLE} - {milliseconds:.1} ms/frame ({:.0} fps) - {hint}",
                1000.0 / milliseconds
            ));
        }
        self.title_frames = 0;
        self.title_since = Instant::now();
    }
}

/// `rayterra-terrain-NNN.png` in `dir`, the first number from `from` that names no file yet.
fn free_screenshot_path(dir: &Path, from: u32) -> PathBuf {
    (from + 1..)
        .map(|n| dir.join(format!("rayterra-terrain-{n:03}.png")))
        .find(|path| !path.exists())
        .unwrap_or_else(|| dir.join("rayterra-terrain.png"))
}

impl ApplicationHandler for App<'_> {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if self.running.is_some() {
            return;
        }
        match self.open(event_loop) {
            Ok(running) => {
                self.running = Some(running);
                self.set_mouse_captured(true);
            }
            Err(error) => self.fail(event_loop, error),
        }
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _id: WindowId, event: WindowEvent) {
        // The panel sees input first; what it uses (typing, clicks on it) is not for the scene.
        if self.panel_open
            && let Some(running) = &mut self.running
        {
            let for_panel = running.gui.takes(&running.window, &event);
            if for_panel {
                return;
            }
        }
        match event {
            WindowEvent::CloseRequested => event_loop.exit(),
            WindowEvent::Resized(size) => {
                if let Some(running) = &mut self.running {
                    running.surface.resize(&running.gpu, (size.width, size.height));
                }
            }
            WindowEvent::Focused(false) => {
                // Leaving the window frees the mouse; coming back captures it again if it was.
                self.capture_on_focus = self.mouse_captured;
                self.camera.release_all();
                self.set_mouse_captured(false);
            }
            WindowEvent::Focused(true) if self.capture_on_focus => self.set_mouse_captured(true),
            WindowEvent::KeyboardInput { event, .. } => self.key(event_loop, &event),
            WindowEvent::MouseInput { state: ElementState::Pressed, button: MouseButton::Left, .. }
                if !self.mouse_captured && !self.panel_open =>
            {
                self.set_mouse_captured(true)
            }
            WindowEvent::MouseWheel { delta, .. } => self.camera.zoom(controls::scroll_lines(delta)),
            WindowEvent::RedrawRequested => self.redraw(event_loop),
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

    fn about_to_wait(&mut self, _event_loop: &ActiveEventLoop) {
        if let Some(running) = &self.running {
            running.window.request_redraw();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn screenshot_names_skip_existing_files() {
        let dir = std::env::temp_dir().join(format!("rayterra-shots-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("temp dir");
        std::fs::write(dir.join("rayterra-terrain-001.png"), b"taken").expect("write");
        assert_eq!(free_screenshot_path(&dir, 0), dir.join("rayterra-terrain-002.png"));
        assert_eq!(free_screenshot_path(&dir, 4), dir.join("rayterra-terrain-005.png"));
        let _ = std::fs::remove_dir_all(&dir);
    }
}
