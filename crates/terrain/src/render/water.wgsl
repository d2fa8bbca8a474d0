// The water: a plane at y = 0 over the sky box's floor, its texture repeated and drifting with
// time, drawn translucent over the mirrored world.

struct Water {
    // Opacity of the water.
    alpha: f32,
    padding0: f32,
    padding1: f32,
    padding2: f32,
}

@group(1) @binding(0) var<uniform> water: Water;
@group(1) @binding(1) var water_texture: texture_2d<f32>;
@group(1) @binding(2) var wrap: sampler;

struct WaterVertex {
    @builtin(position) clip: vec4<f32>,
    @location(0) uv: vec2<f32>,
}

@vertex
fn vs_main(@location(0) position: vec3<f32>, @location(1) uv: vec2<f32>) -> WaterVertex {
    var out: WaterVertex;
    out.clip = to_clip(position);
    out.uv = uv + frame.water_offset;
    return out;
}

@fragment
fn fs_main(in: WaterVertex) -> @location(0) vec4<f32> {
    return vec4<f32>(textureSample(water_texture, wrap, in.uv).rgb, water.alpha);
}
