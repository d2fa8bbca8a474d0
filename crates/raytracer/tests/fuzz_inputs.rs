//! The fuzz targets' seed corpora and every input a fuzzer ever crashed on (`fuzz/seeds/` and
//! `fuzz/regressions/`), run through the same code as the targets on every `cargo test`, so a
//! fixed crash stays fixed without a fuzzer at hand.
//!
//! The seeds of `part_file` and `checkpoint` are files of a tiny render of the project's
//! `scenes/caustics.txt`: after a change of either format,
//! `RAYTERRA_WRITE_FUZZ_SEEDS=1 cargo test -p raytracer --test fuzz_inputs seeds` writes them
//! again, and every run checks that the committed ones still read as that render.

mod support;

use std::io::Cursor;
use std::path::{Path, PathBuf};

use raytracer::geometry::obj::{MeshTransform, parse_obj};
use raytracer::integrator::Model;
use raytracer::parts::{Part, PartHeader, Split, read_part_from, write_part};
use raytracer::render::checkpoint::Checkpoint;
use raytracer::render::{RenderSettings, Rows, Sampling, render_portion, render_portion_resumable};
use raytracer::scene::{self, SourceFile};
use raytracer::texture::Texture;
use raytracer::{MemoryBudget, PreparedScene};
use support::{load, workspace};

/// The files of `fuzz/seeds/TARGET` and `fuzz/regressions/TARGET`.
fn inputs(target: &str) -> Vec<(PathBuf, Vec<u8>)> {
    let fuzz = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fuzz");
    let mut files = Vec::new();
    for kind in ["seeds", "regressions"] {
        let Ok(entries) = std::fs::read_dir(fuzz.join(kind).join(target)) else { continue };
        for entry in entries.filter_map(Result::ok) {
            let bytes = std::fs::read(entry.path()).expect("readable input");
            files.push((entry.path(), bytes));
        }
    }
    files.sort();
    assert!(!files.is_empty(), "no seed inputs for {target} under {}", fuzz.display());
    files
}

#[test]
fn scene_parser_inputs() {
    for (path, bytes) in inputs("scene_parser") {
        let source = SourceFile::from_bytes(path.display().to_string(), None, bytes.as_slice());
        match scene::parse(&source) {
            Ok(parsed) => parsed.diagnostics.iter().for_each(|d| drop(d.to_string())),
            Err(error) => {
                assert!(error.error_count() > 0, "{}", path.display());
                drop(error.to_string());
            }
        }
    }
}

#[test]
fn mitsuba_xml_inputs() {
    use raytracer::scene::mitsuba;
    for (path, bytes) in inputs("mitsuba_xml") {
        // As the fuzz target does: the text without a folder, `spp` defined.
        let source = SourceFile::from_bytes(path.display().to_string(), None, bytes.as_slice());
        let defines = [("spp".to_owned(), "4".to_owned())];
        let read = mitsuba::read_source(source, &defines);
        let name = path.to_string_lossy();
        if name.contains("/seeds/") {
            // The seeds that show errors fail; the others read.
            assert_eq!(read.is_err(), name.contains("errors"), "{name}: {read:?}");
        }
        match read {
            Ok(doc) => {
                for plugin in doc.plugins() {
                    assert!(plugin.children.iter().all(|c| doc.target(c).is_some()), "{name}");
                }
            }
            Err(error) => drop(error.diagnostic().to_string()),
        }
    }
}

/// As the mesh fuzz targets check: indices in range, attributes as long as the positions.
fn check_mesh(mesh: &raytracer::geometry::mesh_file::MeshData, name: &str) {
    let n = mesh.positions.len();
    assert!(mesh.triangles.iter().all(|t| t.iter().all(|&i| (i as usize) < n)), "{name}");
    assert!(mesh.normals.as_ref().is_none_or(|v| v.len() == n), "{name}");
    assert!(mesh.uvs.as_ref().is_none_or(|v| v.len() == n), "{name}");
}

#[test]
fn ply_mesh_inputs() {
    for (path, bytes) in inputs("ply_mesh") {
        let name = path.display().to_string();
        let mesh = raytracer::geometry::ply::parse_ply(&bytes, &name);
        if name.contains("/seeds/") {
            assert!(mesh.is_ok(), "a seed must read: {mesh:?}");
        }
        if let Ok(mesh) = mesh {
            check_mesh(&mesh, &name);
        }
    }
}

