//! Wavefront OBJ files for `primitive mesh` and `primitive polyhedron`, read with the `tobj`
//! crate: `v`, `vt`, `vn`, `f` with polygons fanned into triangles, indices `i`, `i/j`, `i//k`,
//! `i/j/k` (negative ones count back from the last vertex), vertex normals from the file or
//! averaged over the faces around each vertex, and `mtllib` / `usemtl` materials (their `Kd` is
//! the colour).
//!
//! Before `tobj` parses a file, one pass over its lines checks what `tobj` would accept silently
//! or report without a place: faces with fewer than three vertices and indices out of range. Every
//! problem is reported with the OBJ file's own line.

use std::io::{BufRead, Read};
use std::path::{Path, PathBuf};
use std::sync::Arc;

use glam::{DMat3, DVec3};

use super::mesh::{MeshVertices, TriangleIndices, smooth_normals};
use crate::base::diagnostic::{Location, clip};

/// Largest OBJ file read, in bytes (2 GiB: about 40 million triangles).
pub const MAX_OBJ_BYTES: u64 = 2 << 30;
/// Largest material library (`.mtl`) read, in bytes.
pub const MAX_MTL_BYTES: u64 = 64 << 20;
/// Most triangles one mesh file may hold after fanning polygons: as many as one BVH holds (about
/// 134 million, whose indices alone take 1.5 GiB).
pub const MAX_TRIANGLES: usize = crate::accel::wide::MAX_ITEMS;

/// Where a mesh's vertices go: `O + size * Rz(az) Ry(ay) Rx(ax) v` (rotate about x first, then
/// y, then z, right-handed; then scale per axis; then translate).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MeshTransform {
    /// Translation (`O=`).
    pub origin: DVec3,
    /// Scale per axis (`size=` / `scale=`), no component zero.
    pub scale: DVec3,
    /// Rotation angles about x, y and z, in radians (`angles=` is in degrees, `rotation=` in
    /// radians).
    pub rotation: DVec3,
}

impl Default for MeshTransform {
    fn default() -> MeshTransform {
        MeshTransform { origin: DVec3::ZERO, scale: DVec3::ONE, rotation: DVec3::ZERO }
    }
}

impl MeshTransform {
    /// The rotation `Rz Ry Rx`.
    pub fn rotation_matrix(&self) -> DMat3 {
        DMat3::from_rotation_z(self.rotation.z)
            * DMat3::from_rotation_y(self.rotation.y)
            * DMat3::from_rotation_x(self.rotation.x)
    }

    /// Where a vertex of the file goes.
    pub fn point(&self, v: DVec3) -> DVec3 {
        self.origin + self.scale * (self.rotation_matrix() * v)
    }
}

/// A mesh file named by a scene (`file=` / `mesh=`), before it is loaded.
#[derive(Clone, Debug, PartialEq)]
pub struct MeshFile {
    /// The path as written (found like a texture: next to the scene file, then in the
    /// `--textures` folders, then in the working directory).
    pub path: String,
    /// Where the path is written in the scene file.
    pub location: Location,
    /// Where the vertices go.
    pub transform: MeshTransform,
}

/// A mesh file read into world space.
#[derive(Debug)]
pub struct LoadedObj {
    /// The vertices, shared by all groups.
    pub vertices: Arc<MeshVertices>,
    /// The triangles, by material: the `Kd` colour of the `usemtl` material (`None`: the
    /// scene's material), each with its triangles.
    pub groups: Vec<(Option<DVec3>, Vec<TriangleIndices>)>,
    /// Things worth a warning (a material library that cannot be read, unknown materials).
    pub warnings: Vec<String>,
    /// The material libraries read (or tried), beside the OBJ file.
    pub material_libraries: Vec<PathBuf>,
}

impl LoadedObj {
    /// Number of triangles.
    pub fn triangle_count(&self) -> usize {
        self.groups.iter().map(|g| g.1.len()).sum()
    }
}

/// An OBJ file that cannot be used.
#[derive(Debug, thiserror::Error)]
#[error("{}", match .line { Some(l) => format!("{}:{l}: {}", .file, .message), None => format!("{}: {}", .file, .message) })]
pub struct ObjError {
    /// The file as shown to the user.
    pub file: String,
    /// The 1-based line of the file, when the problem has one.
    pub line: Option<u32>,
    /// What is wrong.
    pub message: String,
}

