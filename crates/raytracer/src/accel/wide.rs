//! An 8-wide bounding-volume hierarchy with single-precision boxes: the acceleration structure of
//! the scene (over its primitives) and of every triangle mesh (over its triangles).
//!
//! Layout: a node holds the boxes of its up to eight children in structure-of-arrays form (the
//! eight lower x bounds, the eight upper x bounds, ...), so one ray tests all eight boxes with the
//! same few vector instructions (through the `wide` crate: two 4-lane SSE operations each on
//! baseline x86-64, one with AVX), and the children's references. A child is another node or a
//! leaf, a run of consecutive items (at most [`MAX_LEAF`]). A node takes 224 bytes, four cache
//! lines. Eight children rather than four make the tree shallower: an incoherent ray on the bunny
//! visited 5.4 nodes on average instead of 7.8 (with leaves of up to eight triangles), and
//! waiting for memory at each is what limits such rays.
//!
//! Build: top-down, binned surface-area heuristic over all three axes; each node splits its items
//! into up to eight groups by splitting the group with the largest box again until there are
//! eight (the usual way of collapsing a binary SAH tree into a wide one, done while building); a
//! group that fits in a leaf becomes one. Large subtrees are built and large groups binned in
//! parallel; the result does not depend on the thread count.
//!
//! Traversal: nearest child first, with a small explicit stack; boxes are rounded outwards when
//! built and the far distance of a slab test is widened by a few ulps, so no ray slips past a box
//! it touches (which keeps the watertight triangle test watertight). Items are anything with a
//! bounding box: the caller tests the items of a leaf and says how far the ray may still go.

use glam::DVec3;
use smallvec::{SmallVec, smallvec};
use wide::f32x8 as Lanes;

use crate::base::bounds::Bounds;
use crate::base::ray::Ray;

/// Most items in a leaf.
pub const MAX_LEAF: usize = 16;
/// Width of a node.
pub const WIDTH: usize = 8;
/// Cost of visiting a node (eight box tests) in the SAH, in the units of `BuildParams::item_cost`.
const NODE_COST: f32 = 1.0;
/// Number of SAH bins per axis.
const BINS: usize = 16;
/// Subtrees of at least this many items are built on another thread.
const PARALLEL_ITEMS: usize = 16 * 1024;
/// Most items a tree may hold (leaf references keep 27 bits for the first item).
pub const MAX_ITEMS: usize = (1 << 27) - 1;
/// Entries of the traversal stack kept in a fixed array (enough for the paths of trees 9 levels
/// deep, 134 million leaves, even when every level leaves seven children behind); longer paths
/// spill to the heap.
const STACK: usize = 64;

/// Leaf flag of a child reference: bits 0..27 the first item, bits 27..31 the item count minus 1.
const LEAF: u32 = 1 << 31;
/// An unused child slot.
const EMPTY: u32 = u32::MAX;

/// A node: the boxes of up to eight children and what they are.
#[derive(Clone, Debug)]
#[repr(C, align(32))]
pub struct Node {
    /// `bounds[0][axis]`: the lower bounds on that axis (x, y, z), one lane per child;
    /// `bounds[1][axis]`: the upper bounds. Unused lanes hold an empty box.
    bounds: [[[f32; WIDTH]; 3]; 2],
    /// Per child: a node index, a leaf (`LEAF | (count - 1) << 27 | first`), or [`EMPTY`].
    child: [u32; WIDTH],
}

/// A box in single precision, rounded outwards from a double-precision box. Each corner takes
/// four lanes (the fourth always 0), so that growing a box is one vector minimum and one maximum
/// (the builder grows boxes tens of millions of times; with three lanes it was 7% slower).
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C, align(16))]
pub struct Box32 {
    /// Lower corner (and a fourth lane, 0).
    pub lo: [f32; 4],
    /// Upper corner (and a fourth lane, 0).
    pub hi: [f32; 4],
}

impl Box32 {
    /// The empty box.
    pub const EMPTY: Box32 = Box32 {
        lo: [f32::INFINITY, f32::INFINITY, f32::INFINITY, 0.0],
        hi: [f32::NEG_INFINITY, f32::NEG_INFINITY, f32::NEG_INFINITY, 0.0],
    };

    /// The smallest single-precision box holding `b` (rounded outwards; infinite coordinates
    /// stay infinite).
    pub fn from_bounds(b: &Bounds) -> Box32 {
        let (down, up) = (f32_at_or_below, f32_at_or_above);
        Box32 {
            lo: [down(b.min.x), down(b.min.y), down(b.min.z), 0.0],
            hi: [up(b.max.x), up(b.max.y), up(b.max.z), 0.0],
        }
    }

    /// The box around single-precision points.
    pub fn around(points: &[[f32; 3]]) -> Box32 {
        points.iter().fold(Box32::EMPTY, |b, p| b.include(*p))
    }

