//! What the physically based materials and emitters (Mitsuba scenes) need once a scene is
//! prepared: the bitmaps of textured parameters and the environment map read within the memory
//! budget, which primitive emits, and the lookups of parameters at a surface point.

use std::collections::HashMap;
use std::f64::consts::{PI, TAU};
use std::sync::Arc;

use glam::{DMat3, DVec3};
use rayon::prelude::*;

use super::{Interaction, PreparedScene};
use crate::base::memory::MemoryBudget;
use crate::geometry::{Shape, ShapePart};
use crate::light::Emitter;
use crate::material::{Material, Param, Perturbation, TextureSpec};
use crate::scene::mitsuba::transform::coordinate_system;
use crate::scene::{Diagnostic, Location, Scene, Severity};
use crate::texture::{Bitmap, TextureError};

/// No emitter.
const NO_EMITTER: u32 = u32::MAX;

/// An environment map ready for lookups (Mitsuba's `envmap`): latitude-longitude, the map's `+y`
/// up; the direction `d` in the map's frame is at `u = atan2(d.x, -d.z) / 2 pi` (wrapped to
/// [0, 1)), `v = acos(d.y) / pi`.
#[derive(Debug)]
pub struct EnvironmentMap {
    /// The image, linear RGB.
    pub image: Bitmap,
    /// Factor on its values.
    pub scale: f64,
    /// The map's frame to the world.
    pub to_world: DMat3,
    /// The world to the map's frame.
    pub to_local: DMat3,
}

impl EnvironmentMap {
    /// Texture coordinates of the world direction `dir` (unit).
    #[inline]
    pub fn uv(&self, dir: DVec3) -> (f64, f64) {
        let d = self.to_local * dir;
        let u = d.x.atan2(-d.z) / TAU;
        (u - u.floor(), d.y.clamp(-1.0, 1.0).acos() / PI)
    }

    /// The world direction at texture coordinates `(u, v)`, and `sin theta` there.
    #[inline]
    pub fn direction(&self, u: f64, v: f64) -> (DVec3, f64) {
        let (sin_t, cos_t) = (PI * v).sin_cos();
        let (sin_p, cos_p) = (TAU * u).sin_cos();
        (self.to_world * DVec3::new(sin_t * sin_p, cos_t, -sin_t * cos_p), sin_t)
    }

    /// The radiance arriving from direction `dir`: bilinear in the image as Mitsuba's `envmap`
    /// evaluates it, texel centres at `u = (i + 0.5) / width` (wrapping around) and at
    /// `v = j / (height - 1)` (the first and last rows on the poles).
    #[inline]
    pub fn radiance(&self, dir: DVec3) -> DVec3 {
        let (u, v) = self.uv(dir);
        let (w, h) = (self.image.width(), self.image.height());
        let x = u * w as f64 - 0.5;
        let x0 = x.floor();
        let fx = x - x0;
        let x0 = (x0 as i64).rem_euclid(w as i64) as u32;
        let x1 = (x0 + 1) % w;
        let y = (v * h.saturating_sub(1) as f64).clamp(0.0, h.saturating_sub(1) as f64);
        let y0 = (y.floor() as u32).min(h.saturating_sub(2));
        let fy = if h > 1 { y - y0 as f64 } else { 0.0 };
        let y1 = (y0 + 1).min(h - 1);
        let t = |x, y| self.image.texel(x, y);
        let top = t(x0, y0) * (1.0 - fx) + t(x1, y0) * fx;
        let bottom = t(x0, y1) * (1.0 - fx) + t(x1, y1) * fx;
        (top * (1.0 - fy) + bottom * fy) * self.scale
    }
}

/// The physically based part of a prepared scene.
#[derive(Debug, Default)]
pub(super) struct Physical {
    /// Bitmaps of textured parameters, by the address of their [`TextureSpec`].
    bitmaps: HashMap<usize, Bitmap>,
    /// The environment map, if the scene has one.
    pub(super) environment: Option<Arc<EnvironmentMap>>,
    /// For each primitive, the index of its area emitter in `scene.emitters`.
    emitter_of: Vec<u32>,
}

