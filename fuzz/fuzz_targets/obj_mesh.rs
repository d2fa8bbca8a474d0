//! The OBJ mesh loader on any bytes: the face check, `tobj`'s parser, the fan into triangles,
//! normals and texture coordinates, and the transform. Material libraries are looked up in a
//! folder that does not exist, so only those named by an absolute path can be read (bounded,
//! regular files only, as for any mesh).
#![no_main]

use std::path::Path;

use libfuzzer_sys::fuzz_target;
use raytracer::geometry::obj::{MeshTransform, parse_obj};

fuzz_target!(|bytes: &[u8]| {
    let transform = MeshTransform::default();
    if let Ok(mesh) = parse_obj(bytes, "fuzz.obj", Path::new("/nonexistent-fuzz-dir"), &transform) {
        // Every index a triangle holds points into the vertices.
        let v = &mesh.vertices;
        for (_, triangles) in &mesh.groups {
            for t in triangles {
                assert!(t.position.iter().all(|&i| (i as usize) < v.positions.len()));
                assert!(t.normal.iter().all(|&i| (i as usize) < v.normals.len()));
                assert!(t.uv.iter().all(|&i| i == u32::MAX || (i as usize) < v.uvs.len()));
            }
        }
    }
});
