//! Tests of the scene parser: every key of every block, and every diagnostic with its position.

use std::sync::Arc;

use glam::{DVec2, DVec3};

use super::pieces::pieces;
use super::*;
use crate::geometry::Shape;
use crate::light::Light;
use crate::material::Material;
use crate::scene::texture::{Builtin, TextureSource};
use crate::scene::{Algorithm, PhotonSettings, Severity};

fn source(text: &str) -> SourceFile {
    SourceFile::from_text("test.txt", None, text.to_owned())
}

fn ok(text: &str) -> Parsed {
    match parse(&source(text)) {
        Ok(p) => p,
        Err(e) => panic!("expected the scene to parse:\n{e}"),
    }
}

/// `(severity, line, column, message)` of every diagnostic.
fn diagnostics(text: &str) -> Vec<(Severity, u32, u32, String)> {
    let all = match parse(&source(text)) {
        Ok(p) => p.diagnostics,
        Err(e) => e.diagnostics,
    };
    all.into_iter()
        .map(|d| {
            let (line, column) = d.location.as_ref().map_or((0, 0), |l| (l.span.line, l.span.column));
            (d.severity, line, column, d.message)
        })
        .collect()
}

/// The single error of `text`, as `(line, column, message)`.
fn single_error(text: &str) -> (u32, u32, String) {
    let errors: Vec<_> = diagnostics(text).into_iter().filter(|d| d.0 == Severity::Error).collect();
    assert_eq!(errors.len(), 1, "expected exactly one error, got {errors:#?}");
    let (_, line, column, message) = errors.into_iter().next().expect("one error");
    (line, column, message)
}

const SPHERE: &str = "primitive sphere\n O= 0 0 0\n R= 1\nend\n";

#[test]
fn background_keys() {
    let p = ok("background\n color= 0.1 0.2 0.3\nend\n");
    assert_eq!(p.scene.background.color, DVec3::new(0.1, 0.2, 0.3));
    assert!(p.scene.background.gradient.is_none());
    let p = ok("background\n top= 0 0 1\n bottom= 1 0 0\nend\n");
    let g = p.scene.background.gradient.expect("gradient");
    assert_eq!((g.top, g.bottom), (DVec3::Z, DVec3::X));
    let p = ok("background\n top= 0 0 1\nend\n");
    assert_eq!(p.scene.background.gradient.expect("gradient").bottom, DVec3::ONE, "top alone");
    // The gradient: straight up is `top`, straight down `bottom`.
    let bg = p.scene.background;
    assert_eq!(bg.miss_color(DVec3::Z), DVec3::Z);
    assert_eq!(bg.miss_color(-DVec3::Z), DVec3::ONE);
    assert_eq!(bg.miss_color(DVec3::X), DVec3::new(0.5, 0.5, 1.0));
}

#[test]
fn camera_keys_and_defaults() {
    let defaults = ok(SPHERE).scene.camera;
    assert_eq!(defaults, CameraSettings::default());
    assert_eq!((defaults.image_width, defaults.image_height), (420, 420));
    assert_eq!((defaults.lens_width, defaults.lens_height), (0.88, 0.88));
    assert_eq!((defaults.shade_quality, defaults.drefl_quality), (4, 4));
    let text = "camera\n O= 1 2 3\n N= 0 2 0\n lens_W= 1.2\n lens_H= 0.6\n image_W= 640\n image_H= 320\n \
                shade_quality= 2\n drefl_quality= 3\n max_photons= 10\n emit_photons= 20\n \
                sample_photons= 30\n sample_dist= 0.5\n aperture= 0.05\n focal_dist= 4\nend\n";
    let cam = ok(text).scene.camera;
    assert_eq!(cam.eye, DVec3::new(1.0, 2.0, 3.0));
    assert_eq!(cam.dir, DVec3::Y, "N is normalised");
    assert_eq!((cam.lens_width, cam.lens_height), (1.2, 0.6));
    assert_eq!((cam.image_width, cam.image_height), (640, 320));
    assert_eq!((cam.shade_quality, cam.drefl_quality), (2, 3));
    let p = &cam.photons;
    assert_eq!((p.max_photons, p.emit_photons, p.sample_photons, p.sample_dist), (10, 20, 30, 0.5));
    let keys: Vec<(&str, u32)> = p.keys.iter().map(|(k, l)| (*k, l.span.line)).collect();
    assert_eq!(
        keys,
        [("max_photons", 10), ("emit_photons", 11), ("sample_photons", 12), ("sample_dist", 13)]
    );
    assert_eq!((cam.aperture, cam.focal_distance), (0.05, Some(4.0)));
    assert_eq!(cam.algorithm, None);
}

#[test]
fn photon_mapping_keys_of_the_students_renderers() {
    let defaults = PhotonSettings::default();
    assert_eq!((defaults.iterations, defaults.reduction, defaults.max_hitpoints), (64, 2.0 / 3.0, None));
    for (name, algorithm) in [
        ("RT", Algorithm::RayTracing),
        ("PM", Algorithm::PhotonMapping),
        ("ppm", Algorithm::ProgressivePhotonMapping),
        ("SPPM", Algorithm::StochasticProgressivePhotonMapping),
    ] {
        let text = format!(
            "camera\n algorithm= {name}\n iterations= 12\n reduction= 0.7\n max_hitpoints= 5000\nend\n{SPHERE}"
        );
        let cam = ok(&text).scene.camera;
        let (a, location) = cam.algorithm.expect("algorithm");
        assert_eq!((a, location.span.line, location.span.column), (algorithm, 2, 13));
        let p = &cam.photons;
        assert_eq!((p.iterations, p.reduction, p.max_hitpoints), (12, 0.7, Some(5000)));
    }
}

#[test]
fn bad_photon_keys_are_errors_at_their_place() {
    for (line, column, message) in [
        (" algorithm= MLT", 13, "unknown `algorithm=` `MLT`"),
        (" emit_photons= 0", 16, "`emit_photons=` must be a whole number from 1"),
        (" max_photons= -5", 15, "`max_photons=` must be a whole number from 1"),
        (" sample_photons= 2.5", 18, "`sample_photons=` must be a whole number from 1"),
        (" sample_dist= 0", 15, "`sample_dist=` (the gathering radius) must be positive"),
        (" iterations= 0", 14, "`iterations=` must be a whole number from 1"),
        (" reduction= 1.5", 13, "`reduction=` (the radius reduction alpha) must lie in (0, 1]"),
        (" max_hitpoints= 0", 17, "`max_hitpoints=` must be a whole number from 1"),
    ] {
        let (l, c, m) = single_error(&format!("camera\n{line}\nend\n{SPHERE}"));
        assert!(m.starts_with(message), "{line}: {m}");
        assert_eq!((l, c), (2, column), "{line}");
    }
}

