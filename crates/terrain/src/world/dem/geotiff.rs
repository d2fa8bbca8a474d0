//! GeoTIFF elevation models, read with the pure-Rust `tiff` crate: one sample a pixel of 8-, 16-,
//! 32- or 64-bit integers (signed or not) or 16-, 32- or 64-bit floats, in strips or tiles,
//! uncompressed, LZW, Deflate or PackBits, with no predictor, the horizontal one (2) or the
//! floating-point one (3), little- or big-endian, TIFF or BigTIFF.
//!
//! The GeoTIFF tags give the spacing: `ModelPixelScale` (or `ModelTransformation`) in the
//! units of the coordinate system that the `GeoKeyDirectory` names (geographic: degrees, with the
//! latitude from `ModelTiepoint`; projected: metres, or feet converted). Web Mercator (EPSG:3857)
//! metres are true metres only at the equator: they are scaled by the cosine of the latitude. The
//! `GDAL_NODATA` tag (42113, a number written as text) marks the voids.
//!
//! Strips (or rows of tiles) are decoded in parallel, each straight into its place in the result.
//! Before anything large is allocated, the declared size is checked against the limits and every
//! strip or tile against the file's length.

use std::io::Cursor;

use rayon::prelude::*;
use tiff::decoder::{ChunkType, Decoder, DecodingResult, Limits};
use tiff::tags::Tag;

use super::{DemError, Elevation, SizeLimit, Spacing};

/// The `GDAL_NODATA` tag.
const GDAL_NODATA: u16 = 42113;

/// Reads a GeoTIFF from its bytes. Errors name the file and, where one is at fault, the strip or
/// tile.
pub fn read(bytes: &[u8], name: &str, limit: SizeLimit) -> Result<Elevation, DemError> {
    let tiff_error = |error: tiff::TiffError| DemError::new(name, format!("not a readable TIFF: {error}"));
    let mut decoder = open(bytes).map_err(tiff_error)?;
    let (columns, rows) = decoder.dimensions().map_err(tiff_error)?;
    limit.check(name, u64::from(columns), u64::from(rows))?;
    let colour = decoder.colortype().map_err(tiff_error)?;
    let bits = match colour {
        tiff::ColorType::Gray(bits) => bits,
        tiff::ColorType::Multiband { bit_depth, num_samples: 1 } => bit_depth,
        other => {
            return Err(DemError::new(
                name,
                format!("holds {other:?} pixels; an elevation model has one sample a pixel"),
            ));
        }
    };
    if !matches!(bits, 8 | 16 | 32 | 64) {
        return Err(DemError::new(
            name,
            format!("{bits}-bit samples are not elevations this program reads (8, 16, 32 or 64)"),
        ));
    }
    let layout = Layout::of(&mut decoder, bytes.len(), name, columns, rows, u64::from(bits / 8))?;
    let nodata = nodata(&mut decoder);
    let spacing = spacing(&mut decoder, columns, rows);

    let (width, height) = (columns as usize, rows as usize);
    let mut heights = vec![0.0f32; width * height];
    let band_rows = layout.chunk_height as usize;
    let failures: Vec<Option<DemError>> = heights
        .par_chunks_mut(width * band_rows)
        .enumerate()
        .map_init(
            || open(bytes),
            |decoder, (band, slab)| {
                let decoder = match decoder {
                    Ok(decoder) => decoder,
                    Err(error) => return Some(DemError::new(name, format!("not a readable TIFF: {error}"))),
                };
                decode_band(decoder, &layout, band as u32, slab, width, nodata, name).err()
            },
        )
        .collect();
    if let Some(error) = failures.into_iter().flatten().next() {
        return Err(error);
    }
    Ok(Elevation { columns, rows, heights, spacing })
}

