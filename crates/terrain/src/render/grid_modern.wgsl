// The modern look's terrain: the ground's materials (rock, scree, grass and soil, sand, snow)
// chosen from the land's shape and blended by their relief, projected from three sides where the
// ground is steep, with their relief on the light (detail normals); lit by the sun (with the
// land's shadows) and the sky as the light map says (per heightmap sample, see `bake.wgsl`),
// faded into the sky's colour by the fog. With the materials off: the colour map (without baked
// shading where the world has one) with the detail map.

// Whether the ground's materials are drawn: a constant of the pipeline (one pipeline each way),
// because lavapipe, which runs the shader on the CPU, works out both sides of a `select` and
// would pay for the materials' samples with them off and for the colour map's detail with them on.
override GROUND_MATERIALS: bool = true;

@group(1) @binding(2) var colour_map: texture_2d<f32>;
@group(1) @binding(3) var detail_map: texture_2d<f32>;
@group(1) @binding(4) var edge_clamp: sampler;
@group(1) @binding(5) var wrap: sampler;
@group(1) @binding(6) var light_map: texture_2d<f32>;

// The land's shape (`world::ground::ground_map`): normal x and z, curvature, flow.
@group(3) @binding(0) var ground_map: texture_2d<f32>;
// The materials' noise (`world::ground::material_noise`): grain, patches, strata, pebbles.
@group(3) @binding(1) var material_noise: texture_2d<f32>;
@group(3) @binding(2) var noise_wrap: sampler;

struct LitGridVertex {
    @builtin(position) clip: vec4<f32>,
    @location(0) world: vec3<f32>,
    @location(1) uv: vec2<f32>,
    // The horizon's colour and the fog's amount (see `aerial`).
    @location(2) aerial: vec4<f32>,
    // The land's smooth normal here (from the shape map).
    @location(3) normal: vec3<f32>,
    // The materials' shares from the land's shape: rock, scree, sand, snow (grass the rest).
    @location(4) shares: vec4<f32>,
    // Where water gathers (the erosion's flow and hollows), 0 to 1.
    @location(5) wet: f32,
}

@vertex
fn vs_lit(@location(0) corner: vec4<u32>, @location(1) node: vec4<u32>) -> LitGridVertex {
    let world = grid_point(corner, node);
    var out: LitGridVertex;
    out.clip = to_clip(world);
    out.world = world;
    out.uv = world.xz * grid.inverse_extent + vec2<f32>(0.5, 0.5);
    let eye = frame.eye.xyz;
    // In the mirror image the light travels from the point to the water and up to the eye.
    let seen = vec3<f32>(world.x, world.y * frame.y_sign, world.z);
    out.aerial = aerial(eye, world, length(seen - eye));
    // The land's shape and the materials' shares change slowly across the ground: worked out per
    // vertex (the nearest patches have a vertex per heightmap sample).
    let shape = textureSampleLevel(ground_map, edge_clamp, out.uv, 0.0);
    let nxz = shape.rg * 2.0 - vec2<f32>(1.0);
    let normal = normalize(vec3<f32>(nxz.x, sqrt(max(1.0 - dot(nxz, nxz), 0.0)), nxz.y));
    let curvature = shape.b * 2.0 - 1.0;
    let flow = shape.a;
    // Patches at a coarser scale: the detail map, repeated a few times over the terrain.
    let broad = textureSampleLevel(detail_map, wrap, out.uv * grid.detail_repeat, 0.0).g;
    let slope = 1.0 - normal.y;
    let height = world.y;
    let rock_slope = scene.ground.y;
    let top = scene.ground_scale.z;
    let rock = smoothstep(rock_slope * 0.85, rock_slope * 1.15, slope + 0.12 * rock_slope * (broad - 0.5));
    // Scree: the moderately steep hollows below the cliffs.
    let scree = smoothstep(rock_slope * 0.35, rock_slope * 0.7, slope) * smoothstep(-0.05, 0.35, curvature) * (1.0 - rock);
    let band = 0.3 * abs(scene.ground.w) + 1e-4;
    let sand = (1.0 - smoothstep(scene.ground.w - band, scene.ground.w + band, height + 0.02 * top * (broad - 0.5)))
        * (1.0 - smoothstep(0.1, 0.25, slope));
    // The snow line drops on slopes facing north (-z) and with the patches; steep slopes shed it.
    let line = scene.ground.z + 0.12 * top * normal.z + 0.08 * top * (broad - 0.5);
    let snow = smoothstep(line - 0.03 * top, line + 0.03 * top, height)
        * (1.0 - smoothstep(rock_slope * 1.1, rock_slope * 1.6, slope));
    out.normal = normal;
    out.shares = vec4<f32>(rock * (1.0 - snow), scree * (1.0 - snow), sand * (1.0 - rock) * (1.0 - snow), snow);
    out.wet = clamp(flow * 1.2 + 0.3 * max(curvature, 0.0), 0.0, 1.0);
    return out;
}

// A material's weight raised by its relief where it is present: the blend keeps only what
// stands highest (within a small depth), so transitions follow the stones and the grass rather
// than fading softly.
fn relief(weight: f32, height: f32) -> f32 {
    return select(-1.0, weight + 0.6 * height, weight > 0.002);
}

