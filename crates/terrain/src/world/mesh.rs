//! The terrain's static mesh: the part of the heightfield at or above the water, built once.

use std::collections::HashMap;

use super::Heightfield;

/// The terrain above the water as one indexed triangle list.
///
/// Every heightmap cell is two triangles, wound counter-clockwise seen from above (their normals
/// point up, +y). Triangles entirely under water (y < 0) are left out and those crossing the
/// water are cut along y = 0. Heights vary linearly across a triangle, so this keeps exactly the
/// surface the course's renderer kept by discarding fragments below the water, but the GPU never
/// sees the underwater part and needs no `discard` (which would cost it its early depth test).
#[derive(Debug, Clone, PartialEq)]
pub struct TerrainMesh {
    /// World positions (x, y, z): the samples, row by row from the far (-z) row, then the points
    /// where cell edges cross the water.
    pub positions: Vec<[f32; 3]>,
    /// Triangle-list indices into `positions`.
    pub indices: Vec<u32>,
}

impl TerrainMesh {
    /// Builds the mesh of `field`'s part at or above y = 0.
    pub fn new(field: &Heightfield) -> Self {
        let (columns, rows) = (field.columns(), field.rows());
        let mut positions = Vec::with_capacity(columns as usize * rows as usize);
        for row in 0..rows {
            for column in 0..columns {
                positions.push(field.point(row, column).to_array());
            }
        }
        let mut clipper = WaterClipper {
            positions,
            crossings: HashMap::new(),
            indices: Vec::new(),
        };
        for row in 0..rows - 1 {
            for column in 0..columns - 1 {
                let a = row * columns + column;
                let (b, c, d) = (a + columns, a + 1, a + columns + 1);
                // (a, b, c) and (c, b, d) turn counter-clockwise seen from above.
                clipper.add([a, b, c]);
                clipper.add([c, b, d]);
            }
        }
        Self {
            positions: clipper.positions,
            indices: clipper.indices,
        }
    }

    /// Number of triangles.
    pub fn triangle_count(&self) -> usize {
        self.indices.len() / 3
    }
}

/// Cuts triangles along y = 0, sharing each crossing point between the triangles of its edge.
struct WaterClipper {
    positions: Vec<[f32; 3]>,
    /// Crossing vertex of each cut edge, keyed by its endpoints (smaller index first).
    crossings: HashMap<(u32, u32), u32>,
    indices: Vec<u32>,
}

impl WaterClipper {
    fn height(&self, vertex: u32) -> f32 {
        self.positions[vertex as usize][1]
    }

    /// Adds the part of `triangle` at or above the water.
    fn add(&mut self, triangle: [u32; 3]) {
        let above = triangle.map(|v| self.height(v) >= 0.0);
        if above.iter().all(|&a| a) {
            self.indices.extend(triangle);
            return;
        }
        if !above.iter().any(|&a| a) {
            return;
        }
        // Sutherland-Hodgman against one plane: keep the vertices above, insert the crossings,
        // in the triangle's own order (so the winding is kept). Gives 3 or 4 vertices.
        let mut polygon = Vec::with_capacity(4);
        for i in 0..3 {
            let (p, q) = (triangle[i], triangle[(i + 1) % 3]);
            if above[i] {
                polygon.push(p);
            }
            if above[i] != above[(i + 1) % 3] {
                polygon.push(self.crossing(p, q));
            }
        }
        for k in 1..polygon.len() - 1 {
            self.indices
                .extend([polygon[0], polygon[k], polygon[k + 1]]);
        }
    }

    /// The vertex where edge (p, q) crosses y = 0 (one above, one below).
    fn crossing(&mut self, p: u32, q: u32) -> u32 {
        let key = (p.min(q), p.max(q));
        if let Some(&vertex) = self.crossings.get(&key) {
            return vertex;
        }
        // Interpolate from the lower-indexed end so both triangles of the edge agree exactly.
        let (from, to) = (
            self.positions[key.0 as usize],
            self.positions[key.1 as usize],
        );
        let t = from[1] / (from[1] - to[1]);
        let vertex = self.positions.len() as u32;
        self.positions.push([
            from[0] + (to[0] - from[0]) * t,
            0.0,
            from[2] + (to[2] - from[2]) * t,
        ]);
        self.crossings.insert(key, vertex);
        vertex
    }
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::*;
    use crate::config::SceneConfig;
    use crate::world::Heightmap;

