//! The reader on small scenes: each feature, and each error with its exact place.

use std::path::Path;

use glam::{DMat4, DVec3};

use super::*;
use crate::scene::SourceFile;

fn read(text: &str) -> Result<Document, MitsubaError> {
    read_source(SourceFile::from_text("s.xml", None, text.to_owned()), &[])
}

fn read_with(text: &str, defines: &[(&str, &str)]) -> Result<Document, MitsubaError> {
    let defines: Vec<_> = defines.iter().map(|(a, b)| (a.to_string(), b.to_string())).collect();
    read_source(SourceFile::from_text("s.xml", None, text.to_owned()), &defines)
}

/// The error's `file:line:column: message`, checked to start with `place`.
fn error_at(result: Result<Document, MitsubaError>, place: &str) -> MitsubaError {
    let err = result.expect_err("an error");
    let text = err.to_string();
    assert!(text.starts_with(&format!("{place}: ")), "expected {place}, got: {text}");
    err
}

fn scene(body: &str) -> String {
    format!("<scene version=\"3.0.0\">\n{body}\n</scene>\n")
}

fn value<'a>(p: &'a Plugin, name: &str) -> &'a Value {
    &p.property(name).unwrap_or_else(|| panic!("no property {name} in {p:?}")).value
}

fn first(doc: &Document, kind: PluginKind) -> &Plugin {
    doc.plugins().find(|p| p.kind == kind).unwrap_or_else(|| panic!("no {kind:?}"))
}

fn matrix(v: &Value) -> DMat4 {
    match v {
        Value::Transform(m) => *m,
        other => panic!("not a transform: {other:?}"),
    }
}

#[test]
fn properties_of_every_type_are_read() {
    let doc = read(&scene(
        r#"<shape type="sphere" id="ball">
    <integer name="i" value="-7"/>
    <float name="f" value="2.5e-1"/>
    <boolean name="b" value="TRUE"/>
    <string name="s" value="a b"/>
    <rgb name="c3" value="0.1, 0.2 0.3"/>
    <rgb name="c1" value="0.5"/>
    <spectrum name="u" value="0.4"/>
    <spectrum name="w" value="400:1, 700:2"/>
    <point name="p" value="1, 2, 3"/>
    <point name="q" x="1" y="2" z="3"/>
    <vector name="v" value="4"/>
</shape>"#,
    ))
    .expect("reads");
    let s = first(&doc, PluginKind::Shape);
    assert_eq!((s.type_name.as_str(), s.id.as_deref()), ("sphere", Some("ball")));
    assert_eq!(value(s, "i"), &Value::Integer(-7));
    assert_eq!(value(s, "f"), &Value::Float(0.25));
    assert_eq!(value(s, "b"), &Value::Boolean(true));
    assert_eq!(value(s, "s"), &Value::String("a b".into()));
    assert_eq!(value(s, "c3"), &Value::Rgb(DVec3::new(0.1, 0.2, 0.3)));
    assert_eq!(value(s, "c1"), &Value::Rgb(DVec3::splat(0.5)));
    assert_eq!(value(s, "u"), &Value::Spectrum(Spectrum::Uniform(0.4)));
    assert_eq!(
        value(s, "w"),
        &Value::Spectrum(Spectrum::Sampled { wavelengths: vec![400.0, 700.0], values: vec![1.0, 2.0] })
    );
    assert_eq!(value(s, "p"), &Value::Point(DVec3::new(1.0, 2.0, 3.0)));
    assert_eq!(value(s, "q"), &Value::Point(DVec3::new(1.0, 2.0, 3.0)));
    assert_eq!(value(s, "v"), &Value::Vector(DVec3::splat(4.0)));
    // Positions: the shape's `<` is on line 2, column 1; the float on line 4, column 5.
    assert_eq!((s.pos.span.line, s.pos.span.column), (2, 1));
    let f = s.property("f").expect("f");
    assert_eq!((f.pos.span.line, f.pos.span.column, f.pos.span.len), (4, 5, 6));
    assert_eq!(doc.place(f.pos), "s.xml:4:5");
}

