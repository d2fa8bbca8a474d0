// The sky box: five faces sampled from one texture array (layer 0..3 the walls, 4 the top).

@group(1) @binding(0) var faces: texture_2d_array<f32>;
@group(1) @binding(1) var edge_clamp: sampler;

struct SkyVertex {
    @builtin(position) clip: vec4<f32>,
    @location(0) uv: vec2<f32>,
    @location(1) @interpolate(flat) layer: u32,
}

@vertex
fn vs_main(@location(0) position: vec3<f32>, @location(1) uv: vec2<f32>, @location(2) layer: u32) -> SkyVertex {
    var out: SkyVertex;
    out.clip = to_clip(position);
    out.uv = uv;
    out.layer = layer;
    return out;
}

@fragment
fn fs_main(in: SkyVertex) -> @location(0) vec4<f32> {
    return vec4<f32>(textureSample(faces, edge_clamp, in.uv, in.layer).rgb, 1.0);
}
