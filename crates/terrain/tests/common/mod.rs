//! Helpers shared by the integration tests: the GPU, the course's assets, small synthetic worlds
//! and golden-image comparison.

#![allow(dead_code)] // Each test binary uses a different part of this module.

use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use image::{Rgba, RgbaImage};
use terrain::camera::CameraPose;
use terrain::headless::render_image;
use terrain::render::{Backend, FrameView, Gpu};
use terrain::world::{Heightmap, SkyBox, World};
use terrain::{SceneConfig, Settings};

/// Whether the tests run under CI (`CI` set to anything but `false` or empty), where a missing
/// GPU or missing course assets are failures rather than skips.
pub fn under_ci() -> bool {
    std::env::var("CI").is_ok_and(|value| !value.is_empty() && value != "false" && value != "0")
}

/// Skips the calling test loudly, or fails it under CI. The message goes straight to the
/// terminal: the test harness would swallow `eprintln!` from a test that passes.
pub fn skip(reason: &str) {
    assert!(!under_ci(), "CI=true, so this cannot be skipped: {reason}");
    test_skips::skip("terrain tests", reason);
}

/// The GPU on `backend`, opened once per test binary and shared (the adapter is printed); `None`
/// (after a loud message) when there is none, which fails under CI.
pub fn gpu(backend: Backend) -> Option<&'static Gpu> {
    static VULKAN: OnceLock<Result<Gpu, String>> = OnceLock::new();
    static GL: OnceLock<Result<Gpu, String>> = OnceLock::new();
    let cell = match backend {
        Backend::Gl => &GL,
        _ => &VULKAN,
    };
    let opened = cell.get_or_init(|| {
        let gpu = Gpu::headless(backend).map_err(|error| error.to_string());
        if let Ok(gpu) = &gpu {
            eprintln!("adapter ({backend}): {}", gpu.describe());
        }
        gpu
    });
    match opened {
        Ok(gpu) => Some(gpu),
        Err(reason) => {
            skip(&format!("no {backend} adapter: {reason}"));
            None
        }
    }
}

/// The course's terrain assets (`../shared/course-assets/terrain` from the project's root);
/// `None` (after a loud message) when absent, which fails under CI.
pub fn course_assets() -> Option<PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/course-assets/terrain");
    if dir.join("heightmap.bmp").is_file() {
        Some(dir)
    } else {
        skip(&format!("the course assets are not at {}", dir.display()));
        None
    }
}

/// The course's starting view at `time_seconds`.
pub fn start_view(time_seconds: f64) -> FrameView {
    FrameView { pose: SceneConfig::default().camera_start, field_of_view_degrees: 45.0, time_seconds }
}

/// A view from `position` with yaw and pitch in degrees, at time 0, 45 degrees field of view.
pub fn view_from(position: [f32; 3], yaw: f32, pitch: f32) -> FrameView {
    FrameView {
        pose: CameraPose::new(position.into(), yaw, pitch),
        field_of_view_degrees: 45.0,
        time_seconds: 0.0,
    }
}

/// Renders `world` with the course's numbers, in the course's look.
pub fn render(gpu: &Gpu, world: &World, size: (u32, u32), view: &FrameView) -> RgbaImage {
    render_with(gpu, world, &Settings::course(), size, view)
}

/// Renders `world` with the course's numbers and `settings`.
pub fn render_with(
    gpu: &Gpu,
    world: &World,
    settings: &Settings,
    size: (u32, u32),
    view: &FrameView,
) -> RgbaImage {
    render_image(gpu, world, &SceneConfig::default(), settings, size, view).expect("renders")
}

fn flat(colour: [u8; 3], size: u32) -> RgbaImage {
    RgbaImage::from_pixel(size, size, Rgba([colour[0], colour[1], colour[2], 255]))
}

/// The default procedural island (seed 1, 512 x 512), generated once per test binary.
pub fn default_island() -> &'static World {
    static WORLD: OnceLock<World> = OnceLock::new();
    WORLD.get_or_init(|| {
        terrain::world::procedural::generate(Default::default(), &SceneConfig::default(), &mut |_| {})
            .expect("default world")
    })
}

/// A world of flat colours that makes every part of the picture identifiable: land pure red, sky
/// pure green, water pure blue, a neutral detail map (grey 128) unless given. Its heightmap has
/// its left half under water (level 50, y = -0.75) and its right half above (level 180, y = 1.2).
pub fn marker_world(detail_grey: u8) -> World {
    let columns = 64;
    let levels =
        (0..columns * columns).map(|i| if i % columns < columns / 2 { 50.0 } else { 180.0 }).collect();
    let green = flat([0, 255, 0], 8);
    World {
        heightmap: Heightmap::new(columns, columns, levels).expect("valid"),
        colour_map: flat([255, 0, 0], 16),
        detail_map: flat([detail_grey; 3], 16),
        sky: SkyBox { sides: [green.clone(), green.clone(), green.clone(), green.clone()], top: green },
        water: flat([0, 0, 255], 8),
        unlit: None,
        elevation: None,
        erosion: None,
    }
}

