//! The photon map: stored photons in a k-d tree, with the two queries the photon models ask of
//! it: the `k` nearest photons within a radius (the course's photon mapper, spec section 10) and
//! every photon within a radius (stochastic progressive photon mapping). The map holds any
//! [`MapEntry`]: the course's [`Photon`], or SPPM's photons, which also carry their path depth.
//!
//! Layout: photons are reordered so that every subtree is a contiguous range of the photon array,
//! split at the median of the widest axis of its photons' bounding box until at most
//! [`LEAF_SIZE`] remain, so a leaf's distance tests read a few contiguous cache lines. Each
//! interior node stores only its split plane and its second child, in 8 bytes. A stored photon
//! costs 36 bytes plus about 2 bytes of tree, and the map is built in place (no second copy).
//!
//! Positions are world coordinates (z-up) in `f32`: photon maps live on the surfaces near the
//! scene's centre, where `f32` resolves a thousandth of a millimetre at metre scale.
//!
//! Queries give the same answer whatever the thread count: the tree is built deterministically
//! (ties are broken by the photons' order) and every query walks it in a fixed order.

use std::cell::RefCell;

use glam::{DVec3, Vec3};

use crate::scene::PhotonSettings;

/// Most photons in a leaf.
pub const LEAF_SIZE: usize = 8;
/// Ranges at least this long are split on two threads while building.
const PARALLEL_BUILD: usize = 1 << 16;
/// Bytes a stored photon costs in the map, tree included (upper bound, for memory checks).
pub const BYTES_PER_PHOTON: u64 = 40;

/// A photon as stored: where it landed, the unit direction it travelled in, and its power (RGB).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Photon {
    /// Hit point, world space.
    pub position: Vec3,
    /// Unit direction of travel when it arrived.
    pub direction: Vec3,
    /// Power, linear RGB.
    pub power: Vec3,
}

/// What a photon map can hold: anything with a position.
pub trait MapEntry: Copy + Send + Sync {
    /// The position, world space.
    fn position(&self) -> Vec3;
}

impl MapEntry for Photon {
    #[inline]
    fn position(&self) -> Vec3 {
        self.position
    }
}

/// An interior node: the split plane and the index of the second child (the first follows the
/// node). Leaves have no node of their own: a range of at most [`LEAF_SIZE`] photons is a leaf.
#[derive(Clone, Copy, Debug, Default)]
struct Node {
    split: f32,
    /// Split axis in the top two bits, index of the second child in the others.
    axis_and_right: u32,
}

const AXIS_SHIFT: u32 = 30;
const RIGHT_MASK: u32 = (1 << AXIS_SHIFT) - 1;

/// Photons in a k-d tree.
#[derive(Clone, Debug)]
pub struct PhotonMap<P: MapEntry = Photon> {
    photons: Vec<P>,
    nodes: Vec<Node>,
}

impl<P: MapEntry> Default for PhotonMap<P> {
    fn default() -> PhotonMap<P> {
        PhotonMap { photons: Vec::new(), nodes: Vec::new() }
    }
}

/// A photon found by a query: its index in the map and its squared distance to the query point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Found {
    /// Squared distance to the query point.
    pub dist2: f32,
    /// Index of the photon (see [`PhotonMap::photon`]).
    pub index: u32,
}

/// The result of a k-nearest query.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Nearest {
    /// Photons found (at most `k`).
    pub found: usize,
    /// The squared distance of the farthest photon kept when `k` were found, otherwise the
    /// squared search radius.
    pub radius2: f32,
}

/// The number of nodes of a subtree over `len` photons.
fn node_count(len: usize) -> usize {
    if len <= LEAF_SIZE { 0 } else { 1 + node_count(len / 2) + node_count(len - len / 2) }
}

impl<P: MapEntry> PhotonMap<P> {
    /// Builds the map over `photons` (in any order; the map's order is its own).
    pub fn build(mut photons: Vec<P>) -> PhotonMap<P> {
        assert!(photons.len() < (1 << AXIS_SHIFT), "photon map too large");
        let mut nodes = vec![Node::default(); node_count(photons.len())];
        build_subtree(&mut photons, &mut nodes, 0);
        photons.shrink_to_fit();
        PhotonMap { photons, nodes }
    }

    /// Number of photons stored.
    pub fn len(&self) -> usize {
        self.photons.len()
    }

