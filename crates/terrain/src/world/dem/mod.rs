//! Elevation data of the Earth (digital elevation models): GeoTIFF, SRTM `.hgt`, Esri ASCII
//! grids and OpenEXR height images, recognised from their content.
//!
//! A reader takes the file's bytes (no file system: the web page can feed it a dropped file) and
//! returns an [`Elevation`]: heights in **metres**, row 0 the northern (top) row, `NaN` where the
//! file has no data, and the horizontal spacing the file states ([`Spacing`]). [`prepare`] then
//! fills the voids from their neighbours (keeping a mask of them), makes the cells square in
//! metres and fits the grid within the engine's size limit; [`place`] puts the result in the
//! scene. The course's 8-bit greyscale heightmaps never come here: they keep their own path
//! ([`super::Heightmap`]).

pub mod ascii_grid;
pub mod fill;
pub mod geotiff;
pub mod hgt;
pub mod place;
pub mod resample;

use std::path::Path;

pub use place::{DemScene, PlaceOptions, WaterLevel};

use super::MAX_HEIGHTMAP_SIDE;

/// Largest number of samples a file may hold to be decoded at all, when it is to be downsampled
/// (`--max-size`): 16385 x 16385 float samples (about 1 GiB). Larger files are refused before
/// anything is decoded.
pub const MAX_DECODED_SAMPLES: u64 = 16_385 * 16_385;

/// Why elevation data could not be read: the file's name and what is wrong, with the row, tile or
/// strip where there is one.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{file}: {problem}")]
pub struct DemError {
    /// The file, as named to the reader.
    pub file: String,
    /// What is wrong with it.
    pub problem: String,
}

impl DemError {
    /// An error about `file`.
    pub fn new(file: &str, problem: impl Into<String>) -> Self {
        Self { file: file.to_string(), problem: problem.into() }
    }
}

/// The horizontal spacing of a grid's samples, as its file states it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Spacing {
    /// A projected grid: metres between neighbouring samples along x (east) and along the rows
    /// (north-south).
    Metres {
        /// Metres between columns.
        x: f64,
        /// Metres between rows.
        y: f64,
    },
    /// A geographic grid: degrees between neighbouring samples, and the latitude of the grid's
    /// centre (degrees north) at which degrees are turned into metres.
    Degrees {
        /// Degrees of longitude between columns.
        longitude: f64,
        /// Degrees of latitude between rows.
        latitude: f64,
        /// Latitude of the grid's centre, degrees north.
        centre_latitude: f64,
    },
    /// The file does not say (`--cell-size` gives it).
    Unknown,
}

impl Spacing {
    /// Metres between columns and between rows, where the file says: degrees become metres with
    /// the length of a degree on the WGS 84 ellipsoid at the centre latitude (a degree of
    /// longitude shrinks with the latitude's cosine).
    pub fn metres(&self) -> Option<(f64, f64)> {
        match *self {
            Spacing::Metres { x, y } => Some((x, y)),
            Spacing::Degrees { longitude, latitude, centre_latitude } => {
                let (east, north) = metres_per_degree(centre_latitude);
                Some((longitude * east, latitude * north))
            }
            Spacing::Unknown => None,
        }
    }
}

/// Metres a degree of longitude and a degree of latitude measure at `latitude` (degrees) on the
/// WGS 84 ellipsoid.
pub fn metres_per_degree(latitude: f64) -> (f64, f64) {
    const A: f64 = 6_378_137.0;
    const E2: f64 = 6.694_379_990_14e-3;
    let phi = latitude.clamp(-90.0, 90.0).to_radians();
    let w = (1.0 - E2 * phi.sin().powi(2)).sqrt();
    let east = std::f64::consts::PI / 180.0 * A * phi.cos() / w;
    let north = std::f64::consts::PI / 180.0 * A * (1.0 - E2) / (w * w * w);
    (east, north)
}

