//! The water: a translucent plane at y = 0 over the sky box's floor, its texture repeated and
//! drifting with time.

use bytemuck::{Pod, Zeroable};
use wgpu::util::DeviceExt;

use super::RenderError;
use super::pipeline::{
    Binding, PassContext, PipelinePair, PipelineSpec, bind_group, pipelines, shader_source,
};
use super::texture::{sampler, upload};
use crate::config::SceneConfig;

/// The course's water: the WGSL source its pipeline is built from.
pub(super) const SHADER: &str = shader_source!("water.wgsl");

/// A corner of the water plane: its position and its texture coordinates.
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable)]
pub struct WaterVertex {
    position: [f32; 3],
    uv: [f32; 2],
}

/// The WGSL struct `Water`.
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable)]
struct WaterUniforms {
    alpha: f32,
    padding: [f32; 3],
}

/// The water's GPU resources.
#[derive(Debug)]
pub struct WaterPass {
    pipelines: PipelinePair,
    vertices: wgpu::Buffer,
    bind_group: wgpu::BindGroup,
}

impl WaterPass {
    /// Uploads the water texture and builds the plane of `config`.
    pub fn new(
        context: &PassContext<'_>,
        texture: &image::RgbaImage,
        config: &SceneConfig,
    ) -> Result<Self, RenderError> {
        let device = context.device;
        let texture = upload(device, context.queue, "water texture", &[texture])?;
        let uniforms = WaterUniforms { alpha: config.water_alpha, padding: [0.0; 3] };
        let uniform_buffer = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("water uniforms"),
            contents: bytemuck::bytes_of(&uniforms),
            usage: wgpu::BufferUsages::UNIFORM,
        });
        let view = texture.create_view(&wgpu::TextureViewDescriptor::default());
        let (layout, bind_group) = bind_group(
            device,
            "water",
            &[
                Binding::Uniform(&uniform_buffer),
                Binding::Texture(&view),
                Binding::Sampler(&sampler(device, true)),
            ],
        );
        let attributes = wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x2];
        let buffers = [wgpu::VertexBufferLayout {
            array_stride: size_of::<WaterVertex>() as u64,
            step_mode: wgpu::VertexStepMode::Vertex,
            attributes: &attributes,
        }];
        let pipelines = pipelines(
            context,
            &PipelineSpec {
                topology: wgpu::PrimitiveTopology::TriangleStrip,
                blend: true,
                ..PipelineSpec::new("water", SHADER, &[&layout], &buffers)
            },
        );
        Ok(Self {
            pipelines,
            vertices: device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("water vertices"),
                contents: bytemuck::cast_slice(&plane(config)),
                usage: wgpu::BufferUsages::VERTEX,
            }),
            bind_group,
        })
    }

    /// Draws the water (never mirrored) in one draw call.
    pub fn draw(&self, pass: &mut wgpu::RenderPass<'_>, frame: &wgpu::BindGroup) {
        pass.set_pipeline(self.pipelines.get(false));
        pass.set_bind_group(0, frame, &[]);
        pass.set_bind_group(1, &self.bind_group, &[]);
        pass.set_vertex_buffer(0, self.vertices.slice(..));
        pass.draw(0..4, 0..1);
    }
}

/// The plane over the sky box's floor as a 4-vertex strip, counter-clockwise seen from above,
/// with the texture repeated `water_repeat` times (u along +x, v along +z).
pub fn plane(config: &SceneConfig) -> [WaterVertex; 4] {
    let (hx, hz) = (config.sky_box_size.x / 2.0, config.sky_box_size.z / 2.0);
    let (ru, rv) = (config.water_repeat.x, config.water_repeat.y);
    [
        WaterVertex { position: [-hx, 0.0, -hz], uv: [0.0, 0.0] },
        WaterVertex { position: [-hx, 0.0, hz], uv: [0.0, rv] },
        WaterVertex { position: [hx, 0.0, -hz], uv: [ru, 0.0] },
        WaterVertex { position: [hx, 0.0, hz], uv: [ru, rv] },
    ]
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::*;

    #[test]
    fn plane_covers_the_floor_and_faces_up() {
        let config = SceneConfig::default();
        let corners = plane(&config);
        let p = |i: usize| Vec3::from_array(corners[i].position);
        assert_eq!(p(0), Vec3::new(-100.0, 0.0, -140.0));
        assert_eq!(p(3), Vec3::new(100.0, 0.0, 140.0));
        assert_eq!(corners[3].uv, [20.0, 28.0]);
        // Both strip triangles (0 1 2) and (2 1 3) turn counter-clockwise seen from above.
        for [a, b, c] in [[0, 1, 2], [2, 1, 3]] {
            assert!((p(b) - p(a)).cross(p(c) - p(a)).y > 0.0);
        }
    }
}