    /// Whether the map holds no photon.
    pub fn is_empty(&self) -> bool {
        self.photons.is_empty()
    }

    /// Bytes of memory the map holds.
    pub fn memory_bytes(&self) -> usize {
        self.photons.capacity() * std::mem::size_of::<P>()
            + self.nodes.capacity() * std::mem::size_of::<Node>()
    }

    /// Photon `i` (indices as [`Found`] gives them).
    #[inline]
    pub fn photon(&self, i: u32) -> &P {
        &self.photons[i as usize]
    }

    /// The at most `k` photons nearest to `point` within `sqrt(max_dist2)` of it (distances equal
    /// to the radius count), in `out` in no particular order. `out` is cleared first.
    pub fn k_nearest(&self, point: DVec3, k: usize, max_dist2: f32, out: &mut Vec<Found>) -> Nearest {
        out.clear();
        if k == 0 || self.is_empty() {
            return Nearest { found: 0, radius2: max_dist2 };
        }
        let p = point.as_vec3();
        let mut radius2 = max_dist2;
        // Candidates within the current radius are gathered until there are twice `k`; then the
        // `k` nearest are kept and the radius shrinks to the farthest of them. This amortises the
        // selection to O(1) a candidate, against O(log k) for a heap.
        self.walk(p, &mut radius2, |map, lo, hi, radius2| {
            for i in lo..hi {
                let d2 = map.dist2(p, i);
                if d2 <= *radius2 {
                    out.push(Found { dist2: d2, index: i as u32 });
                }
            }
            if out.len() >= 2 * k {
                keep_nearest(out, k);
                *radius2 = out.iter().fold(0.0f32, |m, f| m.max(f.dist2));
            }
        });
        if out.len() > k {
            keep_nearest(out, k);
        }
        let radius2 = if out.len() == k { out.iter().fold(0.0f32, |m, f| m.max(f.dist2)) } else { max_dist2 };
        Nearest { found: out.len(), radius2 }
    }

    /// Calls `visit(index, dist2)` for every photon within `sqrt(radius2)` of `point` (distances
    /// equal to the radius count), in a fixed order.
    pub fn for_each_within(&self, point: DVec3, radius2: f32, mut visit: impl FnMut(u32, f32)) {
        if self.is_empty() {
            return;
        }
        let p = point.as_vec3();
        let mut r2 = radius2;
        self.walk(p, &mut r2, |map, lo, hi, r2| {
            for i in lo..hi {
                let d2 = map.dist2(p, i);
                if d2 <= *r2 {
                    visit(i as u32, d2);
                }
            }
        });
    }

    #[inline]
    fn dist2(&self, p: Vec3, i: usize) -> f32 {
        let q = self.photons[i].position();
        let (dx, dy, dz) = (q.x - p.x, q.y - p.y, q.z - p.z);
        dx * dx + dy * dy + dz * dz
    }

    /// Visits the leaves that may hold photons within the (possibly shrinking) radius, nearest
    /// side first: `leaf(map, lo, hi, radius2)` scans photons `lo..hi` and may shrink the radius.
    #[inline]
    fn walk(&self, p: Vec3, radius2: &mut f32, mut leaf: impl FnMut(&PhotonMap<P>, usize, usize, &mut f32)) {
        /// A pending subtree: its first node, its photon range and a lower bound of the squared
        /// distance from the query point to its cell.
        #[derive(Clone, Copy, Default)]
        struct Pending {
            node: u32,
            lo: u32,
            hi: u32,
            dist2: f32,
        }
        let mut stack = [Pending::default(); 64];
        let mut top = 0;
        let mut current = Pending { node: 0, lo: 0, hi: self.len() as u32, dist2: 0.0 };
        loop {
            if current.dist2 <= *radius2 {
                let (lo, hi) = (current.lo as usize, current.hi as usize);
                if hi - lo <= LEAF_SIZE {
                    leaf(self, lo, hi, radius2);
                } else {
                    let node = self.nodes[current.node as usize];
                    let axis = (node.axis_and_right >> AXIS_SHIFT) as usize;
                    let right = node.axis_and_right & RIGHT_MASK;
                    let mid = (lo + (hi - lo) / 2) as u32;
                    let d = p[axis] - node.split;
                    let left =
                        Pending { node: current.node + 1, lo: current.lo, hi: mid, dist2: current.dist2 };
                    let right = Pending { node: right, lo: mid, hi: current.hi, dist2: current.dist2 };
                    let (near, mut far) = if d < 0.0 { (left, right) } else { (right, left) };
                    far.dist2 = far.dist2.max(d * d);
                    // The depth is below 40 for any map that fits in memory.
                    stack[top] = far;
                    top += 1;
                    current = near;
                    continue;
                }
            }
            if top == 0 {
                break;
            }
            top -= 1;
            current = stack[top];
        }
    }
}