/// Reads the OBJ file at `path` and moves its vertices by `transform` ([`parse_obj`] on the
/// file's bytes, its material libraries read beside it).
pub fn load_obj(path: &Path, transform: &MeshTransform) -> Result<LoadedObj, ObjError> {
    let file = path.display().to_string();
    let fail = |message: String| ObjError { file: file.clone(), line: None, message };
    let cannot_read = |e: std::io::Error| match atomic_file::not_regular(&e) {
        Some(_) => fail(e.to_string()),
        None => fail(format!("cannot read it: {e}")),
    };
    let opened = atomic_file::open_regular(path).map_err(cannot_read)?;
    let size = opened.metadata().map_err(cannot_read)?.len();
    if size > MAX_OBJ_BYTES {
        return Err(fail(format!("it is {size} bytes; meshes of at most {MAX_OBJ_BYTES} bytes are read")));
    }
    let mut bytes = Vec::with_capacity(size as usize);
    // The bound is on what is read: the file may grow meanwhile.
    opened.take(MAX_OBJ_BYTES + 1).read_to_end(&mut bytes).map_err(cannot_read)?;
    if bytes.len() as u64 > MAX_OBJ_BYTES {
        return Err(fail(format!("it is over {MAX_OBJ_BYTES} bytes; meshes of at most that are read")));
    }
    let dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
    parse_obj(&bytes, &file, &dir, transform)
}

/// Reads the bytes of an OBJ file, named `file` in messages, whose material libraries (`mtllib`)
/// are read from the folder `dir` (at most [`MAX_MTL_BYTES`] each, regular files only), and
/// moves its vertices by `transform`.
pub fn parse_obj(
    bytes: &[u8],
    file: &str,
    dir: &Path,
    transform: &MeshTransform,
) -> Result<LoadedObj, ObjError> {
    let fail = |line: Option<u32>, message: String| ObjError { file: file.to_owned(), line, message };
    // Only ASCII matters outside comments (which may be GBK, as in the course's files).
    let text = String::from_utf8_lossy(bytes);
    let text = joined_continuations(&text);
    check_faces(&text).map_err(|(line, message)| fail(Some(line), message))?;
    let text = without_polylines(&text);
    let mut reader = LineReader { data: text.as_bytes(), pos: 0 };
    let options =
        tobj::LoadOptions { triangulate: true, single_index: false, ignore_points: true, ignore_lines: true };
    let material_libraries = std::cell::RefCell::new(Vec::new());
    // Why the last material library could not be read, in our words rather than `tobj`'s.
    let library_problem = std::cell::RefCell::new(None);
    let (models, materials) = tobj::load_obj_buf(&mut reader, &options, |p| {
        let path = dir.join(p);
        material_libraries.borrow_mut().push(path.clone());
        let bytes = read_material_library(&path).map_err(|problem| {
            *library_problem.borrow_mut() = Some(problem);
            tobj::LoadError::OpenFileFailed
        })?;
        tobj::load_mtl_buf(&mut bytes.as_slice())
    })
    .map_err(|e| fail(Some(reader.line()), format!("{e}")))?;
    let material_libraries = material_libraries.into_inner();
    let mut warnings = Vec::new();
    let materials = match materials {
        Ok(m) => m,
        Err(e) => {
            if let Some((line, lib)) = first_mtllib(&text) {
                let why = library_problem.into_inner().unwrap_or_else(|| e.to_string());
                warnings.push(format!(
                    "{file}:{line}: cannot read the material library `{}` ({why}); the scene's material is used",
                    clip(&lib)
                ));
            }
            Vec::new()
        }
    };
    let transform_normal = {
        let r = transform.rotation_matrix();
        let inv_scale = transform.scale.recip();
        move |n: DVec3| (inv_scale * (r * n)).normalize_or(DVec3::Z)
    };
    let mut positions: Vec<[f32; 3]> = Vec::new();
    let mut normals: Vec<[f32; 3]> = Vec::new();
    let mut uvs: Vec<[f32; 2]> = Vec::new();
    let mut groups: Vec<(Option<usize>, Vec<TriangleIndices>)> = Vec::new();
    let has_uvs = models.iter().any(|m| !m.mesh.texcoord_indices.is_empty());
    let total: usize = models.iter().map(|m| m.mesh.indices.len() / 3).sum();
    if total > MAX_TRIANGLES {
        return Err(fail(None, format!("it has {total} triangles; at most {MAX_TRIANGLES} are read")));
    }
    for model in &models {
        let m = &model.mesh;
        let p0 = positions.len() as u32;
        let n0 = normals.len() as u32;
        let t0 = uvs.len() as u32;
        positions.extend(m.positions.chunks_exact(3).map(|p| {
            transform.point(DVec3::new(p[0] as f64, p[1] as f64, p[2] as f64)).as_vec3().to_array()
        }));
        let tris: Vec<[u32; 3]> = m.indices.chunks_exact(3).map(|t| [t[0], t[1], t[2]]).collect();
        let file_normals = !m.normal_indices.is_empty() && !m.normals.is_empty();
        if file_normals {
            normals.extend(m.normals.chunks_exact(3).map(|n| {
                transform_normal(DVec3::new(n[0] as f64, n[1] as f64, n[2] as f64)).as_vec3().to_array()
            }));
        } else {
            let local: Vec<[f32; 3]> = positions[p0 as usize..].to_vec();
            normals.extend(smooth_normals(&local, &tris));
        }
        let model_uvs = !m.texcoord_indices.is_empty() && !m.texcoords.is_empty();
        if model_uvs {
            uvs.extend(m.texcoords.chunks_exact(2).map(|t| [t[0], t[1]]));
        }
        let material = m.material_id.filter(|&id| id < materials.len());
        if let Some(id) = m.material_id
            && id >= materials.len()
            && !materials.is_empty()
        {
            warnings.push(format!(
                "{file}: a `usemtl` material is not in the material library; the scene's material is used"
            ));
        }
        let group = match groups.iter().position(|g| g.0 == material) {
            Some(i) => i,
            None => {
                groups.push((material, Vec::new()));
                groups.len() - 1
            }
        };
        let out = &mut groups[group].1;
        for (k, t) in tris.iter().enumerate() {
            let normal = if file_normals {
                let n = &m.normal_indices[3 * k..3 * k + 3];
                [n[0] + n0, n[1] + n0, n[2] + n0]
            } else {
                [t[0] + n0, t[1] + n0, t[2] + n0]
            };
            let uv = if model_uvs {
                let u = &m.texcoord_indices[3 * k..3 * k + 3];
                [u[0] + t0, u[1] + t0, u[2] + t0]
            } else {
                [u32::MAX; 3]
            };
            out.push(TriangleIndices { position: [t[0] + p0, t[1] + p0, t[2] + p0], normal, uv });
        }
    }
    if !has_uvs {
        uvs.clear();
    }
    if positions.iter().flatten().any(|v| !v.is_finite()) {
        return Err(fail(None, "a vertex is not finite (after the mesh's transform)".into()));
    }
    let groups = groups
        .into_iter()
        .map(|(id, tris)| {
            let colour = id
                .and_then(|i| materials[i].diffuse)
                .map(|d| DVec3::new(d[0] as f64, d[1] as f64, d[2] as f64));
            (colour, tris)
        })
        .collect();
    Ok(LoadedObj {
        vertices: Arc::new(MeshVertices { positions, normals, uvs, attributes: Vec::new() }),
        groups,
        warnings,
        material_libraries,
    })
}