    /// This box grown to hold `p` (NaN coordinates of `p` are ignored).
    #[inline]
    pub fn include(self, p: [f32; 3]) -> Box32 {
        Box32 {
            lo: [lower(self.lo[0], p[0]), lower(self.lo[1], p[1]), lower(self.lo[2], p[2]), self.lo[3]],
            hi: [upper(self.hi[0], p[0]), upper(self.hi[1], p[1]), upper(self.hi[2], p[2]), self.hi[3]],
        }
    }

    /// The smallest box holding both (NaN coordinates of `o` are ignored).
    #[inline]
    pub fn union(self, o: Box32) -> Box32 {
        Box32 {
            lo: [
                lower(self.lo[0], o.lo[0]),
                lower(self.lo[1], o.lo[1]),
                lower(self.lo[2], o.lo[2]),
                lower(self.lo[3], o.lo[3]),
            ],
            hi: [
                upper(self.hi[0], o.hi[0]),
                upper(self.hi[1], o.hi[1]),
                upper(self.hi[2], o.hi[2]),
                upper(self.hi[3], o.hi[3]),
            ],
        }
    }

    /// Half the surface area (the SAH only needs relative areas); 0 for an empty box.
    #[inline]
    fn half_area(&self) -> f32 {
        // Negative or NaN extents (an empty box, an infinite one) count as 0.
        let extent = |axis: usize| {
            let d = self.hi[axis] - self.lo[axis];
            if d > 0.0 { d } else { 0.0 }
        };
        let d = [extent(0), extent(1), extent(2)];
        let a = d[0] * d[1] + d[1] * d[2] + d[2] * d[0];
        if a.is_finite() { a } else { f32::MAX }
    }

    /// Twice the centre (the SAH bins centroids; the factor 2 does not matter).
    #[inline]
    fn centre2(&self) -> [f32; 3] {
        let c = |i: usize| {
            let s = self.lo[i] + self.hi[i];
            if s.is_finite() { s } else { 0.0 }
        };
        [c(0), c(1), c(2)]
    }

    /// The box in double precision.
    pub fn to_bounds(self) -> Bounds {
        Bounds {
            min: DVec3::new(self.lo[0] as f64, self.lo[1] as f64, self.lo[2] as f64),
            max: DVec3::new(self.hi[0] as f64, self.hi[1] as f64, self.hi[2] as f64),
        }
    }
}

/// The largest `f32` at or below `v` (NaN stays NaN): `v as f32`, or the `f32` below it
/// ([`f32::next_down`]) when rounding went up. Without branches: the signs of a box's
/// coordinates and the direction of rounding are as good as random, and mispredicted branches
/// made this the costliest step of preparing a million spheres' boxes.
#[inline]
fn f32_at_or_below(v: f64) -> f32 {
    let f = v as f32;
    let bits = f.to_bits();
    // `f` is neither NaN nor -inf when it is above `v`.
    let below = if f > 0.0 {
        bits.wrapping_sub(1)
    } else if bits & !SIGN_BIT == 0 {
        SIGN_BIT | 1
    } else {
        bits.wrapping_add(1)
    };
    f32::from_bits(if f as f64 > v { below } else { bits })
}

/// The smallest `f32` at or above `v` (NaN stays NaN; see [`f32_at_or_below`]).
#[inline]
fn f32_at_or_above(v: f64) -> f32 {
    let f = v as f32;
    let bits = f.to_bits();
    // `f` is neither NaN nor +inf when it is below `v`.
    let above = if f < 0.0 {
        bits.wrapping_sub(1)
    } else if bits & !SIGN_BIT == 0 {
        1
    } else {
        bits.wrapping_add(1)
    };
    f32::from_bits(if (f as f64) < v { above } else { bits })
}

/// The sign bit of an `f32`.
const SIGN_BIT: u32 = 1 << 31;

/// `a.min(b)`, for `a` that is not NaN: `b` when it is smaller, else `a` (so a NaN `b` is
/// ignored). One instruction, where `f32::min` takes several to handle a NaN `a` too; boxes are
/// grown this way millions of times while a tree is built.
#[inline(always)]
fn lower(a: f32, b: f32) -> f32 {
    if b < a { b } else { a }
}

/// `a.max(b)`, for `a` that is not NaN (see [`lower`]).
#[inline(always)]
fn upper(a: f32, b: f32) -> f32 {
    if b > a { b } else { a }
}

/// A ray prepared for box tests in single precision.
#[derive(Clone, Copy, Debug)]
pub struct BoxRay {
    /// Origin.
    pub origin: [f32; 3],
    /// Component-wise inverse of the direction (zero components replaced by a tiny value of the
    /// same sign, so no test produces NaN).
    pub inv_dir: [f32; 3],
    /// `inv_dir` widened by a few ulps (see [`FAR_SCALE`]), for the far distance of slab tests.
    pub inv_dir_far: [f32; 3],
    /// Whether each direction component is negative: the ray then enters a box by its upper
    /// face on that axis. The faces are picked by indexing with it rather than by a branch,
    /// which incoherent rays would mispredict.
    pub negative: [bool; 3],
}

