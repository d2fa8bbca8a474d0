//! `<shape>` plugins to primitives: meshes (`obj`, `ply`, `serialized`) read and moved to world
//! space here, Mitsuba's analytic shapes (`sphere` exactly; `rectangle` and `cube` as their
//! exact triangles; `disk` and `cylinder` as fine triangle meshes), shape groups and their
//! instances. A shape with an `area` emitter inside is a light.

use std::f64::consts::TAU;
use std::path::PathBuf;
use std::sync::Arc;

use glam::{DMat3, DMat4, DVec3};

use super::super::{Plugin, PluginKind};
use super::{Builder, Props};
use crate::base::diagnostic::clip;
use crate::geometry::mesh::smooth_normals;
use crate::geometry::mesh_file::MeshData;
use crate::geometry::obj::load_obj;
use crate::geometry::ply::read_ply;
use crate::geometry::serialized::read_serialized;
use crate::geometry::{MeshTransform, MeshVertices, Shape, Sphere, TriangleIndices, TriangleMesh};
use crate::light::Emitter;
use crate::material::{Material, Param, TextureSpec};
use crate::scene::{Diagnostic, Primitive, Severity};

/// Segments around the circle of a `disk` or `cylinder`: the area of the polygon is within
/// 2.6e-5 of the circle's.
pub const CIRCLE_SEGMENTS: u32 = 512;

/// Most triangles of all a scene's meshes together (instances count their copies): as many as
/// one mesh file may hold.
pub const MAX_SCENE_TRIANGLES: usize = crate::geometry::obj::MAX_TRIANGLES;

/// `u32::MAX`: no index (no normals, no texture coordinates).
const NONE: u32 = u32::MAX;

impl<'a> Builder<'a> {
    /// A shape of the scene (or of an instance, moved by `parent`).
    pub(super) fn shape(&mut self, plugin: &'a Plugin, parent: Option<DMat4>) -> Result<(), Diagnostic> {
        let props = Props::new(self.doc, plugin);
        match props.type_name() {
            // A group is drawn only through its instances.
            "shapegroup" => {
                let _ = props.children(PluginKind::Shape);
                if parent.is_some() {
                    return Err(props.error("a shape group cannot be inside another"));
                }
                self.finish(&props);
                return Ok(());
            }
            "instance" => return self.instance(&props, parent),
            _ => {}
        }
        let Some(shape) = self.geometry(&props, parent.unwrap_or(DMat4::IDENTITY))? else {
            return Ok(());
        };
        let material = self.shape_material(&props)?;
        check_mesh_attributes(&props, &shape, &material)?;
        let index = self.scene.primitives.len() as u32;
        self.scene.primitives.push(Primitive { shape, material });
        for (_, emitter) in props.children(PluginKind::Emitter) {
            let e = Props::new(self.doc, emitter);
            if e.type_name() != "area" {
                return Err(e.error(format!(
                    "a shape holds only `area` emitters, not `{}`",
                    crate::base::diagnostic::clip(e.type_name())
                )));
            }
            let radiance = self.param(&e, "radiance", 1.0)?;
            if let crate::material::Param::Texture(t) = &radiance
                && matches!(**t, crate::material::TextureSpec::MeshAttribute { .. })
                && !matches!(self.scene.primitives[index as usize].shape, Shape::Mesh(_))
            {
                return Err(e.error("a `mesh_attribute` radiance needs a mesh shape"));
            }
            self.finish(&e);
            self.push_emitter(Emitter::Area { primitive: index, radiance });
        }
        for ignored in ["id", "interior", "exterior"] {
            props.ignore(ignored);
        }
        for kind in [PluginKind::Medium, PluginKind::Texture] {
            for (_, p) in props.children(kind) {
                self.warn(&Props::new(self.doc, p), "the shape is rendered without it");
            }
        }
        self.finish(&props);
        Ok(())
    }

    /// `instance`: the shapes of a shape group, moved by the instance's `to_world`.
    fn instance(&mut self, props: &Props<'a>, parent: Option<DMat4>) -> Result<(), Diagnostic> {
        if parent.is_some() {
            return Err(props.error("an instance cannot be inside a shape group"));
        }
        let to_world = props.transform("to_world")?;
        let groups = props.children(PluginKind::Shape);
        let Some((_, group)) = groups.first().filter(|(_, g)| g.type_name == "shapegroup") else {
            return Err(props.error("an `instance` refers to a `shapegroup` (`<ref id=\"...\"/>`)"));
        };
        self.finish(props);
        for (_, shape) in self.doc.children(group).filter(|(_, p)| p.kind == PluginKind::Shape) {
            self.shape(shape, Some(to_world))?;
        }
        Ok(())
    }