#[test]
fn nested_plugins_keep_their_names_kinds_and_order() {
    let doc = read(&scene(
        r#"<sensor type="perspective">
    <film type="hdrfilm"><rfilter type="gaussian"/></film>
    <sampler type="independent" name="smp"/>
</sensor>
<shape type="obj"><bsdf type="twosided"><bsdf type="diffuse"><texture type="bitmap" name="reflectance"/></bsdf></bsdf>
<emitter type="area"/></shape>
<integrator type="path"/><medium type="homogeneous"><phase type="hg"/><volume type="grid" name="albedo"/></medium>
<spectrum type="d65" name="x"/>"#,
    ))
    .expect("reads");
    let kinds: Vec<_> = doc.plugins().map(|p| p.kind).collect();
    use PluginKind::*;
    assert_eq!(
        kinds,
        [
            Scene,
            Sensor,
            Film,
            ReconstructionFilter,
            Sampler,
            Shape,
            Bsdf,
            Bsdf,
            Texture,
            Emitter,
            Integrator,
            Medium,
            Phase,
            Volume,
            Texture
        ]
    );
    let sensor = first(&doc, Sensor);
    assert_eq!(sensor.children[1].name.as_deref(), Some("smp"));
    assert_eq!(sensor.children[0].name, None);
    assert_eq!(doc.root.type_name, "scene");
}

#[test]
fn transforms_compose_in_mitsubas_order() {
    let doc = read(&scene(
        r#"<shape type="cube"><transform name="to_world">
    <translate x="1"/>
    <scale value="2"/>
    <rotate z="1" angle="90"/>
</transform></shape>"#,
    ))
    .expect("reads");
    let m = matrix(value(first(&doc, PluginKind::Shape), "to_world"));
    // Each new element multiplies on the left: rotate * scale * translate.
    let p = m.transform_point3(DVec3::ZERO);
    assert!(p.abs_diff_eq(DVec3::new(0.0, 2.0, 0.0), 1e-12), "{p}");
    let expected = DMat4::from_axis_angle(DVec3::Z, 90f64.to_radians())
        * DMat4::from_scale(DVec3::splat(2.0))
        * DMat4::from_translation(DVec3::X);
    assert!(m.abs_diff_eq(expected, 1e-12));
}

#[test]
fn matrices_lookat_and_rotation_forms() {
    let doc = read(&scene(
        r#"<sensor type="perspective"><transform name="to_world">
    <lookat origin="0, 0, 5" target="0 0 0" up="0,1,0"/>
</transform></sensor>
<shape type="cube"><transform name="to_world">
    <matrix value="1 0 0 5  0 1 0 6  0 0 1 7  0 0 0 1"/>
    <matrix value="0 -1 0 1 0 0 0 0 1"/>
    <rotate value="0, 0, 2" angle="-90"/>
    <scale x="2"/>
</transform></shape>"#,
    ))
    .expect("reads");
    let cam = matrix(value(first(&doc, PluginKind::Sensor), "to_world"));
    assert!(cam.transform_point3(DVec3::ZERO).abs_diff_eq(DVec3::new(0.0, 0.0, 5.0), 1e-12));
    assert!(cam.transform_vector3(DVec3::Z).abs_diff_eq(-DVec3::Z, 1e-12));
    let m = matrix(value(first(&doc, PluginKind::Shape), "to_world"));
    // translate(5,6,7), then +90 and -90 about z (cancel), then x doubled.
    let p = m.transform_point3(DVec3::new(1.0, 0.0, 0.0));
    assert!(p.abs_diff_eq(DVec3::new(12.0, 6.0, 7.0), 1e-12), "{p}");
}

#[test]
fn singular_and_degenerate_transforms_are_errors_at_their_element() {
    let e = error_at(
        read(&scene(
            "<shape type=\"cube\"><transform name=\"to_world\">\n  <scale y=\"0\"/>\n</transform></shape>",
        )),
        "s.xml:3:3",
    );
    assert!(matches!(e, MitsubaError::SingularTransform { .. }), "{e}");
    error_at(
        read(&scene(
            "<sensor type=\"perspective\"><transform name=\"to_world\">\n<lookat origin=\"1 1 1\" target=\"1,1,1\"/></transform></sensor>",
        )),
        "s.xml:3:1",
    );
    error_at(
        read(&scene("<shape type=\"cube\"><transform name=\"t\"><rotate angle=\"5\"/></transform></shape>")),
        "s.xml:2:40",
    );
    error_at(
        read(&scene(
            "<shape type=\"cube\"><transform name=\"t\"><matrix value=\"1 2 3\"/></transform></shape>",
        )),
        "s.xml:2:55",
    );
    // An operation outside a transform, and something else inside one.
    error_at(read(&scene("<shape type=\"cube\"><scale value=\"2\"/></shape>")), "s.xml:2:20");
    error_at(
        read(&scene(
            "<shape type=\"cube\"><transform name=\"t\"><float name=\"a\" value=\"1\"/></transform></shape>",
        )),
        "s.xml:2:40",
    );
}

