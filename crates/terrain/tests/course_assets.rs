//! The course's own asset folder (`../shared/course-assets/terrain`), loaded and rendered. Its
//! images are not ours, so renders are checked by their properties and never stored: sky above
//! the horizon, land where the heightmap is above water, water where it is below.

mod common;

use common::{course_assets, gpu, project, render, start_view, view_from};
use image::RgbaImage;
use terrain::SceneConfig;
use terrain::render::Backend;
use terrain::world::assets::load_course_folder;
use terrain::world::{Heightfield, World};

const SIZE: (u32, u32) = (320, 180);

fn course_world() -> Option<World> {
    let dir = course_assets()?;
    Some(load_course_folder(&dir).expect("the course folder loads"))
}

#[test]
fn loads_the_course_folder() {
    let Some(world) = course_world() else { return };
    assert_eq!((world.heightmap.columns(), world.heightmap.rows()), (256, 256));
    assert_eq!(world.colour_map.dimensions(), (512, 512));
    assert_eq!(world.detail_map.dimensions(), (512, 512));
    assert!(world.sky.faces().iter().all(|face| face.dimensions() == (256, 256)));
    assert_eq!(world.water.dimensions(), (128, 128));
    // About a third of the island is under water (spec section 2).
    let config = SceneConfig::default();
    let levels = world.heightmap.levels();
    let count = levels.len();
    let under = levels.filter(|&l| config.height_of_level(l) < 0.0).count() as f32 / count as f32;
    assert!((0.28..0.38).contains(&under), "{under}");
}

fn mean_rgb(image: &RgbaImage) -> [f64; 3] {
    let n = f64::from(image.width() * image.height());
    [0, 1, 2].map(|c| image.pixels().map(|p| f64::from(p.0[c])).sum::<f64>() / n)
}

fn distance(a: [f64; 3], b: [f64; 3]) -> f64 {
    (0..3).map(|c| (a[c] - b[c]).abs()).sum::<f64>() / 3.0
}

#[test]
fn the_starting_view_has_sky_above_and_the_island_below() {
    let Some(world) = course_world() else { return };
    let Some(gpu) = gpu(Backend::Vulkan) else {
        return;
    };
    let image = render(gpu, &world, SIZE, &start_view(0.0));
    // The top rows show the sky: blue dominant and bright, like the sky faces.
    for x in (0..SIZE.0).step_by(16) {
        let p = image.get_pixel(x, 2).0;
        assert!(p[2] > 150 && p[2] >= p[0], "sky at {x}: {p:?}");
    }
    // The bottom rows show the island's land (not blue-dominant sky).
    let land = (0..SIZE.0)
        .filter(|&x| {
            let p = image.get_pixel(x, SIZE.1 - 2).0;
            p[2] < p[0].max(p[1]) + 20
        })
        .count();
    assert!(land > SIZE.0 as usize * 3 / 4, "only {land} land pixels on the bottom row");
}

#[test]
fn land_and_water_where_the_heightmap_puts_them() {
    let Some(world) = course_world() else { return };
    let Some(gpu) = gpu(Backend::Vulkan) else {
        return;
    };
    let config = SceneConfig::default();
    let view = view_from([0.0, 26.0, 0.0], 0.0, -89.0);
    let image = render(gpu, &world, SIZE, &view);
    let field = Heightfield::new(&world.heightmap, &config);
    // What a water pixel should look like: 80% water texture over the mirrored sky top (seen
    // from above, the water reflects the top face); both are minified to about their mean here.
    let water = mean_rgb(&world.water);
    let sky = mean_rgb(&world.sky.top);
    let expected_water = [0, 1, 2].map(|c| 0.8 * water[c] + 0.2 * sky[c]);
    // A land pixel covers about 3x3 texels of the colour map at this distance and is mipmapped:
    // expect the colour map's mean over a 5x5 block there (the detail map averages out to 0.5).
    let colour_at = |x: f32, z: f32| {
        let uv = field.uv(x, z);
        let (w, h) = world.colour_map.dimensions();
        let (cx, cy) = ((uv.x * w as f32) as i64, (uv.y * h as f32) as i64);
        let mut sum = [0.0; 3];
        for dy in -2..=2 {
            for dx in -2..=2 {
                let p = world.colour_map.get_pixel(
                    (cx + dx).clamp(0, i64::from(w) - 1) as u32,
                    (cy + dy).clamp(0, i64::from(h) - 1) as u32,
                );
                for (total, &channel) in sum.iter_mut().zip(&p.0) {
                    *total += f64::from(channel) / 25.0;
                }
            }
        }
        sum
    };
    let (mut land_right, mut land_total, mut water_right, mut water_total) = (0, 0, 0, 0);
    // Cells well inside land or sea: all 5x5 neighbours on the same side of the water.
    for row in (4..252).step_by(6) {
        for column in (4..252).step_by(6) {
            let heights: Vec<f32> = (row - 2..=row + 2)
                .flat_map(|r| (column - 2..=column + 2).map(move |c| (r, c)))
                .map(|(r, c)| field.height(r, c))
                .collect();
            let point = field.point(row, column);
            let Some((x, y)) = project(&image, &view, point.to_array()) else {
                continue;
            };
            let p = image.get_pixel(x, y).0;
            let pixel = [0, 1, 2].map(|c| f64::from(p[c]));
            let (to_land, to_water) =
                (distance(pixel, colour_at(point.x, point.z)), distance(pixel, expected_water));
            if heights.iter().all(|&h| h > 0.05) {
                land_total += 1;
                land_right += usize::from(to_land < to_water);
            } else if heights.iter().all(|&h| h < -0.05) {
                water_total += 1;
                water_right += usize::from(to_water < to_land);
            }
        }
    }
    eprintln!("land {land_right}/{land_total}, water {water_right}/{water_total}");
    assert!(land_total > 200 && water_total > 100, "too few cells sampled");
    assert!(land_right * 100 >= land_total * 90, "land looks like land at {land_right}/{land_total} cells");
    assert!(
        water_right * 100 >= water_total * 90,
        "water looks like water at {water_right}/{water_total} cells"
    );
}
