//! `rayterra terrain` as a user runs it: screenshots, and clear errors with the right exit codes
//! for bad input, never a panic or a half-written file.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

mod terrain_common;
use terrain_common::{assert_fails, no_gpu, rayterra, stderr, under_ci};

fn scratch(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("terrain-cli");
    std::fs::create_dir_all(&dir).expect("scratch folder");
    dir.join(name)
}

#[test]
fn renders_a_screenshot_off_screen() {
    let out = scratch("shot.png");
    let _ = std::fs::remove_file(&out);
    let output = rayterra(&[
        "--screenshot",
        out.to_str().expect("utf-8 path"),
        "--size",
        "96x54",
        "--grid",
        "64",
        "--camera",
        "0,3,12,0,-5",
        "--time",
        "2",
        "--backend",
        "vulkan",
    ]);
    let text = stderr(&output);
    // Without XDG_RUNTIME_DIR (as under CI), Mesa's device-select layer used to make libwayland
    // print an error twice.
    assert!(!text.contains("XDG_RUNTIME_DIR"), "{text}");
    if !output.status.success() && text.contains("no graphics adapter") && !under_ci() {
        test_skips::skip("rayterra terrain GPU tests", &format!("no Vulkan adapter: {text}"));
        return;
    }
    assert!(output.status.success(), "{text}");
    assert!(text.contains("adapter:"), "the adapter is not printed: {text}");
    assert!(String::from_utf8_lossy(&output.stdout).contains("shot.png"));
    let image = image_size(&out);
    assert_eq!(image, (96, 54));
}

/// Width and height from a PNG's header.
fn image_size(path: &Path) -> (u32, u32) {
    let bytes = std::fs::read(path).expect("the screenshot exists");
    assert_eq!(&bytes[1..4], b"PNG", "not a PNG");
    let word = |at: usize| u32::from_be_bytes([bytes[at], bytes[at + 1], bytes[at + 2], bytes[at + 3]]);
    (word(16), word(20))
}

#[test]
fn without_a_display_it_says_so() {
    let output = rayterra(&["--grid", "8"]);
    assert_fails(&output, 1, "no display");
    assert!(stderr(&output).contains("--screenshot"), "no hint given");
}

#[test]
fn a_bad_display_is_named_without_winits_source_path() {
    let output = Command::new(env!("CARGO_BIN_EXE_rayterra"))
        .args(["terrain", "--grid", "8"])
        .env("DISPLAY", ":7351")
        .env_remove("WAYLAND_DISPLAY")
        .env_remove("WAYLAND_SOCKET")
        .output()
        .expect("rayterra runs");
    assert_fails(&output, 1, "no display to open a window on (DISPLAY=:7351: ");
    let text = stderr(&output);
    assert!(!text.contains(".rs:") && !text.contains("winit"), "{text}");
}

#[test]
fn malformed_options_are_usage_errors() {
    assert_fails(&rayterra(&["--camera", "1,2", "--screenshot", "x.png"]), 2, "five comma-separated numbers");
    assert_fails(&rayterra(&["--camera", "0,1,2,3,100", "--screenshot", "x.png"]), 2, "pitch");
    assert_fails(&rayterra(&["--size", "100000x100000", "--screenshot", "x.png"]), 2, "between 1 and 16384");
    assert_fails(&rayterra(&["--size", "0x10", "--screenshot", "x.png"]), 2, "between 1 and 16384");
    assert_fails(&rayterra(&["--size", "wide", "--screenshot", "x.png"]), 2, "WIDTHxHEIGHT");
    assert_fails(&rayterra(&["--fov", "0", "--screenshot", "x.png"]), 2, "field of view");
    assert_fails(&rayterra(&["--time", "nan", "--screenshot", "x.png"]), 2, "finite");
    assert_fails(&rayterra(&["--assets", "a", "--heightmap", "b.png"]), 2, "cannot be used with");
    assert_fails(&rayterra(&["--time-of-day", "25:00", "--screenshot", "x.png"]), 2, "not a time of day");
    assert_fails(&rayterra(&["--latitude", "91", "--screenshot", "x.png"]), 2, "latitude");
    assert_fails(&rayterra(&["--day-of-year", "0", "--screenshot", "x.png"]), 2, "day-of-year");
    assert_fails(&rayterra(&["--sun-elevation", "-20", "--screenshot", "x.png"]), 2, "sun's elevation");
}

