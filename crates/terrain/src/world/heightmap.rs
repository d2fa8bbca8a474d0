//! Heightmaps: a grid of grey levels read from any greyscale image (8- or 16-bit, any size).

use std::path::Path;

use image::DynamicImage;

use super::{WorldError, decode_checked, header_decoder, open_decoder};

/// Largest heightmap side accepted, in samples. Beyond this the mesh no longer fits the buffers of
/// common GPUs (and the course maps are 256 wide); it keeps absurd inputs from exhausting memory.
pub const MAX_HEIGHTMAP_SIDE: u32 = 8193;

/// Why a grid of samples is not a usable heightmap.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum HeightmapError {
    /// Fewer than 2x2 samples: there is no cell to draw.
    #[error("a heightmap needs at least 2x2 samples, this one is {columns}x{rows}")]
    TooSmall {
        /// Samples per row.
        columns: u32,
        /// Rows.
        rows: u32,
    },
    /// More than [`MAX_HEIGHTMAP_SIDE`] samples along a side.
    #[error(
        "a heightmap may have at most {MAX_HEIGHTMAP_SIDE} samples per side, this one is {columns}x{rows}"
    )]
    TooLarge {
        /// Samples per row.
        columns: u32,
        /// Rows.
        rows: u32,
    },
    /// The sample vector's length is not `columns * rows`.
    #[error("{len} samples given for a {columns}x{rows} heightmap")]
    SampleCount {
        /// Samples per row.
        columns: u32,
        /// Rows.
        rows: u32,
        /// Samples given.
        len: usize,
    },
    /// A sample is NaN or infinite.
    #[error("the sample at row {row}, column {column} is not a finite number")]
    NotFinite {
        /// Row of the bad sample.
        row: u32,
        /// Column of the bad sample.
        column: u32,
    },
}

/// A grid of heights as grey levels on the 8-bit scale: 0.0 is black, 255.0 white. 16-bit images
/// keep their precision as fractional levels. Row 0 is the image's top row, which the terrain puts
/// at its far (-z) edge; column 0 is the image's left column, at the terrain's -x edge.
///
/// Images are kept as their 16-bit values (`level = value / 257`, exact for 8- and 16-bit
/// images): 2 bytes a sample. Grids built from numbers ([`Heightmap::new`]) keep them as `f32`:
/// 4 bytes a sample.
#[derive(Debug, Clone, PartialEq)]
pub struct Heightmap {
    columns: u32,
    rows: u32,
    samples: Samples,
}

/// How a heightmap stores its samples.
#[derive(Debug, Clone, PartialEq)]
enum Samples {
    /// Grey levels as numbers.
    Levels(Vec<f32>),
    /// 16-bit values: `level = value / 257`.
    Sixteen(Vec<u16>),
}

