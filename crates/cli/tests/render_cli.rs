//! `rayterra render` from the outside: exit codes, messages, and files written or not.

use std::path::Path;
use std::process::{Command, Output};

fn rayterra(args: &[&str], dir: &Path) -> Output {
    Command::new(env!("CARGO_BIN_EXE_rayterra")).args(args).current_dir(dir).output().expect("run rayterra")
}

fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

const SMALL_SCENE: &str = "camera\n O= 0 -4 1\n N= 0 1 0\n image_W= 40\n image_H= 30\n lens_W= 0.8\n lens_H= 0.6\nend\n\
                           light point\n O= 2 -2 4\n color= 1 1 1\nend\n\
                           primitive sphere\n O= 0 0 1\n R= 1\n color= 1 0.5 0.2\n diff= 1\n texture= builtin:marble\nend\n\
                           primitive plane\n N= 0 0 1\n R= 0\n color= 1 1 1\n diff= 0.8\nend\n";

#[test]
fn renders_a_scene_and_reports_time_and_rays() {
    let dir = tempfile::tempdir().expect("temp dir");
    std::fs::write(dir.path().join("scene.txt"), SMALL_SCENE).expect("write scene");
    let out = rayterra(&["render", "scene.txt", "-o", "out.png"], dir.path());
    assert!(out.status.success(), "{}", text(&out.stderr));
    let stdout = text(&out.stdout);
    assert!(stdout.contains("wrote out.png"), "{stdout}");
    assert!(stdout.contains("40x30 pixels in") && stdout.contains("M rays/s"), "{stdout}");
    let img = image::open(dir.path().join("out.png")).expect("a PNG");
    assert_eq!((img.width(), img.height()), (40, 30));
}

#[test]
fn size_spp_threads_gamma_and_formats() {
    let dir = tempfile::tempdir().expect("temp dir");
    std::fs::write(dir.path().join("scene.txt"), SMALL_SCENE).expect("write scene");
    for (name, extra) in [("a.bmp", &["--gamma"][..]), ("b.exr", &[][..]), ("c.hdr", &["--spp", "4"][..])] {
        let mut args = vec!["render", "scene.txt", "-q", "--size", "24x18", "--threads", "2", "-o", name];
        args.extend_from_slice(extra);
        let out = rayterra(&args, dir.path());
        assert!(out.status.success(), "{name}: {}", text(&out.stderr));
        assert!(out.stdout.is_empty(), "--quiet prints nothing");
        let img = image::open(dir.path().join(name)).expect("readable");
        assert_eq!((img.width(), img.height()), (24, 18), "{name}");
    }
}

#[test]
fn scene_errors_name_file_line_and_column_and_write_nothing() {
    let dir = tempfile::tempdir().expect("temp dir");
    std::fs::write(
        dir.path().join("broken.txt"),
        "primitive sphere\n O= 0 0 0\n R= -1\n color= 1 x 0\nend\n",
    )
    .expect("write scene");
    let out = rayterra(&["render", "broken.txt", "-o", "out.png"], dir.path());
    assert_eq!(out.status.code(), Some(1));
    let stderr = text(&out.stderr);
    assert!(
        stderr.contains(
            "error: in `primitive sphere`, the radius must be positive, not -1\n --> broken.txt:3:5"
        ),
        "{stderr}"
    );
    assert!(stderr.contains("--> broken.txt:4:11"), "{stderr}");
    assert!(stderr.contains("4 |  color= 1 x 0\n  |           ^\n"), "{stderr}");
    assert!(stderr.contains("error: `broken.txt` has 2 errors; nothing was rendered"), "{stderr}");
    assert!(!dir.path().join("out.png").exists());
}

#[test]
fn check_validates_without_rendering() {
    let dir = tempfile::tempdir().expect("temp dir");
    std::fs::write(
        dir.path().join("scene.txt"),
        format!("{SMALL_SCENE}primitive sphere\n O= 0 0 0\n R= 1\n gloss= 1\nend\n"),
    )
    .expect("write scene");
    let out = rayterra(&["render", "--check", "scene.txt"], dir.path());
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert!(text(&out.stderr).contains("warning: unknown key `gloss=` in `primitive sphere`; ignored"));
    assert!(
        text(&out.stdout).contains("scene.txt: ok (3 primitives, 1 light, 40x30 pixels, classic model)"),
        "{}",
        text(&out.stdout)
    );
    assert!(!dir.path().join("render.png").exists(), "--check renders nothing");
    let builtin = rayterra(&["render", "--check"], dir.path());
    assert!(builtin.status.success(), "{}", text(&builtin.stderr));
    assert!(
        text(&builtin.stdout)
            .contains("showcase.txt (built in): ok (9 primitives, 1 light, 1280x760 pixels, classic model)")
    );
}

#[test]
fn thousands_of_errors_print_fifty_and_a_count() {
    let dir = tempfile::tempdir().expect("temp dir");
    // 100,000 unclosed blocks: 300,000 errors.
    std::fs::write(dir.path().join("blocks.txt"), "primitive sphere\n".repeat(100_000)).expect("write");
    let out = rayterra(&["render", "blocks.txt"], dir.path());
    assert_eq!(out.status.code(), Some(1));
    let stderr = text(&out.stderr);
    assert_eq!(stderr.matches("error: the `primitive sphere` block has no `end`").count(), 17, "{stderr}");
    assert!(stderr.contains("\n... and 299950 more errors\n"), "{stderr}");
    assert!(stderr.ends_with("error: `blocks.txt` has 300000 errors; nothing was rendered\n"), "{stderr}");
    assert!(stderr.len() < 20_000, "{} bytes", stderr.len());
}

