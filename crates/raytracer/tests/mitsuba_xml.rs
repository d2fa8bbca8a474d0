//! Every Mitsuba 3 scene file of the published test data (`../shared/mitsuba-data`: the Cornell
//! box, the material preview, the documentation's scenes) reads into a plugin tree, with
//! plausible plugin counts. When the data is absent the tests are skipped with a loud message,
//! except under CI, where they fail.

mod support;

use std::collections::{BTreeMap, HashMap};
use std::path::{Path, PathBuf};
use std::process::Command;

use raytracer::scene::mitsuba::{self, Document, MitsubaError, Node, PluginKind, Value};

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

/// Every `.xml` file of the data's scenes.
fn all_scene_files(data: &Path) -> Vec<PathBuf> {
    let mut files = Vec::new();
    for dir in ["scenes/cbox", "scenes/matpreview", "docs/scenes"] {
        xml_files(&data.join(dir), &mut files);
    }
    files
}

#[test]
fn every_scene_of_the_mitsuba_data_reads() {
    let Some(data) = mitsuba_data() else { return };
    let files = all_scene_files(&data);
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

/// What Mitsuba's parser read from one file (see `tools/mitsuba/parse_scenes.py`).
#[derive(Default)]
struct Parsed {
    error: Option<String>,
    counts: BTreeMap<String, usize>,
    matrices: Vec<(String, Vec<f64>)>,
}

/// Mitsuba's name of a plugin kind.
fn mitsuba_type(kind: PluginKind) -> &'static str {
    match kind {
        PluginKind::Scene => "Scene",
        PluginKind::Bsdf => "BSDF",
        PluginKind::Texture => "Texture",
        PluginKind::Emitter => "Emitter",
        PluginKind::Shape => "Shape",
        PluginKind::Sensor => "Sensor",
        PluginKind::Film => "Film",
        PluginKind::ReconstructionFilter => "ReconstructionFilter",
        PluginKind::Sampler => "Sampler",
        PluginKind::Integrator => "Integrator",
        PluginKind::Medium => "Medium",
        PluginKind::Phase => "PhaseFunction",
        PluginKind::Volume => "Volume",
    }
}

/// Every scene file of the data, read by our reader and by Mitsuba 3's own parser
/// (`mitsuba.parser.parse_file`): the same number of plugins of each kind, and the same
/// `to_world` and `to_uv` matrices in the same order (Mitsuba's nodes are in file order with
/// includes in place, as our preorder). Mitsuba's parser does not resolve references, so a
/// fragment that names ids of its including scene reads there and fails here.
#[test]
fn the_reader_agrees_with_mitsubas_own_parser() {
    let Some(data) = mitsuba_data() else { return };
    let Some(python) = support::pbr::mitsuba_python() else { return };
    let mut docs = Vec::new();
    let mut args = Vec::new();
    for path in all_scene_files(&data) {
        let mut defines = Vec::new();
        let mut doc = mitsuba::read_file(&path, &defines);
        if matches!(&doc, Err(MitsubaError::UndefinedParameter { .. })) {
            defines.push(("spp".to_owned(), "4".to_owned()));
            doc = mitsuba::read_file(&path, &defines);
        }
        let define_arg: Vec<String> = defines.iter().map(|(k, v)| format!("{k}={v}")).collect();
        args.push(format!("{}::{}", path.display(), define_arg.join(",")));
        docs.push((path, doc));
    }
    let script = support::workspace().join("tools/mitsuba/parse_scenes.py");
    let output = Command::new(&python).arg(&script).args(&args).output().expect("runs Mitsuba's parser");
    assert!(output.status.success(), "{}", String::from_utf8_lossy(&output.stderr));
    let mut theirs: HashMap<String, Parsed> = HashMap::new();
    let mut current = String::new();
    for line in String::from_utf8_lossy(&output.stdout).lines() {
        let fields: Vec<&str> = line.split('\t').collect();
        match fields[..] {
            ["FILE", path] => {
                current = path.to_owned();
                theirs.insert(current.clone(), Parsed::default());
            }
            ["ERROR", message] => theirs.get_mut(&current).expect("a file").error = Some(message.to_owned()),
            ["COUNT", kind, n] => {
                theirs
                    .get_mut(&current)
                    .expect("a file")
                    .counts
                    .insert(kind.to_owned(), n.parse().expect("count"));
            }
            ["MATRIX", name, values] => {
                let values = values.split(' ').map(|v| v.parse().expect("number")).collect();
                theirs.get_mut(&current).expect("a file").matrices.push((name.to_owned(), values));
            }
            _ => panic!("unexpected line from the parser script: {line}"),
        }
    }
    let (mut compared, mut matrices) = (0, 0);
    for (path, doc) in &docs {
        let key = path.display().to_string();
        let parsed = theirs.get(&key).unwrap_or_else(|| panic!("no result for {key}"));
        let doc = match (doc, &parsed.error) {
            (Ok(doc), None) => doc,
            (Err(MitsubaError::UnknownId { .. }), None) if is_fragment(path) => continue,
            (Err(_), Some(_)) => continue,
            (ours, theirs) => panic!("{key}: we read {:?}, Mitsuba {theirs:?}", ours.as_ref().err()),
        };
        let mut counts = BTreeMap::new();
        for p in doc.plugins() {
            *counts.entry(mitsuba_type(p.kind).to_owned()).or_insert(0) += 1;
        }
        assert_eq!(counts, parsed.counts, "{key}: plugins of each kind");
        let ours: Vec<(String, Vec<f64>)> = doc
            .plugins()
            .flat_map(|p| p.properties.iter())
            .filter(|p| p.name == "to_world" || p.name == "to_uv")
            .filter_map(|p| match &p.value {
                Value::Transform(m) => Some((p.name.clone(), m.transpose().to_cols_array().to_vec())),
                _ => None,
            })
            .collect();
        assert_eq!(ours.len(), parsed.matrices.len(), "{key}: transforms");
        for ((name, a), (their_name, b)) in ours.iter().zip(&parsed.matrices) {
            assert_eq!(name, their_name, "{key}");
            // Mitsuba rounds some steps (its rotations) through single precision.
            let close = a.iter().zip(b).all(|(x, y)| (x - y).abs() <= 1e-7 * y.abs().max(1.0));
            assert!(close, "{key}: {name}\nours:    {a:?}\nMitsuba: {b:?}");
            matrices += 1;
        }
        compared += 1;
    }
    eprintln!("{compared} scene files and {matrices} transforms agree with Mitsuba's parser");
    assert!(compared >= 100 && matrices >= 500, "{compared} files, {matrices} transforms compared");
}

