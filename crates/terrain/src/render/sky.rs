//! The sky box and its mirror image: five faces (four walls and the top) from one texture array,
//! sampled clamp-to-edge so no seams show.

use bytemuck::{Pod, Zeroable};
use wgpu::util::DeviceExt;

use super::RenderError;
use super::pipeline::{
    Binding, PassContext, PipelinePair, PipelineSpec, bind_group, pipeline, shader_source,
};
use super::texture::{sampler, upload};
use crate::config::SceneConfig;
use crate::world::{SkyBox, SkyFace};

/// The course's sky box: the WGSL source its pipeline is built from.
pub(super) const COURSE_SHADER: &str = shader_source!("sky.wgsl");

/// The modern look's sky box, graded for the sun: the WGSL source its pipeline is built from.
pub(super) const MODERN_SHADER: &str = shader_source!("lighting.wgsl", "sky.wgsl", "sky_modern.wgsl");

/// A corner of a sky face.
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable)]
struct SkyVertex {
    position: [f32; 3],
    uv: [f32; 2],
    layer: u32,
}

/// The sky box's faces on the GPU: a texture array, one layer a face.
#[derive(Debug)]
pub struct SkyFaces {
    /// The faces' view (a 2-D array).
    pub view: wgpu::TextureView,
    /// GPU memory, in bytes (with mip levels).
    pub bytes: u64,
}

impl SkyFaces {
    /// Uploads `sky` (faces of different sizes are resampled to the front wall's size).
    pub fn new(context: &PassContext<'_>, sky: &SkyBox) -> Result<Self, RenderError> {
        let faces = sky.faces();
        let (width, height) = faces[0].dimensions();
        let resized: Vec<image::RgbaImage> = faces
            .iter()
            .map(|face| {
                if face.dimensions() == (width, height) {
                    (*face).clone()
                } else {
                    image::imageops::resize(*face, width, height, image::imageops::FilterType::Triangle)
                }
            })
            .collect();
        let layers: Vec<&image::RgbaImage> = resized.iter().collect();
        let texture = upload(context.device, context.queue, "sky faces", &layers)?;
        let view = texture.create_view(&wgpu::TextureViewDescriptor {
            dimension: Some(wgpu::TextureViewDimension::D2Array),
            ..Default::default()
        });
        Ok(Self { view, bytes: u64::from(width) * u64::from(height) * 4 * 5 * 4 / 3 })
    }
}

/// The sky box's GPU resources: its mesh, its faces' bind group and its pipelines (the world as
/// it is and its mirror image).
#[derive(Debug)]
pub struct SkyPass {
    pipelines: PipelinePair,
    vertices: wgpu::Buffer,
    indices: wgpu::Buffer,
    index_count: u32,
    bind_group: wgpu::BindGroup,
    /// Group 2 of the modern look (its lighting), if this is its sky.
    lighting: Option<wgpu::BindGroup>,
}

impl SkyPass {
    /// The course's sky box: `faces` as they are, on the box of `config`.
    pub fn new(context: &PassContext<'_>, faces: &SkyFaces, config: &SceneConfig) -> Self {
        Self::build(context, context, faces, config, COURSE_SHADER, ("vs_main", "fs_main"), None)
    }

    /// The modern look's sky box: the atmosphere's colours from `lighting` (group 2, with its
    /// `layout`; `faces` are bound but unused); without a sea its walls reach as far below the
    /// horizon as above it (where no land is drawn, the horizon's colour shows). Its mirror image is drawn into the reflection, described by `reflection`.
    pub fn modern(
        context: &PassContext<'_>,
        reflection: &PassContext<'_>,
        faces: &SkyFaces,
        config: &SceneConfig,
        lighting: (&wgpu::BindGroupLayout, &wgpu::BindGroup),
    ) -> Self {
        Self::build(
            context,
            reflection,
            faces,
            config,
            MODERN_SHADER,
            ("vs_modern", "fs_modern"),
            Some(lighting),
        )
    }