#[test]
fn lights_of_every_type() {
    let text = "light point\n O= 1 2 3\n color= 2 2 2\nend\n\
                light square\n O= 0 0 5\n Dx= 1 0 0\n Dy= 0 2 0\n color= 1 1 1\nend\n\
                light area\n O= 0 0 5\n Dx= 1 0 0\n Dy= 0 2 0\n color= 1 1 1\nend\n\
                light sphere\n O= 0 0 4\n R= 0.5\n color= 3 3 3\nend\n";
    let lights = ok(text).scene.lights;
    assert_eq!(lights.len(), 4);
    assert_eq!(lights[0], Light::Point { position: DVec3::new(1.0, 2.0, 3.0), color: DVec3::splat(2.0) });
    assert!(matches!(&lights[1], Light::Square { shape, .. } if shape.dy == DVec3::new(0.0, 2.0, 0.0)));
    assert_eq!(lights[1], lights[2], "area is an alias of square");
    assert!(
        matches!(&lights[3], Light::Sphere { shape, color } if shape.radius == 0.5 && *color == DVec3::splat(3.0))
    );
}

#[test]
fn material_keys_and_defaults() {
    let p = ok(SPHERE);
    assert_eq!(
        *p.scene.primitives[0].material,
        crate::material::Material::Course(crate::material::CourseMaterial::default())
    );
    let text = "primitive sphere\n O= 0 0 0\n R= 1\n color= 0.5 0.6 0.7\n texture= marble.bmp\n diff= 0.1\n \
                spec= 0.2\n refl= 0.3\n drefl= 0.4\n blur= exp\n refr= 0.5\n rindex= 1.5\n absor= 1 2 3\nend\n";
    let m = ok(text).scene.primitives[0].material.as_course().cloned().expect("a course material");
    assert_eq!(m.color, DVec3::new(0.5, 0.6, 0.7));
    assert_eq!((m.diff, m.spec, m.refl, m.drefl, m.refr, m.rindex), (0.1, 0.2, 0.3, 0.4, 0.5, 1.5));
    assert_eq!(m.absor, DVec3::new(1.0, 2.0, 3.0));
    let t = m.texture.as_ref().expect("texture");
    assert_eq!(t.source, TextureSource::File("marble.bmp".into()));
    assert_eq!((t.location.span.line, t.location.span.column), (5, 11));
}

#[test]
fn texture_paths_keep_spaces_and_builtins_parse() {
    let text = "primitive sphere\n O= 0 0 0\n R= 1\n texture= my  textures/a b.png\nend\n";
    let m = ok(text).scene.primitives[0].material.as_course().cloned().expect("a course material");
    assert_eq!(
        m.texture.as_ref().expect("texture").source,
        TextureSource::File("my  textures/a b.png".into())
    );
    let text = "primitive sphere\n O= 0 0 0\n R= 1\n texture= builtin:checker:4\nend\n";
    let m = ok(text).scene.primitives[0].material.as_course().cloned().expect("a course material");
    assert_eq!(m.texture.as_ref().expect("texture").source, TextureSource::Builtin(Builtin::Checker(4)));
}

#[test]
fn shapes_of_every_type() {
    let text = "primitive sphere\n O= 1 2 3\n R= 0.5\n De= 0 0 2\n Dc= 0 3 0\nend\n\
                primitive plane\n N= 0 0 2\n R= -2\n Dx= 8 0 0\n Dy= 0 8 0\nend\n\
                primitive square\n O= 1 7 -1\n Dx= 1 0 0\n Dy= 0 0 1\nend\n\
                primitive cylinder\n O1= 2 5 -2\n O2= 2 5 -0.8\n R= 0.2\nend\n";
    let prims = ok(text).scene.primitives;
    match &prims[0].shape {
        Shape::Sphere(s) => {
            assert_eq!((s.centre, s.radius), (DVec3::new(1.0, 2.0, 3.0), 0.5));
            assert_eq!((s.pole(), s.seam()), (DVec3::Z, DVec3::Y), "frame normalised");
        }
        other => panic!("{other:?}"),
    }
    match &prims[1].shape {
        Shape::Plane(p) => {
            assert_eq!((p.normal, p.offset), (DVec3::Z, -2.0));
            assert_eq!(p.texture_coordinates(DVec3::new(4.0, 2.0, -2.0)), (0.5, 0.25));
        }
        other => panic!("{other:?}"),
    }
    assert!(matches!(&prims[2].shape, Shape::Square(s) if s.normal == -DVec3::Y));
    assert!(
        matches!(&prims[3].shape, Shape::Cylinder(c) if c.radius == 0.2 && (c.height - 1.2).abs() < 1e-12)
    );
}

#[test]
fn comments_crlf_indentation_and_number_forms() {
    let text = "# a comment with the words light and camera\r\n\
                // another; primitive sphere\r\n\
                primitive sphere # trailing comment\r\n\
                \tO=\t.5 -2 1e1 // comment after values\r\n\
                    R= +3.\r\n\
                end\r\n";
    let p = ok(text);
    assert!(p.diagnostics.is_empty(), "{:?}", p.diagnostics);
    assert!(matches!(&p.scene.primitives[0].shape, Shape::Sphere(s)
        if s.centre == DVec3::new(0.5, -2.0, 10.0) && s.radius == 3.0));
}

#[test]
fn value_glued_to_the_key_and_later_keys_win() {
    let text = "primitive sphere\n O=1 2 3\n R= 1\n R= 2\nend\n";
    let p = ok(text);
    assert!(
        matches!(&p.scene.primitives[0].shape, Shape::Sphere(s) if s.centre == DVec3::new(1.0, 2.0, 3.0) && s.radius == 2.0)
    );
    assert_eq!(
        diagnostics(text),
        vec![(Severity::Warning, 4, 2, "`R=` is given again; this value replaces the one on line 3".into())]
    );
}

#[test]
fn space_before_equals_is_accepted_with_a_warning() {
    let text = "primitive sphere\n O = 1 2 3\n R= 1\nend\n";
    let p = ok(text);
    assert!(
        matches!(&p.scene.primitives[0].shape, Shape::Sphere(s) if s.centre == DVec3::new(1.0, 2.0, 3.0))
    );
    assert_eq!(
        diagnostics(text),
        vec![(Severity::Warning, 2, 2, "write `O=` with no space before `=`".into())]
    );
}

#[test]
fn gbk_scene_with_chinese_comments_parses() {
    // "设置" (set up) in GBK after `#`.
    let bytes = b"background\t\t\t#\xC9\xE8\xD6\xC3\n\tcolor= 0.05 0.05 0.05\t//\xC9\xE8\xD6\xC3\nend\n";
    let p = parse(&SourceFile::from_bytes("gbk.txt", None, bytes)).expect("parses");
    assert_eq!(p.scene.background.color, DVec3::splat(0.05));
}