/// A decoder on `bytes` with limits that let one strip or tile of the largest accepted grid be
/// decoded (the grid's size is checked before any chunk is read).
fn open(bytes: &[u8]) -> Result<Decoder<Cursor<&[u8]>>, tiff::TiffError> {
    let mut limits = Limits::default();
    limits.decoding_buffer_size = 1 << 31;
    limits.intermediate_buffer_size = bytes.len().max(1 << 20);
    limits.ifd_value_size = 16 << 20;
    Ok(Decoder::new(Cursor::new(bytes))?.with_limits(limits))
}

/// How the image is cut into strips or tiles.
#[derive(Debug, Clone, Copy)]
struct Layout {
    tiled: bool,
    chunk_width: u32,
    chunk_height: u32,
    across: u32,
}

impl Layout {
    /// The layout, checked: the chunk count matches the image and every chunk lies within the
    /// file.
    fn of(
        decoder: &mut Decoder<Cursor<&[u8]>>,
        file_length: usize,
        name: &str,
        columns: u32,
        rows: u32,
        bytes_per_sample: u64,
    ) -> Result<Self, DemError> {
        let tiled = decoder.get_chunk_type() == ChunkType::Tile;
        let what = if tiled { "tile" } else { "strip" };
        let (chunk_width, chunk_height) = decoder.chunk_dimensions();
        let chunk_height = if tiled { chunk_height } else { chunk_height.min(rows) };
        if chunk_width == 0 || chunk_height == 0 {
            return Err(DemError::new(name, format!("declares {chunk_width}x{chunk_height}-sample {what}s")));
        }
        // A tile larger than its image, or one that would take more than a gigabyte, is a lie.
        let chunk_bytes = u64::from(chunk_width) * u64::from(chunk_height) * bytes_per_sample;
        if tiled
            && (chunk_width > columns.max(16) * 2 || chunk_height > rows.max(16) * 2 || chunk_bytes > 1 << 30)
        {
            return Err(DemError::new(
                name,
                format!("declares {chunk_width}x{chunk_height}-sample tiles for a {columns}x{rows} image"),
            ));
        }
        let across = columns.div_ceil(chunk_width);
        let down = rows.div_ceil(chunk_height);
        let expected = u64::from(across) * u64::from(down);
        let (offsets_tag, counts_tag) = if tiled {
            (Tag::TileOffsets, Tag::TileByteCounts)
        } else {
            (Tag::StripOffsets, Tag::StripByteCounts)
        };
        let read_list = |decoder: &mut Decoder<Cursor<&[u8]>>, tag| {
            decoder
                .get_tag_u64_vec(tag)
                .map_err(|error| DemError::new(name, format!("cannot read the {what} table: {error}")))
        };
        let offsets = read_list(decoder, offsets_tag)?;
        let counts = read_list(decoder, counts_tag)?;
        if offsets.len() as u64 != expected || counts.len() as u64 != expected {
            return Err(DemError::new(
                name,
                format!(
                    "lists {} {what} offsets and {} byte counts, but a {columns}x{rows} image in {chunk_width}x{chunk_height} {what}s has {expected}",
                    offsets.len(),
                    counts.len()
                ),
            ));
        }
        for (index, (&offset, &count)) in offsets.iter().zip(&counts).enumerate() {
            let end = offset.checked_add(count);
            if end.is_none_or(|end| end > file_length as u64) {
                let place = chunk_place(tiled, index as u32, across, chunk_width, chunk_height);
                return Err(DemError::new(
                    name,
                    format!(
                        "{what} {index} ({place}) lies at bytes {offset}..{}, past the end of the file ({file_length} bytes): the file is truncated or corrupt",
                        offset.saturating_add(count)
                    ),
                ));
            }
        }
        Ok(Self { tiled, chunk_width, chunk_height, across })
    }
}

/// Where chunk `index` sits, for messages: its row and column of tiles, or its first row.
fn chunk_place(tiled: bool, index: u32, across: u32, width: u32, height: u32) -> String {
    if tiled {
        let (row, column) = (index / across, index % across);
        format!("tile row {row}, column {column}: pixels from x {}, y {}", column * width, row * height)
    } else {
        format!("rows {} to {}", index * height, (index + 1) * height - 1)
    }
}

