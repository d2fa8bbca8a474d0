//! An OpenEXR output with the auxiliary images of `--aov` as layers beside the image: channels
//! `R`, `G`, `B` (the image), then `albedo.R`, `albedo.G`, `albedo.B`, `normal.X`, `normal.Y`,
//! `normal.Z` and `depth.Z`, as OpenEXR names layers (viewers such as tev list them as layers).
//! All 32-bit floats, linear; the image's channels hold the very values a plain `.exr` output
//! holds.

use std::path::Path;

use exr::prelude::{
    AnyChannel, AnyChannels, Encoding, FlatSamples, Image as ExrImage, Layer, LayerAttributes, WritableImage,
};

/// An auxiliary image as layer channels: the channels' names (with their layer) and values.
pub struct AovLayer {
    /// `(channel name, one value a pixel)`, e.g. `("albedo.R", ...)`.
    pub channels: Vec<(String, Vec<f32>)>,
}

impl AovLayer {
    /// The layer `name` of an RGB-like image, its channels named `name.X` for X in `names`.
    pub fn from_rgb(name: &str, names: [&str; 3], pixels: &[[f32; 3]]) -> AovLayer {
        let channels =
            (0..3).map(|c| (format!("{name}.{}", names[c]), pixels.iter().map(|p| p[c]).collect())).collect();
        AovLayer { channels }
    }

    /// The layer `name` of a one-channel image, its channel `name.channel`.
    pub fn single(name: &str, channel: &str, values: Vec<f32>) -> AovLayer {
        AovLayer { channels: vec![(format!("{name}.{channel}"), values)] }
    }
}

/// What writing the file can fail with.
pub type LayersWriteError = atomic_file::WriteError<exr::error::Error>;

/// Writes `pixels` (`width` x `height`, row by row from the top) with `layers` to `path`, whole
/// or not at all.
pub fn write_with_layers(
    path: &Path,
    width: u32,
    height: u32,
    pixels: &[[f32; 3]],
    layers: &[AovLayer],
) -> Result<(), LayersWriteError> {
    let rgb = ["R", "G", "B"]
        .iter()
        .enumerate()
        .map(|(c, name)| AnyChannel::new(*name, FlatSamples::F32(pixels.iter().map(|p| p[c]).collect())));
    let aovs = layers
        .iter()
        .flat_map(|l| l.channels.iter())
        .map(|(name, values)| AnyChannel::new(name.as_str(), FlatSamples::F32(values.clone())));
    let channels: smallvec::SmallVec<[AnyChannel<FlatSamples>; 4]> = rgb.chain(aovs).collect();
    let layer = Layer::new(
        (width as usize, height as usize),
        LayerAttributes::default(),
        Encoding::FAST_LOSSLESS,
        AnyChannels::sort(channels),
    );
    let image = ExrImage::from_layer(layer);
    atomic_file::write_atomically(path, |out| image.write().to_buffered(out))
}

#[cfg(test)]
mod tests {
    use super::*;
    use exr::prelude::{ReadChannels, ReadLayers};

    #[test]
    fn the_layers_read_back_by_name() {
        let dir = tempfile::tempdir().expect("temp dir");
        let path = dir.path().join("layers.exr");
        let pixels = [[0.5, 1.5, -2.0], [4.0, 0.0, 1e-3]];
        let layers = [
            AovLayer::from_rgb("albedo", ["R", "G", "B"], &[[0.1, 0.2, 0.3], [0.4, 0.5, 0.6]]),
            AovLayer::single("depth", "Z", vec![3.0, 7.5]),
        ];
        write_with_layers(&path, 2, 1, &pixels, &layers).expect("written");
        let image = exr::prelude::read()
            .no_deep_data()
            .largest_resolution_level()
            .all_channels()
            .first_valid_layer()
            .all_attributes()
            .from_file(&path)
            .expect("read back");
        let channel = |name: &str| -> Vec<f32> {
            let c = image.layer_data.channel_data.list.iter().find(|c| c.name.to_string() == name);
            c.unwrap_or_else(|| panic!("no channel {name}")).sample_data.values_as_f32().collect()
        };
        assert_eq!(channel("R"), vec![0.5, 4.0]);
        assert_eq!(channel("B"), vec![-2.0, 1e-3]);
        assert_eq!(channel("albedo.G"), vec![0.2, 0.5]);
        assert_eq!(channel("depth.Z"), vec![3.0, 7.5]);
        // The image crate (and so every reader of plain outputs) reads the image's channels.
        let plain = image::open(&path).expect("image reads it").to_rgb32f();
        assert_eq!(plain.get_pixel(1, 0).0, [4.0, 0.0, 1e-3]);
    }
}
