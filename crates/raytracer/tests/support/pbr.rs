//! Helpers of the physically based models' tests: linear renders split in two halves (whose
//! difference measures the noise), Mitsuba 3 renders of the same scene through
//! `tools/mitsuba/rayterra_mitsuba.py`, and the block-by-block comparison of two such images.

use std::path::{Path, PathBuf};
use std::process::Command;

use raytracer::integrator::Model;
use raytracer::render::{Progress, RenderSettings, Sampling};
use raytracer::{Image, PreparedScene};

use super::workspace;

/// A linear render as two independent halves of the samples (seeds 0 and 1): their mean is the
/// image, half their difference measures its noise.
pub struct Halves {
    pub width: u32,
    pub height: u32,
    /// Per pixel and channel: the mean of the halves.
    pub mean: Vec<[f64; 3]>,
    /// Per pixel and channel: half the difference of the halves, whose square is an unbiased
    /// estimate of the variance of `mean`, and whose products between neighbours estimate their
    /// covariance.
    pub half_difference: Vec<[f64; 3]>,
}

/// How far apart (in pixels, on each axis) two pixels of a render can share samples: Mitsuba
/// splats a sample into every pixel its reconstruction filter reaches (the default Gaussian's
/// radius is 2 pixels), so its neighbouring pixels' noise is correlated. rayterra samples the
/// filter instead (a sample lands in one pixel), so its covariances are zero in expectation.
pub const FILTER_REACH: i64 = 2;

impl Halves {
    /// Combines two renders of equal size.
    pub fn new(a: &Image, b: &Image) -> Halves {
        assert_eq!((a.width(), a.height()), (b.width(), b.height()));
        let (mut mean, mut half_difference) = (Vec::new(), Vec::new());
        for (p, q) in a.pixels().iter().zip(b.pixels()) {
            mean.push(std::array::from_fn(|c| (p[c] as f64 + q[c] as f64) / 2.0));
            half_difference.push(std::array::from_fn(|c| (p[c] as f64 - q[c] as f64) / 2.0));
        }
        Halves { width: a.width(), height: a.height(), mean, half_difference }
    }

    /// The variance of the sum of `mean` over the pixels `x0..x1` x `y0..y1` in channel `c`:
    /// every pixel's variance plus the covariances of the pairs at most [`FILTER_REACH`] apart
    /// (estimated by the products of their half-differences; pixels farther apart share no
    /// sample). Summing the variances alone would take a splatting renderer's image for less
    /// noisy than it is. Never less than the variances' sum: the covariances' estimate is noisy,
    /// and a negative one would only make the comparison stricter by chance.
    pub fn variance_of_sum(&self, (x0, x1): (u32, u32), (y0, y1): (u32, u32), c: usize) -> f64 {
        let d = |x: i64, y: i64| self.half_difference[(y * self.width as i64 + x) as usize][c];
        let (x0, x1, y0, y1) = (x0 as i64, x1 as i64, y0 as i64, y1 as i64);
        let (mut diagonal, mut all) = (0.0, 0.0);
        for y in y0..y1 {
            for x in x0..x1 {
                let here = d(x, y);
                diagonal += here * here;
                for ny in (y - FILTER_REACH).max(y0)..(y + FILTER_REACH + 1).min(y1) {
                    for nx in (x - FILTER_REACH).max(x0)..(x + FILTER_REACH + 1).min(x1) {
                        all += here * d(nx, ny);
                    }
                }
            }
        }
        all.max(diagonal)
    }
}

/// Renders `scene` with a physically based model at `width x height`, `spp` samples (path) or
/// `passes` passes (sppm), with `seed`.
pub fn render_model(
    scene: &PreparedScene,
    model: Model,
    (width, height): (u32, u32),
    spp: u32,
    seed: u64,
    passes: Option<u64>,
    photons: Option<u64>,
) -> Image {
    let settings = RenderSettings {
        width,
        height,
        sampling: Sampling::Uniform(spp),
        seed,
        model,
        passes,
        photons,
        ..RenderSettings::for_scene(scene)
    };
    raytracer::render(scene, &settings, &|_: Progress| {}).expect("render").image
}

/// Our path tracer's render as two halves of `spp / 2` samples each.
pub fn path_halves(scene: &PreparedScene, size: (u32, u32), spp: u32) -> Halves {
    let a = render_model(scene, Model::Path, size, spp / 2, 0, None, None);
    let b = render_model(scene, Model::Path, size, spp / 2, 1, None, None);
    Halves::new(&a, &b)
}

/// The Python of the virtual environment that has Mitsuba 3: `RAYTERRA_MITSUBA_PYTHON`, or
/// `target/mitsuba-venv/bin/python` (where `.ci/run` installs it). When it is missing the test
/// is skipped with a loud message, except under CI, where that is a failure.
pub fn mitsuba_python() -> Option<PathBuf> {
    let python = std::env::var_os("RAYTERRA_MITSUBA_PYTHON")
        .map(PathBuf::from)
        .unwrap_or_else(|| workspace().join("target/mitsuba-venv/bin/python"));
    let works = Command::new(&python)
        .args(["-c", "import mitsuba, numpy; mitsuba.set_variant('scalar_rgb')"])
        .output()
        .is_ok_and(|o| o.status.success());
    if works {
        return Some(python);
    }
    let message = format!(
        "Mitsuba 3 is not available at {} (set RAYTERRA_MITSUBA_PYTHON, or run: python3 -m venv \
         target/mitsuba-venv && target/mitsuba-venv/bin/pip install mitsuba numpy)",
        python.display()
    );
    if std::env::var_os("CI").is_some() {
        panic!("{message} (required under CI)");
    }
    eprintln!("\n**** SKIPPED: {message} ****\n");
    None
}

