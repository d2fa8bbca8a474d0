//! The terrain as a grid displaced on the GPU: the heightmap as a 16-bit texture (2 bytes a
//! sample, whatever the map's size) and one small patch mesh drawn once per node the
//! level-of-detail tree ([`TerrainTree`]) chooses: a pass is one instanced draw call per
//! combination of skirts in use.
//!
//! Both looks draw with it (the course's look for maps too large for its static mesh); its bind
//! group (group 1) is `[grid uniform, heights, colour map, detail map, clamp sampler, wrap
//! sampler, light map]`.

use bytemuck::{Pod, Zeroable};
use wgpu::util::DeviceExt;

use super::RenderError;
use super::pipeline::{Binding, PassContext, bind_group};
use super::texture::{sampler, upload};
use crate::config::SceneConfig;
use crate::world::quadtree::{PATCH_CELLS, Patch, SKIRT_MASKS, TerrainTree, TreeView};
use crate::world::{Heightfield, Heightmap};

/// Rows of heights uploaded at a time, to bound the staging memory.
const UPLOAD_ROWS: u32 = 256;

/// The WGSL struct `Grid` of `heights.wgsl`.
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable)]
struct GridUniforms {
    columns: u32,
    rows: u32,
    patch_cells: u32,
    padding0: u32,
    origin: [f32; 2],
    cell: f32,
    level_offset: f32,
    unit_height: f32,
    detail_repeat: f32,
    inverse_extent: [f32; 2],
}

/// Which pass a set of chosen patches is for.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum GridPass {
    /// The world as it is.
    Direct = 0,
    /// Its mirror image (the course's mirrored land, the modern look's reflection).
    Mirrored = 1,
    /// The sun's view, for the shadow map.
    Sun = 2,
}

/// The chosen patches of one pass, on the GPU.
#[derive(Debug)]
struct Instances {
    buffer: wgpu::Buffer,
    capacity: usize,
    /// How many patches each skirt mask has (they follow one another in the buffer).
    groups: [u32; SKIRT_MASKS],
}

/// The grid terrain's GPU resources.
#[derive(Debug)]
pub struct GridTerrain {
    tree: TerrainTree,
    uniforms: wgpu::Buffer,
    heights: wgpu::TextureView,
    patch_vertices: wgpu::Buffer,
    patch_indices: wgpu::Buffer,
    /// The index range of each skirt mask: the surface, then the masked edges' skirts.
    ranges: [std::ops::Range<u32>; SKIRT_MASKS],
    instances: [Instances; 3],
    scratch: Vec<Patch>,
    samples: (u32, u32),
    gpu_bytes: u64,
}