#[test]
fn defaults_parameters_and_defines() {
    let text = scene(
        r#"<default name="spp" value="16"/>
<default name="res" value="$spp"/>
<sampler type="independent"><integer name="sample_count" value="$spp"/></sampler>
<film type="hdrfilm"><integer name="width" value="$res"/><string name="note" value="\$5"/></film>"#,
    );
    let doc = read(&text).expect("reads");
    assert_eq!(value(first(&doc, PluginKind::Sampler), "sample_count"), &Value::Integer(16));
    let film = first(&doc, PluginKind::Film);
    assert_eq!(value(film, "width"), &Value::Integer(16));
    assert_eq!(value(film, "note"), &Value::String("$5".into()));
    // The caller's definitions win over the file's defaults; unused ones draw a warning.
    let doc = read_with(&text, &[("spp", "4"), ("unused", "1")]).expect("reads");
    assert_eq!(value(first(&doc, PluginKind::Sampler), "sample_count"), &Value::Integer(4));
    assert_eq!(value(first(&doc, PluginKind::Film), "width"), &Value::Integer(4));
    assert_eq!(doc.warnings.len(), 1);
    assert!(doc.warnings[0].message.contains("-D unused=1"), "{:?}", doc.warnings);
    // Without a value: an error at the attribute.
    let e = error_at(
        read(&scene(
            "<integrator type=\"path\">\n  <integer name=\"max_depth\" value=\"$depth\"/></integrator>",
        )),
        "s.xml:3:36",
    );
    assert!(e.to_string().contains("`$depth`"), "{e}");
    // A default must come before its use.
    error_at(
        read(&scene(
            "<film type=\"x\"><integer name=\"w\" value=\"$w\"/></film><default name=\"w\" value=\"1\"/>",
        )),
        "s.xml:2:41",
    );
}

#[test]
fn old_files_are_upgraded_as_mitsuba_upgrades_them() {
    let doc = read(
        r#"<scene version="0.6.0">
    <default name="maxDepth" value="3"/>
    <integrator type="path"><integer name="maxDepth" value="$maxDepth"/></integrator>
    <sensor type="perspective">
        <string name="fovAxis" value="x"/>
        <transform name="toWorld"><lookAt origin="0 0 1" target="0 0 0" up="0 1 0"/></transform>
    </sensor>
    <bsdf type="diffuse" id="d"><rgb name="diffuseReflectance" value="0.5"/></bsdf>
    <bsdf type="roughplastic"><float name="intIOR" value="1.5"/></bsdf>
    <texture type="bitmap"><float name="uscale" value="2"/><float name="uoffset" value="0.5"/></texture>
</scene>"#,
    )
    .expect("reads");
    assert_eq!(doc.version, Version { major: 0, minor: 6, patch: 0 });
    assert_eq!(value(first(&doc, PluginKind::Integrator), "max_depth"), &Value::Integer(3));
    let sensor = first(&doc, PluginKind::Sensor);
    assert_eq!(value(sensor, "fov_axis"), &Value::String("x".into()));
    assert!(matches!(value(sensor, "to_world"), Value::Transform(_)));
    assert_eq!(value(doc.get("d").expect("d"), "reflectance"), &Value::Rgb(DVec3::splat(0.5)));
    let plastic = doc.plugins().find(|p| p.type_name == "roughplastic").expect("plastic");
    assert_eq!(value(plastic, "int_ior"), &Value::Float(1.5));
    let tex = first(&doc, PluginKind::Texture);
    assert!(tex.property("uscale").is_none() && tex.property("uoffset").is_none());
    let uv = matrix(value(tex, "to_uv"));
    // scale(2, 1, 1) * translate(0.5, 0, 0)
    assert!(uv.transform_point3(DVec3::ZERO).abs_diff_eq(DVec3::new(1.0, 0.0, 0.0), 1e-12));
    // A 3.0.0 file keeps its names, and <lookAt> is no element of it.
    let doc =
        read(&scene("<sensor type=\"p\"><string name=\"fovAxis\" value=\"x\"/></sensor>")).expect("reads");
    assert!(first(&doc, PluginKind::Sensor).property("fovAxis").is_some());
    error_at(
        read(&scene(
            "<sensor type=\"p\"><transform name=\"t\"><lookAt origin=\"0 0 1\" target=\"0 0 0\"/></transform></sensor>",
        )),
        "s.xml:2:38",
    );
}

