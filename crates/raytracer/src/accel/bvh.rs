//! A bounding-volume hierarchy built with the binned surface-area heuristic and flattened into an
//! array in depth-first order (pbrt's `LinearBVHNode` layout: the first child follows its parent,
//! the parent stores the index of the second).

use crate::geometry::{Bounds, Ray};

/// Most items in a leaf.
const MAX_LEAF_ITEMS: usize = 4;
/// Number of SAH bins per split.
const BINS: usize = 12;
/// Cost of visiting a node relative to testing one item.
const TRAVERSAL_COST: f64 = 0.5;

#[derive(Clone, Debug)]
struct Node {
    bounds: Bounds,
    /// Leaf: index of the first item in `items`. Interior: index of the second child.
    offset: u32,
    /// Number of items in a leaf; 0 for an interior node.
    count: u16,
    /// Split axis of an interior node (0, 1, 2).
    axis: u8,
}

/// A BVH over items identified by `u32` indices.
#[derive(Clone, Debug, Default)]
pub struct Bvh {
    nodes: Vec<Node>,
    items: Vec<u32>,
}

struct BuildItem {
    index: u32,
    bounds: Bounds,
    centroid: glam::DVec3,
}

impl Bvh {
    /// Builds the hierarchy over `(index, bounds)` pairs.
    pub fn build(items: &[(u32, Bounds)]) -> Bvh {
        let mut build: Vec<BuildItem> = items
            .iter()
            .map(|&(index, bounds)| BuildItem { index, bounds, centroid: bounds.centroid() })
            .collect();
        let mut bvh =
            Bvh { nodes: Vec::with_capacity(2 * items.len()), items: Vec::with_capacity(items.len()) };
        if !build.is_empty() {
            bvh.build_node(&mut build);
        }
        bvh
    }

    /// Appends the subtree of `items` and returns its node index.
    fn build_node(&mut self, items: &mut [BuildItem]) -> usize {
        let bounds = items.iter().fold(Bounds::EMPTY, |b, it| b.union(it.bounds));
        let node_index = self.nodes.len();
        self.nodes.push(Node { bounds, offset: 0, count: 0, axis: 0 });
        let split = if items.len() <= 1 { None } else { choose_split(items, &bounds) };
        match split {
            None => {
                self.nodes[node_index].offset = self.items.len() as u32;
                self.nodes[node_index].count = items.len() as u16;
                self.items.extend(items.iter().map(|it| it.index));
            }
            Some((axis, mid)) => {
                self.build_node(&mut items[..mid]);
                let second = self.build_node(&mut items[mid..]);
                self.nodes[node_index].offset = second as u32;
                self.nodes[node_index].axis = axis as u8;
            }
        }
        node_index
    }

    /// Visits the items whose boxes the ray's segment `t_min < t < t_max` enters, nearest subtree
    /// first. `test(item, t_max)` returns the hit distance of an item closer than `t_max`, which
    /// then shortens the segment.
    #[inline]
    pub fn closest(
        &self,
        ray: &Ray,
        t_min: f64,
        mut t_max: f64,
        mut test: impl FnMut(u32, f64) -> Option<f64>,
    ) {
        if self.nodes.is_empty() {
            return;
        }
        let inv_dir = ray.dir.recip();
        let negative = [inv_dir.x < 0.0, inv_dir.y < 0.0, inv_dir.z < 0.0];
        let mut stack = [0u32; 64];
        let mut top = 0usize;
        let mut current = 0usize;
        loop {
            let node = &self.nodes[current];
            if node.bounds.hit(ray, inv_dir, t_min, t_max) {
                if node.count > 0 {
                    let first = node.offset as usize;
                    for &item in &self.items[first..first + node.count as usize] {
                        if let Some(t) = test(item, t_max) {
                            t_max = t;
                        }
                    }
                } else {
                    // Visit the child on the ray's near side first.
                    let (near, far) = if negative[node.axis as usize] {
                        (node.offset as usize, current + 1)
                    } else {
                        (current + 1, node.offset as usize)
                    };
                    if top < stack.len() {
                        stack[top] = far as u32;
                        top += 1;
                        current = near;
                        continue;
                    }
                    // Deeper than the stack: fall back to testing every item of this subtree
                    // (unreachable for trees built from fewer than 2^60 items; kept for safety).
                    t_max = self.test_subtree(current, t_max, &mut test);
                }
            }
            if top == 0 {
                break;
            }
            top -= 1;
            current = stack[top] as usize;
        }
    }

    /// Tests every item under `node`; returns the shortened `t_max`.
    fn test_subtree(
        &self,
        node: usize,
        mut t_max: f64,
        test: &mut impl FnMut(u32, f64) -> Option<f64>,
    ) -> f64 {
        let n = &self.nodes[node];
        if n.count > 0 {
            for &item in &self.items[n.offset as usize..n.offset as usize + n.count as usize] {
                if let Some(t) = test(item, t_max) {
                    t_max = t;
                }
            }
            t_max
        } else {
            let t_max = self.test_subtree(node + 1, t_max, test);
            self.test_subtree(n.offset as usize, t_max, test)
        }
    }

    /// Whether any item accepted by `test(item)` lies on the segment (stops at the first).
    #[inline]
    pub fn any(&self, ray: &Ray, t_min: f64, t_max: f64, mut test: impl FnMut(u32) -> bool) -> bool {
        let mut found = false;
        self.closest(ray, t_min, t_max, |item, _| {
            if !found && test(item) {
                found = true;
                // Shrinks the segment to nothing so traversal ends quickly.
                return Some(t_min);
            }
            None
        });
        found
    }
}

