//! A [`World`] and its [`SceneConfig`] taken apart into named layers of plain numbers and put
//! back together: how a world built in the page's worker crosses to the page (each layer's
//! buffer is transferred, not copied, between the two). The scene's numbers cross with it, so a
//! world made from elevation data keeps its height mapping, its sea (or none) and its camera
//! start on the page, as in the native program.

use glam::{Vec2, Vec3};
use image::RgbaImage;
use terrain::SceneConfig;
use terrain::camera::CameraPose;
use terrain::world::dem::place::ElevationInfo;
use terrain::world::heightmap::StoredSamples;
use terrain::world::{Heightmap, SkyBox, UnlitLayers, World};

/// One layer's numbers.
#[derive(Debug, Clone, PartialEq)]
pub enum LayerData {
    /// RGBA bytes, row by row from the top.
    Rgba(Vec<u8>),
    /// Heightmap grey levels as numbers.
    Levels(Vec<f32>),
    /// Heightmap 16-bit values (`level = value / 257`).
    Sixteen(Vec<u16>),
    /// Plain numbers (the scene's settings, what the world knows of its elevation data).
    Numbers(Vec<f64>),
    /// A yes/no a sample, 0 or 1 (the samples elevation data had no data for).
    Mask(Vec<u8>),
}

/// A named image or heightmap of `width` x `height` samples.
#[derive(Debug, Clone, PartialEq)]
pub struct Layer {
    /// Which part of the world it is (see [`world_into_layers`]).
    pub name: String,
    /// Samples a row.
    pub width: u32,
    /// Rows.
    pub height: u32,
    /// The samples.
    pub data: LayerData,
}

/// Why layers do not make a world.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum TransferError {
    /// A layer the world needs is missing.
    #[error("the world's `{0}` layer is missing")]
    Missing(String),
    /// A layer's numbers do not fit its size or kind.
    #[error("the world's `{name}` layer is not a {width}x{height} {expected}")]
    Malformed {
        /// The layer.
        name: String,
        /// Its stated width.
        width: u32,
        /// Its stated height.
        height: u32,
        /// What it should have been.
        expected: &'static str,
    },
}

const SIDES: [&str; 4] = ["front", "right", "back", "left"];

/// Takes `world` apart (no copies of its images): the heightmap as `heightmap`, then
/// `colour`, `detail`, `water`, the sky box as `sky-front`, `sky-right`, `sky-back`, `sky-left`,
/// `sky-top`, and, when the world has them, `albedo` and the clear sky as `clear-front` ...
/// `clear-top`; `config`'s numbers as `scene`; for a world made from elevation data, what it
/// knows of them as `elevation` and, where the file had voids, their mask as `voids`. (The
/// erosion's maps do not cross: the page does not erode.)
pub fn world_into_layers(world: World, config: &SceneConfig) -> Vec<Layer> {
    let heightmap = &world.heightmap;
    let data = match heightmap.samples() {
        StoredSamples::Levels(levels) => LayerData::Levels(levels.to_vec()),
        StoredSamples::Sixteen(values) => LayerData::Sixteen(values.to_vec()),
    };
    let mut layers =
        vec![Layer { name: "heightmap".into(), width: heightmap.columns(), height: heightmap.rows(), data }];
    push_image(&mut layers, "colour".into(), world.colour_map);
    push_image(&mut layers, "detail".into(), world.detail_map);
    push_image(&mut layers, "water".into(), world.water);
    push_sky_box(&mut layers, "sky", world.sky);
    if let Some(unlit) = world.unlit {
        push_image(&mut layers, "albedo".into(), unlit.albedo_map);
        push_sky_box(&mut layers, "clear", unlit.sky);
    }
    push_numbers(&mut layers, "scene", scene_numbers(config));
    if let Some(info) = world.elevation {
        push_numbers(&mut layers, "elevation", elevation_numbers(&info));
        if !info.voids.is_empty() {
            let data = LayerData::Mask(info.voids.iter().map(|&void| u8::from(void)).collect());
            let (width, height) = (world.heightmap.columns(), world.heightmap.rows());
            layers.push(Layer { name: "voids".into(), width, height, data });
        }
    }
    layers
}

fn push_numbers(layers: &mut Vec<Layer>, name: &str, numbers: Vec<f64>) {
    let width = numbers.len() as u32;
    layers.push(Layer { name: name.into(), width, height: 1, data: LayerData::Numbers(numbers) });
}