impl GridTerrain {
    /// Uploads `heightmap` (placed with `config`) and builds its tree.
    pub fn new(
        context: &PassContext<'_>,
        heightmap: &Heightmap,
        config: &SceneConfig,
    ) -> Result<Self, RenderError> {
        let device = context.device;
        let (columns, rows) = (heightmap.columns(), heightmap.rows());
        let max = device.limits().max_texture_dimension_2d;
        if columns > max || rows > max {
            return Err(RenderError::TextureSize {
                what: "heightmap".into(),
                width: columns,
                height: rows,
                max,
            });
        }
        let field_cell = Heightfield::cell_size_of(heightmap, config);
        let extent = [columns as f32 * field_cell, rows as f32 * field_cell];
        let uniforms = GridUniforms {
            columns,
            rows,
            patch_cells: PATCH_CELLS,
            padding0: 0,
            origin: [0.5 * field_cell - extent[0] / 2.0, 0.5 * field_cell - extent[1] / 2.0],
            cell: field_cell,
            level_offset: config.level_offset,
            unit_height: config.unit_height,
            detail_repeat: config.detail_repeat,
            inverse_extent: [1.0 / extent[0], 1.0 / extent[1]],
        };
        let (heights, height_bytes) = upload_heights(context, heightmap);
        let (indices, ranges) = patch_indices();
        let corners = patch_corners();
        let patch_vertices = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("grid patch vertices"),
            contents: bytemuck::cast_slice(&corners),
            usage: wgpu::BufferUsages::VERTEX,
        });
        let patch_indices = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("grid patch indices"),
            contents: bytemuck::cast_slice(&indices),
            usage: wgpu::BufferUsages::INDEX,
        });
        let instances = [0, 1, 2].map(|_| Instances::new(device, 256));
        Ok(Self {
            tree: TerrainTree::new(heightmap, config),
            uniforms: device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("grid uniforms"),
                contents: bytemuck::bytes_of(&uniforms),
                usage: wgpu::BufferUsages::UNIFORM,
            }),
            heights,
            patch_vertices,
            patch_indices,
            ranges,
            instances,
            scratch: Vec::new(),
            samples: (columns, rows),
            gpu_bytes: height_bytes + (indices.len() * 2 + corners.len() * 4) as u64,
        })
    }

    /// GPU memory the heights, normals and patch take, in bytes.
    pub fn gpu_bytes(&self) -> u64 {
        self.gpu_bytes
    }

    /// CPU memory the level-of-detail tree takes, in bytes.
    pub fn tree_bytes(&self) -> usize {
        self.tree.memory_bytes()
    }

    /// The grid uniform buffer (group 1, binding 0).
    pub fn uniforms(&self) -> &wgpu::Buffer {
        &self.uniforms
    }

    /// The heights (group 1, binding 1).
    pub fn heights(&self) -> &wgpu::TextureView {
        &self.heights
    }

    /// The size of the heightmap, in samples.
    pub fn samples(&self) -> (u32, u32) {
        self.samples
    }

    /// The bind group of the heights alone (group 1 of `heights.wgsl`).
    pub fn heights_group(&self, device: &wgpu::Device) -> (wgpu::BindGroupLayout, wgpu::BindGroup) {
        bind_group(
            device,
            "heights",
            &[Binding::Uniform(&self.uniforms), Binding::UintTexture(&self.heights)],
        )
    }

    /// The bind group of the land drawn with `colour` and `detail` maps and a `light` map (the
    /// modern look's; any texture for the course's) (group 1).
    pub fn land_group(
        &self,
        device: &wgpu::Device,
        label: &str,
        colour: &wgpu::TextureView,
        detail: &wgpu::TextureView,
        light: &wgpu::TextureView,
    ) -> (wgpu::BindGroupLayout, wgpu::BindGroup) {
        bind_group(
            device,
            label,
            &[
                Binding::Uniform(&self.uniforms),
                Binding::UintTexture(&self.heights),
                Binding::Texture(colour),
                Binding::Texture(detail),
                Binding::Sampler(&sampler(device, false)),
                Binding::Sampler(&sampler(device, true)),
                Binding::Texture(light),
            ],
        )
    }

    /// The vertex buffer layouts of the grid: the patch's corners (location 0), then the
    /// patches (one instance each, location 1).
    pub fn buffer_layouts() -> [wgpu::VertexBufferLayout<'static>; 2] {
        const CORNER: [wgpu::VertexAttribute; 1] = wgpu::vertex_attr_array![0 => Uint8x4];
        const NODE: [wgpu::VertexAttribute; 1] = wgpu::vertex_attr_array![1 => Uint32x4];
        [
            wgpu::VertexBufferLayout {
                array_stride: 4,
                step_mode: wgpu::VertexStepMode::Vertex,
                attributes: &CORNER,
            },
            wgpu::VertexBufferLayout {
                array_stride: size_of::<Patch>() as u64,
                step_mode: wgpu::VertexStepMode::Instance,
                attributes: &NODE,
            },
        ]
    }

    /// Chooses the patches of `pass` for `view` and uploads them.
    pub fn prepare(&mut self, device: &wgpu::Device, queue: &wgpu::Queue, pass: GridPass, view: &TreeView) {
        let groups = self.tree.select(view, &mut self.scratch);
        let instances = &mut self.instances[pass as usize];
        if self.scratch.len() > instances.capacity {
            *instances = Instances::new(device, self.scratch.len().next_power_of_two());
        }
        instances.groups = groups;
        if !self.scratch.is_empty() {
            queue.write_buffer(&instances.buffer, 0, bytemuck::cast_slice(&self.scratch));
        }
    }

    /// Draws the patches chosen for `pass` (the pipeline and bind groups are set by the caller):
    /// one instanced draw per skirt mask in use.
    pub fn draw(&self, render_pass: &mut wgpu::RenderPass<'_>, pass: GridPass) {
        let instances = &self.instances[pass as usize];
        if instances.groups.iter().all(|&count| count == 0) {
            return;
        }
        render_pass.set_vertex_buffer(0, self.patch_vertices.slice(..));
        render_pass.set_vertex_buffer(1, instances.buffer.slice(..));
        render_pass.set_index_buffer(self.patch_indices.slice(..), wgpu::IndexFormat::Uint16);
        let mut first = 0;
        for (range, &count) in self.ranges.iter().zip(&instances.groups) {
            if count > 0 {
                render_pass.draw_indexed(range.clone(), 0, first..first + count);
            }
            first += count;
        }
    }

    /// Triangles drawn by `pass` in its last preparation (skirts included).
    pub fn triangles(&self, pass: GridPass) -> u64 {
        let groups = &self.instances[pass as usize].groups;
        self.ranges
            .iter()
            .zip(groups)
            .map(|(range, &count)| u64::from(count) * u64::from(range.len() as u32 / 3))
            .sum()
    }
}

