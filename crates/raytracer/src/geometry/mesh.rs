//! Triangle meshes (`primitive mesh`, `primitive polyhedron`, Mitsuba's mesh shapes): vertices in
//! single precision, triangles tested four at a time with the watertight test
//! ([`super::triangle_set`]).
//!
//! A mesh is one primitive of the scene (one material); a mesh file with several `usemtl`
//! materials becomes one primitive per material, sharing the vertex arrays. A prepared scene puts
//! the triangles of all its meshes in one BVH (`prepare::SceneTriangles`); a mesh asked alone
//! (tests, benchmarks) builds a BVH of its own at the first ray.
//!
//! Storage per triangle: its vertex indices (12 bytes, plus 12 for separate normal or texture
//! indices when the file has them), its corners in the leaf-ordered packets of a BVH and its
//! index there (40 bytes), and its share of the BVH nodes (about 12 bytes: 3,867 nodes for the
//! bunny's 70,580 triangles); vertices take 12 bytes for the position and 12 for the normal (8 for
//! texture coordinates).
//!
//! Precision: single-precision vertices and tests, as in Embree; the hit point is recomputed in
//! double precision from the barycentric weights (so it lies on the triangle's plane), and rays
//! leaving a mesh start [`MESH_ERROR_SCALE`] times farther off the surface than rays leaving the
//! double-precision shapes.

use std::sync::{Arc, OnceLock};

use glam::{DVec3, Vec3};

use super::mesh_file::MeshAttribute;
use super::triangle_set::{MeshRay, TriangleSet, degenerate};
use super::{Bounds, Ray, ShapeHit, ShapePart};
use crate::accel::Box32;

/// How much larger the rounding error of a single-precision mesh hit is than that of a
/// double-precision shape, relative to the magnitude of the coordinates: secondary rays leaving a
/// mesh start `SPAWN_OFFSET * MESH_ERROR_SCALE` (1e-5) times the magnitude off the surface, about
/// 80 single-precision ulps.
pub const MESH_ERROR_SCALE: f64 = 1e4;

/// No index (a triangle without normal or texture indices).
const NONE: u32 = u32::MAX;

/// The vertex data of a mesh file, in world space, shared by its parts.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MeshVertices {
    /// Positions.
    pub positions: Vec<[f32; 3]>,
    /// Unit vertex normals (from the file, or averaged over the faces around each position).
    pub normals: Vec<[f32; 3]>,
    /// Texture coordinates `(s, t)` as the file gives them (`vt`): `s` across, `t` up.
    pub uvs: Vec<[f32; 2]>,
    /// Further values per vertex (indexed as the positions) or per triangle (indexed as the
    /// triangles of a mesh of one part, every triangle kept: a Mitsuba mesh), read by the
    /// `mesh_attribute` texture.
    pub attributes: Vec<MeshAttribute>,
}

/// The corners of one triangle: indices into the positions, normals and texture coordinates.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TriangleIndices {
    /// Position indices.
    pub position: [u32; 3],
    /// Normal indices, or `u32::MAX` for none (the face normal is used).
    pub normal: [u32; 3],
    /// Texture coordinate indices, or `u32::MAX` for none (the barycentric coordinates are used).
    pub uv: [u32; 3],
}

impl TriangleIndices {
    /// A triangle with positions only.
    pub fn positions(position: [u32; 3]) -> TriangleIndices {
        TriangleIndices { position, normal: [NONE; 3], uv: [NONE; 3] }
    }
}

/// A triangle mesh ready for rays.
#[derive(Clone, Debug)]
pub struct TriangleMesh {
    vertices: Arc<MeshVertices>,
    /// Position indices of each triangle.
    positions: Vec<[u32; 3]>,
    /// Normal indices of each triangle; empty when they equal the position indices.
    normals: Vec<[u32; 3]>,
    /// Texture coordinate indices of each triangle; empty when they equal the position indices.
    uvs: Vec<[u32; 3]>,
    /// The mesh's own BVH, built when a ray first asks the mesh alone: a prepared scene puts
    /// every mesh's triangles in one set of its own instead (see [`TriangleSet`]).
    accel: OnceLock<TriangleSet>,
    bounds: Bounds,
    magnitude: f64,
}

impl PartialEq for TriangleMesh {
    /// Meshes are equal when they are the same mesh.
    fn eq(&self, other: &TriangleMesh) -> bool {
        std::ptr::eq(self, other)
    }
}

