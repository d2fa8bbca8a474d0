//! `rayterra render --denoise` and `--aov`: the auxiliary images, the missing-library error, and
//! what Open Image Denoise buys on the Cornell box. The tests that need OIDN skip loudly without
//! it (and fail under CI=true, whose `.ci/run` installs `pyoidn` in target/mitsuba-venv).

use std::path::{Path, PathBuf};

use exr::prelude::{ReadChannels, ReadLayers};
use std::process::{Command, Output};

fn rayterra(args: &[&str], dir: &Path, env: &[(&str, &str)]) -> Output {
    let mut command = Command::new(env!("CARGO_BIN_EXE_rayterra"));
    command.args(args).current_dir(dir);
    for (k, v) in env {
        command.env(k, v);
    }
    command.output().expect("run rayterra")
}

fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

/// The repository's root (two folders above this crate).
fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn cornell() -> String {
    root().join("scenes/cornell-box.txt").display().to_string()
}

/// Reads an EXR's pixels.
fn pixels(path: &Path) -> Vec<[f32; 3]> {
    let img = image::open(path).unwrap_or_else(|e| panic!("{}: {e}", path.display())).to_rgb32f();
    img.pixels().map(|p| p.0).collect()
}

/// Whether OIDN is found; without it the test skips (and fails under CI).
fn oidn_or_skip(dir: &Path, group: &str) -> bool {
    let out =
        rayterra(&["render", "--denoise", "--size", "4x4", "--spp", "1", "-q", "-o", "probe.exr"], dir, &[]);
    if out.status.success() {
        return true;
    }
    let stderr = text(&out.stderr);
    assert!(stderr.contains("pip install pyoidn==2.5.1.0"), "an unexpected failure: {stderr}");
    assert!(
        std::env::var("CI").as_deref() != Ok("true"),
        "Open Image Denoise is not installed (CI installs pyoidn in target/mitsuba-venv): {stderr}"
    );
    test_skips::skip(group, "Open Image Denoise not found (pip install pyoidn==2.5.1.0, or set OIDN_DIR)");
    false
}

#[test]
fn a_missing_library_is_a_clear_error_before_rendering() {
    let dir = tempfile::tempdir().expect("temp dir");
    let empty = dir.path().join("empty");
    std::fs::create_dir(&empty).expect("a folder");
    let env = [("OIDN_DIR", empty.to_str().expect("a UTF-8 path")), ("RAYTERRA_OIDN_SEARCH", "none")];
    let out =
        rayterra(&["render", &cornell(), "--model", "path", "--denoise", "-o", "out.exr"], dir.path(), &env);
    assert_eq!(out.status.code(), Some(1));
    let stderr = text(&out.stderr);
    assert!(stderr.contains("--denoise needs Intel Open Image Denoise"), "{stderr}");
    assert!(stderr.contains("pip install pyoidn==2.5.1.0") && stderr.contains("OIDN_DIR"), "{stderr}");
    assert!(stderr.contains("tried OIDN_DIR"), "says what it tried: {stderr}");
    assert!(!dir.path().join("out.exr").exists(), "nothing rendered");
    // A bad search list is an error of its own.
    let env = [("RAYTERRA_OIDN_SEARCH", "pip")];
    let out = rayterra(&["render", "--denoise", "-o", "out.exr"], dir.path(), &env);
    assert_eq!(out.status.code(), Some(1));
    assert!(text(&out.stderr).contains("unknown place `pip`"), "{}", text(&out.stderr));
}

/// The channels of an EXR file by name (every layer's).
fn exr_channels(path: &Path) -> Vec<(String, Vec<f32>)> {
    let image = exr::prelude::read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .first_valid_layer()
        .all_attributes()
        .from_file(path)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    image
        .layer_data
        .channel_data
        .list
        .iter()
        .map(|c| (c.name.to_string(), c.sample_data.values_as_f32().collect()))
        .collect()
}