#[test]
fn scene_paths_that_are_not_files_are_refused() {
    let dir = tempfile::tempdir().expect("temp dir");
    let out = rayterra(&["render", "."], dir.path());
    assert_eq!(out.status.code(), Some(1));
    assert!(
        text(&out.stderr).contains("cannot read scene file `.`: it is a directory"),
        "{}",
        text(&out.stderr)
    );
    let out = rayterra(&["render", "/dev/zero", "--check"], dir.path());
    assert_eq!(out.status.code(), Some(1));
    assert!(text(&out.stderr).contains("it is not a regular file"), "{}", text(&out.stderr));
}

#[test]
fn missing_texture_is_an_error_at_its_line() {
    let dir = tempfile::tempdir().expect("temp dir");
    std::fs::write(dir.path().join("scene.txt"), SMALL_SCENE.replace("builtin:marble", "stone.bmp"))
        .expect("write");
    let out = rayterra(&["render", "scene.txt", "-o", "out.png"], dir.path());
    assert_eq!(out.status.code(), Some(1));
    let stderr = text(&out.stderr);
    assert!(stderr.contains("cannot find texture `stone.bmp` (looked in `./stone.bmp`)"), "{stderr}");
    assert!(stderr.contains("--> scene.txt:18:11"), "{stderr}");
    assert!(stderr.contains("--textures DIR"), "{stderr}");
    assert!(!dir.path().join("out.png").exists());
    // A corrupt texture file is named with the decoder's reason.
    std::fs::write(dir.path().join("stone.bmp"), b"BM not really a bitmap").expect("write");
    let out = rayterra(&["render", "scene.txt", "-o", "out.png"], dir.path());
    assert_eq!(out.status.code(), Some(1));
    assert!(text(&out.stderr).contains("cannot read texture"), "{}", text(&out.stderr));
    // Found through --textures.
    std::fs::create_dir(dir.path().join("tex")).expect("mkdir");
    image::RgbImage::from_pixel(4, 4, image::Rgb([200, 100, 50]))
        .save(dir.path().join("tex/stone.bmp"))
        .expect("bmp");
    std::fs::remove_file(dir.path().join("stone.bmp")).expect("rm");
    let out = rayterra(&["render", "scene.txt", "-q", "--textures", "tex", "-o", "out.png"], dir.path());
    assert!(out.status.success(), "{}", text(&out.stderr));
}

#[test]
fn memory_limit_bounds_the_textures_and_missing_texture_folders_are_warned_about() {
    let dir = tempfile::tempdir().expect("temp dir");
    image::GrayImage::new(1024, 1024).save(dir.path().join("big.png")).expect("png");
    std::fs::write(dir.path().join("scene.txt"), SMALL_SCENE.replace("builtin:marble", "big.png"))
        .expect("write");
    let out = rayterra(&["render", "scene.txt", "--check", "--memory-limit", "6M"], dir.path());
    assert_eq!(out.status.code(), Some(1));
    let stderr = text(&out.stderr);
    assert!(stderr.contains("texture `big.png` (1024x1024 pixels) needs 8.0 MiB"), "{stderr}");
    assert!(
        stderr.contains("over the memory limit of 6.0 MiB") && stderr.contains("scene.txt:18:11"),
        "{stderr}"
    );
    let out = rayterra(&["render", "scene.txt", "--check", "--textures", "nowhere"], dir.path());
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert!(
        text(&out.stderr)
            .contains("warning: --textures `nowhere` does not exist; no texture or mesh is looked for there"),
        "{}",
        text(&out.stderr)
    );
    let out = rayterra(&["render", "scene.txt", "--check", "--memory-limit", "lots"], dir.path());
    assert_eq!(out.status.code(), Some(2), "a malformed option");
}

#[test]
fn bad_requests_are_refused_without_output() {
    let dir = tempfile::tempdir().expect("temp dir");
    std::fs::write(dir.path().join("scene.txt"), SMALL_SCENE).expect("write scene");
    let cases: [(&[&str], i32, &str); 8] = [
        (&["render", "scene.txt", "--size", "100000x100000"], 2, "out of range"),
        (&["render", "scene.txt", "--size", "30000x30000"], 2, "too large"),
        (&["render", "scene.txt", "--size", "12"], 2, "expected WIDTHxHEIGHT"),
        (&["render", "scene.txt", "-o", "out.gif"], 1, "use .png, .bmp, .exr or .hdr"),
        (&["render", "scene.txt", "--spp", "0"], 2, "--spp"),
        (&["render", "no-such-scene.txt"], 1, "cannot read scene file `no-such-scene.txt`"),
        (
            &["render", "scene.txt", "-o", "no/such/dir/out.png"],
            1,
            "cannot write `no/such/dir/out.png`: the folder",
        ),
        (&["render", "scene.txt", "-o", "."], 1, "cannot tell the image format of `.`"),
    ];
    for (args, code, message) in cases {
        let out = rayterra(args, dir.path());
        assert_eq!(out.status.code(), Some(code), "{args:?}: {}", text(&out.stderr));
        assert!(text(&out.stderr).contains(message), "{args:?}: {}", text(&out.stderr));
    }
    let left: Vec<_> =
        std::fs::read_dir(dir.path()).expect("list").map(|e| e.expect("entry").file_name()).collect();
    assert_eq!(left, vec![std::ffi::OsString::from("scene.txt")], "nothing written");
}

