//! Mitsuba 3's own scene files (`../shared/mitsuba-data`: the Cornell box, the material preview,
//! the documentation's scene of each plugin) rendered by rayterra and by Mitsuba 3 itself
//! (`tools/mitsuba/render_xml.py`, variant `scalar_rgb`), at the same small size and sample
//! count, and compared **statistically**.
//!
//! Each renderer renders each scene as two independent halves (seeds 0 and 1); half the
//! difference of the halves estimates the noise of their mean, pixel by pixel, and the products
//! of neighbours' half-differences the covariance of pixels that share samples (Mitsuba splats a
//! sample into every pixel its Gaussian filter reaches, so a block's noise is more than the sum of
//! its pixels': `Halves::variance_of_sum`). Over every 8 x 8
//! block and channel, the difference of the two means divided by the noise of the difference is
//! a z-score (with a floor of 1e-4 of the block's value on the noise, the output's precision); a block fails when `|z| > 5` (a false alarm once in 1.7 million tests for normal
//! noise: over the ~40 scenes of the full set and their ~320 block channels each, one false alarm
//! in about 130 runs). Blocks dark in both images (under 1e-3) are not tested. The whole image's
//! mean must also agree within 1% per channel (unless the difference is within 4.5 standard
//! deviations of the two renders' noise, which a scene of small bright lights or glass can have
//! at these sample counts).
//!
//! A failing scene names its worst blocks and writes both images and their difference under
//! `target/test-output/mitsuba/`. Mitsuba's renders are cached under `target/mitsuba-reference/`,
//! keyed by a hash of the scene's files, the size, the samples and the tool.
//!
//! The documentation's principled scenes, which Mitsuba refuses as written, are compared as
//! scenes derived from them under `target/` (`PRINCIPLED_SCENES`).
//!
//! In CI a subset covering every supported plugin is compared; set `RAYTERRA_MITSUBA_ALL=1` to
//! compare every scene whose plugins rayterra has (`docs/mitsuba-format.md` names the command),
//! and `RAYTERRA_MITSUBA_SCENES=cbox,matpreview` to compare only the scenes named.
//! Skipped loudly when Mitsuba or the data is missing, except under CI.

mod support;

use std::path::{Path, PathBuf};
use std::process::Command;

use raytracer::base::checksum::Fnv;
use raytracer::integrator::Model;
use raytracer::render::{Progress, RenderSettings, Sampling};
use raytracer::scene::Severity;
use raytracer::scene::mitsuba;
use raytracer::{Image, PreparedScene, TextureSearch};
use support::pbr::{Halves, mitsuba_python};
use support::{output_dir, workspace};

/// Image width (the height follows the scene's film).
const WIDTH: u32 = 96;
/// Samples a pixel of each half.
const HALF_SPP: u32 = 64;
/// Block side in pixels.
const BLOCK: u32 = 8;
/// Largest |z| of a block channel.
const Z_LIMIT: f64 = 5.0;
/// Blocks darker than this in both images are not tested.
const FLOOR: f64 = 1e-3;
/// A relative difference always allowed (the output's single precision, and pixels whose every
/// sample is the same, such as an emitter seen directly, whose halves estimate no noise).
const PRECISION: f64 = 1e-4;
/// Largest relative difference of the whole image's mean...
const WHOLE_TOLERANCE: f64 = 0.01;
/// ...unless it is within this many standard deviations of the renders' noise (one test per
/// channel and scene: a false alarm once in 150,000 for normal noise; glass and small lights
/// have heavier tails, which two halves estimate low).
const WHOLE_Z_LIMIT: f64 = 4.5;

