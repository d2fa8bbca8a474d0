//! The terrain and its mirror image: one static mesh (cut at the waterline when it is built) in
//! chunks and levels of detail. Each frame the chunks in view are chosen at the coarsest level
//! whose error stays under a pixel, and each pass draws them with one multi-draw-indirect call
//! (or, where the GPU cannot, one call per chunk: [`LandDrawPath`]).

use bytemuck::{Pod, Zeroable};
use wgpu::util::DeviceExt;

use super::RenderError;
use super::draw_path::{DrawSupport, LandDrawPath};
use super::pipeline::{
    Binding, PassContext, PipelinePair, PipelineSpec, bind_group, pipelines, shader_source,
};
use super::texture::{sampler, upload};
use crate::config::SceneConfig;
use crate::world::mesh::{DrawRange, EDGE_COUNT, LodView};
use crate::world::{Heightfield, TerrainMesh, World};

/// The course look's land mesh: the WGSL source its pipeline is built from.
pub(super) const SHADER: &str = shader_source!("land.wgsl");

/// Bytes of one vertex: its position.
const VERTEX_STRIDE: u64 = size_of::<[f32; 3]>() as u64;

/// Bytes of one indirect draw's arguments.
const INDIRECT_ARGS_SIZE: u64 = size_of::<wgpu::util::DrawIndexedIndirectArgs>() as u64;

/// The WGSL struct `Land`.
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable)]
struct LandUniforms {
    inverse_extent: [f32; 2],
    detail_repeat: f32,
    padding: f32,
}

/// The most draws one pass can make: a surface and four skirt strips per chunk.
fn max_draws(mesh: &TerrainMesh) -> u64 {
    (mesh.chunks.len() as u64 * (1 + EDGE_COUNT as u64)).max(1)
}

/// The land's pipelines, filling triangles or drawing their edges.
fn land_pipelines(
    context: &PassContext<'_>,
    layout: &wgpu::BindGroupLayout,
    polygon_mode: wgpu::PolygonMode,
) -> PipelinePair {
    let attributes = wgpu::vertex_attr_array![0 => Float32x3];
    let buffers = [wgpu::VertexBufferLayout {
        array_stride: VERTEX_STRIDE,
        step_mode: wgpu::VertexStepMode::Vertex,
        attributes: &attributes,
    }];
    let layouts = [layout];
    pipelines(
        context,
        &PipelineSpec { polygon_mode, ..PipelineSpec::new("land", SHADER, &layouts, &buffers) },
    )
}

/// The terrain's GPU resources.
#[derive(Debug)]
pub struct LandPass {
    pipelines: PipelinePair,
    layout: wgpu::BindGroupLayout,
    /// Pipelines drawing the triangles' edges, once asked for.
    wireframe: Option<PipelinePair>,
    /// Draw the edges (when the GPU can).
    show_wireframe: bool,
    /// GPU memory of the mesh and of its textures, in bytes.
    gpu_bytes: (u64, u64),
    vertices: wgpu::Buffer,
    indices: wgpu::Buffer,
    bind_group: wgpu::BindGroup,
    /// The chunk table (its positions and indices live on the GPU only).
    chunks: TerrainMesh,
    /// Draw arguments of the direct pass, then of the mirrored pass (one slot per chunk each),
    /// where the GPU draws indirectly (WebGL2 may not even make such a buffer).
    indirect: Option<wgpu::Buffer>,
    /// What the GPU offers the draws.
    support: DrawSupport,
    /// How the chunks are drawn (one the GPU has).
    path: LandDrawPath,
    /// The chunks chosen for the direct (0) and mirrored (1) pass of the current frame.
    chosen: [Vec<DrawRange>; 2],
    /// Whether the mirrored pass leaves out the chunks the land hides (on unless measuring).
    cull_hidden_reflection: bool,
}