/// How many numbers the `scene` layer holds.
const SCENE_NUMBERS: usize = 22;

/// A scene's numbers in a fixed order (every field of [`SceneConfig`]; `sea` as 0 or 1).
fn scene_numbers(config: &SceneConfig) -> Vec<f64> {
    let pose = &config.camera_start;
    let numbers = [
        config.terrain_length,
        config.level_offset,
        config.unit_height,
        config.detail_repeat,
        config.sky_box_size.x,
        config.sky_box_size.y,
        config.sky_box_size.z,
        config.water_alpha,
        config.water_repeat.x,
        config.water_repeat.y,
        config.wave_velocity.x,
        config.wave_velocity.y,
        pose.position.x,
        pose.position.y,
        pose.position.z,
        pose.yaw_degrees,
        pose.pitch_degrees,
        config.field_of_view_degrees,
        config.near,
        config.far,
        if config.sea { 1.0 } else { 0.0 },
    ];
    let mut numbers: Vec<f64> = numbers.iter().map(|&n| f64::from(n)).collect();
    // A version of the layout, so that a page and a worker of different builds cannot mix.
    numbers.push(1.0);
    numbers
}

/// The scene back from [`scene_numbers`]; `None` if they are not such numbers.
fn scene_of_numbers(numbers: &[f64]) -> Option<SceneConfig> {
    if numbers.len() != SCENE_NUMBERS || numbers[SCENE_NUMBERS - 1] != 1.0 {
        return None;
    }
    // Every number was an f32 (finite) or the sea's 0 or 1.
    let n: Vec<f32> = numbers.iter().map(|&n| n as f32).collect();
    if n.iter().any(|n| !n.is_finite()) || !(n[20] == 0.0 || n[20] == 1.0) {
        return None;
    }
    Some(SceneConfig {
        terrain_length: n[0],
        level_offset: n[1],
        unit_height: n[2],
        detail_repeat: n[3],
        sky_box_size: Vec3::new(n[4], n[5], n[6]),
        water_alpha: n[7],
        water_repeat: Vec2::new(n[8], n[9]),
        wave_velocity: Vec2::new(n[10], n[11]),
        camera_start: CameraPose::new(Vec3::new(n[12], n[13], n[14]), n[15], n[16]),
        field_of_view_degrees: n[17],
        near: n[18],
        far: n[19],
        sea: n[20] == 1.0,
    })
}

/// What a world knows of its elevation data, without the void mask: cell size, metres a
/// world unit, vertical exaggeration, the height at y = 0, the sea (0 or 1), lowest and
/// highest heights.
fn elevation_numbers(info: &ElevationInfo) -> Vec<f64> {
    vec![
        info.cell_size_metres,
        info.metres_per_unit,
        info.vertical_exaggeration,
        info.base_metres,
        if info.sea { 1.0 } else { 0.0 },
        f64::from(info.range_metres.0),
        f64::from(info.range_metres.1),
    ]
}

/// The elevation data's numbers back, with the void mask `voids`.
fn elevation_of_numbers(numbers: &[f64], voids: Vec<bool>) -> Option<ElevationInfo> {
    let &[cell_size_metres, metres_per_unit, vertical_exaggeration, base_metres, sea, low, high] = numbers
    else {
        return None;
    };
    if !(sea == 0.0 || sea == 1.0) || numbers.iter().any(|n| !n.is_finite()) {
        return None;
    }
    Some(ElevationInfo {
        cell_size_metres,
        metres_per_unit,
        vertical_exaggeration,
        base_metres,
        sea: sea == 1.0,
        range_metres: (low as f32, high as f32),
        voids,
    })
}

fn push_image(layers: &mut Vec<Layer>, name: String, image: RgbaImage) {
    let (width, height) = image.dimensions();
    layers.push(Layer { name, width, height, data: LayerData::Rgba(image.into_raw()) });
}

fn push_sky_box(layers: &mut Vec<Layer>, prefix: &str, sky: SkyBox) {
    for (side, face) in SIDES.iter().zip(sky.sides) {
        push_image(layers, format!("{prefix}-{side}"), face);
    }
    push_image(layers, format!("{prefix}-top"), sky.top);
}

