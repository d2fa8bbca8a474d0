//! `<bsdf>` plugins to [`Material`]s, with Mitsuba 3's parameters and defaults.

use std::sync::Arc;

use super::super::{Plugin, PluginKind, Value};
use super::{Builder, Props, metal_ior, named_ior};
use crate::material::{
    Coating, Distribution, Interface, MAX_COMPONENTS, Material, Metal, Microfacet, Param, Perturbation,
    Principled, PrincipledThin,
};
use crate::scene::Diagnostic;

/// Mitsuba's default inside index of dielectrics (`bk7`).
const DIELECTRIC_INT_IOR: f64 = 1.5046;
/// Mitsuba's default inside index of plastics (`polypropylene`).
const PLASTIC_INT_IOR: f64 = 1.49;
/// Mitsuba's default outside index (`air`).
const EXT_IOR: f64 = 1.000277;

impl<'a> Builder<'a> {
    /// The material of a `<bsdf>` (built once per plugin, however often it is referenced).
    pub(super) fn material(&mut self, plugin: &'a Plugin) -> Result<Arc<Material>, Diagnostic> {
        let key = plugin as *const Plugin;
        if let Some(m) = self.materials.get(&key) {
            return Ok(m.clone());
        }
        let props = Props::new(self.doc, plugin);
        let m = Arc::new(self.bsdf(&props)?);
        if m.component_count() > MAX_COMPONENTS {
            return Err(props.error(format!(
                "this BSDF nests {} BSDFs (through twosided, mask and blendbsdf); rayterra renders at most {MAX_COMPONENTS}",
                m.component_count()
            )));
        }
        if m.nests_perturbation() {
            self.warn(
                &props,
                "a `normalmap` or `bumpmap` inside this BSDF is rendered without its perturbation: \
                 rayterra applies them only as a surface's outermost BSDF",
            );
        }
        self.finish(&props);
        self.materials.insert(key, m.clone());
        Ok(m)
    }

    fn bsdf(&mut self, props: &Props<'a>) -> Result<Material, Diagnostic> {
        Ok(match props.type_name() {
            "diffuse" => Material::Diffuse { reflectance: self.param(props, "reflectance", 0.5)? },
            "dielectric" => Material::Dielectric(self.interface(props, DIELECTRIC_INT_IOR)?),
            "thindielectric" => Material::ThinDielectric(self.interface(props, DIELECTRIC_INT_IOR)?),
            "roughdielectric" => Material::RoughDielectric {
                interface: self.interface(props, DIELECTRIC_INT_IOR)?,
                microfacet: self.microfacet(props, true)?,
            },
            "conductor" => Material::Conductor(self.metal(props)?),
            "roughconductor" => Material::RoughConductor {
                metal: self.metal(props)?,
                microfacet: self.microfacet(props, true)?,
            },
            "plastic" => Material::Plastic(self.coating(props)?),
            "roughplastic" => Material::RoughPlastic {
                coating: self.coating(props)?,
                microfacet: self.microfacet(props, false)?,
            },
            "principled" => Material::Principled(self.principled(props)?),
            "principledthin" => Material::PrincipledThin(self.principled_thin(props)?),
            "twosided" => {
                let inner = self.nested_materials(props, 1, 2)?;
                let front = Box::new((*inner[0]).clone());
                let back = Box::new((**inner.get(1).unwrap_or(&inner[0])).clone());
                Material::TwoSided { front, back }
            }
            "mask" => {
                let opacity = self.scalar_param(props, "opacity", 0.5)?;
                let inner = self.nested_materials(props, 1, 1)?;
                Material::Mask { opacity, material: Box::new((*inner[0]).clone()) }
            }
            "blendbsdf" => {
                let weight = self.scalar_param(props, "weight", 0.5)?;
                let inner = self.nested_materials(props, 2, 2)?;
                Material::Blend {
                    weight,
                    first: Box::new((*inner[0]).clone()),
                    second: Box::new((*inner[1]).clone()),
                }
            }
            "null" => Material::Mask { opacity: Param::scalar(0.0), material: Box::new(default_material()) },
            "normalmap" => {
                let inner = self.nested_materials(props, 1, 1)?;
                let Some(texture) = props.named_child("normalmap").filter(|t| t.kind == PluginKind::Texture)
                else {
                    return Err(props.error("the `normalmap` BSDF needs a <texture name=\"normalmap\">"));
                };
                let normals = self.texture(texture)?;
                Material::Perturbed {
                    perturbation: Perturbation::NormalMap(normals),
                    material: Box::new((*inner[0]).clone()),
                }
            }
            "bumpmap" => {
                let inner = self.nested_materials(props, 1, 1)?;
                let textures = props.children(PluginKind::Texture);
                if textures.len() != 1 {
                    return Err(props.error(format!(
                        "the `bumpmap` BSDF holds 1 nested <texture> (the height), not {}",
                        textures.len()
                    )));
                }
                let height = self.texture(textures[0].1)?;
                let scale = props.float("scale", 1.0)?;
                Material::Perturbed {
                    perturbation: Perturbation::BumpMap { height, scale },
                    material: Box::new((*inner[0]).clone()),
                }
            }
            _ => {
                self.warn(
                    props,
                    "the surface is rendered with Mitsuba's default material (diffuse, reflectance 0.5)",
                );
                mark_all_read(props);
                default_material()
            }
        })
    }