/// A grid of elevations as read from a file.
#[derive(Debug, Clone, PartialEq)]
pub struct Elevation {
    /// Samples per row (west to east).
    pub columns: u32,
    /// Rows (north to south).
    pub rows: u32,
    /// Heights in metres, row by row from the northern row; `NaN` where the file has no data.
    pub heights: Vec<f32>,
    /// The spacing the file states.
    pub spacing: Spacing,
}

/// Formats of elevation files, recognised from their first bytes (and, for headerless SRTM
/// tiles, from their length or name).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DemFormat {
    /// TIFF or BigTIFF (GeoTIFF tags read where present).
    GeoTiff,
    /// SRTM `.hgt`: big-endian 16-bit samples, no header.
    Hgt,
    /// Esri ASCII grid (`ncols`, `nrows`, ... then numbers).
    AsciiGrid,
    /// OpenEXR: its first channel (or luminance) as metres.
    Exr,
}

/// The elevation format of a file's `bytes` (`name` is its file name, used only for SRTM tiles,
/// which have no header); `None` for anything else (images such as PNG or BMP included, which
/// the greyscale heightmap path reads).
pub fn detect(bytes: &[u8], name: &str) -> Option<DemFormat> {
    detect_from_head(bytes, bytes.len() as u64, name)
}

/// [`detect`] from the first bytes of a file (a kilobyte is enough) and its full length.
pub fn detect_from_head(head: &[u8], length: u64, name: &str) -> Option<DemFormat> {
    if head.starts_with(b"II*\0")
        || head.starts_with(b"MM\0*")
        || head.starts_with(b"II+\0")
        || head.starts_with(b"MM\0+")
    {
        return Some(DemFormat::GeoTiff);
    }
    if head.starts_with(&[0x76, 0x2f, 0x31, 0x01]) {
        return Some(DemFormat::Exr);
    }
    if ascii_grid::looks_like(head) {
        return Some(DemFormat::AsciiGrid);
    }
    let known_image = head.starts_with(b"\x89PNG")
        || head.starts_with(b"BM")
        || head.starts_with(&[0xff, 0xd8])
        || head.starts_with(b"#?RADIANCE")
        || head.starts_with(b"#?RGBE");
    if known_image {
        return None;
    }
    let is_hgt_name = Path::new(name).extension().is_some_and(|e| e.eq_ignore_ascii_case("hgt"));
    let hgt_length = usize::try_from(length).ok().and_then(hgt::side_of_length).is_some();
    (hgt_length || is_hgt_name).then_some(DemFormat::Hgt)
}

/// Whether a file's name or first bytes make it elevation data rather than an image; reads at
/// most the first kilobyte (and the length) of the file.
pub fn is_elevation_file(path: &Path) -> std::io::Result<bool> {
    use std::io::Read;
    // Never waits on a named pipe; a folder or device is refused.
    let file = atomic_file::open_regular(path)?;
    let length = file.metadata()?.len();
    let mut head = Vec::with_capacity(1024);
    file.take(1024).read_to_end(&mut head)?;
    let name = path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    Ok(detect_from_head(&head, length, &name).is_some())
}

/// Reads elevation data of any [`DemFormat`] from its bytes (`name` names it in messages and
/// gives an SRTM tile's corner). Sizes are checked before any large allocation: a grid may have
/// at most [`MAX_HEIGHTMAP_SIDE`] samples a side, or up to [`MAX_DECODED_SAMPLES`] samples when
/// `allow_downsampling` (it is then reduced by [`prepare`]).
pub fn read(bytes: &[u8], name: &str, allow_downsampling: bool) -> Result<Elevation, DemError> {
    let format = detect(bytes, name).ok_or_else(|| {
        DemError::new(
            name,
            "not elevation data this program reads (GeoTIFF, SRTM .hgt, Esri ASCII grid, OpenEXR)",
        )
    })?;
    let limit = SizeLimit { allow_downsampling };
    match format {
        DemFormat::GeoTiff => geotiff::read(bytes, name, limit),
        DemFormat::Hgt => hgt::read(bytes, name),
        DemFormat::AsciiGrid => ascii_grid::read(bytes, name, limit),
        DemFormat::Exr => read_exr(bytes, name, limit),
    }
}

