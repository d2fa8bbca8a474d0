//! Checkpoints: the finished work of a render (or of a tile or pass of one) kept in a file while
//! it runs, so that a render that is killed (a scheduler's time limit, `scancel`, a reboot) goes
//! on from where it was when started again, and gives the very bytes of a render that never
//! stopped.
//!
//! The unit of work saved is, for the classic, photon and path models, a *chunk*: one run's
//! values for up to a [`CHUNKS`]-th of the portion's rows (any set of rows renders to the same
//! values on its own, see [`super::render_portion`]; a tile's blocks are grouped whole, a whole
//! image is cut into pieces of at least 16 rows); for SPPM, a run's whole state after a pass
//! ([`SppmState`]), whose random numbers depend only on the pass and pixel or photon index.
//!
//! The file: the line `rayterra checkpoint 1`, the length and text of a *key* that says which
//! render it belongs to (the caller's description of the scene and settings, the rows and the
//! chunking), then records, each `tag u8, run u32, chunk u32, length u64, payload, checksum u64`
//! (FNV-1a of what precedes it in the record), all little-endian. Chunk records are appended as
//! chunks finish; SPPM states replace the file (written whole, then renamed into place) at most
//! every [`Checkpoint::sppm_interval`]. A record cut short by a kill is dropped when the file is
//! opened again; a record whose checksum is wrong means a damaged file, which is refused.

use std::collections::BTreeMap;
use std::fs::{File, OpenOptions};
use std::io::{self, Read, Write};
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use glam::DVec3;

use super::Rows;
use crate::base::checksum::Fnv;
use crate::base::sampler::ExactSum;
use crate::integrator::sppm::{SppmState, SppmStats};

/// The most chunks a run's rows are cut into when a render keeps a checkpoint.
pub const CHUNKS: u32 = 32;

/// The first line of a checkpoint file.
const MAGIC: &[u8] = b"rayterra checkpoint 1\n";
/// The longest key a checkpoint file may hold.
const MAX_KEY_BYTES: u64 = 1 << 16;

const TAG_COLORS: u8 = 1;
const TAG_SUMS: u8 = 2;
const TAG_SPPM: u8 = 3;

/// What one run of a model computed for some rows, pixel by pixel in the order of
/// [`Rows::ys`].
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum Estimate {
    /// One estimate a pixel (classic, photon, sppm).
    Colors(Vec<DVec3>),
    /// Exact sums of this many samples a pixel (path).
    Sums(Vec<ExactSum>, u64),
}

/// A checkpoint file that cannot be used.
#[derive(Debug, thiserror::Error)]
pub enum CheckpointError {
    /// The file could not be read or written.
    #[error("checkpoint `{}`: {source}", .path.display())]
    Io {
        /// The checkpoint file.
        path: PathBuf,
        /// What the system said.
        #[source]
        source: io::Error,
    },
    /// The file holds the work of another render.
    #[error(
        "checkpoint `{}` was saved by another render (other scene, settings, tile or pass): remove it \
         or name another file",
        .path.display()
    )]
    OtherRender {
        /// The checkpoint file.
        path: PathBuf,
    },
    /// The file is not a checkpoint, or a damaged one.
    #[error("`{}` is not a usable checkpoint file: {reason}", .path.display())]
    Damaged {
        /// The checkpoint file.
        path: PathBuf,
        /// What is wrong.
        reason: String,
    },
}

/// The checkpoint of a render of some rows, kept in a file.
#[derive(Debug)]
pub struct Checkpoint {
    path: PathBuf,
    /// The whole key: the caller's, the rows and the chunking.
    key: String,
    /// The pixels of each chunk.
    chunk_pixels: Vec<usize>,
    /// The pixels of the rows.
    pixels: usize,
    chunks: BTreeMap<(u32, u32), Estimate>,
    sppm: BTreeMap<u32, SppmState>,
    /// The file open for appending chunk records (once it has its header).
    file: Option<File>,
    last_sppm_save: Option<Instant>,
    /// The least time between two saves of SPPM states (each rewrites the file).
    pub sppm_interval: Duration,
    /// Chunks and SPPM passes found in the file when it was opened.
    resumed: (usize, u64),
}