/// The pixel of `image` where the world point `point` appears in `view`, if on screen.
pub fn project(image: &RgbaImage, view: &FrameView, point: [f32; 3]) -> Option<(u32, u32)> {
    let config = SceneConfig::default();
    let lens = terrain::camera::Lens {
        field_of_view_degrees: view.field_of_view_degrees,
        near: config.near,
        far: config.far,
    };
    let aspect = image.width() as f32 / image.height() as f32;
    let clip = lens.projection(aspect) * view.pose.view_matrix() * glam::Vec3::from(point).extend(1.0);
    if clip.w <= 0.0 {
        return None;
    }
    let ndc = clip.truncate() / clip.w;
    let x = (ndc.x * 0.5 + 0.5) * image.width() as f32;
    let y = (0.5 - ndc.y * 0.5) * image.height() as f32;
    ((0.0..image.width() as f32).contains(&x) && (0.0..image.height() as f32).contains(&y))
        .then_some((x as u32, y as u32))
}

/// How far apart two images are.
#[derive(Debug, Clone, Copy)]
pub struct Difference {
    /// Mean absolute difference per channel, in 8-bit levels.
    pub mean: f64,
    /// Largest difference of any channel of any pixel.
    pub worst: u8,
    /// Fraction of pixels with a channel differing by more than 24 levels.
    pub outliers: f64,
}

/// Compares two images of the same size (RGB channels) and returns the difference image.
pub fn difference(a: &RgbaImage, b: &RgbaImage) -> (Difference, RgbaImage) {
    assert_eq!(a.dimensions(), b.dimensions(), "image sizes differ");
    let mut total = 0u64;
    let mut worst = 0u8;
    let mut outliers = 0usize;
    let diff = RgbaImage::from_fn(a.width(), a.height(), |x, y| {
        let (p, q) = (a.get_pixel(x, y).0, b.get_pixel(x, y).0);
        let d = [0, 1, 2].map(|c| p[c].abs_diff(q[c]));
        total += d.iter().map(|&v| u64::from(v)).sum::<u64>();
        let most = d.iter().copied().max().unwrap_or(0);
        worst = worst.max(most);
        if most > 24 {
            outliers += 1;
        }
        // Amplified so small differences show.
        let [r, g, b] = d.map(|v| v.saturating_mul(4));
        Rgba([r, g, b, 255])
    });
    let pixels = (a.width() * a.height()) as f64;
    (Difference { mean: total as f64 / (pixels * 3.0), worst, outliers: outliers as f64 / pixels }, diff)
}

/// Checks `actual` against the golden image `tests/golden/{name}.png`.
///
/// It passes when the mean difference is at most 1 level per channel and either the worst pixel
/// is within 32 levels or fewer than 0.2% of the pixels differ by more than 24 (edges may move
/// by a pixel between rasterisers). On failure the actual, expected and difference images are
/// written under `target/tmp/golden/`. A missing golden is a failure; `RAYTERRA_BLESS=1` writes
/// the actual image as the new golden instead (look at it before committing it).
pub fn assert_golden(name: &str, actual: &RgbaImage) {
    let golden = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/golden").join(format!("{name}.png"));
    if std::env::var("RAYTERRA_BLESS").is_ok_and(|v| v == "1") {
        actual.save(&golden).expect("write golden");
        eprintln!("blessed {}: look at it before committing", golden.display());
        return;
    }
    let out = Path::new(env!("CARGO_TARGET_TMPDIR")).join("golden");
    std::fs::create_dir_all(&out).expect("output folder");
    let actual_path = out.join(format!("{name}.actual.png"));
    let Ok(expected) = image::open(&golden).map(image::DynamicImage::into_rgba8) else {
        actual.save(&actual_path).expect("write actual");
        panic!(
            "golden image {} is missing (the render is at {}); create it on purpose with RAYTERRA_BLESS=1 and look at it",
            golden.display(),
            actual_path.display()
        );
    };
    let (d, diff) = difference(actual, &expected);
    let passes = d.mean <= 1.0 && (d.worst <= 32 || d.outliers < 0.002);
    if !passes {
        actual.save(&actual_path).expect("write actual");
        expected.save(out.join(format!("{name}.expected.png"))).expect("write expected");
        diff.save(out.join(format!("{name}.diff.png"))).expect("write diff");
        panic!(
            "{name} differs from its golden: mean {:.3}, worst {}, {:.3}% of pixels off by more than 24; see {}",
            d.mean,
            d.worst,
            d.outliers * 100.0,
            out.display()
        );
    }
    eprintln!("{name}: mean {:.3}, worst {}, outliers {:.3}%", d.mean, d.worst, d.outliers * 100.0);
}