/// Keeps the `k` entries of `found` with the smallest distances (ties broken by position in the
/// vector, so the result is deterministic).
fn keep_nearest(found: &mut Vec<Found>, k: usize) {
    found.select_nth_unstable_by(k - 1, |a, b| a.dist2.total_cmp(&b.dist2));
    found.truncate(k);
}

/// Builds the subtree over `photons`, whose first node is `nodes[0]` and whose node indices are
/// offset by `first`.
fn build_subtree<P: MapEntry>(photons: &mut [P], nodes: &mut [Node], first: usize) {
    if photons.len() <= LEAF_SIZE {
        return;
    }
    let (min, max) = photons.iter().fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), p| {
        (lo.min(p.position()), hi.max(p.position()))
    });
    let extent = max - min;
    let axis = if extent.x >= extent.y && extent.x >= extent.z {
        0
    } else if extent.y >= extent.z {
        1
    } else {
        2
    };
    let mid = photons.len() / 2;
    photons.select_nth_unstable_by(mid, |a, b| a.position()[axis].total_cmp(&b.position()[axis]));
    let left_nodes = node_count(mid);
    let right = first + 1 + left_nodes;
    nodes[0] = Node {
        split: photons[mid].position()[axis],
        axis_and_right: (axis as u32) << AXIS_SHIFT | right as u32,
    };
    let parallel = photons.len() >= PARALLEL_BUILD;
    let (left_photons, right_photons) = photons.split_at_mut(mid);
    let (left_tree, right_tree) = nodes[1..].split_at_mut(left_nodes);
    if parallel {
        rayon::join(
            || build_subtree(left_photons, left_tree, first + 1),
            || build_subtree(right_photons, right_tree, right),
        );
    } else {
        build_subtree(left_photons, left_tree, first + 1);
        build_subtree(right_photons, right_tree, right);
    }
}

thread_local! {
    /// Each thread's buffer for the photons a query finds.
    static FOUND: RefCell<Vec<Found>> = const { RefCell::new(Vec::new()) };
}

/// Runs `f` with this thread's query buffer.
pub fn with_buffer<R>(f: impl FnOnce(&mut Vec<Found>) -> R) -> R {
    FOUND.with(|b| f(&mut b.borrow_mut()))
}

/// An estimate with this many photons or fewer is taken as no light (the course's rule).
pub const MIN_PHOTONS: usize = 8;

/// The irradiance estimate of spec section 10 over a photon map.
#[derive(Clone, Copy, Debug)]
pub struct PhotonEstimate<'m> {
    map: &'m PhotonMap,
    /// Photons gathered (`sample_photons=`).
    k: usize,
    /// Squared largest gathering radius (`sample_dist=` squared).
    max_dist2: f32,
    /// `4 / emit_photons`.
    scale: f64,
}

