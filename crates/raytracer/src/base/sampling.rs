//! Warps from uniform numbers in [0, 1) to directions and points, shared by the light-transport
//! models. Directions are unit vectors in world space (z-up); each warp states its density.

use std::f64::consts::{PI, TAU};

use glam::DVec3;

/// A direction uniform over the whole sphere (density `1 / (4 pi)` per steradian).
#[inline]
pub fn uniform_sphere(u1: f64, u2: f64) -> DVec3 {
    let z = 1.0 - 2.0 * u1;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let (sin, cos) = (TAU * u2).sin_cos();
    DVec3::new(r * cos, r * sin, z)
}

/// A direction in the hemisphere around the unit vector `n`, with density `cos / pi` per steradian
/// (the angle measured from `n`), by Malley's method: a uniform point of the unit disc lifted to
/// the hemisphere.
#[inline]
pub fn cosine_hemisphere(n: DVec3, u1: f64, u2: f64) -> DVec3 {
    let r = u1.sqrt();
    let (sin, cos) = (TAU * u2).sin_cos();
    let (x, y) = (r * cos, r * sin);
    let z = (1.0 - u1).max(0.0).sqrt();
    let (t, b) = orthonormal_basis(n);
    t * x + b * y + n * z
}

/// The density of [`cosine_hemisphere`] for a direction whose cosine with `n` is `cos`.
#[inline]
pub fn cosine_hemisphere_pdf(cos: f64) -> f64 {
    if cos > 0.0 { cos / PI } else { 0.0 }
}

/// Two unit vectors that make a right-handed orthonormal basis `(t, b, n)` with the unit vector
/// `n` (Duff et al. 2017: continuous, no normalisation).
#[inline]
pub fn orthonormal_basis(n: DVec3) -> (DVec3, DVec3) {
    let sign = 1.0f64.copysign(n.z);
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    (DVec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x), DVec3::new(b, sign + n.y * n.y * a, -n.y))
}

/// A point uniform over the sphere of `centre` and `radius`, with its outward unit normal
/// (density `1 / area`).
#[inline]
pub fn uniform_sphere_point(centre: DVec3, radius: f64, u1: f64, u2: f64) -> (DVec3, DVec3) {
    let n = uniform_sphere(u1, u2);
    (centre + radius * n, n)
}

/// A direction uniform inside the cone of half-angle `acos(cos_max)` around the unit vector `axis`
/// (density `1 / (2 pi (1 - cos_max))` per steradian).
#[inline]
pub fn uniform_cone(axis: DVec3, cos_max: f64, u1: f64, u2: f64) -> DVec3 {
    let cos = 1.0 - u1 * (1.0 - cos_max);
    let sin = (1.0 - cos * cos).max(0.0).sqrt();
    let (s, c) = (TAU * u2).sin_cos();
    let (t, b) = orthonormal_basis(axis);
    t * (sin * c) + b * (sin * s) + axis * cos
}

/// The density of [`uniform_cone`] inside the cone.
#[inline]
pub fn uniform_cone_pdf(cos_max: f64) -> f64 {
    1.0 / (TAU * (1.0 - cos_max))
}

/// A direction from `p` uniform in the cone the sphere (`centre`, `radius`) fills seen from
/// `p`, with the distance along it to the sphere's nearer surface (tangent at worst) and the
/// cone's density per steradian; `None` from inside the sphere (which sees no outer surface).
#[inline]
pub fn sphere_cone(p: DVec3, centre: DVec3, radius: f64, u1: f64, u2: f64) -> Option<(DVec3, f64, f64)> {
    let axis = centre - p;
    let d2 = axis.length_squared();
    let r2 = radius * radius;
    if d2 <= r2 {
        return None;
    }
    let d = d2.sqrt();
    let cos_max = (1.0 - r2 / d2).max(0.0).sqrt();
    let wi = uniform_cone(axis / d, cos_max, u1, u2);
    let b = -axis.dot(wi);
    let t = -b - (b * b - (d2 - r2)).max(0.0).sqrt();
    Some((wi, t, uniform_cone_pdf(cos_max)))
}