/// The bitmaps the materials name, each once.
fn bitmap_specs(scene: &Scene) -> Vec<&Arc<TextureSpec>> {
    let mut seen = HashMap::new();
    let mut out = Vec::new();
    for e in &scene.emitters {
        let texture = match e {
            Emitter::Spot { texture: Some(t), .. } => t,
            Emitter::Projector { irradiance: Param::Texture(t), .. } => t,
            Emitter::Area { radiance: Param::Texture(t), .. } => t,
            _ => continue,
        };
        if matches!(**texture, TextureSpec::Bitmap { .. })
            && seen.insert(Arc::as_ptr(texture) as usize, ()).is_none()
        {
            out.push(texture);
        }
    }
    for p in &scene.primitives {
        if matches!(*p.material, Material::Course(_)) {
            continue;
        }
        for param in p.material.params() {
            if let Param::Texture(t) = param
                && matches!(**t, TextureSpec::Bitmap { .. })
                && seen.insert(Arc::as_ptr(t) as usize, ()).is_none()
            {
                out.push(t);
            }
        }
    }
    out
}

fn bitmap_error(location: &Location, e: TextureError) -> Diagnostic {
    Diagnostic {
        severity: Severity::Error,
        message: e.to_string(),
        location: Some(location.clone()),
        notes: Vec::new(),
    }
}

/// Reads the bitmaps and the environment map (in parallel, each charged to `budget` before it is
/// decoded) and finds the emitting primitives. Unreadable images are errors at the line that
/// names them.
pub(super) fn load_physical(
    scene: &Scene,
    budget: &MemoryBudget,
    inputs: &mut Vec<std::path::PathBuf>,
    errors: &mut Vec<Diagnostic>,
) -> (Physical, u64) {
    let mut physical =
        Physical { emitter_of: vec![NO_EMITTER; scene.primitives.len()], ..Physical::default() };
    for (i, e) in scene.emitters.iter().enumerate() {
        if let Emitter::Area { primitive, .. } = e
            && let Some(slot) = physical.emitter_of.get_mut(*primitive as usize)
        {
            *slot = i as u32;
        }
    }
    let specs = bitmap_specs(scene);
    let before = budget.used();
    let loaded: Vec<Result<(usize, Bitmap), Diagnostic>> = specs
        .par_iter()
        .filter_map(|t| match &***t {
            TextureSpec::Bitmap { file, location, raw, .. } => Some(
                Bitmap::load(file, *raw, budget)
                    .map(|b| (Arc::as_ptr(t) as usize, b))
                    .map_err(|e| bitmap_error(location, e)),
            ),
            TextureSpec::Checkerboard { .. } | TextureSpec::MeshAttribute { .. } => None,
        })
        .collect();
    for t in &specs {
        if let TextureSpec::Bitmap { file, .. } = &***t {
            inputs.push(file.clone());
        }
    }
    for result in loaded {
        match result {
            Ok((key, bitmap)) => {
                physical.bitmaps.insert(key, bitmap);
            }
            Err(d) => errors.push(d),
        }
    }
    for e in &scene.emitters {
        if let Emitter::Environment { file, location, scale, to_world } = e {
            inputs.push(file.clone());
            match Bitmap::load(file, false, budget) {
                Ok(image) => {
                    physical.environment = Some(Arc::new(EnvironmentMap {
                        image,
                        scale: *scale,
                        to_world: *to_world,
                        to_local: to_world.transpose(),
                    }))
                }
                Err(err) => errors.push(bitmap_error(location, err)),
            }
        }
    }
    let used = budget.used().saturating_sub(before);
    (physical, used)
}

impl PreparedScene {
    /// The index (in `scene.emitters`) of the area emitter of primitive `primitive`, if it
    /// emits.
    #[inline]
    pub fn emitter_of(&self, primitive: u32) -> Option<u32> {
        match self.physical.emitter_of.get(primitive as usize) {
            Some(&e) if e != NO_EMITTER => Some(e),
            _ => None,
        }
    }

