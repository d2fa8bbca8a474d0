//! Surface materials of the classic shading model (spec section 3, material keys).

use glam::DVec3;

use crate::scene::texture::TextureRef;

/// The material of a primitive. All weights are plain factors of the classic model; none is
/// normalised against the others (a course file may well have `diff + refl > 1`).
#[derive(Clone, Debug, PartialEq)]
pub struct Material {
    /// Base colour (`color=`), linear RGB in [0, 1].
    pub color: DVec3,
    /// Texture multiplied into the colour (`texture=`).
    pub texture: Option<TextureRef>,
    /// Tangent-space normal map over the texture coordinates (`bump=`, or `NT=`): red along the
    /// direction in which `v` (the texture's column) grows, green along `u` (its row, counted from
    /// the bottom), blue along the normal; each channel `c` maps to `2 c - 1`.
    pub bump: Option<TextureRef>,
    /// Diffuse weight (`diff=`).
    pub diff: f64,
    /// Highlight weight (`spec=`), with the view-independent `(N.L)^20` lobe.
    pub spec: f64,
    /// Mirror weight (`refl=`).
    pub refl: f64,
    /// Glossiness radius (`drefl=`); 0 is a perfect mirror.
    pub drefl: f64,
    /// Transmission weight (`refr=`).
    pub refr: f64,
    /// Refractive index (`rindex=`), required and positive when `refr > 0`.
    pub rindex: f64,
    /// Beer absorption per unit length inside the object (`absor=`), per channel.
    pub absor: DVec3,
}

impl Default for Material {
    /// The defaults of the scene language: black and inert.
    fn default() -> Material {
        Material {
            color: DVec3::ZERO,
            texture: None,
            bump: None,
            diff: 0.0,
            spec: 0.0,
            refl: 0.0,
            drefl: 0.0,
            refr: 0.0,
            rindex: 1.0,
            absor: DVec3::ZERO,
        }
    }
}

impl Material {
    /// Whether the local (diffuse and highlight) term applies.
    #[inline]
    pub fn has_local(&self) -> bool {
        self.diff > 0.0 || self.spec > 0.0
    }
}
