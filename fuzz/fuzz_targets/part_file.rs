//! Part files of split renders on any bytes: OpenEXR headers, the part's attributes, its blocks
//! of rows and channels checked before the pixels are charged to a 256 MiB memory budget and
//! decoded.
#![no_main]

use std::io::Cursor;
use std::path::Path;

use libfuzzer_sys::fuzz_target;
use raytracer::MemoryBudget;
use raytracer::parts::read_part_from;

fuzz_target!(|bytes: &[u8]| {
    let budget = MemoryBudget::new(256 << 20);
    if let Ok(part) = read_part_from(Cursor::new(bytes), Path::new("fuzz.exr"), &budget) {
        let width = part.header.width as usize;
        for block in &part.blocks {
            assert_eq!(block.pixels.len(), block.rows.len() * width);
            if let Some(sums) = &block.sums {
                assert_eq!(sums.len(), block.pixels.len());
            }
        }
    }
});
