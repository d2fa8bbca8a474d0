//! The modern look's ground on the software GPU: a cliff seen from the side shows its texture at
//! the same grain as flat ground seen from above, not stretched down the slope (the noise
//! projected from the side too), while the colour map's top-down projection (materials off) does stretch it; and
//! the materials follow the land (rock on the cliff, grass on the flat, snow high up).

mod common;

use common::{gpu, project, render_with, view_from};
use image::{Rgba, RgbaImage};
use terrain::SceneConfig;
use terrain::headless::HeadlessRenderer;
use terrain::render::{Backend, FrameView};
use terrain::settings::Settings;
use terrain::world::{Heightmap, SkyBox, World};

const SIZE: (u32, u32) = (320, 240);

/// A 65 x 65 world: low ground (level 120, y = 0.3) west of a cliff rising over one cell (x from
/// -0.31 to 0, about 80 degrees) to a high plateau (level 250, y = 2.25), a grey colour map and a detail map of random speckles (the
/// texture the colour map's projection would stretch).
fn cliff_world() -> World {
    let n = 65u32;
    let levels = (0..n * n)
        .map(|i| {
            let column = i % n;
            if column <= 31 { 120.0 } else { 250.0 }
        })
        .collect();
    let flat = |c: [u8; 3], side: u32| RgbaImage::from_pixel(side, side, Rgba([c[0], c[1], c[2], 255]));
    let mut state = 12345u32;
    let speckles = RgbaImage::from_fn(64, 64, |_, _| {
        state = state.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
        let v = 64 + (state >> 24) as u8 / 2;
        Rgba([v, v, v, 255])
    });
    let sky = flat([150, 180, 220], 8);
    World {
        heightmap: Heightmap::new(n, n, levels).expect("valid"),
        colour_map: flat([110, 140, 70], 16),
        detail_map: speckles,
        sky: SkyBox { sides: [sky.clone(), sky.clone(), sky.clone(), sky.clone()], top: sky },
        water: flat([0, 0, 255], 8),
        unlit: None,
        elevation: None,
        erosion: None,
    }
}

/// Luminance gradients of a square patch of `half` pixels around `centre`: the mean absolute
/// difference between vertical neighbours, then between horizontal ones.
fn gradients(image: &RgbaImage, centre: (u32, u32), half: u32) -> (f32, f32) {
    let lum = |x: u32, y: u32| {
        let Rgba(p) = *image.get_pixel(x, y);
        0.3 * f32::from(p[0]) + 0.59 * f32::from(p[1]) + 0.11 * f32::from(p[2])
    };
    let (mut vertical, mut horizontal, mut count) = (0.0, 0.0, 0.0);
    for y in centre.1 - half..centre.1 + half {
        for x in centre.0 - half..centre.0 + half {
            vertical += (lum(x, y + 1) - lum(x, y)).abs();
            horizontal += (lum(x + 1, y) - lum(x, y)).abs();
            count += 1.0;
        }
    }
    (vertical / count, horizontal / count)
}

fn plain_light(materials: bool) -> Settings {
    let mut settings = Settings::default();
    settings.fog.enabled = false;
    settings.sun.shadows = false;
    // Light from straight above the cliff's foot, a little from the west: both faces lit.
    settings.sun.elevation_degrees = 60.0;
    settings.sun.azimuth_degrees = 270.0;
    settings.ground.materials = materials;
    settings
}

fn pixel(image: &RgbaImage, view: &FrameView, point: [f32; 3]) -> (u32, u32) {
    project(image, view, point).expect("point on screen")
}

#[test]
fn a_cliff_shows_no_stretched_texture() {
    let Some(gpu) = gpu(Backend::Vulkan) else { return };
    let world = cliff_world();
    // The cliff's face (facing west), seen head-on from the west, and the
    // low ground seen from straight above, from about the same distance.
    let side = view_from([-3.0, 1.3, 0.0], 90.0, 0.0);
    let above = view_from([-5.0, 3.3, 0.0], 0.0, -89.0);
    let face = [-0.15, 1.3, 0.0];
    let ground = [-5.0, 0.3, 0.0];
    let mut anisotropy = Vec::new();
    for materials in [true, false] {
        let settings = plain_light(materials);
        let cliff_image = render_with(gpu, &world, &settings, SIZE, &side);
        let flat_image = render_with(gpu, &world, &settings, SIZE, &above);
        let (cliff_v, cliff_h) = gradients(&cliff_image, pixel(&cliff_image, &side, face), 12);
        let (flat_v, flat_h) = gradients(&flat_image, pixel(&flat_image, &above, ground), 12);
        // How much finer the texture is down the slope than across it, on the cliff against
        // the flat ground (1: the same grain).
        let ratio = (cliff_v / cliff_h.max(1e-3)) / (flat_v / flat_h.max(1e-3));
        eprintln!(
            "materials {materials}: cliff {cliff_v:.2} down, {cliff_h:.2} across; flat {flat_v:.2}, {flat_h:.2}; ratio {ratio:.2}"
        );
        anisotropy.push((ratio, cliff_v + cliff_h, flat_v + flat_h));
    }
    let (with_materials, cliff_detail, flat_detail) = anisotropy[0];
    assert!(
        // (Above 1: the rock's strata run across the slope.)
        (0.5..=4.0).contains(&with_materials),
        "the cliff's texture is stretched: {with_materials:.2} times as fine down the slope as on flat ground"
    );
    // The cliff has texture of about the flat ground's strength (not smeared to nothing).
    assert!(cliff_detail > 0.4 * flat_detail, "cliff {cliff_detail:.2} vs flat {flat_detail:.2}");
    // The measure sees the stretching of a top-down projection.
    let (top_down, _, _) = anisotropy[1];
    assert!(top_down < 0.5, "the colour map's projection should stretch the cliff: {top_down:.2}");
}

