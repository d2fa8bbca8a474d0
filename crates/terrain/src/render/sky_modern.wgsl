// The modern look's sky: the atmosphere's colour along the view (`sky_colour`), drawn on the
// sky box's faces (whose painted texels it does not use). Appended to `sky.wgsl`.

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
    // The sun is far away: its glow is where the view points, wherever the eye is (the mirror
    // image is seen from the eye's mirror image).
    let eye = vec3<f32>(frame.eye.x, frame.eye.y * frame.y_sign, frame.eye.z);
    return vec4<f32>(sky_colour(normalize(in.point - eye)), 1.0);
}