impl Checkpoint {
    /// Opens the checkpoint at `path` of the render of `rows` that `key` describes (the scene,
    /// every setting that shapes the pixels, the tile and pass): the work it holds is resumed, or
    /// a new file is started. A file of another render, or a damaged one, is refused; a last
    /// record cut short is dropped.
    pub fn open(path: &Path, key: &str, rows: &Rows) -> Result<Checkpoint, CheckpointError> {
        let key = format!("{key}\nrows {}x{:?}\nchunks {CHUNKS}", rows.width(), rows.blocks());
        let chunk_pixels = chunk_rows(rows).iter().map(Rows::len).collect();
        let mut checkpoint = Checkpoint {
            path: path.to_path_buf(),
            key,
            chunk_pixels,
            pixels: rows.len(),
            chunks: BTreeMap::new(),
            sppm: BTreeMap::new(),
            file: None,
            last_sppm_save: None,
            sppm_interval: Duration::from_secs(10),
            resumed: (0, 0),
        };
        // Never waits on a named pipe; a folder or device is refused.
        match atomic_file::open_regular(path) {
            Ok(file) => checkpoint.read(file)?,
            Err(e) if e.kind() == io::ErrorKind::NotFound => {}
            Err(e) => return Err(io_error(path, e)),
        }
        // Saturating: the counts are the file's word, and only shown.
        let passes = checkpoint.sppm.values().fold(0u64, |total, s| total.saturating_add(s.passes_done));
        checkpoint.resumed = (checkpoint.chunks.len(), passes);
        // Written again whole: a new file gets its header, an old one loses a cut record.
        checkpoint.rewrite()?;
        Ok(checkpoint)
    }

    /// The chunks and the SPPM passes (over all runs) found in the file when it was opened.
    pub fn resumed(&self) -> (usize, u64) {
        self.resumed
    }

    /// The file.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Removes the file: its render is finished and written.
    pub fn remove(self) -> Result<(), CheckpointError> {
        drop(self.file);
        std::fs::remove_file(&self.path).map_err(|e| io_error(&self.path, e))
    }

    /// The saved values of chunk `chunk` of run `run`.
    pub(crate) fn chunk(&self, run: u32, chunk: u32) -> Option<&Estimate> {
        self.chunks.get(&(run, chunk))
    }

    /// Saves the values of chunk `chunk` of run `run` (appended to the file).
    pub(crate) fn save_chunk(
        &mut self,
        run: u32,
        chunk: u32,
        estimate: Estimate,
    ) -> Result<(), CheckpointError> {
        let record = chunk_record(run, chunk, &estimate);
        let file = self.file.as_mut().ok_or_else(|| io_error(&self.path, io::Error::other("not open")))?;
        file.write_all(&record).and_then(|()| file.sync_data()).map_err(|e| io_error(&self.path, e))?;
        self.chunks.insert((run, chunk), estimate);
        Ok(())
    }

    /// The saved state of SPPM run `run`.
    pub(crate) fn sppm_state(&self, run: u32) -> Option<&SppmState> {
        self.sppm.get(&run)
    }

    /// Saves the state of SPPM run `run` if the last save is at least
    /// [`Self::sppm_interval`] old (the file is written again whole).
    pub(crate) fn save_sppm(&mut self, run: u32, state: &SppmState) -> Result<(), CheckpointError> {
        if self.last_sppm_save.is_some_and(|t| t.elapsed() < self.sppm_interval) {
            return Ok(());
        }
        self.sppm.insert(run, state.clone());
        self.rewrite()?;
        self.last_sppm_save = Some(Instant::now());
        Ok(())
    }

    /// Writes the whole file again (whole or not at all) and opens it for appending.
    fn rewrite(&mut self) -> Result<(), CheckpointError> {
        let mut bytes = MAGIC.to_vec();
        bytes.extend_from_slice(&(self.key.len() as u64).to_le_bytes());
        bytes.extend_from_slice(self.key.as_bytes());
        for (&(run, chunk), estimate) in &self.chunks {
            bytes.extend_from_slice(&chunk_record(run, chunk, estimate));
        }
        for (&run, state) in &self.sppm {
            bytes.extend_from_slice(&sppm_record(run, state));
        }
        atomic_file::write_atomically(&self.path, |out| out.write_all(&bytes)).map_err(|e| match e {
            atomic_file::WriteError::Io { source, .. } | atomic_file::WriteError::Encode { source, .. } => {
                io_error(&self.path, source)
            }
            other => io_error(&self.path, io::Error::other(other.to_string())),
        })?;
        self.file =
            Some(OpenOptions::new().append(true).open(&self.path).map_err(|e| io_error(&self.path, e))?);
        Ok(())
    }