/// Reads elevation data from a file: the file is read whole, then [`read`]. Errors name the file.
pub fn read_file(path: &Path, allow_downsampling: bool) -> Result<Elevation, DemError> {
    let name = path.display().to_string();
    let bytes = atomic_file::read_regular(path)
        .map_err(|error| DemError::new(&name, format!("cannot read: {error}")))?;
    read(&bytes, &name, allow_downsampling)
}

/// How large a grid a reader may decode.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SizeLimit {
    /// Whether grids larger than [`MAX_HEIGHTMAP_SIDE`] (up to [`MAX_DECODED_SAMPLES`]) may be
    /// decoded, to be downsampled afterwards.
    pub allow_downsampling: bool,
}

impl SizeLimit {
    /// Checks a declared grid size before anything is allocated for it.
    pub fn check(&self, name: &str, columns: u64, rows: u64) -> Result<(), DemError> {
        if columns < 2 || rows < 2 {
            return Err(DemError::new(
                name,
                format!("a {columns}x{rows} grid has no cell to draw (at least 2x2)"),
            ));
        }
        let side = u64::from(MAX_HEIGHTMAP_SIDE);
        if columns <= side && rows <= side {
            return Ok(());
        }
        if !self.allow_downsampling {
            return Err(DemError::new(
                name,
                format!(
                    "{columns}x{rows} samples is more than the {MAX_HEIGHTMAP_SIDE} a side the terrain may have; \
                     refused before decoding (pass --max-size N to downsample it to N a side)"
                ),
            ));
        }
        if columns.saturating_mul(rows) > MAX_DECODED_SAMPLES {
            return Err(DemError::new(
                name,
                format!(
                    "{columns}x{rows} samples is too large even to downsample (at most {MAX_DECODED_SAMPLES} samples are decoded); refused before decoding"
                ),
            ));
        }
        Ok(())
    }
}

/// OpenEXR: the first channel (or the luminance of RGB), taken as metres; the file states no
/// spacing.
fn read_exr(bytes: &[u8], name: &str, limit: SizeLimit) -> Result<Elevation, DemError> {
    use image::ImageDecoder;
    let bad =
        |error: image::ImageError| DemError::new(name, format!("not a readable OpenEXR image: {error}"));
    let decoder = image::codecs::openexr::OpenExrDecoder::new(std::io::Cursor::new(bytes)).map_err(bad)?;
    let (columns, rows) = decoder.dimensions();
    limit.check(name, u64::from(columns), u64::from(rows))?;
    let image = image::DynamicImage::from_decoder(decoder).map_err(bad)?;
    let heights = match image {
        image::DynamicImage::ImageRgb32F(rgb) => {
            rgb.pixels().map(|p| 0.2126 * p.0[0] + 0.7152 * p.0[1] + 0.0722 * p.0[2]).collect()
        }
        image::DynamicImage::ImageRgba32F(rgba) => {
            rgba.pixels().map(|p| 0.2126 * p.0[0] + 0.7152 * p.0[1] + 0.0722 * p.0[2]).collect()
        }
        other => other.to_luma32f().into_raw(),
    };
    let heights = heights.into_iter().map(|h: f32| if h.is_finite() { h } else { f32::NAN }).collect();
    Ok(Elevation { columns, rows, heights, spacing: Spacing::Unknown })
}