/// The bytes of the material library at `path`, if it is a regular file of at most
/// [`MAX_MTL_BYTES`] (not a device or a pipe that never ends); otherwise why not.
fn read_material_library(path: &Path) -> Result<Vec<u8>, String> {
    // Refused unless a regular file, without waiting on a named pipe.
    let file = atomic_file::open_regular(path).map_err(|e| e.to_string())?;
    let mut bytes = Vec::new();
    // A file may grow, or say it is empty (as those in /proc do): the bound is on what is read.
    file.take(MAX_MTL_BYTES + 1).read_to_end(&mut bytes).map_err(|e| e.to_string())?;
    if bytes.len() as u64 > MAX_MTL_BYTES {
        return Err(format!("it is over {MAX_MTL_BYTES} bytes"));
    }
    Ok(bytes)
}

/// The first `mtllib` line: its number and the library's name.
fn first_mtllib(text: &str) -> Option<(u32, String)> {
    text.lines().enumerate().find_map(|(i, l)| {
        let rest = l.trim_start().strip_prefix("mtllib")?;
        Some((i as u32 + 1, rest.trim().to_owned()))
    })
}

/// The text with every statement continued over several lines (a backslash ending a line, before
/// `\n` or `\r\n`) joined into one line where it starts: each backslash and the line break after
/// it become spaces, and the line breaks are put back after the statement as empty lines, so
/// every line keeps its number and an error in a joined statement names its first line.
/// Comments are never continued: a comment may end with the second byte of a GBK character,
/// which can be a backslash.
fn joined_continuations(text: &str) -> std::borrow::Cow<'_, str> {
    let continues = |line: &str| {
        let body = line.strip_suffix('\n').unwrap_or(line);
        let body = body.strip_suffix('\r').unwrap_or(body);
        body.ends_with('\\')
    };
    if !text.split_inclusive('\n').any(continues) {
        return text.into();
    }
    let mut out = String::with_capacity(text.len());
    let mut held_breaks = 0;
    let mut in_statement = false;
    for line in text.split_inclusive('\n') {
        let starts_comment = !in_statement && line.trim_start().starts_with('#');
        if continues(line) && !starts_comment {
            let body = line.strip_suffix('\n').unwrap_or(line);
            let body = body.strip_suffix('\r').unwrap_or(body);
            out.push_str(&body[..body.len() - 1]);
            out.push(' ');
            held_breaks += usize::from(line.ends_with('\n'));
            in_statement = true;
        } else {
            out.push_str(line);
            for _ in 0..held_breaks {
                out.push('\n');
            }
            held_breaks = 0;
            in_statement = false;
        }
    }
    // A backslash on the last line continues nothing.
    for _ in 0..held_breaks {
        out.push('\n');
    }
    out.into()
}