#[test]
fn unknown_keys_blocks_and_types_are_warnings() {
    let text = "primitive sphere\n O= 0 0 0\n R= 1\n shininess= 3\n o= 1 1 1\nend\n\
                fog\n density= 3\nend\n\
                light laser\n O= 0 0 0\nend\n\
                primitive torus\n O= 0 0 0\nend\n";
    assert_eq!(
        diagnostics(text),
        vec![
            (Severity::Warning, 4, 2, "unknown key `shininess=` in `primitive sphere`; ignored".into()),
            (Severity::Warning, 5, 2, "unknown key `o=` in `primitive sphere`; ignored".into()),
            (Severity::Warning, 7, 1, "unknown block `fog`; its lines up to `end` are skipped".into()),
            (Severity::Warning, 10, 7, "unknown light type `laser`; the block is skipped".into()),
            (
                Severity::Warning,
                13,
                11,
                "`primitive torus` is not part of the scene language (the renderers that read it ignored it too); the block is skipped".into()
            ),
        ]
    );
    // A wrong-case key gets a hint.
    let hint = match parse(&source(text)) {
        Ok(p) => p.diagnostics[1].notes.clone(),
        Err(e) => panic!("{e}"),
    };
    assert_eq!(hint, vec!["did you mean `O=`? keys are case-sensitive".to_owned()]);
}

#[test]
fn stray_lines_outside_blocks_are_warnings() {
    let text = "end\nR= 3\nprimitive sphere\n O= 0 0 0\n R= 1\nend junk\n";
    assert_eq!(
        diagnostics(text),
        vec![
            (Severity::Warning, 1, 1, "`end` without an open block; ignored".into()),
            (Severity::Warning, 2, 1, "`R=` is outside any block; the line is ignored".into()),
            (Severity::Warning, 6, 5, "unexpected text after `end`; ignored".into()),
        ]
    );
}

#[test]
fn cylinder_frame_keys_are_notes_and_bad_blur_a_warning() {
    let text =
        "primitive cylinder\n O1= 0 0 0\n O2= 0 0 1\n R= 1\n De= 0 0 1\n Dc= 0 1 0\n blur= gauss\nend\n";
    assert_eq!(
        diagnostics(text),
        vec![
            (Severity::Note, 5, 2, "`De=` has no effect on a cylinder".into()),
            (Severity::Note, 6, 2, "`Dc=` has no effect on a cylinder".into()),
            (
                Severity::Warning,
                7,
                8,
                "unknown `blur= gauss`; `exp` is the only distribution, and it is used".into()
            ),
        ]
    );
}

#[test]
fn suspicious_values_are_warnings() {
    let text = "light point\n O= 0 0 5\nend\nprimitive sphere\n O= 0 0 0\n R= 1\n diff= -1\n color= 2 0 0\n absor= -1 0 0\nend\n\
                camera\n lens_W= 1\n lens_H= 1\n image_W= 200\n image_H= 100\nend\n";
    assert_eq!(
        diagnostics(text),
        vec![
            (Severity::Warning, 1, 7, "this light has no `color=`, so it gives no light".into()),
            (Severity::Warning, 7, 8, "`diff=` is negative".into()),
            (Severity::Warning, 8, 9, "colour components of `color=` should lie in [0, 1]".into()),
            (Severity::Warning, 9, 9, "`absor=` is negative: light would grow inside the object".into()),
            (
                Severity::Warning,
                12,
                10,
                "the lens aspect lens_W/lens_H = 1.0000 differs from the image aspect 200/100 = 2.0000: the picture will be stretched".into()
            ),
        ]
    );
}

#[test]
fn second_camera_and_empty_scene_are_warnings() {
    let d = diagnostics("camera\nend\ncamera\nend\n");
    assert_eq!(d[0], (Severity::Warning, 3, 1, "a second `camera` block replaces the one on line 1".into()));
    assert_eq!(d[1], (Severity::Warning, 0, 0, "`test.txt` describes no lights and no primitives".into()));
    // Not when the blocks failed: the errors say why.
    assert_eq!(diagnostics("primitive sphere\n R= 1\nend\n").len(), 1);
}

#[test]
fn malformed_numbers_are_errors_at_the_number() {
    assert_eq!(
        single_error("primitive sphere\n O= 0 x 0\n R= 1\nend\n"),
        (2, 7, "`O=` expects 3 numbers; `x` is not a number".into())
    );
    assert_eq!(
        single_error("primitive sphere\n O= 0 0 0\n R= 1..5\nend\n"),
        (3, 5, "`R=` expects a number; `1..5` is not a number".into())
    );
    assert_eq!(
        single_error("primitive sphere\n O= 0 0 0\n R= inf\nend\n"),
        (3, 5, "`inf` is not a finite number".into())
    );
    assert_eq!(
        single_error("primitive sphere\n O= 0 0 0\n R= NaN\nend\n"),
        (3, 5, "`NaN` is not a finite number".into())
    );
}

#[test]
fn wrong_vector_lengths_are_errors_over_the_values() {
    assert_eq!(
        single_error("primitive sphere\n O= 1 2\n R= 1\nend\n"),
        (2, 5, "`O=` expects 3 numbers, found 2 values".into())
    );
    assert_eq!(
        single_error("primitive sphere\n O= 1 2 3 4\n R= 1\nend\n"),
        (2, 5, "`O=` expects 3 numbers, found 4 values".into())
    );
    assert_eq!(
        single_error("primitive sphere\n O= 1 2 3\n R= 1 2\nend\n"),
        (3, 5, "`R=` expects a number, found 2 values".into())
    );
    assert_eq!(single_error("primitive sphere\n O=\n R= 1\nend\n"), (2, 2, "`O=` expects 3 numbers".into()));
    // Text after the values that is not a comment is reported.
    assert_eq!(
        single_error("primitive sphere\n O= 1 2 3 meters\n R= 1\nend\n"),
        (2, 5, "`O=` expects 3 numbers, found 4 values".into())
    );
    // The caret covers all the values.
    let e = parse(&source("primitive sphere\n O= 1 2\n R= 1\nend\n")).expect_err("error");
    assert!(e.to_string().contains("2 |  O= 1 2\n  |     ^^^\n"), "{e}");
}

