//! The interaction record (pbrt's `interaction.h`): what integrators know of a surface a ray
//! hit, whatever its shape: the point, the normals, the side, and its colour there.

use glam::DVec3;

use super::{NO_TEXTURE, PreparedScene};
use crate::geometry::{Ray, Shape, ShapeHit, ShapePart, offset_origin};
use crate::texture::Texture;

/// A ray's hit on a primitive, as integrators see it (world space, z-up).
///
/// Two normals: `normal` is the one to **shade** with (lighting, reflection, refraction,
/// scattering): the smooth vertex normal of a mesh or the normal-mapped one where there is a
/// normal map, else the true normal. `geometric` is the true normal of the surface: secondary
/// rays are **offset** along it ([`Interaction::spawn`] and [`Interaction::shadow_origin`] do
/// this), and it tells which side of the surface a direction points to. Both face the side the ray
/// came from; on spheres, planes and the other analytic shapes they are equal.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Interaction {
    /// Index into `scene.primitives`.
    pub primitive: u32,
    /// Distance along the ray (its direction is a unit vector).
    pub t: f64,
    /// The hit point.
    pub point: DVec3,
    /// Unit shading normal pointing out of the shape (for a plane or square, the side of the
    /// normal of the file).
    pub outward: DVec3,
    /// Unit shading normal on the side the ray came from: `outward` for a front hit, `-outward`
    /// for a back hit. Shade with this one.
    pub normal: DVec3,
    /// Unit geometric (true) normal on the side the ray came from. Rays are offset along it.
    pub geometric: DVec3,
    /// Whether the ray hit the outside (the side the outward normal points to).
    pub front: bool,
    /// The rounding-error magnitude that scales the offset of rays leaving the point (larger for
    /// single-precision meshes).
    pub magnitude: f64,
    /// The part of the shape that was hit (for its texture coordinates).
    pub(super) part: ShapePart,
}

impl Interaction {
    /// A ray leaving the point in direction `dir` (normalised here), started just off the surface
    /// on the side `dir` goes to, so it cannot hit the surface it leaves.
    #[inline]
    pub fn spawn(&self, dir: DVec3) -> Ray {
        let side = if dir.dot(self.geometric) >= 0.0 { self.geometric } else { -self.geometric };
        Ray::new(offset_origin(self.point, side, self.magnitude), dir)
    }

    /// The origin of a shadow ray towards the side the ray came from.
    #[inline]
    pub fn shadow_origin(&self) -> DVec3 {
        offset_origin(self.point, self.geometric, self.magnitude)
    }
}

impl PreparedScene {
    /// The shading frame of a hit of `ray` on `primitive`: the point, the normals and the side
    /// the ray came from. This is everything an integrator needs to know about a surface, whatever
    /// its shape.
    #[inline]
    pub fn interaction(&self, ray: &Ray, primitive: u32, hit: ShapeHit) -> Interaction {
        let shape = &self.scene.primitives[primitive as usize].shape;
        let point = shape.hit_point(ray, &hit);
        let geometric_outward = shape.outward_normal(point, hit.part);
        let front = ray.dir.dot(geometric_outward) < 0.0;
        let geometric = if front { geometric_outward } else { -geometric_outward };
        let mut outward = shape.shading_normal(hit.part).unwrap_or(geometric_outward);
        let bump = self.texture_of[primitive as usize][1];
        if bump != NO_TEXTURE {
            outward = self.bumped(shape, point, hit.part, outward, &self.textures[bump as usize]);
        }
        let mut normal = if front { outward } else { -outward };
        if normal.dot(geometric) <= 0.0 {
            // A shading normal turned away from the side the ray came from (an interpolated normal
            // at a silhouette, a strong normal map): shade with the true normal instead.
            normal = geometric;
            outward = geometric_outward;
        }
        let magnitude = self.magnitude(primitive).max(point.abs().max_element());
        Interaction {
            primitive,
            t: hit.t,
            point,
            outward,
            normal,
            geometric,
            front,
            magnitude,
            part: hit.part,
        }
    }

    /// The outward shading normal `n` tilted by the tangent-space normal map `map` at `point`.
    fn bumped(&self, shape: &Shape, point: DVec3, part: ShapePart, n: DVec3, map: &Texture) -> DVec3 {
        let (u, v) = shape.texture_coordinates(point, part);
        let m = map.sample(u, v) * 2.0 - DVec3::ONE;
        let (du, dv) = shape.texture_tangents(point, part);
        // Red runs along the texture's columns (v), green along its rows (u), blue along n.
        let Some(tx) = (dv - n * n.dot(dv)).try_normalize() else { return n };
        let ty = n.cross(tx);
        let ty = if ty.dot(du) < 0.0 { -ty } else { ty };
        (tx * m.x + ty * m.y + n * m.z).try_normalize().unwrap_or(n)
    }

    /// The surface colour at an interaction: the primitive's `color=` times its texture there.
    #[inline]
    pub fn surface_color(&self, at: &Interaction) -> DVec3 {
        let p = &self.scene.primitives[at.primitive as usize];
        let color = p.material.as_course().map_or(DVec3::ZERO, |m| m.color);
        match self.texture_of[at.primitive as usize][0] {
            NO_TEXTURE => color,
            t => {
                let (u, v) = p.shape.texture_coordinates(at.point, at.part);
                color * self.textures[t as usize].sample(u, v)
            }
        }
    }
}
