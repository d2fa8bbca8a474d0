//! Renders split into parts that run as separate processes (on one machine, or as the tasks of a
//! Slurm array job or a Kubernetes Indexed Job), written as part files and merged into the same
//! bytes as a render in one process.
//!
//! Two ways to split, which combine:
//! - **Tiles** (`--tile K/N`): the image's rows are cut into blocks ([`tile_block_rows`] rows
//!   each), dealt to the `N` tiles in turn (block `b` to tile `b mod N`), so that every tile gets
//!   a share of every part of the picture (costly and cheap rows alike). A tile's
//!   pixels are the very pixels of the whole render: every pixel's random numbers come from its
//!   own coordinates, and the decisions that look at neighbours (adaptive anti-aliasing) see the
//!   same neighbours, computed again at the tile's borders.
//! - **Passes** (`--pass K/N`): run `K` of a render of `N` independent runs
//!   ([`crate::render::RenderSettings::runs`]): its own random streams, or for the path tracer
//!   its own range of sample indices. A pass stores the exact sums of its estimates
//!   ([`ExactSum`]), which do not depend on how they are grouped, so the merge of `N` passes is
//!   the very render of `N` runs in one process.
//!
//! A part file is an OpenEXR file with one layer per block of rows, each placed in the full image
//! by its data window (the display window is the full image), linear 32-bit float RGB (for a pass,
//! its own mean: the part can be looked at), for a pass the exact sums in twelve 32-bit integer
//! channels (`sum.R.0` .. `sum.B.3`, each sum's 128 bits from the lowest word up), and attributes
//! that say what it is: `rayterra.scene` (a digest of the scene and the files it reads),
//! `rayterra.settings` (everything else that shapes the pixels), `rayterra.tile`, `rayterra.pass`
//! and `rayterra.samples` (the estimates in each sum). [`merge`] refuses parts that do not fit
//! together.

use std::collections::BTreeMap;
use std::fmt;
use std::io::{BufReader, Read, Seek, SeekFrom};
use std::ops::Range;
use std::path::{Path, PathBuf};

use exr::block::chunk::CompressedBlock;
use exr::meta::BlockDescription;
use exr::meta::attribute::LevelMode;
use exr::prelude::{
    AnyChannel, AnyChannels, AttributeValue, Encoding, FlatSamples, Image as ExrImage, ImageAttributes,
    IntegerBounds, Layer, LayerAttributes, ReadChannels, ReadLayers, SampleType, Text, Vec2, WritableImage,
};
use sha2::{Digest, Sha256};

use crate::MemoryBudget;
use crate::image_io::Image;
use crate::render::{PortionPixels, Rows};
use crate::sampler::ExactSum;
use crate::scene::{MAX_IMAGE_PIXELS, MAX_IMAGE_SIDE};

/// The most rows in one block of a tile.
pub const MAX_TILE_BLOCK_ROWS: u32 = 16;
/// The fewest rows in one block of a tile when the tile has that many rows.
pub const MIN_TILE_BLOCK_ROWS: u32 = 8;
/// The blocks a tile gets when the image is high enough and blocks are not too small.
pub const BLOCKS_PER_TILE: u32 = 6;

/// The rows in each block of an image `height` rows high cut into `tiles` tiles: as many as make
/// [`BLOCKS_PER_TILE`] blocks a tile, from [`MIN_TILE_BLOCK_ROWS`] (or a tile's share of the rows,
/// if less) to [`MAX_TILE_BLOCK_ROWS`].
///
/// Chosen by measurement (`cargo bench -p raytracer --bench tiles`, rays traced by each tile of
/// four scenes; the README has the table): smaller blocks share the work more evenly, but with
/// adaptive anti-aliasing each block traces the rows above and below it again (its first pass
/// compares every pixel with its neighbours), and the first pass is most of a render's rays.
/// About six blocks a tile is where the largest tile's work is least for 4 and 8 tiles; with more
/// tiles, blocks under 8 rows lose more to the rows traced again than they gain in balance.
pub fn tile_block_rows(height: u32, tiles: u32) -> u32 {
    let tiles = tiles.max(1);
    let least = MIN_TILE_BLOCK_ROWS.min(height / tiles).max(1);
    (height / (BLOCKS_PER_TILE * tiles)).clamp(least, MAX_TILE_BLOCK_ROWS)
}

