//! Golden images of the procedural world (seed 1) at fixed cameras and times, in both looks,
//! rendered on the software GPU and compared with a tolerance. Refresh on purpose with
//! `RAYTERRA_BLESS=1`.

mod common;

use common::{assert_golden, gpu, render, render_with, start_view, view_from};
use terrain::Settings;
use terrain::render::Backend;
use terrain::world::World;

const SIZE: (u32, u32) = (320, 180);

fn island() -> &'static World {
    common::default_island()
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

#[test]
fn the_modern_look_from_the_start() {
    let Some(gpu) = gpu(Backend::Vulkan) else {
        return;
    };
    assert_golden("modern-start", &render_with(gpu, island(), &Settings::default(), SIZE, &start_view(3.0)));
}

#[test]
fn the_modern_look_along_the_coast_at_sunset() {
    let Some(gpu) = gpu(Backend::Vulkan) else {
        return;
    };
    let mut settings = Settings::default();
    settings.sun.elevation_degrees = 6.0;
    settings.sun.azimuth_degrees = 290.0;
    let mut view = view_from([-9.5, 0.7, 6.0], 20.0, -4.0);
    view.time_seconds = 20.0;
    assert_golden("modern-coast-sunset", &render_with(gpu, island(), &settings, SIZE, &view));
}