/// Mitsuba 3's render of a scene file (through the tool) as two halves of `spp / 2` samples;
/// also returns Mitsuba's render time in seconds (both halves).
pub fn mitsuba_halves(
    python: &Path,
    scene: &Path,
    (w, h): (u32, u32),
    spp: u32,
    name: &str,
) -> (Halves, f64) {
    let dir = super::output_dir();
    let mut images = Vec::new();
    let mut seconds = 0.0;
    for seed in 0..2 {
        let out = dir.join(format!("{name}.mitsuba.{seed}.exr"));
        let result = Command::new(python)
            .arg(workspace().join("tools/mitsuba/rayterra_mitsuba.py"))
            .arg(scene)
            .args(["-o", &out.to_string_lossy(), "--size", &format!("{w}x{h}")])
            .args(["--spp", &(spp / 2).to_string(), "--seed", &seed.to_string(), "--max-depth", "10"])
            .output()
            .expect("run the Mitsuba tool");
        let stdout = String::from_utf8_lossy(&result.stdout);
        assert!(
            result.status.success(),
            "the Mitsuba tool failed on {}:\n{stdout}\n{}",
            scene.display(),
            String::from_utf8_lossy(&result.stderr)
        );
        seconds += stdout
            .split_whitespace()
            .skip_while(|w| *w != "render")
            .nth(1)
            .and_then(|s| s.parse::<f64>().ok())
            .unwrap_or(0.0);
        let img = image::open(&out).expect("Mitsuba's EXR").to_rgb32f();
        let pixels = img.pixels().map(|p| p.0).collect();
        images.push(Image::new(w, h, pixels));
    }
    (Halves::new(&images[0], &images[1]), seconds)
}

/// How two images agree block by block.
#[derive(Debug)]
pub struct Agreement {
    /// Blocks (times 3 channels) compared.
    pub blocks: usize,
    /// Blocks whose means differ by at most the relative tolerance.
    pub within_tolerance: usize,
    /// Blocks that differ by more than the tolerance and more than `SIGMAS` of their noise.
    pub failures: Vec<String>,
    /// The largest difference of a block in units of its noise.
    pub worst_sigmas: f64,
    /// The relative difference of the whole images, per channel.
    pub whole: [f64; 3],
}

/// Differences beyond this many standard deviations of the noise are failures.
pub const SIGMAS: f64 = 4.0;

/// Compares `ours` with `reference` over `block x block` pixel blocks (those `include` accepts,
/// given the block's column and row), channel by channel: a block agrees when its means differ by
/// at most `tolerance` of the reference's, or by at most [`SIGMAS`] standard deviations of the two
/// images' noise (the two halves' differences), or both means are below `floor`.
pub fn compare(
    ours: &Halves,
    reference: &Halves,
    block: u32,
    tolerance: f64,
    floor: f64,
    include: impl Fn(u32, u32) -> bool,
) -> Agreement {
    let (w, h) = (ours.width, ours.height);
    let mut agreement = Agreement {
        blocks: 0,
        within_tolerance: 0,
        failures: Vec::new(),
        worst_sigmas: 0.0,
        whole: [0.0; 3],
    };
    for by in 0..h / block {
        for bx in 0..w / block {
            if !include(bx, by) {
                continue;
            }
            for c in 0..3 {
                let (mut a, mut b) = (0.0, 0.0);
                let (xs, ys) = ((bx * block, (bx + 1) * block), (by * block, (by + 1) * block));
                for y in ys.0..ys.1 {
                    for x in xs.0..xs.1 {
                        let i = (y * w + x) as usize;
                        a += ours.mean[i][c];
                        b += reference.mean[i][c];
                    }
                }
                let var = ours.variance_of_sum(xs, ys, c) + reference.variance_of_sum(xs, ys, c);
                let n = (block * block) as f64;
                let (a, b, sigma) = (a / n, b / n, var.sqrt() / n);
                let diff = (a - b).abs();
                agreement.blocks += 1;
                let sigmas = if sigma > 0.0 {
                    diff / sigma
                } else if diff > 0.0 {
                    f64::INFINITY
                } else {
                    0.0
                };
                if diff <= tolerance * b.abs() || a.max(b) < floor {
                    agreement.within_tolerance += 1;
                } else {
                    agreement.worst_sigmas = agreement.worst_sigmas.max(sigmas);
                    if sigmas > SIGMAS {
                        agreement.failures.push(format!(
                            "block ({bx}, {by}) channel {c}: {a:.5} against {b:.5} ({:+.2}%, {sigmas:.1} sigma)",
                            (a - b) / b * 100.0
                        ));
                    }
                }
            }
        }
    }
    for c in 0..3 {
        let a: f64 = ours.mean.iter().map(|p| p[c]).sum();
        let b: f64 = reference.mean.iter().map(|p| p[c]).sum();
        agreement.whole[c] = (a - b) / b;
    }
    agreement
}
