//! The window test: opens the window, draws a few frames and exits. Without a display it runs
//! itself again under `xvfb-run -a` (a virtual X server); without `xvfb-run` it is skipped loudly,
//! or fails under CI. Runs without the test harness: winit wants the main thread.

use std::process::Command;

use terrain::SceneConfig;
use terrain::render::Backend;
use terrain::window::{self, Notice, WindowOptions};
use terrain::world::procedural::{ProceduralOptions, generate};

const INNER: &str = "RAYTERRA_WINDOW_TEST_INNER";

fn under_ci() -> bool {
    std::env::var("CI").is_ok_and(|value| !value.is_empty() && value != "false" && value != "0")
}

fn main() {
    // `cargo test -- --list` and filters that exclude this test: say there is one test.
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.iter().any(|a| a == "--list") {
        println!("opens_draws_and_closes: test");
        return;
    }
    if let Some(filter) = args.iter().find(|a| !a.starts_with('-'))
        && !"opens_draws_and_closes".contains(filter.as_str())
    {
        return;
    }
    if !window::display_available() && std::env::var_os(INNER).is_none() {
        rerun_under_xvfb();
        return;
    }
    opens_draws_and_closes();
}

fn rerun_under_xvfb() {
    let exe = std::env::current_exe().expect("own path");
    eprintln!("no display: running the window test under xvfb-run -a");
    match Command::new("xvfb-run").arg("-a").arg(&exe).env(INNER, "1").status() {
        Ok(status) => assert!(status.success(), "the window test failed under xvfb-run: {status}"),
        Err(error) => {
            let reason = format!("cannot run xvfb-run ({error}); install xvfb and xauth");
            assert!(!under_ci(), "CI=true, so this cannot be skipped: {reason}");
            eprintln!("\n==== SKIPPED window test: {reason} ====\n");
        }
    }
}

fn opens_draws_and_closes() {
    let config = SceneConfig::default();
    let options = ProceduralOptions { seed: 1, heightmap_size: 64 };
    let world = generate(options, &config, &mut |_| {}).expect("world");
    let frames = 5;
    let window_options = WindowOptions {
        backend: Backend::Vulkan,
        size: (320, 180),
        pose: config.camera_start,
        field_of_view_degrees: 45.0,
        start_time_seconds: 0.0,
        max_frames: Some(frames),
        vsync: false,
        screenshot_dir: std::env::temp_dir(),
    };
    let mut adapter = None;
    let result = window::run(&world, &config, window_options, &mut |notice| {
        if let Notice::Adapter(name) = notice {
            eprintln!("adapter: {name}");
            adapter = Some(name);
        }
    });
    match result {
        Ok(summary) => {
            assert_eq!(summary.frames, frames);
            assert!(adapter.is_some(), "the adapter was not reported");
            println!(
                "test opens_draws_and_closes ... ok ({} frames in {:.2} s)",
                summary.frames, summary.seconds
            );
        }
        Err(window::WindowError::Render(error))
            if !under_ci() && error.to_string().contains("no graphics adapter") =>
        {
            eprintln!("\n==== SKIPPED window test: {error} ====\n");
        }
        Err(error) => panic!("the window failed: {error}"),
    }
}
