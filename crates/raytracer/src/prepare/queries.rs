//! The ray queries every integrator uses: the nearest hit, and whether a shadow ray is blocked,
//! through the BVH and the loops of primitives too few or unbounded to go in it.

use super::{Hit, PreparedScene};
use crate::accel::BoxRay;
use crate::geometry::{Cylinder, Plane, Ray, Shape, ShapeHit, Sphere, Square};
use crate::material::{CourseMaterial, Material};
use crate::scene::Scene;

impl PreparedScene {
    /// The nearest primitive or light shape along the ray.
    #[inline]
    pub fn closest_hit(&self, ray: &Ray) -> Hit {
        let (mut best, mut t_max) = match self.closest_surface(ray) {
            Some((primitive, hit)) => (Hit::Surface { primitive, hit }, hit.t),
            None => (Hit::Miss, f64::INFINITY),
        };
        match &self.emitter_squares {
            Some(squares) => {
                for (light, square) in squares {
                    if let Some(hit) = square.intersect(ray, 0.0, t_max) {
                        best = Hit::Emitter { light: *light, t: hit.t };
                        t_max = hit.t;
                    }
                }
            }
            None => {
                for (light, shape) in &self.emitters {
                    if let Some(hit) = shape.intersect(ray, 0.0, t_max) {
                        best = Hit::Emitter { light: *light, t: hit.t };
                        t_max = hit.t;
                    }
                }
            }
        }
        best
    }

    /// The nearest primitive along the ray, ignoring the lights' shapes (which photons and shadow
    /// rays pass through).
    #[inline]
    pub fn closest_surface(&self, ray: &Ray) -> Option<(u32, ShapeHit)> {
        let mut best = self.linear.closest(ray, f64::INFINITY);
        let mut t_max = best.map_or(f64::INFINITY, |(_, h)| h.t);
        if !self.triangles.is_empty()
            && let Some(hit) = self.triangles.closest(ray, t_max)
        {
            t_max = hit.1.t;
            best = Some(hit);
        }
        if self.bvh.is_empty() {
            return best;
        }
        let prims = &self.scene.primitives;
        let items = self.bvh.order();
        self.bvh.traverse(&BoxRay::new(ray), box_limit(t_max), |first, count, _| {
            for &i in &items[first as usize..(first + count) as usize] {
                if let Some(hit) = prims[i as usize].shape.intersect(ray, 0.0, t_max) {
                    best = Some((i, hit));
                    t_max = hit.t;
                }
            }
            box_limit(t_max)
        });
        best
    }

    /// Whether any primitive lies on the ray before distance `t_max` (lights never block).
    #[inline]
    pub fn occluded(&self, ray: &Ray, t_max: f64) -> bool {
        if self.linear.any(ray, t_max) || (!self.triangles.is_empty() && self.triangles.occluded(ray, t_max))
        {
            return true;
        }
        if self.bvh.is_empty() {
            return false;
        }
        let prims = &self.scene.primitives;
        let items = self.bvh.order();
        let mut found = false;
        self.bvh.traverse(&BoxRay::new(ray), box_limit(t_max), |first, count, limit| {
            for &i in &items[first as usize..(first + count) as usize] {
                if prims[i as usize].shape.occludes(ray, t_max) {
                    found = true;
                    return -1.0;
                }
            }
            limit
        });
        found
    }

    /// The rounding-error magnitude of primitive `i` (see [`crate::geometry::offset_origin`]).
    #[inline]
    pub fn magnitude(&self, primitive: u32) -> f64 {
        self.magnitudes[primitive as usize]
    }

    /// The material of primitive `i`.
    #[inline]
    pub fn material(&self, primitive: u32) -> &Material {
        &self.scene.primitives[primitive as usize].material
    }