// `full`: the land as seen directly (a constant at each call: the reflection, seen through waves
// at a fraction of the frame's size, takes its materials from above only, without their relief
// on the light).
fn shade(in: LitGridVertex, full: bool) -> vec4<f32> {
    let colour = textureSample(colour_map, edge_clamp, in.uv).rgb;
    let detail = textureSample(detail_map, wrap, in.uv * grid.detail_repeat).rgb;
    let light = textureSample(light_map, edge_clamp, in.uv).rg;
    let plain = clamp(colour + detail - vec3<f32>(0.5), vec3<f32>(0.0), vec3<f32>(1.0));

    let normal = normalize(in.normal);
    // The noise seen from above and from the side the ground faces most (x or z), weighted by
    // how much the ground faces each: no stretching on cliffs ("biplanar" mapping, two samples
    // where triplanar takes three).
    let p = in.world * scene.ground_scale.x;
    let facing = abs(normal);
    let toward_x = facing.x > facing.z;
    let side = max(facing.x, facing.z);
    let weights = vec2<f32>(facing.y, side) * vec2<f32>(facing.y, side);
    let planes = (weights * weights) / (weights.x * weights.x + weights.y * weights.y);
    let dp_dx = dpdx(p);
    let dp_dy = dpdy(p);
    let from_top = textureSample(material_noise, noise_wrap, p.xz);
    let from_side = textureSample(material_noise, noise_wrap, vec2<f32>(select(p.x, p.z, toward_x), -p.y));
    let noise = select(from_top, from_top * planes.x + from_side * planes.y, full);
    let w_rock = in.shares.x;
    let w_scree = in.shares.y;
    let w_sand = in.shares.z;
    let w_snow = in.shares.w;
    let w_grass = max(1.0 - w_rock - w_scree - w_sand - w_snow, 0.0);

    // Height-based blending: each material's relief from the noise.
    let h_rock = noise.b;
    let h_scree = noise.a;
    let h_grass = noise.r * 0.7 + 0.15;
    let h_sand = noise.g * 0.3;
    let h_snow = noise.g * 0.4 + 0.3;
    let r = vec4<f32>(relief(w_rock, h_rock), relief(w_scree, h_scree), relief(w_grass, h_grass), relief(w_sand, h_sand));
    let r_snow = relief(w_snow, h_snow);
    let highest = max(max(max(r.x, r.y), max(r.z, r.w)), r_snow);
    let depth = 0.12;
    let b = max(r - vec4<f32>(highest - depth), vec4<f32>(0.0));
    let b_snow = max(r_snow - (highest - depth), 0.0);
    let total = b.x + b.y + b.z + b.w + b_snow + 1e-5;

    // The materials' colours (stored values).
    let rock_colour = mix(vec3<f32>(0.40, 0.37, 0.34), vec3<f32>(0.58, 0.55, 0.50), noise.b) * (0.85 + 0.3 * noise.r);
    let scree_colour = mix(vec3<f32>(0.45, 0.43, 0.40), vec3<f32>(0.66, 0.63, 0.58), noise.a) * (0.9 + 0.2 * noise.r);
    // Grass takes the colour map's colours; where water gathers (the erosion's flow) and in
    // hollows, darker soil shows.
    let soil = vec3<f32>(0.38, 0.30, 0.22) * (0.85 + 0.3 * noise.r);
    let wet = in.wet * smoothstep(0.35, 0.65, noise.g + 0.3 * in.wet);
    let grass_colour = mix(clamp(colour + (noise.r - 0.5) * 0.25, vec3<f32>(0.0), vec3<f32>(1.0)), soil, wet * 0.8);
    let sand_colour = vec3<f32>(0.78, 0.71, 0.54) * (0.92 + 0.16 * noise.r);
    let snow_colour = vec3<f32>(0.93, 0.95, 0.98) * (0.96 + 0.04 * noise.r);
    let blended = (rock_colour * b.x + scree_colour * b.y + grass_colour * b.z + sand_colour * b.w + snow_colour * b_snow) / total;
    let bump = (h_rock * b.x + h_scree * b.y + h_grass * b.z + h_sand * b.w + h_snow * b_snow) / total;

    // Detail normals: the relief's gradient across the surface from its screen derivatives
    // (Mikkelsen, "Bump Mapping Unparametrized Surfaces on the GPU", 2010).
    // (dp_dx, dp_dy of `p` are the world position's, scaled alike: the scale cancels.)
    let amplitude = select(0.0, scene.ground_scale.y * 0.04, full);
    let r1 = cross(dp_dy, normal);
    let r2 = cross(normal, dp_dx);
    let det = dot(dp_dx, r1);
    let gradient = sign(det) * (dpdx(bump) * r1 + dpdy(bump) * r2) * amplitude;
    let detailed = normalize(abs(det) * normal - gradient + vec3<f32>(0.0, 1e-12, 0.0));
    // The light map's sun term is for the smooth normal: rescale it for the detailed one.
    let key = scene.sun_direction.xyz;
    let relit = clamp(max(dot(detailed, key), 0.0) / max(dot(normal, key), 0.12), 0.0, 2.0);

    let on = GROUND_MATERIALS;
    let albedo = select(plain, blended, on);
    let sun_light = select(light.x, light.x * relit, on);
    let lit = lit_surface(albedo, vec2<f32>(sun_light, light.y));
    return vec4<f32>(mix(lit, in.aerial.rgb, in.aerial.a), 1.0);
}

@fragment
fn fs_main(in: LitGridVertex) -> @location(0) vec4<f32> {
    return shade(in, true);
}

// The mirrored land seen in the water: nothing that is under the water.
@fragment
fn fs_reflected(in: LitGridVertex) -> @location(0) vec4<f32> {
    let colour = shade(in, false);
    // Shaded first: derivatives need every fragment of a quad.
    if (in.world.y < 0.0) {
        discard;
    }
    return colour;
}
