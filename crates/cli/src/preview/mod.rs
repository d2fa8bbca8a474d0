//! `rayterra render --preview`: the render in a window as it converges, with a fly camera.
//!
//! Two threads: the render runs on a worker ([`worker`]) through the ray tracer's
//! [`raytracer::render::render_watched`], which hands out the image after every batch of
//! samples, pass or block of rows; the window ([`window`], winit and wgpu on the main thread,
//! as winit wants) shows the latest image and sends the camera's new poses back. They meet in
//! [`Shared`]. Without a display, or when the window cannot be opened, the worker renders on
//! its own and writes the same output.

mod fly;
mod pose;
mod view;
mod window;
mod worker;

use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::{Arc, Condvar, Mutex, MutexGuard};
use std::time::Duration;

use raytracer::prepare::Hit;
use raytracer::{PreparedScene, RenderSettings};

pub use pose::PoseSyntax;
use pose::{Pose, pose_note};

use crate::oidn::Oidn;
use crate::render::RenderArgs;

/// The environment variable naming a folder where the window writes every image it shows, as
/// `frame-00001.exr` and on (linear values, as displayed before exposure): for tests.
pub const DUMP_FRAMES_ENV: &str = "RAYTERRA_PREVIEW_FRAMES";

/// What the preview needs of `rayterra render`.
pub struct Job<'a> {
    /// The command line.
    pub args: &'a RenderArgs,
    /// The scene's name, for the title and notes.
    pub scene_name: String,
    /// The prepared scene (the worker moves its camera).
    pub prepared: PreparedScene,
    /// The render's settings.
    pub settings: RenderSettings,
    /// The denoiser, with `--denoise`.
    pub denoiser: Option<Oidn>,
    /// How long loading the scene took, for the summary.
    pub prepare_time: Duration,
    /// The syntax poses are printed in.
    pub syntax: PoseSyntax,
}

/// An image the worker hands to the window.
#[derive(Clone, Debug)]
struct Frame {
    width: u32,
    height: u32,
    /// Linear RGB, row by row from the top.
    pixels: Arc<Vec<[f32; 3]>>,
    /// What the image is (samples, passes or rows so far; time; rays a second).
    status: String,
    /// Whether it is a finished render.
    finished: bool,
    /// Counts the frames handed out, from 1.
    serial: u64,
}

/// What the worker and the window share.
#[derive(Debug, Default)]
struct State {
    /// The latest image.
    frame: Option<Frame>,
    /// The denoised image of the frame with this serial.
    denoised: Option<(u64, Arc<Vec<[f32; 3]>>)>,
    /// Whether the window shows the denoised image (`D`).
    show_denoised: bool,
    /// A new camera pose to render from.
    pose: Option<Pose>,
    /// The window is closed (or was never opened): render the current pose to the end, write
    /// it, and stop.
    window_gone: bool,
    /// The worker has stopped.
    worker_done: bool,
    /// The worker stopped on an error (said on the terminal): the window closes.
    worker_failed: bool,
}

/// [`State`] behind a lock, with a signal for the worker waiting for a new pose.
#[derive(Debug, Default)]
struct Shared {
    state: Mutex<State>,
    changed: Condvar,
}

impl Shared {
    fn lock(&self) -> MutexGuard<'_, State> {
        self.state.lock().unwrap_or_else(|poisoned| poisoned.into_inner())
    }

    /// Changes the state and wakes the worker.
    fn update(&self, change: impl FnOnce(&mut State)) {
        change(&mut self.lock());
        self.changed.notify_all();
    }
}

/// Runs the render with the preview window (or without it when there is no display) and
/// writes the output as `rayterra render` does.
pub fn run(job: Job<'_>) -> Result<(), ExitCode> {
    let shared = Shared::default();
    let scene_pose = Pose::of_camera(&job.prepared.scene.camera);
    let setup = window::Setup {
        title: job.scene_name.clone(),
        image: (job.settings.width, job.settings.height),
        save_as: so_far_path(&job.args.output),
        gamma: job.args.gamma,
        dump_dir: std::env::var_os(DUMP_FRAMES_ENV).map(PathBuf::from),
        pose: scene_pose,
        speed: fly_speed(&job.prepared, &job.settings),
        syntax: job.syntax,
        can_denoise: job.denoiser.is_some(),
        quiet: job.args.quiet,
    };
    let event_loop = if terrain::window::display_available() {
        window::event_loop()
    } else {
        Err("neither DISPLAY nor WAYLAND_DISPLAY is set".to_owned())
    };
    let event_loop = match event_loop {
        Ok(event_loop) => event_loop,
        Err(reason) => {
            no_window(&reason);
            shared.update(|s| s.window_gone = true);
            return worker::work(&shared, job, &|| {});
        }
    };
    let waker = event_loop.create_proxy();
    let wake = move || {
        // The window may be gone: nobody to wake then.
        let _ = waker.send_event(window::Wake);
    };
    std::thread::scope(|scope| {
        let rendering = scope.spawn(|| {
            let result = worker::work(&shared, job, &wake);
            shared.update(|s| {
                s.worker_done = true;
                s.worker_failed = result.is_err();
            });
            wake();
            result
        });
        let shown = window::run(event_loop, &shared, &setup);
        shared.update(|s| s.window_gone = true);
        match shown {
            Ok(end) => {
                outln!("{}", pose_note(&end.pose, setup.syntax, &setup.title, "when the window closed"));
                if !shared.lock().worker_done {
                    errln!("note: the preview window is closed; the render goes on (Ctrl-C stops it)");
                }
            }
            Err(reason) => no_window(&reason),
        }
        rendering.join().unwrap_or_else(|_| {
            errln!("error: internal error: the render thread panicked");
            Err(ExitCode::FAILURE)
        })
    })
}

/// Says that the render goes on without a window, and why.
fn no_window(reason: &str) {
    errln!("note: no preview window ({reason}); the render goes on without it and writes the same output");
}

/// The file `S` writes the image so far to: `render.png` gives `render.so-far.png`.
fn so_far_path(output: &Path) -> PathBuf {
    let stem = output.file_stem().map_or_else(|| "render".into(), |s| s.to_string_lossy().into_owned());
    let name = match output.extension() {
        Some(ext) => format!("{stem}.so-far.{}", ext.to_string_lossy()),
        None => format!("{stem}.so-far"),
    };
    output.with_file_name(name)
}

/// The fly camera's top speed: half the distance to what the camera sees at the image centre
/// a second (1 scene unit a second when it sees nothing).
fn fly_speed(scene: &PreparedScene, settings: &RenderSettings) -> f32 {
    let camera = raytracer::render::camera_for(scene, settings);
    let distance = match scene.closest_hit(&camera.central_ray()) {
        Hit::Surface { hit, .. } => hit.t,
        Hit::Emitter { t, .. } => t,
        Hit::Miss => 2.0,
    };
    (0.5 * distance).clamp(1e-3, 1e6) as f32
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_image_so_far_is_named_beside_the_output() {
        assert_eq!(so_far_path(Path::new("out/box.png")), Path::new("out/box.so-far.png"));
        assert_eq!(so_far_path(Path::new("box.exr")), Path::new("box.so-far.exr"));
    }
}
