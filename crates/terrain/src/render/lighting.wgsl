// The modern look's light, sky and fog, shared by its shaders (group 2, `lighting.rs`). The sky
// is the atmosphere's (`world::atmosphere`): a table of its colour by the view's azimuth from the
// sun (u, 0 to 180 degrees) and elevation (v, the square root of elevation / 90 degrees).
// World convention: y-up, the water is the plane y = 0. Colours are stored values (no sRGB
// decoding, as the course's textures are used); lighting is computed on their squares (a gamma
// of 2) and encoded back with a square root.
//
// No branch of these shaders depends on uniforms alone: Mesa 22's lavapipe inlines the values of
// such uniforms into the shader and compiles it again whenever its pipeline is bound, which cost
// 3-4 ms a frame. Switches are `select`s where both sides are cheap, and flat varyings set by the
// vertex stage where a branch saves work (`sea.wgsl`). `a && b` is such a branch too when `a` is
// a uniform's test (naga keeps WGSL's short circuit as an `if`). `uniform_branches.rs` checks it.

struct Scene {
    // Toward the sun (unit), w: 1 when the land is lit (0: the colour map as it is).
    sun_direction: vec4<f32>,
    // The sun's colour times its intensity, w: 1 when the land casts shadows.
    sun_colour: vec4<f32>,
    // The sky dome's light (linear, times the ambient strength), w: unused.
    sky_light: vec4<f32>,
    // x: fog density at the water per unit, y: height falloff per unit, z: 1 when fog is on,
    // w: seconds (wrapped) for the foam's drift.
    fog: vec4<f32>,
    // Deep water colour (stored values), w: depth in units at which the floor fades to half.
    water_colour: vec4<f32>,
    // The two wave normal maps' offsets, in tiles: xy and zw.
    waves: vec4<f32>,
    // x: 1 / world units a wave tile spans, y: wave strength, z: 1 when the sea floor shows,
    // w: 1 when the sun glints.
    wave_params: vec4<f32>,
    // x: 1 when foam lines the shore, y: 1 when the land's reflection is drawn, z, w: the frame's
    // size in pixels.
    water_flags: vec4<f32>,
    // World to the shadow map's clip space (orthographic, from the sun).
    shadow_matrix: mat4x4<f32>,
    // Half the sky box's width (x) and depth (z), its height (y), w: 1 / the shadow map's side.
    sky_box: vec4<f32>,
    // Toward the sun (unit; `sun_direction` is the light that casts shadows, the moon at night),
    // w: how bright the scene is against a sunny day (0.05 to 1).
    sky_sun: vec4<f32>,
    // The sun's disc colour (stored values), w: 0 by day to 1 at night (the moon's disc).
    sun_disc: vec4<f32>,
    // The ground's materials: x: 1 when on (the land's pipelines are built for it, see
    // `GROUND_MATERIALS`), y: 1 - cos(the rock's slope), z: the snow line and
    // w: the sand line (world y; far below the land without a sea).
    ground: vec4<f32>,
    // x: 1 / world units a tile of the material noise spans, y: the detail normals' strength,
    // z: the land's highest point (world y), w: unused.
    ground_scale: vec4<f32>,
}

@group(2) @binding(0) var<uniform> scene: Scene;
@group(2) @binding(1) var sky_view: texture_2d<f32>;
@group(2) @binding(2) var sky_sampler: sampler;
@group(2) @binding(3) var shadow_map: texture_depth_2d;
@group(2) @binding(4) var shadow_sampler: sampler_comparison;

// Stored value to linear (gamma 2) and back.
fn to_linear(c: vec3<f32>) -> vec3<f32> {
    return c * c;
}

fn to_stored(c: vec3<f32>) -> vec3<f32> {
    return sqrt(max(c, vec3<f32>(0.0)));
}

// How much daylight there is: 1 on a sunny day, less at dusk, 0.05 or more at night.
fn daylight() -> f32 {
    return scene.sky_sun.w;
}

const PI: f32 = 3.14159265;

// The sky's colour (stored values) seen along `direction` (unit, from the eye; below the
// horizon, the horizon's), with the sun's disc and, at night, the full moon's opposite it.
fn sky_colour(direction: vec3<f32>) -> vec3<f32> {
    let sun = scene.sky_sun.xyz;
    let flat_view = normalize(vec2<f32>(direction.x, direction.z) + vec2<f32>(1e-5, 0.0));
    let flat_sun = normalize(vec2<f32>(sun.x, sun.z) + vec2<f32>(1e-5, 0.0));
    let u = acos(clamp(dot(flat_view, flat_sun), -1.0, 1.0)) / PI;
    let v = sqrt(asin(clamp(direction.y, 0.0, 1.0)) / (0.5 * PI));
    var colour = textureSampleLevel(sky_view, sky_sampler, vec2<f32>(u, v), 0.0).rgb;
    // Discs of about 0.8 degrees (larger than life, to read on screen).
    let facing = dot(direction, sun);
    let sun_disc = smoothstep(0.99985, 0.99992, facing);
    colour = mix(colour, scene.sun_disc.rgb, sun_disc * step(0.0, direction.y));
    let moon_disc = smoothstep(0.99985, 0.99992, -facing) * scene.sun_disc.w;
    colour = mix(colour, vec3<f32>(0.80, 0.83, 0.90), moon_disc * step(0.0, direction.y));
    return colour;
}

