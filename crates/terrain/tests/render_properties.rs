//! What the renderer draws, checked on a world of flat marker colours (land red, sky green,
//! water blue), on the software GPU: no terrain under the water, the terrain's and the sky's
//! mirror images in the water, ADD_SIGNED detail, drifting water, and the two backends agreeing.

mod common;

use common::{gpu, marker_world, project, render, view_from};
use image::{Rgba, RgbaImage};
use terrain::headless::{HeadlessRenderer, OffscreenTarget};
use terrain::render::{Backend, LandDrawPath, Renderer, draw_names};
use terrain::{Look, SceneConfig, Settings};

const SIZE: (u32, u32) = (160, 96);

fn near(pixel: Rgba<u8>, expected: [u8; 3], tolerance: u8) -> bool {
    (0..3).all(|c| pixel.0[c].abs_diff(expected[c]) <= tolerance)
}

fn at(image: &RgbaImage, view: &terrain::render::FrameView, point: [f32; 3]) -> Rgba<u8> {
    let (x, y) = project(image, view, point).expect("point on screen");
    *image.get_pixel(x, y)
}

/// Water over the mirrored sky: 0.8 blue + 0.2 green.
const WATER_OVER_SKY: [u8; 3] = [0, 51, 204];
/// Water over the mirrored land: 0.8 blue + 0.2 red.
const WATER_OVER_LAND: [u8; 3] = [51, 0, 204];

#[test]
fn terrain_under_the_water_is_not_drawn() {
    let Some(gpu) = gpu(Backend::Vulkan) else {
        return;
    };
    let view = view_from([0.0, 30.0, 0.0], 0.0, -89.0);
    let image = render(gpu, &marker_world(128), SIZE, &view);
    // Right half: land above water, drawn red.
    for z in [-6.0, 0.0, 6.0] {
        let land = at(&image, &view, [5.0, 1.2, z]);
        assert!(near(land, [255, 0, 0], 2), "land at z {z}: {land:?}");
        // Left half: the terrain is under water (y = -0.75); neither it nor its mirror image
        // (which would stand above the water) may show: only water over the mirrored sky.
        let sea = at(&image, &view, [-5.0, 0.0, z]);
        assert!(near(sea, WATER_OVER_SKY, 3), "sea at z {z}: {sea:?}");
    }
}

#[test]
fn the_water_mirrors_the_terrain_and_the_sky() {
    let Some(gpu) = gpu(Backend::Vulkan) else {
        return;
    };
    // Low over the sea, looking at the land (toward +x).
    let view = view_from([-8.0, 0.5, 0.0], 90.0, -10.0);
    let image = render(gpu, &marker_world(128), SIZE, &view);
    // The land's top seen directly, and its mirror image below the waterline.
    assert!(near(at(&image, &view, [5.0, 1.2, 0.0]), [255, 0, 0], 2));
    let reflection = at(&image, &view, [5.0, -1.2, 0.0]);
    assert!(near(reflection, WATER_OVER_LAND, 3), "mirrored land {reflection:?}");
    // Looking away from the land, the water shows the mirrored sky.
    let view = view_from([-8.0, 0.5, 0.0], 270.0, -10.0);
    let image = render(gpu, &marker_world(128), SIZE, &view);
    let sea = *image.get_pixel(SIZE.0 / 2, SIZE.1 - 4);
    assert!(near(sea, WATER_OVER_SKY, 3), "mirrored sky {sea:?}");
    let sky = *image.get_pixel(SIZE.0 / 2, 2);
    assert!(near(sky, [0, 255, 0], 2), "sky {sky:?}");
}

#[test]
fn detail_is_added_signed() {
    let Some(gpu) = gpu(Backend::Vulkan) else {
        return;
    };
    let view = view_from([0.0, 30.0, 0.0], 0.0, -89.0);
    // Red (1, 0, 0) + grey 200/255 - 0.5 = (1.28 -> 1, 0.284, 0.284).
    let image = render(gpu, &marker_world(200), SIZE, &view);
    let land = at(&image, &view, [5.0, 1.2, 0.0]);
    assert!(near(land, [255, 72, 72], 2), "{land:?}");
    // Grey 60: (1 - 0.265, 0, 0) = (187, 0, 0).
    let image = render(gpu, &marker_world(60), SIZE, &view);
    let land = at(&image, &view, [5.0, 1.2, 0.0]);
    assert!(near(land, [188, 0, 0], 2), "{land:?}");
}

/// The marker world with a water texture of vertical stripes, so its drift shows.
fn striped_water_world() -> terrain::world::World {
    let mut world = marker_world(128);
    world.water =
        RgbaImage::from_fn(
            32,
            32,
            |x, _| {
                if x < 16 { Rgba([0, 0, 255, 255]) } else { Rgba([0, 0, 40, 255]) }
            },
        );
    world
}