/// The density per steradian of [`sphere_cone`]'s directions from `p` (0 from inside).
#[inline]
pub fn sphere_cone_pdf(p: DVec3, centre: DVec3, radius: f64) -> f64 {
    let d2 = (centre - p).length_squared();
    let r2 = radius * radius;
    if d2 <= r2 { 0.0 } else { uniform_cone_pdf((1.0 - r2 / d2).max(0.0).sqrt()) }
}

/// A discrete distribution over `0..n` with probabilities proportional to given non-negative
/// weights, sampled by inverting its cumulative sum.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Discrete {
    /// `cdf[i]` = probability of `0..=i`; the last entry is 1.
    cdf: Vec<f64>,
    /// Sum of the weights.
    total: f64,
}

impl Discrete {
    /// The distribution of `weights` (negative and non-finite weights count as 0). All-zero
    /// weights give an empty distribution, from which nothing can be drawn.
    pub fn new(weights: &[f64]) -> Discrete {
        let clean = |w: f64| if w.is_finite() && w > 0.0 { w } else { 0.0 };
        let total: f64 = weights.iter().map(|&w| clean(w)).sum();
        if total <= 0.0 {
            return Discrete { cdf: Vec::new(), total: 0.0 };
        }
        let mut sum = 0.0;
        let mut cdf: Vec<f64> = weights
            .iter()
            .map(|&w| {
                sum += clean(w);
                sum / total
            })
            .collect();
        if let Some(last) = cdf.last_mut() {
            *last = 1.0;
        }
        Discrete { cdf, total }
    }

    /// Whether nothing can be drawn (every weight was zero).
    pub fn is_empty(&self) -> bool {
        self.cdf.is_empty()
    }

    /// The sum of the weights.
    pub fn total(&self) -> f64 {
        self.total
    }

    /// The probability of `i`.
    #[inline]
    pub fn pmf(&self, i: usize) -> f64 {
        match i {
            0 => self.cdf.first().copied().unwrap_or(0.0),
            _ => self.cdf.get(i).map_or(0.0, |c| c - self.cdf[i - 1]),
        }
    }

    /// The index `u` in [0, 1) selects, and its probability (`None` when empty).
    #[inline]
    pub fn sample(&self, u: f64) -> Option<(usize, f64)> {
        match self.cdf.len() {
            0 => return None,
            // One choice (a scene with one light): its probability is its cumulative one.
            1 => return Some((0, self.cdf[0])),
            _ => {}
        }
        let i = self.cdf.partition_point(|&c| c <= u).min(self.cdf.len() - 1);
        Some((i, self.pmf(i)))
    }

    /// As [`Discrete::sample`], with `u` rescaled to [0, 1) within the chosen index's share, so
    /// that it can choose again (a continuous position inside the index's cell).
    #[inline]
    pub fn sample_remapped(&self, u: f64) -> Option<(usize, f64, f64)> {
        let (i, p) = self.sample(u)?;
        let start = if i == 0 { 0.0 } else { self.cdf[i - 1] };
        let rest = if p > 0.0 { ((u - start) / p).clamp(0.0, 1.0 - f64::EPSILON / 2.0) } else { 0.5 };
        Some((i, p, rest))
    }
}

#[cfg(test)]
pub(crate) mod chi_square {
    //! A chi-square goodness-of-fit test for direction samplers: directions are binned over the
    //! sphere in equal-area cells (uniform in `z` and in the azimuth), each cell's expected count
    //! is the density integrated over it, and cells expecting fewer than 5 samples are pooled.
    use glam::DVec3;
    use std::f64::consts::TAU;

    /// Cells in `z` and in the azimuth.
    const Z_CELLS: usize = 20;
    const PHI_CELLS: usize = 40;
    /// Midpoint-rule sub-cells per cell side when integrating the density.
    const SUB: usize = 32;

    fn cell_of(d: DVec3) -> usize {
        let z = ((d.z + 1.0) * 0.5 * Z_CELLS as f64).clamp(0.0, Z_CELLS as f64 - 1.0) as usize;
        let phi = d.y.atan2(d.x).rem_euclid(TAU);
        let p = (phi / TAU * PHI_CELLS as f64).clamp(0.0, PHI_CELLS as f64 - 1.0) as usize;
        z * PHI_CELLS + p
    }