#[test]
fn missing_end_is_an_error_at_the_open_block() {
    assert_eq!(
        single_error("primitive sphere\n O= 0 0 0\n R= 1\n"),
        (1, 11, "the `primitive sphere` block has no `end`".into())
    );
    // A new block before `end`: the unclosed block is reported, and the new one is still read.
    let text = "primitive sphere\n O= 0 0 0\n R= 1\nprimitive sphere\n O= 1 0 0\n R= 1\nend\n";
    assert_eq!(single_error(text), (1, 11, "the `primitive sphere` block has no `end`".into()));
    assert_eq!(
        single_error("background\n color= 0 0 0\n"),
        (1, 1, "the `background` block has no `end`".into())
    );
    assert_eq!(single_error("fog\n density= 1\n"), (1, 1, "this block has no `end`".into()));
}

#[test]
fn required_keys_are_errors_at_the_header() {
    assert_eq!(
        single_error("primitive sphere\n O= 0 0 0\nend\n"),
        (1, 11, "`primitive sphere` needs `R=` (the radius)".into())
    );
    assert_eq!(
        single_error("primitive sphere\n R= 1\nend\n"),
        (1, 11, "`primitive sphere` needs `O=` (the centre)".into())
    );
    assert_eq!(
        single_error("primitive plane\n R= 1\nend\n"),
        (1, 11, "`primitive plane` needs `N=` (the normal)".into())
    );
    assert_eq!(
        single_error("primitive plane\n N= 0 0 1\nend\n"),
        (1, 11, "`primitive plane` needs `R=` (the offset from the origin along the normal)".into())
    );
    assert_eq!(
        single_error("primitive square\n O= 0 0 0\n Dx= 1 0 0\nend\n"),
        (1, 11, "`primitive square` needs `Dy=` (the second half axis)".into())
    );
    assert_eq!(
        single_error("primitive cylinder\n O1= 0 0 0\n R= 1\nend\n"),
        (1, 11, "`primitive cylinder` needs `O2=` (the top cap centre)".into())
    );
    assert_eq!(
        single_error("light point\n color= 1 1 1\nend\n"),
        (1, 7, "`light point` needs `O=` (the light's position)".into())
    );
    assert_eq!(
        single_error("light square\n O= 0 0 0\n Dy= 0 1 0\n color= 1 1 1\nend\n"),
        (1, 7, "`light square` needs `Dx=` (the first half axis)".into())
    );
    assert_eq!(
        single_error("light sphere\n O= 0 0 0\n color= 1 1 1\nend\n"),
        (1, 7, "`light sphere` needs `R=` (the radius)".into())
    );
    assert_eq!(
        single_error("primitive sphere\n O= 0 0 0\n R= 1\n refr= 1\nend\n"),
        (4, 8, "`refr=` is positive, so `rindex=` (the refractive index) is required".into())
    );
    assert_eq!(
        single_error("primitive plane\n N= 0 0 1\n R= 0\n texture= a.bmp\nend\n"),
        (1, 11, "a textured `primitive plane` needs `Dx=` and `Dy=`".into())
    );
    assert_eq!(
        single_error("light\nend\n"),
        (1, 1, "`light` needs a type: `point`, `square`, `area` or `sphere`".into())
    );
    assert_eq!(
        single_error("primitive\nend\n"),
        (1, 1, "`primitive` needs a type: `sphere`, `plane`, `square`, `cylinder`, `triangle`, `mesh`, `polyhedron` or `bezier`".into())
    );
}

#[test]
fn invalid_geometry_is_an_error_at_the_key() {
    assert_eq!(
        single_error("primitive sphere\n O= 0 0 0\n R= 0\nend\n"),
        (3, 5, "in `primitive sphere`, the radius must be positive, not 0".into())
    );
    assert_eq!(
        single_error("primitive sphere\n O= 0 0 0\n R= -2\nend\n"),
        (3, 5, "in `primitive sphere`, the radius must be positive, not -2".into())
    );
    assert_eq!(
        single_error("primitive plane\n N= 0 0 0\n R= 1\nend\n"),
        (2, 5, "in `primitive plane`, `N=` must not be the zero vector".into())
    );
    assert_eq!(
        single_error("primitive square\n O= 0 0 0\n Dx= 1 0 0\n Dy= 2 0 0\nend\n"),
        (3, 6, "in `primitive square`, `Dx=` must not be parallel to `Dy=`".into())
    );
    assert_eq!(
        single_error("primitive cylinder\n O1= 1 1 1\n O2= 1 1 1\n R= 1\nend\n"),
        (3, 6, "in `primitive cylinder`, the axis from `O1=` to `O2=` has zero length".into())
    );
    assert_eq!(
        single_error("primitive sphere\n O= 0 0 0\n R= 1\n De= 0 0 1\n Dc= 0 0 -3\nend\n"),
        (5, 6, "in `primitive sphere`, `Dc=` must not be parallel to `De=`".into())
    );
    assert_eq!(
        single_error("light sphere\n O= 0 0 0\n R= 0\n color= 1 1 1\nend\n"),
        (3, 5, "in `light sphere`, the radius must be positive, not 0".into())
    );
    assert_eq!(
        single_error("primitive plane\n N= 0 0 1\n R= 0\n Dx= 0 0 0\n Dy= 0 1 0\nend\n"),
        (4, 6, "in `primitive plane`, `Dx=` must not be the zero vector".into())
    );
}

#[test]
fn overflow_and_underflow_are_called_so() {
    // Perpendicular axes whose cross product overflows are not "parallel".
    assert_eq!(
        single_error("primitive square\n O= 0 0 0\n Dx= 1e308 0 0\n Dy= 0 1e308 0\nend\n"),
        (3, 6, "in `primitive square`, `Dx=` is too large to use".into())
    );
    assert_eq!(
        single_error("light square\n O= 0 0 0\n Dx= 1e-300 0 0\n Dy= 0 1 0\n color= 1 1 1\nend\n"),
        (3, 6, "in `light square`, `Dx=` is too small to use".into())
    );
    assert_eq!(
        single_error("primitive square\n O= 0 0 0\n Dx= 1e-160 0 0\n Dy= 0 1e-170 0\nend\n"),
        (4, 6, "in `primitive square`, `Dy=` is too small to use".into())
    );
    assert_eq!(
        single_error("primitive cylinder\n O1= 0 0 -1e300\n O2= 0 0 1e300\n R= 1\nend\n"),
        (3, 6, "in `primitive cylinder`, the axis from `O1=` to `O2=` is too long to use".into())
    );
    assert_eq!(
        single_error("primitive cylinder\n O1= 0 0 0\n O2= 0 0 1e-300\n R= 1\nend\n"),
        (3, 6, "in `primitive cylinder`, the axis from `O1=` to `O2=` is too short to use".into())
    );
    assert_eq!(
        single_error(
            "primitive plane\n N= 0 0 1\n R= 0\n Dx= 1e-300 0 0\n Dy= 0 1 0\n texture= builtin:wood\nend\n"
        ),
        (4, 6, "in `primitive plane`, `Dx=` is too small to use".into())
    );
    assert_eq!(
        single_error(
            "primitive plane\n N= 0 0 1\n R= 0\n Dx= 1 0 0\n Dy= 0 1e200 0\n texture= builtin:wood\nend\n"
        ),
        (5, 6, "in `primitive plane`, `Dy=` is too large to use".into())
    );
    // A tiny or huge direction is still a direction.
    let p = ok(
        "primitive plane\n N= 1e-300 0 0\n R= 1\nend\nprimitive sphere\n O= 0 0 0\n R= 1\n De= 0 0 1e-300\n Dc= 1e300 0 0\nend\ncamera\n N= 0 1e-300 0\nend\n",
    );
    let Shape::Plane(plane) = &p.scene.primitives[0].shape else { panic!("a plane") };
    assert_eq!(plane.normal, DVec3::X);
    let Shape::Sphere(sphere) = &p.scene.primitives[1].shape else { panic!("a sphere") };
    assert_eq!((sphere.pole(), sphere.seam()), (DVec3::Z, DVec3::X));
    assert_eq!(p.scene.camera.dir, DVec3::Y);
}

