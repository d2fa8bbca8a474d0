//! The terrain's SRTM .hgt reader on any bytes (and any file name): the length check, the
//! big-endian samples and voids, the corner from the name.
#![no_main]

use libfuzzer_sys::fuzz_target;
use terrain::world::dem;

fuzz_target!(|input: (&str, &[u8])| {
    let (name, bytes) = input;
    let _ = dem::hgt::corner_of_name(name);
    if let Ok(elevation) = dem::hgt::read(bytes, name) {
        assert_eq!(elevation.heights.len(), elevation.columns as usize * elevation.rows as usize);
        assert!(elevation.spacing.metres().is_some_and(|(x, y)| x.is_finite() && y.is_finite()));
    }
});