    /// Reads the records of an existing file.
    fn read(&mut self, file: File) -> Result<(), CheckpointError> {
        let damaged =
            |reason: &str| CheckpointError::Damaged { path: self.path.clone(), reason: reason.into() };
        let mut input = io::BufReader::new(file);
        let mut magic = vec![0; MAGIC.len()];
        if read_exact_or_end(&mut input, &mut magic).map_err(|e| io_error(&self.path, e))? != MAGIC.len()
            || magic != MAGIC
        {
            return Err(damaged("it does not start as a rayterra checkpoint"));
        }
        let mut len = [0; 8];
        if read_exact_or_end(&mut input, &mut len).map_err(|e| io_error(&self.path, e))? != 8 {
            return Err(damaged("it ends in its header"));
        }
        let key_len = u64::from_le_bytes(len);
        if key_len > MAX_KEY_BYTES {
            return Err(damaged("its header is too long"));
        }
        let mut key = vec![0; key_len as usize];
        if read_exact_or_end(&mut input, &mut key).map_err(|e| io_error(&self.path, e))? != key.len() {
            return Err(damaged("it ends in its header"));
        }
        if key != self.key.as_bytes() {
            return Err(CheckpointError::OtherRender { path: self.path.clone() });
        }
        loop {
            let mut head = [0; 17];
            let got = read_exact_or_end(&mut input, &mut head).map_err(|e| io_error(&self.path, e))?;
            if got < head.len() {
                // The end of the file, or a record cut short by a kill: what came before stands.
                return Ok(());
            }
            let tag = head[0];
            let run = u32::from_le_bytes([head[1], head[2], head[3], head[4]]);
            let chunk = u32::from_le_bytes([head[5], head[6], head[7], head[8]]);
            let len = u64::from_le_bytes(head[9..17].try_into().unwrap_or_default());
            // The payload's length is known from the rows before anything is allocated.
            let expected = match tag {
                TAG_COLORS => self.chunk_pixels.get(chunk as usize).map(|&n| n as u64 * 24),
                TAG_SUMS => self.chunk_pixels.get(chunk as usize).map(|&n| 8 + n as u64 * 48),
                TAG_SPPM if chunk == 0 => {
                    Some(SPPM_FIXED_BYTES + (self.pixels * SppmState::VALUES_PER_PIXEL) as u64 * 8)
                }
                _ => None,
            };
            if expected != Some(len) {
                return Err(damaged("a record does not fit the render's rows"));
            }
            let mut payload = vec![0; len as usize + 8];
            if read_exact_or_end(&mut input, &mut payload).map_err(|e| io_error(&self.path, e))?
                < payload.len()
            {
                return Ok(());
            }
            let (payload, sum) = payload.split_at(len as usize);
            let mut hash = Fnv::default();
            hash.write(&head);
            hash.write(payload);
            if hash.0.to_le_bytes() != sum {
                return Err(damaged("a record's checksum is wrong"));
            }
            match tag {
                TAG_COLORS => {
                    let values = f64s(payload);
                    let colors = values.chunks_exact(3).map(|c| DVec3::new(c[0], c[1], c[2])).collect();
                    self.chunks.insert((run, chunk), Estimate::Colors(colors));
                }
                TAG_SUMS => {
                    let count = u64::from_le_bytes(payload[..8].try_into().unwrap_or_default());
                    let sums = payload[8..]
                        .chunks_exact(48)
                        .map(|s| ExactSum {
                            fixed: [0, 1, 2].map(|c| {
                                i128::from_le_bytes(s[16 * c..16 * (c + 1)].try_into().unwrap_or_default())
                            }),
                        })
                        .collect();
                    self.chunks.insert((run, chunk), Estimate::Sums(sums, count));
                }
                _ => {
                    let word = |i: usize| {
                        u64::from_le_bytes(payload[8 * i..8 * (i + 1)].try_into().unwrap_or_default())
                    };
                    let stats = SppmStats {
                        passes: word(1),
                        photons: word(2),
                        stored: word(3),
                        rays: word(4),
                        photon_seconds: f64::from_bits(word(5)),
                        mean_radius: 0.0,
                    };
                    let values = f64s(&payload[SPPM_FIXED_BYTES as usize..]);
                    self.sppm.insert(run, SppmState::from_values(word(0), &values, stats));
                }
            }
        }
    }
}