    /// The test statistic and degrees of freedom for `n` directions drawn by `sample` (which
    /// returns `None` for a sample that produced no direction, counted against the expected mass)
    /// against the density `pdf` (per steradian).
    pub fn statistic(
        n: usize,
        mut sample: impl FnMut(usize) -> Option<DVec3>,
        pdf: impl Fn(DVec3) -> f64,
    ) -> (f64, usize) {
        let cells = Z_CELLS * PHI_CELLS;
        let mut observed = vec![0.0; cells];
        for i in 0..n {
            if let Some(d) = sample(i) {
                observed[cell_of(d)] += 1.0;
            }
        }
        let cell_area = 4.0 * std::f64::consts::PI / cells as f64;
        let mut expected = vec![0.0; cells];
        for (c, e) in expected.iter_mut().enumerate() {
            let (zi, pi) = (c / PHI_CELLS, c % PHI_CELLS);
            let mut sum = 0.0;
            for a in 0..SUB {
                for b in 0..SUB {
                    let z = -1.0 + 2.0 * (zi as f64 + (a as f64 + 0.5) / SUB as f64) / Z_CELLS as f64;
                    let phi = TAU * (pi as f64 + (b as f64 + 0.5) / SUB as f64) / PHI_CELLS as f64;
                    let r = (1.0 - z * z).max(0.0).sqrt();
                    sum += pdf(DVec3::new(r * phi.cos(), r * phi.sin(), z));
                }
            }
            *e = sum / (SUB * SUB) as f64 * cell_area * n as f64;
        }
        // Pool the cells expecting few samples (in order of expectation) into one.
        let mut order: Vec<usize> = (0..cells).collect();
        order.sort_by(|&a, &b| expected[a].total_cmp(&expected[b]));
        let (mut pooled_e, mut pooled_o, mut chi2, mut dof) = (0.0, 0.0, 0.0, 0usize);
        for &c in &order {
            if expected[c] < 5.0 {
                pooled_e += expected[c];
                pooled_o += observed[c];
            } else {
                chi2 += (observed[c] - expected[c]).powi(2) / expected[c];
                dof += 1;
            }
        }
        if pooled_e > 0.0 {
            chi2 += (pooled_o - pooled_e).powi(2) / pooled_e.max(5.0);
            dof += 1;
        }
        (chi2, dof.saturating_sub(1).max(1))
    }

    /// Panics unless `n` samples follow `pdf`: the statistic must stay below the 99.99th
    /// percentile of the chi-square distribution (Wilson-Hilferty approximation).
    pub fn check(
        name: &str,
        n: usize,
        sample: impl FnMut(usize) -> Option<DVec3>,
        pdf: impl Fn(DVec3) -> f64,
    ) {
        let (chi2, dof) = statistic(n, sample, pdf);
        let k = dof as f64;
        let z = 3.72; // the 99.99th percentile of the standard normal
        let limit = k * (1.0 - 2.0 / (9.0 * k) + z * (2.0 / (9.0 * k)).sqrt()).powi(3);
        assert!(
            chi2 < limit,
            "{name}: chi-square {chi2:.1} over {dof} degrees of freedom (limit {limit:.1})"
        );
    }