/// Part `index` of `count` (`K/N` on the command line, `K` from 0).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct Split {
    /// Which part, from 0.
    pub index: u32,
    /// How many parts in all (at least 1).
    pub count: u32,
}

impl Split {
    /// The whole: part 0 of 1.
    pub const WHOLE: Split = Split { index: 0, count: 1 };

    /// Part `index` of `count`, if `index < count`.
    pub fn new(index: u32, count: u32) -> Option<Split> {
        (index < count).then_some(Split { index, count })
    }

    /// Parses `K/N`.
    pub fn parse(text: &str) -> Result<Split, String> {
        let (k, n) =
            text.split_once('/').ok_or_else(|| format!("expected K/N (such as 3/8), not `{text}`"))?;
        let parse = |s: &str, what: &str| {
            s.trim().parse::<u32>().map_err(|_| format!("`{s}` in `{text}` is not a valid {what}"))
        };
        let (index, count) = (parse(k, "part number")?, parse(n, "part count")?);
        if count == 0 {
            return Err(format!("`{text}`: the number of parts must be at least 1"));
        }
        Split::new(index, count)
            .ok_or_else(|| format!("`{text}`: parts are numbered from 0 to {}", count - 1))
    }
}

impl fmt::Display for Split {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}/{}", self.index, self.count)
    }
}

/// The blocks of rows tile `tile` of an image `height` rows high owns, top first, in blocks of
/// [`tile_block_rows`] rows. A tile count above the height is refused.
pub fn tile_rows(height: u32, tile: Split) -> Result<Vec<Range<u32>>, String> {
    tile_rows_in_blocks(height, tile, tile_block_rows(height, tile.count))
}

/// [`tile_rows`] with blocks of `block_rows` rows (fewer when a tile would get no row).
pub fn tile_rows_in_blocks(height: u32, tile: Split, block_rows: u32) -> Result<Vec<Range<u32>>, String> {
    if tile.count > height {
        return Err(format!(
            "an image {height} rows high can be cut into at most {height} tiles, not {}",
            tile.count
        ));
    }
    let block = (height / tile.count).clamp(1, block_rows.max(1));
    let blocks = height.div_ceil(block);
    Ok((tile.index..blocks)
        .step_by(tile.count as usize)
        .map(|b| b * block..((b + 1) * block).min(height))
        .collect())
}

/// What a part file is: which render, and which part of it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct PartHeader {
    /// Width of the full image in pixels.
    pub width: u32,
    /// Height of the full image in pixels.
    pub height: u32,
    /// Digest of the scene and of every file it reads ([`SceneDigest`]), as hexadecimal.
    pub scene: String,
    /// Everything else that shapes the pixels (model, sampling, seed...), as one line of text.
    pub settings: String,
    /// Which tile (the whole image when not split into tiles).
    pub tile: Split,
    /// Which pass (the only one when not split into passes).
    pub pass: Split,
    /// The estimates summed in each pixel of a pass (its samples, or its runs); for a part of
    /// final values, the estimates behind them.
    pub samples: u64,
}

/// A block of consecutive rows of a part.
#[derive(Clone, Debug, PartialEq)]
pub struct Block {
    /// The rows, of the full image.
    pub rows: Range<u32>,
    /// Their pixels, linear RGB, top row first: final values, or for a pass its own mean.
    pub pixels: Vec<[f32; 3]>,
    /// For a pass, the exact sums of its estimates, pixel by pixel.
    pub sums: Option<Vec<ExactSum>>,
}

/// A part of a render: its header and the blocks of rows it holds.
#[derive(Clone, Debug, PartialEq)]
pub struct Part {
    /// What it is.
    pub header: PartHeader,
    /// The tile's blocks of rows, top first.
    pub blocks: Vec<Block>,
}

impl Part {
    /// The part made of what [`crate::render::render_portion`] computed for the rows of tile
    /// `header.tile`.
    pub fn from_portion(mut header: PartHeader, rows: &Rows, pixels: PortionPixels) -> Part {
        let w = rows.width() as usize;
        let (values, sums): (Vec<[f32; 3]>, Option<Vec<ExactSum>>) = match pixels {
            PortionPixels::Final(values) => (values, None),
            PortionPixels::Sums { sums, count } => {
                header.samples = count;
                (sums.iter().map(|s| s.mean(count).as_vec3().to_array()).collect(), Some(sums))
            }
        };
        let mut start = 0;
        let blocks = rows
            .blocks()
            .iter()
            .map(|b| {
                let range = start..start + b.len() * w;
                start = range.end;
                Block {
                    rows: b.clone(),
                    pixels: values[range.clone()].to_vec(),
                    sums: sums.as_ref().map(|s| s[range].to_vec()),
                }
            })
            .collect();
        Part { header, blocks }
    }
}

