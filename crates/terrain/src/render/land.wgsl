// The terrain: colour map over the whole island, detail map repeated over it, combined
// ADD_SIGNED (colour + detail - 0.5). The mesh holds no part below the water (it is cut at
// y = 0 when built), so nothing needs discarding here, in the direct or the mirrored pass.

struct Land {
    // 1 / (width, depth) of the terrain's footprint: maps x, z to the colour map's u, v.
    inverse_extent: vec2<f32>,
    // Repeats of the detail map across the terrain.
    detail_repeat: f32,
    padding: f32,
}

@group(1) @binding(0) var<uniform> land: Land;
@group(1) @binding(1) var colour_map: texture_2d<f32>;
@group(1) @binding(2) var detail_map: texture_2d<f32>;
@group(1) @binding(3) var edge_clamp: sampler;
@group(1) @binding(4) var wrap: sampler;

struct LandVertex {
    @builtin(position) clip: vec4<f32>,
    @location(0) uv: vec2<f32>,
}

@vertex
fn vs_main(@location(0) position: vec3<f32>) -> LandVertex {
    var out: LandVertex;
    out.clip = to_clip(position);
    out.uv = position.xz * land.inverse_extent + vec2<f32>(0.5, 0.5);
    return out;
}

@fragment
fn fs_main(in: LandVertex) -> @location(0) vec4<f32> {
    let colour = textureSample(colour_map, edge_clamp, in.uv).rgb;
    let detail = textureSample(detail_map, wrap, in.uv * land.detail_repeat).rgb;
    return vec4<f32>(clamp(colour + detail - vec3<f32>(0.5), vec3<f32>(0.0), vec3<f32>(1.0)), 1.0);
}
