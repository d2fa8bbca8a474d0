//! The window test: opens the window, draws frames, follows real keyboard, mouse and scroll input
//! (sent by xdotool) and closes on Esc. Without a display it runs itself again under
//! `xvfb-run -a` (a virtual X server); without `xvfb-run` it is skipped loudly, or fails under CI.
//! Runs without the test harness: winit wants the main thread.

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
    let run = test_skips::run_id().to_string();
    match Command::new("xvfb-run")
        .arg("-a")
        .arg(&exe)
        .env(INNER, "1")
        .env(test_skips::RUN_VARIABLE, run)
        .status()
    {
        Ok(status) => assert!(status.success(), "the window test failed under xvfb-run: {status}"),
        Err(error) => {
            let reason = format!("cannot run xvfb-run ({error}); install xvfb and xauth");
            assert!(!under_ci(), "CI=true, so this cannot be skipped: {reason}");
            test_skips::skip("terrain window test", &reason);
        }
    }
}

/// What the input test does, as one xdotool command: wait for the window, focus it, hold W, move
/// the mouse right, turn the scroll wheel away from the user (button 4), press Esc.
const INPUT_SCRIPT: &str = "search --sync --onlyvisible --name ^rayterra.terrain windowfocus --sync %1 \
    mousemove --window %1 160 90 sleep 0.3 keydown w sleep 0.6 keyup w sleep 0.2 \
    mousemove_relative -- 60 0 sleep 0.3 click 4 sleep 0.3 key Escape";

/// Drives the window with real X input events (xdotool, through the XTEST extension) and says
/// what went wrong, if anything.
fn drive_input() -> Result<(), String> {
    // `timeout` keeps a stuck search from hanging the test; the window's frame cap ends it too.
    let output = Command::new("timeout")
        .args(["60", "xdotool"])
        .args(INPUT_SCRIPT.split_whitespace())
        .output()
        .map_err(|error| format!("cannot run xdotool: {error}"))?;
    if output.status.success() {
        Ok(())
    } else {
        Err(format!("xdotool failed ({}): {}", output.status, String::from_utf8_lossy(&output.stderr)))
    }
}

/// Whether xdotool is installed; without it the input half of the test is skipped loudly (a
/// failure under CI).
fn have_xdotool() -> bool {
    let found = Command::new("xdotool").arg("version").output().is_ok_and(|o| o.status.success());
    if !found {
        let reason = "xdotool is not installed, so keyboard and mouse input is not tested";
        assert!(!under_ci(), "CI=true, so this cannot be skipped: {reason}");
        test_skips::skip("terrain window test (input)", reason);
    }
    found
}

fn opens_draws_and_closes() {
    let config = SceneConfig::default();
    let options = ProceduralOptions { seed: 1, heightmap_size: 64 };
    let world = generate(options, &config, &mut |_| {}).expect("world");
    let driven = have_xdotool();
    // Driven by input, the window runs until Esc; the frame cap only stops a test gone wrong.
    let frames = if driven { 20_000 } else { 5 };
    let start = config.camera_start;
    let window_options = WindowOptions {
        backend: Backend::Vulkan,
        size: (320, 180),
        pose: start,
        field_of_view_degrees: 45.0,
        start_time_seconds: 0.0,
        max_frames: Some(frames),
        vsync: false,
        screenshot_dir: std::env::temp_dir(),
    };
    let driver = driven.then(|| std::thread::spawn(drive_input));
    let mut adapter = None;
    let result = window::run(&world, &config, window_options, &mut |notice| {
        if let Notice::Adapter(name) = notice {
            eprintln!("adapter: {name}");
            adapter = Some(name);
        }
    });
    let input = driver.map(|thread| thread.join().expect("the input thread panicked"));
    match result {
        Ok(summary) => {
            assert!(adapter.is_some(), "the adapter was not reported");
            match input {
                None => assert_eq!(summary.frames, frames),
                Some(Err(error)) => panic!("{error}"),
                Some(Ok(())) => {
                    eprintln!("after the input: {summary:?}");
                    assert!(summary.frames < frames, "Esc did not close the window");
                    let moved = start.position - summary.pose.position;
                    // W moves along the view, toward -z from the start pose, by about a unit.
                    assert!(moved.z > 0.3 && moved.x.abs() < 0.1, "W did not move forward: {moved}");
                    assert!(
                        summary.pose.yaw_degrees > 0.5 && summary.pose.yaw_degrees < 90.0,
                        "the mouse did not turn right"
                    );
                    assert!(summary.field_of_view_degrees < 45.0, "the scroll wheel did not zoom in");
                }
            }
            println!(
                "test opens_draws_and_closes ... ok ({} frames in {:.2} s)",
                summary.frames, summary.seconds
            );
        }
        Err(window::WindowError::Render(error))
            if !under_ci() && error.to_string().contains("no graphics adapter") =>
        {
            test_skips::skip("terrain window test", &error.to_string());
        }
        Err(error) => panic!("the window failed: {error}"),
    }
}