/// The time of day on the command line gives the picture the settings file's `[sky]` gives, and
/// cannot be mixed with a sun placed by hand.
#[test]
fn the_time_of_day_from_the_command_line_or_the_settings_file() {
    let settings = scratch("dusk.toml");
    std::fs::write(&settings, "[sky]\ntime_of_day = \"19:10\"\nlatitude_degrees = 52.0\nday_of_year = 100\n")
        .expect("write");
    let (from_file, from_options) = (scratch("dusk-file.png"), scratch("dusk-options.png"));
    let path = |p: &Path| p.to_str().expect("utf-8 path").to_string();
    let common = ["--size", "48x27", "--grid", "32", "--backend", "vulkan"];
    let mut first = vec!["--settings".to_string(), path(&settings), "--screenshot".into(), path(&from_file)];
    first.extend(common.iter().map(|s| s.to_string()));
    let output = rayterra(&first.iter().map(String::as_str).collect::<Vec<_>>());
    if no_gpu(&output) {
        return;
    }
    assert!(output.status.success(), "{}", stderr(&output));
    let second_out = path(&from_options);
    let mut second = vec![
        "--time-of-day",
        "19:10",
        "--latitude",
        "52",
        "--day-of-year",
        "100",
        "--screenshot",
        &second_out,
    ];
    second.extend(common);
    let output = rayterra(&second);
    assert!(output.status.success(), "{}", stderr(&output));
    assert_eq!(std::fs::read(&from_file).expect("first"), std::fs::read(&from_options).expect("second"));
    // Noon is another picture.
    let noon = path(&scratch("noon.png"));
    let mut third =
        vec!["--time-of-day", "12:00", "--latitude", "52", "--day-of-year", "100", "--screenshot", &noon];
    third.extend(common);
    assert!(rayterra(&third).status.success());
    assert_ne!(std::fs::read(&noon).expect("noon"), std::fs::read(&from_options).expect("dusk"));
    assert_fails(
        &rayterra(&["--time-of-day", "12:00", "--sun-elevation", "10", "--screenshot", &noon]),
        1,
        "leave out --sun-elevation",
    );
}

#[test]
fn bad_files_are_named() {
    let out = scratch("never.png");
    let _ = std::fs::remove_file(&out);
    let out_arg = out.to_str().expect("utf-8 path");
    assert_fails(&rayterra(&["--assets", "/no/such/folder", "--screenshot", out_arg]), 1, "/no/such/folder");
    let corrupt = scratch("corrupt.png");
    std::fs::write(&corrupt, b"\x89PNG\r\n\x1a\n but then nothing").expect("write");
    assert_fails(
        &rayterra(&["--heightmap", corrupt.to_str().expect("utf-8 path"), "--screenshot", out_arg]),
        1,
        "corrupt.png",
    );
    let incomplete = scratch("incomplete-assets");
    std::fs::create_dir_all(&incomplete).expect("folder");
    assert_fails(
        &rayterra(&["--assets", incomplete.to_str().expect("utf-8 path"), "--screenshot", out_arg]),
        1,
        "SkyBox5.bmp",
    );
    assert_fails(&rayterra(&["--screenshot", "picture.tiff", "--grid", "8"]), 1, "picture.tiff");
    assert!(!out.exists(), "a failed run left {}", out.display());
}

#[test]
fn an_unwritable_destination_leaves_no_file() {
    let out = scratch("missing-folder").join("deeper").join("shot.png");
    let output =
        rayterra(&["--screenshot", out.to_str().expect("utf-8 path"), "--size", "32x18", "--grid", "16"]);
    if no_gpu(&output) {
        return;
    }
    assert_fails(&output, 1, "shot.png");
    assert!(!out.exists());
}

