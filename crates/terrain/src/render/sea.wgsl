// The modern look's water: a surface at y = 0 tilted by two scrolling wave normal maps. It
// reflects the land and the sky (a texture rendered from the mirrored camera, distorted by the
// waves) and shows the sea floor through shallow water, the two blended by Schlick's Fresnel
// term; the sun glints on it and foam lines the shore. The floor is found in the heightmap
// itself: the refracted ray is followed to the depth under the surface point, then to the
// depth where it lands.

@group(1) @binding(2) var colour_map: texture_2d<f32>;
@group(1) @binding(3) var wave_map_a: texture_2d<f32>;
@group(1) @binding(4) var wave_map_b: texture_2d<f32>;
@group(1) @binding(5) var reflection: texture_2d<f32>;
@group(1) @binding(6) var wrap: sampler;
@group(1) @binding(7) var edge_clamp: sampler;
@group(1) @binding(8) var light_map: texture_2d<f32>;

struct SeaVertex {
    @builtin(position) clip: vec4<f32>,
    @location(0) world: vec3<f32>,
    // The horizon's colour and the fog's amount (see `aerial`).
    @location(1) aerial: vec4<f32>,
    // The water's switches (`REFLECT_LAND`...), the same at every vertex. They come from the
    // vertex stage so that no branch of the fragment stage depends on uniforms alone (see
    // `lighting.wgsl`; `&` rather than `&&` below, which naga turns into such a branch).
    @location(2) @interpolate(flat) switches: u32,
}

// The water's switches.
const REFLECT_LAND: u32 = 1u;
const SEA_FLOOR: u32 = 2u;
const GLINT: u32 = 4u;
const FOAM: u32 = 8u;

@vertex
fn vs_main(@location(0) position: vec3<f32>) -> SeaVertex {
    var out: SeaVertex;
    out.clip = to_clip(position);
    out.world = position;
    out.aerial = aerial(frame.eye.xyz, position, length(position - frame.eye.xyz));
    out.switches = select(0u, REFLECT_LAND, scene.water_flags.y > 0.5)
        | select(0u, SEA_FLOOR, scene.wave_params.z > 0.5)
        | select(0u, GLINT, (scene.wave_params.w > 0.5) & (scene.sun_direction.w > 0.5))
        | select(0u, FOAM, scene.water_flags.x > 0.5);
    return out;
}

// The terrain's world height under (x, z), interpolated between the four samples around it;
// far below the water outside the heightmap.
fn floor_height(xz: vec2<f32>) -> f32 {
    let coordinates = (xz - grid.origin) / grid.cell;
    let last = vec2<f32>(f32(grid.columns - 1u), f32(grid.rows - 1u));
    if (any(coordinates < vec2<f32>(0.0)) || any(coordinates > last)) {
        return -100.0;
    }
    let base = min(vec2<u32>(floor(coordinates)), vec2<u32>(grid.columns - 2u, grid.rows - 2u));
    let f = coordinates - vec2<f32>(base);
    let h00 = sample_height(base.x, base.y);
    let h10 = sample_height(base.x + 1u, base.y);
    let h01 = sample_height(base.x, base.y + 1u);
    let h11 = sample_height(base.x + 1u, base.y + 1u);
    return mix(mix(h00, h10, f.x), mix(h01, h11, f.x), f.y);
}

const F0: f32 = 0.02;

