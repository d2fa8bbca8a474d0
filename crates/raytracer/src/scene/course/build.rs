//! Building the scene description from a block's keys: the background, camera, lights,
//! materials and primitives.

use glam::{DVec2, DVec3};

use super::super::{
    Algorithm, Background, CameraSettings, Gradient, MeshPrimitive, PhotonSettings, Primitive,
};
use super::blocks::{BlockKind, Entry, LightKind, OpenBlock, Parser, PrimitiveKind};
use super::keys::{BlockReader, Lookup, Reported};
use super::{
    MAX_EMITTED_PHOTONS, MAX_IMAGE_SIDE, MAX_ITERATIONS, MAX_QUALITY, MAX_SAMPLE_PHOTONS, MAX_STORED_PHOTONS,
    aspect_mismatch, check_image_size,
};
use crate::base::diagnostic::{Severity, clip};
use crate::base::source::Span;
use crate::geometry::{Bezier, Cylinder, MeshFile, MeshTransform, Plane, Shape, Sphere, Square, Triangle};
use crate::light::Light;
use crate::material::CourseMaterial;
use crate::scene::texture::{BUILTIN_PREFIX, Builtin, TextureRef, TextureSource};

impl<'s> Parser<'s> {
    /// Turns a complete block into scene data.
    pub(super) fn finish_block(&mut self, block: OpenBlock<'s>) {
        let mut reader = BlockReader::new(block, self);
        match reader.kind {
            BlockKind::Background => reader.background(),
            BlockKind::Camera => reader.camera(),
            BlockKind::Light(kind) => reader.light(kind),
            BlockKind::Primitive(kind) => reader.primitive(kind),
        }
        reader.finish();
    }
}

impl<'p, 's> BlockReader<'p, 's> {
    pub(super) fn background(&mut self) {
        if let Some(line) = self.parser.seen.background.replace(self.header.line) {
            let header = self.header;
            self.warning(header, format!("a second `background` block replaces the one on line {line}"));
        }
        let mut bg = Background::default();
        if let Ok(Some(c)) = self.color("color", false) {
            bg.color = c;
        }
        let top = self.color("top", true).ok().flatten();
        let bottom = self.color("bottom", true).ok().flatten();
        if top.is_some() || bottom.is_some() {
            bg.gradient =
                Some(Gradient { bottom: bottom.unwrap_or(DVec3::ONE), top: top.unwrap_or(DVec3::ONE) });
        }
        self.parser.scene.background = bg;
    }

    pub(super) fn camera(&mut self) {
        if let Some(line) = self.parser.seen.camera.replace(self.header.line) {
            let header = self.header;
            self.warning(header, format!("a second `camera` block replaces the one on line {line}"));
        }
        let mut cam = CameraSettings::default();
        if let Ok(Some(o)) = self.vec3("O") {
            cam.eye = o;
        }
        if let Ok(Some(n)) = self.vec3("N") {
            match crate::base::error::unit_direction(n, "N") {
                Ok(n) => cam.dir = n,
                Err(_) => {
                    let span = self.span_of("N");
                    self.error(span, "the view direction `N=` must not be the zero vector");
                }
            }
        }
        // Whether the lens and image sizes all read; the aspect is compared only then (an error
        // in one of them is not also a stretched picture).
        let mut sizes_read = true;
        for (key, slot) in [("lens_W", &mut cam.lens_width), ("lens_H", &mut cam.lens_height)] {
            match self.number(key) {
                Ok(Some(v)) if v > 0.0 => *slot = v,
                Ok(Some(_)) => {
                    let span = self.span_of(key);
                    self.error(span, format!("`{key}=` must be positive"));
                    sizes_read = false;
                }
                Ok(None) => {}
                Err(Reported) => sizes_read = false,
            }
        }
        let side = MAX_IMAGE_SIDE as u64;
        match self.integer("image_W", 1, side) {
            Ok(Some(w)) => cam.image_width = w as u32,
            Ok(None) => {}
            Err(Reported) => sizes_read = false,
        }
        match self.integer("image_H", 1, side) {
            Ok(Some(h)) => cam.image_height = h as u32,
            Ok(None) => {}
            Err(Reported) => sizes_read = false,
        }
        if let Err(message) = check_image_size(cam.image_width, cam.image_height) {
            let span = self.span_of("image_W");
            self.error(span, message);
            sizes_read = false;
        }
        let q = MAX_QUALITY as u64;
        if let Ok(Some(v)) = self.integer("shade_quality", 1, q) {
            cam.shade_quality = v as u32;
        }
        if let Ok(Some(v)) = self.integer("drefl_quality", 1, q) {
            cam.drefl_quality = v as u32;
        }
        cam.photons = self.photon_settings();
        if let Ok(Some((name, span))) = self.text("algorithm") {
            match Algorithm::from_name(&name) {
                Some(a) => cam.algorithm = Some((a, self.parser.source.location(span))),
                None => {
                    let expected = Algorithm::NAMES.map(|n| format!("`{n}`")).join(", ");
                    self.error(span, format!("unknown `algorithm=` `{}`", clip(&name)))
                        .notes
                        .push(format!("expected one of {expected}"));
                }
            }
        }
        if let Ok(Some(a)) = self.number("aperture") {
            if a >= 0.0 {
                cam.aperture = a;
            } else {
                let span = self.span_of("aperture");
                self.error(span, "`aperture=` must not be negative");
            }
        }
        if let Ok(Some(f)) = self.number("focal_dist") {
            if f > 0.0 {
                cam.focal_distance = Some(f);
            } else {
                let span = self.span_of("focal_dist");
                self.error(span, "`focal_dist=` must be positive");
            }
        }
        if let Some(message) = aspect_mismatch(&cam, cam.image_width, cam.image_height).filter(|_| sizes_read)
        {
            let span = self.span_of("lens_W");
            self.warning(span, message);
        }
        self.parser.scene.camera = cam;
    }

