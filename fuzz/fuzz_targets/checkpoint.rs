//! Checkpoint files on any bytes, opened for a render of 3 x 5 pixels: the header, the key, and
//! records whose lengths, tags or ends are wrong. Records carry checksums, which random bytes
//! rarely match, so each input is opened as it is, then again with its records' checksums set
//! right (so that what follows a checksum gets fuzzed too; a crash of that kind is kept in
//! `fuzz/regressions/checkpoint/` with its checksums set). Opening rewrites the file, so each
//! process works in a folder of its own (in /dev/shm when there is one: no disk writes), removed
//! after every input.
#![no_main]

use std::path::{Path, PathBuf};

use libfuzzer_sys::fuzz_target;
use raytracer::render::Rows;
use raytracer::render::checkpoint::Checkpoint;

/// The first line of a checkpoint file.
const MAGIC: &[u8] = b"rayterra checkpoint 1\n";

/// The 64-bit FNV-1a hash of `bytes`, the checksum of a record (see the format in
/// `render/checkpoint.rs`).
fn fnv(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325, |h, &b| (h ^ b as u64).wrapping_mul(0x0100_0000_01b3))
}

/// Sets the checksum of every whole record after the header of `file` to what its head and
/// payload hash to.
fn repair_checksums(file: &mut [u8]) {
    let word = |at: u64| {
        let at = usize::try_from(at).ok()?;
        file.get(at..at.checked_add(8)?).map(|w| u64::from_le_bytes(w.try_into().expect("8 bytes")))
    };
    let Some(key_len) = word(MAGIC.len() as u64) else { return };
    let mut at = (MAGIC.len() as u64 + 8).saturating_add(key_len);
    let mut records = Vec::new();
    while let Some(len) = word(at.saturating_add(9)) {
        let end = at.saturating_add(17).saturating_add(len);
        if end.saturating_add(8) > file.len() as u64 {
            break;
        }
        records.push((at as usize, end as usize));
        at = end + 8;
    }
    for (start, end) in records {
        let sum = fnv(&file[start..end]);
        file[end..end + 8].copy_from_slice(&sum.to_le_bytes());
    }
}

/// Opens `bytes` as the checkpoint of the render of 3 x 5 pixels keyed `fuzz`, in `dir`.
fn open(dir: &Path, bytes: &[u8]) {
    let path = dir.join("fuzz.ckpt");
    std::fs::write(&path, bytes).expect("the checkpoint file is written");
    let rows = Rows::full(3, 5);
    if let Ok(checkpoint) = Checkpoint::open(&path, "fuzz", &rows) {
        // What was read is written again as it was: opening the new file finds the same work.
        let resumed = checkpoint.resumed();
        drop(checkpoint);
        let again = Checkpoint::open(&path, "fuzz", &rows).expect("a rewritten checkpoint opens");
        assert_eq!(again.resumed(), resumed);
    }
}

fuzz_target!(|bytes: &[u8]| {
    let shm = Path::new("/dev/shm");
    let base = if shm.is_dir() { shm.to_path_buf() } else { std::env::temp_dir() };
    let dir: PathBuf = base.join(format!("rayterra-fuzz-checkpoint-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("a folder for the checkpoint");
    open(&dir, bytes);
    let mut repaired = bytes.to_vec();
    repair_checksums(&mut repaired);
    if repaired != bytes {
        open(&dir, &repaired);
    }
    std::fs::remove_dir_all(&dir).expect("the folder is removed");
});