#[test]
fn versions_are_required_and_checked() {
    error_at(read("<scene>\n</scene>"), "s.xml:1:1");
    let e = error_at(read("<scene version=\"three\"/>"), "s.xml:1:17");
    assert!(matches!(e, MitsubaError::Version { .. }), "{e}");
    assert!(read("<scene version=\"2.1.0\"/>").is_ok());
    // The root must be a plugin.
    error_at(read("<float version=\"3.0.0\" name=\"a\" value=\"1\"/>"), "s.xml:1:1");
    // Any plugin may be the root (Mitsuba loads single plugins so).
    let doc = read("<bsdf version=\"3.0.0\" type=\"diffuse\"/>").expect("a bsdf file");
    assert_eq!(doc.root.kind, PluginKind::Bsdf);
}

#[test]
fn references_aliases_and_their_errors() {
    let doc = read(&scene(
        r#"<shape type="obj"><ref id="later" name="bsdf"/></shape>
<bsdf type="diffuse" id="later"/>
<alias id="later" as="other"/>
<shape type="obj"><ref id="other"/></shape>"#,
    ))
    .expect("reads");
    let shape = first(&doc, PluginKind::Shape);
    assert_eq!(shape.children[0].name.as_deref(), Some("bsdf"));
    assert_eq!(shape.child("bsdf").map(|c| c.pos.span.line), Some(2));
    let resolved: Vec<_> =
        doc.children(shape).map(|(c, p)| (c.name.as_deref(), p.type_name.as_str())).collect();
    assert_eq!(resolved, [(Some("bsdf"), "diffuse")]);
    assert_eq!(doc.target(&shape.children[0]).map(|p| p.type_name.as_str()), Some("diffuse"));
    assert_eq!(doc.get("other").map(|p| p.id.as_deref()), Some(Some("later")));
    let e = error_at(read(&scene("<shape type=\"obj\">\n    <ref id=\"nowhere\"/></shape>")), "s.xml:3:5");
    assert!(matches!(e, MitsubaError::UnknownId { ref id, .. } if id == "nowhere"), "{e}");
    let e = error_at(read(&scene("<bsdf type=\"a\" id=\"x\"/>\n<bsdf type=\"b\" id=\"x\"/>")), "s.xml:3:1");
    assert!(e.to_string().contains("first declared at s.xml:2:1"), "{e}");
    error_at(read(&scene("<alias id=\"none\" as=\"b\"/>")), "s.xml:2:12");
    // Plugins that need each other.
    let e = error_at(
        read(&scene(
            "<texture type=\"a\" id=\"a\"><ref id=\"b\"/></texture>\n<texture type=\"b\" id=\"b\"><ref id=\"a\"/></texture>",
        )),
        "s.xml:3:26",
    );
    assert!(e.to_string().ends_with("circular reference: a -> b -> a"), "{e}");
    error_at(
        read(&scene("<bsdf type=\"a\" id=\"self\"><bsdf type=\"b\"><ref id=\"self\"/></bsdf></bsdf>")),
        "s.xml:2:41",
    );
}

#[test]
fn duplicate_properties_are_errors() {
    let e = error_at(
        read(&scene(
            "<bsdf type=\"diffuse\">\n  <float name=\"a\" value=\"1\"/>\n  <rgb name=\"a\" value=\"1\"/></bsdf>",
        )),
        "s.xml:4:3",
    );
    assert!(e.to_string().contains("duplicate property `a` (first given at s.xml:3:3)"), "{e}");
    // A nested plugin fills a parameter too.
    error_at(
        read(&scene(
            "<bsdf type=\"x\"><float name=\"r\" value=\"1\"/><texture type=\"t\" name=\"r\"/></bsdf>",
        )),
        "s.xml:2:43",
    );
}