#[test]
fn materials_follow_the_land() {
    let Some(gpu) = gpu(Backend::Vulkan) else { return };
    let world = cliff_world();
    let side = view_from([-7.0, 4.0, 0.0], 90.0, -25.0);
    let mut settings = plain_light(true);
    // Snow on the high plateau only.
    settings.ground.snow_line = 0.9;
    let image = render_with(gpu, &world, &settings, SIZE, &side);
    let colour = |point: [f32; 3]| {
        let (x, y) = pixel(&image, &side, point);
        let Rgba(p) = *image.get_pixel(x, y);
        [p[0], p[1], p[2]].map(f32::from)
    };
    let grass = colour([-3.0, 0.3, 0.3]);
    let rock = colour([-0.15, 1.0, 0.4]);
    let snow = colour([3.0, 2.25, 0.0]);
    // Grass is green; rock is grey (no channel far from the others); snow is bright and white.
    assert!(grass[1] > grass[0] + 15.0 && grass[1] > grass[2] + 15.0, "grass {grass:?}");
    let spread =
        rock.iter().copied().fold(f32::MIN, f32::max) - rock.iter().copied().fold(f32::MAX, f32::min);
    assert!(spread < 30.0, "rock {rock:?}");
    assert!(snow.iter().all(|&c| c > 170.0), "snow {snow:?}");
}

/// The land's pipelines are built for the materials on or off (`GROUND_MATERIALS`): switching
/// them on a running renderer builds them again, and gives the pictures a renderer made with
/// either setting draws.
#[test]
fn switching_the_materials_rebuilds_the_land() {
    let Some(gpu) = gpu(Backend::Vulkan) else { return };
    let world = cliff_world();
    let view = view_from([-3.0, 1.3, 0.0], 90.0, 0.0);
    let (on, off) = (plain_light(true), plain_light(false));
    let mut headless =
        HeadlessRenderer::new(gpu, &world, &SceneConfig::default(), &on, SIZE.0, SIZE.1).expect("renderer");
    let first = headless.render(gpu, &view).expect("renders");
    headless.renderer_mut().apply(gpu, &world, &off).expect("switches");
    let plain = headless.render(gpu, &view).expect("renders");
    headless.renderer_mut().apply(gpu, &world, &on).expect("switches back");
    let again = headless.render(gpu, &view).expect("renders");
    assert!(first != plain, "switching the materials off changed nothing");
    assert!(first == again, "the materials switched back on draw another picture");
    assert!(
        plain == render_with(gpu, &world, &off, SIZE, &view),
        "not the picture of a renderer made without them"
    );
    assert!(
        first == render_with(gpu, &world, &on, SIZE, &view),
        "not the picture of a renderer made with them"
    );
}

/// The land's pipeline constant (`GROUND_MATERIALS`) reaches the OpenGL backend too (the web
/// page's WebGL2 goes through it): there the materials draw as they do on Vulkan.
#[test]
fn gl_draws_the_materials_as_vulkan_does() {
    let Some(vulkan) = gpu(Backend::Vulkan) else { return };
    let Some(gl) = gpu(Backend::Gl) else { return };
    let world = cliff_world();
    let view = view_from([-3.0, 1.3, 0.0], 90.0, 0.0);
    for materials in [true, false] {
        let settings = plain_light(materials);
        let on_vulkan = render_with(vulkan, &world, &settings, SIZE, &view);
        let on_gl = render_with(gl, &world, &settings, SIZE, &view);
        let (d, _) = common::difference(&on_vulkan, &on_gl);
        eprintln!("materials {materials}: {d:?}");
        assert!(d.mean < 0.5 && d.outliers < 0.01, "materials {materials}: {d:?}");
    }
}
