//! The meshes of the published Mitsuba data (`../shared/mitsuba-data`): its `serialized` and PLY
//! files read with the counts, first vertices and first triangles that Mitsuba 3.9.1 reads from
//! them (printed once with `mitsuba.load_dict` and `mitsuba.traverse`). Skipped loudly when the
//! data is absent, except under CI.

use std::path::{Path, PathBuf};

use raytracer::geometry::mesh_file::MeshData;
use raytracer::geometry::ply::read_ply;
use raytracer::geometry::serialized::{read_serialized, serialized_mesh_count};

/// `../shared/mitsuba-data` beside the repository (or under `$RAYTERRA_SHARED`), or `None`
/// (skipped, loudly) without it.
fn mitsuba_data() -> Option<PathBuf> {
    let shared = std::env::var_os("RAYTERRA_SHARED")
        .map(PathBuf::from)
        .unwrap_or_else(|| Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared"));
    let dir = shared.join("mitsuba-data");
    if dir.join("common/meshes").is_dir() {
        return Some(dir);
    }
    let message = format!("the Mitsuba test data is missing: expected it at {}", dir.display());
    if std::env::var_os("CI").is_some() {
        panic!("{message} (required under CI)");
    }
    test_skips::skip("raytracer Mitsuba-mesh tests", &message);
    None
}

/// Checks a mesh against what Mitsuba read: vertex and triangle counts, the first vertex
/// position and the first triangle, and which attributes the file has.
fn check(
    mesh: &MeshData,
    what: &str,
    counts: (usize, usize),
    first: [f32; 3],
    triangle: [u32; 3],
    normals: bool,
    uvs: bool,
) {
    assert_eq!((mesh.positions.len(), mesh.triangles.len()), counts, "{what}");
    // Mitsuba printed the f32 values as doubles; the literals here are rounded to 8 digits.
    let close = mesh.positions[0].iter().zip(first).all(|(a, b)| (a - b).abs() <= 1e-7 * b.abs().max(1.0));
    assert!(close, "{what}: {:?} vs {first:?}", mesh.positions[0]);
    assert_eq!(mesh.triangles[0], triangle, "{what}");
    assert_eq!(mesh.normals.as_ref().map(Vec::len), normals.then_some(counts.0), "{what}");
    assert_eq!(mesh.uvs.as_ref().map(Vec::len), uvs.then_some(counts.0), "{what}");
}

#[test]
fn the_material_preview_meshes_read_as_mitsuba_reads_them() {
    let Some(data) = mitsuba_data() else { return };
    let path = data.join("common/meshes/matpreview.serialized");
    let bytes = std::fs::read(&path).expect("readable");
    assert_eq!(serialized_mesh_count(&bytes, "matpreview").expect("dictionary"), 3);
    let expected = [
        ((289, 512), [-0.504_866_24, 0.574_720_9, 0.784_379]),
        ((2078, 3936), [0.667_028_55, 0.276_292_26, 0.062_822_94]),
        ((29439, 57152), [0.047_490_597, -0.449_503_18, -0.902_684_45]),
    ];
    for (index, (counts, first)) in expected.into_iter().enumerate() {
        let mesh = read_serialized(&path, index as u32).expect("reads");
        check(&mesh, &format!("matpreview mesh {index}"), counts, first, [0, 1, 2], true, true);
    }
    let e = read_serialized(&path, 3).expect_err("only three meshes");
    assert!(e.to_string().ends_with("mesh 3: the file holds 3 meshes (shape_index 0 to 2)"), "{e}");
    // The copy beside the scene is the same file.
    let beside = read_serialized(&data.join("scenes/matpreview/matpreview.serialized"), 2).expect("reads");
    assert_eq!(beside.positions.len(), 29439);
}

#[test]
fn the_ply_meshes_read_as_mitsuba_reads_them() {
    let Some(data) = mitsuba_data() else { return };
    let meshes = data.join("common/meshes");
    let bunny = read_ply(&meshes.join("bunny.ply")).expect("binary bunny");
    check(
        &bunny,
        "bunny",
        (35947, 69451),
        [-0.037_829_7, 0.127_94, 0.004_474_67],
        [21216, 21215, 20399],
        false,
        false,
    );
    let low = read_ply(&meshes.join("bunny_lowres.ply")).expect("ASCII bunny with extra properties");
    check(
        &low,
        "bunny_lowres",
        (453, 948),
        [-0.031_221_6, 0.126_304, 0.005_149_24],
        [164, 94, 98],
        false,
        false,
    );
    let sphere = read_ply(&meshes.join("sphere.ply")).expect("sphere");
    check(&sphere, "sphere", (422, 840), [0.0, 0.0, -127.0], [0, 1, 2], false, false);
    let teapot = read_ply(&meshes.join("teapot.ply")).expect("teapot");
    check(&teapot, "teapot", (1177, 2256), [1.381_37, 0.0, 2.454_69], [0, 1, 2], false, false);
    let coloured =
        read_ply(&data.join("docs/scenes/meshes/bunny_attribute_color.ply")).expect("with normals");
    check(
        &coloured,
        "bunny_attribute_color",
        (6056, 12000),
        [-0.026_476_618, 0.110_840_61, 0.037_770_193],
        [4868, 4397, 3595],
        true,
        false,
    );
}

#[test]
fn truncated_copies_of_the_real_meshes_are_refused() {
    let Some(data) = mitsuba_data() else { return };
    let dir = tempfile::tempdir().expect("temp dir");
    for name in ["bunny.ply", "teapot.ply", "matpreview.serialized"] {
        let bytes = std::fs::read(data.join("common/meshes").join(name)).expect("readable");
        let cut = dir.path().join(name);
        // Two thirds of a PLY file; the first mesh of the serialized file (at its start) cut.
        let keep = if name.ends_with(".ply") { bytes.len() * 2 / 3 } else { 2000 };
        std::fs::write(&cut, &bytes[..keep]).expect("write");
        let error = if name.ends_with(".ply") {
            read_ply(&cut).expect_err("truncated PLY")
        } else {
            read_serialized(&cut, 0).expect_err("truncated serialized")
        };
        // "bunny.ply: element face: ... Unexpected end of file ...", "matpreview.serialized:
        // mesh 0: the data ends in the normals ...": the file and the part cut.
        assert!(error.to_string().starts_with(&cut.display().to_string()), "{error}");
        let part = if name.ends_with(".ply") { "element face" } else { "mesh 0" };
        assert_eq!(error.element, part, "{error}");
    }
}