#[test]
fn diagnostics_past_the_cap_are_counted_not_kept() {
    // 100,000 unclosed blocks: three errors each.
    let text = "primitive sphere\n".repeat(100_000);
    let e = parse(&source(&text)).expect_err("errors");
    assert_eq!(e.diagnostics.iter().filter(|d| d.is_error()).count(), MAX_KEPT_DIAGNOSTICS);
    assert_eq!(e.error_count(), 300_000, "{:?}", e.omitted);
    assert!(e.to_string().contains(&format!("... and {} more\n", 300_000 - MAX_KEPT_DIAGNOSTICS)));
    // Warnings are capped on their own, so an error after many warnings is still kept.
    let text = format!("{}primitive sphere\n R= 1\nend\n", "end\n".repeat(10_000));
    let e = parse(&source(&text)).expect_err("errors");
    assert_eq!(e.error_count(), 1);
    assert_eq!(e.diagnostics.len(), MAX_KEPT_DIAGNOSTICS + 1);
    assert_eq!(e.omitted, Omitted { errors: 0, others: 10_000 - MAX_KEPT_DIAGNOSTICS });
    // A warning-only file past the cap still parses, and says how many were left out.
    let p = ok(&format!("{}light point\n O= 0 0 0\n color= 1 1 1\nend\n", "end\n".repeat(60)));
    assert_eq!((p.diagnostics.len(), p.omitted.others), (MAX_KEPT_DIAGNOSTICS, 10));
}

#[test]
fn invalid_camera_values_are_errors() {
    assert_eq!(
        single_error("camera\n N= 0 0 0\nend\n"),
        (2, 5, "the view direction `N=` must not be the zero vector".into())
    );
    assert_eq!(single_error("camera\n lens_W= 0\nend\n"), (2, 10, "`lens_W=` must be positive".into()));
    assert_eq!(
        single_error("camera\n image_W= 12.5\nend\n"),
        (2, 11, "`image_W=` must be a whole number from 1 to 32768, not 12.5".into())
    );
    assert_eq!(
        single_error("camera\n image_H= 0\nend\n"),
        (2, 11, "`image_H=` must be a whole number from 1 to 32768, not 0".into())
    );
    assert_eq!(
        single_error("camera\n shade_quality= 0\nend\n"),
        (2, 17, "`shade_quality=` must be a whole number from 1 to 256, not 0".into())
    );
    assert_eq!(
        single_error("camera\n drefl_quality= 1000\nend\n"),
        (2, 17, "`drefl_quality=` must be a whole number from 1 to 256, not 1000".into())
    );
    assert_eq!(
        single_error("camera\n aperture= -1\nend\n"),
        (2, 12, "`aperture=` must not be negative".into())
    );
    assert_eq!(
        single_error("camera\n focal_dist= 0\nend\n"),
        (2, 14, "`focal_dist=` must be positive".into())
    );
    assert_eq!(
        single_error("primitive sphere\n O= 0 0 0\n R= 1\n refr= 1\n rindex= 0\nend\n"),
        (5, 10, "`rindex=` must be positive".into())
    );
}

#[test]
fn a_bad_image_or_lens_size_is_one_error_without_an_aspect_warning() {
    for text in [
        "camera\n image_W= 0\n lens_W= 1\n lens_H= 1\nend\n",
        "camera\n image_H= 3.5\n lens_W= 1\n lens_H= 1\nend\n",
        "camera\n lens_W= -1\n image_W= 640\n image_H= 380\nend\n",
        "camera\n lens_H= x\n image_W= 640\n image_H= 380\nend\n",
    ] {
        let all = diagnostics(text);
        assert_eq!(all.len(), 1, "{text}: {all:#?}");
        assert_eq!(all[0].0, Severity::Error, "{text}");
    }
    // A valid but mismatched size still draws the warning.
    let all = diagnostics("camera\n image_W= 640\n image_H= 380\n lens_W= 1\n lens_H= 1\nend\n");
    assert!(all[0].3.contains("will be stretched"), "{all:#?}");
}

#[test]
fn absurd_image_sizes_are_refused() {
    // Each side is allowed, the area is not.
    let (line, _, message) =
        single_error("camera\n image_W= 30000\n image_H= 30000\n lens_W= 1\n lens_H= 1\nend\n");
    assert_eq!(line, 2);
    assert!(message.starts_with("the image size 30000x30000 is too large"), "{message}");
    assert!(check_image_size(8192, 8192).is_ok());
    assert!(check_image_size(8193, 8192).is_err());
    assert!(check_image_size(0, 10).is_err());
}

#[test]
fn unknown_builtin_texture_is_an_error() {
    let (line, column, message) =
        single_error("primitive sphere\n O= 0 0 0\n R= 1\n texture= builtin:granite\nend\n");
    assert_eq!((line, column), (4, 11));
    assert!(message.starts_with("unknown built-in texture `granite`"), "{message}");
}

#[test]
fn bad_key_lines_are_errors() {
    assert_eq!(
        single_error("primitive sphere\n O= 0 0 0\n R= 1\n shiny\nend\n"),
        (4, 2, "expected `key= value`, found `shiny`".into())
    );
    assert_eq!(
        single_error("primitive sphere\n O= 0 0 0\n R= 1\n = 3\nend\n"),
        (4, 2, "a key is missing before `=`".into())
    );
    assert_eq!(
        single_error("primitive sphere\n O= 0 0 0\n R= 1\n texture=\nend\n"),
        (4, 2, "`texture=` needs a value".into())
    );
}