/// Puts a world and its scene back together from [`world_into_layers`]' layers (in any order).
pub fn world_from_layers(layers: Vec<Layer>) -> Result<(World, SceneConfig), TransferError> {
    let mut pool = Pool(layers.into_iter().map(Some).collect());
    let Layer { name, width, height, data } =
        pool.take("heightmap").ok_or_else(|| TransferError::Missing("heightmap".into()))?;
    let heightmap = match data {
        LayerData::Levels(levels) => Heightmap::new(width, height, levels),
        LayerData::Sixteen(values) => Heightmap::from_sixteen_bit(width, height, values),
        _ => return Err(malformed(&name, width, height, "heightmap")),
    }
    .map_err(|_| malformed(&name, width, height, "heightmap"))?;
    let colour_map = pool.required("colour")?;
    let detail_map = pool.required("detail")?;
    let water = pool.required("water")?;
    let sky = pool.sky_box("sky")?;
    let unlit = match pool.image("albedo")? {
        Some(albedo_map) => Some(UnlitLayers { albedo_map, sky: pool.sky_box("clear")? }),
        None => None,
    };
    let config = match pool.numbers("scene")? {
        Some(numbers) => scene_of_numbers(&numbers),
        None => return Err(TransferError::Missing("scene".into())),
    }
    .ok_or_else(|| malformed("scene", SCENE_NUMBERS as u32, 1, "list of the scene's numbers"))?;
    let voids = pool.voids(&heightmap)?;
    let elevation = match pool.numbers("elevation")? {
        Some(numbers) => Some(
            elevation_of_numbers(&numbers, voids)
                .ok_or_else(|| malformed("elevation", numbers.len() as u32, 1, "list of 7 numbers"))?,
        ),
        None if voids.is_empty() => None,
        None => return Err(TransferError::Missing("elevation".into())),
    };
    let world = World { heightmap, colour_map, detail_map, sky, water, unlit, elevation, erosion: None };
    Ok((world, config))
}

fn malformed(name: &str, width: u32, height: u32, expected: &'static str) -> TransferError {
    TransferError::Malformed { name: name.into(), width, height, expected }
}

/// The layers not taken yet.
struct Pool(Vec<Option<Layer>>);

impl Pool {
    fn take(&mut self, name: &str) -> Option<Layer> {
        self.0.iter_mut().find(|layer| layer.as_ref().is_some_and(|layer| layer.name == name))?.take()
    }

    fn image(&mut self, name: &str) -> Result<Option<RgbaImage>, TransferError> {
        let Some(layer) = self.take(name) else { return Ok(None) };
        let Layer { width, height, data, .. } = layer;
        match data {
            LayerData::Rgba(bytes) if bytes.len() as u64 == u64::from(width) * u64::from(height) * 4 => {
                Ok(RgbaImage::from_raw(width, height, bytes))
            }
            _ => Err(malformed(name, width, height, "RGBA image")),
        }
    }

    /// The numbers of the layer `name`, if there is one.
    fn numbers(&mut self, name: &str) -> Result<Option<Vec<f64>>, TransferError> {
        let Some(layer) = self.take(name) else { return Ok(None) };
        match layer.data {
            LayerData::Numbers(numbers)
                if numbers.len() as u64 == u64::from(layer.width) * u64::from(layer.height) =>
            {
                Ok(Some(numbers))
            }
            _ => Err(malformed(name, layer.width, layer.height, "list of numbers")),
        }
    }

    /// The void mask, the heightmap's size (empty when there is none).
    fn voids(&mut self, heightmap: &Heightmap) -> Result<Vec<bool>, TransferError> {
        let Some(layer) = self.take("voids") else { return Ok(Vec::new()) };
        let (columns, rows) = (heightmap.columns(), heightmap.rows());
        match layer.data {
            LayerData::Mask(mask)
                if (layer.width, layer.height) == (columns, rows)
                    && mask.len() as u64 == u64::from(columns) * u64::from(rows) =>
            {
                Ok(mask.into_iter().map(|void| void != 0).collect())
            }
            _ => Err(malformed("voids", layer.width, layer.height, "mask the heightmap's size")),
        }
    }

    fn required(&mut self, name: &str) -> Result<RgbaImage, TransferError> {
        self.image(name)?.ok_or_else(|| TransferError::Missing(name.into()))
    }

    fn sky_box(&mut self, prefix: &str) -> Result<SkyBox, TransferError> {
        let [front, right, back, left] = SIDES.map(|side| format!("{prefix}-{side}"));
        Ok(SkyBox {
            sides: [
                self.required(&front)?,
                self.required(&right)?,
                self.required(&back)?,
                self.required(&left)?,
            ],
            top: self.required(&format!("{prefix}-top"))?,
        })
    }
}