#[test]
fn help_lists_every_option() {
    let out = rayterra(&["render", "--help"], Path::new("."));
    let help = text(&out.stdout);
    for option in [
        "--output",
        "--size",
        "--spp",
        "--threads",
        "--textures",
        "--gamma",
        "--check",
        "--seed",
        "--quiet",
        "--model",
        "--photons",
        "--passes",
        "--max-depth",
        "path",
        "sppm",
    ] {
        assert!(help.contains(option), "{option} missing from:\n{help}");
    }
}

/// A small scene set up for the course's photon mapper.
const PHOTON_SCENE: &str = "camera\n O= 0 -4 1\n N= 0 1 0\n image_W= 40\n image_H= 30\n lens_W= 0.8\n lens_H= 0.6\n\
                            emit_photons= 20000\n sample_photons= 30\nend\n\
                            light area\n O= 0 0 3\n Dx= 1 0 0\n Dy= 0 1 0\n color= 4 4 4\nend\n\
                            primitive sphere\n O= 0 0 1\n R= 1\n refr= 1\n rindex= 1.5\nend\n\
                            primitive plane\n N= 0 0 1\n R= 0\n color= 1 1 1\n diff= 0.8\nend\n";

#[test]
fn the_photon_model_reports_both_phases() {
    let dir = tempfile::tempdir().expect("temp dir");
    std::fs::write(dir.path().join("scene.txt"), PHOTON_SCENE).expect("write scene");
    let out = rayterra(
        &["render", "scene.txt", "--model", "photon", "--photons", "5000", "-o", "out.png"],
        dir.path(),
    );
    assert!(out.status.success(), "{}", text(&out.stderr));
    let stdout = text(&out.stdout);
    assert!(stdout.contains("5000 photons emitted in"), "{stdout}");
    assert!(stdout.contains("stored") && stdout.contains("search tree built in"), "{stdout}");
    assert!(stdout.contains("40x30 pixels in") && stdout.contains("photon-map lookups"), "{stdout}");
    assert!(!text(&out.stderr).contains("warning"), "{}", text(&out.stderr));
    assert!(dir.path().join("out.png").is_file());
}

#[test]
fn photon_keys_under_the_default_model_draw_one_warning() {
    let dir = tempfile::tempdir().expect("temp dir");
    std::fs::write(dir.path().join("scene.txt"), PHOTON_SCENE).expect("write scene");
    let out = rayterra(&["render", "scene.txt", "-q", "-o", "out.png"], dir.path());
    assert!(out.status.success());
    let stderr = text(&out.stderr);
    assert_eq!(stderr.matches("warning:").count(), 1, "{stderr}");
    assert!(stderr.contains("photon-mapping keys") && stderr.contains("--model photon"), "{stderr}");
    assert!(stderr.contains("scene.txt:8:1"), "{stderr}");
    // Chosen on purpose: no warning.
    let out = rayterra(&["render", "scene.txt", "-q", "--model", "classic", "-o", "out.png"], dir.path());
    assert!(out.status.success() && out.stderr.is_empty(), "{}", text(&out.stderr));
}

#[test]
fn algorithm_picks_the_model_and_unknown_values_are_errors() {
    let dir = tempfile::tempdir().expect("temp dir");
    let with = |value: &str| {
        PHOTON_SCENE.replace("sample_photons= 30\n", &format!("sample_photons= 30\n algorithm= {value}\n"))
    };
    std::fs::write(dir.path().join("pm.txt"), with("PM")).expect("write scene");
    let out = rayterra(&["render", "pm.txt", "--check"], dir.path());
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert!(text(&out.stdout).contains("photon model"), "{}", text(&out.stdout));
    for value in ["SPPM", "PPM", "sppm"] {
        std::fs::write(dir.path().join("sppm.txt"), with(value)).expect("write scene");
        let out = rayterra(&["render", "sppm.txt", "--check"], dir.path());
        assert!(out.status.success() && out.stderr.is_empty(), "{value}: {}", text(&out.stderr));
        assert!(text(&out.stdout).contains("sppm model"), "{value}: {}", text(&out.stdout));
    }
    std::fs::write(dir.path().join("bad.txt"), with("MLT")).expect("write scene");
    let out = rayterra(&["render", "bad.txt", "-o", "out.png"], dir.path());
    assert_eq!(out.status.code(), Some(1));
    let stderr = text(&out.stderr);
    assert!(stderr.contains("unknown `algorithm=` `MLT`") && stderr.contains("bad.txt:10:13"), "{stderr}");
    assert!(!dir.path().join("out.png").exists());
    let out = rayterra(&["render", "pm.txt", "--model", "wavelets"], dir.path());
    assert_eq!(out.status.code(), Some(2), "malformed options exit with 2");
}

#[test]
fn a_photon_map_over_the_memory_limit_is_refused_at_its_line_before_rendering() {
    let dir = tempfile::tempdir().expect("temp dir");
    let scene =
        PHOTON_SCENE.replace("emit_photons= 20000\n", "emit_photons= 20000\n max_photons= 500000000\n");
    std::fs::write(dir.path().join("scene.txt"), scene).expect("write scene");
    for args in [
        &["render", "scene.txt", "--model", "photon", "--check"][..],
        &["render", "scene.txt", "--model", "photon"][..],
    ] {
        let out = rayterra(args, dir.path());
        assert_eq!(out.status.code(), Some(1), "{args:?}");
        let stderr = text(&out.stderr);
        assert!(stderr.contains("would need 18.6 GiB of memory, over the limit of 4.0 GiB"), "{stderr}");
        assert!(stderr.contains("scene.txt:9:"), "{stderr}");
    }
    assert!(!dir.path().join("render.png").exists());
}