    /// The integral of `pdf` over the sphere (midpoint rule on a fine equal-area grid).
    pub fn integral(pdf: impl Fn(DVec3) -> f64) -> f64 {
        let (nz, nphi) = (400, 800);
        let mut sum = 0.0;
        for i in 0..nz {
            let z = -1.0 + 2.0 * (i as f64 + 0.5) / nz as f64;
            let r = (1.0 - z * z).max(0.0).sqrt();
            for j in 0..nphi {
                let phi = TAU * (j as f64 + 0.5) / nphi as f64;
                sum += pdf(DVec3::new(r * phi.cos(), r * phi.sin(), z));
            }
        }
        sum * 4.0 * std::f64::consts::PI / (nz * nphi) as f64
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::test_util::TestRng;

    #[test]
    fn bases_are_orthonormal_and_right_handed() {
        let mut rng = TestRng::new(4);
        for _ in 0..1000 {
            let n = rng.unit_vector();
            let (t, b) = orthonormal_basis(n);
            assert!((t.length() - 1.0).abs() < 1e-12 && (b.length() - 1.0).abs() < 1e-12);
            assert!(t.dot(b).abs() < 1e-12 && t.dot(n).abs() < 1e-12 && b.dot(n).abs() < 1e-12);
            assert!((t.cross(b) - n).length() < 1e-12);
        }
        for n in [DVec3::Z, -DVec3::Z, DVec3::X] {
            let (t, b) = orthonormal_basis(n);
            assert!((t.cross(b) - n).length() < 1e-12, "{n}");
        }
    }

    #[test]
    fn cosine_directions_stay_in_the_hemisphere_with_mean_cosine_two_thirds() {
        let mut rng = TestRng::new(8);
        let n = DVec3::new(0.3, -0.5, 0.8).normalize();
        let count = 200_000;
        let mut sum = 0.0;
        for _ in 0..count {
            let d = cosine_hemisphere(n, rng.uniform(), rng.uniform());
            assert!((d.length() - 1.0).abs() < 1e-12);
            let c = d.dot(n);
            assert!(c >= 0.0);
            sum += c;
        }
        // E[cos] under cos/pi is 2/3.
        assert!((sum / count as f64 - 2.0 / 3.0).abs() < 3e-3, "{}", sum / count as f64);
    }

    #[test]
    fn uniform_sphere_directions_have_no_preferred_side() {
        let mut rng = TestRng::new(2);
        let count = 200_000;
        let mut mean = DVec3::ZERO;
        let mut z2 = 0.0;
        for _ in 0..count {
            let d = uniform_sphere(rng.uniform(), rng.uniform());
            assert!((d.length() - 1.0).abs() < 1e-12);
            mean += d;
            z2 += d.z * d.z;
        }
        assert!((mean / count as f64).length() < 6e-3);
        // E[z^2] over the sphere is 1/3.
        assert!((z2 / count as f64 - 1.0 / 3.0).abs() < 3e-3);
    }

    #[test]
    fn cosine_and_cone_sampling_follow_their_densities() {
        use super::chi_square::{check, integral};
        let n = DVec3::new(0.3, -0.5, 0.8).normalize();
        let mut rng = TestRng::new(11);
        check(
            "cosine",
            200_000,
            |_| Some(cosine_hemisphere(n, rng.uniform(), rng.uniform())),
            |d| cosine_hemisphere_pdf(d.dot(n)),
        );
        assert!((integral(|d| cosine_hemisphere_pdf(d.dot(n))) - 1.0).abs() < 1e-3);
        let cos_max = 0.7;
        let cone_pdf = |d: DVec3| if d.dot(n) >= cos_max { uniform_cone_pdf(cos_max) } else { 0.0 };
        check("cone", 200_000, |_| Some(uniform_cone(n, cos_max, rng.uniform(), rng.uniform())), cone_pdf);
        assert!((integral(cone_pdf) - 1.0).abs() < 2e-3);
        check(
            "sphere",
            200_000,
            |_| Some(uniform_sphere(rng.uniform(), rng.uniform())),
            |_| 1.0 / (4.0 * PI),
        );
    }

    #[test]
    fn discrete_distributions_pick_in_proportion() {
        let d = Discrete::new(&[1.0, 0.0, 3.0, -2.0]);
        assert_eq!((d.pmf(0), d.pmf(1), d.pmf(2), d.pmf(3)), (0.25, 0.0, 0.75, 0.0));
        assert_eq!(d.total(), 4.0);
        assert_eq!(d.sample(0.0), Some((0, 0.25)));
        assert_eq!(d.sample(0.2499), Some((0, 0.25)));
        assert_eq!(d.sample(0.25), Some((2, 0.75)));
        assert_eq!(d.sample(0.999_999), Some((2, 0.75)));
        assert!(Discrete::new(&[0.0, 0.0]).sample(0.5).is_none());
    }
}