/// The scenes compared in CI: every supported BSDF, emitter, shape, texture and integrator
/// appears in at least one.
const CI_SCENES: [&str; 25] = [
    "scenes/cbox/cbox.xml",
    "scenes/matpreview/matpreview.xml",
    "docs/scenes/bsdf_diffuse_textured.xml",
    "docs/scenes/bsdf_dielectric_glass.xml",
    "docs/scenes/bsdf_thindielectric_glass.xml",
    "docs/scenes/bsdf_roughdielectric_rough.xml",
    "docs/scenes/bsdf_conductor_gold.xml",
    "docs/scenes/bsdf_roughconductor_anisotropic_aluminium.xml",
    "docs/scenes/bsdf_plastic_shiny.xml",
    "docs/scenes/bsdf_roughplastic_ggx.xml",
    "docs/scenes/bsdf_twosided_cbox_onesided.xml",
    "docs/scenes/bsdf_mask_after.xml",
    "docs/scenes/bsdf_normalmap_with.xml",
    "docs/scenes/bsdf_bumpmap_with.xml",
    "docs/scenes/emitter_spot_no_texture.xml",
    "docs/scenes/emitter_spot_texture.xml",
    "docs/scenes/emitter_projector_textured.xml",
    "docs/scenes/integrator_direct_bsdf.xml",
    "docs/scenes/integrator_depth_2.xml",
    "docs/scenes/shape_disk.xml",
    "docs/scenes/shape_cylinder_onesided.xml",
    "docs/scenes/shape_sphere_light_analytic.xml",
    "docs/scenes/shape_ply_bunny.xml",
    "docs/scenes/sensor_orthographic.xml",
    "docs/scenes/texture_mesh_attribute_vertex.xml",
];

/// Scenes derived from the documentation's principled scenes
/// (`docs/scenes/principled_blend_creation/`), which Mitsuba 3.9.1 refuses as written (their
/// shapes are spelled `Sphere` and `Rectangle`, its plugin names are lower case): `(name, file,
/// the material's parameters)`. Each is written under `target/test-output/derived/` with the
/// shape names lower-cased, the folder on the search path (for `envmap.hdr`) and the material's
/// `base_color` line replaced by the parameters given (kept when they are empty).
const PRINCIPLED_SCENES: [(&str, &str, &str); 7] = [
    ("principled_defaults", "scene.xml", ""),
    (
        "principled_full",
        "scene.xml",
        r#"<rgb name="base_color" value="0.8, 0.3, 0.1"/> <float name="metallic" value="0.3"/>
           <float name="specular" value="0.6"/> <float name="roughness" value="0.3"/>
           <float name="spec_tint" value="0.4"/> <float name="anisotropic" value="0.5"/>
           <float name="sheen" value="0.3"/> <float name="sheen_tint" value="0.2"/>
           <float name="clearcoat" value="0.6"/> <float name="clearcoat_gloss" value="0.3"/>
           <float name="flatness" value="0.4"/>"#,
    ),
    (
        "principled_glass",
        "scene.xml",
        r#"<rgb name="base_color" value="0.9, 0.9, 0.8"/> <float name="spec_trans" value="0.9"/>
           <float name="roughness" value="0.2"/> <float name="eta" value="1.45"/>"#,
    ),
    (
        "principled_textured",
        "scene.xml",
        r#"<rgb name="base_color" value="0.2, 0.4, 0.8"/>
           <texture name="metallic" type="checkerboard"><float name="color0" value="0"/>
               <float name="color1" value="1"/><transform name="to_uv"><scale x="4" y="4"/></transform>
           </texture>
           <texture name="roughness" type="checkerboard"><float name="color0" value="0.15"/>
               <float name="color1" value="0.6"/><transform name="to_uv"><scale x="2" y="8"/></transform>
           </texture>"#,
    ),
    ("principledthin_defaults", "scene_thin.xml", ""),
    (
        "principledthin_full",
        "scene_thin.xml",
        r#"<rgb name="base_color" value="0.7, 0.1, 0.1"/> <float name="roughness" value="0.15"/>
           <float name="spec_tint" value="0.1"/> <float name="anisotropic" value="0.5"/>
           <float name="spec_trans" value="0.8"/> <float name="diff_trans" value="0.3"/>
           <float name="eta" value="1.33"/> <float name="sheen" value="0.3"/>
           <float name="flatness" value="0.5"/>"#,
    ),
    ("principledthin_light", "scene_thin_light.xml", ""),
];