#[test]
fn exports_an_asset_folder_that_loads_again() {
    let dir = scratch("exported");
    let _ = std::fs::remove_dir_all(&dir);
    let dir_arg = dir.to_str().expect("utf-8 path");
    let output = rayterra(&["--grid", "16", "--seed", "3", "--export-assets", dir_arg]);
    assert!(output.status.success(), "{}", stderr(&output));
    for name in ["heightmap.bmp", "terrain-texture3.bmp", "detail.bmp", "SkyBox0.bmp", "SkyBox5.bmp"] {
        assert!(dir.join(name).is_file(), "{name} missing");
    }
    let out = scratch("exported.png");
    let output = rayterra(&[
        "--assets",
        dir_arg,
        "--screenshot",
        out.to_str().expect("utf-8 path"),
        "--size",
        "32x18",
    ]);
    if no_gpu(&output) {
        return;
    }
    let text = stderr(&output);
    assert!(output.status.success(), "{text}");
    assert!(text.contains("course assets"), "{text}");
}

#[test]
fn settings_files_set_the_look_and_the_view() {
    let settings = scratch("course-view.toml");
    std::fs::write(
        &settings,
        "look = \"course\"\n[view]\nposition = [0.0, 3.0, 12.0]\nyaw_degrees = 0.0\npitch_degrees = -5.0\n\
         field_of_view_degrees = 45.0\ntime_seconds = 2.0\n",
    )
    .expect("write");
    let (from_file, from_options) = (scratch("from-file.png"), scratch("from-options.png"));
    let common = ["--size", "48x27", "--grid", "32", "--backend", "vulkan"];
    let path = |p: &Path| p.to_str().expect("utf-8 path").to_string();
    let mut first = vec!["--settings".to_string(), path(&settings), "--screenshot".into(), path(&from_file)];
    first.extend(common.iter().map(|s| s.to_string()));
    let output = rayterra(&first.iter().map(String::as_str).collect::<Vec<_>>());
    if no_gpu(&output) {
        return;
    }
    let text = stderr(&output);
    assert!(output.status.success(), "{text}");
    // The memory is reported, with what a height sample costs.
    assert!(text.contains("memory (CPU)") && text.contains("memory (GPU)"), "{text}");
    assert!(text.contains("bytes in all"), "{text}");
    assert!(text.contains("course look"), "{text}");
    // The same picture from the command line's look and camera.
    let mut second = vec!["--look", "course", "--camera", "0,3,12,0,-5", "--time", "2", "--screenshot"];
    let second_out = path(&from_options);
    second.push(&second_out);
    second.extend(common);
    let output = rayterra(&second);
    assert!(output.status.success(), "{}", stderr(&output));
    assert_eq!(std::fs::read(&from_file).expect("first"), std::fs::read(&from_options).expect("second"));
}

#[test]
fn bad_settings_are_named() {
    let out = scratch("never-settings.png");
    let out_arg = out.to_str().expect("utf-8 path");
    let bad = scratch("bad.toml");
    std::fs::write(&bad, "[fog]\ndensty = 0.1\n").expect("write");
    let output =
        rayterra(&["--settings", bad.to_str().expect("utf-8 path"), "--screenshot", out_arg, "--grid", "8"]);
    assert_fails(&output, 1, "bad.toml");
    assert!(stderr(&output).contains("densty"), "{}", stderr(&output));
    let missing = scratch("missing-settings.toml");
    let _ = std::fs::remove_file(&missing);
    let output = rayterra(&[
        "--settings",
        missing.to_str().expect("utf-8 path"),
        "--screenshot",
        out_arg,
        "--grid",
        "8",
    ]);
    assert_fails(&output, 1, "missing-settings.toml");
    assert_fails(&rayterra(&["--look", "fancy", "--screenshot", out_arg]), 2, "modern");
    assert!(!out.exists());
}

