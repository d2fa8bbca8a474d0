//! Tests of the scene builder on small scenes written here.

use glam::DVec3;

use super::build;
use crate::light::Emitter;
use crate::material::{Material, Param};
use crate::scene::mitsuba::read_source;
use crate::scene::{PixelFilter, Severity, SourceFile};

fn built(text: &str) -> super::Built {
    let doc = read_source(SourceFile::from_text("t.xml", None, text.to_owned()), &[]).expect("reads");
    match build(&doc) {
        Ok(b) => b,
        Err(e) => panic!("{e:#?}"),
    }
}

fn errors(text: &str) -> Vec<String> {
    let doc = read_source(SourceFile::from_text("t.xml", None, text.to_owned()), &[]).expect("reads");
    build(&doc).expect_err("fails").into_iter().filter(|d| d.is_error()).map(|d| d.message).collect()
}

const SENSOR: &str = r#"<sensor type="perspective">
    <float name="fov" value="90"/>
    <transform name="to_world"><lookat origin="0, 0, 5" target="0, 0, 0" up="0, 1, 0"/></transform>
    <sampler type="independent"><integer name="sample_count" value="8"/></sampler>
    <film type="hdrfilm"><integer name="width" value="64"/><integer name="height" value="32"/>
        <rfilter type="tent"/></film>
</sensor>"#;

#[test]
fn a_sensor_becomes_the_camera_and_the_render_settings() {
    let b = built(&format!(
        r#"<scene version="3.0.0"><integrator type="path"><integer name="max_depth" value="7"/></integrator>{SENSOR}</scene>"#
    ));
    let cam = &b.scene.camera;
    assert_eq!((cam.image_width, cam.image_height), (64, 32));
    assert!((cam.dir - -DVec3::Z).length() < 1e-12);
    assert_eq!(cam.up, Some(DVec3::Y));
    // fov 90 along x: the plane at distance 1 is 2 wide, and 1 high at aspect 2.
    assert!((cam.lens_width - 2.0).abs() < 1e-12 && (cam.lens_height - 1.0).abs() < 1e-12);
    assert_eq!(b.scene.render.samples, Some(8));
    assert_eq!(b.scene.render.max_depth, Some(7));
    assert_eq!(b.scene.render.filter, PixelFilter::Tent { radius: 1.0 });
    assert!(b.scene.render.srgb_output);
}

#[test]
fn shapes_with_area_emitters_are_lights_and_share_their_bsdf() {
    let b = built(&format!(
        r#"<scene version="3.0.0">{SENSOR}
        <bsdf type="diffuse" id="red"><rgb name="reflectance" value="0.8, 0.1, 0.1"/></bsdf>
        <shape type="rectangle"><ref id="red"/><emitter type="area"><rgb name="radiance" value="5"/></emitter></shape>
        <shape type="cube"><ref id="red"/></shape>
        <shape type="sphere"><float name="radius" value="2"/>
            <transform name="to_world"><scale value="0.5"/><translate x="1"/></transform></shape>
        </scene>"#
    ));
    let prims = &b.scene.primitives;
    assert_eq!(prims.len(), 3);
    assert!(std::sync::Arc::ptr_eq(&prims[0].material, &prims[1].material));
    assert_eq!(
        *prims[0].material,
        Material::Diffuse { reflectance: Param::Constant(DVec3::new(0.8, 0.1, 0.1)) }
    );
    assert_eq!(
        b.scene.emitters,
        vec![Emitter::Area { primitive: 0, radiance: Param::Constant(DVec3::splat(5.0)) }]
    );
    match &prims[2].shape {
        crate::geometry::Shape::Sphere(s) => {
            assert!((s.centre - DVec3::X).length() < 1e-12 && (s.radius - 1.0).abs() < 1e-12)
        }
        other => panic!("{other:?}"),
    }
    // Mitsuba's default material for a shape without a BSDF.
    assert_eq!(*prims[2].material, Material::Diffuse { reflectance: Param::scalar(0.5) });
}