/// What [`prepare`] did to a grid, for messages.
#[derive(Debug, Clone, PartialEq)]
pub struct Prepared {
    /// Samples per row.
    pub columns: u32,
    /// Rows.
    pub rows: u32,
    /// Heights in metres, voids filled, row by row from the north.
    pub heights: Vec<f32>,
    /// `true` where the file had no data (filled from the neighbours), same layout.
    pub voids: Vec<bool>,
    /// Metres between neighbouring samples (square cells).
    pub cell_size: f64,
    /// The file's own size, before any resampling.
    pub source_size: (u32, u32),
    /// Whether the spacing came from `--cell-size` (the file said nothing).
    pub cell_size_given: bool,
    /// Why the grid was resampled, if it was (non-square cells, `--max-size`).
    pub resampled: Option<String>,
    /// Samples without data in the file (before any resampling).
    pub source_voids: usize,
}

/// Makes `elevation` ready for the terrain: voids filled from their neighbours (and kept in a
/// mask), cells made square in metres (`cell_size` in metres is used where the file states no
/// spacing, 1 m without it), and the grid reduced to at most `max_side` samples a side.
pub fn prepare(
    elevation: Elevation,
    name: &str,
    cell_size: Option<f64>,
    max_side: u32,
) -> Result<Prepared, DemError> {
    let Elevation { columns, rows, heights, spacing } = elevation;
    let max_side = max_side.clamp(2, MAX_HEIGHTMAP_SIDE);
    let (filled, voids) = fill::fill_voids(columns, rows, heights)
        .ok_or_else(|| DemError::new(name, "every sample is nodata: there is no height to draw"))?;
    let source_voids = voids.iter().filter(|&&v| v).count();
    let (metres, cell_size_given) = match spacing.metres() {
        Some(metres) => (metres, false),
        None => {
            let cell = cell_size.unwrap_or(1.0);
            ((cell, cell), true)
        }
    };
    let (dx, dy) = metres;
    if !(dx.is_finite() && dy.is_finite() && dx > 0.0 && dy > 0.0) {
        return Err(DemError::new(
            name,
            format!("the file's sample spacing ({dx} m x {dy} m) is not positive"),
        ));
    }
    // Square cells at the finer spacing, unless that makes the grid too large.
    let width = dx * f64::from(columns);
    let depth = dy * f64::from(rows);
    let mut cell = dx.min(dy);
    let longest = width.max(depth);
    if (longest / cell).round() > f64::from(max_side) {
        cell = longest / f64::from(max_side);
    }
    let new_columns = ((width / cell).round() as u32).clamp(2, max_side);
    let new_rows = ((depth / cell).round() as u32).clamp(2, max_side);
    let mut result = Prepared {
        columns,
        rows,
        heights: filled,
        voids,
        cell_size: dx,
        source_size: (columns, rows),
        cell_size_given,
        resampled: None,
        source_voids,
    };
    let square = ((dx - dy) / dx).abs() < 1e-3;
    if (new_columns, new_rows) != (columns, rows) && !(square && columns <= max_side && rows <= max_side) {
        let why = if columns > max_side || rows > max_side {
            format!(
                "downsampled from {columns}x{rows} to {new_columns}x{new_rows} samples (--max-size {max_side})"
            )
        } else {
            format!(
                "resampled from {columns}x{rows} to {new_columns}x{new_rows} samples for square cells ({dx:.2} m x {dy:.2} m became {:.2} m)",
                width / f64::from(new_columns)
            )
        };
        result.heights = resample::resample(columns, rows, &result.heights, new_columns, new_rows);
        result.voids = resample::resample_mask(columns, rows, &result.voids, new_columns, new_rows);
        result.columns = new_columns;
        result.rows = new_rows;
        result.resampled = Some(why);
    }
    result.cell_size = width / f64::from(result.columns);
    Ok(result)
}

/// How to load elevation data.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct LoadOptions {
    /// Metres between samples where the file does not say (`--cell-size`; 1 m without it).
    pub cell_size: Option<f64>,
    /// Reduce the grid to at most this many samples a side (`--max-size`); without it a grid
    /// larger than [`MAX_HEIGHTMAP_SIDE`] is refused.
    pub max_size: Option<u32>,
    /// Water level and vertical exaggeration.
    pub place: PlaceOptions,
}

