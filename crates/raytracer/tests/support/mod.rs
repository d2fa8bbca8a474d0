//! Helpers shared by the integration tests: loading scenes, rendering them small, comparing
//! images with a tolerance, and finding the course's test data.

#![allow(dead_code)] // each test binary uses a part of this module

pub mod pbr;

use std::path::{Path, PathBuf};

use image::RgbImage;
use raytracer::render::{Progress, RenderSettings, Sampling};
use raytracer::scene::{self, SourceFile};
use raytracer::{PreparedScene, TextureSearch};

/// The workspace root.
pub fn workspace() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// Where tests write images for people to look at (actual and difference images).
pub fn output_dir() -> PathBuf {
    let dir = std::env::var_os("CARGO_TARGET_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| workspace().join("target"))
        .join("test-output");
    std::fs::create_dir_all(&dir).expect("create target/test-output");
    dir
}

/// The course's public test data (`../shared/course-assets` beside the project). When it is
/// absent the test is skipped with a loud message, except under CI, where that is a failure.
pub fn course_assets() -> Option<PathBuf> {
    let dir = workspace().join("../shared/course-assets");
    if dir.join("scenes").is_dir() {
        return Some(dir);
    }
    let message = format!("the course test data is missing: expected it at {}", dir.display());
    if std::env::var_os("CI").is_some() {
        panic!("{message} (required under CI)");
    }
    test_skips::skip("raytracer course-data tests", &message);
    None
}

/// Parses and prepares a scene file; panics with the diagnostics on error.
pub fn load(path: &Path) -> PreparedScene {
    let source = SourceFile::read(path).expect("readable scene");
    let parsed = scene::parse(&source).unwrap_or_else(|e| panic!("{}:\n{e}", path.display()));
    let search = TextureSearch { scene_dir: source.dir().map(Path::to_path_buf), extra_dirs: Vec::new() };
    PreparedScene::new(parsed.scene, &search).unwrap_or_else(|d| panic!("{d:?}"))
}

/// Parses and prepares scene text (built-in textures only); panics with the diagnostics on error.
pub fn from_text(text: &str) -> PreparedScene {
    let parsed = scene::parse(&SourceFile::from_text("test.txt", None, text.to_owned()))
        .unwrap_or_else(|e| panic!("scene text:\n{e}"));
    PreparedScene::new(parsed.scene, &TextureSearch::default()).unwrap_or_else(|d| panic!("{d:?}"))
}

/// Renders `scene` at `width x height` (adaptive sampling unless `spp` is given).
pub fn render(
    scene: &PreparedScene,
    width: u32,
    height: u32,
    spp: Option<u32>,
    threads: Option<usize>,
) -> RgbImage {
    let settings = RenderSettings {
        width,
        height,
        sampling: spp.map_or(Sampling::Adaptive, Sampling::Uniform),
        threads,
        seed: 0,
        ..RenderSettings::for_scene(scene)
    };
    let rendered = raytracer::render(scene, &settings, &|_: Progress| {}).expect("render");
    rendered.image.to_rgb8(false)
}

/// How two images of the same size differ, in 8-bit steps.
#[derive(Debug)]
pub struct Difference {
    /// Mean absolute difference over all channels.
    pub mean: f64,
    /// Largest absolute difference of any channel.
    pub worst: u8,
    /// Fraction of pixels with some channel differing by more than 24.
    pub fraction_over_24: f64,
    /// Fraction of pixels with some channel differing by more than 2 (more than rounding).
    pub fraction_over_2: f64,
}

pub fn difference(a: &RgbImage, b: &RgbImage) -> Difference {
    assert_eq!(a.dimensions(), b.dimensions(), "image sizes differ");
    let (mut sum, mut worst, mut over, mut over_2) = (0u64, 0u8, 0usize, 0usize);
    for (pa, pb) in a.pixels().zip(b.pixels()) {
        let d = (0..3).map(|c| pa.0[c].abs_diff(pb.0[c])).max().unwrap_or(0);
        over += (d > 24) as usize;
        over_2 += (d > 2) as usize;
        worst = worst.max(d);
        sum += (0..3).map(|c| pa.0[c].abs_diff(pb.0[c]) as u64).sum::<u64>();
    }
    let n = (a.width() * a.height()) as f64;
    Difference {
        mean: sum as f64 / (3.0 * n),
        worst,
        fraction_over_24: over as f64 / n,
        fraction_over_2: over_2 as f64 / n,
    }
}

/// Writes the actual image and an amplified difference image under `target/test-output`;
/// returns their paths for the failure message.
pub fn write_failure_images(name: &str, actual: &RgbImage, expected: &RgbImage) -> String {
    let dir = output_dir();
    let actual_path = dir.join(format!("{name}.actual.png"));
    let diff_path = dir.join(format!("{name}.diff.png"));
    actual.save(&actual_path).expect("write actual image");
    let diff = RgbImage::from_fn(actual.width(), actual.height(), |x, y| {
        let (a, e) = (actual.get_pixel(x, y), expected.get_pixel(x, y));
        image::Rgb([0, 1, 2].map(|c| (a.0[c].abs_diff(e.0[c]) as u16 * 4).min(255) as u8))
    });
    diff.save(&diff_path).expect("write diff image");
    format!("actual: {}\ndifference (x4): {}", actual_path.display(), diff_path.display())
}