impl<'m> PhotonEstimate<'m> {
    /// The estimate over `map` with the scene's settings (`emit_photons` the photons asked for).
    pub fn new(map: &'m PhotonMap, settings: &PhotonSettings) -> PhotonEstimate<'m> {
        PhotonEstimate {
            map,
            k: settings.sample_photons as usize,
            max_dist2: (settings.sample_dist * settings.sample_dist) as f32,
            scale: 4.0 / settings.emit_photons.max(1) as f64,
        }
    }

    /// The irradiance at `point`, whose unit normal `normal` faces the viewer: the powers of those
    /// of the `k` nearest photons within the radius that arrived on the normal's side, times
    /// `4 / (emit_photons r^2)`; zero when [`MIN_PHOTONS`] or fewer are found.
    pub fn irradiance(&self, point: DVec3, normal: DVec3) -> DVec3 {
        with_buffer(|found| {
            let nearest = self.map.k_nearest(point, self.k, self.max_dist2, found);
            if nearest.found <= MIN_PHOTONS || nearest.radius2 <= 0.0 {
                return DVec3::ZERO;
            }
            let n = normal.as_vec3();
            let sum = found.iter().fold(Vec3::ZERO, |sum, f| {
                let photon = self.map.photon(f.index);
                if n.dot(photon.direction) < 0.0 { sum + photon.power } else { sum }
            });
            sum.as_dvec3() * (self.scale / nearest.radius2 as f64)
        })
    }
}

#[cfg(test)]
/// The photons within `sqrt(radius2)` of `point`, nearest first, by testing every one.
fn brute_force(photons: &[Photon], point: Vec3, radius2: f32) -> Vec<(f32, Vec3)> {
    let mut v: Vec<(f32, Vec3)> = photons
        .iter()
        .map(|p| ((p.position - point).length_squared(), p.position))
        .filter(|(d2, _)| *d2 <= radius2)
        .collect();
    v.sort_by(|a, b| a.0.total_cmp(&b.0));
    v
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::test_util::TestRng;

    fn random_photons(n: usize, rng: &mut TestRng) -> Vec<Photon> {
        (0..n)
            .map(|_| Photon {
                position: Vec3::new(rng.uniform() as f32, rng.uniform() as f32, (rng.uniform() * 0.1) as f32),
                direction: Vec3::NEG_Z,
                power: Vec3::ONE,
            })
            .collect()
    }

    #[test]
    fn k_nearest_agrees_with_brute_force() {
        let mut rng = TestRng::new(3);
        for n in [0, 1, 7, 8, 9, 100, 5000] {
            let photons = random_photons(n, &mut rng);
            let map = PhotonMap::build(photons.clone());
            assert_eq!(map.len(), n);
            let mut out = Vec::new();
            for _ in 0..200 {
                let q = DVec3::new(rng.uniform(), rng.uniform(), rng.uniform() * 0.1);
                for (k, r2) in [(1, 1.0), (10, 0.01), (50, 0.05), (500, 2.0)] {
                    let res = map.k_nearest(q, k, r2, &mut out);
                    let brute = brute_force(&photons, q.as_vec3(), r2);
                    let expect_found = brute.len().min(k);
                    assert_eq!(res.found, expect_found, "n={n} k={k}");
                    let mut got: Vec<f32> = out.iter().map(|f| f.dist2).collect();
                    got.sort_by(f32::total_cmp);
                    let want: Vec<f32> = brute.iter().take(k).map(|b| b.0).collect();
                    assert_eq!(got, want, "n={n} k={k}");
                    let expect_r2 = if brute.len() >= k { want[k - 1] } else { r2 };
                    assert_eq!(res.radius2, expect_r2);
                    for f in &out {
                        assert_eq!((map.photon(f.index).position - q.as_vec3()).length_squared(), f.dist2);
                    }
                }
            }
        }
    }

    #[test]
    fn radius_query_finds_exactly_the_photons_inside() {
        let mut rng = TestRng::new(9);
        let photons = random_photons(3000, &mut rng);
        let map = PhotonMap::build(photons.clone());
        for _ in 0..100 {
            let q = DVec3::new(rng.uniform(), rng.uniform(), 0.05);
            let r2 = (rng.uniform() * 0.02) as f32;
            let mut got = Vec::new();
            map.for_each_within(q, r2, |i, d2| got.push((d2, map.photon(i).position)));
            got.sort_by(|a, b| a.0.total_cmp(&b.0));
            let brute = brute_force(&photons, q.as_vec3(), r2);
            assert_eq!(got.len(), brute.len());
            for (g, b) in got.iter().zip(&brute) {
                assert_eq!(g.0, b.0);
            }
        }
    }

    #[test]
    fn many_equal_positions_still_build_and_query() {
        let p = Photon { position: Vec3::splat(0.5), direction: Vec3::Z, power: Vec3::ONE };
        let map = PhotonMap::build(vec![p; 1000]);
        let mut out = Vec::new();
        let res = map.k_nearest(DVec3::splat(0.5), 20, 1.0, &mut out);
        assert_eq!((res.found, res.radius2), (20, 0.0));
    }

    #[test]
    fn a_stored_photon_costs_at_most_the_documented_bytes() {
        let mut rng = TestRng::new(1);
        let map = PhotonMap::build(random_photons(100_000, &mut rng));
        let per_photon = map.memory_bytes() as f64 / map.len() as f64;
        assert!(per_photon <= BYTES_PER_PHOTON as f64, "{per_photon} bytes a photon");
    }
}