#[test]
fn a_camera_under_the_water_or_outside_the_sky_box_is_moved_inside_with_a_warning() {
    let common = ["--size", "48x27", "--grid", "32", "--backend", "vulkan", "--look", "course"];
    let render = |camera: &str, name: &str| {
        let out = scratch(name);
        let mut args = vec!["--camera", camera, "--screenshot", out.to_str().expect("utf-8 path")];
        args.extend(common);
        (rayterra(&args), out)
    };
    for (camera, reason) in [("0,-3,9.5,0,10", "under the water"), ("0,2,500,0,0", "outside the sky box")] {
        let (output, moved_shot) = render(camera, "camera-moved.png");
        if no_gpu(&output) {
            return;
        }
        let text = stderr(&output);
        assert!(output.status.success(), "{text}");
        assert!(text.contains("warning: --camera") && text.contains(reason), "{text}");
        // The picture is the one taken from where the warning says the camera went.
        let moved = text
            .split("moved to ")
            .nth(1)
            .and_then(|rest| rest.split_whitespace().next())
            .expect("the warning names the new position");
        let [x, y, z]: [f32; 3] = moved
            .split(',')
            .map(|n| n.parse().expect("a number"))
            .collect::<Vec<_>>()
            .try_into()
            .expect("three numbers");
        let config = terrain::SceneConfig::default();
        let limits = config.camera_limits();
        let inside = |v: f32, axis: usize| (limits.min[axis]..=limits.max[axis]).contains(&v);
        assert!(y >= 0.2 && inside(x, 0) && inside(y, 1) && inside(z, 2), "{moved}");
        let (output, direct_shot) =
            render(&format!("{moved},0,{}", camera.rsplit(',').next().expect("pitch")), "camera-direct.png");
        let direct_text = stderr(&output);
        assert!(output.status.success(), "{direct_text}");
        assert!(!direct_text.contains("warning"), "{direct_text}");
        assert_eq!(
            std::fs::read(&moved_shot).expect("moved"),
            std::fs::read(&direct_shot).expect("direct"),
            "{camera}: not the picture from {moved}"
        );
    }
}

#[test]
fn running_out_of_memory_is_a_clear_error() {
    // 8192x8192 pixels need about 1.9 GB; under a 1.5 GB address-space limit the command must
    // refuse (before or while making the frame) with a message and status 1, not abort or panic.
    let out = scratch("out-of-memory.png");
    let _ = std::fs::remove_file(&out);
    let limited = Command::new("prlimit")
        .arg("--as=1500000000")
        .arg(env!("CARGO_BIN_EXE_rayterra"))
        .args(["terrain", "--grid", "64", "--size", "8192x8192", "--backend", "vulkan", "--screenshot"])
        .arg(&out)
        .env_remove("DISPLAY")
        .env_remove("WAYLAND_DISPLAY")
        .env_remove("XDG_RUNTIME_DIR")
        .output();
    let output = match limited {
        Ok(output) => output,
        Err(error) => {
            assert!(!under_ci(), "CI=true, so this cannot be skipped: prlimit: {error}");
            test_skips::skip("rayterra terrain memory limit", &format!("cannot run prlimit: {error}"));
            return;
        }
    };
    if no_gpu(&output) {
        return;
    }
    assert_fails(&output, 1, "memory");
    assert!(!out.exists(), "an image was written");
}