#[test]
fn the_water_drifts_with_time_and_only_the_water() {
    let Some(gpu) = gpu(Backend::Vulkan) else {
        return;
    };
    let world = striped_water_world();
    let mut view = view_from([0.0, 30.0, 0.0], 0.0, -89.0);
    let still = render(gpu, &world, SIZE, &view);
    view.time_seconds = 10.0;
    let later = render(gpu, &world, SIZE, &view);
    let land = project(&still, &view, [5.0, 1.2, 0.0]).expect("on screen");
    assert_eq!(still.get_pixel(land.0, land.1), later.get_pixel(land.0, land.1), "the land moved");
    let sea = project(&still, &view, [-5.0, 0.0, 0.0]).expect("on screen");
    let changed = (0..SIZE.1).filter(|&y| still.get_pixel(sea.0, y) != later.get_pixel(sea.0, y)).count();
    assert!(changed > 10, "only {changed} water pixels changed in 10 s");
    // The drift is 0.02 texture repeats a second: after 50 s the texture has moved by exactly
    // one repeat and looks as it did at the start, however the frames were spaced.
    view.time_seconds = 50.0;
    let period = render(gpu, &world, SIZE, &view);
    let (d, _) = common::difference(&still, &period);
    assert!(d.mean < 0.05, "after one period the water differs by {d:?}");
}

#[test]
fn gl_and_vulkan_draw_the_same_picture() {
    let Some(vulkan) = gpu(Backend::Vulkan) else {
        return;
    };
    let Some(gl) = gpu(Backend::Gl) else { return };
    let world = striped_water_world();
    let view = view_from([-8.0, 1.5, 6.0], 120.0, -12.0);
    let (d, _) = common::difference(&render(vulkan, &world, SIZE, &view), &render(gl, &world, SIZE, &view));
    assert!(d.mean < 0.5 && d.outliers < 0.01, "{d:?}");
}

#[test]
fn a_bgra_target_reads_back_as_rgba() {
    // Window surfaces are often BGRA; screenshots taken in the window read such a target back.
    let Some(gpu) = gpu(Backend::Vulkan) else {
        return;
    };
    let world = striped_water_world();
    let view = view_from([-8.0, 1.5, 6.0], 120.0, -12.0);
    let expected = render(gpu, &world, SIZE, &view);
    let format = wgpu::TextureFormat::Bgra8Unorm;
    let mut renderer =
        Renderer::new(gpu, &world, &SceneConfig::default(), &Settings::course(), format).expect("renderer");
    let target = OffscreenTarget::new(gpu, format, SIZE.0, SIZE.1).expect("target");
    renderer.draw(gpu, target.view(), SIZE, &view);
    let image = target.read(gpu).expect("read back");
    let (d, _) = common::difference(&image, &expected);
    assert!(d.worst <= 1, "{d:?}");
}

#[test]
fn what_the_gpu_refuses_is_an_error_naming_it_not_a_panic() {
    let Some(gpu) = gpu(Backend::Vulkan) else { return };
    // Larger than any buffer the device allows: wgpu's default error handler would panic.
    let too_large = gpu.device.limits().max_buffer_size.saturating_add(4);
    let made = gpu.scoped("test buffer", || {
        gpu.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("too large"),
            size: too_large,
            usage: wgpu::BufferUsages::VERTEX,
            mapped_at_creation: false,
        })
    });
    let error = made.expect_err("an impossible buffer was made").to_string();
    assert!(error.contains("test buffer"), "{error}");
    // The scope took the error: nothing is left for the next check.
    assert!(gpu.check().is_ok());
    // Without a problem the result comes through.
    assert_eq!(gpu.scoped("nothing", || 7).expect("no error"), 7);
}

/// Leaving out the mirrored land that the land hides changes no pixel: the course look with the
/// culling on and off, byte for byte, from views where it removes much (low over the island),
/// little (high above) and where it must stay off (at the waterline, outside the map).
#[test]
fn culling_the_hidden_reflection_changes_no_pixel() {
    let Some(gpu) = gpu(Backend::Vulkan) else {
        return;
    };
    let world = common::default_island();
    let config = SceneConfig::default();
    let views = [
        common::start_view(0.0),
        common::view_from([0.0, 0.6, 9.0], 0.0, -2.0),
        common::view_from([6.0, 1.2, 3.0], 70.0, -8.0),
        common::view_from([-4.0, 9.0, 12.0], -20.0, -35.0),
        common::view_from([2.0, 0.05, 11.0], 10.0, 3.0),
        common::view_from([0.0, 2.5, 18.0], 180.0, -4.0),
    ];
    let mut renderer =
        HeadlessRenderer::new(gpu, world, &config, &Settings::course(), 320, 180).expect("renderer");
    let mut left_out = 0;
    for view in &views {
        renderer.renderer_mut().set_cull_hidden_reflection(true);
        let culled = renderer.render(gpu, view).expect("renders");
        let mirrored_culled = renderer.renderer().terrain_triangles()[1];
        renderer.renderer_mut().set_cull_hidden_reflection(false);
        let whole = renderer.render(gpu, view).expect("renders");
        let mirrored_whole = renderer.renderer().terrain_triangles()[1];
        assert!(culled == whole, "culling changed the picture from {:?}", view.pose);
        left_out += mirrored_whole - mirrored_culled;
    }
    // And it did leave some out (else this test would prove nothing).
    assert!(left_out > 1000, "the culling left out only {left_out} triangles");
}