    /// The course material of primitive `i`, for the models that read only the course's
    /// materials (classic, photon, SPPM): a physically based material reads as the inert
    /// default there, and the render refuses such scenes in those models before it starts
    /// ([`PreparedScene::has_physical_materials`]).
    #[inline]
    pub fn course_material(&self, primitive: u32) -> &CourseMaterial {
        static INERT: std::sync::OnceLock<CourseMaterial> = std::sync::OnceLock::new();
        self.material(primitive).as_course().unwrap_or_else(|| INERT.get_or_init(CourseMaterial::default))
    }

    /// Whether any primitive has a physically based material (which only the path model reads).
    pub fn has_physical_materials(&self) -> bool {
        self.scene.primitives.iter().any(|p| p.material.as_course().is_none())
    }
}

/// The single-precision limit of a box test for the double-precision distance `t` (rounded up).
#[inline]
fn box_limit(t: f64) -> f32 {
    let f = t as f32;
    if (f as f64) < t { f.next_up() } else { f }
}

/// Primitives tested in plain loops, one loop per kind of shape, so that every test is inlined
/// without a dispatch per shape.
#[derive(Debug, Default)]
pub(super) struct FlatSet {
    spheres: Vec<(u32, Sphere)>,
    planes: Vec<(u32, Plane)>,
    squares: Vec<(u32, Square)>,
    cylinders: Vec<(u32, Cylinder)>,
    /// Triangles, meshes and Bezier surfaces.
    others: Vec<(u32, Shape)>,
}

/// Tests every shape of a list, keeping the nearest hit.
#[inline]
fn nearest<S>(
    list: &[(u32, S)],
    ray: &Ray,
    t_max: &mut f64,
    best: &mut Option<(u32, ShapeHit)>,
    intersect: impl Fn(&S, &Ray, f64) -> Option<ShapeHit>,
) {
    for (i, shape) in list {
        if let Some(hit) = intersect(shape, ray, *t_max) {
            *best = Some((*i, hit));
            *t_max = hit.t;
        }
    }
}

impl FlatSet {
    pub(super) fn new(indices: &[u32], scene: &Scene) -> FlatSet {
        let mut set = FlatSet::default();
        for &i in indices {
            match &scene.primitives[i as usize].shape {
                Shape::Sphere(s) => set.spheres.push((i, s.clone())),
                Shape::Plane(p) => set.planes.push((i, p.clone())),
                Shape::Square(q) => set.squares.push((i, (**q).clone())),
                Shape::Cylinder(c) => set.cylinders.push((i, (**c).clone())),
                other => set.others.push((i, other.clone())),
            }
        }
        set
    }

    /// The nearest hit closer than `t_max`.
    #[inline]
    fn closest(&self, ray: &Ray, mut t_max: f64) -> Option<(u32, ShapeHit)> {
        let mut best = None;
        nearest(&self.spheres, ray, &mut t_max, &mut best, |s, r, t| s.intersect(r, 0.0, t));
        nearest(&self.planes, ray, &mut t_max, &mut best, |s, r, t| s.intersect(r, 0.0, t));
        nearest(&self.squares, ray, &mut t_max, &mut best, |s, r, t| s.intersect(r, 0.0, t));
        nearest(&self.cylinders, ray, &mut t_max, &mut best, |s, r, t| s.intersect(r, 0.0, t));
        nearest(&self.others, ray, &mut t_max, &mut best, |s, r, t| s.intersect(r, 0.0, t));
        best
    }

    /// Whether anything lies on the ray before `t_max`.
    #[inline]
    fn any(&self, ray: &Ray, t_max: f64) -> bool {
        self.spheres.iter().any(|(_, s)| s.intersect(ray, 0.0, t_max).is_some())
            || self.planes.iter().any(|(_, s)| s.intersect(ray, 0.0, t_max).is_some())
            || self.squares.iter().any(|(_, s)| s.intersect(ray, 0.0, t_max).is_some())
            || self.cylinders.iter().any(|(_, s)| s.intersect(ray, 0.0, t_max).is_some())
            || self.others.iter().any(|(_, s)| s.occludes(ray, t_max))
    }
}
