//! The terrain and its mirror image: one static mesh (clipped at the waterline when it is built)
//! drawn with one draw call per pass.

use bytemuck::{Pod, Zeroable};
use wgpu::util::DeviceExt;

use super::RenderError;
use super::pipeline::{
    PipelinePair, PipelineSpec, pipelines, sampler_entry, shader_source, texture_entry,
    uniform_entry,
};
use super::texture::{sampler, upload};
use crate::config::SceneConfig;
use crate::world::{Heightfield, TerrainMesh, World};

/// The WGSL struct `Land`.
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable)]
struct LandUniforms {
    inverse_extent: [f32; 2],
    detail_repeat: f32,
    padding: f32,
}

/// The terrain's GPU resources.
#[derive(Debug)]
pub struct LandPass {
    pipelines: PipelinePair,
    vertices: wgpu::Buffer,
    indices: wgpu::Buffer,
    index_count: u32,
    bind_group: wgpu::BindGroup,
}

impl LandPass {
    /// Builds the mesh of `world`'s heightmap and uploads it with the colour and detail maps.
    pub fn new(
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        frame_layout: &wgpu::BindGroupLayout,
        target_format: wgpu::TextureFormat,
        world: &World,
        config: &SceneConfig,
    ) -> Result<Self, RenderError> {
        let field = Heightfield::new(&world.heightmap, config);
        let mesh = TerrainMesh::new(&field);
        let max_buffer = device.limits().max_buffer_size;
        let vertex_bytes = (mesh.positions.len() * size_of::<[f32; 3]>()) as u64;
        let index_bytes = (mesh.indices.len() * size_of::<u32>()) as u64;
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
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("land"),
            entries: &[
                uniform_entry(0),
                texture_entry(1, false),
                texture_entry(2, false),
                sampler_entry(3),
                sampler_entry(4),
            ],
        });
        let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("land"),
            layout: &layout,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: uniform_buffer.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: wgpu::BindingResource::TextureView(
                        &colour.create_view(&wgpu::TextureViewDescriptor::default()),
                    ),
                },
                wgpu::BindGroupEntry {
                    binding: 2,
                    resource: wgpu::BindingResource::TextureView(
                        &detail.create_view(&wgpu::TextureViewDescriptor::default()),
                    ),
                },
                wgpu::BindGroupEntry {
                    binding: 3,
                    resource: wgpu::BindingResource::Sampler(&sampler(device, false)),
                },
                wgpu::BindGroupEntry {
                    binding: 4,
                    resource: wgpu::BindingResource::Sampler(&sampler(device, true)),
                },
            ],
        });
        let attributes = wgpu::vertex_attr_array![0 => Float32x3];
        let pipelines = pipelines(
            device,
            &PipelineSpec {
                label: "land",
                source: shader_source!("land.wgsl"),
                bind_group_layouts: &[frame_layout, &layout],
                vertex_layout: wgpu::VertexBufferLayout {
                    array_stride: size_of::<[f32; 3]>() as u64,
                    step_mode: wgpu::VertexStepMode::Vertex,
                    attributes: &attributes,
                },
                topology: wgpu::PrimitiveTopology::TriangleList,
                strip_index_format: None,
                blend: false,
                target_format,
            },
        );
        Ok(Self {
            pipelines,
            vertices: device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("land vertices"),
                contents: bytemuck::cast_slice(&mesh.positions),
                usage: wgpu::BufferUsages::VERTEX,
            }),
            indices: device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("land indices"),
                contents: bytemuck::cast_slice(&mesh.indices),
                usage: wgpu::BufferUsages::INDEX,
            }),
            index_count: mesh.indices.len() as u32,
            bind_group,
        })
    }

    /// Draws the terrain, or its mirror image, in one draw call.
    pub fn draw(&self, pass: &mut wgpu::RenderPass<'_>, frame: &wgpu::BindGroup, mirrored: bool) {
        pass.set_pipeline(self.pipelines.get(mirrored));
        pass.set_bind_group(0, frame, &[]);
        pass.set_bind_group(1, &self.bind_group, &[]);
        pass.set_vertex_buffer(0, self.vertices.slice(..));
        pass.set_index_buffer(self.indices.slice(..), wgpu::IndexFormat::Uint32);
        pass.draw_indexed(0..self.index_count, 0, 0..1);
    }
}
