//! The PLY mesh reader on any bytes: the header, the count check against the file's size,
//! ASCII and binary payloads through `ply-rs-bw`, fans of polygons and the index check.
#![no_main]

use libfuzzer_sys::fuzz_target;
use raytracer::geometry::ply::parse_ply;

fuzz_target!(|bytes: &[u8]| {
    if let Ok(mesh) = parse_ply(bytes, "fuzz.ply") {
        let n = mesh.positions.len();
        assert!(mesh.triangles.iter().all(|t| t.iter().all(|&i| (i as usize) < n)));
        assert!(mesh.normals.as_ref().is_none_or(|v| v.len() == n));
        assert!(mesh.uvs.as_ref().is_none_or(|v| v.len() == n));
    }
});
