// The modern look's sky: the sky box (without a painted sun where the world has such a sky),
// graded for the sun of the settings: its glow and disc, darker and warm toward it as it sets.
// Appended to `sky.wgsl`, whose bindings it uses.

struct ModernSkyVertex {
    @builtin(position) clip: vec4<f32>,
    @location(0) uv: vec2<f32>,
    @location(1) @interpolate(flat) layer: u32,
    // The point on the box (not mirrored).
    @location(2) point: vec3<f32>,
}

@vertex
fn vs_modern(@location(0) position: vec3<f32>, @location(1) uv: vec2<f32>, @location(2) layer: u32) -> ModernSkyVertex {
    var out: ModernSkyVertex;
    out.clip = to_clip(position);
    out.uv = uv;
    out.layer = layer;
    out.point = position;
    return out;
}

@fragment
fn fs_modern(in: ModernSkyVertex) -> @location(0) vec4<f32> {
    let stored = textureSample(faces, edge_clamp, in.uv, in.layer).rgb;
    // The sun is far away: its glow is where the view points, wherever the eye is (the mirror
    // image is seen from the eye's mirror image).
    let eye = vec3<f32>(frame.eye.x, frame.eye.y * frame.y_sign, frame.eye.z);
    return vec4<f32>(graded_sky(stored, normalize(in.point - eye)), 1.0);
}