#[test]
fn several_errors_are_reported_in_one_run_in_file_order() {
    // Every value that does not read is reported; the checks of the shape as a whole (here a
    // negative radius) wait until the block's values read.
    let text = "primitive sphere\n O= 0 0\n R= -1\n diff= x\nend\nprimitive plane\n N= 0 0 0\n R= y\nend\n";
    let e = parse(&source(text)).expect_err("errors");
    let lines: Vec<u32> =
        e.diagnostics.iter().map(|d| d.location.as_ref().map_or(0, |l| l.span.line)).collect();
    assert_eq!(lines, vec![2, 4, 8]);
    assert_eq!(e.error_count(), 3, "{e}");
    assert!(e.to_string().ends_with("3 errors"));
}

#[test]
fn error_display_names_file_line_and_column() {
    let e = parse(&source("primitive sphere\n\tO= 0 0 0\n\tR= zero\nend\n")).expect_err("error");
    assert_eq!(
        e.to_string(),
        "error: `R=` expects a number; `zero` is not a number\n --> test.txt:3:5\n  |\n3 |     R= zero\n  |        ^^^^\n\n1 error"
    );
}

mod properties {
    //! The parser never panics, whatever the input, and every diagnostic points inside the file.
    use proptest::prelude::*;

    use super::*;

    const VALID: &str = include_str!("../../../../../scenes/showcase.txt");

    fn check(text: &str) {
        let src = source(text);
        let lines = src.lines().count() as u32;
        let all = match parse(&src) {
            Ok(p) => p.diagnostics,
            Err(e) => {
                assert!(e.error_count() > 0);
                e.diagnostics
            }
        };
        for d in all {
            if let Some(l) = &d.location {
                assert!(l.span.line >= 1 && l.span.line <= lines.max(1), "{d}");
                assert!(l.span.column >= 1, "{d}");
            }
            let _ = d.to_string();
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 512, ..ProptestConfig::default() })]

        #[test]
        fn arbitrary_bytes(bytes in proptest::collection::vec(any::<u8>(), 0..400)) {
            let src = SourceFile::from_bytes("fuzz.txt", None, bytes.as_slice());
            check(src.text());
        }

        #[test]
        fn scene_like_text(lines in proptest::collection::vec(
            prop_oneof![
                Just("primitive sphere".to_owned()), Just("primitive plane".to_owned()),
                Just("primitive square".to_owned()), Just("primitive cylinder".to_owned()),
                Just("light point".to_owned()), Just("light area".to_owned()), Just("light sphere".to_owned()),
                Just("camera".to_owned()), Just("background".to_owned()), Just("end".to_owned()),
                "[A-Za-z_]{1,8}= ?[-0-9.e x]{0,20}",
                "[ -~\t]{0,30}",
            ],
            0..40,
        )) {
            check(&lines.join("\n"));
        }

        #[test]
        fn truncated_valid_scene(cut in 0..VALID.len()) {
            let mut end = cut;
            while !VALID.is_char_boundary(end) { end -= 1; }
            check(&VALID[..end]);
        }

        #[test]
        fn mutated_valid_scene(position in 0..VALID.len(), insert in "[ -~\n]{0,12}", delete in 0usize..12) {
            let mut start = position;
            while !VALID.is_char_boundary(start) { start -= 1; }
            let mut end = (start + delete).min(VALID.len());
            while !VALID.is_char_boundary(end) { end -= 1; }
            let text = format!("{}{}{}", &VALID[..start], insert, &VALID[end..]);
            check(&text);
        }
    }
}

#[test]
fn triangles_in_both_forms_and_obj_as_a_block_name() {
    let text = "primitive triangle\n P0= 0 0 0\n P1= 1 0 0\n P2= 0 1 0\n color= 1 0 0\nend\n\
                obj triangle\n O1= 0 0 1\n O2= 0 1 1\n O3= 1 0 1\nend\n";
    let prims = ok(text).scene.primitives;
    match &prims[0].shape {
        Shape::Triangle(t) => assert_eq!(t.normal, DVec3::Z),
        other => panic!("{other:?}"),
    }
    match &prims[1].shape {
        Shape::Triangle(t) => assert_eq!(t.corners[2], DVec3::new(1.0, 0.0, 1.0)),
        other => panic!("{other:?}"),
    }
    assert_eq!(prims[0].material.as_course().map(|m| m.color), Some(DVec3::X));
    let (line, _, message) = single_error("primitive triangle\n P0= 0 0 0\n P1= 1 0 0\nend\n");
    assert_eq!((line, message.as_str()), (1, "`primitive triangle` needs `P2=` (its corners)"));
    let (line, _, message) = single_error("primitive triangle\n P0= 0 0 0\n P1= 1 0 0\n P2= 2 0 0\nend\n");
    assert_eq!(line, 4);
    assert!(message.contains("collinear"), "{message}");
}

#[test]
fn mesh_and_polyhedron_keys_and_defaults() {
    use crate::geometry::MeshTransform;
    let text = "primitive mesh\n file= models/bunny.obj\n O= 1 2 3\n scale= 2\n rotation= 0 0 1.5\nend\n\
                primitive polyhedron\n mesh= teapot.obj\n size= 1 2 3\n angles= 90 0 0\nend\n\
                primitive polyhedron\n mesh= a b.obj\nend\n";
    let meshes = ok(text).scene.meshes;
    let file = |i: usize| (meshes[i].file.path.clone(), meshes[i].file.transform);
    assert_eq!(
        file(0),
        (
            "models/bunny.obj".into(),
            MeshTransform {
                origin: DVec3::new(1.0, 2.0, 3.0),
                scale: DVec3::splat(2.0),
                rotation: DVec3::new(0.0, 0.0, 1.5)
            }
        )
    );
    let (path, t) = file(1);
    assert_eq!((path.as_str(), t.scale), ("teapot.obj", DVec3::new(1.0, 2.0, 3.0)));
    assert!((t.rotation.x - std::f64::consts::FRAC_PI_2).abs() < 1e-15, "degrees become radians");
    assert_eq!(file(2), ("a b.obj".into(), MeshTransform::default()));
    let (line, _, message) = single_error("primitive mesh\n O= 0 0 0\nend\n");
    assert_eq!((line, message.as_str()), (1, "`primitive mesh` needs `file=` (the OBJ file)"));
    let (line, _, message) = single_error("primitive polyhedron\n mesh= x.obj\n size= 1 0 1\nend\n");
    assert_eq!(line, 3);
    assert!(message.contains("zero component"), "{message}");
}