/// The [`PRINCIPLED_SCENES`] compared in CI.
const CI_PRINCIPLED: [&str; 2] = ["principled_full", "principledthin_full"];

/// Writes the [`PRINCIPLED_SCENES`] entry `name` (see there) and returns its path.
fn principled_scene(data: &Path, name: &str) -> PathBuf {
    let (_, file, params) =
        PRINCIPLED_SCENES.iter().find(|(n, _, _)| *n == name).expect("a principled scene of that name");
    let folder = data.join("docs/scenes/principled_blend_creation");
    let source = std::fs::read_to_string(folder.join(file)).expect("read the principled scene");
    let mut text = String::new();
    for line in source.lines() {
        if line.contains("name=\"base_color\"") && !params.is_empty() {
            text.push_str(params);
        } else if line.trim_start().starts_with("<scene ") {
            text.push_str(line);
            text.push_str(&format!("\n    <path value=\"{}\"/>", folder.display()));
        } else {
            text.push_str(
                &line
                    .replace("type=\"Sphere\"", "type=\"sphere\"")
                    .replace("type=\"Rectangle\"", "type=\"rectangle\""),
            );
        }
        text.push('\n');
    }
    let dir = output_dir().join("derived");
    std::fs::create_dir_all(&dir).expect("derived scene folder");
    let path = dir.join(format!("{name}.xml"));
    std::fs::write(&path, text).expect("write the derived scene");
    path
}
/// Why the Veach scene's `direct` renders with emitter samples are not compared.
const SMALL_SPHERE_SEEN: &str = "the Veach scene's smallest sphere lights (radius 0.033, radiance 902; radius 0.1, radiance 100) seen \
     directly cover a pixel or two: rayterra draws each pixel's samples from the Gaussian filter's density, so the pixels at \
     their edges are heavy-tailed (a few samples of 902 or none), which two halves of 64 samples \
     estimate low, where Mitsuba's splatting gives them smooth values; only blocks at those \
     spheres differ (z 5.5 to 17.6, rayterra's values scattered about Mitsuba's), every other block \
     agrees (`integrator_direct_bsdf`, the same scene, agrees throughout)";

/// Scenes where rayterra and Mitsuba 3.9.1 knowingly differ, with why; they are reported, not
/// compared.
const KNOWN_DIFFERENCES: [(&str, &str); 3] = [
    ("integrator_direct_both", SMALL_SPHERE_SEEN),
    ("integrator_direct_lum", SMALL_SPHERE_SEEN),
    (
        "bsdf_blendbsdf",
        "Mitsuba renders a `blendbsdf` that holds a smooth (delta) BSDF darker than the blend of its two \
     BSDFs (a rough plastic and a smooth conductor at weight 0.5 give 0.179 in red where each alone \
     gives 0.087 and 0.476): its blend samples with the chosen BSDF's own density, which its path \
     tracer's MIS then mixes with the blend's; with two rough BSDFs it renders the blend, as \
     rayterra always does",
    ),
];

/// Defines some documentation scenes need (they are written for Mitsuba's docs generator).
const DEFINES: [(&str, &str); 1] = [("spp", "16")];

/// `../shared/mitsuba-data`, or `None` (skipped loudly; a failure under CI).
fn mitsuba_data() -> Option<PathBuf> {
    let dir = test_skips::shared_data(
        Path::new(env!("CARGO_MANIFEST_DIR")),
        "mitsuba-data",
        "raytracer Mitsuba scenes",
    )?;
    Some(dir)
}

fn defines() -> Vec<(String, String)> {
    DEFINES.iter().map(|(k, v)| (k.to_string(), v.to_string())).collect()
}