/// A SHA-256 digest of a scene: its text and the contents of every file it reads (textures,
/// meshes), so that parts rendered on machines that see different files are told apart.
#[derive(Clone, Debug, Default)]
pub struct SceneDigest(Sha256);

impl SceneDigest {
    /// A digest of nothing yet.
    pub fn new() -> SceneDigest {
        SceneDigest::default()
    }

    /// Adds a named piece of input (the name keeps `ab` + `c` apart from `a` + `bc`).
    pub fn add(&mut self, name: &str, bytes: &[u8]) {
        for piece in [name.as_bytes(), bytes] {
            self.0.update((piece.len() as u64).to_le_bytes());
            self.0.update(piece);
        }
    }

    /// The digest as 64 hexadecimal digits.
    pub fn finish(self) -> String {
        self.0.finalize().iter().map(|b| format!("{b:02x}")).collect()
    }
}

/// Attribute names of a part file.
const ATTR_SCENE: &str = "rayterra.scene";
const ATTR_SETTINGS: &str = "rayterra.settings";
const ATTR_TILE: &str = "rayterra.tile";
const ATTR_PASS: &str = "rayterra.pass";
const ATTR_SAMPLES: &str = "rayterra.samples";

/// Why a part file could not be written; the message names the target.
pub type PartWriteError = atomic_file::WriteError<exr::error::Error>;

/// Writes `part` to `path` as an OpenEXR part file, whole or not at all.
pub fn write_part(part: &Part, path: &Path) -> Result<(), PartWriteError> {
    let h = &part.header;
    let mut attributes =
        ImageAttributes::new(IntegerBounds::new((0, 0), (h.width as usize, h.height as usize)));
    for (name, value) in [
        (ATTR_SCENE, h.scene.clone()),
        (ATTR_SETTINGS, h.settings.clone()),
        (ATTR_TILE, h.tile.to_string()),
        (ATTR_PASS, h.pass.to_string()),
        (ATTR_SAMPLES, h.samples.to_string()),
    ] {
        attributes.other.insert(Text::from(name), AttributeValue::Text(text(&value)));
    }
    let layers: Vec<Layer<AnyChannels<FlatSamples>>> = part
        .blocks
        .iter()
        .map(|Block { rows, pixels, sums }| {
            let channel = |name: &str, c: usize| {
                AnyChannel::new(name, FlatSamples::F32(pixels.iter().map(|p| p[c]).collect()))
            };
            let mut channels: smallvec::SmallVec<[AnyChannel<FlatSamples>; 4]> =
                smallvec::smallvec![channel("R", 0), channel("G", 1), channel("B", 2)];
            if let Some(sums) = sums {
                for c in 0..3 {
                    for word in 0..4 {
                        let values =
                            sums.iter().map(|s| (s.fixed[c] as u128 >> (32 * word)) as u32).collect();
                        channels
                            .push(AnyChannel::new(sum_channel(c, word).as_str(), FlatSamples::U32(values)));
                    }
                }
            }
            let mut layer = LayerAttributes::named(text(&format!("rows {}..{}", rows.start, rows.end)))
                .with_position(Vec2(0, rows.start as i32));
            layer.software_name = Some(text(concat!("rayterra ", env!("CARGO_PKG_VERSION"))));
            Layer::new(
                (h.width as usize, rows.len()),
                layer,
                Encoding::FAST_LOSSLESS,
                AnyChannels::sort(channels),
            )
        })
        .collect();
    let image = ExrImage::from_layers(attributes, layers);
    atomic_file::write_atomically(path, |out| image.write().to_buffered(out))
}

/// The name of the channel of word `word` (0: the lowest 32 bits) of the sums of colour channel
/// `c` (0, 1, 2: R, G, B): `sum.R.0` .. `sum.B.3`.
fn sum_channel(c: usize, word: usize) -> String {
    format!("sum.{}.{word}", ["R", "G", "B"][c])
}

