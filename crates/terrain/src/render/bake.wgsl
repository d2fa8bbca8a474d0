// The light map: for every heightmap sample (at mip level k, every 2^k samples), the sun's light
// on the ground there (the cosine of its angle of incidence times the fraction not shadowed by
// the land, from the shadow map) and how much of the sky the ground faces. Drawn once per sun
// direction, so a frame reads one texel where it would light every pixel: per-pixel normals at
// the heightmap's resolution, for the price of one texture sample.

struct Bake {
    // Samples per texel of the level being drawn (2^k), then 1 when the land casts shadows.
    span: u32,
    shadows: u32,
    padding0: u32,
    padding1: u32,
}

@group(1) @binding(2) var<uniform> bake: Bake;

@vertex
fn vs_bake(@builtin(vertex_index) vertex: u32) -> @builtin(position) vec4<f32> {
    // One triangle over the whole target.
    let xy = vec2<f32>(f32((vertex << 1u) & 2u), f32(vertex & 2u));
    return vec4<f32>(xy * 2.0 - vec2<f32>(1.0), 0.0, 1.0);
}

// The sun's light reaching `point`: the fraction of a 4x4 block of shadow-map texels around it
// whose depth is beyond the point's (a percentage-closer filter with soft edges).
fn soft_sunlight(point: vec3<f32>, normal: vec3<f32>) -> f32 {
    let offset_point = point + normal * 0.02;
    let clip = scene.shadow_matrix * vec4<f32>(offset_point, 1.0);
    let uv = vec2<f32>(clip.x * 0.5 + 0.5, 0.5 - clip.y * 0.5);
    let depth = clip.z - 0.0015;
    let step = scene.sky_box.w * 1.5;
    let low = vec2<f32>(0.0);
    let high = vec2<f32>(1.0);
    // Nine taps, each with the hardware's bilinear comparison: soft edges. (Written out: the
    // software Vulkan driver this is tested on crashes on such taps in loops or after an early
    // return.)
    var lit = textureSampleCompareLevel(shadow_map, shadow_sampler, clamp(uv, low, high), depth);
    lit += textureSampleCompareLevel(shadow_map, shadow_sampler, clamp(uv + vec2<f32>(-step, -step), low, high), depth);
    lit += textureSampleCompareLevel(shadow_map, shadow_sampler, clamp(uv + vec2<f32>(0.0, -step), low, high), depth);
    lit += textureSampleCompareLevel(shadow_map, shadow_sampler, clamp(uv + vec2<f32>(step, -step), low, high), depth);
    lit += textureSampleCompareLevel(shadow_map, shadow_sampler, clamp(uv + vec2<f32>(-step, 0.0), low, high), depth);
    lit += textureSampleCompareLevel(shadow_map, shadow_sampler, clamp(uv + vec2<f32>(step, 0.0), low, high), depth);
    lit += textureSampleCompareLevel(shadow_map, shadow_sampler, clamp(uv + vec2<f32>(-step, step), low, high), depth);
    lit += textureSampleCompareLevel(shadow_map, shadow_sampler, clamp(uv + vec2<f32>(0.0, step), low, high), depth);
    lit += textureSampleCompareLevel(shadow_map, shadow_sampler, clamp(uv + vec2<f32>(step, step), low, high), depth);
    // Outside the map nothing casts a shadow.
    let inside = all(uv >= low) && all(uv <= high) && clip.z <= 1.0;
    return select(1.0, lit / 9.0, inside);
}

@fragment
fn fs_bake(@builtin(position) position: vec4<f32>) -> @location(0) vec4<f32> {
    let span = bake.span;
    let texel = vec2<u32>(position.xy);
    let centre = min(texel * span + vec2<u32>(span / 2u), vec2<u32>(grid.columns - 1u, grid.rows - 1u));
    let reach = max(span / 2u, 1u);
    let left = select(0u, centre.x - reach, centre.x >= reach);
    let right = min(centre.x + reach, grid.columns - 1u);
    let up = select(0u, centre.y - reach, centre.y >= reach);
    let down = min(centre.y + reach, grid.rows - 1u);
    let slope_x = (sample_height(right, centre.y) - sample_height(left, centre.y)) / (f32(max(right - left, 1u)) * grid.cell);
    let slope_z = (sample_height(centre.x, down) - sample_height(centre.x, up)) / (f32(max(down - up, 1u)) * grid.cell);
    let normal = normalize(vec3<f32>(-slope_x, 1.0, -slope_z));
    let point = vec3<f32>(
        grid.origin.x + f32(centre.x) * grid.cell,
        sample_height(centre.x, centre.y),
        grid.origin.y + f32(centre.y) * grid.cell,
    );
    let shadow = soft_sunlight(point, normal);
    // A select, not a branch on the uniform (see `lighting.wgsl`).
    let sun = max(dot(normal, scene.sun_direction.xyz), 0.0) * select(1.0, shadow, bake.shadows != 0u);
    return vec4<f32>(sun, normal.y, 0.0, 1.0);
}