#[test]
fn structure_errors_name_their_place() {
    // Malformed XML: where the XML parser stopped.
    let e = error_at(read("<scene version=\"3.0.0\">\n  <bsdf type=\"a\">\n</scene>"), "s.xml:3:1");
    assert!(matches!(e, MitsubaError::Xml { .. }), "{e}");
    // Unknown element, unknown property type.
    let e = error_at(read(&scene("  <bdsf type=\"x\"/>")), "s.xml:2:3");
    assert!(e.to_string().ends_with("unknown element <bdsf>"), "{e}");
    error_at(read(&scene("<bsdf type=\"x\"><color name=\"c\" value=\"1\"/></bsdf>")), "s.xml:2:16");
    // Attributes.
    let e = error_at(read(&scene("<bsdf type=\"x\"><float name=\"c\" valeu=\"1\"/></bsdf>")), "s.xml:2:32");
    assert!(matches!(e, MitsubaError::UnexpectedAttribute { .. }), "{e}");
    let e = error_at(read(&scene("<bsdf type=\"x\"><float name=\"c\"/></bsdf>")), "s.xml:2:16");
    assert!(e.to_string().ends_with("<float> needs the attribute `value`"), "{e}");
    error_at(read(&scene("<bsdf id=\"x\"/>")), "s.xml:2:1");
    // Numbers, strictly.
    let e =
        error_at(read(&scene("<bsdf type=\"x\"><float name=\"c\" value=\"1.5x\"/></bsdf>")), "s.xml:2:39");
    assert!(e.to_string().ends_with("`1.5x` is not a finite number"), "{e}");
    error_at(read(&scene("<bsdf type=\"x\"><integer name=\"c\" value=\"2.0\"/></bsdf>")), "s.xml:2:41");
    error_at(read(&scene("<bsdf type=\"x\"><boolean name=\"c\" value=\"yes\"/></bsdf>")), "s.xml:2:41");
    error_at(read(&scene("<bsdf type=\"x\"><rgb name=\"c\" value=\"1 2\"/></bsdf>")), "s.xml:2:37");
    error_at(read(&scene("<bsdf type=\"x\"><point name=\"c\" x=\"1\" value=\"1\"/></bsdf>")), "s.xml:2:35");
    error_at(
        read(&scene("<bsdf type=\"x\"><spectrum name=\"c\" value=\"500:1, 400:2\"/></bsdf>")),
        "s.xml:2:42",
    );
    error_at(read(&scene("<bsdf type=\"x\"><spectrum name=\"c\"/></bsdf>")), "s.xml:2:16");
    // A property holds no elements; <path> only at the root.
    error_at(
        read(&scene("<bsdf type=\"x\"><float name=\"c\" value=\"1\"><bsdf type=\"y\"/></float></bsdf>")),
        "s.xml:2:42",
    );
    error_at(read(&scene("<bsdf type=\"x\"><path value=\".\"/></bsdf>")), "s.xml:2:16");
}

#[test]
fn errors_print_as_file_line_column_and_as_diagnostics() {
    let e = read(&scene("<bsdf type=\"x\"><float name=\"c\" value=\"oops\"/></bsdf>")).expect_err("error");
    assert_eq!(e.to_string(), "s.xml:2:39: `oops` is not a finite number");
    let d = e.diagnostic().to_string();
    assert!(d.starts_with("error: `oops` is not a finite number\n --> s.xml:2:39\n"), "{d}");
    assert!(d.contains("^^^^"), "{d}");
}

#[test]
fn nesting_is_bounded() {
    let depth = MAX_NESTING + 5;
    let text = scene(&format!("{}{}", "<bsdf type=\"a\">".repeat(depth), "</bsdf>".repeat(depth)));
    let e = read(&text).expect_err("too deep");
    assert!(matches!(e, MitsubaError::Limit { .. }), "{e}");
}

#[test]
fn very_deep_xml_is_refused_without_overflowing_the_stack() {
    // Far deeper than the limit: the XML parser and the reader must not recurse on it.
    let depth = 200_000;
    let text = format!(
        "<scene version=\"3.0.0\">{}{}</scene>",
        "<bsdf type=\"a\">".repeat(depth),
        "</bsdf>".repeat(depth)
    );
    let e = read(&text).expect_err("too deep");
    assert!(matches!(e, MitsubaError::Limit { .. }), "{e}");
}

