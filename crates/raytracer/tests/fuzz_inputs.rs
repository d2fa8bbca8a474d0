//! The fuzz targets' seed corpora and every input a fuzzer ever crashed on (`fuzz/seeds/` and
//! `fuzz/regressions/`), run through the same code as the targets on every `cargo test`, so a
//! fixed crash stays fixed without a fuzzer at hand.

use std::path::{Path, PathBuf};

use raytracer::MemoryBudget;
use raytracer::scene::{self, SourceFile};
use raytracer::texture::Texture;

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
        let source = SourceFile::from_bytes(path.display().to_string(), None, &bytes);
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
