//! What the `rayterra terrain` tests share: running the binary without a display, reading its
//! messages, and the loud skip without a GPU. Each test file uses some of it.
#![allow(dead_code)]

use std::process::{Command, Output};

/// Whether the tests run under CI, where nothing may be skipped.
pub fn under_ci() -> bool {
    std::env::var("CI").is_ok_and(|value| !value.is_empty() && value != "false" && value != "0")
}

/// `rayterra terrain`, with no display to open a window on.
pub fn terrain_command() -> Command {
    let mut command = Command::new(env!("CARGO_BIN_EXE_rayterra"));
    command
        .arg("terrain")
        // No window may open from these tests.
        .env_remove("DISPLAY")
        .env_remove("WAYLAND_DISPLAY")
        .env_remove("WAYLAND_SOCKET")
        .env_remove("XDG_RUNTIME_DIR");
    command
}

/// `rayterra terrain ARGS`, run to its end.
pub fn rayterra(args: &[&str]) -> Output {
    terrain_command().args(args).output().expect("rayterra runs")
}

/// The standard error of `output`, as text.
pub fn stderr(output: &Output) -> String {
    String::from_utf8_lossy(&output.stderr).into_owned()
}

/// Whether `output` failed for want of a GPU; if so the test is skipped loudly (or fails
/// under CI).
pub fn no_gpu(output: &Output) -> bool {
    let text = stderr(output);
    let missing = !output.status.success() && text.contains("no graphics adapter");
    if missing {
        assert!(!under_ci(), "CI=true, so this cannot be skipped: {text}");
        test_skips::skip("rayterra terrain GPU tests", &format!("no Vulkan adapter: {text}"));
    }
    missing
}

/// Asserts a failure with `code` whose message contains every one of `needles`, and no panic.
pub fn assert_fails_with(output: &Output, code: i32, needles: &[&str]) {
    let text = stderr(output);
    assert_eq!(output.status.code(), Some(code), "stderr: {text}");
    for needle in needles {
        assert!(text.contains(needle), "expected `{needle}` in: {text}");
    }
    assert!(!text.contains("panicked"), "it panicked: {text}");
}

/// Asserts a failure with `code` whose message contains `needle`, and no panic.
pub fn assert_fails(output: &Output, code: i32, needle: &str) {
    assert_fails_with(output, code, &[needle]);
}