#[test]
fn large_scenes_read_in_linear_time() {
    // 100,000 properties of one plugin, all on one line, and as many plugins with ids: each
    // position and each duplicate check costs the same whatever came before.
    let n = 100_000;
    let mut text = String::from("<scene version=\"3.0.0\"><bsdf type=\"x\">");
    for i in 0..n {
        text.push_str(&format!("<float name=\"p{i}\" value=\"{i}\"/>"));
    }
    text.push_str("</bsdf>");
    for i in 0..n {
        text.push_str(&format!(
            "<texture type=\"t\" id=\"t{i}\"><ref id=\"t{}\"/></texture>",
            (i + 1) % n + n * usize::from(i + 1 == n)
        ));
    }
    text.push_str(&format!("<texture type=\"t\" id=\"t{}\"/></scene>", n));
    let started = std::time::Instant::now();
    let doc = read(&text).expect("reads");
    assert_eq!(first(&doc, PluginKind::Bsdf).properties.len(), n);
    let last = first(&doc, PluginKind::Bsdf).properties.last().expect("last");
    // `<float name="pI" value="I"/>` takes 26 characters and twice the digits of I.
    let before: usize = (0..n - 1).map(|i| 26 + 2 * i.to_string().len()).sum();
    assert_eq!((last.pos.span.line, last.pos.span.column as usize), (1, 39 + before));
    assert_eq!(doc.get(&format!("t{}", n / 2)).map(|p| p.pos.span.line), Some(1));
    assert!(started.elapsed() < std::time::Duration::from_secs(20), "{:?}", started.elapsed());
}

/// Writes `files` (name, text) into a new temporary folder.
fn folder(files: &[(&str, &str)]) -> tempfile::TempDir {
    let dir = tempfile::tempdir().expect("temp dir");
    for (name, text) in files {
        let path = dir.path().join(name);
        std::fs::create_dir_all(path.parent().expect("parent")).expect("mkdir");
        std::fs::write(path, text).expect("write");
    }
    dir
}

fn name_of(doc: &Document, pos: Pos) -> String {
    let file = doc.files[pos.file as usize].name();
    Path::new(file).file_name().and_then(|n| n.to_str()).unwrap_or_default().to_owned()
}

#[test]
fn includes_splice_scenes_and_name_other_plugins() {
    let dir = folder(&[
        (
            "main.xml",
            &scene(
                "<include filename=\"parts/shapes.xml\"/>\n<include filename=\"parts/mat.xml\" name=\"bsdf\"/>",
            ),
        ),
        (
            "parts/shapes.xml",
            "<scene version=\"3.0.0\">\n  <include filename=\"deeper.xml\"/>\n  <shape type=\"sphere\"><ref id=\"m\"/></shape>\n</scene>",
        ),
        ("parts/deeper.xml", "<scene version=\"2.1.0\"><shape type=\"cube\" id=\"c\"/></scene>"),
        ("parts/mat.xml", "<bsdf version=\"3.0.0\" type=\"diffuse\" id=\"m\"/>"),
    ]);
    let doc = read_file(&dir.path().join("main.xml"), &[]).expect("reads");
    let kids: Vec<_> = doc.root.children.iter().map(|c| doc.target(c).map(|p| p.type_name.clone())).collect();
    assert_eq!(kids, [Some("cube".into()), Some("sphere".into()), Some("diffuse".into())]);
    assert_eq!(doc.root.children[2].name.as_deref(), Some("bsdf"));
    assert_eq!(doc.files.len(), 4);
    // Each plugin knows its file.
    let cube = doc.get("c").expect("cube");
    assert_eq!(
        (name_of(&doc, cube.pos), cube.pos.span.line, cube.pos.span.column),
        ("deeper.xml".into(), 1, 24)
    );
}

