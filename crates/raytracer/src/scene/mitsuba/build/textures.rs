//! `<texture>` plugins: `bitmap`, `checkerboard` and `mesh_attribute` become [`TextureSpec`]s
//! (the images are read when the scene is prepared; a mesh attribute is checked against the
//! meshes that use it when their shapes are built).

use std::sync::Arc;

use glam::{DAffine2, DMat2, DMat4, DVec2, DVec3};

use super::super::Plugin;
use super::{Builder, Props};
use crate::material::{Param, TextureSpec, Wrap};
use crate::scene::Diagnostic;

impl<'a> Builder<'a> {
    /// The parameter a `<texture>` plugin gives.
    pub(super) fn texture(&mut self, plugin: &'a Plugin) -> Result<Param, Diagnostic> {
        let key = plugin as *const Plugin;
        if let Some(t) = self.textures.get(&key) {
            return Ok(Param::Texture(t.clone()));
        }
        let props = Props::new(self.doc, plugin);
        let spec = match props.type_name() {
            "bitmap" => self.bitmap(&props)?,
            "checkerboard" => TextureSpec::Checkerboard {
                color0: props.color("color0")?.unwrap_or(DVec3::splat(0.4)),
                color1: props.color("color1")?.unwrap_or(DVec3::splat(0.2)),
                to_uv: to_uv(&props)?,
            },
            "mesh_attribute" => {
                let (name, pos) = props.string("name")?.ok_or_else(|| {
                    props.error("a `mesh_attribute` needs a `name` (`vertex_color`, `face_color`...)")
                })?;
                if !name.starts_with("vertex_") && !name.starts_with("face_") {
                    return Err(props.error_at(
                        pos,
                        format!(
                            "a mesh attribute's name starts with `vertex_` or `face_`, not `{}`",
                            crate::base::diagnostic::clip(name)
                        ),
                    ));
                }
                TextureSpec::MeshAttribute {
                    name: name.to_owned(),
                    scale: props.float("scale", 1.0)?,
                    location: self.doc.location(props.plugin.pos),
                }
            }
            _ => {
                self.warn(&props, "it reads as a constant 0.5 grey");
                super::bsdfs::mark_all_read(&props);
                self.finish(&props);
                return Ok(Param::scalar(0.5));
            }
        };
        self.finish(&props);
        let spec = Arc::new(spec);
        self.textures.insert(key, spec.clone());
        Ok(Param::Texture(spec))
    }

    fn bitmap(&mut self, props: &Props<'a>) -> Result<TextureSpec, Diagnostic> {
        let (name, pos) =
            props.string("filename")?.ok_or_else(|| props.error("a `bitmap` needs a `filename`"))?;
        let file = self.doc.resolve_file(name).ok_or_else(|| {
            props.error_at(
                pos,
                format!(
                    "the texture `{}` is not found (looked for in {})",
                    crate::base::diagnostic::clip(name),
                    self.looked_in()
                ),
            )
        })?;
        let nearest = props.choice("filter_type", &["bilinear", "nearest"], "bilinear")? == "nearest";
        let wrap = match props.choice("wrap_mode", &["repeat", "mirror", "clamp"], "repeat")? {
            "mirror" => Wrap::Mirror,
            "clamp" => Wrap::Clamp,
            _ => Wrap::Repeat,
        };
        props.ignore("format");
        Ok(TextureSpec::Bitmap {
            file,
            location: self.doc.location(pos),
            raw: props.boolean("raw", false)?,
            nearest,
            wrap,
            to_uv: to_uv(props)?,
        })
    }

    /// The folders a relative file name is looked for in, for a message.
    pub(super) fn looked_in(&self) -> String {
        let list: Vec<String> = self.doc.resolver.iter().map(|d| format!("`{}`", d.display())).collect();
        if list.is_empty() { "the working folder".to_owned() } else { list.join(", ") }
    }
}

/// A texture's `to_uv`: the 2-D affine part of the transform (its x, y rows and translation).
fn to_uv(props: &Props<'_>) -> Result<DAffine2, Diagnostic> {
    let m: DMat4 = props.transform("to_uv")?;
    Ok(DAffine2 {
        matrix2: DMat2::from_cols(DVec2::new(m.x_axis.x, m.x_axis.y), DVec2::new(m.y_axis.x, m.y_axis.y)),
        translation: DVec2::new(m.w_axis.x, m.w_axis.y),
    })
}