/// The documentation's `sensor_*.xml` scenes name `meshes/` and `textures/` of `common/` without
/// a `<path>` (Mitsuba's documentation build adds it to its file resolver): they are read through
/// a wrapper under `target/` that gives both renderers the two search folders and includes the
/// scene. Other scenes are read as they are.
fn with_search_folders(path: &Path, data: &Path) -> PathBuf {
    let stem = path.file_stem().map_or(String::new(), |s| s.to_string_lossy().into_owned());
    if !stem.starts_with("sensor_") {
        return path.to_path_buf();
    }
    let dir = output_dir().join("wrapped");
    std::fs::create_dir_all(&dir).expect("wrapper folder");
    let wrapper = dir.join(format!("{stem}.xml"));
    let text = format!(
        "<scene version=\"3.0.0\">\n    <path value=\"{}\"/>\n    <path value=\"{}\"/>\n    \
         <include filename=\"{}\"/>\n</scene>\n",
        data.join("docs/scenes").display(),
        data.join("common").display(),
        path.display()
    );
    std::fs::write(&wrapper, text).expect("write the wrapper");
    wrapper
}

/// A scene prepared for the comparison: ours, the files it was read from, its definitions.
type Prepared = (PreparedScene, Vec<PathBuf>, Vec<(String, String)>);

/// Our scene, prepared, the files it was read from and the definitions it takes (the test's
/// `-D spp` only where the scene uses it: Mitsuba refuses unused ones), or why it is not compared
/// (a plugin rayterra does not have).
fn prepare(path: &Path) -> Result<Prepared, String> {
    let mut defines = defines();
    let mut doc = mitsuba::read_file(path, &defines).map_err(|e| format!("unreadable: {e}"))?;
    if doc.warnings.iter().any(|d| d.message.contains("is not used by the scene")) {
        defines.clear();
        doc = mitsuba::read_file(path, &defines).map_err(|e| format!("unreadable: {e}"))?;
    }
    let built = mitsuba::build(&doc).map_err(|d| format!("not built: {}", d[0].message))?;
    if let Some(w) = built.diagnostics.iter().find(|d| d.severity == Severity::Warning) {
        return Err(format!("not compared: {}", w.message));
    }
    let files = doc.files.iter().map(|f| PathBuf::from(f.name())).collect();
    let prepared =
        PreparedScene::new(built.scene, &TextureSearch::default()).map_err(|d| format!("{d:?}"))?;
    Ok((prepared, files, defines))
}

/// Our render at `size`, `HALF_SPP` samples, with `seed`.
fn ours(scene: &PreparedScene, size: (u32, u32), seed: u64) -> Image {
    let settings = RenderSettings {
        width: size.0,
        height: size.1,
        sampling: Sampling::Uniform(HALF_SPP),
        seed,
        model: Model::Path,
        ..RenderSettings::for_scene(scene)
    };
    raytracer::render(scene, &settings, &|_: Progress| {}).expect("render").image
}

/// Mitsuba's render (cached), and whether it came from the cache.
fn theirs(
    python: &Path,
    scene: &Path,
    files: &[PathBuf],
    defines: &[(String, String)],
    size: (u32, u32),
    seed: u64,
) -> Image {
    let tool = workspace().join("tools/mitsuba/render_xml.py");
    let mut key = Fnv::default();
    for f in files.iter().chain([&tool]) {
        key.write(&std::fs::read(f).unwrap_or_default());
    }
    key.write_text(&format!("{size:?} {HALF_SPP} {seed} {defines:?} mitsuba 3.9.1 scalar_rgb"));
    let dir = output_dir().join("../mitsuba-reference");
    std::fs::create_dir_all(&dir).expect("cache folder");
    let stem = scene.file_stem().map_or(String::new(), |s| s.to_string_lossy().into_owned());
    let out = dir.join(format!("{stem}-{:016x}-{seed}.exr", key.0));
    if !out.exists() {
        let tmp = out.with_extension("partial.exr");
        let mut cmd = Command::new(python);
        cmd.arg(&tool).arg(scene).arg("-o").arg(&tmp);
        for (k, v) in defines {
            cmd.args(["-D", &format!("{k}={v}")]);
        }
        cmd.args(["--size", &format!("{}x{}", size.0, size.1), "--spp", &HALF_SPP.to_string()]);
        let result = cmd.args(["--seed", &seed.to_string()]).output().expect("run Mitsuba");
        assert!(
            result.status.success(),
            "Mitsuba failed on {}:\n{}",
            scene.display(),
            String::from_utf8_lossy(&result.stderr)
        );
        std::fs::rename(&tmp, &out).expect("cache the reference");
    }
    let img = image::open(&out).expect("Mitsuba's EXR").to_rgb32f();
    Image::new(img.width(), img.height(), img.pixels().map(|p| p.0).collect())
}