/// A heightmap's samples as stored (see [`Heightmap::samples`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum StoredSamples<'a> {
    /// Grey levels as numbers.
    Levels(&'a [f32]),
    /// 16-bit values: `level = value / 257`.
    Sixteen(&'a [u16]),
}

/// The grey level of a 16-bit value: `value / 257` (so 8-bit grey `g`, stored as `257 g`, is `g`).
pub fn level_of_sixteen(value: u16) -> f32 {
    f32::from(value) / 257.0
}

/// The 16-bit value nearest to a grey level (`level * 257`, rounded and clamped to 0..=65535).
pub fn sixteen_of_level(level: f32) -> u16 {
    // `(level * 257.0).round().clamp(0.0, 65535.0) as u16`, bit for bit, without `f32::round`,
    // which is a library call on x86-64 (an 8193-sample map makes 67 million): within 0..=65535
    // the truncation is exact, and so is the fraction it leaves. NaN gives 0, as the cast would.
    let scaled = (level * 257.0).clamp(0.0, 65535.0);
    let whole = scaled as u16;
    whole + u16::from(scaled - f32::from(whole) >= 0.5)
}

impl Heightmap {
    /// A heightmap of `columns` x `rows` grey levels, given row by row from the top row.
    pub fn new(columns: u32, rows: u32, levels: Vec<f32>) -> Result<Self, HeightmapError> {
        Self::check_size(columns, rows)?;
        if levels.len() != columns as usize * rows as usize {
            return Err(HeightmapError::SampleCount { columns, rows, len: levels.len() });
        }
        if let Some(index) = levels.iter().position(|level| !level.is_finite()) {
            let index = index as u32;
            return Err(HeightmapError::NotFinite { row: index / columns, column: index % columns });
        }
        Ok(Self { columns, rows, samples: Samples::Levels(levels) })
    }

    /// A heightmap of `columns` x `rows` 16-bit values (`level = value / 257`), given row by row
    /// from the top row: 2 bytes a sample.
    pub fn from_sixteen_bit(columns: u32, rows: u32, values: Vec<u16>) -> Result<Self, HeightmapError> {
        Self::check_size(columns, rows)?;
        if values.len() != columns as usize * rows as usize {
            return Err(HeightmapError::SampleCount { columns, rows, len: values.len() });
        }
        Ok(Self { columns, rows, samples: Samples::Sixteen(values) })
    }

    /// The heightmap of a decoded image. Colour images are reduced to their luminance; 8-bit
    /// images give whole levels, 16-bit ones fractional levels (`value / 257`).
    pub fn from_image(image: &DynamicImage) -> Result<Self, HeightmapError> {
        // Check the size before converting, so a huge image fails before a huge allocation.
        Self::check_size(image.width(), image.height())?;
        Self::from_luma16(image.to_luma16())
    }

    /// Like [`Self::from_image`], taking the image: a 16-bit greyscale image becomes the
    /// heightmap without a copy.
    pub fn from_image_owned(image: DynamicImage) -> Result<Self, HeightmapError> {
        Self::check_size(image.width(), image.height())?;
        Self::from_luma16(image.into_luma16())
    }

    fn from_luma16(grey: image::ImageBuffer<image::Luma<u16>, Vec<u16>>) -> Result<Self, HeightmapError> {
        let (columns, rows) = grey.dimensions();
        Self::from_sixteen_bit(columns, rows, grey.into_raw())
    }

    /// Reads a heightmap from an image file (PNG, BMP, JPEG, ...; the format is recognised from
    /// the content). The size is checked from the file's header before it is decoded. Errors
    /// name the file.
    pub fn load(path: &Path) -> Result<Self, WorldError> {
        Self::decode_from(open_decoder(path)?, path)
    }

    /// Reads a heightmap from an image held in memory, as [`Heightmap::load`] reads a file
    /// (`name` is used in messages).
    pub fn decode(bytes: &[u8], name: &str) -> Result<Self, WorldError> {
        let path = Path::new(name);
        Self::decode_from(header_decoder(image::ImageReader::new(std::io::Cursor::new(bytes)), path)?, path)
    }

    /// Checks the size a decoder's header gives against the heightmap's limits, then decodes.
    fn decode_from(decoder: impl image::ImageDecoder, path: &Path) -> Result<Self, WorldError> {
        let bad = |problem| WorldError::BadHeightmap { path: path.to_path_buf(), problem };
        let (columns, rows) = image::ImageDecoder::dimensions(&decoder);
        Self::check_size(columns, rows).map_err(bad)?;
        let image = decode_checked(decoder, path)?;
        Self::from_image_owned(image).map_err(bad)
    }

    /// Whether a heightmap may have `columns` x `rows` samples (2 to [`MAX_HEIGHTMAP_SIDE`] per side).
    pub fn check_size(columns: u32, rows: u32) -> Result<(), HeightmapError> {
        if columns < 2 || rows < 2 {
            Err(HeightmapError::TooSmall { columns, rows })
        } else if columns > MAX_HEIGHTMAP_SIDE || rows > MAX_HEIGHTMAP_SIDE {
            Err(HeightmapError::TooLarge { columns, rows })
        } else {
            Ok(())
        }
    }

    /// Samples per row (the image's width).
    pub fn columns(&self) -> u32 {
        self.columns
    }

    /// Number of rows (the image's height).
    pub fn rows(&self) -> u32 {
        self.rows
    }

    /// Grey level at `row`, `column` (0.0..=255.0 for images). Panics when out of range.
    pub fn level(&self, row: u32, column: u32) -> f32 {
        assert!(row < self.rows && column < self.columns, "sample out of range");
        let index = row as usize * self.columns as usize + column as usize;
        match &self.samples {
            Samples::Levels(levels) => levels[index],
            Samples::Sixteen(values) => level_of_sixteen(values[index]),
        }
    }

    /// The samples as stored, row by row from the top row: what [`Heightmap::new`] or
    /// [`Heightmap::from_sixteen_bit`] rebuild the same heightmap from.
    pub fn samples(&self) -> StoredSamples<'_> {
        match &self.samples {
            Samples::Levels(levels) => StoredSamples::Levels(levels),
            Samples::Sixteen(values) => StoredSamples::Sixteen(values),
        }
    }

    /// All grey levels, row by row from the top row.
    pub fn levels(&self) -> LevelIter<'_> {
        match &self.samples {
            Samples::Levels(levels) => LevelIter::Levels(levels.iter()),
            Samples::Sixteen(values) => LevelIter::Sixteen(values.iter()),
        }
    }

    /// The samples of row `row` as 16-bit values (`level * 257`, rounded and clamped), appended
    /// to `out`: what the GPU's height texture holds.
    pub fn extend_sixteen_bit_row(&self, row: u32, out: &mut Vec<u16>) {
        let start = row as usize * self.columns as usize;
        let end = start + self.columns as usize;
        match &self.samples {
            Samples::Levels(levels) => out.extend(levels[start..end].iter().map(|&l| sixteen_of_level(l))),
            Samples::Sixteen(values) => out.extend_from_slice(&values[start..end]),
        }
    }

    /// Bytes of memory one sample takes: 2 for images and large procedural maps, 4 for grids
    /// built from numbers.
    pub fn bytes_per_sample(&self) -> usize {
        match &self.samples {
            Samples::Levels(_) => size_of::<f32>(),
            Samples::Sixteen(_) => size_of::<u16>(),
        }
    }

    /// The heightmap as a 16-bit greyscale image (`level * 257`, clamped to 0..=65535).
    pub fn to_image(&self) -> image::ImageBuffer<image::Luma<u16>, Vec<u16>> {
        let mut data = Vec::with_capacity(self.columns as usize * self.rows as usize);
        for row in 0..self.rows {
            self.extend_sixteen_bit_row(row, &mut data);
        }
        image::ImageBuffer::from_raw(self.columns, self.rows, data)
            .expect("a heightmap holds exactly columns * rows levels")
    }
}

