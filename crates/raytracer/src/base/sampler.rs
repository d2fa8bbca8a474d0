//! Deterministic random numbers, stratified sample patterns and exact sums of samples.
//!
//! Every pixel seeds its own generator from its coordinates, the pass and the render seed, so an
//! image does not depend on how many threads rendered it or in which order. The physically based
//! models go further: every sample of a pixel (path tracer) and every photon of a pass (SPPM)
//! has its own stream ([`PixelRng::for_sample`], [`PixelRng::for_photon`]), so any sub-range of
//! pixels or samples can be rendered on its own and gives the same numbers, and their samples are
//! summed exactly ([`ExactSum`]), so partial sums merge into the same bytes in any grouping.

use rand::{RngExt, SeedableRng};
use rand_pcg::Pcg64Mcg;

/// SplitMix64's finaliser: a fast, well-mixing hash of a 64-bit value.
#[inline]
pub fn mix64(mut x: u64) -> u64 {
    x = (x ^ (x >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    x = (x ^ (x >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    x ^ (x >> 31)
}

/// Hashes a sequence of values into one key.
#[inline]
pub fn hash_values(values: &[u64]) -> u64 {
    values.iter().fold(0x51_7cc1_b727_220a, |h, &v| mix64(h ^ v.wrapping_add(0x9e37_79b9_7f4a_7c15)))
}

/// The random-number generator of one pixel in one pass.
#[derive(Clone, Debug)]
pub struct PixelRng {
    rng: Pcg64Mcg,
    /// A key identifying the pixel and pass (for per-pixel decisions shared by its samples).
    key: u64,
}

impl PixelRng {
    /// The generator of pixel `(x, y)` in pass `pass` of a render seeded with `seed`.
    pub fn new(seed: u64, x: u32, y: u32, pass: u32) -> PixelRng {
        PixelRng::from_key(hash_values(&[seed, x as u64, y as u64, pass as u64]))
    }

    /// The generator of the random stream `key` (for example a photon's, hashed from its index
    /// and the seed).
    pub fn from_key(key: u64) -> PixelRng {
        PixelRng { rng: Pcg64Mcg::seed_from_u64(key), key }
    }

    /// A uniform number in [0, 1).
    #[inline]
    pub fn uniform(&mut self) -> f64 {
        self.rng.random::<f64>()
    }

    /// The pixel's key.
    #[inline]
    pub fn key(&self) -> u64 {
        self.key
    }
}

/// Stream codes that keep the random numbers of different uses apart.
pub mod stream {
    /// A path-tracer camera sample.
    pub const PATH: u64 = 0x7061_7468;
    /// An SPPM camera path (one a pixel a pass).
    pub const SPPM_CAMERA: u64 = 0x0073_7070_6d63_616d;
    /// An SPPM photon.
    pub const SPPM_PHOTON: u64 = 0x7370_706d_7068_6f74;
    /// A camera ray of the auxiliary images (albedo, normal, depth) for a denoiser.
    pub const AOV: u64 = 0x0061_6f76_6175_7873;
    /// The seed of a run of a render after the first (see `render::run_seed`).
    pub const RUN: u64 = 0x7275_6e73;
}

impl PixelRng {
    /// The stream of sample `sample` of pixel `(x, y)` (0, 0 at the top left) for the use
    /// `stream` (see [`stream`]) in a render seeded with `seed`.
    #[inline]
    pub fn for_sample(seed: u64, stream: u64, x: u32, y: u32, sample: u64) -> PixelRng {
        PixelRng::from_key(hash_values(&[seed, stream, x as u64, y as u64, sample]))
    }

    /// The stream of photon `photon` of pass `pass` for the use `stream` in a render seeded with
    /// `seed`.
    #[inline]
    pub fn for_photon(seed: u64, stream: u64, pass: u64, photon: u64) -> PixelRng {
        PixelRng::from_key(hash_values(&[seed, stream, pass, photon]))
    }
}

/// An exact sum of RGB samples: each sample is rounded once to a fixed-point grid of
/// [`ExactSum::RESOLUTION`] (2^-40, about 1e-12) and summed in 128-bit integers, so a sum does
/// not depend on the order or grouping of its terms. Samples beyond [`ExactSum::LIMIT`] (`2^54`,
/// about 1.8e16) in magnitude are clamped to it (no light path of a sane scene comes near) and
/// non-finite samples count as 0, so up to 2^32 samples can be summed without overflow. These
/// bounds are the only clamping of the path model, as `docs/raytracer-models.md` says (a test
/// keeps the two in step).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct ExactSum {
    /// The sum of each channel in units of [`ExactSum::RESOLUTION`].
    pub fixed: [i128; 3],
}

impl ExactSum {
    /// The grid samples are rounded to.
    pub const RESOLUTION: f64 = 1.0 / (1u64 << 40) as f64;
    /// The largest magnitude of a sample.
    pub const LIMIT: f64 = (1u64 << 54) as f64;

    /// Adds a sample.
    #[inline]
    pub fn add(&mut self, sample: glam::DVec3) {
        for (sum, v) in self.fixed.iter_mut().zip(sample.to_array()) {
            let v = if v.is_finite() { v.clamp(-Self::LIMIT, Self::LIMIT) } else { 0.0 };
            *sum += round_to_i128(v / Self::RESOLUTION);
        }
    }

    /// Adds another sum (for example of another range of samples).
    #[inline]
    pub fn merge(&mut self, other: &ExactSum) {
        for (a, b) in self.fixed.iter_mut().zip(other.fixed) {
            *a += b;
        }
    }

    /// The mean of `count` samples summed here (0 for none).
    #[inline]
    pub fn mean(&self, count: u64) -> glam::DVec3 {
        if count == 0 {
            return glam::DVec3::ZERO;
        }
        let scale = Self::RESOLUTION / count as f64;
        glam::DVec3::from_array(self.fixed.map(|f| f as f64 * scale))
    }
}

/// `y.round() as i128` (halves away from zero) for a finite `y`, without the library calls that
/// baseline x86-64 needs for both (it has no rounding instruction and no 128-bit conversion):
/// below `2^62` in magnitude, through a 64-bit truncation and the exact fraction it leaves
/// (`y - trunc(y)` is exact; from `2^52` on `y` is already an integer and the fraction 0).
#[inline]
fn round_to_i128(y: f64) -> i128 {
    const FAST: f64 = (1u64 << 62) as f64;
    if y.abs() < FAST {
        let whole = y as i64;
        let fraction = y - whole as f64;
        (whole + (fraction >= 0.5) as i64 - (fraction <= -0.5) as i64) as i128
    } else {
        y.round() as i128
    }
}

/// A stratified grid of `nx * ny` cells over the unit square; cell `s` is column `s % nx`, row
/// `s / nx`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Strata {
    /// Cells across.
    pub nx: u32,
    /// Cells down.
    pub ny: u32,
}

impl Strata {
    /// The most nearly square grid of exactly `n` cells (`n >= 1`): `4 x 4` for 16, `4 x 8` for
    /// 32, `8 x 8` for 64.
    pub fn for_count(n: u32) -> Strata {
        let n = n.max(1);
        let mut nx = (n as f64).sqrt() as u32;
        while nx > 1 && !n.is_multiple_of(nx) {
            nx -= 1;
        }
        Strata { nx: nx.max(1), ny: n / nx.max(1) }
    }

    /// Number of cells.
    #[inline]
    pub fn count(&self) -> u32 {
        self.nx * self.ny
    }

    /// A point jittered uniformly inside cell `s`.
    #[inline]
    pub fn sample(&self, s: u32, rng: &mut PixelRng) -> (f64, f64) {
        let (cx, cy) = (s % self.nx, (s / self.nx) % self.ny);
        ((cx as f64 + rng.uniform()) / self.nx as f64, (cy as f64 + rng.uniform()) / self.ny as f64)
    }
}

/// How the samples of one estimate are shared out among sibling estimates.
///
/// A pixel takes `P` primary samples, and each may open nested estimates (a glossy reflection's
/// directions, an area light's shadow rays) that the spec sizes at `N` samples each. Rather than
/// spending `N` samples in every sibling, the siblings split the `N` strata between them: sibling
/// `i` of `m` takes strata `i, i + m, i + 2m, ...` (rotated by a per-pixel shift), `ceil(N / m)` of
/// them. Each stratum is then sampled as often as before across the pixel, the estimate stays
/// unbiased (the shift is uniform), and the cost no longer multiplies with depth.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Siblings {
    /// Number of sibling estimates sharing the strata.
    pub count: u32,
    /// This estimate's index among them.
    pub index: u32,
}

impl Siblings {
    /// A lone estimate: takes all strata.
    pub const ALONE: Siblings = Siblings { count: 1, index: 0 };

    /// Samples this sibling takes of an estimate with `total` strata.
    #[inline]
    pub fn share(&self, total: u32) -> u32 {
        total.div_ceil(self.count).max(1)
    }

    /// The stratum of this sibling's `j`-th sample among `total`, rotated by `shift`.
    #[inline]
    pub fn stratum(&self, j: u32, total: u32, shift: u64) -> u32 {
        ((self.index as u64 + j as u64 * self.count as u64 + shift) % total as u64) as u32
    }

    /// The siblings of the `j`-th of `k` nested samples taken by this estimate.
    #[inline]
    pub fn nested(&self, k: u32, j: u32) -> Siblings {
        const MAX_COUNT: u32 = 1 << 20;
        let count = self.count.saturating_mul(k).min(MAX_COUNT);
        Siblings { count, index: (self.index.saturating_mul(k).saturating_add(j)) % count }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rounding_to_i128_is_rounding_halves_away_from_zero() {
        let mut rng = PixelRng::from_key(3);
        let mut values =
            vec![0.0, -0.0, 0.5, -0.5, 1.5, -1.5, 2.5, -2.5, 0.49999999999999994, -0.49999999999999994];
        for e in [40, 51, 52, 53, 61, 62, 63, 80, 94] {
            let p = 2f64.powi(e);
            for x in
                [p, -p, p.next_down(), -p.next_down(), p.next_up(), -p.next_up(), p + 0.5, p - 0.5, -p + 0.5]
            {
                values.push(x);
            }
        }
        for _ in 0..100_000 {
            let scale = 2f64.powi((rng.uniform() * 100.0) as i32 - 10);
            values.push((rng.uniform() - 0.5) * scale);
            values.push(((rng.uniform() * 1e6).floor() + 0.5) * if rng.uniform() < 0.5 { -1.0 } else { 1.0 });
        }
        for y in values {
            assert_eq!(round_to_i128(y), y.round() as i128, "{y:e}");
        }
    }

    #[test]
    fn strata_are_as_square_as_possible() {
        assert_eq!(Strata::for_count(16), Strata { nx: 4, ny: 4 });
        assert_eq!(Strata::for_count(32), Strata { nx: 4, ny: 8 });
        assert_eq!(Strata::for_count(64), Strata { nx: 8, ny: 8 });
        assert_eq!(Strata::for_count(7), Strata { nx: 1, ny: 7 });
        assert_eq!(Strata::for_count(0).count(), 1);
    }

    #[test]
    fn samples_fall_in_their_cells() {
        let s = Strata::for_count(16);
        let mut rng = PixelRng::new(1, 2, 3, 0);
        for cell in 0..16 {
            let (x, y) = s.sample(cell, &mut rng);
            assert_eq!(((x * 4.0) as u32, (y * 4.0) as u32), (cell % 4, cell / 4));
        }
    }

    #[test]
    fn siblings_cover_every_stratum_equally() {
        for (m, total) in [(1, 16), (4, 16), (16, 16), (5, 16), (32, 16)] {
            let mut hits = vec![0u32; total as usize];
            for index in 0..m {
                let s = Siblings { count: m, index };
                for j in 0..s.share(total) {
                    hits[s.stratum(j, total, 7) as usize] += 1;
                }
            }
            let (lo, hi) = (hits.iter().min().copied(), hits.iter().max().copied());
            assert!(lo >= Some(1) && hi.zip(lo).is_some_and(|(h, l)| h - l <= 1), "{m}/{total}: {hits:?}");
        }
    }

    #[test]
    fn pixel_generators_are_reproducible_and_distinct() {
        let a: Vec<f64> = (0..4)
            .map({
                let mut r = PixelRng::new(9, 10, 11, 0);
                move |_| r.uniform()
            })
            .collect();
        let b: Vec<f64> = (0..4)
            .map({
                let mut r = PixelRng::new(9, 10, 11, 0);
                move |_| r.uniform()
            })
            .collect();
        let c = PixelRng::new(9, 11, 10, 0).uniform();
        assert_eq!(a, b);
        assert_ne!(a[0], c);
    }

    #[test]
    fn the_sums_bounds_are_those_the_docs_state() {
        // 2^32 samples at the limit fit in the 128-bit sum.
        let per_sample = (ExactSum::LIMIT / ExactSum::RESOLUTION) as i128;
        assert_eq!(per_sample, 1i128 << 94);
        assert!(per_sample.checked_mul(1 << 32).is_some_and(|total| total < i128::MAX));
        let mut sum = ExactSum::default();
        sum.add(glam::DVec3::new(1e300, -1e300, f64::NAN));
        assert_eq!(sum.fixed, [1i128 << 94, -(1i128 << 94), 0], "clamped to the limit; NaN is 0");
        let mut tiny = ExactSum::default();
        tiny.add(glam::DVec3::new(4.0e-13, 5.0e-13, 1.0));
        assert_eq!(tiny.fixed, [0, 1, 1i128 << 40], "below half the grid's step counts as 0");
        // The documentation says the path model clamps nothing but this, with these numbers (it
        // said "Nothing is clamped", which was not so).
        let docs =
            std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../../docs/raytracer-models.md"))
                .expect("docs/raytracer-models.md");
        assert!(!docs.contains("Nothing is\nclamped") && !docs.contains("Nothing is clamped"));
        for stated in
            ["beyond 2^54", "about 1.8e16", "grid of 2^-40", "below 2^-41", "count as 0", "2^32 samples"]
        {
            assert!(docs.contains(stated), "docs/raytracer-models.md should say `{stated}`");
        }
        assert_eq!(ExactSum::LIMIT, 2f64.powi(54));
        assert_eq!(ExactSum::RESOLUTION, 2f64.powi(-40));
    }

    #[test]
    fn exact_sums_do_not_depend_on_grouping() {
        let samples: Vec<glam::DVec3> = (0..1000)
            .map(|i| {
                let mut r = PixelRng::for_sample(3, stream::PATH, 1, 2, i);
                glam::DVec3::new(r.uniform() * 1e3, r.uniform() * 1e-6, -r.uniform())
            })
            .collect();
        let mut whole = ExactSum::default();
        samples.iter().for_each(|&s| whole.add(s));
        let mut parts = ExactSum::default();
        for chunk in samples.chunks(37).rev() {
            let mut part = ExactSum::default();
            chunk.iter().for_each(|&s| part.add(s));
            parts.merge(&part);
        }
        assert_eq!(whole, parts);
        let plain: glam::DVec3 = samples.iter().sum::<glam::DVec3>() / 1000.0;
        assert!((whole.mean(1000) - plain).abs().max_element() < 1e-11);
        let mut odd = ExactSum::default();
        odd.add(glam::DVec3::new(f64::NAN, f64::INFINITY, 1e300));
        assert_eq!(odd.mean(1), glam::DVec3::new(0.0, 0.0, ExactSum::LIMIT));
    }

    #[test]
    fn sample_and_photon_streams_are_keyed_by_every_index() {
        let first = |mut r: PixelRng| r.uniform();
        let a = first(PixelRng::for_sample(1, stream::PATH, 2, 3, 4));
        assert_eq!(a, first(PixelRng::for_sample(1, stream::PATH, 2, 3, 4)));
        for other in [
            PixelRng::for_sample(2, stream::PATH, 2, 3, 4),
            PixelRng::for_sample(1, stream::SPPM_CAMERA, 2, 3, 4),
            PixelRng::for_sample(1, stream::PATH, 3, 2, 4),
            PixelRng::for_sample(1, stream::PATH, 2, 3, 5),
        ] {
            assert_ne!(a, first(other));
        }
        let p = first(PixelRng::for_photon(1, stream::SPPM_PHOTON, 0, 7));
        assert_ne!(p, first(PixelRng::for_photon(1, stream::SPPM_PHOTON, 1, 7)));
        assert_ne!(p, first(PixelRng::for_photon(1, stream::SPPM_PHOTON, 0, 8)));
    }
}