/// How a scene compared: the worst block's z-score, the failures, the whole image's relative
/// difference.
struct Outcome {
    worst_z: f64,
    failures: Vec<String>,
    whole: [f64; 3],
    /// The whole image's difference in units of its noise, per channel.
    whole_z: [f64; 3],
}

fn compare(a: &Halves, b: &Halves) -> Outcome {
    let (w, h) = (a.width, a.height);
    let mut out = Outcome { worst_z: 0.0, failures: Vec::new(), whole: [0.0; 3], whole_z: [0.0; 3] };
    let mut blocks = Vec::new();
    for by in 0..h / BLOCK {
        for bx in 0..w / BLOCK {
            for c in 0..3 {
                let (mut ma, mut mb) = (0.0, 0.0);
                let (xs, ys) = ((bx * BLOCK, (bx + 1) * BLOCK), (by * BLOCK, (by + 1) * BLOCK));
                for y in ys.0..ys.1 {
                    for x in xs.0..xs.1 {
                        let i = (y * w + x) as usize;
                        ma += a.mean[i][c];
                        mb += b.mean[i][c];
                    }
                }
                let var = a.variance_of_sum(xs, ys, c) + b.variance_of_sum(xs, ys, c);
                let n = (BLOCK * BLOCK) as f64;
                let (ma, mb) = (ma / n, mb / n);
                let sigma = (var / (n * n) + (PRECISION * ma.max(mb)).powi(2)).sqrt();
                if ma.max(mb) < FLOOR {
                    continue;
                }
                let z = if sigma > 0.0 {
                    (ma - mb) / sigma
                } else if ma == mb {
                    0.0
                } else {
                    f64::INFINITY
                };
                out.worst_z = out.worst_z.max(z.abs());
                if z.abs() > Z_LIMIT {
                    blocks.push((
                        z.abs(),
                        format!("block ({bx}, {by}) channel {c}: {ma:.5} against {mb:.5}, z = {z:+.1}"),
                    ));
                }
            }
        }
    }
    blocks.sort_by(|x, y| y.0.total_cmp(&x.0));
    out.failures = blocks.into_iter().take(8).map(|b| b.1).collect();
    for c in 0..3 {
        let sa: f64 = a.mean.iter().map(|p| p[c]).sum();
        let sb: f64 = b.mean.iter().map(|p| p[c]).sum();
        let var = a.variance_of_sum((0, w), (0, h), c) + b.variance_of_sum((0, w), (0, h), c);
        out.whole[c] = if sb > 0.0 { (sa - sb) / sb } else { 0.0 };
        out.whole_z[c] = if var > 0.0 { (sa - sb) / var.sqrt() } else { 0.0 };
    }
    out
}

/// Writes both images and their difference for a failing scene.
fn write_evidence(name: &str, a: &Halves, b: &Halves) -> PathBuf {
    let dir = output_dir().join("mitsuba").join(name);
    std::fs::create_dir_all(&dir).expect("evidence folder");
    let image = |values: Vec<[f32; 3]>| Image::new(a.width, a.height, values);
    let ours: Vec<[f32; 3]> = a.mean.iter().map(|p| p.map(|v| v as f32)).collect();
    let theirs: Vec<[f32; 3]> = b.mean.iter().map(|p| p.map(|v| v as f32)).collect();
    let diff: Vec<[f32; 3]> = a
        .mean
        .iter()
        .zip(&b.mean)
        .map(|(p, q)| std::array::from_fn(|c| (p[c] - q[c]).abs() as f32))
        .collect();
    for (file, img) in [("rayterra.exr", ours), ("mitsuba.exr", theirs), ("difference.exr", diff)] {
        raytracer::image_io::write_image(&image(img), &dir.join(file), false).expect("write evidence");
    }
    dir
}