    /// The photon-mapping keys of the camera block, validated (spec section 10).
    pub(super) fn photon_settings(&mut self) -> PhotonSettings {
        let mut photons = PhotonSettings::default();
        let mut keys: Vec<(&'static str, Span)> =
            PhotonSettings::KEYS.iter().filter_map(|&k| self.find(k).map(|e| (k, e.key_span))).collect();
        keys.sort_by_key(|(_, span)| (span.line, span.column));
        photons.keys = keys.into_iter().map(|(k, span)| (k, self.parser.source.location(span))).collect();
        for (key, slot, max) in [
            ("max_photons", &mut photons.max_photons, MAX_STORED_PHOTONS),
            ("emit_photons", &mut photons.emit_photons, MAX_EMITTED_PHOTONS),
            ("sample_photons", &mut photons.sample_photons, MAX_SAMPLE_PHOTONS),
            ("iterations", &mut photons.iterations, MAX_ITERATIONS),
        ] {
            if let Ok(Some(v)) = self.integer(key, 1, max) {
                *slot = v;
            }
        }
        if let Ok(Some(v)) = self.integer("max_hitpoints", 1, MAX_STORED_PHOTONS) {
            photons.max_hitpoints = Some(v);
        }
        if let Ok(Some(v)) = self.number("sample_dist") {
            if v > 0.0 {
                photons.sample_dist = v;
            } else {
                let span = self.span_of("sample_dist");
                self.error(span, "`sample_dist=` (the gathering radius) must be positive");
            }
        }
        if let Ok(Some(v)) = self.number("reduction") {
            if v > 0.0 && v <= 1.0 {
                photons.reduction = v;
            } else {
                let span = self.span_of("reduction");
                self.error(span, "`reduction=` (the radius reduction alpha) must lie in (0, 1]")
                    .notes
                    .push("2/3, the default, is the usual choice".into());
            }
        }
        photons
    }

    pub(super) fn light(&mut self, kind: LightKind) {
        let color = match self.color("color", true) {
            Ok(Some(c)) => c,
            Ok(None) => {
                let header = self.header;
                self.warning(header, "this light has no `color=`, so it gives no light");
                DVec3::ZERO
            }
            Err(Reported) => DVec3::ZERO,
        };
        let o = self.required_vec3("O", "the light's position");
        let light = match kind {
            LightKind::Point => o.map(|position| Light::Point { position, color }),
            LightKind::Square => {
                let dx = self.required_vec3("Dx", "the first half axis");
                let dy = self.required_vec3("Dy", "the second half axis");
                match (o, dx, dy) {
                    (Some(o), Some(dx), Some(dy)) => {
                        self.built(Square::new(o, dx, dy)).map(|shape| Light::Square { shape, color })
                    }
                    _ => None,
                }
            }
            LightKind::Sphere => {
                let r = self.required_number("R", "the radius");
                match (o, r) {
                    (Some(o), Some(r)) => {
                        self.built(Sphere::new(o, r)).map(|shape| Light::Sphere { shape, color })
                    }
                    _ => None,
                }
            }
        };
        if let Some(light) = light {
            self.parser.scene.lights.push(light);
        }
    }

    pub(super) fn material(&mut self) -> CourseMaterial {
        let mut m = CourseMaterial::default();
        if let Ok(Some(c)) = self.color("color", false) {
            m.color = c;
        }
        m.diff = self.weight("diff");
        m.spec = self.weight("spec");
        m.refl = self.weight("refl");
        m.drefl = self.weight("drefl");
        m.refr = self.weight("refr");
        if let Ok(Some(a)) = self.vec3("absor") {
            if a.min_element() < 0.0 {
                let span = self.span_of("absor");
                self.warning(span, "`absor=` is negative: light would grow inside the object");
            }
            m.absor = a;
        }
        match self.number("rindex") {
            Ok(Some(n)) if n > 0.0 => m.rindex = n,
            Ok(Some(_)) => {
                let span = self.span_of("rindex");
                self.error(span, "`rindex=` must be positive");
            }
            Ok(None) if m.refr > 0.0 => {
                let span = self.span_of("refr");
                self.error(span, "`refr=` is positive, so `rindex=` (the refractive index) is required");
            }
            _ => {}
        }
        if let Ok(Some((blur, span))) = self.text("blur")
            && blur != "exp"
        {
            self.warning(
                span,
                format!("unknown `blur= {}`; `exp` is the only distribution, and it is used", clip(&blur)),
            );
        }
        m.texture = self.texture_ref("texture");
        // A normal map: `bump=`, or `NT=` (LuChengTHU's name for it); `bump=` wins if both are given.
        let nt = self.texture_ref("NT");
        m.bump = self.texture_ref("bump").or(nt);
        m
    }

    /// A texture named by `key=`: a file or a built-in texture.
    pub(super) fn texture_ref(&mut self, key: &str) -> Option<TextureRef> {
        let Ok(Some((path, span))) = self.text(key) else { return None };
        let location = self.parser.source.location(span);
        let source = match path.strip_prefix(BUILTIN_PREFIX) {
            Some(name) => match Builtin::parse(name) {
                Ok(b) => TextureSource::Builtin(b),
                Err(message) => {
                    self.error(span, message);
                    return None;
                }
            },
            None => TextureSource::File(path),
        };
        Some(TextureRef { source, location })
    }

    pub(super) fn primitive(&mut self, kind: PrimitiveKind) {
        let material = self.material();
        let mesh_file = match kind {
            PrimitiveKind::Mesh => Some(self.mesh("file", "scale", "rotation", 1.0)),
            PrimitiveKind::Polyhedron => {
                Some(self.mesh("mesh", "size", "angles", std::f64::consts::PI / 180.0))
            }
            _ => None,
        };
        if let Some(file) = mesh_file {
            if let Some(file) = file {
                let material = self.parser.share(material);
                let index = self.parser.scene.primitives.len();
                self.parser.scene.meshes.push(MeshPrimitive { index, file, material });
            }
            return;
        }
        let shape = match kind {
            PrimitiveKind::Triangle => self.triangle(),
            PrimitiveKind::Mesh | PrimitiveKind::Polyhedron => unreachable!("mesh files are read above"),
            PrimitiveKind::Bezier => self.bezier(),
            PrimitiveKind::Sphere => {
                let o = self.required_vec3("O", "the centre");
                let r = self.required_number("R", "the radius");
                let pole = self.vec3("De").ok().flatten().unwrap_or(DVec3::Z);
                let seam = self.vec3("Dc").ok().flatten().unwrap_or(DVec3::Y);
                match (o, r) {
                    (Some(o), Some(r)) => self.built(Sphere::with_frame(o, r, pole, seam).map(Shape::Sphere)),
                    _ => None,
                }
            }
            PrimitiveKind::Plane => {
                let n = self.required_vec3("N", "the normal");
                let r = self.required_number("R", "the offset from the origin along the normal");
                let dx = self.vec3("Dx");
                let dy = self.vec3("Dy");
                let (n, r) = match (n, r) {
                    (Some(n), Some(r)) => (n, r),
                    _ => return,
                };
                let Some(plane) = self.built(Plane::new(n, r)) else { return };
                match (dx, dy) {
                    (Ok(Some(dx)), Ok(Some(dy))) => {
                        self.built(plane.with_texture_axes(dx, dy).map(Shape::Plane))
                    }
                    (Ok(None), _) | (_, Ok(None)) if material.texture.is_some() => {
                        let header = self.header;
                        self.error(header, "a textured `primitive plane` needs `Dx=` and `Dy=`")
                            .notes
                            .push("their lengths are the world size of one texture tile".into());
                        None
                    }
                    (Err(Reported), _) | (_, Err(Reported)) => None,
                    _ => Some(Shape::Plane(plane)),
                }
            }
            PrimitiveKind::Square => {
                let o = self.required_vec3("O", "the centre");
                let dx = self.required_vec3("Dx", "the first half axis");
                let dy = self.required_vec3("Dy", "the second half axis");
                match (o, dx, dy) {
                    (Some(o), Some(dx), Some(dy)) => {
                        self.built(Square::new(o, dx, dy).map(|s| Shape::Square(Box::new(s))))
                    }
                    _ => None,
                }
            }
            PrimitiveKind::Cylinder => {
                let o1 = self.required_vec3("O1", "the bottom cap centre");
                let o2 = self.required_vec3("O2", "the top cap centre");
                let r = self.required_number("R", "the radius");
                for key in ["De", "Dc"] {
                    if let Some(e) = self.entry(key) {
                        self.parser
                            .report(
                                Severity::Note,
                                e.key_span,
                                format!("`{key}=` has no effect on a cylinder"),
                            )
                            .notes
                            .push("the side texture's seam follows the axis (spec 5.6)".into());
                    }
                }
                match (o1, o2, r) {
                    (Some(o1), Some(o2), Some(r)) => {
                        self.built(Cylinder::new(o1, o2, r).map(|c| Shape::Cylinder(Box::new(c))))
                    }
                    _ => None,
                }
            }
        };
        if let Some(shape) = shape {
            let material = self.parser.share(material);
            self.parser.scene.primitives.push(Primitive { shape, material });
        }
    }

    /// `primitive triangle`: corners `P0= P1= P2=`, or `O1= O2= O3=`.
    pub(super) fn triangle(&mut self) -> Option<Shape> {
        let form = if ["O1", "O2", "O3"].iter().any(|k| self.has(k))
            && !["P0", "P1", "P2"].iter().any(|k| self.has(k))
        {
            ["O1", "O2", "O3"]
        } else {
            ["P0", "P1", "P2"]
        };
        let corners = form.map(|k| self.vec3(k));
        if corners.iter().any(|c| c.is_err()) {
            return None;
        }
        let missing: Vec<&str> =
            form.iter().zip(&corners).filter(|(_, c)| matches!(c, Ok(None))).map(|(k, _)| *k).collect();
        if !missing.is_empty() {
            let header = self.header;
            let list = missing.iter().map(|k| format!("`{k}=`")).collect::<Vec<_>>().join(", ");
            self.error(header, format!("`primitive triangle` needs {list} (its corners)"))
                .notes
                .push("give the corners as `P0= P1= P2=` or as `O1= O2= O3=`".into());
            return None;
        }
        let [a, b, c] = corners.map(|c| c.ok().flatten().unwrap_or_default());
        match Triangle::new(a, b, c) {
            Ok(t) => Some(Shape::Triangle(Box::new(t))),
            Err(e) => {
                let span = self.span_of(form[2]);
                self.error(span, format!("in `primitive triangle`, {e}"));
                None
            }
        }
    }

    /// `primitive mesh` (`file=`, `O=`, `scale=`, `rotation=` in radians) and `primitive
    /// polyhedron` (`mesh=`, `O=`, `size=`, `angles=` in degrees): the file is loaded when the
    /// scene is prepared.
    pub(super) fn mesh(
        &mut self,
        file_key: &str,
        scale_key: &str,
        rotation_key: &str,
        to_radians: f64,
    ) -> Option<MeshFile> {
        let file = match self.text(file_key) {
            Ok(Some(f)) => Some(f),
            Ok(None) => {
                let header = self.header;
                self.error(header, format!("`{}` needs `{file_key}=` (the OBJ file)", self.kind));
                None
            }
            Err(Reported) => None,
        };
        let origin = self.vec3("O");
        let scale = match self.numbers_1_or_3(scale_key) {
            Ok(Some(s)) if s.x == 0.0 || s.y == 0.0 || s.z == 0.0 => {
                let span = self.span_of(scale_key);
                self.error(
                    span,
                    format!("`{scale_key}=` must not have a zero component (the mesh would be flat)"),
                );
                Err(Reported)
            }
            other => other,
        };
        let rotation = self.vec3(rotation_key);
        let (Some((path, span)), Ok(origin), Ok(scale), Ok(rotation)) = (file, origin, scale, rotation)
        else {
            return None;
        };
        let transform = MeshTransform {
            origin: origin.unwrap_or(DVec3::ZERO),
            scale: scale.unwrap_or(DVec3::ONE),
            rotation: rotation.unwrap_or(DVec3::ZERO) * to_radians,
        };
        let location = self.parser.source.location(span);
        Some(MeshFile { path, location, transform })
    }

    /// A vector of 3 numbers, or 1 number for all three components.
    pub(super) fn numbers_1_or_3(&mut self, key: &str) -> Lookup<DVec3> {
        match self.find(key).map(|e| e.values.len()) {
            Some(1) => Ok(self.number(key)?.map(DVec3::splat)),
            _ => self.vec3(key),
        }
    }

    /// `primitive bezier`: axis `O1=` to `O2=` with profile points `P= z r` (one a line), or
    /// `center=` with `V0= .. V3=` (abcbdf's form: a cubic about the vertical through `center`).
    pub(super) fn bezier(&mut self) -> Option<Shape> {
        if self.has("center") {
            let center = self.required_vec3("center", "the point the vertical axis passes through");
            let v = ["V0", "V1", "V2", "V3"].map(|k| self.required_vec3(k, "a control point of the cubic"));
            let center = center?;
            if v.iter().any(Option::is_none) {
                return None;
            }
            let profile: Vec<DVec2> =
                v.iter().flatten().map(|p| DVec2::new(p.z, (p.x - center.x).abs())).collect();
            let base = DVec3::new(center.x, center.y, 0.0);
            return self.built(Bezier::new(base, DVec3::Z, profile).map(|b| Shape::Bezier(Box::new(b))));
        }
        let o1 = self.required_vec3("O1", "the bottom of the axis");
        let o2 = self.required_vec3("O2", "a point up the axis");
        let points = std::mem::take(&mut self.points);
        let mut profile = Vec::with_capacity(points.len());
        let mut bad = false;
        for e in &points {
            let mut values = Vec::with_capacity(2);
            for (text, span) in e.values.iter() {
                match text.parse::<f64>() {
                    Ok(v) if v.is_finite() => values.push(v),
                    _ => {
                        self.error(
                            *span,
                            format!("`P=` expects 2 numbers (z r); `{}` is not a number", clip(text)),
                        );
                        bad = true;
                    }
                }
            }
            if values.len() == 2 {
                profile.push(DVec2::new(values[0], values[1]));
            } else if !bad {
                let found = e.values.len();
                self.error(e.values_span(), format!("`P=` expects 2 numbers (z r), found {found}"));
                bad = true;
            }
        }
        let (o1, o2) = (o1?, o2?);
        if bad {
            return None;
        }
        if profile.len() < 2 || profile.len() > crate::geometry::bezier::MAX_CONTROL_POINTS {
            let header = self.header;
            self.error(
                header,
                format!(
                    "`primitive bezier` needs 2 to 32 `P= z r` lines (its profile), not {}",
                    profile.len()
                ),
            )
            .notes
            .push("one line per control point, in order; or give `center=` and `V0=` .. `V3=`".into());
            return None;
        }
        if profile.iter().any(|p| p.y < 0.0) {
            let span = points.iter().find(|e| e.values.get(1).is_some_and(|v| v.0.starts_with('-')));
            let span = span.map_or(self.header, Entry::values_span);
            self.warning(span, "a negative `r` in `P= z r` is a distance from the axis; its size is used");
        }
        self.built(Bezier::new(o1, o2 - o1, profile).map(|b| Shape::Bezier(Box::new(b))))
    }
}