#[test]
fn a_full_photon_map_is_reported() {
    let dir = tempfile::tempdir().expect("temp dir");
    let scene = PHOTON_SCENE.replace("emit_photons= 20000\n", "emit_photons= 200000\n max_photons= 2000\n");
    std::fs::write(dir.path().join("scene.txt"), scene).expect("write scene");
    let out = rayterra(&["render", "scene.txt", "--model", "photon", "-q", "-o", "out.png"], dir.path());
    assert!(out.status.success());
    let stderr = text(&out.stderr);
    assert!(stderr.contains("warning: the photon map was full (`max_photons= 2000`)"), "{stderr}");
}

#[test]
fn the_path_model_reports_samples_a_second_and_writes_linear_or_tone_mapped_images() {
    let dir = tempfile::tempdir().expect("temp dir");
    std::fs::write(dir.path().join("scene.txt"), PHOTON_SCENE).expect("write scene");
    let out = rayterra(
        &["render", "scene.txt", "--model", "path", "--spp", "8", "--max-depth", "6", "-o", "out.exr"],
        dir.path(),
    );
    assert!(out.status.success(), "{}", text(&out.stderr));
    let stdout = text(&out.stdout);
    assert!(stdout.contains("path model, paths of at most 6 segments"), "{stdout}");
    assert!(stdout.contains("8 samples a pixel, 9600 samples") && stdout.contains("M samples/s"), "{stdout}");
    assert!(text(&out.stderr).is_empty(), "{}", text(&out.stderr));
    let hdr = image::open(dir.path().join("out.exr")).expect("an EXR").to_rgb32f();
    assert!(hdr.pixels().any(|p| p.0[0] > 0.0), "the floor is lit");
    let out = rayterra(
        &["render", "scene.txt", "--model", "path", "--spp", "2", "-q", "-o", "out.png"],
        dir.path(),
    );
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert!(image::open(dir.path().join("out.png")).is_ok());
}

#[test]
fn the_sppm_model_reports_passes_and_photons_and_warns_about_unused_options() {
    let dir = tempfile::tempdir().expect("temp dir");
    std::fs::write(dir.path().join("scene.txt"), PHOTON_SCENE).expect("write scene");
    let out = rayterra(
        &[
            "render",
            "scene.txt",
            "--model",
            "sppm",
            "--passes",
            "3",
            "--photons",
            "4000",
            "--spp",
            "4",
            "-o",
            "out.png",
        ],
        dir.path(),
    );
    assert!(out.status.success(), "{}", text(&out.stderr));
    let stdout = text(&out.stdout);
    assert!(stdout.contains("3 passes of 4000 photons (12000 emitted"), "{stdout}");
    assert!(stdout.contains("passes/s") && stdout.contains("M photons/s"), "{stdout}");
    assert!(text(&out.stderr).contains("--spp has no effect on the sppm model"), "{}", text(&out.stderr));
    let out = rayterra(&["render", "scene.txt", "--max-depth", "4", "-q", "-o", "c.png"], dir.path());
    let stderr = text(&out.stderr);
    assert!(stderr.contains("--max-depth has no effect on the classic model"), "{stderr}");
}

#[test]
fn sppm_refuses_more_pixels_than_max_hitpoints_allows() {
    let dir = tempfile::tempdir().expect("temp dir");
    let scene = PHOTON_SCENE.replace("emit_photons= 20000\n", "emit_photons= 20000\n max_hitpoints= 1000\n");
    std::fs::write(dir.path().join("scene.txt"), scene).expect("write scene");
    let out = rayterra(&["render", "scene.txt", "--model", "sppm", "-o", "out.png"], dir.path());
    assert_eq!(out.status.code(), Some(1));
    let stderr = text(&out.stderr);
    assert!(stderr.contains("1200 pixels, but `max_hitpoints= 1000` allows fewer"), "{stderr}");
    assert!(stderr.contains("scene.txt:9:"), "{stderr}");
    assert!(!dir.path().join("out.png").exists());
}

/// A scene that takes a few seconds at 2048x2048, most of it rendering, then ~0.2 s writing.
#[cfg(unix)]
const SLOW_SCENE: &str = "camera\n O= 0 -4 0\n N= 0 1 0\n lens_W= 1\n lens_H= 1\nend\n\
                          light point\n O= 0 -3 3\n color= 1 1 1\nend\n\
                          primitive sphere\n O= 0 0 0\n R= 2.5\n diff= 1\n texture= builtin:marble\nend\n";

#[cfg(unix)]
fn send_signal(child: &std::process::Child, signal: &str) {
    let status = Command::new("kill").args([signal, &child.id().to_string()]).status().expect("kill");
    assert!(status.success());
}

#[cfg(unix)]
fn file_names(dir: &Path) -> Vec<String> {
    std::fs::read_dir(dir)
        .expect("list")
        .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
        .collect()
}