/// Decodes the chunks of band `band` (one strip, or one row of tiles) into `slab`, its rows of
/// the result (`width` samples a row).
fn decode_band(
    decoder: &mut Decoder<Cursor<&[u8]>>,
    layout: &Layout,
    band: u32,
    slab: &mut [f32],
    width: usize,
    nodata: Option<f64>,
    name: &str,
) -> Result<(), DemError> {
    let what = if layout.tiled { "tile" } else { "strip" };
    for column in 0..layout.across {
        let index = band * layout.across + column;
        let fail = |error: tiff::TiffError| {
            let place =
                chunk_place(layout.tiled, index, layout.across, layout.chunk_width, layout.chunk_height);
            DemError::new(name, format!("{what} {index} ({place}) cannot be decoded: {error}"))
        };
        let result = decoder.read_chunk(index).map_err(fail)?;
        let (data_width, data_height) = decoder.chunk_data_dimensions(index);
        let (data_width, data_height) = (data_width as usize, data_height as usize);
        let x0 = (column * layout.chunk_width) as usize;
        let rows_here = slab.len() / width;
        if x0 + data_width > width || data_height > rows_here {
            return Err(fail(tiff::TiffError::FormatError(
                tiff::TiffFormatError::InconsistentSizesEncountered,
            )));
        }
        macro_rules! place {
            ($values:expr, $convert:expr) => {{
                let values = $values;
                if values.len() < data_width * data_height {
                    return Err(fail(tiff::TiffError::FormatError(
                        tiff::TiffFormatError::InconsistentSizesEncountered,
                    )));
                }
                for (row, source) in values.chunks(data_width).take(data_height).enumerate() {
                    let target = &mut slab[row * width + x0..row * width + x0 + data_width];
                    for (out, &value) in target.iter_mut().zip(source) {
                        *out = $convert(value);
                    }
                }
            }};
        }
        let whole = |value: f64| match nodata {
            Some(nodata) if value == nodata => f32::NAN,
            _ => value as f32,
        };
        let float = |value: f64| match nodata {
            _ if !value.is_finite() => f32::NAN,
            Some(nodata) if value == nodata || value as f32 == nodata as f32 => f32::NAN,
            _ => value as f32,
        };
        match result {
            DecodingResult::U8(v) => place!(v, |x: u8| whole(f64::from(x))),
            DecodingResult::U16(v) => place!(v, |x: u16| whole(f64::from(x))),
            DecodingResult::U32(v) => place!(v, |x: u32| whole(f64::from(x))),
            DecodingResult::U64(v) => place!(v, |x: u64| whole(x as f64)),
            DecodingResult::I8(v) => place!(v, |x: i8| whole(f64::from(x))),
            DecodingResult::I16(v) => place!(v, |x: i16| whole(f64::from(x))),
            DecodingResult::I32(v) => place!(v, |x: i32| whole(f64::from(x))),
            DecodingResult::I64(v) => place!(v, |x: i64| whole(x as f64)),
            DecodingResult::F16(v) => {
                let values: Vec<f32> = v.into_iter().map(|x| x.to_f32()).collect();
                place!(values, |x: f32| float(f64::from(x)))
            }
            DecodingResult::F32(v) => place!(v, |x: f32| float(f64::from(x))),
            DecodingResult::F64(v) => place!(v, |x: f64| float(x)),
        }
    }
    Ok(())
}

/// The `GDAL_NODATA` value, if the file has a readable one.
fn nodata(decoder: &mut Decoder<Cursor<&[u8]>>) -> Option<f64> {
    let value = decoder.find_tag(Tag::Unknown(GDAL_NODATA)).ok()??;
    match value {
        tiff::decoder::ifd::Value::Ascii(text) => {
            text.trim_matches(|c: char| c == '\0' || c.is_whitespace()).parse().ok()
        }
        other => other.into_f64().ok(),
    }
}

