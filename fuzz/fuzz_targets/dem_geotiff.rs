//! The terrain's GeoTIFF elevation reader on any bytes: the tiff crate's parsing, the size checks
//! before decoding, the strip and tile table checks, the parallel decoding and the GeoKeys; then
//! the void filling and the placement.
#![no_main]

use libfuzzer_sys::fuzz_target;
use terrain::world::dem::{self, SizeLimit};

fuzz_target!(|bytes: &[u8]| {
    let limit = SizeLimit { allow_downsampling: false };
    if let Ok(elevation) = dem::geotiff::read(bytes, "fuzz.tif", limit) {
        assert_eq!(elevation.heights.len(), elevation.columns as usize * elevation.rows as usize);
        assert!(elevation.heights.iter().all(|h| h.is_finite() || h.is_nan()));
        // Keep the placement cheap: only small grids go on.
        if elevation.heights.len() <= 1 << 16 {
            if let Ok(prepared) = dem::prepare(elevation, "fuzz.tif", None, 512) {
                assert!(prepared.heights.iter().all(|h| h.is_finite()));
            }
        }
    }
});
