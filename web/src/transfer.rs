//! A [`World`] taken apart into named layers of plain numbers and put back together: how a world
//! generated in the page's worker crosses to the page (each layer's buffer is transferred, not
//! copied, between the two).

use image::RgbaImage;
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
/// `clear-top`.
pub fn world_into_layers(world: World) -> Vec<Layer> {
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
    layers
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

/// Puts a world back together from [`world_into_layers`]' layers (in any order).
pub fn world_from_layers(layers: Vec<Layer>) -> Result<World, TransferError> {
    let mut pool = Pool(layers.into_iter().map(Some).collect());
    let Layer { name, width, height, data } =
        pool.take("heightmap").ok_or_else(|| TransferError::Missing("heightmap".into()))?;
    let heightmap = match data {
        LayerData::Levels(levels) => Heightmap::new(width, height, levels),
        LayerData::Sixteen(values) => Heightmap::from_sixteen_bit(width, height, values),
        LayerData::Rgba(_) => return Err(malformed(&name, width, height, "heightmap")),
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
    Ok(World { heightmap, colour_map, detail_map, sky, water, unlit, elevation: None, erosion: None })
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
    use terrain::world::procedural::{self, ProceduralOptions};

    use super::*;

    fn small_world() -> World {
        let options = ProceduralOptions { seed: 3, heightmap_size: 17 };
        procedural::generate(options, &SceneConfig::default(), &mut |_| {}).expect("generated")
    }

    #[test]
    fn a_world_survives_the_trip() {
        let world = small_world();
        let layers = world_into_layers(world.clone());
        assert_eq!(layers.len(), 1 + 3 + 5 + 1 + 5);
        let mut reversed = layers;
        reversed.reverse();
        assert_eq!(world_from_layers(reversed).expect("whole"), world);
    }

    #[test]
    fn sixteen_bit_heightmaps_stay_sixteen_bit() {
        let mut world = small_world();
        world.heightmap = Heightmap::from_sixteen_bit(2, 2, vec![0, 257, 65535, 1000]).expect("valid");
        world.unlit = None;
        let layers = world_into_layers(world.clone());
        assert_eq!(layers[0].data, LayerData::Sixteen(vec![0, 257, 65535, 1000]));
        assert_eq!(world_from_layers(layers).expect("whole"), world);
    }

    #[test]
    fn missing_and_malformed_layers_are_named() {
        let layers = world_into_layers(small_world());
        let without_water: Vec<Layer> =
            layers.iter().filter(|layer| layer.name != "water").cloned().collect();
        assert_eq!(world_from_layers(without_water), Err(TransferError::Missing("water".into())));
        let mut short = layers.clone();
        let detail = short.iter_mut().find(|layer| layer.name == "detail").expect("detail");
        detail.height += 1;
        let error = world_from_layers(short).expect_err("short");
        assert!(error.to_string().contains("`detail`"), "{error}");
        let mut wrong_kind = layers;
        wrong_kind[0].data = LayerData::Rgba(vec![0; 17 * 17 * 4]);
        assert!(world_from_layers(wrong_kind).is_err());
    }
}
