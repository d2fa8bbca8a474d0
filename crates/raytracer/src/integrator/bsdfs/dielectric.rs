//! `dielectric` and `thindielectric` (Mitsuba 3's `dielectric.cpp`, `thindielectric.cpp`):
//! smooth interfaces, both pure delta lobes, working from both sides.

use glam::DVec3;

use super::LocalSample;
use super::fresnel::{fresnel_dielectric, reflect_z};

/// A smooth interface between two dielectrics of relative index `eta` (inside over outside):
/// Fresnel reflection and refraction, chosen with probabilities `F` and `1 - F`. Radiance
/// crossing it is scaled by `1 / eta_crossed^2` (Mitsuba's radiance mode).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Dielectric {
    /// `int_ior / ext_ior`.
    pub eta: f64,
    /// Tint of reflection (`specular_reflectance`).
    pub reflect_tint: DVec3,
    /// Tint of transmission (`specular_transmittance`).
    pub transmit_tint: DVec3,
}

impl Dielectric {
    /// Reflection with probability `F` (weight `reflect_tint`), refraction otherwise (weight
    /// `transmit_tint / eta_it^2`), `u` choosing.
    pub fn sample(&self, wo: DVec3, u: f64) -> Option<LocalSample> {
        if wo.z == 0.0 {
            return None;
        }
        let f = fresnel_dielectric(wo.z, self.eta);
        if u < f.r {
            Some(LocalSample {
                wi: reflect_z(wo),
                weight: self.reflect_tint,
                pdf: f.r,
                delta: true,
                eta: 1.0,
            })
        } else {
            let wi = DVec3::new(-f.eta_ti * wo.x, -f.eta_ti * wo.y, f.cos_t);
            let weight = self.transmit_tint * (f.eta_ti * f.eta_ti);
            Some(LocalSample { wi, weight, pdf: 1.0 - f.r, delta: true, eta: f.eta_it })
        }
    }
}

/// A thin slab of dielectric: reflection and straight transmission (`wi = -wo`), the slab's
/// inner reflections summed (`R' = R + T^2 R / (1 - R^2)`, `T' = 1 - R'`), no change of index.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ThinDielectric {
    /// `int_ior / ext_ior`.
    pub eta: f64,
    /// Tint of reflection.
    pub reflect_tint: DVec3,
    /// Tint of transmission.
    pub transmit_tint: DVec3,
}

impl ThinDielectric {
    /// The slab's total reflectance at the cosine `cos` (either side).
    pub fn reflectance(&self, cos: f64) -> f64 {
        let r = fresnel_dielectric(cos.abs(), self.eta).r;
        if r < 1.0 { r + (1.0 - r) * (1.0 - r) * r / (1.0 - r * r) } else { r }
    }

    /// Reflection with probability `R'`, straight transmission otherwise.
    pub fn sample(&self, wo: DVec3, u: f64) -> Option<LocalSample> {
        if wo.z == 0.0 {
            return None;
        }
        let r = self.reflectance(wo.z);
        if u < r {
            Some(LocalSample { wi: reflect_z(wo), weight: self.reflect_tint, pdf: r, delta: true, eta: 1.0 })
        } else {
            Some(LocalSample { wi: -wo, weight: self.transmit_tint, pdf: 1.0 - r, delta: true, eta: 1.0 })
        }
    }
}