impl BoxRay {
    /// The box-test form of a double-precision ray.
    #[inline]
    pub fn new(ray: &Ray) -> BoxRay {
        BoxRay::from_f32(
            [ray.origin.x as f32, ray.origin.y as f32, ray.origin.z as f32],
            [ray.dir.x as f32, ray.dir.y as f32, ray.dir.z as f32],
        )
    }

    /// The box-test form of a single-precision ray.
    #[inline]
    pub fn from_f32(origin: [f32; 3], dir: [f32; 3]) -> BoxRay {
        let away_from_zero = |d: f32| if d.abs() < 1e-30 { 1e-30f32.copysign(d) } else { d };
        // One 4-lane division instead of three (the same quotients).
        let inv = wide::f32x4::ONE / wide::f32x4::from([dir[0], dir[1], dir[2], 1.0].map(away_from_zero));
        let [x, y, z, _] = inv.to_array();
        let inv_dir = [x, y, z];
        BoxRay {
            origin,
            inv_dir,
            inv_dir_far: inv_dir.map(|i| i * FAR_SCALE),
            negative: [inv_dir[0] < 0.0, inv_dir[1] < 0.0, inv_dir[2] < 0.0],
        }
    }
}

/// Widening of the far distance of a slab test: a few ulps, so a box that the ray touches in exact
/// arithmetic is never missed through rounding (pbrt's `1 + 2 gamma(3)`).
const FAR_SCALE: f32 = 1.0 + 4.0 * f32::EPSILON;

/// A [`BoxRay`] with its numbers repeated in every lane, made once per traversal rather than at
/// every node.
struct RayLanes {
    origin: [Lanes; 3],
    inv_dir: [Lanes; 3],
    inv_dir_far: [Lanes; 3],
    negative: [bool; 3],
}

impl RayLanes {
    #[inline(always)]
    fn new(ray: &BoxRay) -> RayLanes {
        RayLanes {
            origin: ray.origin.map(Lanes::from),
            inv_dir: ray.inv_dir.map(Lanes::from),
            inv_dir_far: ray.inv_dir_far.map(Lanes::from),
            negative: ray.negative,
        }
    }
}

/// The entry distance of the ray into each of the node's eight boxes, and a mask of the boxes the
/// ray meets within `[0, t_max]` (bit `i` for child `i`).
#[inline(always)]
fn node_distances(node: &Node, ray: &RayLanes, t_max: f32) -> (Lanes, u32) {
    let mut near = Lanes::ZERO;
    let mut far = Lanes::from(t_max);
    for axis in 0..3 {
        let negative = ray.negative[axis];
        let (n, f) = (node.bounds[negative as usize][axis], node.bounds[!negative as usize][axis]);
        let tn = (Lanes::from(n) - ray.origin[axis]) * ray.inv_dir[axis];
        let tf = (Lanes::from(f) - ray.origin[axis]) * ray.inv_dir_far[axis];
        // `tn > near ? tn : near` and `tf < far ? tf : far`: a NaN keeps the running bound.
        near = tn.fast_max(near);
        far = tf.fast_min(far);
    }
    (near, near.simd_le(far).to_bitmask())
}

/// An 8-wide BVH over items `0..n`; leaves hold runs of [`WideBvh::order`].
#[derive(Clone, Debug, Default)]
pub struct WideBvh {
    nodes: Vec<Node>,
    /// The items in leaf order: leaf `(first, count)` holds `order[first..first + count]`.
    order: Vec<u32>,
    /// The root: a node, a leaf, or [`EMPTY`].
    root: u32,
    /// The box around everything.
    bounds: Option<Box32>,
}

/// One item for the builder.
#[derive(Clone, Copy)]
struct BuildItem {
    bounds: Box32,
    centre: [f32; 3],
    index: u32,
}

/// A finished subtree: its box and the reference to it.
#[derive(Clone, Copy)]
struct Built {
    bounds: Box32,
    reference: u32,
}

/// The most triangles a set may hold to be built in leaves of one packet
/// ([`BuildParams::SMALL_TRIANGLES`]): 4,096 triangles' packets take 144 KiB, within a core's
/// second-level cache.
pub const SMALL_TRIANGLE_SET: usize = 4096;

/// Settings of a build.
#[derive(Clone, Copy, Debug)]
pub struct BuildParams {
    /// Items a leaf may hold at most (1..=[`MAX_LEAF`]).
    pub max_leaf: usize,
    /// Cost of testing one item, relative to testing one node's eight boxes.
    pub item_cost: f32,
    /// Leaves are sized in multiples of this (a mesh tests triangles four at a time, so a leaf of
    /// one to four costs the same).
    pub leaf_granularity: usize,
}

