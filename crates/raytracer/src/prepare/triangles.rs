//! Every mesh triangle of a scene in one [`TriangleSet`]: a ray walks one tree over all the
//! triangles, whatever the number of meshes, and makes its single-precision form once.
//!
//! (A tree of meshes each with its own tree made every ray enter most of the meshes of a room
//! built of several: Mitsuba's `cbox.xml` spent a quarter of its time preparing the ray again
//! for each mesh, and more walking the small trees.) A hit is reported as the mesh's primitive
//! and the triangle's index in that mesh, as the mesh itself would report it, so everything
//! after the query is the same.

use crate::accel::wide::MAX_ITEMS;
use crate::geometry::{MeshRay, Ray, Shape, ShapeHit, ShapePart, TriangleMesh, TriangleSet};
use crate::scene::{Diagnostic, Primitive, Severity};

/// The triangles of all the meshes of a scene.
#[derive(Debug, Default)]
pub(super) struct SceneTriangles {
    set: TriangleSet,
    /// For each mesh primitive, in the scene's order: the number of its first triangle in the
    /// set and the primitive's index.
    starts: Vec<(u32, u32)>,
}

impl SceneTriangles {
    /// The set over the triangles of every mesh primitive, numbered mesh after mesh in the
    /// scene's order. An error when they are more than one tree holds.
    pub(super) fn build(prims: &[Primitive]) -> Result<SceneTriangles, Diagnostic> {
        let meshes: Vec<(u32, &TriangleMesh)> = prims
            .iter()
            .enumerate()
            .filter_map(|(i, p)| match &p.shape {
                Shape::Mesh(m) => Some((i as u32, &**m)),
                _ => None,
            })
            .collect();
        let total: usize = meshes.iter().map(|(_, m)| m.len()).sum();
        if total > MAX_ITEMS {
            return Err(Diagnostic::general(
                Severity::Error,
                format!("the scene's meshes have {total} triangles; at most {MAX_ITEMS} fit in its BVH"),
            ));
        }
        let mut starts = Vec::with_capacity(meshes.len());
        let mut next = 0u32;
        for (primitive, mesh) in &meshes {
            starts.push((next, *primitive));
            next += mesh.len() as u32;
        }
        let set = TriangleSet::build(total, |i| {
            let m = starts.partition_point(|&(first, _)| first as usize <= i) - 1;
            meshes[m].1.corners_f32((i - starts[m].0 as usize) as u32)
        });
        Ok(SceneTriangles { set, starts })
    }

    /// Whether no ray can hit any triangle.
    #[inline]
    pub(super) fn is_empty(&self) -> bool {
        self.set.is_empty()
    }

    /// Bytes of the set and the table of meshes.
    pub(super) fn memory(&self) -> usize {
        self.set.memory() + self.starts.capacity() * 8
    }

    /// The nearest triangle closer than `t_max` (compared in single precision, as a mesh
    /// compares): its primitive and the hit as its mesh reports it.
    #[inline]
    pub(super) fn closest(&self, ray: &Ray, t_max: f64) -> Option<(u32, ShapeHit)> {
        let (id, t, b1, b2) = self.set.intersect(&MeshRay::new(ray), t_max as f32)?;
        let m = self.starts.partition_point(|&(first, _)| first <= id) - 1;
        let (first, primitive) = self.starts[m];
        Some((primitive, ShapeHit { t: t as f64, part: ShapePart::Triangle { index: id - first, b1, b2 } }))
    }

    /// Whether a triangle lies on the ray closer than `t_max`.
    #[inline]
    pub(super) fn occluded(&self, ray: &Ray, t_max: f64) -> bool {
        self.set.occluded(&MeshRay::new(ray), t_max as f32)
    }
}

#[cfg(test)]
mod tests {
    use std::sync::Arc;

    use glam::DVec3;

    use super::*;
    use crate::geometry::test_util::TestRng;
    use crate::geometry::{MeshVertices, TriangleIndices};
    use crate::material::{Material, Param};

    /// A patch of `n` x `n` squares (two triangles each) of side `1 / n`, tilted and moved to
    /// `centre`, with its corners jittered by `rng`.
    fn patch(n: u32, centre: DVec3, rng: &mut TestRng) -> Primitive {
        let mut positions = Vec::new();
        for i in 0..=n {
            for j in 0..=n {
                let (x, y) = (i as f64 / n as f64 - 0.5, j as f64 / n as f64 - 0.5);
                let p = centre + DVec3::new(x, y * 0.8, y * 0.6 + 0.05 * rng.uniform());
                positions.push(p.as_vec3().to_array());
            }
        }
        let id = |i: u32, j: u32| i * (n + 1) + j;
        let mut triangles = Vec::new();
        for i in 0..n {
            for j in 0..n {
                triangles.push(TriangleIndices::positions([id(i, j), id(i + 1, j), id(i + 1, j + 1)]));
                triangles.push(TriangleIndices::positions([id(i, j), id(i + 1, j + 1), id(i, j + 1)]));
            }
        }
        let vertices = Arc::new(MeshVertices { positions, ..MeshVertices::default() });
        Primitive {
            shape: Shape::Mesh(Arc::new(TriangleMesh::new(vertices, &triangles))),
            material: Arc::new(Material::Diffuse { reflectance: Param::scalar(0.5) }),
        }
    }

    /// The one tree over several meshes (with a sphere among them, which it leaves out) finds
    /// the hit each mesh's own tree finds nearest, and names its primitive and triangle.
    #[test]
    fn one_tree_agrees_with_each_mesh_alone() {
        let mut rng = TestRng::new(29);
        let sphere = Primitive {
            shape: Shape::Sphere(crate::geometry::Sphere::new(DVec3::ZERO, 0.3).expect("a sphere")),
            material: Arc::new(Material::Diffuse { reflectance: Param::scalar(0.5) }),
        };
        let prims = vec![
            patch(7, DVec3::new(0.0, 0.0, 0.0), &mut rng),
            sphere,
            patch(3, DVec3::new(0.2, 0.1, 0.3), &mut rng),
            patch(12, DVec3::new(-0.1, 0.2, -0.4), &mut rng),
        ];
        let set = SceneTriangles::build(&prims).expect("few triangles");
        assert_eq!(set.starts, vec![(0, 0), (98, 2), (116, 3)]);
        let mut hits = 0;
        for _ in 0..3000 {
            let origin = rng.unit_vector() * 2.0;
            let target = DVec3::new(rng.uniform() - 0.5, rng.uniform() - 0.5, rng.uniform() - 0.5);
            let ray = Ray::new(origin, target - origin);
            let alone = prims
                .iter()
                .enumerate()
                .filter_map(|(i, p)| match &p.shape {
                    Shape::Mesh(m) => m.intersect(&ray, f64::INFINITY).map(|h| (i as u32, h)),
                    _ => None,
                })
                .min_by(|a, b| a.1.t.total_cmp(&b.1.t));
            let together = set.closest(&ray, f64::INFINITY);
            assert_eq!(together, alone, "{ray:?}");
            assert_eq!(set.occluded(&ray, f64::INFINITY), alone.is_some());
            if let Some((_, h)) = alone {
                hits += 1;
                assert!(set.closest(&ray, h.t * 0.999).is_none());
                assert!(!set.occluded(&ray, h.t * 0.999));
            }
        }
        assert!(hits > 1000, "only {hits} rays hit");
    }
}
