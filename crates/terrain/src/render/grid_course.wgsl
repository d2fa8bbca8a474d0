// The course's shading of the terrain drawn as a grid (for maps too large for the static mesh):
// colour map plus detail map, ADD_SIGNED, and no land below the water (the grid is not cut at
// the waterline, so the fragments under it are discarded).

@group(1) @binding(2) var colour_map: texture_2d<f32>;
@group(1) @binding(3) var detail_map: texture_2d<f32>;
@group(1) @binding(4) var edge_clamp: sampler;
@group(1) @binding(5) var wrap: sampler;

@fragment
fn fs_main(in: GridVertex) -> @location(0) vec4<f32> {
    let colour = textureSample(colour_map, edge_clamp, in.uv).rgb;
    let detail = textureSample(detail_map, wrap, in.uv * grid.detail_repeat).rgb;
    // Sampled first: derivatives need every fragment of a quad.
    if (in.world.y < 0.0) {
        discard;
    }
    return vec4<f32>(clamp(colour + detail - vec3<f32>(0.5), vec3<f32>(0.0), vec3<f32>(1.0)), 1.0);
}
