//! The terrain's heightmap loader on any bytes: format detection, the size check from the
//! header, decoding behind image::Limits, and the conversion to grey levels.
#![no_main]

use libfuzzer_sys::fuzz_target;
use terrain::world::Heightmap;

fuzz_target!(|bytes: &[u8]| {
    if let Ok(map) = Heightmap::decode(bytes, "fuzz.img") {
        assert!(map.levels().all(|l| l.is_finite()));
    }
});