impl LandPass {
    /// Builds the mesh of `world`'s heightmap and uploads it with the colour and detail maps, to
    /// draw it by `path` where the GPU (offering `support`) can, else by the next path down.
    pub fn new(
        context: &PassContext<'_>,
        world: &World,
        config: &SceneConfig,
        support: DrawSupport,
        path: LandDrawPath,
    ) -> Result<Self, RenderError> {
        let (device, queue) = (context.device, context.queue);
        let field = Heightfield::new(&world.heightmap, config);
        let mesh = TerrainMesh::new(&field);
        let max_buffer = device.limits().max_buffer_size;
        let vertex_bytes = mesh.positions.len() as u64 * VERTEX_STRIDE;
        let index_bytes = (mesh.indices.len() * size_of::<u16>()) as u64;
        if vertex_bytes.max(index_bytes) > max_buffer {
            return Err(RenderError::MeshSize {
                columns: field.columns(),
                rows: field.rows(),
                bytes: vertex_bytes.max(index_bytes),
                max: max_buffer,
            });
        }
        let colour = upload(device, queue, "colour map", &[&world.colour_map])?;
        let detail = upload(device, queue, "detail map", &[&world.detail_map])?;
        let extent = field.extent();
        let uniforms = LandUniforms {
            inverse_extent: [1.0 / extent.x, 1.0 / extent.y],
            detail_repeat: config.detail_repeat,
            padding: 0.0,
        };
        let uniform_buffer = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("land uniforms"),
            contents: bytemuck::bytes_of(&uniforms),
            usage: wgpu::BufferUsages::UNIFORM,
        });
        let (colour_view, detail_view) = (
            colour.create_view(&wgpu::TextureViewDescriptor::default()),
            detail.create_view(&wgpu::TextureViewDescriptor::default()),
        );
        let (layout, bind_group) = bind_group(
            device,
            "land",
            &[
                Binding::Uniform(&uniform_buffer),
                Binding::Texture(&colour_view),
                Binding::Texture(&detail_view),
                Binding::Sampler(&sampler(device, false)),
                Binding::Sampler(&sampler(device, true)),
            ],
        );
        let pipelines = land_pipelines(context, &layout, wgpu::PolygonMode::Fill);
        let texture_bytes = |image: &image::RgbaImage| image.as_raw().len() as u64 * 4 / 3;
        let gpu_bytes =
            (vertex_bytes + index_bytes, texture_bytes(&world.colour_map) + texture_bytes(&world.detail_map));
        // Created empty and filled through the queue (not mapped at creation): a buffer the GPU
        // has no memory for is then reported by the caller's error scope instead of panicking
        // when its mapping is written.
        let filled = |label, contents: &[u8], usage| {
            let buffer = device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: (contents.len() as u64).next_multiple_of(wgpu::COPY_BUFFER_ALIGNMENT),
                usage: usage | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
            // Whole words straight from the mesh, then the last bytes padded to a word.
            let whole = contents.len() / 4 * 4;
            queue.write_buffer(&buffer, 0, &contents[..whole]);
            if whole < contents.len() {
                let mut tail = [0u8; 4];
                tail[..contents.len() - whole].copy_from_slice(&contents[whole..]);
                queue.write_buffer(&buffer, whole as u64, &tail);
            }
            buffer
        };
        let vertices =
            filled("land vertices", bytemuck::cast_slice(&mesh.positions), wgpu::BufferUsages::VERTEX);
        let indices = filled("land indices", bytemuck::cast_slice(&mesh.indices), wgpu::BufferUsages::INDEX);
        let indirect = support.indirect.then(|| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("land draws"),
                size: 2 * INDIRECT_ARGS_SIZE * max_draws(&mesh),
                usage: wgpu::BufferUsages::INDIRECT | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            })
        });
        Ok(Self {
            pipelines,
            layout,
            wireframe: None,
            show_wireframe: false,
            gpu_bytes,
            vertices,
            indices,
            bind_group,
            // Keep the chunk table only: the geometry now lives on the GPU.
            chunks: TerrainMesh { positions: Vec::new(), indices: Vec::new(), ..mesh },
            indirect,
            support,
            path: support.resolve(path),
            chosen: [Vec::new(), Vec::new()],
            cull_hidden_reflection: true,
        })
    }

    /// Chooses the chunks and levels of the direct and mirrored passes and uploads their draws.
    pub fn prepare(&mut self, queue: &wgpu::Queue, [direct, mirrored]: [&LodView; 2]) {
        self.chosen = if self.cull_hidden_reflection {
            self.chunks.select_pair(direct, mirrored)
        } else {
            [self.chunks.select(direct), self.chunks.select(mirrored)]
        };
        for slot in 0..2 {
            let args: Vec<wgpu::util::DrawIndexedIndirectArgs> = self.chosen[slot]
                .iter()
                .map(|range| wgpu::util::DrawIndexedIndirectArgs {
                    index_count: range.index_count,
                    instance_count: 1,
                    first_index: range.first_index,
                    base_vertex: range.base_vertex as i32,
                    first_instance: 0,
                })
                .collect();
            if let (LandDrawPath::Indirect, Some(indirect)) = (self.path, &self.indirect)
                && !args.is_empty()
            {
                let bytes: Vec<u8> = args.iter().flat_map(|a| a.as_bytes().to_vec()).collect();
                queue.write_buffer(indirect, self.slot_offset(slot), &bytes);
            }
        }
    }

    fn slot_offset(&self, slot: usize) -> u64 {
        slot as u64 * INDIRECT_ARGS_SIZE * max_draws(&self.chunks)
    }

    /// Draws the terrain, or its mirror image, with the chunks chosen by [`Self::prepare`]: one
    /// multi-draw call, or one call per chunk (see [`LandDrawPath`]).
    pub fn draw(&self, pass: &mut wgpu::RenderPass<'_>, frame: &wgpu::BindGroup, mirrored: bool) {
        let slot = usize::from(mirrored);
        let chosen = &self.chosen[slot];
        if chosen.is_empty() {
            return;
        }
        let pipelines = match (&self.wireframe, self.show_wireframe) {
            (Some(wireframe), true) => wireframe,
            _ => &self.pipelines,
        };
        pass.set_pipeline(pipelines.get(mirrored));
        pass.set_bind_group(0, frame, &[]);
        pass.set_bind_group(1, &self.bind_group, &[]);
        pass.set_vertex_buffer(0, self.vertices.slice(..));
        pass.set_index_buffer(self.indices.slice(..), wgpu::IndexFormat::Uint16);
        match (self.path, &self.indirect) {
            (LandDrawPath::Indirect, Some(indirect)) => {
                pass.multi_draw_indexed_indirect(indirect, self.slot_offset(slot), chosen.len() as u32)
            }
            (LandDrawPath::Indirect, None) | (LandDrawPath::BaseVertex, _) => {
                for range in chosen {
                    let indices = range.first_index..range.first_index + range.index_count;
                    pass.draw_indexed(indices, range.base_vertex as i32, 0..1);
                }
            }
            (LandDrawPath::VertexOffset, _) => {
                // The chunk's indices count from its first vertex: bind the buffer there.
                for range in chosen {
                    let indices = range.first_index..range.first_index + range.index_count;
                    pass.set_vertex_buffer(
                        0,
                        self.vertices.slice(u64::from(range.base_vertex) * VERTEX_STRIDE..),
                    );
                    pass.draw_indexed(indices, 0, 0..1);
                }
            }
        }
    }

    /// Draws the chunks by `path` from the next frame on, or by the next path down where the GPU
    /// lacks it; returns the path taken.
    pub fn set_draw_path(&mut self, path: LandDrawPath) -> LandDrawPath {
        self.path = self.support.resolve(path);
        self.path
    }

    /// Draws the triangles' edges (`on`) or their faces. The edges need the GPU's
    /// `POLYGON_MODE_LINE` feature: without it this does nothing.
    pub fn set_wireframe(&mut self, context: &PassContext<'_>, on: bool) {
        if on
            && self.wireframe.is_none()
            && context.device.features().contains(wgpu::Features::POLYGON_MODE_LINE)
        {
            self.wireframe = Some(land_pipelines(context, &self.layout, wgpu::PolygonMode::Line));
        }
        self.show_wireframe = on;
    }

    /// Leaves out of the mirrored pass the chunks the land hides (`on`, the default) or draws
    /// them all, to measure what leaving them out saves; the picture is the same either way.
    pub fn set_cull_hidden_reflection(&mut self, on: bool) {
        self.cull_hidden_reflection = on;
    }

    /// GPU memory of the mesh and of its textures, in bytes.
    pub fn gpu_bytes(&self) -> (u64, u64) {
        self.gpu_bytes
    }

    /// Triangles drawn by the direct and mirrored passes of the current frame (skirts included).
    pub fn triangles_chosen(&self) -> [u64; 2] {
        [0, 1].map(|slot| self.chosen[slot].iter().map(|range| u64::from(range.index_count) / 3).sum())
    }
}