    /// The geometry of a shape, in world space; `None` for a shape rayterra does not have (with a
    /// warning).
    fn geometry(&mut self, props: &Props<'a>, parent: DMat4) -> Result<Option<Shape>, Diagnostic> {
        let to_world = parent * props.transform("to_world")?;
        if to_world.determinant() == 0.0 || !to_world.is_finite() {
            return Err(props.error("the shape's `to_world` is singular"));
        }
        let flip = props.boolean("flip_normals", false)?;
        let face_normals = props.boolean("face_normals", false)?;
        let mesh = match props.type_name() {
            "obj" => {
                let path = self.mesh_path(props)?;
                let flip_uv = props.boolean("flip_tex_coords", true)?;
                let obj = load_obj(&path, &MeshTransform::default())
                    .map_err(|e| props.error(format!("the mesh cannot be read: {e}")))?;
                self.inputs.push(path);
                let mut vertices = (*obj.vertices).clone();
                if flip_uv {
                    for uv in &mut vertices.uvs {
                        uv[1] = 1.0 - uv[1];
                    }
                }
                let mut triangles: Vec<TriangleIndices> =
                    obj.groups.into_iter().flat_map(|(_, t)| t).collect();
                if triangles.is_empty() {
                    return Err(props.error("the mesh has no triangles"));
                }
                if face_normals {
                    triangles.iter_mut().for_each(|t| t.normal = [NONE; 3]);
                }
                Indexed { vertices, triangles }
            }
            "ply" | "serialized" => {
                let path = self.mesh_path(props)?;
                let data = if props.type_name() == "ply" {
                    read_ply(&path)
                } else {
                    let index = props.integer("shape_index", 0)?;
                    let index = u32::try_from(index)
                        .map_err(|_| props.error(format!("`shape_index` must be 0 or more, not {index}")))?;
                    read_serialized(&path, index)
                }
                .map_err(|e| props.error(format!("the mesh cannot be read: {e}")))?;
                self.inputs.push(path);
                if data.triangles.is_empty() {
                    return Err(props.error("the mesh has no triangles"));
                }
                Indexed::from_data(data, face_normals)
            }
            "sphere" => {
                let centre = props.vector("center", DVec3::ZERO)?;
                let radius = props.positive("radius", 1.0)?;
                if flip {
                    return Err(props.error("`flip_normals` on a sphere is not supported"));
                }
                let linear = DMat3::from_mat4(to_world);
                let scales = [linear.x_axis.length(), linear.y_axis.length(), linear.z_axis.length()];
                let uniform = scales.iter().all(|s| (s - scales[0]).abs() <= 1e-6 * scales[0]);
                let orthogonal = linear.x_axis.dot(linear.y_axis).abs() <= 1e-6 * scales[0] * scales[1]
                    && linear.x_axis.dot(linear.z_axis).abs() <= 1e-6 * scales[0] * scales[2];
                if !uniform || !orthogonal {
                    return Err(props.error("a sphere's `to_world` must scale it alike along every axis"));
                }
                // Its frame (for its texture coordinates): `to_world`'s local `+z` and `+y`.
                let sphere = Sphere::with_frame(
                    to_world.transform_point3(centre),
                    radius * scales[0],
                    linear.z_axis / scales[2],
                    linear.y_axis / scales[1],
                )
                .map_err(|e| props.error(e.to_string()))?;
                self.finish(props);
                return Ok(Some(Shape::Sphere(sphere)));
            }
            "rectangle" => Indexed::rectangle(),
            "cube" => Indexed::cube(),
            "disk" => Indexed::disk(),
            "cylinder" => {
                let p0 = props.vector("p0", DVec3::ZERO)?;
                let p1 = props.vector("p1", DVec3::Z)?;
                let radius = props.positive("radius", 1.0)?;
                let Some(axis) = (p1 - p0).try_normalize() else {
                    return Err(props.error("a cylinder's `p0` and `p1` must differ"));
                };
                let (t, b) = crate::base::sampling::orthonormal_basis(axis);
                let local = DMat4::from_cols(
                    (t * radius).extend(0.0),
                    (b * radius).extend(0.0),
                    (p1 - p0).extend(0.0),
                    p0.extend(1.0),
                );
                let mesh = Indexed::cylinder();
                self.count_triangles(props, mesh.triangles.len())?;
                return Ok(Some(mesh.into_shape(to_world * local, flip)));
            }
            _ => {
                self.warn(props, "the scene is rendered without this shape");
                super::bsdfs::mark_all_read(props);
                return Ok(None);
            }
        };
        self.count_triangles(props, mesh.triangles.len())?;
        Ok(Some(mesh.into_shape(to_world, flip)))
    }