/// `rayterra terrain ARGS` as [`rayterra`] runs it, killed after `seconds` (`None`: it hung).
fn rayterra_within(args: &[&str], seconds: u64) -> Option<Output> {
    use std::process::Stdio;
    use std::time::{Duration, Instant};
    let mut child = Command::new(env!("CARGO_BIN_EXE_rayterra"))
        .arg("terrain")
        .args(args)
        .env_remove("DISPLAY")
        .env_remove("WAYLAND_DISPLAY")
        .env_remove("WAYLAND_SOCKET")
        .env_remove("XDG_RUNTIME_DIR")
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("rayterra runs");
    let started = Instant::now();
    while started.elapsed() < Duration::from_secs(seconds) {
        if child.try_wait().expect("wait").is_some() {
            return Some(child.wait_with_output().expect("output"));
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    let _ = child.kill();
    let _ = child.wait();
    None
}

/// A named pipe that nothing writes to, at `path`.
#[cfg(unix)]
fn fifo(path: &Path) {
    let _ = std::fs::remove_file(path);
    let made = Command::new("mkfifo").arg(path).status().expect("mkfifo runs");
    assert!(made.success(), "mkfifo {}", path.display());
}

/// Issue 31, defect 2: a named pipe given as a heightmap, a settings file or in an asset folder
/// is refused at once instead of waiting forever for a writer.
#[cfg(unix)]
#[test]
fn named_pipes_are_refused_without_waiting() {
    let out = scratch("never-fifo.png");
    let _ = std::fs::remove_file(&out);
    let out_arg = out.to_str().expect("utf-8 path");
    let pipe = scratch("pipe.png");
    fifo(&pipe);
    let pipe_arg = pipe.to_str().expect("utf-8 path");
    let assets = scratch("fifo-assets");
    let _ = std::fs::remove_dir_all(&assets);
    std::fs::create_dir_all(&assets).expect("folder");
    // Every file of a course folder is there, and one is a pipe.
    for name in ["heightmap.bmp", "terrain-texture3.bmp", "detail.bmp"]
        .into_iter()
        .map(String::from)
        .chain((0..6).map(|i| format!("SkyBox{i}.bmp")))
    {
        if name == "detail.bmp" {
            fifo(&assets.join(&name));
        } else {
            image::RgbImage::from_pixel(4, 4, image::Rgb([120; 3])).save(assets.join(&name)).expect("bmp");
        }
    }
    let assets_arg = assets.to_str().expect("utf-8 path");
    for args in [
        &["--heightmap", pipe_arg, "--screenshot", out_arg][..],
        &["--settings", pipe_arg, "--screenshot", out_arg, "--grid", "8"][..],
        &["--assets", assets_arg, "--screenshot", out_arg][..],
    ] {
        let output = rayterra_within(args, 60).unwrap_or_else(|| panic!("{args:?} hung on a named pipe"));
        assert_fails(&output, 1, "not a regular file");
    }
    assert!(!out.exists());
}

/// Issue 31, defect 6: a screenshot path ending with a slash is refused before any work.
#[test]
fn a_screenshot_path_ending_with_a_slash_is_refused_before_any_work() {
    let out = scratch("slash.png");
    let _ = std::fs::remove_file(&out);
    let arg = format!("{}/", out.display());
    // The largest grid: generating it would take many seconds before the write failed.
    let output = rayterra_within(&["--screenshot", &arg, "--grid", "8193"], 60).expect("it stops at once");
    assert_fails(&output, 1, "names a folder");
    assert!(!stderr(&output).contains("world:"), "the world was made: {}", stderr(&output));
    assert!(!out.exists());
}

/// Issue 31, defect 3: `rayterra terrain --screenshot x.png 2>&1 | head -1` closes both streams
/// after a line: the screenshot is still written, nothing panics, the exit status is 0.
#[cfg(unix)]
#[test]
fn closed_output_streams_neither_panic_nor_lose_the_screenshot() {
    use std::process::Stdio;
    let out = scratch("closed-pipe.png");
    let _ = std::fs::remove_file(&out);
    let args =
        ["terrain", "--screenshot", out.to_str().expect("utf-8 path"), "--size", "32x18", "--grid", "16"];
    let mut child = Command::new(env!("CARGO_BIN_EXE_rayterra"))
        .args(args)
        .env_remove("DISPLAY")
        .env_remove("WAYLAND_DISPLAY")
        .env_remove("XDG_RUNTIME_DIR")
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("rayterra runs");
    drop(child.stdout.take());
    drop(child.stderr.take());
    let status = child.wait().expect("wait");
    if !status.success() {
        // Why, with the streams open: no GPU is a skip, anything else a failure.
        let output = rayterra(&args[1..]);
        if no_gpu(&output) {
            return;
        }
        panic!("with closed streams it exited with {status}; with open ones: {}", stderr(&output));
    }
    assert!(out.exists(), "the screenshot is written");
}

/// Issue 31, defect 7: an out-of-range value in a settings file names its line (before any GPU
/// work).
#[test]
fn out_of_range_settings_name_their_line() {
    let out = scratch("never-range.png");
    let _ = std::fs::remove_file(&out);
    let bad = scratch("range.toml");
    std::fs::write(&bad, "look = \"modern\"\n[sun]\nintensity = 1\nelevation_degrees = 95\n").expect("write");
    let output = rayterra(&[
        "--settings",
        bad.to_str().expect("utf-8 path"),
        "--screenshot",
        out.to_str().expect("utf-8 path"),
        "--grid",
        "8",
    ]);
    assert_fails(&output, 1, "range.toml:4: `sun.elevation_degrees` is 95");
    assert!(!out.exists());
}