#[cfg(test)]
mod tests {
    use terrain::SceneConfig;
    use terrain::world::dem::{self, LoadOptions};
    use terrain::world::procedural::{self, ProceduralOptions};

    use super::*;

    fn small_world() -> World {
        let options = ProceduralOptions { seed: 3, heightmap_size: 17 };
        procedural::generate(options, &SceneConfig::default(), &mut |_| {}).expect("generated")
    }

    #[test]
    fn a_world_survives_the_trip() {
        let world = small_world();
        let config = SceneConfig::default();
        let layers = world_into_layers(world.clone(), &config);
        assert_eq!(layers.len(), 1 + 3 + 5 + 1 + 5 + 1);
        let mut reversed = layers;
        reversed.reverse();
        assert_eq!(world_from_layers(reversed).expect("whole"), (world, config));
    }

    /// Elevation data with a void, wholly above the water: its scene (no sea, its own height
    /// mapping and camera start) and what the world knows of it cross with it.
    #[test]
    fn an_elevation_world_keeps_its_scene_and_voids() {
        let text = "ncols 4\nnrows 3\nxllcorner 0\nyllcorner 0\ncellsize 30\nNODATA_value -9999\n\
                    500 510 520 530\n505 -9999 525 540\n510 520 530 560\n";
        let loaded = dem::load_bytes(text.as_bytes(), "hill.asc", &LoadOptions::default()).expect("grid");
        let dem::DemScene { heightmap, config, info } = loaded.scene;
        assert!(!config.sea && info.void_count() == 1);
        assert_ne!(config, SceneConfig::default());
        let mut world = procedural::dress_heightmap(heightmap, 1, &config, &mut |_| {});
        world.elevation = Some(info);
        let layers = world_into_layers(world.clone(), &config);
        assert!(layers.iter().any(|layer| layer.name == "voids"
            && layer.data == LayerData::Mask(vec![0, 0, 0, 0, 0, 1, 0, 0, 0, 0, 0, 0])));
        let (back, back_config) = world_from_layers(layers).expect("whole");
        assert_eq!(back_config, config);
        assert_eq!(back, world);
    }

    #[test]
    fn sixteen_bit_heightmaps_stay_sixteen_bit() {
        let mut world = small_world();
        world.heightmap = Heightmap::from_sixteen_bit(2, 2, vec![0, 257, 65535, 1000]).expect("valid");
        world.unlit = None;
        let config = SceneConfig::default();
        let layers = world_into_layers(world.clone(), &config);
        assert_eq!(layers[0].data, LayerData::Sixteen(vec![0, 257, 65535, 1000]));
        assert_eq!(world_from_layers(layers).expect("whole"), (world, config));
    }

    #[test]
    fn missing_and_malformed_layers_are_named() {
        let layers = world_into_layers(small_world(), &SceneConfig::default());
        let without = |name: &str| -> Vec<Layer> {
            layers.iter().filter(|layer| layer.name != name).cloned().collect()
        };
        assert_eq!(world_from_layers(without("water")), Err(TransferError::Missing("water".into())));
        assert_eq!(world_from_layers(without("scene")), Err(TransferError::Missing("scene".into())));
        let mut short = layers.clone();
        let detail = short.iter_mut().find(|layer| layer.name == "detail").expect("detail");
        detail.height += 1;
        let error = world_from_layers(short).expect_err("short");
        assert!(error.to_string().contains("`detail`"), "{error}");
        let mut bad_scene = layers.clone();
        let scene = bad_scene.iter_mut().find(|layer| layer.name == "scene").expect("scene");
        scene.data = LayerData::Numbers(vec![1.0; SCENE_NUMBERS - 1]);
        scene.width -= 1;
        let error = world_from_layers(bad_scene).expect_err("short scene");
        assert!(error.to_string().contains("`scene`"), "{error}");
        let mut stray_voids = layers.clone();
        stray_voids.push(Layer {
            name: "voids".into(),
            width: 17,
            height: 17,
            data: LayerData::Mask(vec![0; 17 * 17]),
        });
        assert_eq!(world_from_layers(stray_voids), Err(TransferError::Missing("elevation".into())));
        let mut wrong_kind = layers;
        wrong_kind[0].data = LayerData::Rgba(vec![0; 17 * 17 * 4]);
        assert!(world_from_layers(wrong_kind).is_err());
    }
}