#[test]
fn include_errors_name_the_include() {
    let dir = folder(&[
        ("a.xml", &scene("  <include filename=\"b.xml\"/>")),
        ("b.xml", &scene("<include filename=\"a.xml\"/>")),
        ("missing.xml", &scene("<include filename=\"nothere.xml\"/>")),
        ("bad.xml", &scene("<include filename=\"broken.xml\"/>")),
        ("broken.xml", "<scene version=\"3.0.0\">\n<bsdf>\n</scene>"),
    ]);
    let a = dir.path().join("a.xml").display().to_string();
    let b = dir.path().join("b.xml").display().to_string();
    let e = error_at(read_file(&dir.path().join("a.xml"), &[]), &format!("{b}:2:1"));
    assert!(e.to_string().ends_with(&format!("recursive include: {a} -> {b} -> {a}")), "{e}");
    let m = dir.path().join("missing.xml").display().to_string();
    let e = error_at(read_file(&dir.path().join("missing.xml"), &[]), &format!("{m}:2:20"));
    assert!(matches!(e, MitsubaError::IncludeNotFound { .. }), "{e}");
    let broken = dir.path().join("broken.xml").display().to_string();
    let e = error_at(read_file(&dir.path().join("bad.xml"), &[]), &format!("{broken}:3:1"));
    assert!(matches!(e, MitsubaError::Xml { .. }), "{e}");
    let e = read_file(&dir.path().join("none.xml"), &[]).expect_err("missing file");
    assert!(matches!(e, MitsubaError::Read { .. }) && e.location().is_none(), "{e}");
}

#[test]
fn include_chains_are_bounded() {
    // MAX_INCLUDE_DEPTH includes nested read; one more is refused.
    let chain = |levels: usize| -> Vec<(String, String)> {
        let mut files: Vec<(String, String)> = (0..levels)
            .map(|i| (format!("f{i}.xml"), scene(&format!("<include filename=\"f{}.xml\"/>", i + 1))))
            .collect();
        files.push((format!("f{levels}.xml"), scene("<shape type=\"sphere\"/>")));
        files
    };
    let files = chain(MAX_INCLUDE_DEPTH);
    let refs: Vec<(&str, &str)> = files.iter().map(|(a, b)| (a.as_str(), b.as_str())).collect();
    let dir = folder(&refs);
    let doc = read_file(&dir.path().join("f0.xml"), &[]).expect("15 includes deep");
    assert_eq!(doc.files.len(), MAX_INCLUDE_DEPTH + 1);
    let files = chain(MAX_INCLUDE_DEPTH + 1);
    let refs: Vec<(&str, &str)> = files.iter().map(|(a, b)| (a.as_str(), b.as_str())).collect();
    let dir = folder(&refs);
    let e = read_file(&dir.path().join("f0.xml"), &[]).expect_err("too deep");
    assert!(matches!(e, MitsubaError::Limit { .. }), "{e}");
}

#[test]
fn include_chains_far_too_deep_are_refused() {
    let mut files: Vec<(String, String)> = (0..MAX_INCLUDE_DEPTH + 2)
        .map(|i| (format!("f{i}.xml"), scene(&format!("<include filename=\"f{}.xml\"/>", i + 1))))
        .collect();
    files.push((format!("f{}.xml", MAX_INCLUDE_DEPTH + 2), scene("")));
    let refs: Vec<(&str, &str)> = files.iter().map(|(a, b)| (a.as_str(), b.as_str())).collect();
    let dir = folder(&refs);
    let e = read_file(&dir.path().join("f0.xml"), &[]).expect_err("too deep");
    assert!(matches!(e, MitsubaError::Limit { .. }), "{e}");
}

#[test]
fn search_folders_resolve_includes_spectra_and_plugin_files() {
    let dir = folder(&[
        (
            "scenes/main.xml",
            &scene(
                "<path value=\"../common\"/>\n<include filename=\"part.xml\"/>\n<bsdf type=\"conductor\"><spectrum name=\"eta\" filename=\"ior/x.spd\"/></bsdf>",
            ),
        ),
        (
            "common/part.xml",
            &scene("<shape type=\"obj\"><string name=\"filename\" value=\"mesh.obj\"/></shape>"),
        ),
        ("common/mesh.obj", "v 0 0 0\n"),
        ("common/ior/x.spd", "# eta\n400 1.5\n700 1.6\n"),
        ("scenes/nopath.xml", &scene("<path value=\"../nowhere\"/>")),
        (
            "scenes/nospd.xml",
            &scene("<bsdf type=\"c\"><spectrum name=\"eta\" filename=\"none.spd\"/></bsdf>"),
        ),
    ]);
    let doc = read_file(&dir.path().join("scenes/main.xml"), &[]).expect("reads");
    let bsdf = first(&doc, PluginKind::Bsdf);
    assert!(
        matches!(value(bsdf, "eta"), Value::Spectrum(Spectrum::Sampled { values, .. }) if values == &[1.5, 1.6])
    );
    let resolved = doc.resolve_file("mesh.obj").expect("found through <path>");
    assert!(resolved.ends_with("common/mesh.obj"), "{}", resolved.display());
    let p = dir.path().join("scenes/nopath.xml").display().to_string();
    error_at(read_file(&dir.path().join("scenes/nopath.xml"), &[]), &format!("{p}:2:14"));
    let p = dir.path().join("scenes/nospd.xml").display().to_string();
    error_at(read_file(&dir.path().join("scenes/nospd.xml"), &[]), &format!("{p}:2:47"));
}