    /// The scene's environment map, if it has one.
    pub fn environment_map(&self) -> Option<&Arc<EnvironmentMap>> {
        self.physical.environment.as_ref()
    }

    /// Whether the scene is physically based (a Mitsuba scene): it has physical materials or
    /// emitters, which only the path model renders.
    pub fn is_physical(&self) -> bool {
        !self.scene.emitters.is_empty() || self.has_physical_materials()
    }

    /// Mitsuba's texture coordinates at an interaction: a mesh's `(u, v)` as its file gives them
    /// (the barycentric weights without), a sphere's `(phi / 2 pi, theta / pi)` in its own frame
    /// (`to_world`'s rotation: the pole its local `+z`, `phi = 0` its local `+x`; see
    /// [`sphere_local`]).
    #[inline]
    pub fn surface_uv(&self, at: &Interaction) -> (f64, f64) {
        self.uv_on(at.primitive, at.part, at.point)
    }

    /// [`PreparedScene::surface_uv`] at `point` on part `part` of primitive `primitive`.
    fn uv_on(&self, primitive: u32, part: ShapePart, point: DVec3) -> (f64, f64) {
        let shape = &self.scene.primitives[primitive as usize].shape;
        match (shape, part) {
            (Shape::Sphere(s), _) => {
                let d = sphere_local(s, (point - s.centre) / s.radius);
                let phi = d.y.atan2(d.x) / TAU;
                (phi - phi.floor(), d.z.clamp(-1.0, 1.0).acos() / PI)
            }
            (_, part @ ShapePart::Triangle { .. }) => {
                // The course's order is `(t, s)`.
                let (t, s) = shape.texture_coordinates(point, part);
                (s, t)
            }
            (_, part) => shape.texture_coordinates(point, part),
        }
    }

    /// Mitsuba's shading frame at an interaction: the shading normal as the shape defines it
    /// (`at.outward`) and a first tangent along `dp/du` (a mesh's texture parameterisation, a
    /// sphere's azimuth), or Mitsuba's `coordinate_system` of the true normal where there is
    /// none, made perpendicular to the normal. Returns `(tangent, bitangent, normal)`.
    pub fn shading_frame(&self, at: &Interaction) -> (DVec3, DVec3, DVec3) {
        let n = at.outward;
        let shape = &self.scene.primitives[at.primitive as usize].shape;
        let dpdu = match (shape, at.part) {
            (Shape::Mesh(m), ShapePart::Triangle { index, .. }) => m.dp_ds(index),
            (Shape::Sphere(s), _) => {
                let d = sphere_local(s, at.point - s.centre);
                Some(sphere_world(s, DVec3::new(-d.y, d.x, 0.0)))
            }
            _ => None,
        };
        let outward = if at.front { at.geometric } else { -at.geometric };
        let dpdu = dpdu.unwrap_or_else(|| coordinate_system(outward).0);
        let t = (dpdu - n * n.dot(dpdu)).try_normalize().unwrap_or_else(|| coordinate_system(n).0);
        (t, n.cross(t), n)
    }

    /// `(dp/du, dp/dv)` at an interaction as Mitsuba's shapes define them: a mesh's over its
    /// texture coordinates, a sphere's over `(phi / 2 pi, theta / pi)`; `None` for other shapes
    /// or a mesh without (or with degenerate) texture coordinates.
    pub fn surface_derivatives(&self, at: &Interaction) -> Option<(DVec3, DVec3)> {
        let shape = &self.scene.primitives[at.primitive as usize].shape;
        match (shape, at.part) {
            (Shape::Mesh(m), ShapePart::Triangle { index, .. }) => m.dp_dst(index),
            (Shape::Sphere(s), _) => {
                let d = sphere_local(s, at.point - s.centre);
                let rho = d.x.hypot(d.y);
                let dpdu = DVec3::new(-d.y, d.x, 0.0) * TAU;
                let dpdv = if rho > 0.0 {
                    DVec3::new(d.z * d.x / rho, d.z * d.y / rho, -rho) * PI
                } else {
                    DVec3::new(d.z, 0.0, 0.0) * PI
                };
                Some((sphere_world(s, dpdu), sphere_world(s, dpdv)))
            }
            _ => None,
        }
    }