/// The grey levels of a [`Heightmap`], row by row.
#[derive(Debug, Clone)]
pub enum LevelIter<'a> {
    /// Over levels stored as numbers.
    Levels(std::slice::Iter<'a, f32>),
    /// Over 16-bit values.
    Sixteen(std::slice::Iter<'a, u16>),
}

impl Iterator for LevelIter<'_> {
    type Item = f32;

    fn next(&mut self) -> Option<f32> {
        match self {
            LevelIter::Levels(levels) => levels.next().copied(),
            LevelIter::Sixteen(values) => values.next().map(|&value| level_of_sixteen(value)),
        }
    }

    fn size_hint(&self) -> (usize, Option<usize>) {
        match self {
            LevelIter::Levels(levels) => levels.size_hint(),
            LevelIter::Sixteen(values) => values.size_hint(),
        }
    }
}

impl ExactSizeIterator for LevelIter<'_> {}

#[cfg(test)]
mod tests {
    use super::*;
    use image::{GrayImage, ImageBuffer, Luma, Rgb, RgbImage};

    #[test]
    fn sixteen_bit_values_round_as_f32_round_does() {
        let rounded = |level: f32| (level * 257.0).round().clamp(0.0, 65535.0) as u16;
        // Every value near each half step, and a spread of all the floats (negative, huge,
        // infinite, NaN).
        let halves = (-2..=65540).flat_map(|k| {
            let half = (k as f32 + 0.5) / 257.0;
            [half, f32::from_bits(half.to_bits() - 1), f32::from_bits(half.to_bits() + 1)]
        });
        let spread = (0..u32::MAX / 4099).map(|i| f32::from_bits(i * 4099));
        for level in halves.chain(spread).chain([f32::INFINITY, f32::NEG_INFINITY, f32::NAN, -0.0]) {
            assert_eq!(sixteen_of_level(level), rounded(level), "{level:e}");
        }
    }