    /// Counts a mesh's triangles against [`MAX_SCENE_TRIANGLES`] (instances copy their group's
    /// meshes, so a small file could otherwise ask for any number), refusing before the copy.
    fn count_triangles(&mut self, props: &Props<'a>, triangles: usize) -> Result<(), Diagnostic> {
        self.triangles = self.triangles.saturating_add(triangles);
        if self.triangles > MAX_SCENE_TRIANGLES {
            return Err(props.error(format!(
                "the scene's meshes hold more than {MAX_SCENE_TRIANGLES} triangles with this one; \
                 rayterra renders at most that many"
            )));
        }
        Ok(())
    }

    /// The mesh file a shape names (`filename`), found as Mitsuba finds it.
    fn mesh_path(&self, props: &Props<'a>) -> Result<PathBuf, Diagnostic> {
        let (name, pos) =
            props.string("filename")?.ok_or_else(|| props.error("the shape needs a `filename`"))?;
        self.doc.resolve_file(name).ok_or_else(|| {
            props.error_at(
                pos,
                format!(
                    "the mesh `{}` is not found (looked for in {})",
                    crate::base::diagnostic::clip(name),
                    self.looked_in()
                ),
            )
        })
    }
}

/// Refuses a `mesh_attribute` texture of `material` that `shape` lacks (Mitsuba's "Invalid
/// attribute requested" when it renders), at the texture, naming the shape's file and line and
/// the attributes it has.
fn check_mesh_attributes(props: &Props<'_>, shape: &Shape, material: &Material) -> Result<(), Diagnostic> {
    for param in material.params() {
        let Param::Texture(t) = param else { continue };
        let TextureSpec::MeshAttribute { name, location, .. } = &**t else { continue };
        let mesh = match shape {
            Shape::Mesh(m) => Some(m),
            _ => None,
        };
        if mesh.is_some_and(|m| m.attribute(name).is_some()) {
            continue;
        }
        let at = props.error("").location.map_or(String::new(), |l| format!("{}:{}", l.file, l.span.line));
        let what = match props.string("filename")? {
            Some((file, _)) => format!("the mesh `{}` of the shape at {at}", clip(file)),
            None => format!("the `{}` shape at {at}", props.type_name()),
        };
        let has: Vec<String> = mesh
            .map(|m| m.vertices().attributes.iter().map(|a| format!("`{}`", a.name)).collect())
            .unwrap_or_default();
        let has =
            if has.is_empty() { "it has none".to_owned() } else { format!("it has {}", has.join(", ")) };
        return Err(Diagnostic {
            severity: Severity::Error,
            message: format!("{what} has no mesh attribute `{}`: {has}", clip(name)),
            location: Some(location.clone()),
            notes: Vec::new(),
        });
    }
    Ok(())
}

/// A mesh in its own coordinates: vertices and indexed triangles.
struct Indexed {
    vertices: MeshVertices,
    triangles: Vec<TriangleIndices>,
}

impl Indexed {
    /// From a mesh file's data: per-vertex attributes, normals averaged when the file has none
    /// (Mitsuba recomputes them), or none with `face_normals`.
    fn from_data(data: MeshData, face_normals: bool) -> Indexed {
        let normals = match (face_normals, data.normals) {
            (true, _) => Vec::new(),
            (false, Some(n)) => n,
            (false, None) => smooth_normals(&data.positions, &data.triangles),
        };
        let has_uv = data.uvs.is_some();
        let has_n = !normals.is_empty();
        let triangles = data
            .triangles
            .iter()
            .map(|&t| TriangleIndices {
                position: t,
                normal: if has_n { t } else { [NONE; 3] },
                uv: if has_uv { t } else { [NONE; 3] },
            })
            .collect();
        Indexed {
            vertices: MeshVertices {
                positions: data.positions,
                normals,
                uvs: data.uvs.unwrap_or_default(),
                attributes: data.attributes,
            },
            triangles,
        }
    }

    /// Quads as two triangles each, every vertex with its normal and texture coordinates.
    fn quads(corners: &[([f64; 3], [f64; 3], [f64; 2])]) -> Indexed {
        let mut v = MeshVertices::default();
        let mut triangles = Vec::new();
        for quad in corners.chunks(4) {
            let base = v.positions.len() as u32;
            for (p, n, uv) in quad {
                v.positions.push(p.map(|x| x as f32));
                v.normals.push(n.map(|x| x as f32));
                v.uvs.push(uv.map(|x| x as f32));
            }
            for t in [[0, 1, 2], [0, 2, 3]] {
                let t = t.map(|i| base + i);
                triangles.push(TriangleIndices { position: t, normal: t, uv: t });
            }
        }
        Indexed { vertices: v, triangles }
    }

    /// Mitsuba's `rectangle`: `[-1, 1]^2` in the plane `z = 0`, facing `+z`.
    fn rectangle() -> Indexed {
        let n = [0.0, 0.0, 1.0];
        Indexed::quads(&[
            ([-1.0, -1.0, 0.0], n, [0.0, 0.0]),
            ([1.0, -1.0, 0.0], n, [1.0, 0.0]),
            ([1.0, 1.0, 0.0], n, [1.0, 1.0]),
            ([-1.0, 1.0, 0.0], n, [0.0, 1.0]),
        ])
    }