#[test]
fn unsupported_plugins_are_warnings_naming_them() {
    let b = built(&format!(
        r#"<scene version="3.0.0">{SENSOR}
        <shape type="rectangle"><bsdf type="hair"/></shape>
        <shape type="sdfgrid"/>
        <emitter type="area_light_of_the_future"/>
        </scene>"#
    ));
    let warnings: Vec<&str> = b
        .diagnostics
        .iter()
        .filter(|d| d.severity == Severity::Warning)
        .map(|d| d.message.as_str())
        .collect();
    assert!(warnings.iter().any(|w| w.contains("`hair`")), "{warnings:?}");
    assert!(warnings.iter().any(|w| w.contains("`sdfgrid`")), "{warnings:?}");
    assert!(warnings.iter().any(|w| w.contains("`area_light_of_the_future`")), "{warnings:?}");
    assert_eq!(b.scene.primitives.len(), 1);
}

#[test]
fn bad_scenes_are_errors_at_their_place() {
    let no_sensor = errors(r#"<scene version="3.0.0"><shape type="cube"/></scene>"#);
    assert!(no_sensor[0].contains("no <sensor>"), "{no_sensor:?}");
    let metal = errors(&format!(
        r#"<scene version="3.0.0">{SENSOR}<shape type="cube"><bsdf type="conductor"><string name="material" value="Unobtainium"/></bsdf></shape></scene>"#
    ));
    assert!(metal[0].contains("unknown conductor `Unobtainium`"), "{metal:?}");
    let ior = errors(&format!(
        r#"<scene version="3.0.0">{SENSOR}<shape type="cube"><bsdf type="dielectric"><string name="int_ior" value="glas"/></bsdf></shape></scene>"#
    ));
    assert!(ior[0].contains("unknown index of refraction `glas`"), "{ior:?}");
    let film = errors(
        r#"<scene version="3.0.0"><sensor type="perspective"><film type="hdrfilm"><integer name="width" value="2000000"/></film></sensor></scene>"#,
    );
    assert!(!film.is_empty());
    let mesh = errors(&format!(
        r#"<scene version="3.0.0">{SENSOR}<shape type="ply"><string name="filename" value="missing.ply"/></shape></scene>"#
    ));
    assert!(mesh[0].contains("`missing.ply` is not found"), "{mesh:?}");
}

#[test]
fn named_iors_and_metals_resolve() {
    let b = built(&format!(
        r#"<scene version="3.0.0">{SENSOR}
        <shape type="cube"><bsdf type="dielectric"><string name="int_ior" value="water"/></bsdf></shape>
        <shape type="cube"><bsdf type="roughconductor"><string name="material" value="Au"/>
            <string name="distribution" value="ggx"/><float name="alpha" value="0.2"/></bsdf></shape>
        </scene>"#
    ));
    match &*b.scene.primitives[0].material {
        Material::Dielectric(i) => assert_eq!((i.int_ior, i.ext_ior), (1.333, 1.000277)),
        other => panic!("{other:?}"),
    }
    match &*b.scene.primitives[1].material {
        Material::RoughConductor { metal, microfacet } => {
            assert_eq!(metal.eta, DVec3::new(0.143036, 0.375307, 1.44205));
            assert_eq!(microfacet.alpha_u, Param::scalar(0.2));
            assert_eq!(microfacet.distribution, crate::material::Distribution::Ggx);
        }
        other => panic!("{other:?}"),
    }
}

/// A unit sphere at the origin with `bsdf`, and the interaction (with its unperturbed and its
/// perturbed frame) where the ray from `+x` meets it.
#[allow(clippy::type_complexity)]
fn sphere_frames(bsdf: &str) -> ((DVec3, DVec3, DVec3), Option<(DVec3, DVec3, DVec3)>, Vec<String>) {
    let b = built(&format!(
        r#"<scene version="3.0.0">{SENSOR}<shape type="sphere"><float name="radius" value="1"/>{bsdf}</shape></scene>"#
    ));
    let warnings = b.diagnostics.iter().map(|d| d.message.clone()).collect();
    let scene = crate::PreparedScene::new(b.scene, &Default::default()).expect("prepares");
    let ray = crate::geometry::Ray::new(DVec3::new(5.0, 0.2, 0.3), DVec3::new(-1.0, 0.0, 0.0));
    let (primitive, hit) = scene.closest_surface(&ray).expect("hits");
    let at = scene.interaction(&ray, primitive, hit);
    let frame = scene.shading_frame(&at);
    (frame, scene.perturbed_frame(&at, frame), warnings)
}

fn close(a: DVec3, b: DVec3) -> bool {
    (a - b).length() < 1e-9
}

#[test]
fn normal_and_bump_maps_perturb_the_shading_frame_as_mitsuba() {
    let nested = r#"<bsdf type="diffuse"/>"#;
    // A flat normal map, (0.5, 0.5, 1), leaves the frame as it is.
    let flat = format!(
        r#"<bsdf type="normalmap"><texture name="normalmap" type="checkerboard">
           <rgb name="color0" value="0.5, 0.5, 1"/><rgb name="color1" value="0.5, 0.5, 1"/></texture>{nested}</bsdf>"#
    );
    // (The tangent turns: Mitsuba's Gram-Schmidt takes the world dp/du as local coordinates.)
    let ((_, _, n), perturbed, _) = sphere_frames(&flat);
    let (t2, b2, n2) = perturbed.expect("a normal map perturbs");
    assert!(close(n, n2), "{n} {n2}");
    assert!(t2.dot(n2).abs() < 1e-9 && close(n2.cross(t2), b2) && (t2.length() - 1.0).abs() < 1e-9);
    // (1, 0.5, 0.5) is the first tangent: the normal turns to dp/du.
    let tilted = format!(
        r#"<bsdf type="normalmap"><texture name="normalmap" type="checkerboard">
           <rgb name="color0" value="1, 0.5, 0.5"/><rgb name="color1" value="1, 0.5, 0.5"/></texture>{nested}</bsdf>"#
    );
    let ((t, _, n), perturbed, _) = sphere_frames(&tilted);
    let (t2, b2, n2) = perturbed.expect("perturbs");
    assert!(close(n2, t), "{n2} {t}");
    assert!(t2.dot(n2).abs() < 1e-9 && b2.dot(n2).abs() < 1e-9 && (t2.length() - 1.0).abs() < 1e-9);
    assert!(n2.dot(n).abs() < 1e-9);
    // A constant height has no gradient: the bumped normal is the shading normal.
    let bump = format!(
        r#"<bsdf type="bumpmap"><float name="scale" value="3"/><texture type="checkerboard">
           <rgb name="color0" value="0.2"/><rgb name="color1" value="0.2"/></texture>{nested}</bsdf>"#
    );
    let ((_, _, n), perturbed, _) = sphere_frames(&bump);
    assert!(close(perturbed.expect("perturbs").2, n));
    // Without a map the frame is not perturbed.
    assert!(sphere_frames(nested).1.is_none());
    // Nested in a wrapper, the map is not applied, and the builder says so.
    let (_, perturbed, warnings) = sphere_frames(&format!(r#"<bsdf type="twosided">{tilted}</bsdf>"#));
    assert!(perturbed.is_none());
    assert!(warnings.iter().any(|w| w.contains("outermost")), "{warnings:?}");
}

#[test]
fn normal_and_bump_maps_need_their_texture() {
    let nested = r#"<bsdf type="diffuse"/>"#;
    let e = errors(&format!(
        r#"<scene version="3.0.0">{SENSOR}<shape type="sphere"><bsdf type="normalmap">{nested}</bsdf></shape></scene>"#
    ));
    assert!(e.iter().any(|m| m.contains("normalmap")), "{e:?}");
    let e = errors(&format!(
        r#"<scene version="3.0.0">{SENSOR}<shape type="sphere"><bsdf type="bumpmap">{nested}</bsdf></shape></scene>"#
    ));
    assert!(e.iter().any(|m| m.contains("1 nested <texture>")), "{e:?}");
    let b = built(&format!(
        r#"<scene version="3.0.0">{SENSOR}<shape type="sphere"><bsdf type="bumpmap"><float name="scale" value="0.5"/>
           <texture type="checkerboard"/>{nested}</bsdf></shape></scene>"#
    ));
    match &*b.scene.primitives[0].material {
        Material::Perturbed {
            perturbation: crate::material::Perturbation::BumpMap { scale, .. },
            material,
        } => {
            assert_eq!(*scale, 0.5);
            assert!(matches!(**material, Material::Diffuse { .. }));
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn an_orthographic_sensor_shows_its_to_world_scaled_square() {
    let b = built(
        r#"<scene version="3.0.0"><sensor type="orthographic">
            <transform name="to_world"><scale x="2" y="3"/>
                <lookat origin="0, 0, 5" target="0, 0, 0" up="0, 1, 0"/></transform>
            <film type="hdrfilm"><integer name="width" value="64"/><integer name="height" value="32"/></film>
        </sensor></scene>"#,
    );
    let cam = &b.scene.camera;
    assert!(cam.orthographic);
    assert!((cam.dir - -DVec3::Z).length() < 1e-12);
    // Rays start on the near plane (0.01 along the view).
    assert!((cam.eye - DVec3::new(0.0, 0.0, 4.99)).length() < 1e-12, "{}", cam.eye);
    // x in [-1, 1] scaled by 2; y in [-1/aspect, 1/aspect] scaled by 3.
    assert!((cam.lens_width - 4.0).abs() < 1e-12 && (cam.lens_height - 3.0).abs() < 1e-12);
    let e = errors(r#"<scene version="3.0.0"><sensor type="radiancemeter"/></scene>"#);
    assert!(e.iter().any(|m| m.contains("`orthographic`")), "{e:?}");
}

#[test]
fn a_spot_keeps_its_texture_and_frame() {
    let b = built(&format!(
        r#"<scene version="3.0.0">{SENSOR}<emitter type="spot">
            <transform name="to_world"><lookat origin="0, 0, 5" target="0, 0, 0" up="0, 1, 0"/></transform>
            <texture name="texture" type="checkerboard"/></emitter></scene>"#
    ));
    match &b.scene.emitters[0] {
        Emitter::Spot { texture, to_local, axis, .. } => {
            assert!(texture.is_some());
            // The axis is the spot's local +z.
            assert!((*to_local * *axis - DVec3::Z).length() < 1e-12, "{}", *to_local * *axis);
        }
        other => panic!("{other:?}"),
    }
    let e = errors(&format!(
        r#"<scene version="3.0.0">{SENSOR}<emitter type="spot"><bsdf name="texture" type="diffuse"/></emitter></scene>"#
    ));
    assert!(e.iter().any(|m| m.contains("must be a <texture>")), "{e:?}");
}

#[test]
fn a_checkerboard_read_as_a_scalar_takes_mitsubas_other_phase() {
    // Mitsuba 3.9.1's checkerboard gives `eval_1` (a roughness, an opacity) `color1` where `eval`
    // (a colour) gives `color0`: the scalar reading is built with the colours swapped.
    let b = built(&format!(
        r#"<scene version="3.0.0">{SENSOR}
        <shape type="cube"><bsdf type="roughconductor">
            <texture name="alpha" type="checkerboard"><float name="color0" value="0.05"/><float name="color1" value="0.3"/></texture>
        </bsdf></shape>
        <shape type="cube"><bsdf type="diffuse">
            <texture name="reflectance" type="checkerboard"><float name="color0" value="0.05"/><float name="color1" value="0.3"/></texture>
        </bsdf></shape>
        </scene>"#
    ));
    let colours = |p: &Param| match p {
        Param::Texture(t) => match &**t {
            crate::material::TextureSpec::Checkerboard { color0, color1, .. } => (color0.x, color1.x),
            other => panic!("{other:?}"),
        },
        other => panic!("{other:?}"),
    };
    match &*b.scene.primitives[0].material {
        Material::RoughConductor { microfacet, .. } => assert_eq!(colours(&microfacet.alpha_u), (0.3, 0.05)),
        other => panic!("{other:?}"),
    }
    match &*b.scene.primitives[1].material {
        Material::Diffuse { reflectance } => assert_eq!(colours(reflectance), (0.05, 0.3)),
        other => panic!("{other:?}"),
    }
}

#[test]
fn principled_takes_mitsubas_defaults_and_parameters() {
    let b = built(&format!(
        r#"<scene version="3.0.0">{SENSOR}
        <shape type="sphere"><bsdf type="principled"/></shape>
        <shape type="sphere"><bsdf type="principled">
            <rgb name="base_color" value="0.8, 0.3, 0.1"/><float name="metallic" value="0.3"/>
            <float name="eta" value="1.33"/><float name="clearcoat" value="0.6"/>
            <texture name="roughness" type="checkerboard"/>
            <float name="main_specular_sampling_rate" value="0.5"/></bsdf></shape>
        <shape type="sphere"><bsdf type="principled"><float name="spec_trans" value="0.5"/>
            <float name="specular" value="0"/></bsdf></shape>
        <shape type="sphere"><bsdf type="principledthin"><float name="diff_trans" value="1.2"/>
            <texture name="eta" type="checkerboard"/></bsdf></shape>
        </scene>"#
    ));
    assert!(b.diagnostics.iter().all(|d| d.severity != Severity::Warning), "{:?}", b.diagnostics);
    let eta_of = |specular: f64| 2.0 / (1.0 - (0.08 * specular).sqrt()) - 1.0;
    match &*b.scene.primitives[0].material {
        Material::Principled(p) => {
            assert_eq!(p.base_color, Param::scalar(0.5));
            assert_eq!(p.roughness, Param::scalar(0.5));
            assert_eq!(p.metallic, Param::scalar(0.0));
            assert_eq!(p.clearcoat_gloss, Param::scalar(0.0));
            assert_eq!(p.eta, eta_of(0.5));
            assert_eq!(
                (p.specular_sampling_rate, p.clearcoat_sampling_rate, p.diffuse_sampling_rate),
                (1.0, 1.0, 1.0)
            );
        }
        other => panic!("{other:?}"),
    }
    match &*b.scene.primitives[1].material {
        Material::Principled(p) => {
            assert_eq!(p.base_color, Param::Constant(DVec3::new(0.8, 0.3, 0.1)));
            assert_eq!((p.metallic.clone(), p.clearcoat.clone()), (Param::scalar(0.3), Param::scalar(0.6)));
            assert!(matches!(p.roughness, Param::Texture(_)));
            assert_eq!((p.eta, p.specular_sampling_rate), (1.33, 0.5));
        }
        other => panic!("{other:?}"),
    }
    // With transmission, Mitsuba raises a zero `specular` to 1e-3.
    match &*b.scene.primitives[2].material {
        Material::Principled(p) => assert_eq!(p.eta, eta_of(1e-3)),
        other => panic!("{other:?}"),
    }
    match &*b.scene.primitives[3].material {
        Material::PrincipledThin(p) => {
            assert_eq!(p.diff_trans, Param::scalar(1.2));
            assert!(matches!(p.eta, Param::Texture(_)));
            assert_eq!(p.roughness, Param::scalar(0.5));
            assert_eq!(p.base_color, Param::scalar(0.5));
        }
        other => panic!("{other:?}"),
    }
    let both = errors(&format!(
        r#"<scene version="3.0.0">{SENSOR}<shape type="sphere"><bsdf type="principled">
            <float name="eta" value="1.5"/><float name="specular" value="0.5"/></bsdf></shape></scene>"#
    ));
    assert!(both[0].contains("`eta` or `specular`"), "{both:?}");
}

#[test]
fn a_textured_area_emitter_emits_its_texture() {
    let b = built(&format!(
        r#"<scene version="3.0.0">{SENSOR}
        <shape type="rectangle"><emitter type="area"><texture name="radiance" type="checkerboard"/></emitter></shape>
        <shape type="sphere"><emitter type="area"><rgb name="radiance" value="2, 3, 4"/></emitter></shape>
        </scene>"#
    ));
    assert!(b.diagnostics.iter().all(|d| d.severity != Severity::Warning), "{:?}", b.diagnostics);
    match &b.scene.emitters[..] {
        [
            Emitter::Area { primitive: 0, radiance: Param::Texture(t) },
            Emitter::Area { primitive: 1, radiance },
        ] => {
            assert!(matches!(**t, crate::material::TextureSpec::Checkerboard { .. }), "{t:?}");
            assert_eq!(*radiance, Param::Constant(DVec3::new(2.0, 3.0, 4.0)));
        }
        other => panic!("{other:?}"),
    }
    let refused = errors(&format!(
        r#"<scene version="3.0.0">{SENSOR}<shape type="sphere"><emitter type="area">
            <texture name="radiance" type="mesh_attribute"><string name="name" value="vertex_color"/></texture>
        </emitter></shape></scene>"#
    ));
    assert!(refused[0].contains("needs a mesh shape"), "{refused:?}");
}

/// A triangle whose corners are red, green and blue (`vertex_color`) and whose face is grey
/// (`face_color`), as a PLY file in a temporary folder with `scene` (its `{MESH}` replaced by
/// the mesh's name) beside it; the scene read.
fn with_coloured_triangle(
    scene: &str,
) -> (tempfile::TempDir, Result<super::Built, Vec<crate::scene::Diagnostic>>) {
    let dir = tempfile::tempdir().expect("temp dir");
    let ply = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n\
property float color_0\nproperty float color_1\nproperty float color_2\nelement face 1\n\
property list uchar int vertex_indices\nproperty float color_0\nproperty float color_1\nproperty float color_2\n\
end_header\n0 0 0 1 0 0\n1 0 0 0 1 0\n0 1 0 0 0 1\n3 0 1 2 0.5 0.5 0.5\n";
    std::fs::write(dir.path().join("tri.ply"), ply).expect("write the mesh");
    let path = dir.path().join("scene.xml");
    std::fs::write(&path, scene.replace("{MESH}", "tri.ply")).expect("write the scene");
    let doc = crate::scene::mitsuba::read_file(&path, &[]).expect("reads");
    (dir, build(&doc))
}

fn mesh_attribute_scene(name: &str, shape: &str) -> String {
    format!(
        r#"<scene version="3.0.0">{SENSOR}
<shape type="{shape}"><string name="filename" value="{{MESH}}"/>
    <bsdf type="diffuse"><texture type="mesh_attribute" name="reflectance">
        <string name="name" value="{name}"/><float name="scale" value="0.5"/></texture></bsdf>
</shape></scene>"#
    )
}

#[test]
fn a_mesh_attribute_reads_the_vertex_and_face_values_of_its_mesh() {
    for (name, b1, b2, expected) in [
        // Barycentric over the corners' colours.
        ("vertex_color", 0.25f32, 0.5f32, DVec3::new(0.25, 0.25, 0.5)),
        // Constant over the face.
        ("face_color", 0.25, 0.5, DVec3::splat(0.5)),
    ] {
        let (_dir, b) = with_coloured_triangle(&mesh_attribute_scene(name, "ply"));
        let b = b.unwrap_or_else(|e| panic!("{e:#?}"));
        let Material::Diffuse { reflectance: Param::Texture(t) } = &*b.scene.primitives[0].material else {
            panic!("{:?}", b.scene.primitives[0].material)
        };
        let crate::material::TextureSpec::MeshAttribute { name: n, scale, .. } = &**t else {
            panic!("{t:?}")
        };
        assert_eq!((n.as_str(), *scale), (name, 0.5));
        let crate::geometry::Shape::Mesh(mesh) = &b.scene.primitives[0].shape else { panic!("a mesh") };
        let attribute = mesh.attribute(name).expect("the attribute");
        let v = mesh.attribute_value(attribute, 0, b1, b2);
        assert!((v - expected).length() < 1e-6, "{name}: {v}");
    }
}

#[test]
fn a_mesh_attribute_the_shape_lacks_is_an_error_at_the_texture() {
    let (_dir, b) = with_coloured_triangle(&mesh_attribute_scene("vertex_colour", "ply"));
    let e = b.expect_err("no such attribute");
    let e = e.iter().find(|d| d.is_error()).expect("an error");
    assert_eq!(e.message.split(" of the shape at ").next(), Some("the mesh `tri.ply`"), "{}", e.message);
    assert!(
        e.message.ends_with(
            "scene.xml:8 has no mesh attribute `vertex_colour`: it has `vertex_color`, `face_color`"
        ),
        "{}",
        e.message
    );
    let at = e.location.as_ref().expect("a place");
    assert!(at.file.ends_with("scene.xml") && at.span.line == 9, "{at:?}");
    // Not a mesh: none.
    let (_dir, b) = with_coloured_triangle(
        &mesh_attribute_scene("vertex_color", "sphere")
            .replace(r#"<string name="filename" value="{MESH}"/>"#, ""),
    );
    let e = b.expect_err("a sphere has no attributes");
    assert!(
        e.iter().any(|d| d.message.contains("the `sphere` shape at") && d.message.ends_with("it has none")),
        "{e:#?}"
    );
    // Neither `vertex_` nor `face_`.
    let (_dir, b) = with_coloured_triangle(&mesh_attribute_scene("color", "ply"));
    let e = b.expect_err("a bad name");
    assert!(e.iter().any(|d| d.message.contains("starts with `vertex_` or `face_`, not `color`")), "{e:#?}");
}

fn projector(inner: &str) -> String {
    format!(
        r#"<scene version="3.0.0">{SENSOR}
<emitter type="projector">
    <transform name="to_world"><lookat origin="0, 0, 0" target="0, 0, 1" up="0, 1, 0"/></transform>
    {inner}
</emitter></scene>"#
    )
}

#[test]
fn a_projector_keeps_its_image_field_of_view_and_frame() {
    let b = built(&projector(
        r#"<float name="fov" value="90"/><float name="scale" value="2"/><rgb name="irradiance" value="1, 2, 3"/>"#,
    ));
    let Emitter::Projector { irradiance, scale, tan_half, fov_axis, to_world, to_local } =
        &b.scene.emitters[0]
    else {
        panic!("{:?}", b.scene.emitters)
    };
    assert_eq!(
        (irradiance, *scale, *fov_axis),
        (&Param::Constant(DVec3::new(1.0, 2.0, 3.0)), 2.0, crate::light::FovAxis::X)
    );
    assert!((tan_half - 1.0).abs() < 1e-12);
    assert!((to_world.transform_vector3(DVec3::Z) - DVec3::Z).length() < 1e-12);
    assert!((*to_local * *to_world - glam::DMat4::IDENTITY).abs_diff_eq(glam::DMat4::ZERO, 1e-12));
    // Mitsuba's default: 50 mm on 35 mm film, along the diagonal.
    let b = built(&projector(r#"<rgb name="irradiance" value="1"/>"#));
    let Emitter::Projector { tan_half, fov_axis, .. } = &b.scene.emitters[0] else { panic!() };
    assert_eq!(*fov_axis, crate::light::FovAxis::Diagonal);
    assert!((tan_half - 36f64.hypot(24.0) / 100.0).abs() < 1e-12);
    // The horizontal half-angle of a diagonal field of view on a 2:1 image.
    assert!((crate::light::FovAxis::Diagonal.tan_half_x(1.0, 2.0) - 2.0 / 5f64.sqrt()).abs() < 1e-12);
    assert!((crate::light::FovAxis::Larger.tan_half_x(1.0, 0.5) - 0.5).abs() < 1e-12);
}

#[test]
fn a_projector_needs_an_irradiance_and_one_field_of_view() {
    let e = errors(&projector(r#"<float name="fov" value="30"/>"#));
    assert!(e.iter().any(|m| m.contains("needs an `irradiance`")), "{e:?}");
    let e = errors(&projector(
        r#"<float name="fov" value="30"/><string name="focal_length" value="35mm"/><rgb name="irradiance" value="1"/>"#,
    ));
    assert!(e.iter().any(|m| m.contains("not both")), "{e:?}");
    let e = errors(&projector(r#"<float name="fov" value="180"/><rgb name="irradiance" value="1"/>"#));
    assert!(e.iter().any(|m| m.contains("between 0 and 180")), "{e:?}");
}

#[test]
fn the_direct_integrator_keeps_its_sample_counts() {
    let scene = |inner: &str| {
        format!(r#"<scene version="3.0.0"><integrator type="direct">{inner}</integrator>{SENSOR}</scene>"#)
    };
    let direct = |inner: &str| built(&scene(inner)).scene.render.direct;
    use crate::scene::DirectSamples;
    assert_eq!(direct(""), Some(DirectSamples { emitter_samples: 1, bsdf_samples: 1 }));
    assert_eq!(
        direct(r#"<integer name="emitter_samples" value="0"/><integer name="bsdf_samples" value="3"/>"#),
        Some(DirectSamples { emitter_samples: 0, bsdf_samples: 3 })
    );
    assert_eq!(
        direct(r#"<integer name="shading_samples" value="4"/>"#),
        Some(DirectSamples { emitter_samples: 4, bsdf_samples: 4 })
    );
    assert_eq!(built(&scene("")).scene.render.max_depth, Some(2));
    let e = errors(&scene(
        r#"<integer name="emitter_samples" value="0"/><integer name="bsdf_samples" value="0"/>"#,
    ));
    assert!(e.iter().any(|m| m.contains("at least one emitter or BSDF sample")), "{e:?}");
    let e = errors(&scene(
        r#"<integer name="shading_samples" value="2"/><integer name="bsdf_samples" value="1"/>"#,
    ));
    assert!(e.iter().any(|m| m.contains("not both")), "{e:?}");
    let e = errors(&scene(r#"<integer name="bsdf_samples" value="-1"/>"#));
    assert!(e.iter().any(|m| m.contains("`bsdf_samples` must be from 0")), "{e:?}");
    // The path integrator has none.
    let b = built(&format!(r#"<scene version="3.0.0"><integrator type="path"/>{SENSOR}</scene>"#));
    assert_eq!(b.scene.render.direct, None);
}

#[test]
fn spheres_and_disks_have_mitsubas_texture_coordinates() {
    let b = built(&format!(
        r#"<scene version="3.0.0">{SENSOR}
        <shape type="sphere"><transform name="to_world"><rotate z="1" angle="90"/><scale value="2"/></transform></shape>
        <shape type="disk"/>
        </scene>"#
    ));
    // The sphere's frame is `to_world`'s rotation: world +x is its local -y, world +y its +x.
    let crate::geometry::Shape::Sphere(s) = &b.scene.primitives[0].shape else { panic!("a sphere") };
    let local = |v: DVec3| crate::prepare::sphere_local(s, v);
    assert!(
        close(local(DVec3::X), -DVec3::Y)
            && close(local(DVec3::Y), DVec3::X)
            && close(local(DVec3::Z), DVec3::Z)
    );
    assert!(close(crate::prepare::sphere_world(s, DVec3::X), DVec3::Y));
    // The disk: `v` is the angle over a turn, even near the centre.
    let crate::geometry::Shape::Mesh(m) = &b.scene.primitives[1].shape else { panic!("a mesh") };
    let index = 100;
    let p = m.point_at(index, 0.01, 0.01);
    // Course order `(t, s)`: `s` is Mitsuba's `u`.
    let (v, u) = m.texture_coordinates(index, 0.01, 0.01);
    let angle = p.y.atan2(p.x) / std::f64::consts::TAU;
    assert!((u - p.truncate().length()).abs() < 1e-4, "u {u} at radius {}", p.truncate().length());
    assert!((v - angle).abs() < 1e-3, "v {v} at angle {angle}");
}

#[test]
fn a_crop_window_renders_its_part_of_the_film() {
    for sensor in ["perspective", "orthographic", "thinlens"] {
        let scene = |crop: &str| {
            format!(
                r#"<scene version="3.0.0"><sensor type="{sensor}"><float name="fov" value="50"/>
                <transform name="to_world"><lookat origin="1, 2, 5" target="0, 0, 0" up="0, 1, 0"/></transform>
                <film type="hdrfilm"><integer name="width" value="64"/><integer name="height" value="32"/>{crop}</film>
                </sensor></scene>"#
            )
        };
        let full = built(&scene("")).scene.camera;
        let cropped = built(&scene(
            r#"<integer name="crop_offset_x" value="40"/><integer name="crop_offset_y" value="5"/>
            <integer name="crop_width" value="16"/><integer name="crop_height" value="20"/>"#,
        ))
        .scene
        .camera;
        assert_eq!((cropped.image_width, cropped.image_height), (16, 20));
        let a = crate::camera::Camera::new(&full, 64, 32, 1.0);
        let b = crate::camera::Camera::new(&cropped, 16, 20, 1.0);
        for (x, y) in [(0.0, 0.0), (16.0, 20.0), (3.5, 11.25)] {
            let (ra, rb) = (a.ray(40.0 + x, 5.0 + y, (0.5, 0.5)), b.ray(x, y, (0.5, 0.5)));
            assert!(
                close(ra.origin, rb.origin) && close(ra.dir, rb.dir),
                "{sensor} ({x}, {y}): {ra:?} {rb:?}"
            );
        }
    }
    let e = errors(&format!(
        r#"<scene version="3.0.0">{}</scene>"#,
        SENSOR.replace("<rfilter", r#"<integer name="crop_width" value="65"/><rfilter"#)
    ));
    assert!(
        e.iter()
            .any(|m| m.contains("crop window (65x32 at 0, 0) must be a non-empty part of the 64x32 film")),
        "{e:?}"
    );
}