#[test]
fn text_without_a_folder_resolves_nothing_relative() {
    // The tests run in crates/raytracer, which has a Cargo.toml: not found all the same.
    assert!(Path::new("Cargo.toml").exists());
    let e = error_at(read(&scene("<include filename=\"Cargo.toml\"/>")), "s.xml:2:20");
    assert!(matches!(e, MitsubaError::IncludeNotFound { .. }), "{e}");
    error_at(read(&scene("<path value=\"src\"/>")), "s.xml:2:14");
    let e = error_at(
        read(&scene("<bsdf type=\"c\"><spectrum name=\"eta\" filename=\"Cargo.toml\"/></bsdf>")),
        "s.xml:2:47",
    );
    assert!(e.to_string().ends_with("file not found"), "{e}");
    let doc = read(&scene("")).expect("reads");
    assert!(doc.resolver.is_empty() && doc.resolve_file("Cargo.toml").is_none());
}

#[test]
fn positions_count_characters_and_tabs_as_one_column() {
    let e = read("<scene version=\"3.0.0\">\n\t<!-- é -->\t<bsdf type=\"x\"><float name=\"é\" value=\"?\"/></bsdf>\n</scene>")
        .expect_err("bad number");
    assert!(e.to_string().starts_with("s.xml:2:51: "), "{e}");
}

mod no_panics {
    use super::*;
    use proptest::prelude::*;

    const PIECES: [&str; 24] = [
        "<scene version=\"3.0.0\">",
        "</scene>",
        "<bsdf type=\"diffuse\" id=\"a\">",
        "</bsdf>",
        "<ref id=\"a\"/>",
        "<ref id=\"b\"/>",
        "<float name=\"x\" value=\"1\"/>",
        "<rgb name=\"c\" value=\"1 2\"/>",
        "<transform name=\"t\">",
        "</transform>",
        "<scale value=\"0\"/>",
        "<rotate x=\"1\" angle=\"$a\"/>",
        "<default name=\"a\" value=\"$a\"/>",
        "<include filename=\"x.xml\"/>",
        "<spectrum name=\"s\" value=\"400:1, 500:$a\"/>",
        "<lookat origin=\"0 0 0\" target=\"0 0 1\"/>",
        "<matrix value=\"1 0 0 0 1 0 0 0 1\"/>",
        "<alias id=\"a\" as=\"b\"/>",
        "<path value=\".\"/>",
        "<texture type=\"t\" id=\"b\"><ref id=\"a\"/></texture>",
        "<",
        "\"",
        "&amp;",
        "\u{202e}é",
    ];

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(512))]

        /// Any sequence of pieces of scene text reads or fails with an error that prints;
        /// nothing panics.
        #[test]
        fn pieces_of_scenes_never_panic(picks in proptest::collection::vec(0..PIECES.len(), 0..40)) {
            let text: String = picks.iter().map(|&i| PIECES[i]).collect();
            match read_with(&text, &[("a", "2")]) {
                Ok(doc) => { let _ = doc.plugins().count(); }
                Err(e) => { let _ = e.diagnostic().to_string(); }
            }
        }

        /// Any bytes at all.
        #[test]
        fn any_bytes_never_panic(bytes in proptest::collection::vec(any::<u8>(), 0..300)) {
            let source = SourceFile::from_bytes("s.xml", None, bytes);
            if let Err(e) = read_source(source, &[]) {
                let _ = e.diagnostic().to_string();
            }
        }
    }
}
