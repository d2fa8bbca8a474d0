//! The window test: the window opens, draws frames, follows real keyboard, mouse and scroll
//! input (sent by xdotool), its tuning panel opens with F1, takes real keyboard input and
//! changes the frame, and it closes on Esc. Without a display they run themselves again under
//! `xvfb-run -a` (a virtual X server); without `xvfb-run` they are skipped loudly, or fail under
//! CI. Runs without the test harness: winit wants the main thread.

use std::path::PathBuf;
use std::process::Command;

use terrain::render::Backend;
use terrain::window::{self, Notice, WindowOptions, WindowSummary};
use terrain::world::World;
use terrain::world::procedural::{ProceduralOptions, generate};
use terrain::{Look, SceneConfig, Settings};

const INNER: &str = "RAYTERRA_WINDOW_TEST_INNER";

/// The test's name (one window session: winit opens one event loop per process).
const TEST: &str = "moves_and_tunes_with_real_input";

fn under_ci() -> bool {
    std::env::var("CI").is_ok_and(|value| !value.is_empty() && value != "false" && value != "0")
}

fn main() {
    // `cargo test -- --list` and filters that exclude this test: say there is one test.
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.iter().any(|a| a == "--list") {
        println!("{TEST}: test");
        return;
    }
    if let Some(filter) = args.iter().find(|a| !a.starts_with('-'))
        && !TEST.contains(filter.as_str())
    {
        return;
    }
    if !window::display_available() && std::env::var_os(INNER).is_none() {
        rerun_under_xvfb(&args);
        return;
    }
    let config = SceneConfig::default();
    let world =
        generate(ProceduralOptions { seed: 1, heightmap_size: 64 }, &config, &mut |_| {}).expect("world");
    moves_and_tunes_with_real_input(&world);
}

fn rerun_under_xvfb(args: &[String]) {
    let exe = std::env::current_exe().expect("own path");
    eprintln!("no display: running the window tests under xvfb-run -a");
    let run = test_skips::run_id().to_string();
    match Command::new("xvfb-run")
        .arg("-a")
        .arg(&exe)
        .args(args)
        .env(INNER, "1")
        .env(test_skips::RUN_VARIABLE, run)
        .status()
    {
        Ok(status) => assert!(status.success(), "the window tests failed under xvfb-run: {status}"),
        Err(error) => {
            let reason = format!("cannot run xvfb-run ({error}); install xvfb and xauth");
            assert!(!under_ci(), "CI=true, so this cannot be skipped: {reason}");
            test_skips::skip("terrain window test", &reason);
        }
    }
}

/// Runs `script` (xdotool commands, the first finding the window as `%1`) and says what went
/// wrong, if anything.
fn drive_input(script: &str) -> Result<(), String> {
    // `timeout` keeps a stuck search from hanging the test; the window's frame cap ends it too.
    let output = Command::new("timeout")
        .args(["90", "xdotool"])
        .args(script.split_whitespace())
        .output()
        .map_err(|error| format!("cannot run xdotool: {error}"))?;
    if output.status.success() {
        Ok(())
    } else {
        Err(format!("xdotool failed ({}): {}", output.status, String::from_utf8_lossy(&output.stderr)))
    }
}

/// Whether xdotool is installed; without it the input tests are skipped loudly (a failure under
/// CI).
fn have_xdotool() -> bool {
    let found = Command::new("xdotool").arg("version").output().is_ok_and(|o| o.status.success());
    if !found {
        let reason = "xdotool is not installed, so keyboard and mouse input is not tested";
        assert!(!under_ci(), "CI=true, so this cannot be skipped: {reason}");
        test_skips::skip("terrain window test (input)", reason);
    }
    found
}

/// Finds the window and focuses it.
const FIND_WINDOW: &str = "search --sync --onlyvisible --name ^rayterra.terrain windowfocus --sync %1";

