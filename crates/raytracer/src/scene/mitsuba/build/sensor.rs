//! `<sensor>` (with its `<film>`, `<rfilter>` and `<sampler>`) to the camera and the render
//! settings.
//!
//! Mitsuba's camera looks along its local `+z` with `+y` up; its `to_world` places it. The image
//! plane at distance 1 spans `2 tan(fov / 2)` along the `fov_axis`, the other side following the
//! film's aspect ratio. An `orthographic` sensor shows its local `[-1, 1] x [-1/aspect, 1/aspect]`
//! as `to_world` places and scales it, with parallel rays along its `+z` from the near plane.

use glam::{DVec3, DVec4};

use super::super::{Plugin, PluginKind};
use super::{Builder, Props};
use crate::scene::{Diagnostic, PixelFilter, check_image_size};

/// Mitsuba's default film size.
const DEFAULT_FILM: (i64, i64) = (768, 576);
/// Mitsuba's default samples a pixel (`independent` sampler).
const DEFAULT_SAMPLES: i64 = 4;

impl<'a> Builder<'a> {
    /// The first `<sensor>` is the camera; later ones are left out with a warning.
    pub(super) fn sensor(&mut self, plugin: &'a Plugin) -> Result<(), Diagnostic> {
        let props = Props::new(self.doc, plugin);
        if self.sensor_seen {
            self.diagnostics.push(props.warning("only the first <sensor> is rendered; this one is left out"));
            return Ok(());
        }
        self.sensor_seen = true;
        let (thin_lens, orthographic) = match props.type_name() {
            "perspective" => (false, false),
            "thinlens" => (true, false),
            "orthographic" => (false, true),
            other => {
                return Err(props.error(format!(
                    "the sensor `{other}` is not supported: rayterra renders `perspective`, `thinlens` \
                     and `orthographic` sensors"
                )));
            }
        };
        // The film first: the field of view depends on its aspect ratio.
        let (width, height, crop) = match props.children(PluginKind::Film).first() {
            Some((_, film)) => self.film(film)?,
            None => (DEFAULT_FILM.0 as u32, DEFAULT_FILM.1 as u32, None),
        };
        let samples = match props.children(PluginKind::Sampler).first() {
            Some((_, sampler)) => {
                let s = Props::new(self.doc, sampler);
                let n = s.integer("sample_count", DEFAULT_SAMPLES)?;
                if !(1..=1 << 24).contains(&n) {
                    return Err(s.error(format!("`sample_count` must be from 1 to {}, not {n}", 1 << 24)));
                }
                for ignored in ["seed", "jitter", "scramble_seed", "strength", "dimension"] {
                    s.ignore(ignored);
                }
                self.finish(&s);
                n as u32
            }
            None => DEFAULT_SAMPLES as u32,
        };
        self.scene.render.samples = Some(samples);

        let to_world = props.transform("to_world")?;
        let eye = to_world.transform_point3(DVec3::ZERO);
        let forward = (to_world * DVec4::new(0.0, 0.0, 1.0, 0.0)).truncate();
        let up_axis = (to_world * DVec4::new(0.0, 1.0, 0.0, 0.0)).truncate();
        let up = up_axis;
        let left = (to_world * DVec4::new(1.0, 0.0, 0.0, 0.0)).truncate();
        let Some(dir) = forward.try_normalize() else {
            return Err(props.error("the sensor's `to_world` has no viewing direction"));
        };
        let Some(up) = (up - dir * up.dot(dir)).try_normalize() else {
            return Err(
                props.error("the sensor's `to_world` has no up direction apart from its viewing direction")
            );
        };
        if left.dot(up.cross(dir)) < 0.0 {
            self.diagnostics.push(
                props.warning("the sensor's `to_world` mirrors the image; rayterra renders it unmirrored"),
            );
        }

        let aspect = width as f64 / height as f64;
        if orthographic {
            // Mitsuba's camera space shows x in [-1, 1] and y in [-1/aspect, 1/aspect] (the
            // film's aspect); `to_world` scales it. Rays start on the near plane.
            let near = props.positive("near_clip", 1e-2)?;
            props.ignore("far_clip");
            for ignored in ["shutter_open", "shutter_close", "srf"] {
                props.ignore(ignored);
            }
            let cam = &mut self.scene.camera;
            cam.eye = to_world.transform_point3(DVec3::new(0.0, 0.0, near));
            cam.dir = dir;
            cam.up = Some(up);
            cam.lens_width = 2.0 * left.length();
            cam.lens_height = 2.0 * (up_axis.length() / aspect);
            cam.image_width = width;
            cam.image_height = height;
            cam.orthographic = true;
            crop_window(cam, crop);
            self.finish(&props);
            return Ok(());
        }
        let axes = ["x", "y", "diagonal", "smaller", "larger"];
        let (tan_half, axis) = match props.get("fov") {
            Some(_) => {
                let fov = props.float("fov", 0.0)?;
                if !(fov > 0.0 && fov < 180.0) {
                    return Err(props.error("`fov` must be an angle between 0 and 180 degrees"));
                }
                ((fov.to_radians() / 2.0).tan(), props.choice("fov_axis", &axes, "x")?)
            }
            None => {
                // A focal length on 35 mm film (36 x 24 mm), along the diagonal; Mitsuba's default
                // is 50 mm.
                let (mm, pos) = props.string("focal_length")?.unwrap_or(("50mm", props.plugin.pos));
                let f: f64 = mm.trim_end_matches("mm").parse().unwrap_or(f64::NAN);
                if !(f > 0.0 && f.is_finite()) {
                    let text = crate::base::diagnostic::clip(mm);
                    return Err(
                        props.error_at(pos, format!("`focal_length` must be like `50mm`, not `{text}`"))
                    );
                }
                props.ignore("fov_axis");
                (36f64.hypot(24.0) / 2.0 / f, "diagonal")
            }
        };
        let axis = match axis {
            "smaller" if aspect >= 1.0 => "y",
            "smaller" => "x",
            "larger" if aspect >= 1.0 => "x",
            "larger" => "y",
            a => a,
        };
        let (half_w, half_h) = match axis {
            "x" => (tan_half, tan_half / aspect),
            "y" => (tan_half * aspect, tan_half),
            _ => {
                let d = tan_half / (aspect * aspect + 1.0).sqrt();
                (d * aspect, d)
            }
        };
        let cam = &mut self.scene.camera;
        cam.eye = eye;
        cam.dir = dir;
        cam.up = Some(up);
        cam.lens_width = 2.0 * half_w;
        cam.lens_height = 2.0 * half_h;
        cam.image_width = width;
        cam.image_height = height;
        crop_window(cam, crop);
        if thin_lens {
            cam.aperture = props.float("aperture_radius", 0.0)?.max(0.0);
            cam.focal_distance = Some(props.positive("focus_distance", 1.0)?);
        } else {
            props.ignore("focus_distance");
        }
        for ignored in [
            "near_clip",
            "far_clip",
            "shutter_open",
            "shutter_close",
            "principal_point_offset_x",
            "principal_point_offset_y",
            "srf",
        ] {
            props.ignore(ignored);
        }
        self.finish(&props);
        Ok(())
    }