    /// The one or two materials a wrapper holds.
    fn nested_materials(
        &mut self,
        props: &Props<'a>,
        min: usize,
        max: usize,
    ) -> Result<Vec<Arc<Material>>, Diagnostic> {
        let nested = props.children(PluginKind::Bsdf);
        if nested.len() < min || nested.len() > max {
            let count = if min == max { format!("{min}") } else { format!("{min} or {max}") };
            return Err(props.error(format!(
                "the `{}` BSDF holds {count} nested <bsdf>, not {}",
                props.type_name(),
                nested.len()
            )));
        }
        nested.into_iter().map(|(_, p)| self.material(p)).collect()
    }

    fn interface(&mut self, props: &Props<'a>, default_int: f64) -> Result<Interface, Diagnostic> {
        Ok(Interface {
            int_ior: ior(props, "int_ior", default_int)?,
            ext_ior: ior(props, "ext_ior", EXT_IOR)?,
            specular_reflectance: self.param(props, "specular_reflectance", 1.0)?,
            specular_transmittance: self.param(props, "specular_transmittance", 1.0)?,
        })
    }

    fn coating(&mut self, props: &Props<'a>) -> Result<Coating, Diagnostic> {
        Ok(Coating {
            diffuse_reflectance: self.param(props, "diffuse_reflectance", 0.5)?,
            specular_reflectance: self.param(props, "specular_reflectance", 1.0)?,
            int_ior: ior(props, "int_ior", PLASTIC_INT_IOR)?,
            ext_ior: ior(props, "ext_ior", EXT_IOR)?,
            nonlinear: props.boolean("nonlinear", false)?,
        })
    }

    fn principled(&mut self, props: &Props<'a>) -> Result<Principled, Diagnostic> {
        let spec_trans = self.scalar_param(props, "spec_trans", 0.0)?;
        // Mitsuba's `get_flag`: the lobe exists unless the parameter is absent or a zero float.
        let has_spec_trans = match &spec_trans {
            Param::Texture(_) => true,
            Param::Constant(c) => props.plugin.property("spec_trans").is_some() && *c != glam::DVec3::ZERO,
        };
        let eta = match (props.plugin.property("eta"), props.plugin.property("specular")) {
            (Some(_), Some(_)) => {
                return Err(props.error("give `eta` or `specular`, not both (they set the same index)"));
            }
            (Some(_), None) => {
                let eta = props.positive("eta", 1.5)?;
                if has_spec_trans && eta == 1.0 { 1.001 } else { eta }
            }
            (None, _) => {
                let mut specular = props.float("specular", 0.5)?;
                if has_spec_trans && specular == 0.0 {
                    specular = 1e-3;
                }
                let eta = 2.0 / (1.0 - (0.08 * specular).sqrt()) - 1.0;
                if !(eta > 0.0 && eta.is_finite()) {
                    return Err(props.error(format!(
                        "`specular` = {specular} gives no index of refraction (it must lie in [0, 12.5))"
                    )));
                }
                eta
            }
        };
        Ok(Principled {
            base_color: self.param(props, "base_color", 0.5)?,
            roughness: self.scalar_param(props, "roughness", 0.5)?,
            anisotropic: self.scalar_param(props, "anisotropic", 0.0)?,
            metallic: self.scalar_param(props, "metallic", 0.0)?,
            spec_trans,
            spec_tint: self.scalar_param(props, "spec_tint", 0.0)?,
            sheen: self.scalar_param(props, "sheen", 0.0)?,
            sheen_tint: self.scalar_param(props, "sheen_tint", 0.0)?,
            flatness: self.scalar_param(props, "flatness", 0.0)?,
            clearcoat: self.scalar_param(props, "clearcoat", 0.0)?,
            clearcoat_gloss: self.scalar_param(props, "clearcoat_gloss", 0.0)?,
            eta,
            specular_sampling_rate: props.float("main_specular_sampling_rate", 1.0)?,
            clearcoat_sampling_rate: props.float("clearcoat_sampling_rate", 1.0)?,
            diffuse_sampling_rate: props.float("diffuse_reflectance_sampling_rate", 1.0)?,
        })
    }