    /// The shading frame of a `normalmap` or `bumpmap` that is the outermost material at `at`
    /// (Mitsuba's `frame()` of those plugins), given the unperturbed `frame` (`(t, b, n)` of
    /// [`PreparedScene::shading_frame`]); `None` for any other material.
    ///
    /// `normalmap`: `n' = normalize(2 c - 1)` in `frame`. `bumpmap`: `dp/du` and `dp/dv` moved
    /// along `n` to `dp/du + n (scale dh/du - n . dp/du)` (likewise for `v`), `n'` their cross
    /// product turned to the geometric normal's side. The tangent is then Mitsuba's
    /// Gram-Schmidt of `dp/du` against `n'` with `n'` in the local frame and `dp/du` in world
    /// coordinates, as Mitsuba 3.9 computes it (only anisotropic BSDFs see the difference).
    pub fn perturbed_frame(
        &self,
        at: &Interaction,
        frame: (DVec3, DVec3, DVec3),
    ) -> Option<(DVec3, DVec3, DVec3)> {
        let Material::Perturbed { perturbation, .. } =
            &*self.scene.primitives[at.primitive as usize].material
        else {
            return None;
        };
        let (t, b, n) = frame;
        let derivatives = self.surface_derivatives(at);
        let dpdu = derivatives.map_or(t, |d| d.0);
        let local_n = match perturbation {
            Perturbation::NormalMap(p) => (self.param(p, at) * 2.0 - DVec3::ONE).try_normalize()?,
            Perturbation::BumpMap { height, scale } => {
                let (gu, gv) = self.scalar_gradient(height, at);
                let dpdv = derivatives.map_or(b, |d| d.1);
                let du = dpdu + n * (scale * gu - n.dot(dpdu));
                let dv = dpdv + n * (scale * gv - n.dot(dpdv));
                let mut world = du.cross(dv).try_normalize()?;
                let geometric = if at.front { at.geometric } else { -at.geometric };
                if geometric.dot(world) < 0.0 {
                    world = -world;
                }
                DVec3::new(world.dot(t), world.dot(b), world.dot(n))
            }
        };
        let s = (dpdu - local_n * local_n.dot(dpdu))
            .try_normalize()
            .unwrap_or_else(|| coordinate_system(local_n).0);
        let to_world = |v: DVec3| t * v.x + b * v.y + n * v.z;
        let (s, n2) = (to_world(s), to_world(local_n));
        Some((s, n2.cross(s), n2))
    }

    /// The gradient in texture coordinates of a scalar parameter (Mitsuba's `eval_1_grad`): a
    /// bilinear bitmap's luminance gradient through its `to_uv`; 0 for constants, checkerboards
    /// and nearest-texel bitmaps (as Mitsuba).
    pub fn scalar_gradient(&self, param: &Param, at: &Interaction) -> (f64, f64) {
        let Param::Texture(spec) = param else { return (0.0, 0.0) };
        let TextureSpec::Bitmap { nearest: false, wrap, to_uv, .. } = &**spec else { return (0.0, 0.0) };
        let Some(bitmap) = self.physical.bitmaps.get(&(Arc::as_ptr(spec) as usize)) else {
            return (0.0, 0.0);
        };
        let (u, v) = self.surface_uv(at);
        let p = to_uv.transform_point2(glam::DVec2::new(u, v));
        let (gx, gy) = bitmap.luminance_gradient(p.x, p.y, *wrap);
        // Through the affine map by its transposed linear part, then the resolution, in
        // Mitsuba's order (exact for a `to_uv` without rotation or shear).
        let m = to_uv.matrix2;
        let (w, h) = (bitmap.width() as f64, bitmap.height() as f64);
        (w * (m.x_axis.x * gx + m.x_axis.y * gy), h * (m.y_axis.x * gx + m.y_axis.y * gy))
    }