#[test]
fn mitsuba_scenes_render_as_mitsuba_renders_them() {
    let Some(data) = mitsuba_data() else { return };
    let Some(python) = mitsuba_python() else { return };
    let all = std::env::var_os("RAYTERRA_MITSUBA_ALL").is_some();
    let mut scenes: Vec<PathBuf> = CI_SCENES.iter().map(|s| data.join(s)).collect();
    scenes.extend(CI_PRINCIPLED.iter().map(|n| principled_scene(&data, n)));
    if all {
        scenes.clear();
        scenes.extend(PRINCIPLED_SCENES.iter().map(|(n, _, _)| principled_scene(&data, n)));
        for dir in ["scenes/cbox", "scenes/matpreview", "docs/scenes"] {
            let mut found: Vec<PathBuf> = std::fs::read_dir(data.join(dir))
                .expect("list")
                .map(|e| e.expect("entry").path())
                .filter(|p| p.extension().is_some_and(|e| e == "xml"))
                .collect();
            found.sort();
            scenes.extend(found);
        }
    }
    // `RAYTERRA_MITSUBA_SCENES=cbox,matpreview` compares only the scenes named (file stems).
    if let Ok(only) = std::env::var("RAYTERRA_MITSUBA_SCENES") {
        let names: Vec<&str> = only.split(',').collect();
        scenes.retain(|p| p.file_stem().is_some_and(|s| names.contains(&s.to_string_lossy().as_ref())));
    }
    let mut failed = Vec::new();
    for path in &scenes {
        let name = path.file_stem().map_or(String::new(), |s| s.to_string_lossy().into_owned());
        let path = &with_search_folders(path, &data);
        if let Some((_, why)) = KNOWN_DIFFERENCES.iter().find(|(n, _)| *n == name) {
            eprintln!("{name}: not compared: {why}");
            continue;
        }
        let (scene, files, defines) = match prepare(path) {
            Ok(p) => p,
            Err(why) => {
                assert!(all, "{name} is in the CI set but {why}");
                eprintln!("{name}: {why}");
                continue;
            }
        };
        let cam = &scene.scene.camera;
        let height =
            ((WIDTH as f64 * cam.image_height as f64 / cam.image_width as f64).round() as u32).max(BLOCK);
        let size = (WIDTH, height);
        let started = std::time::Instant::now();
        let a = Halves::new(&ours(&scene, size, 0), &ours(&scene, size, 1));
        let our_time = started.elapsed().as_secs_f64();
        let started = std::time::Instant::now();
        let b = Halves::new(
            &theirs(&python, path, &files, &defines, size, 0),
            &theirs(&python, path, &files, &defines, size, 1),
        );
        let their_time = started.elapsed().as_secs_f64();
        let o = compare(&a, &b);
        eprintln!(
            "{name}: worst block |z| {:.1}, whole image {:+.2}% {:+.2}% {:+.2}% (z {:+.1} {:+.1} {:+.1}; ours {our_time:.1} s, Mitsuba {their_time:.1} s or cached)",
            o.worst_z,
            o.whole[0] * 100.0,
            o.whole[1] * 100.0,
            o.whole[2] * 100.0,
            o.whole_z[0],
            o.whole_z[1],
            o.whole_z[2]
        );
        // The mean agrees within 1%, or the two renders cannot tell it apart from noise.
        let whole_ok =
            (0..3).all(|c| o.whole[c].abs() <= WHOLE_TOLERANCE || o.whole_z[c].abs() <= WHOLE_Z_LIMIT);
        if !o.failures.is_empty() || !whole_ok {
            let dir = write_evidence(&name, &a, &b);
            failed.push(format!(
                "{name}: whole image {:+.2}% {:+.2}% {:+.2}%; {} (images in {})",
                o.whole[0] * 100.0,
                o.whole[1] * 100.0,
                o.whole[2] * 100.0,
                if o.failures.is_empty() { "every block agrees".to_string() } else { o.failures.join("; ") },
                dir.display()
            ));
        }
    }
    assert!(failed.is_empty(), "scenes that disagree with Mitsuba:\n{}", failed.join("\n"));
}