#[test]
fn aov_writes_albedo_normal_and_depth_as_layers_of_an_exr() {
    let dir = tempfile::tempdir().expect("temp dir");
    let args = [
        "render",
        &cornell(),
        "--model",
        "path",
        "--size",
        "24x24",
        "--spp",
        "1",
        "--aov",
        "albedo,normal,depth",
    ];
    let out = rayterra(&[&args[..], &["-o", "box.exr"]].concat(), dir.path(), &[]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert!(text(&out.stdout).contains("holds the auxiliary images as layers: albedo, normal, depth"));
    assert!(!dir.path().join("box.albedo.exr").exists(), "an EXR output holds them: nothing beside it");
    let channels = exr_channels(&dir.path().join("box.exr"));
    let names: Vec<&str> = channels.iter().map(|(n, _)| n.as_str()).collect();
    for name in
        ["R", "G", "B", "albedo.R", "albedo.G", "albedo.B", "normal.X", "normal.Y", "normal.Z", "depth.Z"]
    {
        assert!(names.contains(&name), "no channel {name} in {names:?}");
    }
    let channel = |name: &str| &channels.iter().find(|(n, _)| n == name).expect("a channel").1;
    let zip3 = |a: &str, b: &str, c: &str| -> Vec<[f32; 3]> {
        (0..576).map(|i| [channel(a)[i], channel(b)[i], channel(c)[i]]).collect()
    };
    let albedo = zip3("albedo.R", "albedo.G", "albedo.B");
    let normal = zip3("normal.X", "normal.Y", "normal.Z");
    let depth = channel("depth.Z");
    assert_eq!((albedo.len(), normal.len(), depth.len()), (576, 576, 576));
    assert!(albedo.iter().flatten().all(|c| (0.0..=1.0).contains(c)));
    assert!(normal.iter().all(|n| n.iter().map(|c| c * c).sum::<f32>() <= 1.0 + 1e-5));
    // The box's back wall is about 4 units away from the camera at y = -3.9.
    let centre = depth[12 * 24 + 12];
    assert!(centre > 2.0 && centre < 6.0, "{centre}");
    // The image's channels are the render without --aov.
    let out = rayterra(&[&args[..8], &["-o", "plain.exr"]].concat(), dir.path(), &[]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert_eq!(pixels(&dir.path().join("plain.exr")), zip3("R", "G", "B"));
    assert_eq!(
        pixels(&dir.path().join("box.exr")),
        zip3("R", "G", "B"),
        "readers of plain EXR files see the image"
    );
    // Same bytes with another thread count.
    let out = rayterra(&[&args[..], &["--threads", "1", "-o", "one.exr"]].concat(), dir.path(), &[]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let read = |name: &str| std::fs::read(dir.path().join(name)).expect("read");
    assert!(read("box.exr") == read("one.exr"), "the layered file differs between thread counts");
}

#[test]
fn aov_writes_albedo_normal_and_depth_beside_other_outputs() {
    let dir = tempfile::tempdir().expect("temp dir");
    let args = [
        "render",
        &cornell(),
        "--model",
        "path",
        "--size",
        "24x24",
        "--spp",
        "1",
        "--aov",
        "albedo,normal,depth",
    ];
    let out = rayterra(&[&args[..], &["-o", "box.png"]].concat(), dir.path(), &[]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let albedo = pixels(&dir.path().join("box.albedo.exr"));
    let normal = pixels(&dir.path().join("box.normal.exr"));
    let depth = pixels(&dir.path().join("box.depth.exr"));
    assert_eq!((albedo.len(), normal.len(), depth.len()), (576, 576, 576));
    assert!(albedo.iter().flatten().all(|c| (0.0..=1.0).contains(c)));
    assert!(normal.iter().all(|n| n.iter().map(|c| c * c).sum::<f32>() <= 1.0 + 1e-5));
    let centre = depth[12 * 24 + 12][0];
    assert!(centre > 2.0 && centre < 6.0, "{centre}");
    // Same bytes with another thread count.
    let out = rayterra(&[&args[..], &["--threads", "1", "-o", "one.png"]].concat(), dir.path(), &[]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    for name in ["albedo", "normal", "depth"] {
        let a = std::fs::read(dir.path().join(format!("box.{name}.exr"))).expect("read");
        let b = std::fs::read(dir.path().join(format!("one.{name}.exr"))).expect("read");
        assert!(a == b, "{name} differs between thread counts");
    }
}

#[test]
fn the_denoised_image_is_the_same_bytes_on_reruns_and_thread_counts() {
    let dir = tempfile::tempdir().expect("temp dir");
    if !oidn_or_skip(dir.path(), "denoise determinism") {
        return;
    }
    let mut files = Vec::new();
    for (name, threads) in [("a.exr", "1"), ("b.exr", "2"), ("c.exr", "2")] {
        let args = [
            "render",
            &cornell(),
            "--model",
            "path",
            "--size",
            "48x48",
            "--spp",
            "4",
            "--denoise",
            "--threads",
            threads,
        ];
        let out = rayterra(&[&args[..], &["-q", "-o", name]].concat(), dir.path(), &[]);
        assert!(out.status.success(), "{}", text(&out.stderr));
        files.push(std::fs::read(dir.path().join(name)).expect("read"));
    }
    assert!(files[1] == files[2], "a rerun gives other bytes");
    assert!(files[0] == files[1], "--threads 1 and 2 give other bytes");
}

/// Relative MSE of `x` against `reference` over the pixels `keep` selects.
fn rel_mse(x: &[[f32; 3]], reference: &[[f32; 3]], keep: impl Fn(usize) -> bool) -> f64 {
    let (mut sum, mut n) = (0.0, 0);
    for (_, (a, r)) in x.iter().zip(reference).enumerate().filter(|(i, _)| keep(*i)) {
        for c in 0..3 {
            let (a, r) = (a[c] as f64, r[c] as f64);
            sum += (a - r) * (a - r) / (r * r + 0.01);
            n += 1;
        }
    }
    sum / n.max(1) as f64
}

#[test]
fn sixteen_denoised_samples_beat_256_plain_ones_and_keep_edges() {
    const SIZE: usize = 96;
    let dir = tempfile::tempdir().expect("temp dir");
    if !oidn_or_skip(dir.path(), "denoise quality") {
        return;
    }
    let size = format!("{SIZE}x{SIZE}");
    let base = ["render", &cornell(), "--model", "path", "--size", &size, "-q"];
    // The 4096-sample reference, kept under target/ keyed by the scene's bytes and the settings.
    let scene = std::fs::read(root().join("scenes/cornell-box.txt")).expect("the scene");
    let key =
        scene.iter().fold(0xcbf2_9ce4_8422_2325u64, |h, &b| (h ^ b as u64).wrapping_mul(0x100_0000_01b3));
    let cache = root().join("target/denoise-reference");
    std::fs::create_dir_all(&cache).expect("a cache folder");
    // (Its normals are a layer of the file, `normal.X` and so on.)
    let reference_path = cache.join(format!("cornell-{key:016x}-{size}-path-4096-normal-layer.exr"));
    if !reference_path.exists() {
        let partial = cache.join(format!("{}.{}.tmp.exr", key, std::process::id()));
        let out = rayterra(
            &[&base[..], &["--spp", "4096", "--aov", "normal", "-o", partial.to_str().expect("UTF-8")]]
                .concat(),
            dir.path(),
            &[],
        );
        assert!(out.status.success(), "{}", text(&out.stderr));
        std::fs::rename(&partial, &reference_path).expect("kept");
    }
    let reference = pixels(&reference_path);
    let channels = exr_channels(&reference_path);
    let channel = |name: &str| &channels.iter().find(|(n, _)| n == name).expect("the normal layer").1;
    let normal: Vec<[f32; 3]> = (0..reference.len())
        .map(|i| [channel("normal.X")[i], channel("normal.Y")[i], channel("normal.Z")[i]])
        .collect();
    for (name, spp, denoise) in
        [("noisy16.exr", "16", false), ("denoised16.exr", "16", true), ("plain256.exr", "256", false)]
    {
        let mut args = [&base[..], &["--spp", spp, "-o", name]].concat();
        if denoise {
            args.push("--denoise");
        }
        let out = rayterra(&args, dir.path(), &[]);
        assert!(out.status.success(), "{}", text(&out.stderr));
    }
    let noisy = pixels(&dir.path().join("noisy16.exr"));
    let denoised = pixels(&dir.path().join("denoised16.exr"));
    let plain = pixels(&dir.path().join("plain256.exr"));
    let all = |_| true;
    let (e_noisy, e_denoised, e_plain) = (
        rel_mse(&noisy, &reference, all),
        rel_mse(&denoised, &reference, all),
        rel_mse(&plain, &reference, all),
    );
    eprintln!("relative MSE: 16 spp {e_noisy:.5}, 16 spp denoised {e_denoised:.5}, 256 spp {e_plain:.5}");
    // Edges: pixels whose normal differs from a neighbour's (the walls' corners, the balls' and
    // the cylinder's rims), and one pixel around them.
    let n = SIZE;
    let differs =
        |i: usize, j: usize| (0..3).map(|c| (normal[i][c] - normal[j][c]).abs()).fold(0.0, f32::max) > 0.3;
    let mut edge = vec![false; n * n];
    for y in 0..n {
        for x in 0..n {
            let i = y * n + x;
            if (x + 1 < n && differs(i, i + 1)) || (y + 1 < n && differs(i, i + n)) {
                for (dx, dy) in (-1i32..=1).flat_map(|dx| (-1i32..=1).map(move |dy| (dx, dy))) {
                    let (xx, yy) = (x as i32 + dx, y as i32 + dy);
                    if (0..n as i32).contains(&xx) && (0..n as i32).contains(&yy) {
                        edge[yy as usize * n + xx as usize] = true;
                    }
                }
            }
        }
    }
    let count = edge.iter().filter(|e| **e).count();
    assert!(count > n && count < n * n / 2, "an edge band of {count} pixels");
    let band = |i: usize| edge[i];
    let (b_denoised, b_plain) = (rel_mse(&denoised, &reference, band), rel_mse(&plain, &reference, band));
    eprintln!(
        "relative MSE on the {count} edge pixels: 16 spp denoised {b_denoised:.5}, 256 spp {b_plain:.5}"
    );
    assert!(e_denoised < e_plain, "denoised 16 spp {e_denoised} vs 256 spp {e_plain}");
    // Blurred edges would cost far more than the noise of 256 samples there.
    assert!(b_denoised < 1.5 * b_plain, "edges: denoised 16 spp {b_denoised} vs 256 spp {b_plain}");
}
