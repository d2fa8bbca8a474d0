//! Checkpoint files on any bytes, opened for a render of 3 x 5 pixels: the header, the key, and
//! records whose lengths, checksums or ends are wrong. Opening rewrites the file, so each process
//! works in a folder of its own (in /dev/shm when there is one: no disk writes), removed after
//! every input.
#![no_main]

use std::path::{Path, PathBuf};

use libfuzzer_sys::fuzz_target;
use raytracer::render::Rows;
use raytracer::render::checkpoint::Checkpoint;

fuzz_target!(|bytes: &[u8]| {
    let shm = Path::new("/dev/shm");
    let base = if shm.is_dir() { shm.to_path_buf() } else { std::env::temp_dir() };
    let dir: PathBuf = base.join(format!("rayterra-fuzz-checkpoint-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("a folder for the checkpoint");
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
    std::fs::remove_dir_all(&dir).expect("the folder is removed");
});
