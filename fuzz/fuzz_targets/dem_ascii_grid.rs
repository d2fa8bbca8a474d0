//! The terrain's Esri ASCII grid reader on any bytes: the header, the size checks against the
//! limits and the file's length, the numbers row by row; then the void filling.
#![no_main]

use libfuzzer_sys::fuzz_target;
use terrain::world::dem::{self, SizeLimit};

fuzz_target!(|bytes: &[u8]| {
    let limit = SizeLimit { allow_downsampling: false };
    if let Ok(elevation) = dem::ascii_grid::read(bytes, "fuzz.asc", limit) {
        assert_eq!(elevation.heights.len(), elevation.columns as usize * elevation.rows as usize);
        if elevation.heights.len() <= 1 << 16 {
            if let Ok(prepared) = dem::prepare(elevation, "fuzz.asc", Some(10.0), 512) {
                assert!(prepared.heights.iter().all(|h| h.is_finite()));
            }
        }
    }
});