/// The text with every polyline (`l`) made a comment, byte for byte in place (so lines keep
/// their numbers): a polyline has no surface to hit, and `tobj` would read one of three or more
/// vertices as a polygon, its indices unchecked.
fn without_polylines(text: &str) -> std::borrow::Cow<'_, str> {
    let is_polyline = |line: &str| line.split_whitespace().next() == Some("l");
    if !text.lines().any(is_polyline) {
        return text.into();
    }
    let mut out = String::with_capacity(text.len());
    for line in text.split_inclusive('\n') {
        if is_polyline(line) {
            let indent = line.len() - line.trim_start().len();
            out.push_str(&line[..indent]);
            out.push('#');
            out.push_str(&line[indent + 1..]);
        } else {
            out.push_str(line);
        }
    }
    out.into()
}

/// Checks every `f` line: at least three vertices, and every index (`i`, `i/j`, `i//k`, `i/j/k`,
/// negative ones relative to the last vertex so far) within the vertices, texture coordinates and
/// normals defined before it. Returns the line and the problem.
fn check_faces(text: &str) -> Result<(), (u32, String)> {
    let (mut nv, mut nt, mut nn) = (0i64, 0i64, 0i64);
    for (i, line) in text.lines().enumerate() {
        let number = i as u32 + 1;
        let mut words = line.split_whitespace();
        match words.next() {
            Some("v") => nv += 1,
            Some("vt") => nt += 1,
            Some("vn") => nn += 1,
            Some("f") => {
                let mut corners = 0;
                for word in words {
                    corners += 1;
                    for (k, part) in word.split('/').enumerate() {
                        if part.is_empty() && k > 0 {
                            continue;
                        }
                        let (what, plural, count) = match k {
                            0 => ("vertex", "vertices", nv),
                            1 => ("texture coordinate", "texture coordinates", nt),
                            2 => ("normal", "normals", nn),
                            _ => {
                                return Err((
                                    number,
                                    format!("`{}` has more than three indices", clip(word)),
                                ));
                            }
                        };
                        let index: i64 = part.parse().map_err(|_| {
                            (
                                number,
                                format!(
                                    "`{}` is not a face corner (`v`, `v/vt`, `v//vn` or `v/vt/vn`)",
                                    clip(word)
                                ),
                            )
                        })?;
                        let valid = if index > 0 { index <= count } else { index < 0 && -index <= count };
                        if !valid {
                            return Err((
                                number,
                                format!(
                                    "{what} index {index} is out of range: {count} {} defined before this line",
                                    if count == 1 { format!("{what} is") } else { format!("{plural} are") }
                                ),
                            ));
                        }
                    }
                }
                if corners < 3 {
                    return Err((
                        number,
                        format!("a face needs at least 3 vertices, this one has {corners}"),
                    ));
                }
            }
            _ => {}
        }
    }
    Ok(())
}

/// A reader over the file's text that knows which line it stopped in (for `tobj`'s errors,
/// which have no place).
struct LineReader<'a> {
    data: &'a [u8],
    pos: usize,
}

impl LineReader<'_> {
    /// The 1-based line of the last byte read.
    fn line(&self) -> u32 {
        let read = &self.data[..self.pos];
        let breaks = read.iter().filter(|&&b| b == b'\n').count();
        let ended = read.last() == Some(&b'\n');
        (breaks + usize::from(!ended)).max(1) as u32
    }
}

