//! `rayterra terrain` as a user runs it: screenshots, and clear errors with the right exit codes
//! for bad input, never a panic or a half-written file.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn under_ci() -> bool {
    std::env::var("CI").is_ok_and(|value| !value.is_empty() && value != "false" && value != "0")
}

fn rayterra(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_rayterra"))
        .arg("terrain")
        .args(args)
        // No window may open from these tests.
        .env_remove("DISPLAY")
        .env_remove("WAYLAND_DISPLAY")
        .env_remove("WAYLAND_SOCKET")
        .env_remove("XDG_RUNTIME_DIR")
        .output()
        .expect("rayterra runs")
}

fn stderr(output: &Output) -> String {
    String::from_utf8_lossy(&output.stderr).into_owned()
}

fn scratch(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("terrain-cli");
    std::fs::create_dir_all(&dir).expect("scratch folder");
    dir.join(name)
}

/// Whether `output` failed for want of a GPU; if so the test is skipped loudly (or fails
/// under CI).
fn no_gpu(output: &Output) -> bool {
    let text = stderr(output);
    let missing = !output.status.success() && text.contains("no graphics adapter");
    if missing {
        assert!(!under_ci(), "CI=true, so this cannot be skipped: {text}");
        test_skips::skip("rayterra terrain GPU tests", &format!("no Vulkan adapter: {text}"));
    }
    missing
}

/// Asserts a failure with `code` whose message contains `needle`, and no panic.
fn assert_fails(output: &Output, code: i32, needle: &str) {
    let text = stderr(output);
    assert_eq!(output.status.code(), Some(code), "stderr: {text}");
    assert!(text.contains(needle), "expected `{needle}` in: {text}");
    assert!(!text.contains("panicked"), "it panicked: {text}");
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