impl TriangleMesh {
    /// Builds the mesh over `triangles` of `vertices`. Triangles with an index out of range or
    /// with no area are dropped (the loader reports them). Vertex normals are computed when the
    /// data has none.
    pub fn new(vertices: Arc<MeshVertices>, triangles: &[TriangleIndices]) -> TriangleMesh {
        let pos = &vertices.positions;
        let valid = |t: &&TriangleIndices| {
            t.position.iter().all(|&i| (i as usize) < pos.len())
                && t.normal.iter().all(|&i| i == NONE || (i as usize) < vertices.normals.len())
                && t.uv.iter().all(|&i| i == NONE || (i as usize) < vertices.uvs.len())
        };
        let tris: Vec<&TriangleIndices> = triangles.iter().filter(valid).collect();
        let positions: Vec<[u32; 3]> = tris.iter().map(|t| t.position).collect();
        let normals: Vec<[u32; 3]> = if tris.iter().all(|t| t.normal == t.position) {
            Vec::new()
        } else {
            tris.iter().map(|t| t.normal).collect()
        };
        let uvs: Vec<[u32; 3]> = if tris.iter().all(|t| t.uv == t.position) {
            Vec::new()
        } else {
            tris.iter().map(|t| t.uv).collect()
        };
        // The box around the triangles a ray can hit (the degenerate ones left out).
        let bounds = positions
            .iter()
            .map(|t| t.map(|i| pos[i as usize]))
            .filter(|c| !degenerate(c))
            .fold(None, |b: Option<Box32>, c| {
                Some(b.map_or(Box32::around(&c), |b| b.union(Box32::around(&c))))
            })
            .map_or(Bounds::EMPTY, Box32::to_bounds);
        let magnitude = bounds.min.abs().max(bounds.max.abs()).max_element().max(0.0);
        TriangleMesh { vertices, positions, normals, uvs, accel: OnceLock::new(), bounds, magnitude }
    }

    /// Builds the mesh's own BVH now (otherwise the first ray that asks the mesh alone builds
    /// it): for callers that time the build apart from the rays.
    pub fn build_bvh(&self) {
        self.accel();
    }

    /// The mesh's own BVH over its triangles, built at the first call.
    fn accel(&self) -> &TriangleSet {
        self.accel.get_or_init(|| TriangleSet::build(self.positions.len(), |i| self.corners_f32(i as u32)))
    }

    /// The corners of triangle `index` in single precision, as stored.
    #[inline]
    pub fn corners_f32(&self, index: u32) -> [[f32; 3]; 3] {
        self.positions[index as usize].map(|i| self.vertices.positions[i as usize])
    }

    /// Number of triangles.
    pub fn len(&self) -> usize {
        self.positions.len()
    }

    /// Whether the mesh has no triangles.
    pub fn is_empty(&self) -> bool {
        self.positions.is_empty()
    }

    /// The shared vertex data.
    pub fn vertices(&self) -> &MeshVertices {
        &self.vertices
    }

    /// Bytes of the triangles' indices, and of the mesh's own BVH if a ray has built it (not the
    /// shared vertex data).
    pub fn memory(&self) -> usize {
        (self.positions.len() + self.normals.len() + self.uvs.len()) * 12
            + self.accel.get().map_or(0, TriangleSet::memory)
    }

    /// The nearest hit with `0 < t < t_max` (`t_max` may be infinite).
    #[inline]
    pub fn intersect(&self, ray: &Ray, t_max: f64) -> Option<ShapeHit> {
        let mray = MeshRay::new(ray);
        let (index, t, b1, b2) = self.intersect_f32(&mray, t_max as f32)?;
        Some(ShapeHit { t: t as f64, part: ShapePart::Triangle { index, b1, b2 } })
    }

    /// The nearest hit of a single-precision ray closer than `t_max`: `(triangle, t, b1, b2)`.
    #[inline]
    pub fn intersect_f32(&self, ray: &MeshRay, t_max: f32) -> Option<(u32, f32, f32, f32)> {
        self.accel().intersect(ray, t_max)
    }

    /// Whether any triangle lies on the ray closer than `t_max`.
    #[inline]
    pub fn occluded(&self, ray: &Ray, t_max: f64) -> bool {
        self.occluded_f32(&MeshRay::new(ray), t_max as f32)
    }