#[test]
fn bezier_in_both_forms() {
    let text = "primitive bezier\n O1= 0 0 0\n O2= 0 0 2\n P= 0 0\n P= 0.5 1 // a point\n P= 1 0.5\n color= 0 0 1\nend\n\
                primitive bezier\n center= 1 1 0\n V0= 1.5 1 0\n V1= 2 1 0.5\n V2= 0.2 1 1\n V3= 1.3 1 2\nend\n";
    let prims = ok(text).scene.primitives;
    match &prims[0].shape {
        Shape::Bezier(b) => {
            assert_eq!(b.profile, vec![DVec2::new(0.0, 0.0), DVec2::new(0.5, 1.0), DVec2::new(1.0, 0.5)]);
            assert_eq!(b.axis, DVec3::Z);
        }
        other => panic!("{other:?}"),
    }
    match &prims[1].shape {
        Shape::Bezier(b) => {
            // Radius |V.x - center.x|, height V.z.
            assert_eq!(
                b.profile,
                vec![
                    DVec2::new(0.0, 0.5),
                    DVec2::new(0.5, 1.0),
                    DVec2::new(1.0, 0.8),
                    DVec2::new(2.0, 0.30000000000000004)
                ]
            );
            assert_eq!(b.base, DVec3::new(1.0, 1.0, 0.0));
        }
        other => panic!("{other:?}"),
    }
    // The points are repeated keys, not replacements: no warning.
    assert!(ok(text).diagnostics.is_empty());
    let (line, _, message) = single_error("primitive bezier\n O1= 0 0 0\n O2= 0 0 1\n P= 0 1\nend\n");
    assert_eq!(line, 1);
    assert!(message.contains("2 to 32 `P= z r` lines"), "{message}");
    let (line, column, message) =
        single_error("primitive bezier\n O1= 0 0 0\n O2= 0 0 1\n P= 0 1\n P= 1\nend\n");
    assert_eq!((line, column), (5, 5));
    assert!(message.contains("`P=` expects 2 numbers"), "{message}");
}

#[test]
fn normal_maps_under_both_names() {
    let text = "primitive sphere\n O= 0 0 0\n R= 1\n bump= waves.png\nend\n\
                primitive sphere\n O= 0 0 0\n R= 1\n NT= builtin:stripes:4\nend\n";
    let prims = ok(text).scene.primitives;
    assert_eq!(
        prims[0].material.as_course().and_then(|m| m.bump.as_ref()).as_ref().map(|t| t.source.clone()),
        Some(TextureSource::File("waves.png".into()))
    );
    assert_eq!(
        prims[1].material.as_course().and_then(|m| m.bump.as_ref()).as_ref().map(|t| t.source.clone()),
        Some(TextureSource::Builtin(Builtin::Stripes(4)))
    );
}

#[test]
fn equal_untextured_materials_are_shared() {
    let text = "primitive sphere\n O= 0 0 0\n R= 1\n color= 1 0 0\n diff= 0.5\nend\n\
                primitive sphere\n O= 3 0 0\n R= 1\n diff= 0.5\n color= 1 0 0\nend\n\
                primitive sphere\n O= 6 0 0\n R= 1\n diff= 0.6\n color= 1 0 0\nend\n";
    let prims = ok(text).scene.primitives;
    assert!(std::sync::Arc::ptr_eq(&prims[0].material, &prims[1].material));
    assert!(!std::sync::Arc::ptr_eq(&prims[0].material, &prims[2].material));
}

/// A file of `n` spheres in three materials (8 lines each), with the camera block after the
/// first `camera_after` spheres and `extra` inserted after sphere `extra_after`.
fn many_spheres(n: usize, camera_after: usize, extra_after: usize, extra: &str) -> String {
    let mut text =
        String::from("background\n color= 0.1 0.1 0.1\nend\nlight point\n O= 0 0 5\n color= 1 1 1\nend\n");
    for i in 0..n {
        if i == camera_after {
            text.push_str("camera\n O= 0 -5 0\n N= 0 1 0\n image_W= 64\n image_H= 64\nend\n");
        }
        if i == extra_after {
            text.push_str(extra);
        }
        let m = i % 3;
        text.push_str(&format!(
            "primitive sphere\n O= {} {} 0\n R= 0.25\n color= 0.{m} 0.5 0.5\n diff= 0.8\n spec= 0.2\n\nend\n",
            i % 100,
            i / 100
        ));
    }
    text
}

/// The scene of `text` parsed line by line (as the file is when it is small or has problems).
fn parse_line_by_line(text: &str) -> Result<Parsed, SceneError> {
    super::parse_line_by_line(&source(text))
}

#[test]
fn large_files_parsed_in_pieces_give_the_scene_of_one_pass() {
    // 20,000 spheres: 160,000 lines, 1.6 MB, four pieces; the camera block in the second.
    let text = many_spheres(20_000, 12_000, usize::MAX, "");
    let cut = pieces(&text);
    assert_eq!(cut.len(), 4);
    // The pieces are the file's lines, in order, numbered as in the file, each but the first
    // starting with a block.
    let mut joined = String::new();
    for (i, piece) in cut.iter().enumerate() {
        assert_eq!(joined.lines().count() as u32 + 1, piece.first_line);
        if i > 0 {
            assert!(piece.text.starts_with("primitive sphere\n"), "{}", &piece.text[..40]);
            joined.push('\n');
        }
        joined.push_str(piece.text);
    }
    assert_eq!(joined, text);
    let pieces = parse_in_pieces(&source(&text)).expect("a clean file is parsed in pieces");
    let whole = parse_line_by_line(&text).expect("valid");
    assert!(whole.diagnostics.is_empty());
    assert_eq!(pieces.scene, whole.scene);
    assert_eq!(pieces.scene.camera.image_width, 64);
    // Equal materials are shared within each piece (each piece keeps its own copies, so that
    // the threads do not contend for their reference counts): three materials in each of the
    // four pieces.
    let mut distinct: Vec<*const Material> = Vec::new();
    for p in &pieces.scene.primitives {
        if !distinct.contains(&Arc::as_ptr(&p.material)) {
            distinct.push(Arc::as_ptr(&p.material));
        }
    }
    assert_eq!(distinct.len(), 12);
    // Small files are not cut.
    assert!(parse_in_pieces(&source(&many_spheres(100, 0, usize::MAX, ""))).is_none());
}