/// The channels every block of a part holds: `R`, `G`, `B` as 32-bit floats, then for a pass
/// the words of its sums as 32-bit integers, colour by colour, lowest word first.
fn part_channels(is_pass: bool) -> Vec<(String, SampleType)> {
    let mut channels: Vec<(String, SampleType)> =
        ["R", "G", "B"].iter().map(|c| (c.to_string(), SampleType::F32)).collect();
    if is_pass {
        channels.extend((0..12).map(|i| (sum_channel(i / 4, i % 4), SampleType::U32)));
    }
    channels
}

/// The text of an attribute, with anything but printable ASCII replaced (EXR text is bytes).
fn text(value: &str) -> Text {
    let ascii: String =
        value.chars().map(|c| if c.is_ascii_graphic() || c == ' ' { c } else { '?' }).collect();
    Text::from(ascii.as_str())
}

/// A part file that cannot be used.
#[derive(Debug, thiserror::Error)]
pub enum PartError {
    /// The file could not be read or decoded.
    #[error("cannot read `{}`: {reason}", .path.display())]
    Read {
        /// The file.
        path: PathBuf,
        /// Why.
        reason: String,
    },
    /// The file is an image, but not a part file of rayterra, or a damaged one.
    #[error("`{}` is not a rayterra part file: {reason}", .path.display())]
    NotAPart {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        reason: String,
    },
    /// Parts that do not belong together.
    #[error("{0}")]
    Mismatch(String),
}

impl PartError {
    /// The file at `path` could not be read or decoded, for `reason`.
    fn read(path: &Path, reason: impl fmt::Display) -> PartError {
        PartError::Read { path: path.to_path_buf(), reason: reason.to_string() }
    }

    /// The file at `path` is not a part file, for `reason`.
    fn not_a_part(path: &Path, reason: impl Into<String>) -> PartError {
        PartError::NotAPart { path: path.to_path_buf(), reason: reason.into() }
    }
}

/// Reads a part file written by [`write_part`], its pixels within the default memory budget
/// ([`MemoryBudget::default`]).
pub fn read_part(path: &Path) -> Result<Part, PartError> {
    let file = atomic_file::open_regular(path).map_err(|e| PartError::read(path, e))?;
    read_part_from(BufReader::new(file), path, &MemoryBudget::default())
}