    /// Whether any triangle lies on a single-precision ray closer than `t_max`.
    #[inline]
    pub fn occluded_f32(&self, ray: &MeshRay, t_max: f32) -> bool {
        self.accel().occluded(ray, t_max)
    }

    /// The corners of triangle `index` in double precision.
    #[inline]
    pub fn corners(&self, index: u32) -> [DVec3; 3] {
        let t = self.positions[index as usize];
        t.map(|i| to_dvec(self.vertices.positions[i as usize]))
    }

    /// The point of triangle `index` with barycentric weights `b1`, `b2` of its second and third
    /// corners, computed in double precision (so it lies on the triangle's plane).
    #[inline]
    pub fn point_at(&self, index: u32, b1: f32, b2: f32) -> DVec3 {
        let [p0, p1, p2] = self.corners(index);
        let (b1, b2) = (b1 as f64, b2 as f64);
        p0 * (1.0 - b1 - b2) + p1 * b1 + p2 * b2
    }

    /// The unit face normal of triangle `index`, `(p1 - p0) x (p2 - p0)` normalised.
    #[inline]
    pub fn face_normal(&self, index: u32) -> DVec3 {
        let [p0, p1, p2] = self.corners(index);
        (p1 - p0).cross(p2 - p0).normalize_or(DVec3::Z)
    }

    /// The interpolated vertex normal (unit) at the barycentric point, or `None` when the mesh
    /// has no vertex normals (flat shading).
    #[inline]
    pub fn shading_normal(&self, index: u32, b1: f32, b2: f32) -> Option<DVec3> {
        let n = &self.vertices.normals;
        if n.is_empty() {
            return None;
        }
        let ids = if self.normals.is_empty() {
            self.positions[index as usize]
        } else {
            self.normals[index as usize]
        };
        if ids[0] == NONE {
            return None;
        }
        let b0 = 1.0 - b1 - b2;
        let s = Vec3::from(n[ids[0] as usize]) * b0
            + Vec3::from(n[ids[1] as usize]) * b1
            + Vec3::from(n[ids[2] as usize]) * b2;
        s.as_dvec3().try_normalize()
    }

    /// Texture coordinates `(u, v)` at the barycentric point (our convention: `u` the row from
    /// the bottom, `v` the column): the file's `vt` interpolated as `(t, s)`, or the barycentric
    /// weights `(b1, b2)` when the mesh has none.
    #[inline]
    pub fn texture_coordinates(&self, index: u32, b1: f32, b2: f32) -> (f64, f64) {
        match self.uv_corners(index) {
            Some(uv) => {
                let b0 = 1.0 - b1 - b2;
                let s = uv[0][0] * b0 + uv[1][0] * b1 + uv[2][0] * b2;
                let t = uv[0][1] * b0 + uv[1][1] * b1 + uv[2][1] * b2;
                (t as f64, s as f64)
            }
            None => (b1 as f64, b2 as f64),
        }
    }

    /// The attribute named `name` (`vertex_color`, `face_color`, ...), if the mesh has it.
    #[inline]
    pub fn attribute(&self, name: &str) -> Option<&MeshAttribute> {
        self.vertices.attributes.iter().find(|a| a.name == name)
    }

    /// The value of `attribute` (one of this mesh's) at the barycentric point of triangle
    /// `index`, as RGB (a scalar attribute repeated): a vertex attribute interpolated over the
    /// triangle's corners, a face attribute constant over it.
    #[inline]
    pub fn attribute_value(&self, attribute: &MeshAttribute, index: u32, b1: f32, b2: f32) -> DVec3 {
        if attribute.per_face {
            return Vec3::from(attribute.rgb(index)).as_dvec3();
        }
        let [i0, i1, i2] = self.positions[index as usize];
        let b0 = 1.0 - b1 - b2;
        let v = Vec3::from(attribute.rgb(i0)) * b0
            + Vec3::from(attribute.rgb(i1)) * b1
            + Vec3::from(attribute.rgb(i2)) * b2;
        v.as_dvec3()
    }