#[test]
fn serialized_mesh_inputs() {
    for (path, bytes) in inputs("serialized_mesh") {
        let name = path.display().to_string();
        for shape_index in 0..2 {
            let mesh = raytracer::geometry::serialized::parse_serialized(&bytes, &name, shape_index);
            if name.contains("/seeds/") {
                assert!(mesh.is_ok(), "a seed's meshes must read: {mesh:?}");
            }
            if let Ok(mesh) = mesh {
                check_mesh(&mesh, &name);
            }
        }
    }
}

#[test]
fn texture_decoder_inputs() {
    for (path, bytes) in inputs("texture_decoder") {
        let budget = MemoryBudget::new(256 << 20);
        let decoded = Texture::from_bytes(&bytes, &path.display().to_string(), &budget);
        if path.to_string_lossy().contains("/seeds/") {
            assert!(decoded.is_ok(), "a seed must decode: {decoded:?}");
        }
        // As the fuzz target does: a texture that decodes can be looked up.
        if let Ok(texture) = decoded {
            assert!(texture.width() > 0 && texture.height() > 0, "{}", path.display());
            let _ = texture.sample(0.3, 0.7);
        }
    }
}

#[test]
fn obj_mesh_inputs() {
    for (path, bytes) in inputs("obj_mesh") {
        // As the fuzz target does: material libraries only by an absolute path.
        let dir = Path::new("/nonexistent-fuzz-dir");
        let mesh = parse_obj(&bytes, &path.display().to_string(), dir, &MeshTransform::default());
        if path.to_string_lossy().contains("/seeds/") {
            assert!(mesh.is_ok(), "a seed must load: {mesh:?}");
        }
        let Ok(mesh) = mesh else { continue };
        let v = &mesh.vertices;
        for (_, triangles) in &mesh.groups {
            for t in triangles {
                assert!(t.position.iter().all(|&i| (i as usize) < v.positions.len()), "{}", path.display());
                assert!(t.normal.iter().all(|&i| (i as usize) < v.normals.len()), "{}", path.display());
                assert!(
                    t.uv.iter().all(|&i| i == u32::MAX || (i as usize) < v.uvs.len()),
                    "{}",
                    path.display()
                );
            }
        }
    }
}

#[test]
fn part_file_inputs() {
    for (path, bytes) in inputs("part_file") {
        let budget = MemoryBudget::new(256 << 20);
        let part = read_part_from(Cursor::new(&bytes), &path, &budget);
        if path.to_string_lossy().contains("/seeds/") {
            assert!(part.is_ok(), "a seed must read: {part:?}");
        }
        if let Ok(part) = part {
            for block in &part.blocks {
                assert_eq!(block.pixels.len(), block.rows.len() * part.header.width as usize);
                assert!(block.sums.as_ref().is_none_or(|s| s.len() == block.pixels.len()));
            }
        }
    }
}

/// The render every `checkpoint` input is opened for (as in the fuzz target).
const CHECKPOINT_KEY: &str = "fuzz";
fn checkpoint_rows() -> Rows {
    Rows::full(3, 5)
}

#[test]
fn checkpoint_inputs() {
    for (path, bytes) in inputs("checkpoint") {
        // Opening rewrites the file: a copy.
        let dir = tempfile::tempdir().expect("temp dir");
        let copy = dir.path().join("fuzz.ckpt");
        std::fs::write(&copy, &bytes).expect("written");
        let opened = Checkpoint::open(&copy, CHECKPOINT_KEY, &checkpoint_rows());
        if path.to_string_lossy().contains("/seeds/") {
            assert!(opened.is_ok(), "a seed must open: {opened:?}");
        }
        if let Ok(checkpoint) = opened {
            let resumed = checkpoint.resumed();
            drop(checkpoint);
            let again = Checkpoint::open(&copy, CHECKPOINT_KEY, &checkpoint_rows()).expect("reopens");
            assert_eq!(again.resumed(), resumed, "{}", path.display());
        }
    }
}

/// A tiny render of `scenes/caustics.txt` in `model`.
fn tiny(scene: &PreparedScene, model: Model, width: u32, height: u32) -> RenderSettings {
    RenderSettings {
        width,
        height,
        model,
        photons: Some(2_000),
        passes: Some(2),
        runs: 2,
        sampling: if model == Model::Path { Sampling::Uniform(2) } else { Sampling::Adaptive },
        ..RenderSettings::for_scene(scene)
    }
}