/// Opens a window on `world` with `settings`, `size` pixels, while `script` drives it (when
/// xdotool is there). Returns what happened, or `None` when the test must be skipped.
fn session(
    world: &World,
    settings: Settings,
    size: (u32, u32),
    script: &str,
    notices: &mut Vec<Notice>,
) -> Option<(WindowSummary, bool)> {
    let config = SceneConfig::default();
    let driven = have_xdotool();
    // Driven by input, the window runs until Esc; the frame cap only stops a test gone wrong.
    let frames = if driven { 20_000 } else { 5 };
    let shots = std::env::temp_dir().join(format!("rayterra-window-test-{}", std::process::id()));
    std::fs::create_dir_all(&shots).expect("screenshot folder");
    let options = WindowOptions {
        backend: Backend::Vulkan,
        size,
        pose: config.camera_start,
        field_of_view_degrees: 45.0,
        start_time_seconds: 0.0,
        max_frames: Some(frames),
        vsync: false,
        screenshot_dir: shots.clone(),
        settings,
        settings_path: shots.join("settings.toml"),
    };
    let script = format!("{FIND_WINDOW} {script}");
    let driver = driven.then(|| std::thread::spawn(move || drive_input(&script)));
    let result = window::run(world, &config, options, &mut |notice| {
        if let Notice::Adapter(name) = &notice {
            eprintln!("adapter: {name}");
        }
        notices.push(notice);
    });
    let input = driver.map(|thread| thread.join().expect("the input thread panicked"));
    match result {
        Ok(summary) => {
            assert!(notices.iter().any(|n| matches!(n, Notice::Adapter(_))), "the adapter was not reported");
            match input {
                None => {
                    assert_eq!(summary.frames, frames);
                    None
                }
                Some(Err(error)) => panic!("{error}"),
                Some(Ok(())) => {
                    assert!(summary.frames < frames, "Esc did not close the window");
                    Some((summary, true))
                }
            }
        }
        Err(window::WindowError::Render(error))
            if !under_ci() && error.to_string().contains("no graphics adapter") =>
        {
            test_skips::skip("terrain window test", &error.to_string());
            None
        }
        Err(error) => panic!("the window failed: {error}"),
    }
}

/// What the test does, as xdotool commands after finding the window: hold W, move the mouse
/// right, turn the scroll wheel away from the user (button 4), let the day run (T); then open the
/// panel (F1), take a
/// screenshot (F12), move the keyboard focus to the look's second radio button (Tab, Tab) and
/// choose it (space), take another screenshot, and press Esc.
const SCRIPT: &str = "mousemove --window %1 320 200 sleep 0.3 keydown w sleep 0.6 keyup w sleep 0.2 \
    mousemove_relative -- 60 0 sleep 0.3 click 4 sleep 0.3 key t sleep 0.5 \
    key F1 sleep 1.0 key F12 sleep 1.5 key Tab sleep 0.4 key Tab sleep 0.4 key space sleep 1.5 \
    key F12 sleep 1.5 key Escape";

fn moves_and_tunes_with_real_input(world: &World) {
    let start = SceneConfig::default().camera_start;
    let mut notices = Vec::new();
    let Some((summary, _)) = session(world, Settings::default(), (640, 400), SCRIPT, &mut notices) else {
        return;
    };
    eprintln!("after the input: {summary:?}");
    let moved = start.position - summary.pose.position;
    // W moves along the view, toward -z from the start pose, by about a unit.
    assert!(moved.z > 0.3 && moved.x.abs() < 0.1, "W did not move forward: {moved}");
    assert!(
        summary.pose.yaw_degrees > 0.5 && summary.pose.yaw_degrees < 90.0,
        "the mouse did not turn right"
    );
    assert!(summary.field_of_view_degrees < 45.0, "the scroll wheel did not zoom in");
    // T let the day run: from noon, the clock moved on.
    assert!(summary.settings.sky.day_runs, "T did not let the day run");
    let hours = summary.settings.sky.time_of_day.map(|t| t.hours());
    assert!(hours.is_some_and(|h| h > 12.0 && h < 16.0), "the day did not run from noon: {hours:?}");
    // The panel: the keyboard chose the course's look, and the frame changed.
    assert_eq!(summary.settings.look, Look::Course, "the keyboard did not switch the look in the panel");
    let shots: Vec<PathBuf> = notices
        .iter()
        .filter_map(|n| if let Notice::ScreenshotSaved(path) = n { Some(path.clone()) } else { None })
        .collect();
    assert_eq!(shots.len(), 2, "{notices:?}");
    let [before, after] =
        [&shots[0], &shots[1]].map(|path| image::open(path).expect("screenshot").into_rgba8());
    // The panel shows in both (its top left corner is the same), the scene beside it changed:
    // its land and water, below the horizon (the sky is the same in both looks here).
    let corner = |image: &image::RgbaImage| *image.get_pixel(20, 20);
    assert_eq!(corner(&before), corner(&after), "the panel is not in both screenshots");
    let (width, height) = before.dimensions();
    let region: Vec<(u32, u32)> =
        (height / 2..height).flat_map(|y| (width / 2..width).map(move |x| (x, y))).collect();
    let changed = region
        .iter()
        .filter(|&&(x, y)| {
            let (a, b) = (before.get_pixel(x, y), after.get_pixel(x, y));
            a.0.iter().zip(b.0).any(|(p, q)| p.abs_diff(q) > 24)
        })
        .count();
    let share = changed as f64 / region.len() as f64;
    assert!(share > 0.3, "only {:.1}% of the lower right quarter changed", share * 100.0);
    for path in shots {
        let _ = std::fs::remove_file(path);
    }
    println!(
        "test moves_and_tunes_with_real_input ... ok ({} frames in {:.2} s, {:.0}% of the lower right quarter changed)",
        summary.frames,
        summary.seconds,
        share * 100.0
    );
}