    /// Mitsuba's `cube`: `[-1, 1]^3`, faces outwards.
    fn cube() -> Indexed {
        let mut corners = Vec::new();
        for axis in 0..3 {
            for sign in [-1.0, 1.0] {
                // Two tangents making (t, b, n) right-handed, so the quad winds outwards.
                let mut n = [0.0; 3];
                n[axis] = sign;
                let nv = DVec3::from(n);
                let t = DVec3::from({
                    let mut t = [0.0; 3];
                    t[(axis + 1) % 3] = 1.0;
                    t
                });
                let b = nv.cross(t);
                for (i, (su, sv)) in
                    [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)].into_iter().enumerate()
                {
                    let _ = i;
                    let p = nv + t * su + b * sv;
                    corners.push((p.to_array(), n, [(su + 1.0) / 2.0, (sv + 1.0) / 2.0]));
                }
            }
        }
        Indexed::quads(&corners)
    }

    /// Mitsuba's `disk`: the unit disk in the plane `z = 0`, facing `+z`, as a fan of
    /// [`CIRCLE_SEGMENTS`] triangles; texture coordinates polar, as Mitsuba's: `u` the radius,
    /// `v` the angle over a turn from `+x`. The centre has one texture coordinate per triangle
    /// (`v` the triangle's middle angle), so that `v` stays the angle towards the centre (within
    /// half a segment, 1/1024 of a turn) rather than running to 0 there.
    fn disk() -> Indexed {
        let mut v = MeshVertices::default();
        v.positions.push([0.0; 3]);
        v.normals.push([0.0, 0.0, 1.0]);
        let n = CIRCLE_SEGMENTS;
        for i in 0..=n {
            let phi = TAU * i as f64 / n as f64;
            v.positions.push([phi.cos() as f32, phi.sin() as f32, 0.0]);
            v.normals.push([0.0, 0.0, 1.0]);
            v.uvs.push([1.0, (i as f64 / n as f64) as f32]);
        }
        // The centre's texture coordinates, one per triangle, after the rim's n + 1.
        for i in 0..n {
            v.uvs.push([0.0, ((i as f64 + 0.5) / n as f64) as f32]);
        }
        let triangles = (0..n)
            .map(|i| {
                let t = [0, i + 1, i + 2];
                TriangleIndices { position: t, normal: t, uv: [n + 1 + i, i, i + 1] }
            })
            .collect();
        Indexed { vertices: v, triangles }
    }

    /// Mitsuba's `cylinder` in its own frame: the open tube of radius 1 around the `z` axis from
    /// `z = 0` to `z = 1`, facing outwards; `u` the angle over a turn, `v` the height.
    fn cylinder() -> Indexed {
        let mut v = MeshVertices::default();
        let n = CIRCLE_SEGMENTS;
        for i in 0..=n {
            let phi = TAU * i as f64 / n as f64;
            let (s, c) = (phi.sin() as f32, phi.cos() as f32);
            let u = (i as f64 / n as f64) as f32;
            for z in [0.0, 1.0] {
                v.positions.push([c, s, z]);
                v.normals.push([c, s, 0.0]);
                v.uvs.push([u, z]);
            }
        }
        let mut triangles = Vec::new();
        for i in 0..n {
            let (a, b, c, d) = (2 * i, 2 * i + 1, 2 * i + 2, 2 * i + 3);
            for t in [[a, c, d], [a, d, b]] {
                triangles.push(TriangleIndices { position: t, normal: t, uv: t });
            }
        }
        Indexed { vertices: v, triangles }
    }

    /// The mesh moved by `to_world` (normals by its inverse transpose), its faces turned with
    /// `flip`.
    fn into_shape(mut self, to_world: DMat4, flip: bool) -> Shape {
        let normal_matrix = DMat3::from_mat4(to_world).inverse().transpose();
        for p in &mut self.vertices.positions {
            *p = to_world.transform_point3(DVec3::from(p.map(f64::from))).as_vec3().to_array();
        }
        for n in &mut self.vertices.normals {
            let mut w = (normal_matrix * DVec3::from(n.map(f64::from))).normalize_or(DVec3::Z);
            if flip {
                w = -w;
            }
            *n = w.as_vec3().to_array();
        }
        if flip {
            for t in &mut self.triangles {
                t.position.swap(1, 2);
                t.normal.swap(1, 2);
                t.uv.swap(1, 2);
            }
        }
        Shape::Mesh(Arc::new(TriangleMesh::new(Arc::new(self.vertices), &self.triangles)))
    }
}