#[cfg(unix)]
#[test]
fn an_interrupted_write_removes_its_temporary_file_and_exits_130() {
    use std::process::Stdio;
    use std::time::{Duration, Instant};
    let dir = tempfile::tempdir().expect("temp dir");
    std::fs::write(dir.path().join("scene.txt"), SLOW_SCENE).expect("write scene");
    // Catch the process while its temporary file exists; a very fast machine may write it before
    // it is seen, so a larger image is tried then.
    for side in [2048, 4096, 4096] {
        let size = format!("{side}x{side}");
        let mut child = Command::new(env!("CARGO_BIN_EXE_rayterra"))
            .args(["render", "scene.txt", "-q", "--size", &size, "-o", "out.png"])
            .current_dir(dir.path())
            .stderr(Stdio::piped())
            .spawn()
            .expect("run rayterra");
        let started = Instant::now();
        let mut caught = false;
        while started.elapsed() < Duration::from_secs(300) {
            if file_names(dir.path()).iter().any(|n| n.ends_with(".part")) {
                send_signal(&child, "-INT");
                caught = true;
                break;
            }
            if child.try_wait().expect("wait").is_some() {
                break;
            }
            std::thread::sleep(Duration::from_millis(1));
        }
        let out = child.wait_with_output().expect("wait");
        if !caught {
            assert!(out.status.success(), "{}", text(&out.stderr));
            std::fs::remove_file(dir.path().join("out.png")).expect("rm");
            continue;
        }
        let stderr = text(&out.stderr);
        assert_eq!(out.status.code(), Some(130), "{stderr}");
        // Caught outside the write, and another try is made: after it (the write finished and
        // renamed its file between the look and the signal), or before it (the file seen was the
        // probe by which the output's folder is checked before rendering, which has the same
        // name). Either way nothing unfinished may be left behind.
        if !stderr.contains("removed") {
            let _ = std::fs::remove_file(dir.path().join("out.png"));
            assert_eq!(file_names(dir.path()), ["scene.txt"], "nothing left behind: {stderr}");
            continue;
        }
        assert!(stderr.contains("rayterra: interrupted; the unfinished output file was removed"), "{stderr}");
        assert_eq!(file_names(dir.path()), ["scene.txt"], "nothing left behind");
        return;
    }
    panic!("the temporary file was never seen while the image was written");
}

#[cfg(unix)]
#[test]
fn sigterm_during_a_render_exits_130_without_output() {
    use std::time::Duration;
    let dir = tempfile::tempdir().expect("temp dir");
    std::fs::write(dir.path().join("scene.txt"), SLOW_SCENE).expect("write scene");
    let child = Command::new(env!("CARGO_BIN_EXE_rayterra"))
        .args(["render", "scene.txt", "-q", "--size", "4096x4096", "-o", "out.png"])
        .current_dir(dir.path())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("run rayterra");
    std::thread::sleep(Duration::from_millis(500));
    send_signal(&child, "-TERM");
    let out = child.wait_with_output().expect("wait");
    assert_eq!(out.status.code(), Some(130), "{}", text(&out.stderr));
    assert!(text(&out.stderr).contains("rayterra: interrupted"), "{}", text(&out.stderr));
    assert_eq!(file_names(dir.path()), ["scene.txt"]);
}