/// The seeds of `part_file`: tile 1 of 2 of a classic render of 2 x 96 pixels, and pass 1 of 2
/// of a path-traced one of 2 x 48 pixels. Both are cut into blocks of 8 rows, high enough for
/// blocks of [`raytracer::parts::tile_block_rows`]'s largest share rather than its least.
fn part_seeds(scene: &PreparedScene) -> Vec<(&'static str, Part)> {
    [
        ("classic-tile-1-of-2.exr", Model::Classic, 96, Split { index: 1, count: 2 }, Split::WHOLE, 0..2),
        ("path-pass-1-of-2.exr", Model::Path, 48, Split::WHOLE, Split { index: 1, count: 2 }, 1..2),
    ]
    .into_iter()
    .map(|(name, model, height, tile, pass, runs)| {
        assert_eq!(raytracer::parts::tile_block_rows(height, tile.count), 8);
        let settings = tiny(scene, model, 2, height);
        let rows = Rows::tile(2, height, tile).expect("tile");
        let portion = render_portion(scene, &settings, &rows, runs, &|_| {}).expect("renders");
        let header = PartHeader {
            width: 2,
            height,
            scene: "caustics".into(),
            settings: format!("{model:?}"),
            tile,
            pass,
            samples: 2,
        };
        (name, Part::from_portion(header, &rows, portion.pixels))
    })
    .collect()
}

/// The seeds of `checkpoint`: the checkpoints of both runs of a classic, a path-traced and an
/// SPPM render of [`checkpoint_rows`], each with the chunks (or SPPM states) it saved; and the
/// classic one cut in the middle of a record, as a kill leaves it. Returns the names, the bytes
/// and what opening them resumes.
fn checkpoint_seeds(scene: &PreparedScene) -> Vec<(String, Vec<u8>, (usize, u64))> {
    let dir = tempfile::tempdir().expect("temp dir");
    let rows = checkpoint_rows();
    let mut seeds = Vec::new();
    for (name, model) in [("classic", Model::Classic), ("path", Model::Path), ("sppm", Model::Sppm)] {
        let path = dir.path().join(name);
        let mut checkpoint = Checkpoint::open(&path, CHECKPOINT_KEY, &rows).expect("new checkpoint");
        checkpoint.sppm_interval = std::time::Duration::ZERO;
        let settings = tiny(scene, model, 3, 5);
        render_portion_resumable(scene, &settings, &rows, 0..2, &|_| {}, Some(&mut checkpoint))
            .expect("renders");
        drop(checkpoint);
        let bytes = std::fs::read(&path).expect("read");
        let resumed = Checkpoint::open(&path, CHECKPOINT_KEY, &rows).expect("reopens").resumed();
        if model == Model::Classic {
            // The header, the first record and half the second. Each record is one run's chunk
            // of all 5 rows (a chunk has at least 16 rows): its head (17 bytes), three f64
            // colours of 15 pixels and a checksum.
            assert_eq!(resumed, (2, 0), "2 runs of 1 chunk");
            let record = 17 + 15 * 24 + 8;
            let header = bytes.len() - 2 * record;
            let cut = bytes[..header + record + record / 2].to_vec();
            seeds.push((format!("{name}-cut.ckpt"), cut, (1, 0)));
        }
        seeds.push((format!("{name}.ckpt"), bytes, resumed));
    }
    seeds
}

#[test]
fn part_file_and_checkpoint_seeds_are_files_of_a_tiny_render() {
    let scene = load(&workspace().join("scenes/caustics.txt"));
    let fuzz = workspace().join("fuzz/seeds");
    let write = std::env::var_os("RAYTERRA_WRITE_FUZZ_SEEDS").is_some();
    for (name, part) in part_seeds(&scene) {
        let path = fuzz.join("part_file").join(name);
        if write {
            write_part(&part, &path).expect("seed written");
        }
        let bytes = std::fs::read(&path).expect("a committed seed");
        let read = read_part_from(Cursor::new(bytes), &path, &MemoryBudget::new(256 << 20)).expect("reads");
        assert!(read == part, "{} is not the part of the render", path.display());
    }
    for (name, bytes, resumed) in checkpoint_seeds(&scene) {
        let path = fuzz.join("checkpoint").join(name);
        if write {
            std::fs::write(&path, &bytes).expect("seed written");
        }
        let dir = tempfile::tempdir().expect("temp dir");
        let copy = dir.path().join("copy.ckpt");
        std::fs::copy(&path, &copy).expect("a committed seed");
        let opened = Checkpoint::open(&copy, CHECKPOINT_KEY, &checkpoint_rows()).expect("opens");
        assert_eq!(opened.resumed(), resumed, "{}", path.display());
        assert!(resumed.0 > 0 || resumed.1 > 0, "{} holds work", path.display());
    }
}