/// The bytes of an SPPM record's payload before the pixels: passes done, then the statistics.
const SPPM_FIXED_BYTES: u64 = 6 * 8;

/// The fewest rows a chunk cut out of a block has: adaptive anti-aliasing renders the rows just
/// above and below a chunk again, so a chunk of 16 rows costs at most 2/16 more first-pass work.
const MIN_CHUNK_ROWS: u32 = 16;

/// The rows of `rows` in about [`CHUNKS`] chunks, top first. Many blocks (a tile's) are grouped
/// whole, which adds no border; few (a whole image's one) are cut into pieces of at least
/// [`MIN_CHUNK_ROWS`] rows.
pub(crate) fn chunk_rows(rows: &Rows) -> Vec<Rows> {
    let blocks = rows.blocks();
    let n = blocks.len();
    if n >= CHUNKS as usize {
        let chunks = CHUNKS as usize;
        return (0..chunks)
            .map(|i| Rows::from_blocks(rows.width(), blocks[i * n / chunks..(i + 1) * n / chunks].to_vec()))
            .collect();
    }
    let total: u32 = blocks.iter().map(|b| b.len() as u32).sum();
    let piece = total.div_ceil(CHUNKS).max(MIN_CHUNK_ROWS);
    blocks
        .iter()
        .flat_map(|b| {
            let pieces = (b.len() as u32 / piece).max(1);
            let (start, len) = (b.start, b.len() as u32);
            (0..pieces).map(move |i| start + i * len / pieces..start + (i + 1) * len / pieces)
        })
        .map(|block| Rows::from_blocks(rows.width(), vec![block]))
        .collect()
}

fn io_error(path: &Path, source: io::Error) -> CheckpointError {
    CheckpointError::Io { path: path.to_path_buf(), source }
}

/// Reads until `buf` is full or the input ends; returns the bytes read.
fn read_exact_or_end(input: &mut impl Read, buf: &mut [u8]) -> io::Result<usize> {
    let mut filled = 0;
    while filled < buf.len() {
        match input.read(&mut buf[filled..]) {
            Ok(0) => break,
            Ok(n) => filled += n,
            Err(e) if e.kind() == io::ErrorKind::Interrupted => {}
            Err(e) => return Err(e),
        }
    }
    Ok(filled)
}

fn f64s(bytes: &[u8]) -> Vec<f64> {
    bytes.chunks_exact(8).map(|b| f64::from_le_bytes(b.try_into().unwrap_or_default())).collect()
}

/// A record: its head, payload and checksum.
fn record(tag: u8, run: u32, chunk: u32, payload: &[u8]) -> Vec<u8> {
    let mut out = Vec::with_capacity(payload.len() + 25);
    out.push(tag);
    out.extend_from_slice(&run.to_le_bytes());
    out.extend_from_slice(&chunk.to_le_bytes());
    out.extend_from_slice(&(payload.len() as u64).to_le_bytes());
    out.extend_from_slice(payload);
    let mut hash = Fnv::default();
    hash.write(&out);
    out.extend_from_slice(&hash.0.to_le_bytes());
    out
}

fn chunk_record(run: u32, chunk: u32, estimate: &Estimate) -> Vec<u8> {
    let mut payload = Vec::new();
    let tag = match estimate {
        Estimate::Colors(colors) => {
            colors
                .iter()
                .flat_map(|c| c.to_array())
                .for_each(|v| payload.extend_from_slice(&v.to_le_bytes()));
            TAG_COLORS
        }
        Estimate::Sums(sums, count) => {
            payload.extend_from_slice(&count.to_le_bytes());
            sums.iter().flat_map(|s| s.fixed).for_each(|v| payload.extend_from_slice(&v.to_le_bytes()));
            TAG_SUMS
        }
    };
    record(tag, run, chunk, &payload)
}