    /// The directions in which the texture coordinates `u` and `v` grow on triangle `index`
    /// (for normal maps).
    pub fn texture_tangents(&self, index: u32) -> (DVec3, DVec3) {
        let [p0, p1, p2] = self.corners(index);
        let (e1, e2) = (p1 - p0, p2 - p0);
        let Some(uv) = self.uv_corners(index) else { return (e1, e2) };
        // Our (u, v) is the file's (t, s).
        let (du1, dv1) = ((uv[1][1] - uv[0][1]) as f64, (uv[1][0] - uv[0][0]) as f64);
        let (du2, dv2) = ((uv[2][1] - uv[0][1]) as f64, (uv[2][0] - uv[0][0]) as f64);
        let det = du1 * dv2 - du2 * dv1;
        if det.abs() < 1e-20 {
            return (e1, e2);
        }
        ((e1 * dv2 - e2 * dv1) / det, (e2 * du1 - e1 * du2) / det)
    }

    /// The direction in which the file's first texture coordinate (`s`, Mitsuba's `u`) grows on
    /// triangle `index`, `dp/ds`; `None` without texture coordinates or where they are
    /// degenerate.
    pub fn dp_ds(&self, index: u32) -> Option<DVec3> {
        self.dp_dst(index).map(|(ds, _)| ds)
    }

    /// `(dp/ds, dp/dt)` on triangle `index` (Mitsuba's `dp_du`, `dp_dv`); `None` as for
    /// [`TriangleMesh::dp_ds`].
    pub fn dp_dst(&self, index: u32) -> Option<(DVec3, DVec3)> {
        let uv = self.uv_corners(index)?;
        let [p0, p1, p2] = self.corners(index);
        let (ds1, dt1) = ((uv[1][0] - uv[0][0]) as f64, (uv[1][1] - uv[0][1]) as f64);
        let (ds2, dt2) = ((uv[2][0] - uv[0][0]) as f64, (uv[2][1] - uv[0][1]) as f64);
        let det = ds1 * dt2 - ds2 * dt1;
        let (e1, e2) = (p1 - p0, p2 - p0);
        (det.abs() > 1e-20).then(|| ((e1 * dt2 - e2 * dt1) / det, (e2 * ds1 - e1 * ds2) / det))
    }

    fn uv_corners(&self, index: u32) -> Option<[[f32; 2]; 3]> {
        let uv = &self.vertices.uvs;
        if uv.is_empty() {
            return None;
        }
        let ids = if self.uvs.is_empty() { self.positions[index as usize] } else { self.uvs[index as usize] };
        if ids[0] == NONE {
            return None;
        }
        Some(ids.map(|i| uv[i as usize]))
    }

    /// The bounding box.
    pub fn bounds(&self) -> Bounds {
        self.bounds
    }

    /// The largest coordinate magnitude of the mesh (the scale of its rounding errors).
    pub fn magnitude(&self) -> f64 {
        self.magnitude
    }
}

fn to_dvec(p: [f32; 3]) -> DVec3 {
    DVec3::new(p[0] as f64, p[1] as f64, p[2] as f64)
}