/// Elevation data loaded and placed, with what was done to it, for messages.
#[derive(Debug, Clone, PartialEq)]
pub struct Loaded {
    /// The data placed in the scene.
    pub scene: DemScene,
    /// The format it was read as.
    pub format: DemFormat,
    /// The file's own size in samples.
    pub source_size: (u32, u32),
    /// Whether the cell size came from the options (the file states none).
    pub cell_size_given: bool,
    /// Why it was resampled, if it was.
    pub resampled: Option<String>,
    /// Samples without data in the file (before any resampling).
    pub source_voids: usize,
}

impl Loaded {
    /// One line saying what was loaded: size, cell size and where it came from, height range,
    /// voids, water.
    pub fn describe(&self) -> String {
        let info = &self.scene.info;
        let (columns, rows) = (self.scene.heightmap.columns(), self.scene.heightmap.rows());
        let source =
            if self.cell_size_given { "from --cell-size, the file states none" } else { "from the file" };
        let mut text = format!(
            "{:?} {}x{} samples, cell {:.3} m ({source}), heights {:.1} to {:.1} m",
            self.format, columns, rows, info.cell_size_metres, info.range_metres.0, info.range_metres.1
        );
        if let Some(why) = &self.resampled {
            text += &format!("; {why}");
        }
        if self.source_voids > 0 {
            text += &format!("; {} nodata samples filled from their neighbours", self.source_voids);
        }
        text += &if info.sea {
            format!("; water at {} m", info.base_metres)
        } else {
            "; no sea (the land lies above the water level, or --water-level none)".to_string()
        };
        if info.vertical_exaggeration != 1.0 {
            text += &format!("; heights x{}", info.vertical_exaggeration);
        }
        text
    }
}

/// Reads, prepares and places elevation data held in memory (`name` names it in messages and
/// gives an SRTM tile's corner).
pub fn load_bytes(bytes: &[u8], name: &str, options: &LoadOptions) -> Result<Loaded, DemError> {
    let format = detect(bytes, name).ok_or_else(|| {
        DemError::new(
            name,
            "not elevation data this program reads (GeoTIFF, SRTM .hgt, Esri ASCII grid, OpenEXR)",
        )
    })?;
    let max_side = options.max_size.unwrap_or(MAX_HEIGHTMAP_SIDE);
    let elevation = read(bytes, name, options.max_size.is_some())?;
    let prepared = prepare(elevation, name, options.cell_size, max_side)?;
    let (source_size, cell_size_given, resampled, source_voids) =
        (prepared.source_size, prepared.cell_size_given, prepared.resampled.clone(), prepared.source_voids);
    let scene =
        place::place(prepared, &options.place).map_err(|error| DemError::new(name, error.to_string()))?;
    Ok(Loaded { scene, format, source_size, cell_size_given, resampled, source_voids })
}