fn sppm_record(run: u32, state: &SppmState) -> Vec<u8> {
    let s = &state.stats;
    let mut payload = Vec::new();
    for word in [state.passes_done, s.passes, s.photons, s.stored, s.rays, s.photon_seconds.to_bits()] {
        payload.extend_from_slice(&word.to_le_bytes());
    }
    state.values().iter().for_each(|v| payload.extend_from_slice(&v.to_le_bytes()));
    record(TAG_SPPM, run, 0, &payload)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn chunks_cover_the_rows_in_order_and_cut_no_tile_block() {
        let ys = |chunks: &[Rows]| chunks.iter().flat_map(|c| c.ys().collect::<Vec<_>>()).collect::<Vec<_>>();
        // A whole image: pieces of at least 16 rows, at most CHUNKS of them.
        let whole = Rows::full(3, 760);
        let chunks = chunk_rows(&whole);
        assert!((30..=32).contains(&chunks.len()), "{}", chunks.len());
        assert!(chunks.iter().all(|c| c.ys().count() >= 16));
        assert_eq!(ys(&chunks), whole.ys().collect::<Vec<_>>());
        assert_eq!(chunk_rows(&Rows::full(4, 40)).len(), 2);
        assert_eq!(chunk_rows(&Rows::full(4, 2)).len(), 1);
        // A tile of many blocks: its blocks grouped whole.
        let tile = Rows::tile(5, 760, crate::parts::Split { index: 1, count: 4 }).expect("tile");
        let chunks = chunk_rows(&tile);
        assert_eq!(chunks.len(), 32.min(tile.blocks().len()));
        assert_eq!(ys(&chunks), tile.ys().collect::<Vec<_>>());
        let blocks: Vec<_> = chunks.iter().flat_map(|c| c.blocks().to_vec()).collect();
        assert_eq!(blocks, tile.blocks());
    }

    #[test]
    fn records_round_trip_and_a_cut_record_is_dropped() {
        let dir = tempfile::tempdir().expect("temp dir");
        let path = dir.path().join("c.ckpt");
        let rows = Rows::full(2, 64);
        let mut c = Checkpoint::open(&path, "key", &rows).expect("new");
        // Four chunks of 16 rows, 32 pixels each.
        let colors = Estimate::Colors(vec![DVec3::new(0.1, -2.0, 1e300); 32]);
        let mut sum = ExactSum::default();
        sum.add(DVec3::new(1.0 / 3.0, 7.0, -0.5));
        let sums = Estimate::Sums(vec![sum; 32], 17);
        c.save_chunk(0, 3, colors.clone()).expect("saved");
        c.save_chunk(2, 3, sums.clone()).expect("saved");
        let state = SppmState::from_values(
            5,
            &[0.25; 128 * 8],
            SppmStats { passes: 5, rays: 9, ..Default::default() },
        );
        c.save_sppm(1, &state).expect("saved");
        drop(c);
        let c = Checkpoint::open(&path, "key", &rows).expect("reopened");
        assert_eq!(c.chunk(0, 3), Some(&colors));
        assert_eq!(c.chunk(2, 3), Some(&sums));
        assert_eq!(c.sppm_state(1), Some(&state));
        assert_eq!(c.resumed(), (2, 5));
        drop(c);

        // A kill in the middle of appending a record: the record is lost, the others stand.
        let whole = std::fs::read(&path).expect("read");
        let mut cut = whole.clone();
        cut.extend_from_slice(&chunk_record(0, 1, &colors)[..30]);
        std::fs::write(&path, &cut).expect("write");
        let c = Checkpoint::open(&path, "key", &rows).expect("a cut record is dropped");
        assert_eq!(c.chunk(0, 1), None);
        assert_eq!(c.resumed(), (2, 5));
        drop(c);
        assert_eq!(std::fs::read(&path).expect("read"), whole, "rewritten without the cut record");

        // Another render's file, and a damaged one, are refused.
        assert!(matches!(Checkpoint::open(&path, "other", &rows), Err(CheckpointError::OtherRender { .. })));
        let mut damaged = whole.clone();
        let last = damaged.len() - 100;
        damaged[last] ^= 1;
        std::fs::write(&path, &damaged).expect("write");
        assert!(matches!(Checkpoint::open(&path, "key", &rows), Err(CheckpointError::Damaged { .. })));
        std::fs::write(&path, b"not a checkpoint").expect("write");
        assert!(matches!(Checkpoint::open(&path, "key", &rows), Err(CheckpointError::Damaged { .. })));
    }
}
