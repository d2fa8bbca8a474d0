//! Surface materials: the closed set of the scene description (pbrt-v4's tagged union).
//!
//! [`Material::Course`] is the course language's weighted material (spec section 3, material
//! keys), the only one the classic and photon models read. The other variants are Mitsuba 3's
//! physically based BSDFs with Mitsuba's parameters and defaults (see `docs/mitsuba-format.md`);
//! the path model evaluates them ([`crate::integrator::bsdfs`]). Colours are linear RGB; every
//! parameter that takes a texture holds a [`Param`].

use std::path::PathBuf;
use std::sync::Arc;

use glam::{DAffine2, DVec3};

use crate::base::diagnostic::Location;

use crate::scene::texture::TextureRef;

/// The course language's material. All weights are plain factors of the classic model; none is
/// normalised against the others (a course file may well have `diff + refl > 1`).
#[derive(Clone, Debug, PartialEq)]
pub struct CourseMaterial {
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

impl Default for CourseMaterial {
    /// The defaults of the scene language: black and inert.
    fn default() -> CourseMaterial {
        CourseMaterial {
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

impl CourseMaterial {
    /// Whether the local (diffuse and highlight) term applies.
    #[inline]
    pub fn has_local(&self) -> bool {
        self.diff > 0.0 || self.spec > 0.0
    }
}

/// The material of a primitive: the course's, or one of Mitsuba 3's physically based BSDFs.
///
/// Conventions of the physically based variants (Mitsuba's): indices of refraction are real
/// (`int_ior` inside, `ext_ior` outside the surface, the outside being where the shape's normal
/// points); conductors take a complex index `eta + i k` per RGB channel; roughness is the
/// microfacet distribution's `alpha` (`alpha_u` along the surface's first tangent, `alpha_v`
/// along the second). One-sided variants (diffuse, conductors, plastics) are black seen from
/// behind, as in Mitsuba; wrap them in [`Material::TwoSided`] to change that.
#[derive(Clone, Debug, PartialEq)]
pub enum Material {
    /// The course language's material.
    Course(CourseMaterial),
    /// `diffuse`: Lambertian reflection of albedo `reflectance` (default 0.5).
    Diffuse {
        /// Albedo, in [0, 1].
        reflectance: Param,
    },
    /// `dielectric`: a smooth interface between two dielectrics (glass, water).
    Dielectric(Interface),
    /// `thindielectric`: a thin slab of dielectric (a window pane): reflection and straight
    /// transmission, with the slab's inner reflections summed.
    ThinDielectric(Interface),
    /// `roughdielectric`: a rough interface (Walter et al. 2007).
    RoughDielectric {
        /// The indices and tints.
        interface: Interface,
        /// The surface's microfacets.
        microfacet: Microfacet,
    },
    /// `conductor`: a smooth metal.
    Conductor(Metal),
    /// `roughconductor`: a rough metal.
    RoughConductor {
        /// The metal.
        metal: Metal,
        /// The surface's microfacets.
        microfacet: Microfacet,
    },
    /// `plastic`: a diffuse base under a smooth dielectric coating (Mitsuba's model with the
    /// internal scattering of the coating, `nonlinear` as Mitsuba).
    Plastic(Coating),
    /// `roughplastic`: a diffuse base under a rough dielectric coating.
    RoughPlastic {
        /// The coating and base.
        coating: Coating,
        /// The coating's microfacets (isotropic).
        microfacet: Microfacet,
    },
    /// `principled`: Mitsuba's Disney-style BSDF (Burley 2012, 2015): diffuse with retro-reflection
    /// and fake subsurface, sheen, a GGX specular lobe that is a tinted dielectric or metal, a
    /// GGX transmission lobe, and a GTR1 clearcoat (Mitsuba's `principled.cpp`).
    Principled(Principled),
    /// `principledthin`: the thin-surface variant (Mitsuba's `principledthin.cpp`): the same
    /// front lobes on both sides, with specular and diffuse transmission through the sheet.
    PrincipledThin(PrincipledThin),
    /// `twosided`: `front` on the side the normal points to, `back` (the same material unless a
    /// second one is given) on the other, each seen as from its front.
    TwoSided {
        /// The material of the front face.
        front: Box<Material>,
        /// The material of the back face.
        back: Box<Material>,
    },
    /// `mask`: `material` where `opacity` is 1, clear (light passes unchanged) where it is 0.
    Mask {
        /// The opacity, in [0, 1] (default 0.5).
        opacity: Param,
        /// The masked material.
        material: Box<Material>,
    },
    /// `blendbsdf`: `(1 - weight) first + weight second`.
    Blend {
        /// The weight of `second`, in [0, 1].
        weight: Param,
        /// The material at weight 0.
        first: Box<Material>,
        /// The material at weight 1.
        second: Box<Material>,
    },
    /// `normalmap` or `bumpmap`: `material` shaded in a perturbed frame (Mitsuba's
    /// `normalmap.cpp`, `bumpmap.cpp`). The path model perturbs the frame only where this is the
    /// primitive's outermost material; the builder warns when it is nested in a wrapper.
    Perturbed {
        /// How the shading normal is perturbed.
        perturbation: Perturbation,
        /// The material shaded in the perturbed frame.
        material: Box<Material>,
    },
}

/// How a [`Material::Perturbed`] moves the shading normal.
#[derive(Clone, Debug, PartialEq)]
pub enum Perturbation {
    /// `normalmap`: the texture's RGB `c` (read as stored, bilinear) is the normal `2 c - 1` in
    /// the shading frame (x along `dp/du`, z along the shading normal), normalised.
    NormalMap(Param),
    /// `bumpmap`: the surface moved along its shading normal by `scale` times the height texture
    /// (its luminance); the normal follows from the height's gradient in texture coordinates.
    BumpMap {
        /// The height texture.
        height: Param,
        /// Factor on the height (`scale`, default 1), in scene units per texture unit.
        scale: f64,
    },
}

/// The most weighted BSDFs one material may flatten to (its leaves, and a mask's pass-through);
/// the Mitsuba builder refuses more.
pub const MAX_COMPONENTS: usize = 8;

impl Material {
    /// The number of weighted BSDFs the material flattens to: its leaves, a mask's pass-through
    /// counting as one (0 for the course's material).
    pub fn component_count(&self) -> usize {
        match self {
            Material::Course(_) => 0,
            Material::TwoSided { front, back } => front.component_count() + back.component_count(),
            Material::Mask { material, .. } => material.component_count() + 1,
            Material::Blend { first, second, .. } => first.component_count() + second.component_count(),
            Material::Perturbed { material, .. } => material.component_count(),
            _ => 1,
        }
    }

    /// The course material, or `None` for a physically based one.
    #[inline]
    pub fn as_course(&self) -> Option<&CourseMaterial> {
        match self {
            Material::Course(m) => Some(m),
            _ => None,
        }
    }

    /// Every parameter of the material and of the materials it wraps, in a fixed order.
    pub fn params(&self) -> Vec<&Param> {
        let mut out = Vec::new();
        self.visit_params(&mut |p| out.push(p));
        out
    }

    fn visit_params<'a>(&'a self, f: &mut dyn FnMut(&'a Param)) {
        match self {
            Material::Course(_) => {}
            Material::Diffuse { reflectance } => f(reflectance),
            Material::Dielectric(i) | Material::ThinDielectric(i) => i.visit_params(f),
            Material::RoughDielectric { interface, microfacet } => {
                interface.visit_params(f);
                microfacet.visit_params(f);
            }
            Material::Conductor(m) => f(&m.specular_reflectance),
            Material::RoughConductor { metal, microfacet } => {
                f(&metal.specular_reflectance);
                microfacet.visit_params(f);
            }
            Material::Plastic(c) => c.visit_params(f),
            Material::RoughPlastic { coating, microfacet } => {
                coating.visit_params(f);
                microfacet.visit_params(f);
            }
            Material::Principled(p) => p.visit_params(f),
            Material::PrincipledThin(p) => p.visit_params(f),
            Material::TwoSided { front, back } => {
                front.visit_params(f);
                back.visit_params(f);
            }
            Material::Mask { opacity, material } => {
                f(opacity);
                material.visit_params(f);
            }
            Material::Blend { weight, first, second } => {
                f(weight);
                first.visit_params(f);
                second.visit_params(f);
            }
            Material::Perturbed { perturbation, material } => {
                match perturbation {
                    Perturbation::NormalMap(p) => f(p),
                    Perturbation::BumpMap { height, .. } => f(height),
                }
                material.visit_params(f);
            }
        }
    }

    /// Whether a [`Material::Perturbed`] is anywhere below this material's outermost level
    /// (where the path model does not apply it).
    pub fn nests_perturbation(&self) -> bool {
        fn any(m: &Material) -> bool {
            matches!(m, Material::Perturbed { .. }) || m.nests_perturbation()
        }
        match self {
            Material::TwoSided { front: a, back: b } | Material::Blend { first: a, second: b, .. } => {
                any(a) || any(b)
            }
            Material::Mask { material, .. } | Material::Perturbed { material, .. } => any(material),
            _ => false,
        }
    }
}

/// The parameters of `principled` (Mitsuba's names and defaults). Every parameter but `eta` and
/// the sampling rates may be a texture; scalar ones read the first channel. All but `eta` and
/// the rates are meant to lie in [0, 1].
#[derive(Clone, Debug, PartialEq)]
pub struct Principled {
    /// `base_color` (default 0.5), linear RGB.
    pub base_color: Param,
    /// `roughness` (default 0.5): the GGX `alpha` is its square (at least 0.001).
    pub roughness: Param,
    /// `anisotropic` (default 0): `alpha_u = r^2 / sqrt(1 - 0.9 a)`, `alpha_v = r^2 sqrt(1 - 0.9 a)`.
    pub anisotropic: Param,
    /// `metallic` (default 0): the weight of the metal (Schlick reflection tinted by the base
    /// colour).
    pub metallic: Param,
    /// `spec_trans` (default 0): the share of the dielectric that transmits (rough glass).
    pub spec_trans: Param,
    /// `spec_tint` (default 0): how much the dielectric reflection takes the base colour.
    pub spec_tint: Param,
    /// `sheen` (default 0): the grazing sheen lobe's weight.
    pub sheen: Param,
    /// `sheen_tint` (default 0): how much the sheen takes the base colour.
    pub sheen_tint: Param,
    /// `flatness` (default 0): diffuse (0) to Hanrahan-Krueger fake subsurface (1).
    pub flatness: Param,
    /// `clearcoat` (default 0): the weight of the GTR1 coat lobe.
    pub clearcoat: Param,
    /// `clearcoat_gloss` (default 0): the coat's `alpha` goes from 0.1 (0) to 0.001 (1).
    pub clearcoat_gloss: Param,
    /// The relative index of refraction inside over outside: `eta`, or from `specular`
    /// (default 0.5) as `2 / (1 - sqrt(0.08 specular)) - 1`, with Mitsuba's adjustments
    /// (1.001 for `eta = 1`, `specular = 1e-3` for 0, when `spec_trans` is given).
    pub eta: f64,
    /// `main_specular_sampling_rate` (default 1).
    pub specular_sampling_rate: f64,
    /// `clearcoat_sampling_rate` (default 1).
    pub clearcoat_sampling_rate: f64,
    /// `diffuse_reflectance_sampling_rate` (default 1).
    pub diffuse_sampling_rate: f64,
}

impl Principled {
    fn visit_params<'a>(&'a self, f: &mut dyn FnMut(&'a Param)) {
        for p in [
            &self.base_color,
            &self.roughness,
            &self.anisotropic,
            &self.metallic,
            &self.spec_trans,
            &self.spec_tint,
            &self.sheen,
            &self.sheen_tint,
            &self.flatness,
            &self.clearcoat,
            &self.clearcoat_gloss,
        ] {
            f(p);
        }
    }
}

/// The parameters of `principledthin` (Mitsuba's names and defaults); every parameter but the
/// sampling rates may be a texture.
#[derive(Clone, Debug, PartialEq)]
pub struct PrincipledThin {
    /// `base_color` (default 0.5), linear RGB.
    pub base_color: Param,
    /// `roughness` (default 0.5).
    pub roughness: Param,
    /// `anisotropic` (default 0).
    pub anisotropic: Param,
    /// `spec_trans` (default 0): the share of the specular (reflecting and transmitting) lobes.
    pub spec_trans: Param,
    /// `eta` (default 1.5): the sheet's relative index (Fresnel, and the transmission's
    /// roughness `(0.65 eta - 0.35) roughness`).
    pub eta: Param,
    /// `spec_tint` (default 0).
    pub spec_tint: Param,
    /// `sheen` (default 0).
    pub sheen: Param,
    /// `sheen_tint` (default 0).
    pub sheen_tint: Param,
    /// `flatness` (default 0).
    pub flatness: Param,
    /// `diff_trans` (default 0, range [0, 2]): diffuse transmission, halved into [0, 1].
    pub diff_trans: Param,
    /// `specular_reflectance_sampling_rate` (default 1).
    pub specular_reflectance_sampling_rate: f64,
    /// `specular_transmittance_sampling_rate` (default 1).
    pub specular_transmittance_sampling_rate: f64,
    /// `diffuse_reflectance_sampling_rate` (default 1).
    pub diffuse_reflectance_sampling_rate: f64,
    /// `diffuse_transmittance_sampling_rate` (default 1).
    pub diffuse_transmittance_sampling_rate: f64,
}

impl PrincipledThin {
    fn visit_params<'a>(&'a self, f: &mut dyn FnMut(&'a Param)) {
        for p in [
            &self.base_color,
            &self.roughness,
            &self.anisotropic,
            &self.spec_trans,
            &self.eta,
            &self.spec_tint,
            &self.sheen,
            &self.sheen_tint,
            &self.flatness,
            &self.diff_trans,
        ] {
            f(p);
        }
    }
}

/// A dielectric interface: `dielectric`, `thindielectric`, `roughdielectric`.
#[derive(Clone, Debug, PartialEq)]
pub struct Interface {
    /// Index of refraction inside (`int_ior`, default 1.5046, BK7 glass).
    pub int_ior: f64,
    /// Index of refraction outside (`ext_ior`, default 1.000277, air).
    pub ext_ior: f64,
    /// Tint of reflection (`specular_reflectance`, default 1; not physical, as in Mitsuba).
    pub specular_reflectance: Param,
    /// Tint of transmission (`specular_transmittance`, default 1).
    pub specular_transmittance: Param,
}

impl Interface {
    fn visit_params<'a>(&'a self, f: &mut dyn FnMut(&'a Param)) {
        f(&self.specular_reflectance);
        f(&self.specular_transmittance);
    }
}

/// A metal: `conductor`, `roughconductor`.
#[derive(Clone, Debug, PartialEq)]
pub struct Metal {
    /// Real part of the complex index of refraction, per RGB channel, relative to the outside.
    pub eta: DVec3,
    /// Imaginary part (the absorption coefficient), per RGB channel, relative to the outside.
    pub k: DVec3,
    /// Tint of reflection (`specular_reflectance`, default 1).
    pub specular_reflectance: Param,
}

/// A coated diffuse base: `plastic`, `roughplastic`.
#[derive(Clone, Debug, PartialEq)]
pub struct Coating {
    /// Albedo of the base (`diffuse_reflectance`, default 0.5).
    pub diffuse_reflectance: Param,
    /// Tint of the coating's reflection (`specular_reflectance`, default 1).
    pub specular_reflectance: Param,
    /// Index of refraction of the coating (`int_ior`, default 1.49, polypropylene).
    pub int_ior: f64,
    /// Index of refraction outside (`ext_ior`, default 1.000277).
    pub ext_ior: f64,
    /// Whether the base's colour saturates through inner reflections (`nonlinear`, default
    /// false).
    pub nonlinear: bool,
}

impl Coating {
    fn visit_params<'a>(&'a self, f: &mut dyn FnMut(&'a Param)) {
        f(&self.diffuse_reflectance);
        f(&self.specular_reflectance);
    }
}

/// The microfacet distribution of a rough surface.
#[derive(Clone, Debug, PartialEq)]
pub struct Microfacet {
    /// Beckmann or GGX (`distribution`, default `beckmann`).
    pub distribution: Distribution,
    /// Roughness along the first tangent (`alpha_u`, or `alpha` for both; default 0.1).
    pub alpha_u: Param,
    /// Roughness along the second tangent (`alpha_v`).
    pub alpha_v: Param,
    /// Whether directions are drawn from the visible normals (`sample_visible`, default true).
    pub sample_visible: bool,
}

impl Microfacet {
    fn visit_params<'a>(&'a self, f: &mut dyn FnMut(&'a Param)) {
        f(&self.alpha_u);
        f(&self.alpha_v);
    }
}

/// A microfacet normal distribution.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Distribution {
    /// Beckmann's Gaussian distribution of slopes.
    Beckmann,
    /// GGX (Trowbridge-Reitz), with longer tails.
    Ggx,
}

/// A material parameter: a constant, or a texture looked up at the surface's texture
/// coordinates. Scalar parameters (roughness, opacity, weights) read the first channel (grey
/// textures, the usual ones, have three equal channels).
#[derive(Clone, Debug, PartialEq)]
pub enum Param {
    /// The same value everywhere (a scalar is repeated in the three channels).
    Constant(DVec3),
    /// A texture.
    Texture(Arc<TextureSpec>),
}

impl Param {
    /// A constant scalar.
    pub fn scalar(value: f64) -> Param {
        Param::Constant(DVec3::splat(value))
    }
}

/// A texture of the physically based materials (Mitsuba's `bitmap`, `checkerboard` and
/// `mesh_attribute`).
#[derive(Clone, Debug, PartialEq)]
pub enum TextureSpec {
    /// `bitmap`: an image file.
    Bitmap {
        /// The file, resolved.
        file: PathBuf,
        /// Where the scene names it (for messages).
        location: Location,
        /// Whether the texels are used as stored (`raw`); otherwise 8-bit images are decoded
        /// from sRGB.
        raw: bool,
        /// Nearest-texel lookups (`filter_type="nearest"`) instead of bilinear.
        nearest: bool,
        /// What lies beyond [0, 1] (`wrap_mode`).
        wrap: Wrap,
        /// Texture coordinates to image coordinates (`to_uv`).
        to_uv: DAffine2,
    },
    /// `checkerboard`: squares of `color0` and `color1`, 2 x 2 over the unit square of texture
    /// coordinates.
    Checkerboard {
        /// Colour of the squares at the origin.
        color0: DVec3,
        /// Colour of the others.
        color1: DVec3,
        /// Texture coordinates to checker coordinates (`to_uv`).
        to_uv: DAffine2,
    },
    /// `mesh_attribute`: the values a mesh file gives its vertices (interpolated over each
    /// triangle by its barycentric weights) or its faces (constant over each), times `scale`; a
    /// scalar attribute reads as a grey. Only on the BSDFs of meshes that have the attribute
    /// (the builder refuses others); black where there is no mesh.
    MeshAttribute {
        /// The attribute's name: `vertex_...` or `face_...` (`vertex_color`, `face_color`).
        name: String,
        /// Factor on the values (`scale`, default 1).
        scale: f64,
        /// Where the scene names it (for messages).
        location: Location,
    },
}

/// What a bitmap shows beyond the unit square.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Wrap {
    /// Repeats (`repeat`, the default).
    Repeat,
    /// Repeats mirrored (`mirror`).
    Mirror,
    /// The edge texels (`clamp`).
    Clamp,
}
