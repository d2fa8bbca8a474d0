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
//! and `rayterra.samples` (the estimates in each sum), and `rayterra.checksum`: the FNV-1a hash of
//! all the rest (size, attributes, rows, pixel values and sums, bit for bit), checked when the part
//! is read, so that a damaged part is refused, naming the file. [`merge`] refuses parts that do
//! not fit together.

mod file;
mod merge;

use std::fmt;
use std::ops::Range;
use std::path::{Path, PathBuf};

use sha2::{Digest, Sha256};

pub use crate::base::rows::{
    BLOCKS_PER_TILE, MAX_TILE_BLOCK_ROWS, MIN_TILE_BLOCK_ROWS, Split, tile_block_rows, tile_rows,
    tile_rows_in_blocks,
};
pub use file::{PartWriteError, read_part, read_part_from, write_part};
pub use merge::merge;

use crate::base::rows::Rows;
use crate::base::sampler::ExactSum;
use crate::render::PortionPixels;

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

#[cfg(test)]
mod tests {
    use glam::DVec3;

    use std::io::BufReader;

    use super::*;
    use crate::base::image_io::Image;
    use crate::base::memory::MemoryBudget;

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
    fn a_part_with_any_byte_changed_is_refused_or_unchanged() {
        // A pass (pixels and sums) of a 3 x 20 image: flipping any one bit of any byte of its
        // file either makes it refused, or leaves what is read the same (a byte the reader
        // ignores); it never changes a pixel or a sum. Before the checksum, a flipped bit in
        // the pixel data changed a pixel of the merged image.
        let dir = tempfile::tempdir().expect("temp dir");
        let path = dir.path().join("part.exr");
        let tile = Split { index: 0, count: 2 };
        let rows = Rows::tile(3, 20, tile).expect("tile");
        let pixels = PortionPixels::Sums { sums: sums_of(&values(&rows, 0.75)), count: 2 };
        let part = Part::from_portion(header(tile, Split { index: 1, count: 2 }), &rows, pixels);
        write_part(&part, &path).expect("written");
        let bytes = std::fs::read(&path).expect("read");
        // Where the checksum attribute (name, type, size, value) lies: a flip there is no
        // damage to the picture.
        let name_at = bytes.windows(17).position(|w| w == b"rayterra.checksum").expect("the attribute");
        let attribute = name_at..name_at + 17 + 1 + 5 + 4 + 16;
        let (mut refused, mut checksum_refusals) = (0, 0);
        for i in 0..bytes.len() {
            for bit in [0x01u8, 0x80] {
                let mut damaged = bytes.clone();
                damaged[i] ^= bit;
                let budget = MemoryBudget::new(1 << 24);
                match read_part_from(std::io::Cursor::new(&damaged), &path, &budget) {
                    Ok(read) => assert_eq!(read, part, "byte {i} ^ {bit:#x} changed the part"),
                    Err(e) => {
                        refused += 1;
                        let message = e.to_string();
                        assert!(message.contains(&path.display().to_string()), "{message}");
                        // Refused by the checksum alone: without it, this flip changed the part.
                        checksum_refusals += (message.contains("does not match its checksum")
                            && !attribute.contains(&i)) as usize;
                    }
                }
            }
        }
        assert!(refused > bytes.len() / 2, "{refused} of {} refused", 2 * bytes.len());
        assert!(
            checksum_refusals > 100,
            "{checksum_refusals} flips of the pixels or sums caught by the checksum"
        );
        // A part file without a checksum (written before there was one) is refused by name.
        let mut old = bytes.clone();
        let at = old.windows(17).position(|w| w == b"rayterra.checksum").expect("the attribute");
        old[at..at + 17].copy_from_slice(b"rayterra.checksun");
        let err = read_part_from(std::io::Cursor::new(&old), &path, &MemoryBudget::new(1 << 24))
            .expect_err("no checksum")
            .to_string();
        assert!(err.contains("has no `rayterra.checksum` attribute"), "{err}");
    }

    #[test]
    fn other_images_are_not_parts() {
        let dir = tempfile::tempdir().expect("temp dir");
        let path = dir.path().join("plain.exr");
        let plain = Image::new(3, 20, vec![[0.5; 3]; 60]);
        crate::base::image_io::write_image(&plain, &path, false).expect("written");
        let err = read_part(&path).expect_err("plain EXR").to_string();
        assert!(err.contains("is not a rayterra part file"), "{err}");
        std::fs::write(&path, b"not an image").expect("written");
        assert!(matches!(read_part(&path), Err(PartError::Read { .. })));
    }
}
