//! The reader of Mitsuba's `serialized` meshes on any bytes: the header, the dictionary of
//! meshes, the zlib stream, the counts against what the compressed data can hold, and the index
//! check. The first and second meshes of the file are read.
#![no_main]

use libfuzzer_sys::fuzz_target;
use raytracer::geometry::serialized::parse_serialized;

fuzz_target!(|bytes: &[u8]| {
    for shape_index in 0..2 {
        if let Ok(mesh) = parse_serialized(bytes, "fuzz.serialized", shape_index) {
            let n = mesh.positions.len();
            assert!(mesh.triangles.iter().all(|t| t.iter().all(|&i| (i as usize) < n)));
            assert!(mesh.normals.as_ref().is_none_or(|v| v.len() == n));
            assert!(mesh.uvs.as_ref().is_none_or(|v| v.len() == n));
        }
    }
});
