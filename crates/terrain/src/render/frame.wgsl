// Shared by every shader (prepended to it): the per-pass uniforms of `uniforms.rs`.
// World convention: y-up, the water is the plane y = 0.

struct Frame {
    // World-to-clip matrix.
    view_projection: mat4x4<f32>,
    // 1 for the world as it is, -1 for its mirror image in the water.
    y_sign: f32,
    padding: f32,
    // The water texture's offset, in texture repeats.
    water_offset: vec2<f32>,
    // The camera's position (world), w: unused.
    eye: vec4<f32>,
}

@group(0) @binding(0) var<uniform> frame: Frame;

// The clip position of a world point, mirrored in y = 0 in the mirrored pass.
fn to_clip(world: vec3<f32>) -> vec4<f32> {
    return frame.view_projection * vec4<f32>(world.x, world.y * frame.y_sign, world.z, 1.0);
}
