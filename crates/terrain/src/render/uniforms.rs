//! The uniforms every pass shares (group 0): the camera, the mirror and the water's drift.

use bytemuck::{Pod, Zeroable};
use glam::{Mat4, Vec2, Vec3};

/// Per-pass values, laid out as the WGSL struct `Frame` in every shader.
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable)]
pub struct FrameUniforms {
    /// World-to-clip matrix, column-major.
    pub view_projection: [[f32; 4]; 4],
    /// 1 for the world as it is, -1 for its mirror image in the water (y negated).
    pub y_sign: f32,
    /// Unused; keeps `water_offset` 8-byte aligned.
    pub padding: f32,
    /// The water texture's offset, in texture repeats.
    pub water_offset: [f32; 2],
    /// The camera's position (world units), then 0.
    pub eye: [f32; 4],
}

impl FrameUniforms {
    /// The uniforms of the direct (`mirrored = false`) or mirrored pass seen from `eye`.
    pub fn new(view_projection: Mat4, mirrored: bool, water_offset: Vec2, eye: Vec3) -> Self {
        Self {
            view_projection: view_projection.to_cols_array_2d(),
            y_sign: if mirrored { -1.0 } else { 1.0 },
            padding: 0.0,
            water_offset: water_offset.to_array(),
            eye: eye.extend(0.0).to_array(),
        }
    }
}

/// The bind group layout of [`FrameUniforms`] (group 0, binding 0, vertex and fragment stages).
pub fn frame_layout(device: &wgpu::Device) -> wgpu::BindGroupLayout {
    device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("frame"),
        entries: &[wgpu::BindGroupLayoutEntry {
            binding: 0,
            visibility: wgpu::ShaderStages::VERTEX_FRAGMENT,
            ty: wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Uniform,
                has_dynamic_offset: false,
                min_binding_size: wgpu::BufferSize::new(size_of::<FrameUniforms>() as u64),
            },
            count: None,
        }],
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn layout_matches_the_wgsl_struct() {
        // mat4x4<f32> (64) + f32 + f32 + vec2<f32> + vec4<f32> = 96 bytes, a multiple of 16.
        assert_eq!(size_of::<FrameUniforms>(), 96);
        let mirrored = FrameUniforms::new(Mat4::IDENTITY, true, Vec2::new(0.25, 0.5), Vec3::ONE);
        assert_eq!(mirrored.y_sign, -1.0);
        assert_eq!(mirrored.water_offset, [0.25, 0.5]);
    }
}
