//! The part file: an OpenEXR file with one layer per block of rows, its exact sums as integer
//! channels and its header as attributes (the format is described in [`super`]).

use std::io::{BufReader, Read, Seek, SeekFrom};
use std::ops::Range;
use std::path::Path;

use exr::block::chunk::CompressedBlock;
use exr::meta::BlockDescription;
use exr::meta::attribute::LevelMode;
use exr::prelude::{
    AnyChannel, AnyChannels, AttributeValue, Encoding, FlatSamples, Image as ExrImage, ImageAttributes,
    IntegerBounds, Layer, LayerAttributes, ReadChannels, ReadLayers, SampleType, Text, Vec2, WritableImage,
};

use super::{Block, Part, PartError, PartHeader, Split, tile_rows};
use crate::base::checksum::Fnv;
use crate::base::memory::MemoryBudget;
use crate::base::sampler::ExactSum;
use crate::scene::{MAX_IMAGE_PIXELS, MAX_IMAGE_SIDE};

/// Attribute names of a part file.
const ATTR_SCENE: &str = "rayterra.scene";
const ATTR_SETTINGS: &str = "rayterra.settings";
const ATTR_TILE: &str = "rayterra.tile";
const ATTR_PASS: &str = "rayterra.pass";
const ATTR_SAMPLES: &str = "rayterra.samples";
/// The checksum of everything else the part holds ([`checksum`]), as 16 hexadecimal digits.
const ATTR_CHECKSUM: &str = "rayterra.checksum";

/// The header's attributes as a part file holds them (text reduced to printable ASCII).
fn header_attributes(h: &PartHeader) -> [(&'static str, String); 5] {
    [
        (ATTR_SCENE, ascii(&h.scene)),
        (ATTR_SETTINGS, ascii(&h.settings)),
        (ATTR_TILE, h.tile.to_string()),
        (ATTR_PASS, h.pass.to_string()),
        (ATTR_SAMPLES, h.samples.to_string()),
    ]
}

/// The 64-bit FNV-1a hash of what a part file holds: the size, the header's attributes as
/// written, and each block's rows, pixel values and sums, bit for bit. A byte changed anywhere
/// in a part (its pixels, its sums, its attributes, its checksum) changes what is read or the
/// checksum it is compared with, so a damaged part is refused rather than merged.
fn checksum(width: u32, height: u32, attributes: &[(&str, String)], blocks: &[Block]) -> u64 {
    let mut hash = Fnv::default();
    hash.write(&width.to_le_bytes());
    hash.write(&height.to_le_bytes());
    for (name, value) in attributes {
        hash.write_text(name);
        hash.write_text(value);
    }
    let mut bytes = Vec::new();
    for block in blocks {
        hash.write(&block.rows.start.to_le_bytes());
        hash.write(&block.rows.end.to_le_bytes());
        bytes.clear();
        bytes.extend(block.pixels.iter().flatten().flat_map(|v| v.to_bits().to_le_bytes()));
        if let Some(sums) = &block.sums {
            bytes.extend(sums.iter().flat_map(|s| s.fixed).flat_map(i128::to_le_bytes));
        }
        hash.write(&bytes);
    }
    hash.0
}

/// Why a part file could not be written; the message names the target.
pub type PartWriteError = atomic_file::WriteError<exr::error::Error>;

/// Writes `part` to `path` as an OpenEXR part file, whole or not at all.
pub fn write_part(part: &Part, path: &Path) -> Result<(), PartWriteError> {
    let h = &part.header;
    let mut attributes =
        ImageAttributes::new(IntegerBounds::new((0, 0), (h.width as usize, h.height as usize)));
    let header = header_attributes(h);
    let sum = checksum(h.width, h.height, &header, &part.blocks);
    for (name, value) in header.into_iter().chain([(ATTR_CHECKSUM, format!("{sum:016x}"))]) {
        attributes.other.insert(Text::from(name), AttributeValue::Text(Text::from(value.as_str())));
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
fn ascii(value: &str) -> String {
    value.chars().map(|c| if c.is_ascii_graphic() || c == ' ' { c } else { '?' }).collect()
}

/// [`ascii`] as an EXR text.
fn text(value: &str) -> Text {
    Text::from(ascii(value).as_str())
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
    let written_sum = attr(ATTR_CHECKSUM)?;
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
    let sum = checksum(header.width, header.height, &header_attributes(&header), &blocks);
    if written_sum != format!("{sum:016x}") {
        budget.release(pixel_bytes);
        return Err(not_a_part(
            "its content does not match its checksum: the file is damaged (render this part again)".into(),
        ));
    }
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
