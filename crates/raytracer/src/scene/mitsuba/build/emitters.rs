//! `<emitter>` plugins outside shapes: `point`, `spot`, `directional`, `constant`, `envmap`.

use glam::{DMat3, DVec3, DVec4};

use super::super::{Plugin, PluginKind};
use super::{Builder, Props};
use crate::light::Emitter;
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