/// Reads a part file from `input` (a file or bytes in memory; buffered, as it is read in small
/// pieces), named `path` in errors. The headers come first: a file whose size, blocks of rows or
/// channels are not those of a part is refused, and the bytes its pixels take once decoded are
/// charged to `budget` (and stay charged: the part holds them), all before any pixel is
/// allocated.
pub fn read_part_from(
    mut input: impl Read + Seek,
    path: &Path,
    budget: &MemoryBudget,
) -> Result<Part, PartError> {
    let not_a_part = |reason: String| PartError::not_a_part(path, reason);
    let cannot_read = |e: exr::error::Error| PartError::read(path, e);
    let start = input.stream_position().map_err(|e| cannot_read(e.into()))?;
    let chunks = exr::block::read(&mut input, false).map_err(cannot_read)?;
    let meta = chunks.meta_data();
    let first = meta.headers.first().ok_or_else(|| not_a_part("it holds no image".into()))?;
    let attr = |name: &str| -> Result<String, PartError> {
        // Written among the image's attributes; a reader may file them under the layer's.
        let key = Text::from(name);
        match first.shared_attributes.other.get(&key).or_else(|| first.own_attributes.other.get(&key)) {
            Some(AttributeValue::Text(t)) => Ok(t.to_string()),
            _ => Err(not_a_part(format!("it has no `{name}` attribute"))),
        }
    };
    let display = first.shared_attributes.display_window;
    let (width, height) = (display.size.0, display.size.1);
    if display.position != Vec2(0, 0)
        || !(1..=MAX_IMAGE_SIDE as usize).contains(&width)
        || !(1..=MAX_IMAGE_SIDE as usize).contains(&height)
        || (width * height) as u64 > MAX_IMAGE_PIXELS
    {
        return Err(not_a_part(format!(
            "its display window ({width}x{height}) is not an image rayterra renders"
        )));
    }
    let split = |name: &str| Split::parse(&attr(name)?).map_err(|e| not_a_part(format!("`{name}`: {e}")));
    let header = PartHeader {
        width: width as u32,
        height: height as u32,
        scene: attr(ATTR_SCENE)?,
        settings: attr(ATTR_SETTINGS)?,
        tile: split(ATTR_TILE)?,
        pass: split(ATTR_PASS)?,
        samples: attr(ATTR_SAMPLES)?
            .parse()
            .map_err(|_| not_a_part(format!("`{ATTR_SAMPLES}` is not a count")))?,
    };
    let expected = tile_rows(header.height, header.tile).map_err(not_a_part)?;
    // In 64 bits: a layer's position and size are the file's word.
    let layout: Vec<Range<u64>> = meta
        .headers
        .iter()
        .map(|h| {
            let start = h.own_attributes.layer_position.1.max(0) as u64;
            start..start + h.layer_size.1 as u64
        })
        .collect();
    let full_width =
        meta.headers.iter().all(|h| h.own_attributes.layer_position.0 == 0 && h.layer_size.0 == width);
    if !layout.iter().cloned().eq(expected.iter().map(|r| r.start as u64..r.end as u64)) || !full_width {
        return Err(not_a_part(format!("its blocks of rows are not those of tile {}", header.tile)));
    }
    // One resolution level of flat samples, as written: `exr` reads other levels' blocks of
    // adversarial files into the wrong level (a failed assertion).
    let one_level = |h: &exr::meta::header::Header| match h.blocks {
        BlockDescription::ScanLines => true,
        BlockDescription::Tiles(t) => t.level_mode == LevelMode::Singular,
    };
    if let Some(h) = meta.headers.iter().find(|h| h.deep || !one_level(h)) {
        let what = if h.deep { "deep samples" } else { "several resolution levels" };
        return Err(not_a_part(format!("a block has {what}")));
    }
    let is_pass = header.pass.count > 1;
    let channels = part_channels(is_pass);
    for h in &meta.headers {
        for (name, sample_type) in &channels {
            if !h.channels.list.iter().any(|c| c.name == *name.as_str() && c.sample_type == *sample_type) {
                let kind = if *sample_type == SampleType::F32 { "32-bit float" } else { "32-bit integer" };
                return Err(not_a_part(format!("a block has no {kind} `{name}` channel")));
            }
        }
    }
    let pixel_bytes: u64 =
        meta.headers.iter().map(|h| h.channels.bytes_per_pixel as u64 * h.layer_size.area() as u64).sum();
    budget.charge(pixel_bytes).map_err(|e| not_a_part(format!("decoding its pixels {e}")))?;
    let blocks = check_blocks(chunks, path)
        .and_then(|()| {
            input.seek(SeekFrom::Start(start)).map_err(|e| cannot_read(e.into()))?;
            let chunks = exr::block::read(&mut input, false).map_err(cannot_read)?;
            decode_blocks(chunks, path, expected, &channels)
        })
        .inspect_err(|_| budget.release(pixel_bytes))?;
    Ok(Part { header, blocks })
}

/// Reads the blocks of pixels the offset tables of `chunks` point to (without decoding them) and
/// checks that each is of the first resolution level, as [`write_part`] writes them: `exr` reads
/// a block that claims another level into the wrong one (a failed assertion), whatever the
/// headers say.
fn check_blocks(chunks: exr::block::reader::Reader<impl Read + Seek>, path: &Path) -> Result<(), PartError> {
    let not_a_part = |reason: &str| PartError::not_a_part(path, reason);
    let cannot_read = |e: exr::error::Error| PartError::read(path, e);
    for chunk in chunks.filter_chunks(false, |_, _, _| true).map_err(cannot_read)? {
        match chunk.map_err(cannot_read)?.compressed_block {
            CompressedBlock::ScanLine(_) => {}
            CompressedBlock::Tile(tile) if tile.coordinates.level_index == Vec2(0, 0) => {}
            CompressedBlock::Tile(_) => {
                return Err(not_a_part("a block of pixels is of a smaller resolution level"));
            }
            CompressedBlock::DeepScanLine(_) | CompressedBlock::DeepTile(_) => {
                return Err(not_a_part("a block of pixels has deep samples"));
            }
        }
    }
    Ok(())
}