impl BuildParams {
    /// Scene primitives: items of unequal and larger cost (spheres, cylinders, meshes).
    pub const SHAPES: BuildParams = BuildParams { max_leaf: 4, item_cost: 1.0, leaf_granularity: 1 };
    /// Triangles of a mesh, tested four at a time, in leaves of up to twelve (three packets):
    /// larger leaves leave fewer nodes on a ray's way, and each node is a wait for memory where
    /// the caches do not hold the mesh (with leaves of up to eight, the bunny's incoherent rays
    /// were about 4% slower on such a machine, its primary rays as fast).
    pub const TRIANGLES: BuildParams = BuildParams { max_leaf: 12, item_cost: 0.5, leaf_granularity: 4 };
    /// Triangles of a set small enough to stay in the caches (at most [`SMALL_TRIANGLE_SET`]),
    /// in leaves of one packet: no wait for memory to save, so fewer triangle tests win (in
    /// Mitsuba's `cbox.xml`, 62 triangles, a ray tested 5.7 packets with leaves of up to twelve
    /// and 2.2 with leaves of four).
    pub const SMALL_TRIANGLES: BuildParams = BuildParams { max_leaf: 4, item_cost: 0.5, leaf_granularity: 4 };

    /// The settings for a set of `count` triangles.
    pub fn triangles(count: usize) -> BuildParams {
        if count <= SMALL_TRIANGLE_SET { BuildParams::SMALL_TRIANGLES } else { BuildParams::TRIANGLES }
    }
}

impl WideBvh {
    /// Builds the tree over items `0..boxes.len()` with the given boxes. Items with an empty or
    /// non-finite box are left out. At most [`MAX_ITEMS`] items.
    pub fn build(boxes: &[Box32], params: BuildParams) -> WideBvh {
        WideBvh::build_with(boxes.len(), |i| boxes[i], params)
    }

    /// [`WideBvh::build`] over items `0..count`, item `i`'s box being `box_of(i)` (asked once
    /// for each, on any thread): the caller need not gather the boxes in a list first.
    pub fn build_with(count: usize, box_of: impl Fn(usize) -> Box32 + Sync, params: BuildParams) -> WideBvh {
        assert!(count <= MAX_ITEMS, "too many items for one BVH");
        use rayon::prelude::*;
        let usable = |it: &BuildItem| {
            let b = &it.bounds;
            (0..3).all(|a| b.lo[a] <= b.hi[a]) && !b.lo.iter().chain(&b.hi).any(|v| v.is_nan())
        };
        let item = |i: usize| {
            let b = box_of(i);
            BuildItem { bounds: b, centre: b.centre2(), index: i as u32 }
        };
        let mut items: Vec<BuildItem> = if count >= PARALLEL_ITEMS {
            // Every item, then the unusable ones left out if there are any: a collect of known
            // length writes its parts in place on all threads, where a filtered one would join
            // them on one (a million items' tree was built 9% faster so).
            let mut items: Vec<BuildItem> = (0..count).into_par_iter().map(item).collect();
            if !items.par_iter().all(usable) {
                items.retain(usable);
            }
            items
        } else {
            (0..count).map(item).filter(usable).collect()
        };
        let mut bvh = WideBvh { nodes: Vec::new(), order: Vec::new(), root: EMPTY, bounds: None };
        if items.is_empty() {
            return bvh;
        }
        let params = BuildParams { max_leaf: params.max_leaf.clamp(1, MAX_LEAF), ..params };
        let mut nodes = Vec::with_capacity(items.len() / 3 + 1);
        let group = group_of(&items);
        let root = build_subtree(&mut items, 0, group, &mut nodes, params);
        bvh.order = items.par_iter().map(|it| it.index).collect();
        bvh.nodes = nodes;
        bvh.root = root.reference;
        bvh.bounds = Some(root.bounds);
        bvh
    }

    /// The items in leaf order (leaf references index into it).
    pub fn order(&self) -> &[u32] {
        &self.order
    }

    /// The box around all items, if there are any.
    pub fn bounds(&self) -> Option<Box32> {
        self.bounds
    }

    /// Bytes taken by the nodes and the item order.
    pub fn memory(&self) -> usize {
        self.nodes.len() * std::mem::size_of::<Node>() + self.order.len() * 4
    }

    /// Whether the tree holds no item (a traversal visits nothing).
    #[inline]
    pub fn is_empty(&self) -> bool {
        self.root == EMPTY
    }

    /// Number of nodes.
    pub fn node_count(&self) -> usize {
        self.nodes.len()
    }

    /// Every leaf as `(first, count)` into [`WideBvh::order`], in order.
    pub fn leaves(&self) -> Vec<(u32, u32)> {
        let mut out = Vec::new();
        let mut stack = vec![self.root];
        while let Some(r) = stack.pop() {
            if r == EMPTY {
                continue;
            }
            if r & LEAF != 0 {
                out.push(leaf_range(r));
            } else {
                stack.extend(self.nodes[r as usize].child.iter().rev());
            }
        }
        out.sort_unstable();
        out
    }