/// The sample spacing the GeoTIFF tags state.
fn spacing(decoder: &mut Decoder<Cursor<&[u8]>>, columns: u32, rows: u32) -> Spacing {
    let doubles = |decoder: &mut Decoder<Cursor<&[u8]>>, tag| -> Option<Vec<f64>> {
        decoder.find_tag(tag).ok()??.into_f64_vec().ok()
    };
    let scale = doubles(decoder, Tag::ModelPixelScaleTag);
    let tiepoint = doubles(decoder, Tag::ModelTiepointTag);
    let transformation = doubles(decoder, Tag::ModelTransformationTag);
    // (x step, y step) and the model y of the top edge's row 0.
    let (step_x, step_y, top) = match (&scale, &transformation) {
        (Some(scale), _) if scale.len() >= 2 => {
            let top = tiepoint.as_ref().filter(|t| t.len() >= 6).map(|t| t[4] + t[1] * scale[1]);
            (scale[0].abs(), scale[1].abs(), top)
        }
        (_, Some(m)) if m.len() >= 16 => {
            let step_x = m[0].hypot(m[4]);
            let step_y = m[1].hypot(m[5]);
            (step_x, step_y, Some(m[7]))
        }
        _ => return Spacing::Unknown,
    };
    if !(step_x > 0.0 && step_y > 0.0 && step_x.is_finite() && step_y.is_finite()) {
        return Spacing::Unknown;
    }
    let keys = GeoKeys::read(decoder);
    let centre_y = top.map(|top| top - step_y * f64::from(rows) / 2.0);
    let geographic = match keys.model_type {
        Some(2) => true,
        Some(1) => false,
        // No model type: degrees if the numbers can only be degrees.
        _ => step_x < 0.01 && centre_y.is_none_or(|y| y.abs() <= 90.0) && keys.projected.is_none(),
    };
    let _ = columns;
    if geographic {
        let unit = match keys.angular_unit {
            Some(9101) => 180.0 / std::f64::consts::PI, // radians
            Some(9105) => 0.9,                          // grads
            Some(9104) => 1.0 / 3600.0,                 // arc-seconds
            _ => 1.0,
        };
        return Spacing::Degrees {
            longitude: step_x * unit,
            latitude: step_y * unit,
            centre_latitude: centre_y.map_or(0.0, |y| (y * unit).clamp(-90.0, 90.0)),
        };
    }
    let unit = match keys.linear_unit {
        Some(9002) => 0.3048,
        Some(9003) => 1200.0 / 3937.0,
        Some(9036) => 1000.0,
        _ => 1.0,
    };
    let mercator = matches!(keys.projected, Some(3857 | 3785));
    let shrink = match (mercator, centre_y) {
        (true, Some(y)) => 1.0 / ((y * unit) / 6_378_137.0).cosh(),
        _ => 1.0,
    };
    Spacing::Metres { x: step_x * unit * shrink, y: step_y * unit * shrink }
}

/// The GeoKeys this reader uses.
#[derive(Debug, Default)]
struct GeoKeys {
    model_type: Option<u16>,
    projected: Option<u16>,
    linear_unit: Option<u16>,
    angular_unit: Option<u16>,
}

