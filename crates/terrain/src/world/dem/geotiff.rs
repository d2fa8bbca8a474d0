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