/// Issue 31, defect 1: the checkpoint is removed once the image is written, so a checkpoint that
/// is the output (under any name) or an input of the render would destroy it.
#[test]
fn a_checkpoint_or_output_that_is_another_file_of_the_render_is_refused() {
    let dir = tempfile::tempdir().expect("temp dir");
    std::fs::write(dir.path().join("scene.txt"), SMALL_SCENE.replace("builtin:marble", "stone.bmp"))
        .expect("write scene");
    image::RgbImage::from_pixel(4, 4, image::Rgb([200, 100, 50]))
        .save(dir.path().join("stone.bmp"))
        .expect("bmp");
    let stone = std::fs::read(dir.path().join("stone.bmp")).expect("read");
    let scene = std::fs::read(dir.path().join("scene.txt")).expect("read");
    let abs = dir.path().join("a.png");
    let abs = abs.to_str().expect("utf-8 path");
    let cases: [(&[&str], &str); 6] = [
        (&["-o", "a.png", "--checkpoint", "a.png"], "are the same file"),
        (&["-o", "a.png", "--checkpoint", "./a.png"], "are the same file"),
        (&["-o", abs, "--checkpoint", "a.png"], "are the same file"),
        (&["-o", "a.png", "--checkpoint", "scene.txt"], "which the render reads"),
        (&["-o", "a.png", "--checkpoint", "./stone.bmp"], "which the render reads"),
        (&["-o", "stone.bmp", "--checkpoint", "c.ckpt"], "which the render reads"),
    ];
    for (extra, needle) in cases {
        let mut args = vec!["render", "scene.txt", "-q", "--size", "8x6"];
        args.extend_from_slice(extra);
        let out = rayterra(&args, dir.path());
        let stderr = text(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{extra:?}: {stderr}");
        assert!(stderr.contains(needle), "{extra:?}: {stderr}");
        assert!(!dir.path().join("a.png").exists() && !dir.path().join("c.ckpt").exists(), "{extra:?}");
        assert_eq!(std::fs::read(dir.path().join("stone.bmp")).expect("read"), stone, "{extra:?}");
        assert_eq!(std::fs::read(dir.path().join("scene.txt")).expect("read"), scene, "{extra:?}");
    }
    // An existing image named twice is the same file too, and is kept.
    let out = rayterra(&["render", "scene.txt", "-q", "--size", "8x6", "-o", "a.png"], dir.path());
    assert!(out.status.success(), "{}", text(&out.stderr));
    let out = rayterra(
        &["render", "scene.txt", "-q", "--size", "8x6", "-o", "a.png", "--checkpoint", abs],
        dir.path(),
    );
    assert_eq!(out.status.code(), Some(2), "{}", text(&out.stderr));
    assert!(dir.path().join("a.png").exists(), "the earlier image is kept");
    // Distinct files are fine, and the checkpoint is gone afterwards.
    let out = rayterra(
        &["render", "scene.txt", "-q", "--size", "8x6", "-o", "b.png", "--checkpoint", "b.ckpt"],
        dir.path(),
    );
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert!(dir.path().join("b.png").exists() && !dir.path().join("b.ckpt").exists());
}

/// `rayterra ARGS` in `dir`, killed after `seconds` (`None`: it hung).
#[cfg(unix)]
fn rayterra_within(args: &[&str], dir: &Path, seconds: u64) -> Option<Output> {
    use std::process::Stdio;
    use std::time::{Duration, Instant};
    let mut child = Command::new(env!("CARGO_BIN_EXE_rayterra"))
        .args(args)
        .current_dir(dir)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("run rayterra");
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

/// Issue 31, defect 2: named pipes (an OBJ's `mtllib`, `--checkpoint`, a part to merge, the scene
/// itself) are refused at once instead of waiting forever for a writer.
#[cfg(unix)]
#[test]
fn named_pipes_are_refused_without_waiting() {
    let dir = tempfile::tempdir().expect("temp dir");
    for name in ["pipe.mtl", "pipe.ckpt", "pipe.exr", "pipe.txt"] {
        let made = Command::new("mkfifo").arg(dir.path().join(name)).status().expect("mkfifo runs");
        assert!(made.success());
    }
    std::fs::write(dir.path().join("m.obj"), "mtllib pipe.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
        .expect("write obj");
    std::fs::write(
        dir.path().join("mesh.txt"),
        format!("{SMALL_SCENE}primitive mesh\n file= m.obj\n diff= 1\nend\n"),
    )
    .expect("write scene");
    std::fs::write(dir.path().join("scene.txt"), SMALL_SCENE).expect("write scene");
    let cases: [(&[&str], &str); 4] = [
        (&["render", "mesh.txt", "--check"], "pipe.mtl"),
        (&["render", "scene.txt", "--size", "8x6", "-o", "a.png", "--checkpoint", "pipe.ckpt"], "pipe.ckpt"),
        (&["merge", "pipe.exr", "-o", "a.png"], "pipe.exr"),
        (&["render", "pipe.txt", "-o", "a.png"], "pipe.txt"),
    ];
    for (args, needle) in cases {
        let out = rayterra_within(args, dir.path(), 60).unwrap_or_else(|| panic!("{args:?} hung on a pipe"));
        let stderr = text(&out.stderr);
        assert!(stderr.contains(needle) && stderr.contains("not a regular file"), "{args:?}: {stderr}");
        assert!(!stderr.contains("panicked"), "{args:?}: {stderr}");
    }
    assert!(!dir.path().join("a.png").exists());
}

/// Runs `rayterra ARGS` in `dir` with its standard output (and, if `close_stderr`, its standard
/// error) a pipe whose reading end is closed before it writes: what `rayterra ... | head -0`
/// gives it.
#[cfg(unix)]
pub fn rayterra_into_closed_pipes(args: &[&str], dir: &Path, close_stderr: bool) -> Output {
    use std::process::Stdio;
    let mut child = Command::new(env!("CARGO_BIN_EXE_rayterra"))
        .args(args)
        .current_dir(dir)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("run rayterra");
    drop(child.stdout.take());
    if close_stderr {
        drop(child.stderr.take());
    }
    child.wait_with_output().expect("wait")
}

/// Issue 31, defect 3: a closed standard output (or error) is not an error of the work: the
/// image is written, nothing panics, and the exit status is the work's.
#[cfg(unix)]
#[test]
fn closed_output_streams_neither_panic_nor_lose_the_image() {
    let dir = tempfile::tempdir().expect("temp dir");
    std::fs::write(dir.path().join("scene.txt"), SMALL_SCENE).expect("write scene");
    for close_stderr in [false, true] {
        let _ = std::fs::remove_file(dir.path().join("a.png"));
        let out = rayterra_into_closed_pipes(
            &["render", "scene.txt", "--size", "8x6", "-o", "a.png"],
            dir.path(),
            close_stderr,
        );
        let stderr = text(&out.stderr);
        assert_eq!(out.status.code(), Some(0), "stderr closed: {close_stderr}: {stderr}");
        assert!(!stderr.contains("panicked"), "{stderr}");
        assert!(image::open(dir.path().join("a.png")).is_ok(), "the image is written");
    }
    // An error is still an error.
    let out = rayterra_into_closed_pipes(&["render", "missing.txt", "-o", "b.png"], dir.path(), true);
    assert_eq!(out.status.code(), Some(1));
}

/// Issue 31, defect 6: an output path ending with a slash names a folder: refused before any
/// work, by render (whole or a part) and merge.
#[test]
fn an_output_path_ending_with_a_slash_is_refused_before_any_work() {
    let dir = tempfile::tempdir().expect("temp dir");
    std::fs::write(dir.path().join("scene.txt"), SMALL_SCENE).expect("write scene");
    let out =
        rayterra(&["render", "scene.txt", "-q", "--size", "8x6", "--tile", "0/1", "-o", "p.exr"], dir.path());
    assert!(out.status.success(), "{}", text(&out.stderr));
    for args in [
        &["render", "scene.txt", "--size", "8x6", "-o", "out.png/"][..],
        &["render", "scene.txt", "--size", "8x6", "-o", "out.png/."][..],
        &["render", "scene.txt", "--size", "8x6", "--tile", "0/2", "-o", "part.exr/"][..],
        &["merge", "p.exr", "-o", "out.png/"][..],
    ] {
        let out = rayterra(args, dir.path());
        let stderr = text(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{args:?}: {stderr}");
        assert!(stderr.contains("names a folder"), "{args:?}: {stderr}");
    }
    let mut left: Vec<_> =
        std::fs::read_dir(dir.path()).expect("list").map(|e| e.expect("entry").file_name()).collect();
    left.sort();
    assert_eq!(left, ["p.exr", "scene.txt"], "nothing written");
}

/// Issue 31, defect 11: malformed options exit with status 2; messages have no debug formatting;
/// the aspect warning names the size rendered.
#[test]
fn small_ones_exit_codes_plain_messages_and_the_size_rendered() {
    let dir = tempfile::tempdir().expect("temp dir");
    std::fs::write(dir.path().join("scene.txt"), SMALL_SCENE).expect("write scene");
    for args in [
        &["render", "scene.txt", "--size", "8200x8200"][..],
        &["render", "scene.txt", "--tile", "3/2", "-o", "t.exr"][..],
        &["render", "scene.txt", "--pass", "auto/0", "-o", "t.exr"][..],
    ] {
        let out = rayterra(args, dir.path());
        assert_eq!(out.status.code(), Some(2), "{args:?}: {}", text(&out.stderr));
    }
    let out = rayterra(&["render", "scene.txt", "-q", "--size", "8x6", "--gamma", "-o", "a.exr"], dir.path());
    let stderr = text(&out.stderr);
    assert!(stderr.contains("no effect on linear EXR output"), "{stderr}");
    // A square lens on a 40x30 image: the file's size is not the one rendered.
    let square = SMALL_SCENE.replace(" lens_W= 0.8\n lens_H= 0.6\n", " lens_W= 1\n lens_H= 1\n");
    std::fs::write(dir.path().join("square.txt"), square).expect("write scene");
    let out = rayterra(&["render", "square.txt", "-q", "--size", "20x20", "-o", "s.png"], dir.path());
    let stderr = text(&out.stderr);
    assert!(out.status.success() && !stderr.contains("aspect"), "{stderr}");
    let out = rayterra(&["render", "square.txt", "-q", "--size", "80x60", "-o", "s.png"], dir.path());
    let stderr = text(&out.stderr);
    assert!(stderr.contains("image aspect 80/60") && !stderr.contains("40/30"), "{stderr}");
    assert_eq!(stderr.matches("aspect").count(), 2, "one warning: {stderr}");
    // A PNG texture with a broken checksum: the decoder's message names the chunk plainly.
    let mut png = Vec::new();
    image::RgbImage::from_pixel(4, 4, image::Rgb([9, 9, 9]))
        .write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
        .expect("png");
    png[30] ^= 0xff; // In IHDR's CRC.
    std::fs::write(dir.path().join("bad.png"), &png).expect("write");
    std::fs::write(dir.path().join("bad.txt"), SMALL_SCENE.replace("builtin:marble", "bad.png"))
        .expect("write");
    let out = rayterra(&["render", "bad.txt", "--check"], dir.path());
    let stderr = text(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.contains("IHDR") && !stderr.contains("ChunkType") && !stderr.contains("critical:"),
        "{stderr}"
    );
}

/// Issue 31, defect 11: after Ctrl-C, a render with `--checkpoint` says the checkpoint is kept and
/// how to go on.
#[cfg(unix)]
#[test]
fn an_interrupted_render_says_its_checkpoint_is_kept() {
    use std::time::{Duration, Instant};
    let dir = tempfile::tempdir().expect("temp dir");
    std::fs::write(dir.path().join("scene.txt"), SLOW_SCENE).expect("write scene");
    let child = Command::new(env!("CARGO_BIN_EXE_rayterra"))
        .args(["render", "scene.txt", "-q", "--size", "2048x2048", "-o", "out.png", "--checkpoint", "c.ckpt"])
        .current_dir(dir.path())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("run rayterra");
    let started = Instant::now();
    while !dir.path().join("c.ckpt").exists() && started.elapsed() < Duration::from_secs(120) {
        std::thread::sleep(Duration::from_millis(5));
    }
    send_signal(&child, "-INT");
    let out = child.wait_with_output().expect("wait");
    let stderr = text(&out.stderr);
    assert_eq!(out.status.code(), Some(130), "{stderr}");
    assert!(
        stderr.contains("the checkpoint `c.ckpt` is kept") && stderr.contains("run the same command again"),
        "{stderr}"
    );
    assert!(dir.path().join("c.ckpt").exists());
}

#[test]
fn a_file_of_nuls_gives_a_short_report() {
    // 8 MB of NUL bytes: one line, one token. The report quoted it whole (5 bytes of escape per
    // NUL, twice: over 80 MB of standard error); each quoted token is now cut with `...`.
    let dir = tempfile::tempdir().expect("temp dir");
    std::fs::write(dir.path().join("n.txt"), vec![0u8; 8 << 20]).expect("write scene");
    // And a texture path of a million characters, quoted by the texture's messages.
    let long_path =
        format!("primitive sphere\n O= 0 0 0\n R= 1\n texture= {}.bmp\nend\n", "d".repeat(1 << 20));
    std::fs::write(dir.path().join("t.txt"), long_path).expect("write scene");
    for scene in ["n.txt", "t.txt"] {
        let out = rayterra(&["render", scene, "-o", "out.png"], dir.path());
        assert_eq!(out.status.code(), Some(1), "{scene}");
        let stderr = text(&out.stderr);
        assert!(stderr.len() < 8_000, "{scene}: {} bytes of messages:\n{:.2000}", stderr.len(), stderr);
        assert!(stderr.contains("...`"), "{scene}: the quoted token is cut:\n{stderr}");
        assert!(stderr.contains(&format!("--> {scene}:")), "{stderr}");
    }
    assert!(!dir.path().join("out.png").exists());
}

/// A Mitsuba 3 scene file is read, built and rendered (with the path model, sRGB-encoded PNG, the
/// same bytes at any thread count); its errors name their file, line and column.
#[test]
fn mitsuba_scene_files_render_and_their_errors_name_their_place() {
    let dir = tempfile::tempdir().expect("temp dir");
    std::fs::write(
        dir.path().join("scene.xml"),
        "<scene version=\"3.0.0\">\n  <default name=\"r\" value=\"0.5\"/>\n  <sensor type=\"perspective\">\n    \
         <float name=\"fov\" value=\"45\"/>\n    <transform name=\"to_world\"><lookat origin=\"0,0,5\" target=\"0,0,0\" up=\"0,1,0\"/></transform>\n    \
         <sampler type=\"independent\"><integer name=\"sample_count\" value=\"4\"/></sampler>\n    \
         <film type=\"hdrfilm\"><integer name=\"width\" value=\"24\"/><integer name=\"height\" value=\"16\"/></film>\n  </sensor>\n  \
         <include filename=\"part.xml\"/>\n</scene>\n",
    )
    .expect("write scene");
    std::fs::write(
        dir.path().join("part.xml"),
        "<scene version=\"3.0.0\">\n  <shape type=\"sphere\">\n    <float name=\"radius\" value=\"$r\"/>\n    \
         <emitter type=\"area\"><rgb name=\"radiance\" value=\"2\"/></emitter>\n  </shape>\n  \
         <shape type=\"rectangle\"><transform name=\"to_world\"><scale value=\"3\"/><translate z=\"-1\"/></transform></shape>\n</scene>\n",
    )
    .expect("write include");
    let out = rayterra(&["render", "scene.xml", "--check", "-D", "r=0.7"], dir.path());
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert!(text(&out.stdout).contains("24x16 pixels, path model"), "{}", text(&out.stdout));

    let out = rayterra(&["render", "scene.xml", "-o", "out.png", "-q"], dir.path());
    assert!(out.status.success(), "{}", text(&out.stderr));
    let png = image::open(dir.path().join("out.png")).expect("a PNG").to_rgb8();
    assert_eq!(png.dimensions(), (24, 16));
    // The emitter of radiance 2 seen directly is white; the lit rectangle is grey.
    assert_eq!(png.get_pixel(12, 8).0, [255, 255, 255]);
    assert!(png.get_pixel(1, 1).0[0] > 10, "the rectangle is lit");
    let exr = |threads: &str, name: &str| {
        let out = rayterra(&["render", "scene.xml", "-o", name, "-q", "--threads", threads], dir.path());
        assert!(out.status.success(), "{}", text(&out.stderr));
        std::fs::read(dir.path().join(name)).expect("EXR")
    };
    assert_eq!(exr("1", "one.exr"), exr("2", "two.exr"), "the same bytes at any thread count");

    let out = rayterra(&["render", "scene.xml", "--model", "classic", "-o", "c.png"], dir.path());
    assert_eq!(out.status.code(), Some(1));
    assert!(text(&out.stderr).contains("only the path model renders"), "{}", text(&out.stderr));
    assert!(!dir.path().join("c.png").exists());

    std::fs::write(
        dir.path().join("bare.xml"),
        "<scene version=\"3.0.0\">\n  <shape type=\"cube\"/>\n</scene>\n",
    )
    .expect("write scene");
    let out = rayterra(&["render", "bare.xml", "-o", "bare.png"], dir.path());
    assert_eq!(out.status.code(), Some(1));
    let stderr = text(&out.stderr);
    assert!(stderr.contains("bare.xml:1:1") && stderr.contains("no <sensor>"), "{stderr}");
    assert!(!dir.path().join("bare.png").exists());

    std::fs::write(dir.path().join("part.xml"), "<scene version=\"3.0.0\">\n  <shape type=\"sphere\">\n    <float name=\"radius\" value=\"x1\"/>\n  </shape>\n</scene>\n")
        .expect("write include");
    let out = rayterra(&["render", "scene.xml", "--check"], dir.path());
    let stderr = text(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(stderr.contains("part.xml:3:33"), "the error names the included file, line and column: {stderr}");

    let out = rayterra(&["render", "scene.xml", "--check", "-D", "no-equals"], dir.path());
    assert_eq!(out.status.code(), Some(2), "{}", text(&out.stderr));
}