/// The course look's land drawn without a base vertex (each chunk's draw binding the vertex
/// buffer at its first vertex, as on WebGL2) or with one per direct draw is the multi-draw
/// picture byte for byte, from views near and far (coarse and fine levels, many chunks each).
#[test]
fn every_land_draw_path_gives_the_same_picture() {
    let Some(gpu) = gpu(Backend::Vulkan) else {
        return;
    };
    let world = common::default_island();
    let views = [
        common::start_view(0.0),
        common::view_from([6.0, 1.2, 3.0], 70.0, -8.0),
        common::view_from([-4.0, 9.0, 12.0], -20.0, -35.0),
        common::view_from([0.0, 1.0, 16.0], 0.0, -4.0),
    ];
    let mut renderer =
        HeadlessRenderer::new(gpu, world, &SceneConfig::default(), &Settings::course(), 320, 180)
            .expect("renderer");
    // The land's two draws alone (the paths differ there only), then the whole frame.
    for limit in [Some(2), None] {
        renderer.renderer_mut().set_draw_limit(limit);
        for view in &views {
            let taken = renderer.renderer_mut().set_land_draw_path(LandDrawPath::default());
            assert!(taken.is_some(), "the course look draws the island as its static mesh");
            let normal = renderer.render(gpu, view).expect("renders");
            let land = normal.pixels().filter(|p| p.0 != [0, 0, 0, 255]).count();
            assert!(land > 1000, "only {land} pixels of land from {:?}", view.pose);
            for path in [LandDrawPath::BaseVertex, LandDrawPath::VertexOffset] {
                let taken = renderer.renderer_mut().set_land_draw_path(path);
                if path == LandDrawPath::VertexOffset {
                    assert_eq!(taken, Some(path), "every GPU can draw without a base vertex");
                }
                let image = renderer.render(gpu, view).expect("renders");
                assert!(
                    image == normal,
                    "{taken:?} changed the picture from {:?} ({limit:?} draws)",
                    view.pose
                );
            }
        }
    }
    renderer.renderer_mut().set_draw_limit(None);
    renderer.renderer_mut().set_land_draw_path(LandDrawPath::default());
}

/// The draw limit adds a look's draws one at a time, in the order `draw_names` lists them: none
/// leaves the cleared frame, each draw that reaches the screen changes it, all of them give the
/// full frame.
#[test]
fn the_draw_limit_adds_the_draws_in_order() {
    let Some(gpu) = gpu(Backend::Vulkan) else {
        return;
    };
    let world = common::default_island();
    // From the sea, low, toward the island: its reflection in front of it.
    let view = common::view_from([0.0, 1.0, 16.0], 0.0, -4.0);
    for settings in [Settings::course(), Settings::default()] {
        let look = settings.look;
        let mut renderer =
            HeadlessRenderer::new(gpu, world, &SceneConfig::default(), &settings, 160, 96).expect("renderer");
        let full = renderer.render(gpu, &view).expect("renders");
        let names = draw_names(look);
        // The modern look's first draws go into the reflection, which only the water shows.
        let off_screen = if look == Look::Modern { 2 } else { 0 };
        let mut previous: Option<RgbaImage> = None;
        for limit in 0..=names.len() {
            renderer.renderer_mut().set_draw_limit(Some(limit));
            let image = renderer.render(gpu, &view).expect("renders");
            if limit <= off_screen {
                assert!(image.pixels().all(|p| p.0 == [0, 0, 0, 255]), "{look:?}: {limit} draws left a mark");
            } else {
                assert!(
                    previous.as_ref() != Some(&image),
                    "{look:?}: drawing the {} changed nothing",
                    names[limit - 1]
                );
            }
            previous = Some(image);
        }
        assert!(previous.as_ref() == Some(&full), "{look:?}: every draw is not the full frame");
        renderer.renderer_mut().set_draw_limit(None);
        assert!(
            renderer.render(gpu, &view).expect("renders") == full,
            "{look:?}: no limit is not the full frame"
        );
    }
}