    /// The film's size and crop window (`[x, y, width, height]` in pixels, when it is not the
    /// whole film), and its reconstruction filter into the render settings.
    fn film(&mut self, plugin: &'a Plugin) -> Result<(u32, u32, Option<[u32; 4]>), Diagnostic> {
        let props = Props::new(self.doc, plugin);
        if !matches!(props.type_name(), "hdrfilm" | "specfilm") {
            self.warn(&props, "it is read as an `hdrfilm`");
        }
        let w = props.integer("width", DEFAULT_FILM.0)?;
        let h = props.integer("height", DEFAULT_FILM.1)?;
        let (w, h) = match (u32::try_from(w), u32::try_from(h)) {
            (Ok(w), Ok(h)) => (w, h),
            _ => return Err(props.error(format!("the film size {w}x{h} is not a size"))),
        };
        check_image_size(w, h).map_err(|m| props.error(m))?;
        // The crop window (Mitsuba's defaults: the whole film).
        let crop_value = |name: &str, default: u32| -> Result<u32, Diagnostic> {
            let v = props.integer(name, default as i64)?;
            u32::try_from(v).map_err(|_| props.error(format!("`{name}` must be 0 or more, not {v}")))
        };
        let crop = [
            crop_value("crop_offset_x", 0)?,
            crop_value("crop_offset_y", 0)?,
            crop_value("crop_width", w)?,
            crop_value("crop_height", h)?,
        ];
        let [x, y, cw, ch] = crop.map(u64::from);
        if cw == 0 || ch == 0 || x + cw > u64::from(w) || y + ch > u64::from(h) {
            return Err(props.error(format!(
                "the crop window ({cw}x{ch} at {x}, {y}) must be a non-empty part of the {w}x{h} film"
            )));
        }
        let crop = (crop != [0, 0, w, h]).then_some(crop);
        for ignored in [
            "pixel_format",
            "component_format",
            "file_format",
            "sample_border",
            "compensate",
            "banner",
            "rfilter",
        ] {
            props.ignore(ignored);
        }
        self.scene.render.filter = match props.children(PluginKind::ReconstructionFilter).first() {
            None => PixelFilter::Gaussian { stddev: 0.5 },
            Some((_, f)) => {
                let f = Props::new(self.doc, f);
                let filter = match f.type_name() {
                    "box" => PixelFilter::Box,
                    "tent" => PixelFilter::Tent { radius: f.positive("radius", 1.0)? },
                    "gaussian" => PixelFilter::Gaussian { stddev: f.positive("stddev", 0.5)? },
                    _ => {
                        self.warn(&f, "pixels are reconstructed with Mitsuba's default `gaussian` filter");
                        super::bsdfs::mark_all_read(&f);
                        PixelFilter::Gaussian { stddev: 0.5 }
                    }
                };
                self.finish(&f);
                filter
            }
        };
        self.finish(&props);
        Ok((w, h, crop))
    }
}

/// Narrows `cam` (set up for the whole film) to the crop window `[x, y, width, height]` (pixels
/// of the film, `y` down): the image becomes the window's size and shows the part of the image
/// plane the window covers, as Mitsuba's film renders only its crop window.
fn crop_window(cam: &mut crate::scene::CameraSettings, crop: Option<[u32; 4]>) {
    let Some([x, y, cw, ch]) = crop else { return };
    let (w, h) = (f64::from(cam.image_width), f64::from(cam.image_height));
    let (x, y, cw, ch) = (f64::from(x), f64::from(y), f64::from(cw), f64::from(ch));
    cam.window_offset =
        (((x + cw / 2.0) / w - 0.5) * cam.lens_width, (0.5 - (y + ch / 2.0) / h) * cam.lens_height);
    cam.lens_width *= cw / w;
    cam.lens_height *= ch / h;
    cam.image_width = cw as u32;
    cam.image_height = ch as u32;
}