    fn build(
        context: &PassContext<'_>,
        mirrored_context: &PassContext<'_>,
        faces: &SkyFaces,
        config: &SceneConfig,
        source: &str,
        (vertex_entry, fragment_entry): (&str, &str),
        lighting: Option<(&wgpu::BindGroupLayout, &wgpu::BindGroup)>,
    ) -> Self {
        let device = context.device;
        let (layout, bind_group) = bind_group(
            device,
            "sky",
            &[Binding::TextureArray(&faces.view), Binding::Sampler(&sampler(device, false))],
        );
        // The modern look's sky (the one with lighting) reaches below the horizon where no sea
        // covers it.
        let (vertices, indices) = box_mesh(config, lighting.is_some() && !config.sea);
        let attributes = wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x2, 2 => Uint32];
        let buffers = [wgpu::VertexBufferLayout {
            array_stride: size_of::<SkyVertex>() as u64,
            step_mode: wgpu::VertexStepMode::Vertex,
            attributes: &attributes,
        }];
        let layouts: Vec<&wgpu::BindGroupLayout> =
            std::iter::once(&layout).chain(lighting.map(|l| l.0)).collect();
        let spec = PipelineSpec {
            vertex_entry,
            fragment_entry: Some(fragment_entry),
            ..PipelineSpec::new("sky", source, &layouts, &buffers)
        };
        let pipelines = PipelinePair {
            direct: pipeline(context, &spec, false),
            mirrored: pipeline(mirrored_context, &spec, true),
        };
        Self {
            pipelines,
            vertices: device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("sky vertices"),
                contents: bytemuck::cast_slice(&vertices),
                usage: wgpu::BufferUsages::VERTEX,
            }),
            indices: device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("sky indices"),
                contents: bytemuck::cast_slice(&indices),
                usage: wgpu::BufferUsages::INDEX,
            }),
            index_count: indices.len() as u32,
            bind_group,
            lighting: lighting.map(|l| l.1.clone()),
        }
    }

    /// Draws the sky box, or its mirror image, in one draw call.
    pub fn draw(&self, pass: &mut wgpu::RenderPass<'_>, frame: &wgpu::BindGroup, mirrored: bool) {
        pass.set_pipeline(self.pipelines.get(mirrored));
        pass.set_bind_group(0, frame, &[]);
        pass.set_bind_group(1, &self.bind_group, &[]);
        if let Some(lighting) = &self.lighting {
            pass.set_bind_group(2, lighting, &[]);
        }
        pass.set_vertex_buffer(0, self.vertices.slice(..));
        pass.set_index_buffer(self.indices.slice(..), wgpu::IndexFormat::Uint16);
        pass.draw_indexed(0..self.index_count, 0, 0..1);
    }
}

/// The five faces as quads, counter-clockwise seen from inside the box; with `below_horizon`,
/// the walls reach down to minus the box's height (their texture coordinates unchanged).
fn box_mesh(config: &SceneConfig, below_horizon: bool) -> (Vec<SkyVertex>, Vec<u16>) {
    let size = config.sky_box_size.as_dvec3();
    let mut vertices = Vec::with_capacity(20);
    let mut indices = Vec::with_capacity(30);
    for (layer, face) in SkyFace::ALL.into_iter().enumerate() {
        let first = vertices.len() as u16;
        // Corners in image order: top left, top right, bottom right, bottom left.
        for (u, v) in [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)] {
            let reach = if below_horizon && face != SkyFace::Top && v == 1.0 { 2.0 } else { v };
            vertices.push(SkyVertex {
                position: face.point(u, reach, size).as_vec3().to_array(),
                uv: [u as f32, v as f32],
                layer: layer as u32,
            });
        }
        // Seen from inside, a face's image reads left to right and top to bottom, so
        // (top left, bottom left, bottom right) turns counter-clockwise.
        indices.extend([0, 3, 2, 0, 2, 1].map(|i| first + i));
    }
    (vertices, indices)
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::*;

    #[test]
    fn faces_turn_toward_the_inside() {
        for below_horizon in [false, true] {
            let (vertices, indices) = box_mesh(&SceneConfig::default(), below_horizon);
            assert_eq!(vertices.len(), 20);
            let lowest = vertices.iter().map(|v| v.position[1]).fold(f32::MAX, f32::min);
            assert_eq!(lowest < 0.0, below_horizon);
            // A point inside the box sees every triangle's front: its normal points at it.
            let inside = Vec3::new(0.0, 2.5, 10.0);
            for triangle in indices.chunks(3) {
                let p = |i: u16| Vec3::from_array(vertices[i as usize].position);
                let (a, b, c) = (p(triangle[0]), p(triangle[1]), p(triangle[2]));
                let normal = (b - a).cross(c - a);
                assert!(normal.dot(inside - a) > 0.0, "triangle {triangle:?} faces outward");
            }
        }
    }
}
