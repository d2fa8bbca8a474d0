//! The course's lobes, shared by its two models (the classic model and the photon mapper): the
//! highlight's exponent, the depth limit, the glossy reflection lobe and refraction. Directions
//! are unit vectors in world space (z-up).

use glam::DVec3;

/// Exponent of the highlight lobe `(N.L)^SPEC_POWER`.
pub const SPEC_POWER: i32 = 20;
/// Deepest ray traced; the primary ray is depth 1, deeper rays return black.
pub const MAX_DEPTH: u32 = 10;

/// The course's glossy reflection lobe (spec 5.4, `blur= exp`): directions `R + drefl (x b1 + y b2)`
/// with `(x, y) = rho (cos theta, sin theta)`, `rho = 2^xi - 1`, `theta = 2 pi xi'`, where `b1`,
/// `b2` are unit vectors perpendicular to the mirror direction `R`. Denser near `R`; not
/// normalised (the caller's ray normalises it).
#[derive(Clone, Copy, Debug)]
pub struct GlossyLobe {
    r: DVec3,
    b1: DVec3,
    b2: DVec3,
    drefl: f64,
}

impl GlossyLobe {
    /// The lobe around the mirror direction `reflected` (any length) of radius `drefl`.
    #[inline]
    pub fn new(reflected: DVec3, drefl: f64) -> GlossyLobe {
        let r = reflected.normalize();
        let b1 = r.cross(DVec3::X).try_normalize().unwrap_or_else(|| r.cross(DVec3::Y).normalize());
        GlossyLobe { r, b1, b2: r.cross(b1), drefl }
    }

    /// The direction for the uniform numbers `xi`, `xi2` in [0, 1).
    #[inline]
    pub fn direction(&self, xi: f64, xi2: f64) -> DVec3 {
        let rho = (xi as f32).exp2() as f64 - 1.0;
        // Single precision is ample for a perturbation of at most `drefl`, and twice as fast.
        let (sin, cos) = (std::f32::consts::TAU * xi2 as f32).sin_cos();
        self.r + self.drefl * rho * (cos as f64 * self.b1 + sin as f64 * self.b2)
    }
}

/// Refracts the unit direction `v` at a surface with unit normal `n` facing it, with relative
/// index `eta` (incoming over outgoing); reflects instead on total internal reflection.
#[inline]
pub fn refract(v: DVec3, n: DVec3, eta: f64) -> DVec3 {
    let cos_i = -n.dot(v);
    let cos_t2 = 1.0 - eta * eta * (1.0 - cos_i * cos_i);
    if cos_t2 > 0.0 { v * eta + n * (eta * cos_i - cos_t2.sqrt()) } else { v + 2.0 * cos_i * n }
}