/// [`load_bytes`] on a file, read whole. Errors name the file.
pub fn load_file(path: &Path, options: &LoadOptions) -> Result<Loaded, DemError> {
    let name = path.display().to_string();
    let bytes = atomic_file::read_regular(path)
        .map_err(|error| DemError::new(&name, format!("cannot read: {error}")))?;
    load_bytes(&bytes, &name, options)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::Cursor;

    fn strip_tiff(columns: u32, rows: u32, value: impl Fn(u32, u32) -> f32) -> Vec<u8> {
        use tiff::encoder::{TiffEncoder, colortype};
        let data: Vec<f32> = (0..columns * rows).map(|i| value(i % columns, i / columns)).collect();
        let mut bytes = Cursor::new(Vec::new());
        let mut encoder = TiffEncoder::new(&mut bytes).expect("encoder");
        let mut image = encoder.new_image::<colortype::Gray32Float>(columns, rows).expect("image");
        image.encoder().write_tag(tiff::tags::Tag::ModelPixelScaleTag, &[5.0f64, 5.0, 0.0][..]).expect("tag");
        image.write_data(&data).expect("data");
        bytes.into_inner()
    }

    #[test]
    fn formats_are_recognised_from_their_content() {
        assert_eq!(detect(&strip_tiff(2, 2, |_, _| 0.0), "x.png"), Some(DemFormat::GeoTiff));
        assert_eq!(detect(b"  NCOLS 4\n", "x"), Some(DemFormat::AsciiGrid));
        assert_eq!(detect(&[0x76, 0x2f, 0x31, 0x01, 0], "x.tif"), Some(DemFormat::Exr));
        assert_eq!(detect(&vec![0; 1201 * 1201 * 2], "tile"), Some(DemFormat::Hgt));
        assert_eq!(detect(&[0; 10], "N00E000.hgt"), Some(DemFormat::Hgt));
        assert_eq!(detect(b"\x89PNG\r\n\x1a\n", "x.hgt"), None);
        assert_eq!(detect(b"BM....", "heightmap.bmp"), None);
        // A BMP as long as an SRTM tile is still a BMP.
        assert_eq!(detect_from_head(b"BM....", 1201 * 1201 * 2, "heightmap.bmp"), None);
        assert_eq!(detect_from_head(&[1, 2, 3], 3601 * 3601 * 2, "tile"), Some(DemFormat::Hgt));
    }

    #[test]
    fn larger_than_the_limit_is_refused_or_downsampled_on_request() {
        let side = MAX_HEIGHTMAP_SIDE + 7;
        let bytes = strip_tiff(side, 3, |x, _| x as f32);
        let error =
            load_bytes(&bytes, "wide.tif", &LoadOptions::default()).expect_err("too wide").to_string();
        assert!(error.contains("refused before decoding (pass --max-size N"), "{error}");
        let options = LoadOptions { max_size: Some(1000), ..LoadOptions::default() };
        let loaded = load_bytes(&bytes, "wide.tif", &options).expect("downsampled");
        assert_eq!((loaded.scene.heightmap.columns(), loaded.scene.heightmap.rows()), (1000, 2));
        assert!(
            loaded.describe().contains(&format!("downsampled from {side}x3 to 1000x2")),
            "{}",
            loaded.describe()
        );
        assert!((loaded.scene.info.cell_size_metres - 5.0 * f64::from(side) / 1000.0).abs() < 1e-9);
    }

    #[test]
    fn openexr_heights_are_metres_with_the_given_cell_size() {
        let image = image::Rgb32FImage::from_fn(3, 2, |x, y| image::Rgb([x as f32 * 10.0 + y as f32; 3]));
        let mut bytes = Cursor::new(Vec::new());
        image::DynamicImage::ImageRgb32F(image)
            .write_to(&mut bytes, image::ImageFormat::OpenExr)
            .expect("exr");
        let options = LoadOptions { cell_size: Some(2.5), ..LoadOptions::default() };
        let loaded = load_bytes(bytes.get_ref(), "h.exr", &options).expect("readable");
        assert_eq!(loaded.format, DemFormat::Exr);
        assert!(loaded.cell_size_given);
        assert_eq!(loaded.scene.info.cell_size_metres, 2.5);
        assert_eq!(loaded.scene.info.range_metres, (0.0, 21.0));
    }

    #[test]
    fn a_grid_with_no_data_at_all_is_refused() {
        let text = "ncols 2\nnrows 2\ncellsize 1\nNODATA_value 7\n7 7\n7 7\n";
        let error = load_bytes(text.as_bytes(), "empty.asc", &LoadOptions::default()).expect_err("no data");
        assert_eq!(error.to_string(), "empty.asc: every sample is nodata: there is no height to draw");
    }
}
