//! Triangles in packets of four under an 8-wide BVH: the accelerator of one mesh, or of every
//! mesh of a scene at once (so that a ray walks one tree, whatever the number of meshes).
//!
//! The set knows only corners, in single precision and in world space, and numbers its
//! triangles `0..count` as its builder gave them: the owner maps a number back to its mesh and
//! triangle. Storage per triangle: its corners in the leaf-ordered packets (36 bytes), its number
//! there (4 bytes), and its share of the BVH nodes.

use glam::Vec3;
use wide::f32x4;

use crate::accel::Box32;
use crate::accel::wide::{BoxRay, BuildParams, WideBvh};
use crate::base::ray::Ray;

/// No triangle (an unused lane of a packet).
const NONE: u32 = u32::MAX;

/// A ray prepared for a mesh: the box-test form and the frame of the watertight test, in single
/// precision.
#[derive(Clone, Copy, Debug)]
pub struct MeshRay {
    /// The ray for box tests.
    pub boxes: BoxRay,
    /// The axis permutation of the watertight test.
    k: [usize; 3],
    /// Its shear `[d_kx / d_kz, d_ky / d_kz, 1 / d_kz]`, in every lane.
    shear: [f32x4; 3],
    /// The origin's coordinates in the permuted order, in every lane (made once per ray rather
    /// than in every packet test).
    origin: [f32x4; 3],
}

impl MeshRay {
    /// The single-precision form of `ray`.
    #[inline(always)]
    pub fn new(ray: &Ray) -> MeshRay {
        let origin = [ray.origin.x as f32, ray.origin.y as f32, ray.origin.z as f32];
        let dir = [ray.dir.x as f32, ray.dir.y as f32, ray.dir.z as f32];
        MeshRay::from_f32(origin, dir)
    }

    /// A ray from single-precision numbers (the direction need not be a unit vector: distances
    /// are then in units of its length).
    // Always inlined: called apart, its arrays went through memory as 4-byte stores read back
    // as wider loads, which stall (a tenth of `cbox.xml`'s time, measured with `perf`).
    #[inline(always)]
    pub fn from_f32(origin: [f32; 3], dir: [f32; 3]) -> MeshRay {
        let [kx, ky, kz] = super::triangle::axis_permutation(dir.map(f64::from));
        let boxes = BoxRay::from_f32(origin, dir);
        // The shear `[d_kx / d_kz, d_ky / d_kz, 1 / d_kz]` from the box test's reciprocal (the
        // dominant component `d_kz` is never replaced there: it is far from zero), without a
        // second division. Every triangle a ray meets is tested in the same sheared frame,
        // which is what keeps the test watertight.
        let inv_z = boxes.inv_dir[kz];
        MeshRay {
            boxes,
            k: [kx, ky, kz],
            shear: [dir[kx] * inv_z, dir[ky] * inv_z, inv_z].map(f32x4::from),
            origin: [origin[kx], origin[ky], origin[kz]].map(f32x4::from),
        }
    }
}

/// Four triangles' corners, in structure-of-arrays form: `v[corner][axis][lane]`; NaN in unused
/// lanes (which no test passes). 144 bytes: consecutive packets start at every 16-byte offset of
/// a cache line and each spans exactly three lines. Their triangles' indices are kept apart (in
/// [`TriangleSet`]'s `ids`), as only a hit needs them.
#[derive(Clone, Debug)]
#[repr(C, align(16))]
struct Packet {
    v: [[[f32; 4]; 3]; 3],
}

/// Triangles `0..count` under a BVH, their corners in packets of four laid out in leaf order.
#[derive(Clone, Debug, Default)]
pub struct TriangleSet {
    packets: Vec<Packet>,
    /// The triangles of each packet's lanes; [`NONE`] in unused lanes.
    ids: Vec<[u32; 4]>,
    bvh: WideBvh,
}