    /// Rewrites every leaf `(first, count)` as `remap(first, count)` (at most [`MAX_LEAF`]
    /// entries), for owners that store their items in other units (a mesh's packets of four
    /// triangles). The item order is dropped: the owner keeps its own.
    pub fn remap_leaves(&mut self, mut remap: impl FnMut(u32, u32) -> (u32, u32)) {
        let fix = |r: &mut u32, remap: &mut dyn FnMut(u32, u32) -> (u32, u32)| {
            if *r != EMPTY && *r & LEAF != 0 {
                let (first, count) = leaf_range(*r);
                let (first, count) = remap(first, count);
                *r = leaf_reference(first, count);
            }
        };
        fix(&mut self.root, &mut remap);
        for node in &mut self.nodes {
            for c in &mut node.child {
                fix(c, &mut remap);
            }
        }
        self.order = Vec::new();
    }

    /// Visits the leaves the ray's segment `[0, t_max]` enters, nearest box first.
    /// `leaf(first, count, t_max)` tests the leaf's items and returns how far the ray may still
    /// go (its argument, or the distance of a nearer hit); returning a negative number stops the
    /// traversal (used by occlusion queries).
    #[inline]
    pub fn traverse(&self, ray: &BoxRay, mut t_max: f32, mut leaf: impl FnMut(u32, u32, f32) -> f32) {
        if self.root == EMPTY {
            return;
        }
        let lanes = RayLanes::new(ray);
        let mut stack = Stack::new();
        let mut current = self.root;
        loop {
            if current & LEAF != 0 {
                let (first, count) = leaf_range(current);
                t_max = leaf(first, count, t_max);
                if t_max < 0.0 {
                    return;
                }
            } else {
                let node = &self.nodes[current as usize];
                let (near, mut mask) = node_distances(node, &lanes, t_max);
                let dist = near.to_array();
                // The common cases first: one child hit, or two.
                if mask != 0 {
                    let a = mask.trailing_zeros() as usize;
                    mask &= mask - 1;
                    if mask == 0 {
                        current = node.child[a];
                        continue;
                    }
                    let b = mask.trailing_zeros() as usize;
                    mask &= mask - 1;
                    if mask == 0 {
                        let (near, far) = if dist[a] <= dist[b] { (a, b) } else { (b, a) };
                        stack.push((node.child[far], dist[far]));
                        current = node.child[near];
                        continue;
                    }
                    // Three or more: sort them, push all but the nearest (farthest first).
                    let mut hits = [(0u32, f32::INFINITY); WIDTH];
                    let mut n = 0;
                    mask |= 1 << a | 1 << b;
                    while mask != 0 {
                        let lane = mask.trailing_zeros() as usize;
                        mask &= mask - 1;
                        let entry = (node.child[lane], dist[lane]);
                        let mut j = n;
                        while j > 0 && hits[j - 1].1 < entry.1 {
                            hits[j] = hits[j - 1];
                            j -= 1;
                        }
                        hits[j] = entry;
                        n += 1;
                    }
                    for &h in &hits[..n - 1] {
                        stack.push(h);
                    }
                    current = hits[n - 1].0;
                    continue;
                }
            }
            // Pop the next subtree that is still within reach.
            loop {
                match stack.pop() {
                    None => return,
                    Some((r, d)) if d <= t_max => {
                        current = r;
                        break;
                    }
                    Some(_) => {}
                }
            }
        }
    }
}

/// The traversal stack: subtrees still to visit and the distance at which the ray enters them. Up
/// to [`STACK`] entries live inline (not initialised until pushed: a traversal is often shorter
/// than clearing a whole array would take); a deeper tree spills to the heap.
type Stack = SmallVec<[(u32, f32); STACK]>;

#[inline]
fn leaf_range(r: u32) -> (u32, u32) {
    (r & ((1 << 27) - 1), ((r >> 27) & 15) + 1)
}

#[inline]
fn leaf_reference(first: u32, count: u32) -> u32 {
    debug_assert!((1..=MAX_LEAF as u32).contains(&count) && first < (1 << 27));
    LEAF | (count - 1) << 27 | first
}

/// The boxes of a group of items: around the items, and around their centres (doubled, as
/// [`Box32::centre2`] keeps them).
#[derive(Clone, Copy)]
struct Group {
    bounds: Box32,
    centroids: Box32,
}

impl Group {
    const EMPTY: Group = Group { bounds: Box32::EMPTY, centroids: Box32::EMPTY };

    fn union(self, o: Group) -> Group {
        Group { bounds: self.bounds.union(o.bounds), centroids: self.centroids.union(o.centroids) }
    }
}