#[test]
fn pieces_start_at_blocks_and_keep_crlf_line_numbers() {
    // One block of a million key lines and then a sphere: the only line opening a block past
    // the first piece's size is the sphere's, so there are two pieces.
    let mut text = String::from("camera\r\n");
    for _ in 0..100_000 {
        text.push_str(" O= 0 -9 0\r\n");
    }
    text.push_str("end\r\nprimitive sphere\r\n O= 0 0 0\r\n R= 1\r\nend\r\n");
    let cut = pieces(&text);
    assert_eq!(cut.len(), 2);
    assert_eq!(cut[1].first_line, 100_003);
    assert!(cut[1].text.starts_with("primitive sphere\r\n"));
    assert_eq!(source(&text).line(100_003), "primitive sphere");
    // A file with no line past the first piece's size that opens a block is one piece.
    let text = format!("camera\n{}end\n", " O= 0 -9 0\n".repeat(100_000));
    let cut = pieces(&text);
    assert!(cut.len() == 1 && cut[0].first_line == 1 && cut[0].text == text);
}

#[test]
fn large_files_with_problems_are_reported_as_line_by_line() {
    let cases = [
        // A warning deep in the file (an unknown key), at line 7 + 8 * 15000 + 3.
        "primitive sphere\n O= 0 0 0\n R= 1\n colour= 1 0 0\nend\n",
        // A second camera block.
        "camera\n O= 0 -9 0\nend\n",
        // A block without `end`, then the next one.
        "primitive sphere\n O= 0 0 0\n R= 1\n",
        // An unknown block that swallows the next sphere up to its `end`.
        "teapot\n",
    ];
    for extra in cases {
        let text = many_spheres(20_000, 0, 15_000, extra);
        assert!(parse_in_pieces(&source(&text)).is_none(), "{extra}");
        let from_parse = match parse(&source(&text)) {
            Ok(p) => p.diagnostics,
            Err(e) => e.diagnostics,
        };
        let expected = match parse_line_by_line(&text) {
            Ok(p) => p.diagnostics,
            Err(e) => e.diagnostics,
        };
        assert!(!from_parse.is_empty(), "{extra}");
        assert_eq!(from_parse, expected, "{extra}");
    }
}

#[test]
fn nomal_ball_and_nomal_plane_are_normal_mapped_sphere_and_plane() {
    // LuChengTHU's renderer names its normal-mapped shapes so (spelled so); `obj` works too.
    let text = "primitive NomalBall\n O= 1 2 3\n R= 0.5\n De= 1 0 0\n Dc= 0 0 1\n NT= builtin:stripes:4\nend\n\
                obj NomalPlane\n N= 0 0 1\n R= -1\n Dx= 2 0 0\n Dy= 0 2 0\n NT= waves.bmp\nend\n";
    let parsed = ok(text);
    let prims = &parsed.scene.primitives;
    assert_eq!(prims.len(), 2);
    match &prims[0].shape {
        Shape::Sphere(s) => {
            assert_eq!((s.centre, s.radius), (DVec3::new(1.0, 2.0, 3.0), 0.5));
            assert_eq!((s.pole(), s.seam()), (DVec3::X, DVec3::Z), "the texture frame from De= and Dc=");
        }
        other => panic!("expected a sphere, got {other:?}"),
    }
    assert_eq!(
        prims[0].material.as_course().and_then(|m| m.bump.as_ref()).as_ref().map(|t| t.source.clone()),
        Some(TextureSource::Builtin(Builtin::Stripes(4)))
    );
    assert!(matches!(prims[1].shape, Shape::Plane(_)), "{:?}", prims[1].shape);
    assert_eq!(
        prims[1].material.as_course().and_then(|m| m.bump.as_ref()).as_ref().map(|t| t.source.clone()),
        Some(TextureSource::File("waves.bmp".into()))
    );
    // One note at each type name, saying what it is read as.
    let notes: Vec<_> = parsed.diagnostics.iter().filter(|d| d.severity == Severity::Note).collect();
    assert_eq!(notes.len(), 2, "{notes:#?}");
    let at = |d: &Diagnostic| d.location.as_ref().map(|l| (l.span.line, l.span.column));
    assert_eq!(at(notes[0]), Some((1, 11)));
    assert_eq!(notes[0].message, "`primitive NomalBall` is read as `primitive sphere`");
    assert!(notes[0].notes[0].contains("normal map `NT=`"), "{:?}", notes[0].notes);
    assert_eq!(at(notes[1]), Some((8, 5)));
    assert_eq!(notes[1].message, "`obj NomalPlane` is read as `primitive plane`");
    // Nothing else is reported: the keys are those of a sphere and a plane.
    assert_eq!(parsed.diagnostics.len(), 2, "{:#?}", parsed.diagnostics);
    // The names are case-sensitive, as the other types are; a light is not a NomalBall.
    let d = diagnostics("primitive nomalball\n O= 0 0 0\n R= 1\nend\nlight NomalBall\n O= 0 0 0\nend\n");
    assert!(d[0].3.starts_with("unknown primitive type `nomalball`"), "{d:?}");
    assert!(d[1].3.starts_with("unknown light type `NomalBall`"), "{d:?}");
    // A NomalBall's keys are checked as a sphere's.
    let (line, _, message) = single_error("primitive NomalBall\n O= 0 0 0\nend\n");
    assert_eq!(line, 1);
    assert!(message.contains("needs `R=`"), "{message}");
}

#[test]
fn quoted_tokens_are_cut_in_messages() {
    // A line of one huge token (a file of NULs is one): every message quotes at most
    // MAX_QUOTED_CHARS characters of it, and the location keeps a bounded part of the line.
    let token = "\0".repeat(1 << 20);
    let text = format!(
        "{token}\n{SPHERE}primitive {token}\nend\nprimitive sphere\n O= {token} 0 0\n R= 1\n {token}= 1\nend\n"
    );
    let error = parse(&source(&text)).expect_err("errors");
    let limit = crate::base::diagnostic::MAX_QUOTED_CHARS;
    for d in &error.diagnostics {
        assert!(d.message.len() < 3 * limit + 200, "{} bytes: {:.200}", d.message.len(), d.message);
        let kept = d.location.as_ref().map_or(0, |l| l.line_text.len());
        assert!(kept <= crate::base::diagnostic::MAX_KEPT_LINE_CHARS, "{kept}");
    }
    let messages: Vec<&str> = error.diagnostics.iter().map(|d| d.message.as_str()).collect();
    let cut = format!("`{}...`", "\0".repeat(limit));
    assert!(messages[0].starts_with(&format!("unknown block {cut}")), "{:?}", &messages[0][..80]);
    assert!(messages.iter().any(|m| m.starts_with(&format!("unknown primitive type {cut}"))), "{messages:?}");
    assert!(messages.iter().any(|m| m.contains(&format!("; {cut} is not a number"))), "{messages:?}");
    assert!(messages.iter().any(|m| m.starts_with(&format!("unknown key `{}...=`", "\0".repeat(limit)))));
    // Printed, the whole report stays small.
    let printed = error.to_string();
    assert!(printed.len() < 20_000, "{} bytes", printed.len());
}