@fragment
fn fs_main(in: SeaVertex) -> @location(0) vec4<f32> {
    let eye = frame.eye.xyz;
    let to_eye = eye - in.world;
    let distance = length(to_eye);
    let view = to_eye / distance;
    // Two wave normal maps (x and z slopes in r, g; foam in b) drifting apart.
    let tile = in.world.xz * scene.wave_params.x;
    let a = textureSample(wave_map_a, wrap, tile + scene.waves.xy);
    let b = textureSample(wave_map_b, wrap, tile * 1.37 + scene.waves.zw);
    // Far away the waves average out (and would only shimmer).
    let strength = scene.wave_params.y / (1.0 + 0.02 * distance);
    let slope = (a.rg + b.rg - vec2<f32>(1.0)) * 2.0 * strength;
    let normal = normalize(vec3<f32>(-slope.x, 1.0, -slope.y));
    let facing = max(dot(normal, view), 0.0);
    // Schlick's (1 - cos)^5 as products (pow would be exp2 and log2).
    let grazing = 1.0 - facing;
    let grazing2 = grazing * grazing;
    let fresnel = F0 + (1.0 - F0) * grazing2 * grazing2 * grazing;
    let shade = daylight();

    // What the surface reflects: the mirrored world (distorted by the waves) or the sky.
    var reflected: vec3<f32>;
    let size = scene.water_flags.zw;
    if ((in.switches & REFLECT_LAND) != 0u) {
        let uv = in.clip.xy / size + normal.xz * vec2<f32>(0.06, 0.06) / (1.0 + 0.15 * distance);
        reflected = textureSampleLevel(reflection, edge_clamp, clamp(uv, vec2<f32>(0.0), vec2<f32>(1.0)), 0.0).rgb;
    } else {
        reflected = sky_colour(reflect(-view, normal));
    }

    // What comes up from below: the sea floor fading into the water's colour with depth.
    let water = scene.water_colour.rgb * shade;
    var below = water;
    let depth = -floor_height(in.world.xz);
    if ((in.switches & SEA_FLOOR) != 0u && depth < 8.0 * scene.water_colour.w) {
        let down = refract(-view, normal, 1.0 / 1.33);
        let step_down = down / max(-down.y, 0.05);
        // Follow the refracted ray to the depth under the surface point, then to the depth
        // where it lands.
        var ground = in.world + step_down * max(depth, 0.0);
        ground = in.world + step_down * max(-floor_height(ground.xz), 0.0);
        let travelled = length(ground - in.world);
        let uv = ground.xz * grid.inverse_extent + vec2<f32>(0.5);
        let floor_colour = textureSampleLevel(colour_map, edge_clamp, uv, 0.0).rgb;
        let lit_floor = lit_surface(floor_colour, textureSampleLevel(light_map, edge_clamp, uv, 0.0).rg);
        // Red is absorbed first, blue last.
        let absorption = vec3<f32>(1.5, 1.0, 0.8) * (0.6931 / max(scene.water_colour.w, 1e-3));
        let transmitted = exp(-absorption * (travelled + max(-ground.y, 0.0)));
        below = lit_floor * transmitted + water * (vec3<f32>(1.0) - transmitted);
    }
    var colour = mix(below, reflected, fresnel);

    // The sun's glint: a sharp highlight of the waves' facets toward the sun.
    if ((in.switches & GLINT) != 0u) {
        let sun = scene.sun_direction.xyz;
        let half_vector = normalize(sun + view);
        let highlight = max(dot(normal, half_vector), 0.0);
        // Two powers of the highlight from one logarithm (pow takes one each); kept off log2(0),
        // which WGSL leaves undefined (both powers are 0 there to the last bit anyway).
        let log_highlight = log2(max(highlight, 1e-6));
        let glint = exp2(700.0 * log_highlight) * 6.0 + exp2(90.0 * log_highlight) * 0.25;
        if (glint > 1e-3) {
            colour += scene.sun_colour.rgb * glint * sunlight(in.world, vec3<f32>(0.0, 1.0, 0.0)) * step(0.0, sun.y);
        }
    }

    // Foam where the water is shallow, broken up by the wave maps' foam channel.
    if ((in.switches & FOAM) != 0u && depth > -0.02) {
        let shore = 1.0 - smoothstep(0.0, 0.06, depth);
        let pattern = smoothstep(0.5, 0.85, (a.b + b.b) * 0.5 + 0.3 * shore);
        let foam = clamp(shore * pattern * 1.5, 0.0, 1.0);
        colour = mix(colour, vec3<f32>(0.92, 0.95, 0.96) * shade, foam * 0.85);
    }

    return vec4<f32>(mix(colour, in.aerial.rgb, in.aerial.a), 1.0);
}
