// The modern look's terrain: the colour map (without baked shading where the world has one)
// with the detail map, lit by the sun (with the land's shadows) and the sky as the light map
// says (per heightmap sample, see `bake.wgsl`), faded into the sky's colour by the fog.

@group(1) @binding(2) var colour_map: texture_2d<f32>;
@group(1) @binding(3) var detail_map: texture_2d<f32>;
@group(1) @binding(4) var edge_clamp: sampler;
@group(1) @binding(5) var wrap: sampler;
@group(1) @binding(6) var light_map: texture_2d<f32>;

struct LitGridVertex {
    @builtin(position) clip: vec4<f32>,
    @location(0) world: vec3<f32>,
    @location(1) uv: vec2<f32>,
    // The horizon's colour and the fog's amount (see `aerial`).
    @location(2) aerial: vec4<f32>,
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
    return out;
}

fn shade(in: LitGridVertex) -> vec4<f32> {
    let colour = textureSample(colour_map, edge_clamp, in.uv).rgb;
    let detail = textureSample(detail_map, wrap, in.uv * grid.detail_repeat).rgb;
    let albedo = clamp(colour + detail - vec3<f32>(0.5), vec3<f32>(0.0), vec3<f32>(1.0));
    let lit = lit_surface(albedo, textureSample(light_map, edge_clamp, in.uv).rg);
    return vec4<f32>(mix(lit, in.aerial.rgb, in.aerial.a), 1.0);
}

@fragment
fn fs_main(in: LitGridVertex) -> @location(0) vec4<f32> {
    return shade(in);
}

// The mirrored land seen in the water: nothing that is under the water.
@fragment
fn fs_reflected(in: LitGridVertex) -> @location(0) vec4<f32> {
    let colour = shade(in);
    // Shaded first: derivatives need every fragment of a quad.
    if (in.world.y < 0.0) {
        discard;
    }
    return colour;
}