/// Computes unit vertex normals for `positions` by averaging the (area-weighted) normals of the
/// faces around each position; positions no face uses get +z.
pub fn smooth_normals(positions: &[[f32; 3]], triangles: &[[u32; 3]]) -> Vec<[f32; 3]> {
    let mut sum = vec![DVec3::ZERO; positions.len()];
    for t in triangles {
        if t.iter().any(|&i| i as usize >= positions.len()) {
            continue;
        }
        let p = t.map(|i| to_dvec(positions[i as usize]));
        let n = (p[1] - p[0]).cross(p[2] - p[0]);
        for &i in t {
            sum[i as usize] += n;
        }
    }
    sum.iter().map(|n| n.normalize_or(DVec3::Z).as_vec3().to_array()).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::test_util::TestRng;

    /// An icosphere-like closed mesh: an octahedron subdivided `levels` times, pushed onto the
    /// unit sphere.
    pub(crate) fn sphere_mesh(levels: u32) -> (Vec<[f32; 3]>, Vec<[u32; 3]>) {
        let mut pos: Vec<DVec3> = vec![DVec3::X, -DVec3::X, DVec3::Y, -DVec3::Y, DVec3::Z, -DVec3::Z];
        let mut tris: Vec<[u32; 3]> =
            vec![[0, 2, 4], [2, 1, 4], [1, 3, 4], [3, 0, 4], [2, 0, 5], [1, 2, 5], [3, 1, 5], [0, 3, 5]];
        for _ in 0..levels {
            let mut mid = std::collections::HashMap::new();
            let mut next = Vec::new();
            let mut midpoint = |a: u32, b: u32, pos: &mut Vec<DVec3>| {
                *mid.entry((a.min(b), a.max(b))).or_insert_with(|| {
                    pos.push(((pos[a as usize] + pos[b as usize]) * 0.5).normalize());
                    pos.len() as u32 - 1
                })
            };
            for [a, b, c] in tris {
                let (ab, bc, ca) =
                    (midpoint(a, b, &mut pos), midpoint(b, c, &mut pos), midpoint(c, a, &mut pos));
                next.extend([[a, ab, ca], [ab, b, bc], [ca, bc, c], [ab, bc, ca]]);
            }
            tris = next;
        }
        (pos.iter().map(|p| p.as_vec3().to_array()).collect(), tris)
    }

    fn mesh(levels: u32) -> TriangleMesh {
        let (positions, tris) = sphere_mesh(levels);
        let normals = smooth_normals(&positions, &tris);
        let vertices = Arc::new(MeshVertices { positions, normals, uvs: Vec::new(), attributes: Vec::new() });
        let tris: Vec<TriangleIndices> =
            tris.iter().map(|&t| TriangleIndices { position: t, normal: t, uv: [NONE; 3] }).collect();
        TriangleMesh::new(vertices, &tris)
    }

    /// The mesh BVH finds the same nearest triangle as testing every triangle.
    #[test]
    fn agrees_with_brute_force() {
        let m = mesh(3);
        let mut rng = TestRng::new(11);
        for _ in 0..2000 {
            let origin = rng.unit_vector() * 3.0 * rng.uniform().max(0.01);
            let ray = Ray::new(origin, rng.unit_vector());
            let mray = MeshRay::new(&ray);
            let brute = (0..m.len() as u32)
                .filter_map(|i| {
                    let w = crate::geometry::triangle::WatertightRay::new(&ray);
                    w.intersect(m.corners(i), 0.0, f64::INFINITY).map(|(t, _, _)| (i, t))
                })
                .min_by(|a, b| a.1.total_cmp(&b.1));
            let found = m.intersect_f32(&mray, f32::INFINITY);
            match (brute, found) {
                (Some((_, tb)), Some((_, t, _, _))) => {
                    assert!((tb - t as f64).abs() < 1e-5, "t {tb} vs {t}")
                }
                (None, None) => {}
                (b, f) => panic!("brute {b:?} vs bvh {f:?} for {ray:?}"),
            }
            assert_eq!(m.occluded_f32(&mray, f32::INFINITY), found.is_some());
        }
    }

    /// Rays aimed at the vertices and edge midpoints of a closed mesh from outside always hit it.
    #[test]
    fn closed_mesh_is_watertight_at_edges_and_vertices() {
        let m = mesh(2);
        let mut rng = TestRng::new(12);
        let v = &m.vertices().positions;
        let mut targets: Vec<DVec3> = v.iter().map(|p| to_dvec(*p)).collect();
        for t in &m.positions {
            for c in 0..3 {
                let (a, b) = (to_dvec(v[t[c] as usize]), to_dvec(v[t[(c + 1) % 3] as usize]));
                targets.push(a + (b - a) * rng.uniform());
            }
        }
        for target in targets {
            for _ in 0..4 {
                let origin = target + (target.normalize() + rng.unit_vector() * 0.7).normalize() * 2.5;
                let ray = Ray::new(origin, target - origin);
                assert!(m.intersect(&ray, f64::INFINITY).is_some(), "{ray:?} slipped into the mesh");
                // And from inside out.
                let inside = Ray::new(target * 0.3, target - target * 0.3);
                assert!(m.intersect(&inside, f64::INFINITY).is_some(), "{inside:?} escaped the mesh");
            }
        }
    }

    #[test]
    fn smooth_normals_of_a_sphere_point_outwards() {
        let m = mesh(3);
        let mut rng = TestRng::new(13);
        for _ in 0..200 {
            let d = rng.unit_vector();
            let ray = Ray::new(d * 3.0, -d);
            let hit = m.intersect(&ray, f64::INFINITY).expect("hit");
            let ShapePart::Triangle { index, b1, b2 } = hit.part else { panic!() };
            let n = m.shading_normal(index, b1, b2).expect("normals");
            let p = m.point_at(index, b1, b2);
            assert!(n.dot(p.normalize()) > 0.99, "normal {n} at {p}");
            assert!((p - ray.at(hit.t)).length() < 1e-5);
        }
    }
}