impl Instances {
    fn new(device: &wgpu::Device, capacity: usize) -> Self {
        Self {
            buffer: device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("grid patches"),
                size: (capacity * size_of::<Patch>()) as u64,
                usage: wgpu::BufferUsages::VERTEX | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            }),
            capacity,
            groups: [0; SKIRT_MASKS],
        }
    }
}

/// The patch's vertices: the surface's samples row by row, then the bottoms of the skirts along
/// its four edges (first row, last row, first column, last column), in increasing order along
/// each; each as (column, row, 1 for a skirt's bottom, 0).
fn patch_corners() -> Vec<[u8; 4]> {
    let side = PATCH_CELLS + 1;
    let mut corners: Vec<[u8; 4]> =
        (0..side * side).map(|v| [(v % side) as u8, (v / side) as u8, 0, 0]).collect();
    for edge in 0..4 {
        for t in 0..side as u8 {
            let last = PATCH_CELLS as u8;
            let (column, row) = match edge {
                0 => (t, 0),
                1 => (t, last),
                2 => (0, t),
                _ => (last, t),
            };
            corners.push([column, row, 1, 0]);
        }
    }
    corners
}

/// The patch's index lists, one after the other, for each skirt mask: the surface (two triangles
/// per cell, (a, b, c) and (c, b, d) as in the static mesh), then one outward-facing strip of two
/// triangles per edge segment along each edge of the mask (vertex numbering of
/// [`patch_corners`]). Returns the indices and each mask's range.
fn patch_indices() -> (Vec<u16>, [std::ops::Range<u32>; SKIRT_MASKS]) {
    let side = PATCH_CELLS + 1;
    let at = |i: u32, j: u32| (i * side + j) as u16;
    let mut surface = Vec::new();
    for i in 0..PATCH_CELLS {
        for j in 0..PATCH_CELLS {
            let (a, b, c, d) = (at(i, j), at(i + 1, j), at(i, j + 1), at(i + 1, j + 1));
            surface.extend([a, b, c, c, b, d]);
        }
    }
    let skirts: Vec<Vec<u16>> = (0..4u32)
        .map(|edge| {
            let top = |t: u32| match edge {
                0 => at(0, t),
                1 => at(PATCH_CELLS, t),
                2 => at(t, 0),
                _ => at(t, PATCH_CELLS),
            };
            let bottom = |t: u32| (side * side + edge * side + t) as u16;
            // The first row faces -z and the last column +x with this winding; the other two
            // edges take the opposite one.
            let forward = matches!(edge, 0 | 3);
            (0..PATCH_CELLS)
                .flat_map(|t| {
                    let (p, q, p_low, q_low) = (top(t), top(t + 1), bottom(t), bottom(t + 1));
                    if forward { [p, q, q_low, p, q_low, p_low] } else { [q, p, p_low, q, p_low, q_low] }
                })
                .collect()
        })
        .collect();
    let mut indices = Vec::new();
    let ranges = std::array::from_fn(|mask| {
        let start = indices.len() as u32;
        indices.extend_from_slice(&surface);
        for (edge, skirt) in skirts.iter().enumerate() {
            if mask & (1 << edge) != 0 {
                indices.extend_from_slice(skirt);
            }
        }
        start..indices.len() as u32
    });
    (indices, ranges)
}

