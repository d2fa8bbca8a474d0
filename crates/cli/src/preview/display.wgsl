// The preview's image on screen: nearest image pixel under each window pixel (zoom and pan),
// linear values times the exposure, clamped to [0, 1] and encoded as sRGB. The target is a
// non-sRGB view, so the encoded values reach the screen as they are.

struct ViewUniforms {
    // Window pixels per image pixel.
    zoom: f32,
    // Linear factor (2^stops).
    exposure: f32,
    // The image's top-left corner in window pixels.
    offset: vec2<f32>,
    // The image's size in pixels.
    size: vec2<f32>,
    _pad: vec2<f32>,
};

@group(0) @binding(0) var<uniform> view: ViewUniforms;
@group(0) @binding(1) var image: texture_2d<f32>;

@vertex
fn vs_main(@builtin(vertex_index) index: u32) -> @builtin(position) vec4<f32> {
    // One triangle covering the window.
    let x = f32((index << 1u) & 2u) * 2.0 - 1.0;
    let y = f32(index & 2u) * 2.0 - 1.0;
    return vec4<f32>(x, y, 0.0, 1.0);
}

fn srgb(c: f32) -> f32 {
    if c <= 0.0031308 {
        return 12.92 * c;
    }
    return 1.055 * pow(c, 1.0 / 2.4) - 0.055;
}

@fragment
fn fs_main(@builtin(position) position: vec4<f32>) -> @location(0) vec4<f32> {
    let p = floor((position.xy - view.offset) / view.zoom);
    if p.x < 0.0 || p.y < 0.0 || p.x >= view.size.x || p.y >= view.size.y {
        return vec4<f32>(0.12, 0.12, 0.12, 1.0);
    }
    let linear = textureLoad(image, vec2<i32>(p), 0).rgb * view.exposure;
    let c = clamp(linear, vec3<f32>(0.0), vec3<f32>(1.0));
    return vec4<f32>(srgb(c.r), srgb(c.g), srgb(c.b), 1.0);
}
