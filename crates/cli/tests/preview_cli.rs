//! `rayterra render --preview`: without a display it renders on and writes the same bytes; under
//! a virtual X server (Xvfb) with real key presses (xdotool) the window's picture changes as
//! passes arrive and ends equal to the output file, `P` prints the pose, an arrow key moves the
//! camera (and `P` prints the new pose), `S` writes the image so far, Esc closes the window.
//! Without xvfb-run or xdotool the window test is skipped loudly (a failure under CI=true).

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn under_ci() -> bool {
    std::env::var("CI").is_ok_and(|value| !value.is_empty() && value != "false" && value != "0")
}

fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

/// The repository's root (two folders above this crate).
fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn cornell() -> String {
    root().join("scenes/cornell.txt").display().to_string()
}

/// `rayterra ARGS` in `dir` with no display to open a window on.
fn headless(args: &[&str], dir: &Path) -> Output {
    Command::new(env!("CARGO_BIN_EXE_rayterra"))
        .args(args)
        .current_dir(dir)
        .env_remove("DISPLAY")
        .env_remove("WAYLAND_DISPLAY")
        .env_remove("WAYLAND_SOCKET")
        .output()
        .expect("run rayterra")
}

/// Reads an image's pixels as linear floats (EXR) or 8-bit values scaled to [0, 1] (PNG).
fn pixels(path: &Path) -> Vec<[f32; 3]> {
    let img = image::open(path).unwrap_or_else(|e| panic!("{}: {e}", path.display())).to_rgb32f();
    img.pixels().map(|p| p.0).collect()
}

#[test]
fn without_a_display_the_render_goes_on_and_writes_the_same_bytes() {
    let dir = tempfile::tempdir().expect("temp dir");
    let scene = cornell();
    for (model, extra) in [
        ("path", &["--spp", "8"][..]),
        ("classic", &[][..]),
        ("sppm", &["--passes", "3", "--photons", "3000"][..]),
    ] {
        let common = ["render", scene.as_str(), "--size", "32x24", "--model", model];
        let plain = headless(&[&common[..], extra, &["-o", "plain.png"]].concat(), dir.path());
        assert!(plain.status.success(), "{}", text(&plain.stderr));
        let shown = headless(&[&common[..], extra, &["--preview", "-o", "preview.png"]].concat(), dir.path());
        let stderr = text(&shown.stderr);
        assert!(shown.status.success(), "{stderr}");
        assert!(
            stderr.contains("no preview window (neither DISPLAY nor WAYLAND_DISPLAY is set)"),
            "{stderr}"
        );
        assert!(stderr.contains("the render goes on without it"), "{stderr}");
        assert!(text(&shown.stdout).contains("wrote preview.png"), "{}", text(&shown.stdout));
        let read = |name: &str| std::fs::read(dir.path().join(name)).expect("the output");
        assert!(read("plain.png") == read("preview.png"), "{model}: --preview wrote other bytes");
    }
}

#[test]
fn preview_refuses_parts_and_checkpoints() {
    let dir = tempfile::tempdir().expect("temp dir");
    let scene = cornell();
    for extra in [["--tile", "0/2"], ["--pass", "0/2"], ["--checkpoint", "c.ckpt"]] {
        let out = headless(
            &[&["render", scene.as_str(), "--preview", "-o", "x.exr"][..], &extra[..]].concat(),
            dir.path(),
        );
        assert_eq!(out.status.code(), Some(2), "{extra:?}: {}", text(&out.stderr));
        assert!(text(&out.stderr).contains("--preview shows a whole render"), "{}", text(&out.stderr));
    }
}

/// Whether xvfb-run and xdotool are installed; without them the test is skipped loudly (a
/// failure under CI).
fn have_tools() -> bool {
    let found = |tool: &str| {
        Command::new("sh")
            .args(["-c", &format!("command -v {tool}")])
            .output()
            .is_ok_and(|o| o.status.success())
    };
    let missing: Vec<&str> = ["xvfb-run", "xdotool"].into_iter().filter(|t| !found(t)).collect();
    if missing.is_empty() {
        return true;
    }
    let reason = format!("{} not installed (apt-get install xvfb xauth xdotool)", missing.join(" and "));
    assert!(!under_ci(), "CI=true, so the preview window test cannot be skipped: {reason}");
    test_skips::skip("rayterra render --preview window test", &reason);
    false
}

/// Whether the window could not be opened under Xvfb (no GPU adapter, not even a software
/// one): then the test is skipped loudly (a failure under CI, which installs Mesa's lavapipe).
fn no_window_here(stderr: &str) -> bool {
    let Some(line) = stderr.lines().find(|l| l.starts_with("note: no preview window")) else { return false };
    assert!(!under_ci(), "CI=true, so the preview window test cannot be skipped: {line}");
    test_skips::skip("rayterra render --preview window test", line);
    true
}