/// Decodes the pixels of a part whose headers and blocks were checked: its blocks of rows
/// `rows`, which hold `channels` ([`part_channels`]).
fn decode_blocks(
    chunks: exr::block::reader::Reader<impl Read + Seek>,
    path: &Path,
    rows: Vec<Range<u32>>,
    channels: &[(String, SampleType)],
) -> Result<Vec<Block>, PartError> {
    let not_a_part = |reason: String| PartError::not_a_part(path, reason);
    let cannot_read = |e: exr::error::Error| PartError::read(path, e);
    let is_pass = channels.len() > 3;
    // One thread: a part is decoded about as fast as it is read, and a thread pool for each
    // file would cost more than it saves.
    let image = exr::prelude::read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .all_layers()
        .all_attributes()
        .non_parallel()
        .from_chunks(chunks)
        .map_err(cannot_read)?;
    let mut blocks = Vec::with_capacity(image.layer_data.len());
    for (layer, rows) in image.layer_data.iter().zip(rows) {
        let find = |name: &str| layer.channel_data.list.iter().find(|c| c.name == *name);
        let missing = |name: &str| not_a_part(format!("a block has no `{name}` channel"));
        let float = |name: &str| match find(name).map(|c| &c.sample_data) {
            Some(FlatSamples::F32(v)) => Ok(v),
            _ => Err(missing(name)),
        };
        let (r, g, b) = (float("R")?, float("G")?, float("B")?);
        let pixels: Vec<[f32; 3]> = r.iter().zip(g).zip(b).map(|((&r, &g), &b)| [r, g, b]).collect();
        let sums = if is_pass {
            let mut sums = vec![ExactSum::default(); pixels.len()];
            for (i, (name, _)) in channels.iter().enumerate().skip(3) {
                let Some(FlatSamples::U32(values)) = find(name).map(|c| &c.sample_data) else {
                    return Err(missing(name));
                };
                let (c, word) = ((i - 3) / 4, (i - 3) % 4);
                for (sum, &v) in sums.iter_mut().zip(values) {
                    sum.fixed[c] = (sum.fixed[c] as u128 | (v as u128) << (32 * word)) as i128;
                }
            }
            Some(sums)
        } else {
            None
        };
        blocks.push(Block { rows, pixels, sums });
    }
    Ok(blocks)
}

/// Assembles part files into the full image: every tile of every pass must be there once, and all
/// must come from the same scene and settings. Parts are named by their paths in the errors.
pub fn merge(parts: &[(PathBuf, Part)]) -> Result<Image, PartError> {
    let Some((first_path, first)) = parts.first() else {
        return Err(PartError::Mismatch("no part files to merge".into()));
    };
    let f = &first.header;
    // Everything that must agree, with how to say it.
    type Key = fn(&PartHeader) -> String;
    let checks: [(&str, Key); 5] = [
        ("image size", |h| format!("{}x{}", h.width, h.height)),
        ("scene (its text, textures or meshes)", |h| h.scene.clone()),
        ("settings", |h| h.settings.clone()),
        ("number of tiles", |h| h.tile.count.to_string()),
        ("number of passes", |h| h.pass.count.to_string()),
    ];
    for (what, key) in checks {
        let want = key(f);
        if let Some((path, p)) = parts.iter().find(|(_, p)| key(&p.header) != want) {
            return Err(PartError::Mismatch(format!(
                "`{}` and `{}` are parts of different renders: their {what} differ ({} against {})",
                first_path.display(),
                path.display(),
                want,
                key(&p.header)
            )));
        }
    }
    let mut grid: BTreeMap<(u32, u32), &PathBuf> = BTreeMap::new();
    for (path, p) in parts {
        if let Some(other) = grid.insert((p.header.tile.index, p.header.pass.index), path) {
            return Err(PartError::Mismatch(format!(
                "`{}` and `{}` are the same part (tile {}, pass {}): merge each part once",
                other.display(),
                path.display(),
                p.header.tile,
                p.header.pass
            )));
        }
    }
    let missing: Vec<String> = (0..f.tile.count)
        .flat_map(|t| (0..f.pass.count).map(move |p| (t, p)))
        .filter(|key| !grid.contains_key(key))
        .map(|(t, p)| {
            describe(Split { index: t, count: f.tile.count }, Split { index: p, count: f.pass.count })
        })
        .collect();
    if !missing.is_empty() {
        let shown = missing.iter().take(20).cloned().collect::<Vec<_>>().join(", ");
        let more =
            if missing.len() > 20 { format!(" and {} more", missing.len() - 20) } else { String::new() };
        return Err(PartError::Mismatch(format!(
            "{} of {} parts are missing: {shown}{more}",
            missing.len(),
            f.tile.count as u64 * f.pass.count as u64
        )));
    }

    let w = f.width as usize;
    let mut pixels = vec![[0f32; 3]; w * f.height as usize];
    let by_key: BTreeMap<(u32, u32), &Part> =
        parts.iter().map(|(_, p)| ((p.header.tile.index, p.header.pass.index), p)).collect();
    for tile in 0..f.tile.count {
        let passes: Vec<&Part> = (0..f.pass.count).map(|p| by_key[&(tile, p)]).collect();
        for (b, block) in passes[0].blocks.iter().enumerate() {
            let out = &mut pixels[block.rows.start as usize * w..block.rows.end as usize * w];
            if f.pass.count == 1 {
                out.copy_from_slice(&block.pixels);
                continue;
            }
            // Passes: their exact sums added, divided by all their estimates.
            let count: u64 = passes.iter().map(|p| p.header.samples).sum();
            let mut total = vec![ExactSum::default(); out.len()];
            for p in &passes {
                let sums = p.blocks[b].sums.as_ref().expect("a pass part holds sums");
                total.iter_mut().zip(sums).for_each(|(t, s)| t.merge(s));
            }
            for (o, t) in out.iter_mut().zip(&total) {
                *o = t.mean(count).as_vec3().to_array();
            }
        }
    }
    Ok(Image::new(f.width, f.height, pixels))
}