impl TriangleSet {
    /// Builds the set over triangles `0..count`, triangle `i` having the corners `corners(i)`
    /// (asked on any thread, twice). A triangle whose corners coincide or are collinear in single
    /// precision is left out (no ray could hit it). At most
    /// [`crate::accel::wide::MAX_ITEMS`] triangles.
    pub fn build(count: usize, corners: impl Fn(usize) -> [[f32; 3]; 3] + Sync) -> TriangleSet {
        // Each triangle's box, made on the builder's threads; a degenerate triangle's is empty,
        // which leaves it out.
        let triangle_box = |i: usize| {
            let c = corners(i);
            if degenerate(&c) { Box32::EMPTY } else { Box32::around(&c) }
        };
        let mut bvh = WideBvh::build_with(count, triangle_box, BuildParams::triangles(count));
        // Pack each leaf's triangles into packets of four, in leaf order.
        let order = bvh.order().to_vec();
        let mut packets = Vec::with_capacity(order.len() / 3 + 1);
        let mut ids = Vec::with_capacity(packets.capacity());
        let mut packet_of_leaf = Vec::new();
        for (first, count) in bvh.leaves() {
            let start = packets.len() as u32;
            for chunk in order[first as usize..(first + count) as usize].chunks(4) {
                let mut p = Packet { v: [[[f32::NAN; 4]; 3]; 3] };
                let mut lanes = [NONE; 4];
                for (lane, &tri) in chunk.iter().enumerate() {
                    for (corner, point) in p.v.iter_mut().zip(corners(tri as usize)) {
                        for (axis, value) in corner.iter_mut().zip(point) {
                            axis[lane] = value;
                        }
                    }
                    lanes[lane] = tri;
                }
                packets.push(p);
                ids.push(lanes);
            }
            packet_of_leaf.push((first, start, packets.len() as u32 - start));
        }
        bvh.remap_leaves(|first, _| {
            let i = packet_of_leaf.partition_point(|&(f, _, _)| f < first);
            let (_, start, count) = packet_of_leaf[i];
            (start, count)
        });
        TriangleSet { packets, ids, bvh }
    }

    /// Whether the set holds no triangle a ray could hit.
    #[inline]
    pub fn is_empty(&self) -> bool {
        self.bvh.is_empty()
    }

    /// The box around the triangles, if there are any.
    pub fn bounds(&self) -> Option<Box32> {
        self.bvh.bounds()
    }

    /// Bytes of the packets, their triangle numbers and the BVH.
    pub fn memory(&self) -> usize {
        self.packets.len() * (std::mem::size_of::<Packet>() + std::mem::size_of::<[u32; 4]>())
            + self.bvh.memory()
    }

    /// The nearest hit of a single-precision ray closer than `t_max`: `(triangle, t, b1, b2)`.
    #[inline]
    pub fn intersect(&self, ray: &MeshRay, t_max: f32) -> Option<(u32, f32, f32, f32)> {
        // The packet and lane of the nearest hit; its triangle is looked up once, at the end.
        let mut best = None;
        self.bvh.traverse(&ray.boxes, t_max, |first, count, limit| {
            let mut limit = limit;
            for i in first as usize..(first + count) as usize {
                if let Some((lane, t, b1, b2)) = packet_hit(&self.packets[i], ray, limit) {
                    limit = t;
                    best = Some((i, lane, t, b1, b2));
                }
            }
            limit
        });
        best.map(|(i, lane, t, b1, b2)| (self.ids[i][lane], t, b1, b2))
    }

    /// Whether any triangle lies on a single-precision ray closer than `t_max`.
    #[inline]
    pub fn occluded(&self, ray: &MeshRay, t_max: f32) -> bool {
        let mut found = false;
        self.bvh.traverse(&ray.boxes, t_max, |first, count, limit| {
            for p in &self.packets[first as usize..(first + count) as usize] {
                if packet_hit(p, ray, limit).is_some() {
                    found = true;
                    return -1.0;
                }
            }
            limit
        });
        found
    }
}

/// Whether a triangle's corners are collinear or coincide (in single precision).
pub fn degenerate(corners: &[[f32; 3]; 3]) -> bool {
    let p = corners.map(Vec3::from);
    let n = (p[1] - p[0]).cross(p[2] - p[0]);
    n == Vec3::ZERO || !n.is_finite()
}

