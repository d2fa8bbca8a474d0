//! `<emitter>` plugins outside shapes: `point`, `spot`, `projector`, `directional`, `constant`,
//! `envmap`.

use glam::{DMat3, DVec3, DVec4};

use super::super::{Plugin, PluginKind};
use super::{Builder, Props};
use crate::light::{Emitter, FovAxis};
use crate::material::{Param, TextureSpec};
use crate::scene::Diagnostic;

impl<'a> Builder<'a> {
    /// An emitter of the scene.
    pub(super) fn emitter(&mut self, plugin: &'a Plugin) -> Result<(), Diagnostic> {
        let props = Props::new(self.doc, plugin);
        let emitter = match props.type_name() {
            "point" => {
                let to_world = props.transform("to_world")?;
                let position = to_world.transform_point3(props.vector("position", DVec3::ZERO)?);
                Emitter::Point { position, intensity: props.color("intensity")?.unwrap_or(DVec3::ONE) }
            }
            "spot" => {
                let to_world = props.transform("to_world")?;
                let axis = (to_world * DVec4::new(0.0, 0.0, 1.0, 0.0)).truncate();
                let Some(axis) = axis.try_normalize() else {
                    return Err(props.error("the spot's `to_world` has no direction"));
                };
                let cutoff = props.positive("cutoff_angle", 20.0)?;
                let beam = props.positive("beam_width", cutoff * 3.0 / 4.0)?.min(cutoff);
                if cutoff >= 90.0 {
                    return Err(props.error("`cutoff_angle` must be under 90 degrees"));
                }
                let texture = match props.named_child("texture") {
                    None => None,
                    Some(t) if t.kind == PluginKind::Texture => match self.texture(t)? {
                        Param::Texture(spec) if matches!(*spec, TextureSpec::MeshAttribute { .. }) => {
                            return Err(props.error_at(
                                t.pos,
                                "the spot's `texture` cannot be a `mesh_attribute` (it has no mesh)",
                            ));
                        }
                        Param::Texture(spec) => Some(spec),
                        Param::Constant(_) => {
                            return Err(props.error_at(
                                t.pos,
                                "the spot's `texture` must vary (a bitmap or a checkerboard), as in Mitsuba",
                            ));
                        }
                    },
                    Some(other) => {
                        return Err(props.error_at(
                            other.pos,
                            format!("the spot's `texture` must be a <texture>, not a <{}>", other.kind.tag()),
                        ));
                    }
                };
                let linear = DMat3::from_mat4(to_world);
                if linear.determinant().abs() < 1e-300 {
                    return Err(props.error("the spot's `to_world` is singular"));
                }
                Emitter::Spot {
                    position: to_world.transform_point3(DVec3::ZERO),
                    axis,
                    intensity: props.color("intensity")?.unwrap_or(DVec3::ONE),
                    cos_beam: beam.to_radians().cos(),
                    cos_cutoff: cutoff.to_radians().cos(),
                    texture,
                    to_local: linear.inverse(),
                }
            }
            "projector" => {
                let to_world = props.transform("to_world")?;
                if DMat3::from_mat4(to_world).determinant().abs() < 1e-300 || !to_world.is_finite() {
                    return Err(props.error("the projector's `to_world` is singular"));
                }
                let irradiance =
                    match props.get("irradiance").is_some() || props.named_child("irradiance").is_some() {
                        true => self.param(&props, "irradiance", 1.0)?,
                        false => {
                            return Err(props.error(
                            "a `projector` needs an `irradiance` (a colour, or a texture such as a `bitmap`)",
                        ));
                        }
                    };
                if let crate::material::Param::Texture(t) = &irradiance
                    && matches!(**t, TextureSpec::MeshAttribute { .. })
                {
                    return Err(props.error(
                        "the projector's `irradiance` cannot be a `mesh_attribute` (it has no mesh)",
                    ));
                }
                let (tan_half, fov_axis) = fov(&props)?;
                Emitter::Projector {
                    irradiance,
                    scale: props.float("scale", 1.0)?,
                    tan_half,
                    fov_axis,
                    to_world,
                    to_local: to_world.inverse(),
                }
            }
            "directional" => {
                let to_world = props.transform("to_world")?;
                let given = props.vector("direction", DVec3::ZERO)?;
                let local = if given == DVec3::ZERO { DVec3::Z } else { given };
                let dir = (to_world * local.extend(0.0)).truncate();
                let Some(direction) = dir.try_normalize() else {
                    return Err(props.error("the directional emitter has no direction"));
                };
                Emitter::Directional {
                    direction,
                    irradiance: props.color("irradiance")?.unwrap_or(DVec3::ONE),
                }
            }
            "constant" => Emitter::Constant { radiance: props.color("radiance")?.unwrap_or(DVec3::ONE) },
            "envmap" => {
                let (name, pos) =
                    props.string("filename")?.ok_or_else(|| props.error("an `envmap` needs a `filename`"))?;
                let file = self.doc.resolve_file(name).ok_or_else(|| {
                    props.error_at(
                        pos,
                        format!(
                            "the environment map `{}` is not found (looked for in {})",
                            crate::base::diagnostic::clip(name),
                            self.looked_in()
                        ),
                    )
                })?;
                let to_world = DMat3::from_mat4(props.transform("to_world")?);
                // Only the rotation counts for directions; a scale is taken out.
                let rotation = DMat3::from_cols(
                    to_world.x_axis.normalize_or_zero(),
                    to_world.y_axis.normalize_or_zero(),
                    to_world.z_axis.normalize_or_zero(),
                );
                props.ignore("filter_type");
                props.ignore("mis_compensation");
                Emitter::Environment {
                    file,
                    location: self.doc.location(pos),
                    scale: props.float("scale", 1.0)?,
                    to_world: rotation,
                }
            }
            "area" => return Err(props.error("an `area` emitter belongs inside a <shape>")),
            _ => {
                self.warn(&props, "the scene is rendered without this emitter");
                super::bsdfs::mark_all_read(&props);
                return Ok(());
            }
        };
        let infinite = |e: &Emitter| matches!(e, Emitter::Constant { .. } | Emitter::Environment { .. });
        if infinite(&emitter) && self.scene.emitters.iter().any(infinite) {
            return Err(props.error("a scene has at most one `constant` or `envmap` emitter, as in Mitsuba"));
        }
        self.finish(&props);
        self.push_emitter(emitter);
        Ok(())
    }
}