/// Builds the subtree over `items` (whose first item is item `offset` of the whole order, and
/// whose boxes are `group`) and appends its nodes to `nodes`; returns its box and reference.
fn build_subtree(
    items: &mut [BuildItem],
    offset: usize,
    group: Group,
    nodes: &mut Vec<Node>,
    params: BuildParams,
) -> Built {
    let bounds = group.bounds;
    if items.len() <= params.max_leaf {
        return Built { bounds, reference: leaf_reference(offset as u32, items.len() as u32) };
    }
    // Split into up to eight groups: split the group with the largest box until there are eight
    // (groups small enough for a leaf that the SAH keeps whole are not split).
    let mut groups: SmallVec<[(usize, usize, Group); WIDTH]> = smallvec![(0, items.len(), group)];
    while groups.len() < WIDTH {
        let candidate = groups
            .iter()
            .enumerate()
            .filter(|(_, (s, e, _))| e - s > params.max_leaf)
            .max_by(|a, b| a.1.2.bounds.half_area().total_cmp(&b.1.2.bounds.half_area()))
            .map(|(i, _)| i);
        let Some(g) = candidate else { break };
        let (s, e, whole) = groups[g];
        let (count, left, right) = split(&mut items[s..e], &whole, params);
        let mid = s + count;
        groups[g] = (s, mid, left);
        groups.insert(g + 1, (mid, e, right));
    }
    let node_index = nodes.len();
    nodes.push(Node {
        bounds: [[[f32::INFINITY; WIDTH]; 3], [[f32::NEG_INFINITY; WIDTH]; 3]],
        child: [EMPTY; WIDTH],
    });
    // Build the children; big ones in parallel (each into its own node list, appended after).
    let mut children: SmallVec<[Built; WIDTH]> = SmallVec::new();
    let big = items.len() >= PARALLEL_ITEMS;
    let mut slices: SmallVec<[(usize, Group, &mut [BuildItem]); WIDTH]> = SmallVec::new();
    let mut rest: &mut [BuildItem] = items;
    let mut consumed = 0;
    for &(s, e, b) in &groups {
        let (head, tail) = std::mem::take(&mut rest).split_at_mut(e - consumed);
        debug_assert_eq!(s, consumed);
        slices.push((offset + s, b, head));
        rest = tail;
        consumed = e;
    }
    if big {
        use rayon::prelude::*;
        let parts: Vec<(Built, Vec<Node>)> = slices
            .into_vec()
            .into_par_iter()
            .map(|(off, b, slice)| {
                let mut local = Vec::new();
                let built = build_subtree(slice, off, b, &mut local, params);
                (built, local)
            })
            .collect();
        // The parts' nodes follow, in order, their node references shifted by where each part
        // starts; copied on all threads (a known number of nodes is written in place).
        let shift = |r: u32, base: u32| if r != EMPTY && r & LEAF == 0 { r + base } else { r };
        let mut bases = Vec::with_capacity(parts.len());
        let mut base = nodes.len();
        for (built, local) in &parts {
            bases.push(base);
            children.push(Built { bounds: built.bounds, reference: shift(built.reference, base as u32) });
            base += local.len();
        }
        let first = nodes.len();
        nodes.par_extend((first..base).into_par_iter().map(|k| {
            let part = bases.partition_point(|&b| b <= k) - 1;
            let mut n = parts[part].1[k - bases[part]].clone();
            for c in &mut n.child {
                *c = shift(*c, bases[part] as u32);
            }
            n
        }));
    } else {
        for (off, b, slice) in slices {
            children.push(build_subtree(slice, off, b, nodes, params));
        }
    }
    let node = &mut nodes[node_index];
    for (lane, c) in children.iter().enumerate() {
        for axis in 0..3 {
            node.bounds[0][axis][lane] = c.bounds.lo[axis];
            node.bounds[1][axis][lane] = c.bounds.hi[axis];
        }
        node.child[lane] = c.reference;
    }
    Built { bounds, reference: node_index as u32 }
}

/// The SAH cost of a leaf of `n` items, relative to the box's area.
#[inline]
fn leaf_cost(n: usize, params: BuildParams) -> f32 {
    // Without a division when every size counts (a split's sweep asks 90 times).
    let g = params.leaf_granularity;
    let size = if g <= 1 {
        n
    } else if g.is_power_of_two() {
        (n + g - 1) & !(g - 1)
    } else {
        n.div_ceil(g) * g
    };
    size as f32 * params.item_cost
}

/// The best binned SAH split found: its cost relative to the box's area, the axis, the last bin
/// of the left part, and the boxes of both parts.
#[derive(Clone, Copy)]
struct Split {
    cost: f32,
    axis: usize,
    bin: usize,
    centroid_lo: f32,
    scale: f32,
    left: Box32,
    right: Box32,
}