    fn principled_thin(&mut self, props: &Props<'a>) -> Result<PrincipledThin, Diagnostic> {
        Ok(PrincipledThin {
            base_color: self.param(props, "base_color", 0.5)?,
            roughness: self.scalar_param(props, "roughness", 0.5)?,
            anisotropic: self.scalar_param(props, "anisotropic", 0.0)?,
            spec_trans: self.scalar_param(props, "spec_trans", 0.0)?,
            eta: self.scalar_param(props, "eta", 1.5)?,
            spec_tint: self.scalar_param(props, "spec_tint", 0.0)?,
            sheen: self.scalar_param(props, "sheen", 0.0)?,
            sheen_tint: self.scalar_param(props, "sheen_tint", 0.0)?,
            flatness: self.scalar_param(props, "flatness", 0.0)?,
            diff_trans: self.scalar_param(props, "diff_trans", 0.0)?,
            specular_reflectance_sampling_rate: props.float("specular_reflectance_sampling_rate", 1.0)?,
            specular_transmittance_sampling_rate: props.float("specular_transmittance_sampling_rate", 1.0)?,
            diffuse_reflectance_sampling_rate: props.float("diffuse_reflectance_sampling_rate", 1.0)?,
            diffuse_transmittance_sampling_rate: props.float("diffuse_transmittance_sampling_rate", 1.0)?,
        })
    }

    fn metal(&mut self, props: &Props<'a>) -> Result<Metal, Diagnostic> {
        let given = (props.color("eta")?, props.color("k")?);
        let (eta, k) = match given {
            (Some(eta), Some(k)) => {
                props.ignore("material");
                (eta, k)
            }
            (None, None) => {
                let (name, pos) = props.string("material")?.unwrap_or(("none", props.plugin.pos));
                let (eta, k) = metal_ior(name).ok_or_else(|| {
                    props.error_at(
                        pos,
                        format!(
                            "unknown conductor `{}`; Mitsuba's named conductors are {}, and `none`",
                            crate::base::diagnostic::clip(name),
                            super::METALS.iter().map(|m| m.0).collect::<Vec<_>>().join(", ")
                        ),
                    )
                })?;
                (eta.into(), k.into())
            }
            _ => return Err(props.error("give both `eta` and `k`, or neither (and a `material` name)")),
        };
        Ok(Metal { eta, k, specular_reflectance: self.param(props, "specular_reflectance", 1.0)? })
    }

    fn microfacet(&mut self, props: &Props<'a>, anisotropic: bool) -> Result<Microfacet, Diagnostic> {
        let distribution = match props.choice("distribution", &["beckmann", "ggx"], "beckmann")? {
            "ggx" => Distribution::Ggx,
            _ => Distribution::Beckmann,
        };
        let has_uv = props.plugin.property("alpha_u").is_some() || props.named_child("alpha_u").is_some();
        let (alpha_u, alpha_v) = if anisotropic && has_uv {
            (self.scalar_param(props, "alpha_u", 0.1)?, self.scalar_param(props, "alpha_v", 0.1)?)
        } else {
            let a = self.scalar_param(props, "alpha", 0.1)?;
            (a.clone(), a)
        };
        Ok(Microfacet {
            distribution,
            alpha_u,
            alpha_v,
            sample_visible: props.boolean("sample_visible", true)?,
        })
    }
}

/// Mitsuba's default material: diffuse, reflectance 0.5.
fn default_material() -> Material {
    Material::Diffuse { reflectance: Param::scalar(0.5) }
}

/// An index of refraction: a number, or a name from Mitsuba's table.
fn ior(props: &Props<'_>, name: &str, default: f64) -> Result<f64, Diagnostic> {
    let Some(p) = props.get(name) else { return Ok(default) };
    let value = match &p.value {
        Value::Float(x) => *x,
        Value::Integer(i) => *i as f64,
        Value::String(s) => named_ior(s).ok_or_else(|| {
            props.error_at(
                p.pos,
                format!(
                    "unknown index of refraction `{}`; give a number or one of {}",
                    crate::base::diagnostic::clip(s),
                    super::NAMED_IORS.iter().map(|n| format!("`{}`", n.0)).collect::<Vec<_>>().join(", ")
                ),
            )
        })?,
        other => {
            return Err(props.error_at(
                p.pos,
                format!("`{name}` must be a <float> or a <string>, not a <{}>", other.tag()),
            ));
        }
    };
    if value > 0.0 && value.is_finite() {
        Ok(value)
    } else {
        Err(props.error_at(p.pos, format!("`{name}` must be a positive index of refraction, not {value}")))
    }
}

/// Marks every property of an unsupported plugin as read (one warning for the plugin is enough).
pub(super) fn mark_all_read(props: &Props<'_>) {
    for p in &props.plugin.properties {
        props.ignore(&p.name);
    }
}