/// The session: the render in the background, waiting for its output, a copy of it, then keys.
const SCRIPT: &str = r#"
"$BIN" render "$SCENE" --preview --model path --spp 64 --threads 1 --size 64x64 -o "$DIR/out.exr" \
    > "$DIR/stdout.txt" 2> "$DIR/stderr.txt" &
pid=$!
for i in $(seq 1 1200); do [ -f "$DIR/out.exr" ] && break; sleep 0.1; done
cp "$DIR/out.exr" "$DIR/first.exr"
timeout 60 xdotool search --sync --onlyvisible --name '^rayterra preview' windowfocus --sync %1 \
    sleep 0.5 key p sleep 0.5 keydown Up sleep 0.6 keyup Up sleep 1.5 key p sleep 0.5 key s sleep 0.5 key Escape
keys=$?
wait $pid
status=$?
echo "keys $keys status $status"
"#;

/// The `O=` lines printed, as numbers.
fn eyes(stdout: &str) -> Vec<Vec<f64>> {
    stdout
        .lines()
        .filter_map(|l| l.trim().strip_prefix("O= "))
        .map(|l| l.split_whitespace().map(|n| n.parse().expect("a number")).collect())
        .collect()
}

/// sRGB-encodes a linear value as the window does, to 8 bits.
fn srgb8(c: f32) -> f32 {
    let c = c.clamp(0.0, 1.0);
    let e = if c <= 0.0031308 { 12.92 * c } else { 1.055 * c.powf(1.0 / 2.4) - 0.055 };
    (e * 255.0).round()
}

#[test]
fn the_window_converges_ends_on_the_output_and_prints_the_pose() {
    if !have_tools() {
        return;
    }
    let dir = tempfile::tempdir().expect("temp dir");
    let frames = dir.path().join("frames");
    std::fs::create_dir(&frames).expect("frames folder");
    let out = Command::new("timeout")
        .args(["180", "xvfb-run", "-a", "-s", "-screen 0 640x480x24", "bash", "-c", SCRIPT])
        .env("BIN", env!("CARGO_BIN_EXE_rayterra"))
        .env("SCENE", cornell())
        .env("DIR", dir.path())
        .env("RAYTERRA_PREVIEW_FRAMES", &frames)
        .output()
        .expect("run xvfb-run");
    let read = |name: &str| std::fs::read_to_string(dir.path().join(name)).unwrap_or_default();
    let (stdout, stderr) = (read("stdout.txt"), read("stderr.txt"));
    let said = format!(
        "xvfb-run: {}{}\nrayterra's stdout:\n{stdout}\nrayterra's stderr:\n{stderr}",
        text(&out.stdout),
        text(&out.stderr)
    );
    if no_window_here(&stderr) {
        return;
    }
    assert!(text(&out.stdout).contains("keys 0 status 0"), "{said}");
    assert!(!stderr.contains("panicked"), "{said}");
    assert!(stdout.contains("preview on "), "the window did not open: {said}");

    // The pose: the scene's before the move, higher after it (Up flies along the world's z).
    let eyes = eyes(&stdout);
    assert!(eyes.len() >= 3, "{said}");
    assert_eq!(eyes[0], vec![0.0, -3.9, 1.0], "{said}");
    let moved = &eyes[1];
    assert!(moved[0].abs() < 1e-4 && (moved[1] + 3.9).abs() < 1e-4 && moved[2] > 1.2, "{said}");
    assert!(stdout.contains("    N= 0 1 0"), "{said}");
    assert!(stdout.contains("the preview's camera when the window closed"), "{said}");
    assert!(stdout.contains("out.so-far.exr: the "), "S wrote nothing: {said}");

    // The output is the render's own bytes.
    let plain = dir.path().join("plain.exr");
    let rendered = Command::new(env!("CARGO_BIN_EXE_rayterra"))
        .args(["render", &cornell(), "--model", "path", "--spp", "64", "--size", "64x64", "-q", "-o"])
        .arg(&plain)
        .output()
        .expect("run rayterra");
    assert!(rendered.status.success(), "{}", text(&rendered.stderr));
    let first = dir.path().join("first.exr");
    assert!(std::fs::read(&first).ok() == std::fs::read(&plain).ok(), "--preview wrote other bytes");

    // The images shown: several before the finished one, which is the output's.
    let final_pixels = pixels(&first);
    let mut shown: Vec<PathBuf> = std::fs::read_dir(&frames)
        .expect("frames")
        .map(|e| e.expect("entry").path())
        .filter(|p| p.extension().is_some_and(|e| e == "exr"))
        .collect();
    shown.sort();
    let finished = shown
        .iter()
        .position(|p| pixels(p) == final_pixels)
        .unwrap_or_else(|| panic!("no frame shown is the output: {said}"));
    let before: Vec<Vec<[f32; 3]>> = shown[..finished].iter().map(|p| pixels(p)).collect();
    assert!(before.len() >= 2, "{} images before the finished one", before.len());
    assert!(before.windows(2).any(|w| w[0] != w[1]), "the picture did not change as passes arrived");

    // The window's picture of it: the output sRGB-encoded (to one level of rounding).
    let number = shown[finished]
        .file_stem()
        .and_then(|s| s.to_str())
        .and_then(|s| s.strip_prefix("frame-"))
        .expect("a frame name")
        .to_owned();
    let screen = pixels(&frames.join(format!("screen-{number}.png")));
    assert_eq!(screen.len(), final_pixels.len(), "the window is not the image's size at 1:1");
    for (i, (s, f)) in screen.iter().zip(&final_pixels).enumerate() {
        for c in 0..3 {
            let (got, want) = (s[c] * 255.0, srgb8(f[c]));
            assert!(
                (got - want).abs() <= 1.0,
                "pixel {i} channel {c}: the window shows {got}, the output is {want}"
            );
        }
    }
    let screens_before = shown[..finished]
        .iter()
        .filter_map(|p| {
            let n = p.file_stem()?.to_str()?.strip_prefix("frame-")?.to_owned();
            let png = frames.join(format!("screen-{n}.png"));
            png.exists().then(|| pixels(&png))
        })
        .collect::<Vec<_>>();
    assert!(screens_before.iter().any(|s| *s != screen), "the window's picture never changed");
}