impl Split {
    #[inline]
    fn goes_left(&self, it: &BuildItem) -> bool {
        bin_of(it.centre[self.axis], self.centroid_lo, self.scale) <= self.bin
    }
}

/// The bin of a centre coordinate `c` on an axis whose centroids start at `lo`, with `scale` bins
/// a unit: `(c - lo) * scale` rounded down, clamped to the bins (NaN to the first).
#[inline(always)]
fn bin_of(c: f32, lo: f32, scale: f32) -> usize {
    // Through `i32`: a saturating conversion to `i32` takes fewer instructions than to `usize`.
    (((c - lo) * scale) as i32).clamp(0, BINS as i32 - 1) as usize
}

/// Item boxes and counts per bin, on each axis.
#[derive(Clone, Copy)]
struct Bins {
    boxes: [[Box32; BINS]; 3],
    counts: [[u32; BINS]; 3],
}

impl Bins {
    /// Bins `items` on all three axes in one pass, the centroid box being `lo + [0, BINS) / scale`.
    fn of(items: &[BuildItem], lo: [f32; 3], scale: [f32; 3]) -> Bins {
        if items.len() >= PARALLEL_ITEMS {
            use rayon::prelude::*;
            return items
                .par_chunks(PARALLEL_ITEMS / 4)
                .map(|c| Bins::of(c, lo, scale))
                .reduce_with(Bins::merge)
                .unwrap_or_else(Bins::empty);
        }
        let mut bins = Bins::empty();
        for it in items {
            for axis in 0..3 {
                let b = bin_of(it.centre[axis], lo[axis], scale[axis]);
                bins.boxes[axis][b] = bins.boxes[axis][b].union(it.bounds);
                bins.counts[axis][b] += 1;
            }
        }
        bins
    }

    fn empty() -> Bins {
        Bins { boxes: [[Box32::EMPTY; BINS]; 3], counts: [[0; BINS]; 3] }
    }

    fn merge(mut self, o: Bins) -> Bins {
        for axis in 0..3 {
            for b in 0..BINS {
                self.boxes[axis][b] = self.boxes[axis][b].union(o.boxes[axis][b]);
                self.counts[axis][b] += o.counts[axis][b];
            }
        }
        self
    }
}

/// The boxes around the items and around their centres (doubled, as [`Box32::centre2`] keeps
/// them).
fn group_of(items: &[BuildItem]) -> Group {
    if items.len() >= PARALLEL_ITEMS {
        use rayon::prelude::*;
        return items
            .par_chunks(PARALLEL_ITEMS / 4)
            .map(group_of)
            .reduce_with(Group::union)
            .unwrap_or(Group::EMPTY);
    }
    items.iter().fold(Group::EMPTY, |g, it| Group {
        bounds: g.bounds.union(it.bounds),
        centroids: g.centroids.include(it.centre),
    })
}

/// The best binned SAH split of `items` over all three axes, if the items' centres are not all
/// in one place.
fn sah_split(items: &[BuildItem], group: &Group, params: BuildParams) -> Option<Split> {
    let cb = group.centroids;
    let area = group.bounds.half_area().max(f32::MIN_POSITIVE);
    let scale: [f32; 3] = std::array::from_fn(|axis| {
        let extent = cb.hi[axis] - cb.lo[axis];
        if extent > 0.0 { BINS as f32 / extent } else { 0.0 }
    });
    if scale.iter().all(|&s| s == 0.0 || !s.is_finite()) {
        return None;
    }
    let bins = Bins::of(items, [cb.lo[0], cb.lo[1], cb.lo[2]], scale);
    let mut best: Option<Split> = None;
    for (axis, &axis_scale) in scale.iter().enumerate() {
        if axis_scale == 0.0 || !axis_scale.is_finite() {
            continue;
        }
        let (boxes, counts) = (&bins.boxes[axis], &bins.counts[axis]);
        // Only the bins holding items matter: a split after an empty bin divides the items as
        // the split after the bin before it, at the same cost, which cannot win. Small groups,
        // most of a big build's splits, leave most bins empty.
        let mut full = [0u8; BINS];
        let mut k = 0;
        for (b, &count) in counts.iter().enumerate() {
            full[k] = b as u8;
            k += (count > 0) as usize;
        }
        // Sweep from the right, then from the left: `right_box[j]` and `right_n[j]` hold the
        // full bins from the `j`-th on.
        let mut right_box = [Box32::EMPTY; BINS];
        let mut right_n = [0usize; BINS];
        let (mut acc, mut n) = (Box32::EMPTY, 0);
        for j in (1..k).rev() {
            let b = full[j] as usize;
            acc = acc.union(boxes[b]);
            n += counts[b] as usize;
            right_box[j] = acc;
            right_n[j] = n;
        }
        let (mut acc, mut n) = (Box32::EMPTY, 0);
        for j in 0..k.saturating_sub(1) {
            let b = full[j] as usize;
            acc = acc.union(boxes[b]);
            n += counts[b] as usize;
            let nr = right_n[j + 1];
            let cost = NODE_COST
                + (leaf_cost(n, params) * acc.half_area()
                    + leaf_cost(nr, params) * right_box[j + 1].half_area())
                    / area;
            if best.is_none_or(|s| cost < s.cost) {
                best = Some(Split {
                    cost,
                    axis,
                    bin: b,
                    centroid_lo: cb.lo[axis],
                    scale: axis_scale,
                    left: acc,
                    right: right_box[j + 1],
                });
            }
        }
    }
    best
}