    /// A texture's resolution as Mitsuba's `resolution()` gives it: a loaded bitmap's width and
    /// height, `(1, 1)` for any other texture (and for a bitmap the scene did not load).
    pub fn texture_resolution(&self, spec: &Arc<TextureSpec>) -> (u32, u32) {
        match self.physical.bitmaps.get(&(Arc::as_ptr(spec) as usize)) {
            Some(b) => (b.width(), b.height()),
            None => (1, 1),
        }
    }

    /// A colour parameter at an interaction.
    #[inline]
    pub fn param(&self, param: &Param, at: &Interaction) -> DVec3 {
        self.param_on(param, at.primitive, at.part, at.point)
    }

    /// A colour parameter at `point` on part `part` of primitive `primitive` (a point drawn on
    /// an emitter rather than hit by a ray).
    #[inline]
    pub fn param_on(&self, param: &Param, primitive: u32, part: ShapePart, point: DVec3) -> DVec3 {
        match param {
            Param::Constant(c) => *c,
            Param::Texture(spec) => {
                if let TextureSpec::MeshAttribute { name, scale, .. } = &**spec {
                    return self.mesh_attribute(name, primitive, part) * *scale;
                }
                let (u, v) = self.uv_on(primitive, part, point);
                self.texture_at(spec, u, v)
            }
        }
    }

    /// The mesh attribute `name` on part `part` of primitive `primitive`: interpolated or per
    /// face as [`crate::geometry::TriangleMesh::attribute_value`]; black off a mesh that has it.
    fn mesh_attribute(&self, name: &str, primitive: u32, part: ShapePart) -> DVec3 {
        let shape = &self.scene.primitives[primitive as usize].shape;
        match (shape, part) {
            (Shape::Mesh(m), ShapePart::Triangle { index, b1, b2 }) => {
                m.attribute(name).map_or(DVec3::ZERO, |a| m.attribute_value(a, index, b1, b2))
            }
            _ => DVec3::ZERO,
        }
    }

    /// A texture's value at texture coordinates `(u, v)` (before its `to_uv`); black for a
    /// bitmap the scene did not load and for a mesh attribute (which needs a surface point).
    pub fn texture_at(&self, spec: &Arc<TextureSpec>, u: f64, v: f64) -> DVec3 {
        match &**spec {
            TextureSpec::Bitmap { nearest, wrap, to_uv, .. } => {
                let p = to_uv.transform_point2(glam::DVec2::new(u, v));
                match self.physical.bitmaps.get(&(Arc::as_ptr(spec) as usize)) {
                    Some(b) => b.lookup(p.x, p.y, *nearest, *wrap),
                    None => DVec3::ZERO,
                }
            }
            TextureSpec::Checkerboard { color0, color1, to_uv } => {
                let p = to_uv.transform_point2(glam::DVec2::new(u, v));
                let (a, b) = (p.x - p.x.floor() > 0.5, p.y - p.y.floor() > 0.5);
                if a == b { *color0 } else { *color1 }
            }
            TextureSpec::MeshAttribute { .. } => DVec3::ZERO,
        }
    }
}

/// A world vector in a sphere's own frame, Mitsuba's `to_object` rotation: `z` along its
/// [`Sphere::pole`](crate::geometry::Sphere::pole), `y` along its
/// [`Sphere::seam`](crate::geometry::Sphere::seam), `x = y x z` (the Mitsuba builder sets them to
/// `to_world`'s local `+z` and `+y`; the default frame, `+z` and `+y`, is the world's).
#[inline]
pub fn sphere_local(s: &crate::geometry::Sphere, v: DVec3) -> DVec3 {
    let (z, y) = (s.pole(), s.seam());
    DVec3::new(v.dot(y.cross(z)), v.dot(y), v.dot(z))
}

/// A vector of a sphere's own frame in the world (the inverse of [`sphere_local`]).
#[inline]
pub fn sphere_world(s: &crate::geometry::Sphere, v: DVec3) -> DVec3 {
    let (z, y) = (s.pole(), s.seam());
    y.cross(z) * v.x + y * v.y + z * v.z
}