// The sky at the horizon in the direction from `eye` to `point` (seen horizontally): the colour
// the world fades into far away (the air's light along the view, toward the sun or away).
fn horizon_colour(eye: vec3<f32>, point: vec3<f32>) -> vec3<f32> {
    let ray = point.xz - eye.xz;
    let length_xz = length(ray);
    let d = select(vec2<f32>(0.0, -1.0), ray / max(length_xz, 1e-6), length_xz > 1e-6);
    return sky_colour(vec3<f32>(d.x, 0.0, d.y));
}

// How much of the colour at `point` seen from `eye` the fog replaces (0 to 1): exponential
// height fog integrated along the line of sight, and, whatever the fog, a fade into the horizon
// as the point nears the sky box's walls (so the world meets the sky without a seam).
// `path_length` is the distance light travels (longer than |point - eye| for a reflection).
fn fog_amount(eye: vec3<f32>, point: vec3<f32>, path_length: f32) -> f32 {
    let a = scene.fog.x;
    let b = max(scene.fog.y, 1e-4);
    let y0 = max(eye.y, 0.0);
    let y1 = max(point.y, 0.0);
    let dy = y1 - y0;
    // The integral of a exp(-b y) along the path, divided by its length.
    var mean_density = a * exp(-b * y0);
    if (abs(dy) > 1e-3) {
        mean_density = a * (exp(-b * y0) - exp(-b * y1)) / (b * dy);
    }
    var amount = select(0.0, 1.0 - exp(-mean_density * path_length), scene.fog.z > 0.5);
    // Where the walls are in this direction, and how far along the point is.
    let half_size = scene.sky_box.xz;
    let ray = point.xz - eye.xz;
    let length_xz = length(ray);
    if (length_xz > 1e-4) {
        let d = ray / length_xz;
        let to_x = select((-half_size.x - eye.x) / d.x, (half_size.x - eye.x) / d.x, d.x > 0.0);
        let to_z = select((-half_size.y - eye.z) / d.y, (half_size.y - eye.z) / d.y, d.y > 0.0);
        let reach = min(select(1e9, to_x, abs(d.x) > 1e-6), select(1e9, to_z, abs(d.y) > 1e-6));
        amount = max(amount, smoothstep(0.45, 1.0, length_xz / max(reach, 1e-3)));
    }
    return clamp(amount, 0.0, 1.0);
}

// Fraction of the sun's light reaching `point` (0 in the land's shadow, 1 in the open), from
// the shadow map with the hardware's bilinear comparison; `normal` offsets the lookup against
// acne. (No early return before the sample: Mesa 22's lavapipe crashes on that.)
fn sunlight(point: vec3<f32>, normal: vec3<f32>) -> f32 {
    let clip = scene.shadow_matrix * vec4<f32>(point + normal * 0.02, 1.0);
    let uv = vec2<f32>(clip.x * 0.5 + 0.5, 0.5 - clip.y * 0.5);
    let lit = textureSampleCompareLevel(shadow_map, shadow_sampler, clamp(uv, vec2<f32>(0.0), vec2<f32>(1.0)), clip.z - 0.0015);
    let inside = all(uv >= vec2<f32>(0.0)) && all(uv <= vec2<f32>(1.0)) && clip.z <= 1.0;
    return select(1.0, lit, inside && scene.sun_colour.w > 0.5);
}

// A surface of colour `albedo` (stored values) lit as the light map says (`light`: the sun's
// light on it, with shadows, and how much of the sky it faces; see `bake.wgsl`); returns stored
// values.
fn lit_surface(albedo: vec3<f32>, light: vec2<f32>) -> vec3<f32> {
    // Sky light from above, a little bounce from the ground below.
    let sky = scene.sky_light.rgb * (0.6 + 0.4 * light.y);
    let lit = to_stored(to_linear(albedo) * (scene.sun_colour.rgb * light.x + sky));
    return select(albedo, lit, scene.sun_direction.w > 0.5);
}

// The aerial perspective of `point` seen from `eye`: the horizon's colour in its direction (rgb)
// and how much of the point's own colour it replaces (a). It changes slowly across a surface, so
// shaders compute it per vertex. `path_length` is the distance light travels.
fn aerial(eye: vec3<f32>, point: vec3<f32>, path_length: f32) -> vec4<f32> {
    return vec4<f32>(horizon_colour(eye, point), fog_amount(eye, point, path_length));
}