/// Every spectrum file of the data (`ior/*.spd`), reduced to RGB by our reader and by Mitsuba
/// 3.9.1's `scalar_rgb` variant (`tools/mitsuba/spectra.py`) as a reflectance, as a conductor's
/// `eta` and as emitted radiance: the same colours to single precision.
#[test]
fn spectrum_files_reduce_to_the_colours_mitsuba_gives_them() {
    use raytracer::scene::mitsuba::{Spectrum, SpectrumUse};
    let Some(data) = mitsuba_data() else { return };
    let Some(python) = support::pbr::mitsuba_python() else { return };
    let mut files: Vec<PathBuf> = std::fs::read_dir(data.join("ior"))
        .expect("list")
        .map(|e| e.expect("entry").path())
        .filter(|p| p.extension().is_some_and(|e| e == "spd"))
        .collect();
    files.sort();
    assert!(files.len() >= 100, "{} spectrum files", files.len());
    let script = support::workspace().join("tools/mitsuba/spectra.py");
    let output = Command::new(&python).arg(&script).args(&files).output().expect("runs Mitsuba");
    assert!(output.status.success(), "{}", String::from_utf8_lossy(&output.stderr));
    let mut compared = 0;
    for line in String::from_utf8_lossy(&output.stdout).lines() {
        let fields: Vec<&str> = line.split('\t').collect();
        let [usage, path, rgb] = fields[..] else { panic!("unexpected line: {line}") };
        let theirs: Vec<f64> = rgb.split(' ').map(|v| v.parse().expect("number")).collect();
        let usage = match usage {
            "bounded" => SpectrumUse::Bounded,
            "unbounded" => SpectrumUse::Unbounded,
            "emission" => SpectrumUse::Emission,
            other => panic!("unknown use {other}"),
        };
        let text = std::fs::read_to_string(path).expect("readable");
        let spectrum = Spectrum::parse_spd(&text).unwrap_or_else(|e| panic!("{path}: {e}"));
        let ours = spectrum.to_srgb(usage);
        let close = (0..3).all(|i| (ours[i] - theirs[i]).abs() <= 2e-5 * theirs[i].abs().max(1.0));
        assert!(close, "{path} as {usage:?}: ours {ours}, Mitsuba {theirs:?}");
        compared += 1;
    }
    assert_eq!(compared, 3 * files.len());
    eprintln!("{compared} spectrum reductions agree with Mitsuba's");
}