    fn field(columns: u32, rows: u32, levels: Vec<f32>) -> Heightfield {
        let map = Heightmap::new(columns, rows, levels).expect("valid");
        Heightfield::new(&map, &SceneConfig::default())
    }

    fn triangles(mesh: &TerrainMesh) -> impl Iterator<Item = [Vec3; 3]> + '_ {
        let p = |i: u32| Vec3::from_array(mesh.positions[i as usize]);
        mesh.indices
            .chunks_exact(3)
            .map(move |t| [p(t[0]), p(t[1]), p(t[2])])
    }

    /// Area of the mesh projected on the water plane.
    fn plan_area(mesh: &TerrainMesh) -> f32 {
        triangles(mesh)
            .map(|[a, b, c]| {
                let (mut a, mut b, mut c) = (a, b, c);
                a.y = 0.0;
                b.y = 0.0;
                c.y = 0.0;
                (b - a).cross(c - a).length() / 2.0
            })
            .sum()
    }

    #[test]
    fn land_above_water_is_two_upward_triangles_per_cell() {
        for (columns, rows) in [(2, 2), (3, 7), (16, 5)] {
            // Levels 100..=255: all at or above the water.
            let levels = (0..columns * rows)
                .map(|i| 100.0 + (i * 37 % 156) as f32)
                .collect();
            let f = field(columns, rows, levels);
            let mesh = TerrainMesh::new(&f);
            assert_eq!(mesh.positions.len(), (columns * rows) as usize);
            assert_eq!(
                mesh.triangle_count(),
                2 * ((columns - 1) * (rows - 1)) as usize
            );
            for [a, b, c] in triangles(&mesh) {
                let normal = (b - a).cross(c - a);
                assert!(normal.y > 0.0, "triangle faces down");
            }
            let extent = f.extent() - f.cell_size();
            assert!((plan_area(&mesh) - extent.x * extent.y).abs() < 1e-3);
        }
    }

    #[test]
    fn nothing_under_water_is_kept() {
        let f = field(4, 4, vec![20.0; 16]);
        let mesh = TerrainMesh::new(&f);
        assert!(mesh.indices.is_empty());
    }

    #[test]
    fn the_coast_is_cut_exactly_at_the_waterline() {
        // A ramp along x: levels 40, 80, ..., so heights -0.9, -0.3, 0.3, 0.9, 1.5 (y = 0 halfway
        // between columns 1 and 2).
        let levels = (0..5 * 3).map(|i| 40.0 + 40.0 * (i % 5) as f32).collect();
        let f = field(5, 3, levels);
        let mesh = TerrainMesh::new(&f);
        for &i in &mesh.indices {
            assert!(mesh.positions[i as usize][1] >= 0.0);
        }
        for [a, b, c] in triangles(&mesh) {
            assert!((b - a).cross(c - a).y > 0.0, "winding kept");
        }
        // Kept: from the waterline (x halfway between columns 1 and 2) to the last column,
        // i.e. 2.5 cells wide, over 2 cells of depth.
        let cell = f.cell_size();
        let expected = 2.5 * cell * 2.0 * cell;
        assert!(
            (plan_area(&mesh) - expected).abs() < 1e-4,
            "{} vs {expected}",
            plan_area(&mesh)
        );
        // The crossing points sit at the waterline, shared by the triangles on either side.
        let waterline: Vec<_> = mesh.positions[15..].to_vec();
        assert_eq!(
            waterline.len(),
            3 + 2,
            "one crossing per cut edge: 3 rows + 2 diagonals"
        );
        let x = (f.point(0, 1).x + f.point(0, 2).x) / 2.0;
        for p in waterline
            .iter()
            .filter(|p| p[2] == f.point(0, 1).z || p[2] == f.point(2, 1).z)
        {
            assert!((p[0] - x).abs() < 1e-5 && p[1] == 0.0);
        }
    }

    #[test]
    fn every_index_is_in_range() {
        let levels = (0..9 * 9).map(|i| (i * 53 % 256) as f32).collect();
        let mesh = TerrainMesh::new(&field(9, 9, levels));
        assert_eq!(mesh.indices.len() % 3, 0);
        assert!(
            mesh.indices
                .iter()
                .all(|&i| (i as usize) < mesh.positions.len())
        );
    }
}