impl Read for LineReader<'_> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        let n = buf.len().min(self.data.len() - self.pos);
        buf[..n].copy_from_slice(&self.data[self.pos..self.pos + n]);
        self.pos += n;
        Ok(n)
    }
}

impl BufRead for LineReader<'_> {
    fn fill_buf(&mut self) -> std::io::Result<&[u8]> {
        Ok(&self.data[self.pos..])
    }

    fn consume(&mut self, amt: usize) {
        self.pos = (self.pos + amt).min(self.data.len());
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn write(name: &str, text: &str) -> (tempfile::TempDir, std::path::PathBuf) {
        let dir = tempfile::tempdir().expect("temp dir");
        let path = dir.path().join(name);
        std::fs::write(&path, text).expect("write");
        (dir, path)
    }

    fn load(text: &str) -> Result<LoadedObj, ObjError> {
        let (_dir, path) = write("m.obj", text);
        load_obj(&path, &MeshTransform::default())
    }

    #[test]
    fn quads_are_fanned_and_negative_indices_count_back() {
        let m = load("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\nv 0 0 1\nf -1 -4 -3\n").expect("loads");
        assert_eq!(m.triangle_count(), 3);
        assert_eq!(m.vertices.positions.len(), 5);
        let tris = &m.groups[0].1;
        // The last face: vertex 5 (the last), then 2 and 3.
        let last = tris[2].position.map(|i| m.vertices.positions[i as usize]);
        assert_eq!(last, [[0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0]]);
    }

    #[test]
    fn missing_normals_are_smoothed_and_given_ones_are_kept() {
        let m = load("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").expect("loads");
        assert_eq!(m.vertices.normals, vec![[0.0, 0.0, 1.0]; 3]);
        let m =
            load("v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 1 0\nvt 0.5 0.25\nf 1/1/1 2/1/1 3/1/1\n").expect("loads");
        assert_eq!(m.vertices.normals, vec![[0.0, 1.0, 0.0]]);
        assert_eq!(m.vertices.uvs, vec![[0.5, 0.25]]);
        assert_eq!(m.groups[0].1[0].normal, [0, 0, 0]);
    }

    #[test]
    fn errors_name_the_obj_line() {
        let e = load("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n").expect_err("out of range");
        assert_eq!(e.line, Some(4));
        assert!(e.message.contains("vertex index 4 is out of range: 3 vertices"), "{e}");
        let e = load("v 0 0 0\nv 1 0 0\nf 1 2\n").expect_err("too few");
        assert_eq!(e.line, Some(3));
        assert!(e.message.contains("at least 3 vertices"), "{e}");
        let e = load("v 0 0 0\nv 1 0 x\nv 0 1 0\nf 1 2 3\n").expect_err("bad number");
        assert_eq!(e.line, Some(2), "{e}");
        // A file cut off in the middle of a line.
        let e = load("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nv 0.5 0.").expect_err("truncated");
        assert_eq!(e.line, Some(5), "{e}");
        let e = load("v 0 0 0\nf 1/x 1 1\n").expect_err("bad corner");
        assert_eq!(e.line, Some(2), "{e}");
        assert!(e.to_string().contains("m.obj:2: "), "{e}");
    }

    #[test]
    fn missing_material_library_is_a_warning_and_kd_is_the_colour() {
        let m = load("mtllib nowhere.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl red\nf 1 2 3\n").expect("loads");
        assert_eq!(m.warnings.len(), 1, "{:?}", m.warnings);
        assert!(m.warnings[0].contains("nowhere.mtl"));
        assert_eq!(m.groups[0].0, None);
        let dir = tempfile::tempdir().expect("temp dir");
        std::fs::write(dir.path().join("c.mtl"), "newmtl red\nKd 0.8 0.1 0.1\nnewmtl blue\nKd 0 0 1\n")
            .expect("write");
        let path = dir.path().join("m.obj");
        std::fs::write(
            &path,
            "mtllib c.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl red\nf 1 2 3\nusemtl blue\nf 1 3 2\nusemtl red\nf 2 3 1\n",
        )
        .expect("write");
        let m = load_obj(&path, &MeshTransform::default()).expect("loads");
        assert!(m.warnings.is_empty(), "{:?}", m.warnings);
        let colours: Vec<(Option<DVec3>, usize)> = m.groups.iter().map(|g| (g.0, g.1.len())).collect();
        assert_eq!(colours.len(), 2, "{colours:?}");
        assert!(
            colours.contains(&(
                Some(DVec3::new(0.800000011920929, 0.10000000149011612, 0.10000000149011612)),
                2
            ))
        );
        assert!(colours.contains(&(Some(DVec3::new(0.0, 0.0, 1.0)), 1)));
    }

    #[test]
    fn transform_rotates_x_then_y_then_z_then_scales_and_moves() {
        let t = MeshTransform {
            origin: DVec3::new(10.0, 0.0, 0.0),
            scale: DVec3::new(2.0, 3.0, 4.0),
            rotation: DVec3::new(std::f64::consts::FRAC_PI_2, 0.0, std::f64::consts::FRAC_PI_2),
        };
        // x rotation takes y to z; z rotation leaves z; scale 4; move.
        let p = t.point(DVec3::Y);
        assert!((p - DVec3::new(10.0, 0.0, 4.0)).length() < 1e-12, "{p}");
        // x rotation leaves x; z rotation takes x to y; scale 3.
        let p = t.point(DVec3::X);
        assert!((p - DVec3::new(10.0, 3.0, 0.0)).length() < 1e-12, "{p}");
    }

    #[test]
    fn material_libraries_that_are_not_regular_files_are_not_read() {
        // A device that never ends would be read forever.
        let obj = b"mtllib /dev/zero\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl red\nf 1 2 3\n";
        let m = parse_obj(obj, "m.obj", Path::new("."), &MeshTransform::default()).expect("loads");
        assert_eq!(m.warnings.len(), 1, "{:?}", m.warnings);
        assert!(
            m.warnings[0]
                .contains("m.obj:1: cannot read the material library `/dev/zero` (it is not a regular file)"),
            "{:?}",
            m.warnings
        );
    }

    /// Issue 31, defect 5: a backslash ending a line continues the statement on the next (with
    /// LF or CRLF line ends), and errors name the line where the statement starts.
    #[test]
    fn backslashes_continue_lines_and_errors_keep_their_lines() {
        for eol in ["\n", "\r\n"] {
            let text = [
                "v 0 0 0", "v 1 0 0", "v 0 1 0", "v 1 1 \\", "  0", "f 1 2 \\", " 3", "f 2 \\", "4 \\", "3",
                "",
            ]
            .join(eol);
            let obj = load(&text).unwrap_or_else(|e| panic!("{eol:?}: {e}"));
            assert_eq!(obj.vertices.positions.len(), 4, "{eol:?}");
            assert_eq!(obj.groups.iter().map(|g| g.1.len()).sum::<usize>(), 2, "{eol:?}");
            // The face that starts on line 4 (after a continued vertex) is wrong: line 4 it is.
            let text = ["v 0 0 \\", "0", "v 1 0 0", "f 1 2 \\", " 9", "v 0 1 0", "f 1 2 7", ""].join(eol);
            let error = load(&text).expect_err("out of range").to_string();
            assert!(error.contains("m.obj:4: vertex index 9"), "{eol:?}: {error}");
            let text = ["v 0 0 \\", "0", "v 1 0 0", "f 1 2 \\", " 2", "v 0 1 0", "f 1 2 7", ""].join(eol);
            let error = load(&text).expect_err("out of range").to_string();
            assert!(error.contains("m.obj:7: vertex index 7"), "{eol:?}: {error}");
        }
        // A comment is never continued (it may end with half a GBK character).
        let obj = load("# \\\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").expect("valid");
        assert_eq!(obj.vertices.positions.len(), 3);
        assert_eq!(joined_continuations("f 1 \\\n2 3\nv 1"), "f 1  2 3\n\nv 1");
        assert_eq!(joined_continuations("f 1 \\"), "f 1  ");
    }

    #[test]
    fn polylines_are_left_out() {
        // `tobj` would make a polygon of the second, with a texture index before any `vt`.
        let m = load("v 0 0 0\nv 1 0 0\nv 0 1 0\nl 1 2\n  l -1/-3 -2 3//3\nf 1 2 3\n").expect("loads");
        assert_eq!(m.triangle_count(), 1);
        assert!(m.vertices.uvs.is_empty());
    }

    #[test]
    fn unreadable_file_is_an_error() {
        let e = load_obj(Path::new("/nonexistent/mesh.obj"), &MeshTransform::default()).expect_err("missing");
        assert!(e.message.contains("cannot read"), "{e}");
    }
}