/// Uploads the heights as an R16Uint texture, a band of rows at a time. Returns its view and
/// its size in bytes.
fn upload_heights(context: &PassContext<'_>, heightmap: &Heightmap) -> (wgpu::TextureView, u64) {
    let (columns, rows) = (heightmap.columns(), heightmap.rows());
    let texture = context.device.create_texture(&wgpu::TextureDescriptor {
        label: Some("heights"),
        size: wgpu::Extent3d { width: columns, height: rows, depth_or_array_layers: 1 },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: wgpu::TextureFormat::R16Uint,
        usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
        view_formats: &[],
    });
    let mut band = Vec::with_capacity((columns * UPLOAD_ROWS) as usize);
    for first in (0..rows).step_by(UPLOAD_ROWS as usize) {
        let count = UPLOAD_ROWS.min(rows - first);
        band.clear();
        for row in first..first + count {
            heightmap.extend_sixteen_bit_row(row, &mut band);
        }
        write_band(context.queue, &texture, 0, first, columns, count, bytemuck::cast_slice(&band), 2);
    }
    let bytes = u64::from(columns) * u64::from(rows) * 2;
    (texture.create_view(&wgpu::TextureViewDescriptor::default()), bytes)
}

/// Writes `count` rows of `width` texels of `bytes_per_texel` bytes at row `first` of `level`.
#[allow(clippy::too_many_arguments)]
fn write_band(
    queue: &wgpu::Queue,
    texture: &wgpu::Texture,
    level: u32,
    first: u32,
    width: u32,
    count: u32,
    data: &[u8],
    bytes_per_texel: u32,
) {
    queue.write_texture(
        wgpu::TexelCopyTextureInfo {
            texture,
            mip_level: level,
            origin: wgpu::Origin3d { x: 0, y: first, z: 0 },
            aspect: wgpu::TextureAspect::All,
        },
        data,
        wgpu::TexelCopyBufferLayout {
            offset: 0,
            bytes_per_row: Some(width * bytes_per_texel),
            rows_per_image: Some(count),
        },
        wgpu::Extent3d { width, height: count, depth_or_array_layers: 1 },
    );
}

/// Uploads `image` for the grid's land (a mipmapped RGBA texture) and returns its view.
pub fn upload_view(
    context: &PassContext<'_>,
    what: &str,
    image: &image::RgbaImage,
) -> Result<wgpu::TextureView, RenderError> {
    Ok(upload(context.device, context.queue, what, &[image])?
        .create_view(&wgpu::TextureViewDescriptor::default()))
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::*;

    #[test]
    fn the_patch_faces_up_and_its_skirts_face_out() {
        let (all, ranges) = patch_indices();
        let side = PATCH_CELLS + 1;
        assert!(all.iter().all(|&i| u32::from(i) < side * side + 4 * side));
        assert_eq!(ranges[0].len() as u32, PATCH_CELLS * PATCH_CELLS * 6, "mask 0: the surface only");
        assert_eq!(ranges[15].len() as u32, PATCH_CELLS * PATCH_CELLS * 6 + 4 * PATCH_CELLS * 6);
        let indices = &all[ranges[15].start as usize..ranges[15].end as usize];
        // Vertex positions of a flat patch with skirts one unit deep (as `grid.wgsl` places them).
        let corners = patch_corners();
        assert_eq!(corners.len() as u32, side * side + 4 * side);
        let position = |v: u16| {
            let [column, row, skirt, _] = corners[usize::from(v)];
            Vec3::new(f32::from(column), -f32::from(skirt), f32::from(row))
        };
        let surface = (PATCH_CELLS * PATCH_CELLS * 6) as usize;
        for (k, triangle) in indices.chunks(3).enumerate() {
            let [a, b, c] = [0, 1, 2].map(|i| position(triangle[i]));
            let normal = (b - a).cross(c - a);
            if k * 3 < surface {
                assert!(normal.y > 0.0, "surface triangle {k} faces down");
                continue;
            }
            // Outward: away from the patch's centre.
            let centre = Vec3::new(PATCH_CELLS as f32 / 2.0, 0.0, PATCH_CELLS as f32 / 2.0);
            let out = ((a + b + c) / 3.0 - centre) * Vec3::new(1.0, 0.0, 1.0);
            assert!(normal.dot(out) > 0.0, "skirt triangle {k} faces in");
            assert!(normal.y.abs() < 1e-6, "skirt triangle {k} is not vertical");
        }
    }
}