/// `tile 2/8, pass 1/4`, leaving out a split into one.
fn describe(tile: Split, pass: Split) -> String {
    match (tile.count > 1, pass.count > 1) {
        (true, true) => format!("tile {tile} of pass {pass}"),
        (false, true) => format!("pass {pass}"),
        _ => format!("tile {tile}"),
    }
}

#[cfg(test)]
mod tests {
    use glam::DVec3;

    use super::*;

    #[test]
    fn splits_parse_and_refuse_nonsense() {
        assert_eq!(Split::parse("3/8"), Ok(Split { index: 3, count: 8 }));
        for bad in ["8/8", "1/0", "x/2", "3", "-1/4", "1/2/3"] {
            assert!(Split::parse(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn tiles_cover_every_row_once_in_interleaved_blocks() {
        for height in [1, 7, 8, 9, 100, 380, 760, 4321] {
            for count in [1, 2, 3, 4, 7, 16, 100] {
                let Ok(first) = tile_rows(height, Split { index: 0, count }) else {
                    assert!(count > height);
                    continue;
                };
                assert!(!first.is_empty());
                let mut seen = vec![0u32; height as usize];
                for index in 0..count {
                    let rows = tile_rows(height, Split { index, count }).expect("tiles");
                    assert!(!rows.is_empty(), "tile {index}/{count} of {height} rows is empty");
                    for r in rows {
                        assert!(r.len() as u32 <= MAX_TILE_BLOCK_ROWS);
                        for y in r {
                            seen[y as usize] += 1;
                        }
                    }
                }
                assert!(seen.iter().all(|&n| n == 1), "{height} rows, {count} tiles");
            }
        }
        assert!(tile_rows(10, Split { index: 0, count: 11 }).is_err());
    }

    fn header(tile: Split, pass: Split) -> PartHeader {
        PartHeader {
            width: 3,
            height: 20,
            scene: "abc".into(),
            settings: "model=path spp=4".into(),
            tile,
            pass,
            samples: 4,
        }
    }

    /// Pixel values of the rows of `tile` of a 3 x 20 image, varied by `seed`.
    fn values(rows: &Rows, seed: f64) -> Vec<DVec3> {
        rows.ys()
            .flat_map(|y| {
                (0..3).map(move |x| DVec3::new((y * 3 + x) as f64 * seed, -1.5 * seed, 1e6 + seed / 3.0))
            })
            .collect()
    }

    fn sums_of(values: &[DVec3]) -> Vec<ExactSum> {
        values
            .iter()
            .map(|&v| {
                let mut s = ExactSum::default();
                s.add(v);
                s.add(v * 0.5);
                s
            })
            .collect()
    }

    #[test]
    fn parts_round_trip_through_their_files() {
        let dir = tempfile::tempdir().expect("temp dir");
        let tile = Split { index: 1, count: 2 };
        let rows = Rows::tile(3, 20, tile).expect("tile");
        let finals = values(&rows, 0.25).iter().map(|c| c.as_vec3().to_array()).collect();
        let sums = PortionPixels::Sums { sums: sums_of(&values(&rows, 0.25)), count: 2 };
        for (pass, pixels) in
            [(Split::WHOLE, PortionPixels::Final(finals)), (Split { index: 0, count: 3 }, sums)]
        {
            let part = Part::from_portion(header(tile, pass), &rows, pixels);
            let path = dir.path().join("part.exr");
            write_part(&part, &path).expect("written");
            assert_eq!(read_part(&path).expect("read"), part);
            // Another reader sees an ordinary EXR file.
            assert!(image::open(&path).is_ok());
        }
    }

    #[test]
    fn tiles_and_passes_merge_into_the_whole() {
        // Two passes of a 3 x 20 image, each the sums of two estimates.
        let full = Rows::full(3, 20);
        let pass_sums: Vec<Vec<ExactSum>> =
            [1.0, 3.0].iter().map(|&seed| sums_of(&values(&full, seed))).collect();
        let mut whole = pass_sums[0].clone();
        whole.iter_mut().zip(&pass_sums[1]).for_each(|(a, b)| a.merge(b));
        let whole: Vec<[f32; 3]> = whole.iter().map(|s| s.mean(4).as_vec3().to_array()).collect();
        let mut parts = Vec::new();
        for t in 0..3 {
            let tile = Split { index: t, count: 3 };
            let rows = Rows::tile(3, 20, tile).expect("tile");
            for (p, seed) in [1.0, 3.0].iter().enumerate() {
                let pixels = PortionPixels::Sums { sums: sums_of(&values(&rows, *seed)), count: 2 };
                let h = header(tile, Split { index: p as u32, count: 2 });
                parts.push((PathBuf::from(format!("t{t}p{p}.exr")), Part::from_portion(h, &rows, pixels)));
            }
        }
        parts.reverse();
        assert_eq!(merge(&parts).expect("merged").pixels(), whole.as_slice());
    }

    #[test]
    fn merge_refuses_parts_that_do_not_fit() {
        let tile = |t: u32| {
            let split = Split { index: t, count: 3 };
            let rows = Rows::tile(3, 20, split).expect("tile");
            let pixels = PortionPixels::Final(vec![[0.5; 3]; rows.len()]);
            (
                PathBuf::from(format!("part-{t}.exr")),
                Part::from_portion(header(split, Split::WHOLE), &rows, pixels),
            )
        };
        let err = merge(&[tile(0), tile(2)]).expect_err("missing").to_string();
        assert!(err.contains("1 of 3 parts are missing: tile 1/3"), "{err}");
        let err = merge(&[tile(0), tile(1), tile(1), tile(2)]).expect_err("twice").to_string();
        assert!(err.contains("`part-1.exr` and `part-1.exr` are the same part"), "{err}");
        let mut other = tile(1);
        other.1.header.settings = "model=path spp=8".into();
        let err = merge(&[tile(0), other, tile(2)]).expect_err("settings").to_string();
        assert!(
            err.contains("`part-0.exr` and `part-1.exr` are parts of different renders: their settings"),
            "{err}"
        );
    }

    #[test]
    fn pixels_over_the_memory_budget_are_refused_before_decoding() {
        let dir = tempfile::tempdir().expect("temp dir");
        let path = dir.path().join("part.exr");
        let rows = Rows::tile(3, 20, Split::WHOLE).expect("tile");
        let pixels = PortionPixels::Final(vec![[0.5; 3]; rows.len()]);
        write_part(&Part::from_portion(header(Split::WHOLE, Split::WHOLE), &rows, pixels), &path)
            .expect("written");
        let open = || BufReader::new(std::fs::File::open(&path).expect("open"));
        // 60 pixels of three 32-bit floats.
        let budget = MemoryBudget::new(719);
        let err = read_part_from(open(), &path, &budget).expect_err("over budget").to_string();
        assert!(err.contains("decoding its pixels needs 720 bytes") && err.contains("memory limit"), "{err}");
        assert_eq!(budget.used(), 0);
        let budget = MemoryBudget::new(720);
        read_part_from(open(), &path, &budget).expect("within budget");
        assert_eq!(budget.used(), 720, "the part holds its pixels");
    }

    #[test]
    fn other_images_are_not_parts() {
        let dir = tempfile::tempdir().expect("temp dir");
        let path = dir.path().join("plain.exr");
        let plain = Image::new(3, 20, vec![[0.5; 3]; 60]);
        crate::image_io::write_image(&plain, &path, false).expect("written");
        let err = read_part(&path).expect_err("plain EXR").to_string();
        assert!(err.contains("is not a rayterra part file"), "{err}");
        std::fs::write(&path, b"not an image").expect("written");
        assert!(matches!(read_part(&path), Err(PartError::Read { .. })));
    }
}