/// A perspective device's field of view as Mitsuba's `parse_fov` reads it: `fov` (degrees,
/// between 0 and 180) along `fov_axis` (`x`), or `focal_length` (`50mm`) on 35 mm film along
/// the diagonal, not both. Returns the tangent of the half-angle and its axis.
fn fov(props: &Props<'_>) -> Result<(f64, FovAxis), Diagnostic> {
    if props.get("fov").is_some() {
        if props.get("focal_length").is_some() {
            return Err(props.error("give `fov` or `focal_length`, not both"));
        }
        let fov = props.float("fov", 0.0)?;
        if !(fov > 0.0 && fov < 180.0) {
            return Err(props.error("`fov` must be an angle between 0 and 180 degrees"));
        }
        let axis = props.choice("fov_axis", &FovAxis::NAMES, "x")?;
        return Ok(((fov.to_radians() / 2.0).tan(), FovAxis::parse(axis).unwrap_or(FovAxis::X)));
    }
    let (mm, pos) = props.string("focal_length")?.unwrap_or(("50mm", props.plugin.pos));
    let f: f64 = mm.trim_end_matches("mm").parse().unwrap_or(f64::NAN);
    if !(f > 0.0 && f.is_finite()) {
        let text = crate::base::diagnostic::clip(mm);
        return Err(props.error_at(pos, format!("`focal_length` must be like `50mm`, not `{text}`")));
    }
    props.ignore("fov_axis");
    Ok((36f64.hypot(24.0) / 2.0 / f, FovAxis::Diagonal))
}