/// The nearest hit in a packet closer than `t_max`: `(lane, t, b1, b2)`.
///
/// The four lanes are first tested together with 4-wide arithmetic (the same operations in the
/// same order as the per-lane test, so the same numbers): a lane stays a candidate if its edge
/// functions agree in sign and its distance lies in `(0, t_max]`, or if one of them is exactly 0
/// (an edge in single precision, decided again in double precision). Most packets a ray reaches
/// have no candidate; the few that do are decided lane by lane.
#[inline(always)]
fn packet_hit(p: &Packet, r: &MeshRay, t_max: f32) -> Option<(usize, f32, f32, f32)> {
    let [kx, ky, kz] = r.k;
    let [sx, sy, sz] = r.shear;
    let [ox, oy, oz] = r.origin;
    // Corners relative to the origin, sheared: x' = x - sx z, y' = y - sy z.
    let corner = |c: usize| {
        let cz = f32x4::from(p.v[c][kz]) - oz;
        ((f32x4::from(p.v[c][kx]) - ox) - sx * cz, (f32x4::from(p.v[c][ky]) - oy) - sy * cz, sz * cz)
    };
    let (x0, y0, z0) = corner(0);
    let (x1, y1, z1) = corner(1);
    let (x2, y2, z2) = corner(2);
    let u = x2 * y1 - y2 * x1;
    let v = x0 * y2 - y0 * x2;
    let w = x1 * y0 - y1 * x0;
    let zero = f32x4::ZERO;
    let on_edge = u.simd_eq(zero) | v.simd_eq(zero) | w.simd_eq(zero);
    let mixed = u.fast_min(v).fast_min(w).simd_lt(zero) & u.fast_max(v).fast_max(w).simd_gt(zero);
    let det = u + v + w;
    let t_scaled = u * z0 + v * z1 + w * z2;
    // 0 < t_scaled / det <= t_max, with det's sign taken off both (negation is exact); NaN (the
    // padding of unused lanes) fails it.
    let sign = det & f32x4::from(-0.0);
    let (t_abs, det_abs) = (t_scaled ^ sign, det ^ sign);
    let in_range = t_abs.simd_gt(zero) & t_abs.simd_le(f32x4::from(t_max) * det_abs);
    let mut candidates = (on_edge | (in_range & !mixed)).to_bitmask();
    if candidates == 0 {
        return None;
    }
    let (x, y, z) = (
        [x0, x1, x2].map(f32x4::to_array),
        [y0, y1, y2].map(f32x4::to_array),
        [z0, z1, z2].map(f32x4::to_array),
    );
    let (u, v, w) = (u.to_array(), v.to_array(), w.to_array());
    let mut best: Option<(usize, f32, f32, f32)> = None;
    let mut limit = t_max;
    while candidates != 0 {
        let l = candidates.trailing_zeros() as usize;
        candidates &= candidates - 1;
        let (mut ul, mut vl, mut wl) = (u[l], v[l], w[l]);
        if ul == 0.0 || vl == 0.0 || wl == 0.0 {
            // On an edge in single precision: decide in double precision, where the products of
            // single-precision numbers are exact (Woop et al.'s fallback).
            let (x0, y0, x1, y1, x2, y2) = (
                x[0][l] as f64,
                y[0][l] as f64,
                x[1][l] as f64,
                y[1][l] as f64,
                x[2][l] as f64,
                y[2][l] as f64,
            );
            ul = (x2 * y1 - y2 * x1) as f32;
            vl = (x0 * y2 - y0 * x2) as f32;
            wl = (x1 * y0 - y1 * x0) as f32;
        }
        if (ul < 0.0 || vl < 0.0 || wl < 0.0) && (ul > 0.0 || vl > 0.0 || wl > 0.0) {
            continue;
        }
        let det = ul + vl + wl;
        if det == 0.0 {
            continue;
        }
        let t_scaled = ul * z[0][l] + vl * z[1][l] + wl * z[2][l];
        let outside = if det < 0.0 {
            t_scaled >= 0.0 || t_scaled < limit * det
        } else {
            t_scaled <= 0.0 || t_scaled > limit * det
        };
        if outside {
            continue;
        }
        let inv = 1.0 / det;
        let t = t_scaled * inv;
        if t < limit {
            limit = t;
            best = Some((l, t, vl * inv, wl * inv));
        }
    }
    best
}