    #[test]
    fn stored_samples_rebuild_the_same_heightmap() {
        let levels = Heightmap::new(2, 2, vec![0.5, 1.0, 254.25, 3.0]).expect("valid");
        let StoredSamples::Levels(stored) = levels.samples() else { panic!("levels stay numbers") };
        assert_eq!(Heightmap::new(2, 2, stored.to_vec()).expect("valid"), levels);
        let sixteen = Heightmap::from_sixteen_bit(3, 2, vec![0, 1, 257, 1000, 65535, 7]).expect("valid");
        let StoredSamples::Sixteen(stored) = sixteen.samples() else { panic!("16-bit stays 16-bit") };
        assert_eq!(stored, &[0, 1, 257, 1000, 65535, 7]);
    }

    #[test]
    fn eight_bit_levels_are_whole() {
        let image = GrayImage::from_fn(3, 2, |x, y| Luma([(x * 100 + y) as u8]));
        let map = Heightmap::from_image(&DynamicImage::ImageLuma8(image)).expect("valid");
        assert_eq!((map.columns(), map.rows()), (3, 2));
        assert_eq!(map.level(0, 0), 0.0);
        assert_eq!(map.level(0, 2), 200.0);
        assert_eq!(map.level(1, 1), 101.0);
    }

    #[test]
    fn sixteen_bit_levels_keep_precision() {
        let image: ImageBuffer<Luma<u16>, Vec<u16>> =
            ImageBuffer::from_fn(2, 2, |x, y| Luma([[0, 65535, 257 * 100 + 128, 1][(y * 2 + x) as usize]]));
        let map = Heightmap::from_image(&DynamicImage::ImageLuma16(image)).expect("valid");
        assert_eq!(map.level(0, 0), 0.0);
        assert_eq!(map.level(0, 1), 255.0);
        assert!((map.level(1, 0) - (100.0 + 128.0 / 257.0)).abs() < 1e-4);
        assert!(map.level(1, 1) > 0.0 && map.level(1, 1) < 0.01);
    }

    #[test]
    fn grey_rgb_reads_as_its_grey_level() {
        let image = RgbImage::from_fn(4, 3, |x, _| Rgb([x as u8 * 60; 3]));
        let map = Heightmap::from_image(&DynamicImage::ImageRgb8(image)).expect("valid");
        assert_eq!(map.level(2, 3), 180.0);
    }

    #[test]
    fn rejects_bad_grids() {
        assert_eq!(Heightmap::new(1, 5, vec![0.0; 5]), Err(HeightmapError::TooSmall { columns: 1, rows: 5 }));
        assert!(matches!(
            Heightmap::new(MAX_HEIGHTMAP_SIDE + 1, 2, Vec::new()),
            Err(HeightmapError::TooLarge { .. })
        ));
        assert!(matches!(
            Heightmap::new(2, 2, vec![0.0; 3]),
            Err(HeightmapError::SampleCount { len: 3, .. })
        ));
        assert_eq!(
            Heightmap::new(2, 2, vec![0.0, 1.0, f32::NAN, 3.0]),
            Err(HeightmapError::NotFinite { row: 1, column: 0 })
        );
    }

    #[test]
    fn images_take_two_bytes_a_sample_and_keep_their_values() {
        let image: ImageBuffer<Luma<u16>, Vec<u16>> =
            ImageBuffer::from_fn(3, 2, |x, y| Luma([(x * 20_000 + y) as u16]));
        let map = Heightmap::from_image_owned(DynamicImage::ImageLuma16(image.clone())).expect("valid");
        assert_eq!(map.bytes_per_sample(), 2);
        assert_eq!(map.to_image(), image);
        assert_eq!(map.levels().len(), 6);
        let numbers = Heightmap::new(2, 2, vec![1.0, 2.0, 3.0, 255.0]).expect("valid");
        assert_eq!(numbers.bytes_per_sample(), 4);
        let mut row = Vec::new();
        numbers.extend_sixteen_bit_row(1, &mut row);
        assert_eq!(row, vec![771, 65535]);
    }

    #[test]
    fn round_trips_through_a_sixteen_bit_image() {
        let map = Heightmap::new(3, 2, vec![0.0, 12.5, 255.0, 100.0, 99.75, 3.0]).expect("valid");
        let back = Heightmap::from_image(&DynamicImage::ImageLuma16(map.to_image())).expect("valid");
        for (a, b) in map.levels().zip(back.levels()) {
            assert!((a - b).abs() < 1.0 / 257.0, "{a} vs {b}");
        }
    }
}
