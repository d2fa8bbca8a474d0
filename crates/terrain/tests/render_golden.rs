//! Golden images of the procedural world (seed 1) at fixed cameras and times, rendered on the
//! software GPU and compared with a tolerance. Refresh on purpose with `RAYTERRA_BLESS=1`.

mod common;

use std::sync::OnceLock;

use common::{assert_golden, gpu, render, start_view, view_from};
use terrain::SceneConfig;
use terrain::render::Backend;
use terrain::world::World;
use terrain::world::procedural::{ProceduralOptions, generate};

const SIZE: (u32, u32) = (320, 180);

fn island() -> &'static World {
    static WORLD: OnceLock<World> = OnceLock::new();
    WORLD.get_or_init(|| {
        generate(ProceduralOptions::default(), &SceneConfig::default(), &mut |_| {}).expect("default world")
    })
}

#[test]
fn the_starting_view() {
    let Some(gpu) = gpu(Backend::Vulkan) else {
        return;
    };
    assert_golden("island-start", &render(gpu, island(), SIZE, &start_view(0.0)));
}

#[test]
fn from_above_later() {
    let Some(gpu) = gpu(Backend::Vulkan) else {
        return;
    };
    let mut view = view_from([0.0, 16.0, 17.0], 0.0, -40.0);
    view.time_seconds = 7.5;
    assert_golden("island-above", &render(gpu, island(), SIZE, &view));
}

#[test]
fn along_the_coast() {
    let Some(gpu) = gpu(Backend::Vulkan) else {
        return;
    };
    let mut view = view_from([-9.5, 0.7, 6.0], 50.0, -4.0);
    view.time_seconds = 20.0;
    assert_golden("island-coast", &render(gpu, island(), SIZE, &view));
}