/// Splits `items` (with boxes `group`) in two, reordering them; returns the size of the first
/// part, in `1..len`, and the boxes of both parts.
fn split(items: &mut [BuildItem], group: &Group, params: BuildParams) -> (usize, Group, Group) {
    let n = items.len();
    if let Some(best) = sah_split(items, group, params) {
        // The parts' centroid boxes are gathered on the way (the next splits need them).
        let (mut first, mut left_centroids, mut right_centroids) = (0, Box32::EMPTY, Box32::EMPTY);
        for i in 0..n {
            if best.goes_left(&items[i]) {
                left_centroids = left_centroids.include(items[i].centre);
                items.swap(first, i);
                first += 1;
            } else {
                right_centroids = right_centroids.include(items[i].centre);
            }
        }
        if first > 0 && first < n {
            return (
                first,
                Group { bounds: best.left, centroids: left_centroids },
                Group { bounds: best.right, centroids: right_centroids },
            );
        }
    }
    // All centroids coincide (or binning could not separate them): split in the middle of the
    // longest axis's order.
    let cb = group.centroids;
    let axis = (0..3).max_by(|&a, &b| (cb.hi[a] - cb.lo[a]).total_cmp(&(cb.hi[b] - cb.lo[b]))).unwrap_or(0);
    let mid = n / 2;
    items.select_nth_unstable_by(mid, |a, b| a.centre[axis].total_cmp(&b.centre[axis]));
    (mid, group_of(&items[..mid]), group_of(&items[mid..]))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn boxes_round_outwards_as_next_down_and_next_up_do() {
        let reference_down = |v: f64| {
            let f = v as f32;
            if f as f64 > v { f.next_down() } else { f }
        };
        let reference_up = |v: f64| {
            let f = v as f32;
            if (f as f64) < v { f.next_up() } else { f }
        };
        let mut values = vec![
            0.0,
            -0.0,
            f64::MIN_POSITIVE,
            -f64::MIN_POSITIVE,
            1e-300,
            -1e-300,
            1e-45,
            -1e-45,
            f32::MAX as f64,
            f32::MAX as f64 * (1.0 + 1e-12),
            -(f32::MAX as f64) * (1.0 + 1e-12),
            f64::MAX,
            f64::MIN,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NAN,
            1.0 / 3.0,
            -1.0 / 3.0,
            0.1,
        ];
        // Doubles of every sign and magnitude, from a fixed sequence.
        let mut x = 0x9E37_79B9_7F4A_7C15u64;
        for _ in 0..100_000 {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            let magnitude = f64::powi(2.0, (x % 300) as i32 - 150);
            values.push(
                f64::from_bits(x >> 12 | 0x3FF0_0000_0000_0000)
                    * magnitude
                    * if x & 1 == 0 { 1.0 } else { -1.0 },
            );
        }
        for v in values {
            let (lo, hi) = (f32_at_or_below(v), f32_at_or_above(v));
            assert_eq!(lo.to_bits(), reference_down(v).to_bits(), "{v:e}");
            assert_eq!(hi.to_bits(), reference_up(v).to_bits(), "{v:e}");
            assert!(v.is_nan() || (lo as f64 <= v && v <= hi as f64), "{v:e}");
        }
    }

    #[test]
    fn items_without_a_usable_box_are_left_out_of_a_large_tree() {
        let n = PARALLEL_ITEMS + 100;
        let boxes: Vec<Box32> = (0..n)
            .map(|i| match i % 7 {
                0 => Box32::EMPTY,
                1 if i % 3 == 0 => Box32 { lo: [f32::NAN, 0.0, 0.0, 0.0], hi: [1.0, 1.0, 1.0, 0.0] },
                _ => {
                    let c = [(i % 37) as f32, (i % 41) as f32, (i % 43) as f32];
                    Box32::around(&[c, [c[0] + 0.5, c[1] + 0.5, c[2] + 0.5]])
                }
            })
            .collect();
        let bvh = WideBvh::build(&boxes, BuildParams::SHAPES);
        let mut order = bvh.order().to_vec();
        order.sort_unstable();
        let expected: Vec<u32> =
            (0..n as u32).filter(|&i| i % 7 != 0 && !(i % 7 == 1 && i % 3 == 0)).collect();
        assert_eq!(order, expected);
    }
}