/// The session of the denoiser test: the render, then `D` once the output is written.
const DENOISE_SCRIPT: &str = r#"
"$BIN" render "$SCENE" --preview --denoise --model path --spp 4 --size 48x48 -o "$DIR/out.exr" \
    > "$DIR/stdout.txt" 2> "$DIR/stderr.txt" &
pid=$!
for i in $(seq 1 1200); do [ -f "$DIR/out.exr" ] && break; sleep 0.1; done
timeout 60 xdotool search --sync --onlyvisible --name '^rayterra preview' windowfocus --sync %1 \
    sleep 0.5 key d sleep 3 key Escape
keys=$?
wait $pid
status=$?
echo "keys $keys status $status"
"#;

#[test]
fn d_shows_the_denoised_image_which_is_the_denoised_output() {
    if !have_tools() {
        return;
    }
    let dir = tempfile::tempdir().expect("temp dir");
    // OIDN, as the denoiser's own tests find it.
    let probe = Command::new(env!("CARGO_BIN_EXE_rayterra"))
        .args(["render", "--denoise", "--size", "4x4", "--spp", "1", "-q", "-o", "probe.exr"])
        .current_dir(dir.path())
        .output()
        .expect("run rayterra");
    if !probe.status.success() {
        let reason = "Open Image Denoise not found (pip install pyoidn==2.5.1.0, or set OIDN_DIR)";
        assert!(!under_ci(), "CI=true, so the preview's denoiser test cannot be skipped: {reason}");
        test_skips::skip("rayterra render --preview --denoise window test", reason);
        return;
    }
    let frames = dir.path().join("frames");
    std::fs::create_dir(&frames).expect("frames folder");
    let out = Command::new("timeout")
        .args(["180", "xvfb-run", "-a", "-s", "-screen 0 640x480x24", "bash", "-c", DENOISE_SCRIPT])
        .env("BIN", env!("CARGO_BIN_EXE_rayterra"))
        .env("SCENE", root().join("scenes/cornell-box.txt"))
        .env("DIR", dir.path())
        .env("RAYTERRA_PREVIEW_FRAMES", &frames)
        .output()
        .expect("run xvfb-run");
    let read = |name: &str| std::fs::read_to_string(dir.path().join(name)).unwrap_or_default();
    let (stdout, stderr) = (read("stdout.txt"), read("stderr.txt"));
    let said = format!(
        "xvfb-run: {}\nrayterra's stdout:\n{stdout}\nrayterra's stderr:\n{stderr}",
        text(&out.stdout)
    );
    if no_window_here(&stderr) {
        return;
    }
    assert!(text(&out.stdout).contains("keys 0 status 0"), "{said}");
    assert!(stdout.contains("preview: denoised image"), "{said}");
    let mut shown: Vec<PathBuf> = std::fs::read_dir(&frames)
        .expect("frames")
        .map(|e| e.expect("entry").path())
        .filter(|p| p.extension().is_some_and(|e| e == "exr"))
        .collect();
    shown.sort();
    let output = pixels(&dir.path().join("out.exr"));
    let last = pixels(shown.last().expect("frames shown"));
    // The output is the denoised render; the last image shown is the same image, denoised by the
    // preview on D.
    assert!(last == output, "the denoised image shown is not the denoised output: {said}");
    let noisy = &shown[shown.len() - 2];
    assert!(pixels(noisy) != output, "the image before D was already the denoised one");
}