impl GeoKeys {
    fn read(decoder: &mut Decoder<Cursor<&[u8]>>) -> Self {
        let mut keys = Self::default();
        let Some(directory) =
            decoder.find_tag(Tag::GeoKeyDirectoryTag).ok().flatten().and_then(|v| v.into_u16_vec().ok())
        else {
            return keys;
        };
        // A header of four shorts, then entries of (key, location, count, value); only the
        // values held in the entry itself (location 0) are read.
        for entry in directory.get(4..).unwrap_or_default().chunks_exact(4) {
            let (key, location, value) = (entry[0], entry[1], entry[3]);
            if location != 0 {
                continue;
            }
            match key {
                1024 => keys.model_type = Some(value),
                3072 => keys.projected = Some(value),
                3076 => keys.linear_unit = Some(value),
                2054 => keys.angular_unit = Some(value),
                _ => {}
            }
        }
        keys
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use tiff::encoder::{Compression, DeflateLevel, TiffEncoder, colortype};
    use tiff::tags::Predictor;

    const LIMIT: SizeLimit = SizeLimit { allow_downsampling: false };

    /// GeoKeys: projected UTM 33N in metres, or geographic WGS 84.
    const PROJECTED: [u16; 12] = [1, 1, 0, 2, 1024, 0, 1, 1, 3072, 0, 1, 32633];
    const GEOGRAPHIC: [u16; 12] = [1, 1, 0, 2, 1024, 0, 1, 2, 2048, 0, 1, 4326];

    /// A 5 x 4 strip TIFF of `values` written by the tiff crate's encoder, with a 30 m projected
    /// grid's tags and `nodata`.
    fn encoded<C: colortype::ColorType>(
        values: &[C::Inner],
        compression: Compression,
        predictor: Predictor,
        nodata: Option<&str>,
    ) -> Vec<u8>
    where
        [C::Inner]: tiff::encoder::TiffValue,
    {
        let mut bytes = Cursor::new(Vec::new());
        let mut encoder = TiffEncoder::new(&mut bytes)
            .expect("encoder")
            .with_compression(compression)
            .with_predictor(predictor);
        let mut image = encoder.new_image::<C>(5, 4).expect("image");
        image.rows_per_strip(3).expect("strips");
        let dir = image.encoder();
        dir.write_tag(Tag::ModelPixelScaleTag, &[30.0f64, 30.0, 0.0][..]).expect("tag");
        dir.write_tag(Tag::ModelTiepointTag, &[0.0f64, 0.0, 0.0, 500_000.0, 7_000_000.0, 0.0][..])
            .expect("tag");
        dir.write_tag(Tag::GeoKeyDirectoryTag, &PROJECTED[..]).expect("tag");
        if let Some(nodata) = nodata {
            dir.write_tag(Tag::Unknown(GDAL_NODATA), nodata).expect("tag");
        }
        image.write_data(values).expect("data");
        bytes.into_inner()
    }

    fn compressions() -> [(Compression, &'static str); 4] {
        [
            (Compression::Uncompressed, "uncompressed"),
            (Compression::Lzw, "LZW"),
            (Compression::Deflate(DeflateLevel::Fast), "Deflate"),
            (Compression::Packbits, "PackBits"),
        ]
    }

    fn expected(nodata_at: Option<usize>) -> Vec<f32> {
        (0..20).map(|i| if Some(i) == nodata_at { f32::NAN } else { (i * 7 % 23) as f32 }).collect()
    }

    fn same(a: &[f32], b: &[f32]) -> bool {
        a.len() == b.len() && a.iter().zip(b).all(|(x, y)| x == y || (x.is_nan() && y.is_nan()))
    }

    #[test]
    fn every_sample_type_compression_and_horizontal_predictor() {
        let base: Vec<u32> = (0..20).map(|i| i * 7 % 23).collect();
        for (compression, compression_name) in compressions() {
            for predictor in [Predictor::None, Predictor::Horizontal] {
                let floats = predictor == Predictor::None;
                let files = [
                    (
                        "u8",
                        Some(encoded::<colortype::Gray8>(
                            &base.iter().map(|&v| v as u8).collect::<Vec<_>>(),
                            compression,
                            predictor,
                            Some("0"),
                        )),
                    ),
                    (
                        "i8",
                        Some(encoded::<colortype::GrayI8>(
                            &base.iter().map(|&v| v as i8).collect::<Vec<_>>(),
                            compression,
                            predictor,
                            Some("0"),
                        )),
                    ),
                    (
                        "u16",
                        Some(encoded::<colortype::Gray16>(
                            &base.iter().map(|&v| v as u16).collect::<Vec<_>>(),
                            compression,
                            predictor,
                            Some("0"),
                        )),
                    ),
                    (
                        "i16",
                        Some(encoded::<colortype::GrayI16>(
                            &base.iter().map(|&v| v as i16).collect::<Vec<_>>(),
                            compression,
                            predictor,
                            Some("0"),
                        )),
                    ),
                    ("u32", Some(encoded::<colortype::Gray32>(&base, compression, predictor, Some("0")))),
                    (
                        "i32",
                        Some(encoded::<colortype::GrayI32>(
                            &base.iter().map(|&v| v as i32).collect::<Vec<_>>(),
                            compression,
                            predictor,
                            Some("0"),
                        )),
                    ),
                    // The encoder refuses the horizontal predictor on floats (the real
                    // Longyearbyen DEM has it: see the tests in crates/terrain/tests/dem.rs).
                    (
                        "f32",
                        floats.then(|| {
                            encoded::<colortype::Gray32Float>(
                                &base.iter().map(|&v| v as f32).collect::<Vec<_>>(),
                                compression,
                                predictor,
                                Some("0.0"),
                            )
                        }),
                    ),
                    (
                        "f64",
                        floats.then(|| {
                            encoded::<colortype::Gray64Float>(
                                &base.iter().map(|&v| f64::from(v)).collect::<Vec<_>>(),
                                compression,
                                predictor,
                                Some("0"),
                            )
                        }),
                    ),
                ];
                for (kind, bytes) in files {
                    let Some(bytes) = bytes else { continue };
                    let what = format!("{kind} {compression_name} {predictor:?}");
                    let dem = read(&bytes, "t.tif", LIMIT).unwrap_or_else(|e| panic!("{what}: {e}"));
                    assert_eq!((dem.columns, dem.rows), (5, 4), "{what}");
                    // Sample 0 is 0, the nodata value.
                    assert!(same(&dem.heights, &expected(Some(0))), "{what}: {:?}", dem.heights);
                    assert_eq!(dem.spacing, Spacing::Metres { x: 30.0, y: 30.0 }, "{what}");
                }
            }
        }
    }

    /// A little-endian TIFF built by hand, for what the encoder does not write (tiles, the
    /// floating-point predictor) and for lies.
    struct Handmade {
        width: u32,
        height: u32,
        tile: (u32, u32),
        predictor: u16,
        /// Tiles to list (default: all); their data is written in order.
        tiles_listed: Option<usize>,
        /// Added to every tile offset.
        offset_shift: u32,
        geographic: bool,
    }

    impl Handmade {
        fn new(width: u32, height: u32, tile: (u32, u32)) -> Self {
            Self { width, height, tile, predictor: 1, tiles_listed: None, offset_shift: 0, geographic: false }
        }

        /// Float samples `value(x, y)`, in tiles (padded with zeros), uncompressed.
        fn bytes(&self, value: impl Fn(u32, u32) -> f32) -> Vec<u8> {
            let (tw, th) = self.tile;
            let (across, down) = (self.width.div_ceil(tw), self.height.div_ceil(th));
            let mut tiles: Vec<Vec<u8>> = Vec::new();
            for ty in 0..down {
                for tx in 0..across {
                    let mut data = Vec::new();
                    for y in 0..th {
                        let row: Vec<f32> = (0..tw)
                            .map(|x| {
                                let (px, py) = (tx * tw + x, ty * th + y);
                                if px < self.width && py < self.height { value(px, py) } else { 0.0 }
                            })
                            .collect();
                        data.extend(if self.predictor == 3 { float_predicted(&row) } else { le(&row) });
                    }
                    tiles.push(data);
                }
            }
            let listed = self.tiles_listed.unwrap_or(tiles.len());
            let scale = if self.geographic { [0.001, 0.001, 0.0] } else { [10.0, 10.0, 0.0] };
            let tie = if self.geographic {
                [0.0, 0.0, 0.0, 10.0, 60.5, 0.0]
            } else {
                [0.0, 0.0, 0.0, 0.0, 0.0, 0.0]
            };
            let keys: &[u16] = if self.geographic { &GEOGRAPHIC } else { &PROJECTED };
            // Entries: (tag, type, count, value or offset of external data).
            let mut external: Vec<u8> = Vec::new();
            let entry_count = 16u32;
            let ifd_size = 2 + entry_count * 12 + 4;
            let external_start = 8 + ifd_size;
            let mut put = |data: &[u8]| {
                let offset = external_start + external.len() as u32;
                external.extend_from_slice(data);
                if external.len() % 2 == 1 {
                    external.push(0);
                }
                offset
            };
            let doubles = |v: &[f64]| v.iter().flat_map(|d| d.to_le_bytes()).collect::<Vec<u8>>();
            let scale_at = put(&doubles(&scale));
            let tie_at = put(&doubles(&tie));
            let keys_at = put(&keys.iter().flat_map(|k| k.to_le_bytes()).collect::<Vec<u8>>());
            let offsets_at = put(&vec![0u8; listed * 4]);
            let counts_at = put(&tiles
                .iter()
                .take(listed)
                .flat_map(|t| (t.len() as u32).to_le_bytes())
                .collect::<Vec<u8>>());
            let data_start = external_start + external.len() as u32;
            let mut offsets = Vec::new();
            let mut at = data_start;
            for tile in tiles.iter().take(listed) {
                offsets.extend((at + self.offset_shift).to_le_bytes());
                at += tile.len() as u32;
            }
            let o = (offsets_at - external_start) as usize;
            external[o..o + offsets.len()].copy_from_slice(&offsets);
            let entries: [(u16, u16, u32, u32); 16] = [
                (256, 4, 1, self.width),
                (257, 4, 1, self.height),
                (258, 3, 1, 32),
                (259, 3, 1, 1),
                (262, 3, 1, 1),
                (277, 3, 1, 1),
                (284, 3, 1, 1),
                (317, 3, 1, u32::from(self.predictor)),
                (322, 4, 1, tw),
                (323, 4, 1, th),
                (
                    324,
                    4,
                    listed as u32,
                    if listed == 1 {
                        u32::from_le_bytes(offsets[..4].try_into().expect("4"))
                    } else {
                        offsets_at
                    },
                ),
                (325, 4, listed as u32, if listed == 1 { tiles[0].len() as u32 } else { counts_at }),
                (339, 3, 1, 3),
                (33550, 12, 3, scale_at),
                (33922, 12, 6, tie_at),
                (34735, 3, keys.len() as u32, keys_at),
            ];
            let mut file = b"II*\0".to_vec();
            file.extend(8u32.to_le_bytes());
            file.extend((entries.len() as u16).to_le_bytes());
            for (tag, kind, count, value) in entries {
                file.extend(tag.to_le_bytes());
                file.extend(kind.to_le_bytes());
                file.extend(count.to_le_bytes());
                if kind == 3 && count == 1 {
                    file.extend((value as u16).to_le_bytes());
                    file.extend([0, 0]);
                } else {
                    file.extend(value.to_le_bytes());
                }
            }
            file.extend(0u32.to_le_bytes());
            file.extend(external);
            for tile in tiles.iter().take(listed) {
                file.extend(tile);
            }
            file
        }
    }

    fn le(row: &[f32]) -> Vec<u8> {
        row.iter().flat_map(|v| v.to_le_bytes()).collect()
    }

    /// A row under the floating-point predictor (3): the samples' bytes split into planes, most
    /// significant first, then differenced byte by byte.
    fn float_predicted(row: &[f32]) -> Vec<u8> {
        let n = row.len();
        let mut planes = vec![0u8; n * 4];
        for (i, v) in row.iter().enumerate() {
            for (b, byte) in v.to_be_bytes().into_iter().enumerate() {
                planes[b * n + i] = byte;
            }
        }
        for k in (1..planes.len()).rev() {
            planes[k] = planes[k].wrapping_sub(planes[k - 1]);
        }
        planes
    }

    fn ramp(x: u32, y: u32) -> f32 {
        1000.0 + x as f32 * 1.5 - y as f32 * 0.25
    }

    #[test]
    fn tiles_with_and_without_the_floating_point_predictor() {
        for predictor in [1, 3] {
            let mut file = Handmade::new(37, 21, (16, 16));
            file.predictor = predictor;
            let dem = read(&file.bytes(ramp), "tiled.tif", LIMIT).expect("valid");
            assert_eq!((dem.columns, dem.rows), (37, 21));
            let want: Vec<f32> = (0..21 * 37).map(|i| ramp(i % 37, i / 37)).collect();
            assert_eq!(dem.heights, want, "predictor {predictor}");
            assert_eq!(dem.spacing, Spacing::Metres { x: 10.0, y: 10.0 });
        }
    }

    #[test]
    fn geographic_grids_give_degrees_at_their_latitude() {
        let mut file = Handmade::new(32, 20, (16, 16));
        file.geographic = true;
        let dem = read(&file.bytes(ramp), "geo.tif", LIMIT).expect("valid");
        let Spacing::Degrees { longitude, latitude, centre_latitude } = dem.spacing else {
            panic!("{:?}", dem.spacing)
        };
        assert_eq!((longitude, latitude), (0.001, 0.001));
        assert!((centre_latitude - 60.49).abs() < 1e-9, "{centre_latitude}");
        // At 60.5 N a degree of longitude is about half a degree of latitude.
        let (x, y) = dem.spacing.metres().expect("metres");
        assert!((x / y - 0.4935).abs() < 0.01, "{x} {y}");
    }

    #[test]
    fn lies_are_refused_naming_the_file_and_tile() {
        let mut missing = Handmade::new(37, 21, (16, 16));
        missing.tiles_listed = Some(4);
        let error = read(&missing.bytes(ramp), "few.tif", LIMIT).expect_err("tile count").to_string();
        // The tiff crate itself finds this one while reading the directory.
        assert!(error.starts_with("few.tif: ") && error.contains("inconsistent sizes"), "{error}");

        let mut past = Handmade::new(37, 21, (16, 16));
        past.offset_shift = 100_000;
        let error = read(&past.bytes(ramp), "past.tif", LIMIT).expect_err("past the end").to_string();
        assert!(
            error.starts_with("past.tif: tile 0 (tile row 0, column 0")
                && error.contains("past the end of the file"),
            "{error}"
        );

        let huge = Handmade::new(100_000, 100_000, (16, 16)).bytes_header_only();
        let error = read(&huge, "huge.tif", LIMIT).expect_err("huge").to_string();
        assert!(
            error.contains("100000x100000 samples") && error.contains("refused before decoding"),
            "{error}"
        );
        let error =
            read(&huge, "huge.tif", SizeLimit { allow_downsampling: true }).expect_err("huge").to_string();
        assert!(error.contains("too large even to downsample"), "{error}");

        let good = Handmade::new(37, 21, (16, 16)).bytes(ramp);
        for cut in [10, 100, 300, good.len() - 7] {
            assert!(read(&good[..cut], "cut.tif", LIMIT).is_err(), "cut at {cut}");
        }
    }

    impl Handmade {
        /// A file that declares this size but whose tile table is a single tile (never read:
        /// the size is refused first).
        fn bytes_header_only(&self) -> Vec<u8> {
            let mut small = Handmade::new(self.width, self.height, self.tile);
            small.tiles_listed = Some(1);
            // Build the IFD without materialising the declared image: one tile of data.
            let (tw, th) = self.tile;
            let tile =
                Handmade { width: tw, height: th, ..Handmade::new(tw, th, self.tile) }.bytes(|_, _| 0.0);
            // Patch the width and height entries (the first two, values at bytes 18 and 30) and
            // the tile's (entries 8 and 9), so that one tile still covers the image.
            let mut file = tile;
            file[18..22].copy_from_slice(&self.width.to_le_bytes());
            file[30..34].copy_from_slice(&self.height.to_le_bytes());
            file[114..118].copy_from_slice(&self.width.to_le_bytes());
            file[126..130].copy_from_slice(&self.height.to_le_bytes());
            let _ = small;
            file
        }
    }
}