/// The SAH-best split of `items` (reordered in place) as `(axis, index of the first item of the
/// second half)`, or `None` when a leaf is cheaper.
fn choose_split(items: &mut [BuildItem], bounds: &Bounds) -> Option<(usize, usize)> {
    let centroids = items.iter().fold(Bounds::EMPTY, |b, it| b.include(it.centroid));
    let extent = centroids.max - centroids.min;
    let axis = if extent.x >= extent.y && extent.x >= extent.z {
        0
    } else if extent.y >= extent.z {
        1
    } else {
        2
    };
    let (lo, span) = (centroids.min[axis], extent[axis]);
    if span.is_nan() || span <= 0.0 {
        // All centroids coincide: split in the middle if the leaf would be too big.
        return (items.len() > MAX_LEAF_ITEMS).then_some((axis, items.len() / 2));
    }
    let bin_of = |c: f64| (((c - lo) / span * BINS as f64) as usize).min(BINS - 1);
    let mut bin_bounds = [Bounds::EMPTY; BINS];
    let mut bin_counts = [0usize; BINS];
    for it in items.iter() {
        let b = bin_of(it.centroid[axis]);
        bin_bounds[b] = bin_bounds[b].union(it.bounds);
        bin_counts[b] += 1;
    }
    // Cost of splitting after each bin.
    let mut best = (f64::INFINITY, 0);
    for split in 0..BINS - 1 {
        let (mut left, mut right) = (Bounds::EMPTY, Bounds::EMPTY);
        let (mut nl, mut nr) = (0, 0);
        for b in 0..=split {
            left = left.union(bin_bounds[b]);
            nl += bin_counts[b];
        }
        for b in split + 1..BINS {
            right = right.union(bin_bounds[b]);
            nr += bin_counts[b];
        }
        if nl == 0 || nr == 0 {
            continue;
        }
        let cost = nl as f64 * left.half_area() + nr as f64 * right.half_area();
        if cost < best.0 {
            best = (cost, split);
        }
    }
    let area = bounds.half_area().max(f64::MIN_POSITIVE);
    let split_cost = TRAVERSAL_COST + best.0 / area;
    let leaf_cost = items.len() as f64;
    if items.len() <= MAX_LEAF_ITEMS && split_cost >= leaf_cost {
        return None;
    }
    let mid = partition(items, |it| bin_of(it.centroid[axis]) <= best.1);
    if mid == 0 || mid == items.len() {
        return (items.len() > MAX_LEAF_ITEMS).then_some((axis, items.len() / 2));
    }
    Some((axis, mid))
}

/// Moves the items satisfying `pred` to the front; returns how many there are.
fn partition<T>(items: &mut [T], pred: impl Fn(&T) -> bool) -> usize {
    let mut first = 0;
    for i in 0..items.len() {
        if pred(&items[i]) {
            items.swap(first, i);
            first += 1;
        }
    }
    first
}

#[cfg(test)]
mod tests {
    use glam::DVec3;

    use super::*;
    use crate::geometry::test_util::TestRng;
    use crate::geometry::{Shape, Sphere};

    fn spheres(n: usize, rng: &mut TestRng) -> Vec<Shape> {
        (0..n)
            .map(|_| {
                let c = DVec3::new(rng.uniform(), rng.uniform(), rng.uniform()) * 20.0;
                Shape::Sphere(Sphere::new(c, 0.2 + rng.uniform()).expect("valid"))
            })
            .collect()
    }

    /// The BVH finds exactly the hits a linear scan finds.
    #[test]
    fn agrees_with_brute_force() {
        let mut rng = TestRng::new(5);
        for n in [0, 1, 2, 5, 17, 200] {
            let shapes = spheres(n, &mut rng);
            let items: Vec<(u32, Bounds)> =
                shapes.iter().enumerate().map(|(i, s)| (i as u32, s.bounds().expect("bounded"))).collect();
            let bvh = Bvh::build(&items);
            for _ in 0..500 {
                let origin = DVec3::new(rng.uniform(), rng.uniform(), rng.uniform()) * 30.0 - 5.0;
                let ray = Ray::new(origin, rng.unit_vector());
                let brute = shapes
                    .iter()
                    .enumerate()
                    .filter_map(|(i, s)| s.intersect(&ray, 0.0, f64::INFINITY).map(|h| (h.t, i as u32)))
                    .min_by(|a, b| a.0.total_cmp(&b.0));
                let mut found = None;
                bvh.closest(&ray, 0.0, f64::INFINITY, |i, t_max| {
                    let h = shapes[i as usize].intersect(&ray, 0.0, t_max)?;
                    found = Some((h.t, i));
                    Some(h.t)
                });
                assert_eq!(found, brute);
                let any = bvh.any(&ray, 0.0, f64::INFINITY, |i| {
                    shapes[i as usize].intersect(&ray, 0.0, f64::INFINITY).is_some()
                });
                assert_eq!(any, brute.is_some());
            }
        }
    }

    #[test]
    fn coincident_items_still_build() {
        let b = Bounds { min: DVec3::ZERO, max: DVec3::ONE };
        let items: Vec<(u32, Bounds)> = (0..100).map(|i| (i, b)).collect();
        let bvh = Bvh::build(&items);
        let mut seen = 0;
        bvh.closest(&Ray::new(DVec3::splat(-1.0), DVec3::ONE), 0.0, f64::INFINITY, |_, _| {
            seen += 1;
            None
        });
        assert_eq!(seen, 100);
    }
}
