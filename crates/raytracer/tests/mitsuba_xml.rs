//! Every Mitsuba 3 scene file of the published test data (`../shared/mitsuba-data`: the Cornell
//! box, the material preview, the documentation's scenes) reads into a plugin tree, with
//! plausible plugin counts. When the data is absent the tests are skipped with a loud message,
//! except under CI, where they fail.

use std::path::{Path, PathBuf};

use raytracer::scene::mitsuba::{self, Document, Node, PluginKind, Value};

/// `../shared/mitsuba-data` beside the repository (or under `$RAYTERRA_SHARED`, for a checkout
/// elsewhere, such as a git worktree), or `None` (skipped, loudly) without it.
fn mitsuba_data() -> Option<PathBuf> {
    let shared = std::env::var_os("RAYTERRA_SHARED")
        .map(PathBuf::from)
        .unwrap_or_else(|| Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared"));
    let dir = shared.join("mitsuba-data");
    if dir.join("scenes/cbox").is_dir() {
        return Some(dir);
    }
    let message = format!("the Mitsuba test data is missing: expected it at {}", dir.display());
    if std::env::var_os("CI").is_some() {
        panic!("{message} (required under CI)");
    }
    test_skips::skip("raytracer Mitsuba-data tests", &message);
    None
}

/// The `.xml` files under `dir`, sorted.
fn xml_files(dir: &Path, out: &mut Vec<PathBuf>) {
    let mut entries: Vec<PathBuf> =
        std::fs::read_dir(dir).expect("list").map(|e| e.expect("entry").path()).collect();
    entries.sort();
    for path in entries {
        if path.is_dir() {
            xml_files(&path, out);
        } else if path.extension().is_some_and(|e| e == "xml") {
            out.push(path);
        }
    }
}

fn count(doc: &Document, kind: PluginKind) -> usize {
    doc.plugins().filter(|p| p.kind == kind).count()
}

/// Files that are fragments meant to be included, not scenes of their own: their root is a
/// `<scene>` too, but they refer to ids that the including scene declares.
fn is_fragment(path: &Path) -> bool {
    let parent = path.parent().and_then(Path::file_name).and_then(|n| n.to_str());
    matches!(parent, Some("fragments" | "include"))
}

#[test]
fn every_scene_of_the_mitsuba_data_reads() {
    let Some(data) = mitsuba_data() else { return };
    let mut files = Vec::new();
    for dir in ["scenes/cbox", "scenes/matpreview", "docs/scenes"] {
        xml_files(&data.join(dir), &mut files);
    }
    assert!(files.len() >= 100, "expected the published scenes, found {}", files.len());
    let mut failures = Vec::new();
    let mut read = 0;
    for path in &files {
        let mut result = mitsuba::read_file(path, &[]);
        // A few documentation scenes leave the sample count to the command line (`-D spp=...`),
        // as Mitsuba's documentation build gives it.
        if let Err(mitsuba::MitsubaError::UndefinedParameter { name, .. }) = &result {
            assert_eq!(name, "spp", "{}", path.display());
            result = mitsuba::read_file(path, &[("spp".to_owned(), "4".to_owned())]);
        }
        match result {
            Ok(doc) => {
                read += 1;
                assert_eq!(doc.root.kind, PluginKind::Scene, "{}", path.display());
                // Every reference resolves.
                for p in doc.plugins() {
                    for c in &p.children {
                        assert!(doc.target(c).is_some(), "{}: {c:?}", path.display());
                    }
                }
                if !is_fragment(path) {
                    let shapes = count(&doc, PluginKind::Shape);
                    let sensors = count(&doc, PluginKind::Sensor);
                    assert!(shapes + sensors > 0, "{} has neither shapes nor sensors", path.display());
                }
            }
            // A fragment may name ids that only the including scene declares, or search folders
            // relative to it (`include/*.xml` has `<path value="../../common"/>`, found from
            // `docs/scenes/` through the including file's resolver, as Mitsuba finds it).
            Err(mitsuba::MitsubaError::UnknownId { .. } | mitsuba::MitsubaError::PathNotFound { .. })
                if is_fragment(path) => {}
            Err(e) => failures.push(format!("{e}")),
        }
    }
    assert!(
        failures.is_empty(),
        "{} of {} files failed:\n{}",
        failures.len(),
        files.len(),
        failures.join("\n")
    );
    eprintln!("{read} of {} Mitsuba scene files read", files.len());
}

#[test]
fn the_cornell_box_has_its_plugins() {
    let Some(data) = mitsuba_data() else { return };
    let doc = mitsuba::read_file(&data.join("scenes/cbox/cbox-rgb.xml"), &[]).expect("cbox-rgb reads");
    assert_eq!(count(&doc, PluginKind::Sensor), 1);
    assert_eq!(count(&doc, PluginKind::Integrator), 1);
    assert!(count(&doc, PluginKind::Shape) >= 7, "{}", count(&doc, PluginKind::Shape));
    let emitter = doc.get("area-emitter").expect("the area emitter");
    assert_eq!((emitter.kind, emitter.type_name.as_str()), (PluginKind::Emitter, "area"));
    // The luminaire refers to it, and the files are the scene and its three fragments.
    let lights: Vec<_> = doc
        .plugins()
        .filter(|p| p.kind == PluginKind::Shape)
        .filter(|p| p.children.iter().any(|c| matches!(&c.node, Node::Reference(id) if id == "area-emitter")))
        .collect();
    assert_eq!(lights.len(), 1);
    assert_eq!(doc.files.len(), 4);
    // The meshes resolve from the scene's folder, as Mitsuba resolves them.
    let obj = lights[0].property("filename").expect("filename");
    let Value::String(name) = &obj.value else { panic!("{obj:?}") };
    assert!(doc.resolve_file(name).is_some_and(|p| p.is_file()), "{name}");
    let sensor = doc.plugins().find(|p| p.kind == PluginKind::Sensor).expect("sensor");
    assert!(matches!(sensor.property("to_world").map(|p| &p.value), Some(Value::Transform(_))));
}

#[test]
fn the_spectral_cornell_box_reads_its_spectra() {
    let Some(data) = mitsuba_data() else { return };
    let doc =
        mitsuba::read_file(&data.join("scenes/cbox/cbox-spectral.xml"), &[]).expect("cbox-spectral reads");
    let spectra = doc
        .plugins()
        .flat_map(|p| p.properties.iter())
        .filter(|p| matches!(p.value, Value::Spectrum(mitsuba::Spectrum::Sampled { .. })))
        .count();
    assert!(spectra >= 4, "{spectra} sampled spectra");
}

#[test]
fn defines_override_defaults_in_the_documentation_scenes() {
    let Some(data) = mitsuba_data() else { return };
    let path = data.join("docs/scenes/bsdf_diffuse_textured.xml");
    let defines = [("spp".to_owned(), "3".to_owned())];
    let doc = mitsuba::read_file(&path, &defines).expect("reads");
    let sampler = doc.plugins().find(|p| p.kind == PluginKind::Sampler).expect("sampler");
    assert_eq!(sampler.property("sample_count").map(|p| &p.value), Some(&Value::Integer(3)));
    // The serialized mesh resolves through the scene's <path value="../../common"/>.
    let mesh = doc.plugins().find(|p| p.type_name == "serialized").expect("the serialized mesh");
    let Some(Value::String(name)) = mesh.property("filename").map(|p| &p.value) else { panic!("{mesh:?}") };
    assert!(doc.resolve_file(name).is_some_and(|p| p.is_file()), "{name}");
}
