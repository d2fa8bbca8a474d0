//! The modern look's sky with a time of day, on the software GPU: noon, dusk and night differ in
//! the sky and the light as they should (the dusk sky near the horizon redder than noon's, the
//! night darker but never black, the moon lighting the land), and the water reflects that sky.

mod common;

use common::{default_island, gpu, project, render_with, view_from};
use image::{Rgba, RgbaImage};
use terrain::render::{Backend, FrameView};
use terrain::settings::Settings;
use terrain::world::atmosphere::TimeOfDay;

const SIZE: (u32, u32) = (240, 144);

/// Settings with the sun placed by `time` at 45 degrees north on the March equinox (the sun
/// rises due east at 06:00 and sets due west at 18:00).
fn at_time(time: &str) -> Settings {
    let mut settings = Settings::default();
    settings.sky.time_of_day = Some(time.parse::<TimeOfDay>().expect("a time"));
    settings.sky.latitude_degrees = 45.0;
    settings.sky.day_of_year = 80;
    settings
}

/// The mean colour of a 5 x 5 block around the pixel of `point`.
fn around(image: &RgbaImage, view: &FrameView, point: [f32; 3]) -> [f32; 3] {
    let (x, y) = project(image, view, point).expect("point on screen");
    let mut sum = [0.0f32; 3];
    let mut count = 0.0;
    for dy in -2i32..=2 {
        for dx in -2i32..=2 {
            let px = (x as i32 + dx).clamp(0, image.width() as i32 - 1) as u32;
            let py = (y as i32 + dy).clamp(0, image.height() as i32 - 1) as u32;
            let Rgba(p) = *image.get_pixel(px, py);
            for c in 0..3 {
                sum[c] += f32::from(p[c]);
            }
            count += 1.0;
        }
    }
    sum.map(|s| s / count)
}

fn brightness(c: [f32; 3]) -> f32 {
    (c[0] + c[1] + c[2]) / 3.0
}

fn redness(c: [f32; 3]) -> f32 {
    c[0] / c[2].max(1.0)
}

fn mean(image: &RgbaImage) -> f32 {
    image.pixels().map(|p| brightness([0, 1, 2].map(|c| f32::from(p.0[c])))).sum::<f32>()
        / (image.width() * image.height()) as f32
}

#[test]
fn noon_dusk_and_night_differ_in_the_sky_and_the_light() {
    let Some(gpu) = gpu(Backend::Vulkan) else { return };
    let island = default_island();
    // From the south-east of the island, looking west (toward the setting sun) over the land.
    let view = view_from([6.0, 3.0, 6.0], 270.0, -2.0);
    let eye = glam::Vec3::new(6.0, 3.0, 6.0);
    let sky_point = |elevation_degrees: f32| {
        let e = elevation_degrees.to_radians();
        (eye + glam::Vec3::new(-e.cos(), e.sin(), 0.0) * 90.0).to_array()
    };
    let (horizon, higher) = (sky_point(3.0), sky_point(12.0));
    let land = [0.0, 1.2, 6.0];
    let noon = render_with(gpu, island, &at_time("12:00"), SIZE, &view);
    let dusk = render_with(gpu, island, &at_time("17:55"), SIZE, &view);
    let night = render_with(gpu, island, &at_time("23:00"), SIZE, &view);
    let (noon_horizon, dusk_horizon, night_horizon) =
        (around(&noon, &view, horizon), around(&dusk, &view, horizon), around(&night, &view, horizon));
    // The dusk sky near the horizon, toward the sun, is redder than noon's.
    assert!(
        redness(dusk_horizon) > 1.5 * redness(noon_horizon),
        "dusk {dusk_horizon:?} vs noon {noon_horizon:?}"
    );
    // Higher up, noon's sky is blue, dusk's glows around the sun (redder, not darker so near it),
    // night's is darker than both.
    let (noon_high, dusk_high, night_high) =
        (around(&noon, &view, higher), around(&dusk, &view, higher), around(&night, &view, higher));
    assert!(noon_high[2] > noon_high[0] + 20.0, "noon {noon_high:?}");
    assert!(redness(dusk_high) > 1.5 * redness(noon_high), "{noon_high:?} vs {dusk_high:?}");
    assert!(brightness(dusk_high) > brightness(night_high) + 30.0, "{dusk_high:?} vs {night_high:?}");
    assert!(brightness(noon_high) > brightness(night_high) + 30.0, "{noon_high:?} vs {night_high:?}");
    // The night is dark blue, never black.
    assert!(night_high[2] > night_high[0] && brightness(night_high) > 15.0, "night {night_high:?}");
    assert!(brightness(night_horizon) > 15.0, "night horizon {night_horizon:?}");
    assert!(mean(&noon) > mean(&dusk) && mean(&dusk) > mean(&night) && mean(&night) > 10.0);
    // The land is lit by day, and still visible by the moon's light at night.
    let (noon_land, night_land) = (around(&noon, &view, land), around(&night, &view, land));
    assert!(brightness(noon_land) > 2.0 * brightness(night_land), "{noon_land:?} vs {night_land:?}");
    assert!(brightness(night_land) > 8.0, "night land {night_land:?}");
}

#[test]
fn the_water_reflects_the_sky_of_the_hour() {
    let Some(gpu) = gpu(Backend::Vulkan) else { return };
    let island = default_island();
    // Off the west coast, looking west over open water toward the setting sun.
    let view = view_from([-9.0, 0.8, 2.0], 270.0, -6.0);
    let water = [-15.0, 0.0, 2.0];
    let noon = around(&render_with(gpu, island, &at_time("12:00"), SIZE, &view), &view, water);
    let dusk = around(&render_with(gpu, island, &at_time("17:55"), SIZE, &view), &view, water);
    // The water toward the setting sun mirrors its red sky.
    assert!(redness(dusk) > 1.3 * redness(noon), "dusk {dusk:?} vs noon {noon:?}");
}
