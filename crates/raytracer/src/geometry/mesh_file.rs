//! Plain triangle-mesh data read from a mesh file (Mitsuba's `serialized`, PLY), and the errors
//! of those readers.

use std::path::Path;

/// Largest mesh file read, in bytes (2 GiB, as for OBJ files).
pub const MAX_MESH_FILE_BYTES: u64 = 2 << 30;

/// A triangle mesh as a file stores it, in the file's own coordinates (no transform applied).
/// Optional attributes are per vertex, as long as `positions` when present.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MeshData {
    /// The mesh's name, if the file gives one (`serialized` version 4).
    pub name: Option<String>,
    /// Vertex positions.
    pub positions: Vec<[f32; 3]>,
    /// Vertex normals (not necessarily of unit length), if the file has them.
    pub normals: Option<Vec<[f32; 3]>>,
    /// Texture coordinates, if the file has them.
    pub uvs: Option<Vec<[f32; 2]>>,
    /// Triangles as indices into the vertices, each checked to be in range; a polygon of the
    /// file is split into a fan of triangles around its first corner.
    pub triangles: Vec<[u32; 3]>,
    /// Whether the file's flags ask for flat shading (`serialized`'s face-normals flag).
    /// Mitsuba 3 ignores the flag (the shape's `face_normals` parameter decides); it is kept
    /// for information.
    pub face_normals: bool,
    /// Further per-vertex and per-face values the file holds (a PLY file's colours and other
    /// properties, named as Mitsuba names them: `vertex_color`, `face_color`, ...).
    pub attributes: Vec<MeshAttribute>,
}

/// Values a mesh file gives each vertex or each face beyond its geometry (Mitsuba's mesh
/// attributes), read by the `mesh_attribute` texture.
#[derive(Clone, Debug, PartialEq)]
pub struct MeshAttribute {
    /// The name, `vertex_...` or `face_...` (Mitsuba's: a PLY file's `red`, `green`, `blue` of
    /// its vertices are `vertex_color`; `k_0`, `k_1`, `k_2` of its faces are `face_k`).
    pub name: String,
    /// Per vertex (interpolated over a triangle by its barycentric weights) or per face
    /// (constant over it).
    pub per_face: bool,
    /// Values per vertex or face: 1 (a scalar) or 3 (a colour, linear RGB as stored).
    pub components: usize,
    /// `components` values for each vertex (in the order of the positions), or for each
    /// triangle (in the order of the triangles: a polygon split into a fan repeats its face's
    /// values for each of its triangles).
    pub values: Vec<f32>,
}

impl MeshAttribute {
    /// The values of element `index` (a vertex or a triangle) as RGB (a scalar repeated).
    #[inline]
    pub fn rgb(&self, index: u32) -> [f32; 3] {
        let i = index as usize * self.components;
        match self.values.get(i..i + self.components) {
            Some(&[v]) => [v; 3],
            Some(&[r, g, b]) => [r, g, b],
            _ => [0.0; 3],
        }
    }
}

/// A mesh file that cannot be read: the file, the part of it (an element, a mesh, a face) and why.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("{file}: {element}: {message}")]
pub struct MeshFileError {
    /// The file's path as given.
    pub file: String,
    /// The part of the file at fault (`header`, `mesh 2`, `face 17`, `element vertex`...).
    pub element: String,
    /// What is wrong.
    pub message: String,
}

impl MeshFileError {
    /// An error about `element` of `file`.
    pub fn new(file: &str, element: impl Into<String>, message: impl Into<String>) -> MeshFileError {
        MeshFileError { file: file.to_owned(), element: element.into(), message: message.into() }
    }
}

/// Reads a whole mesh file, refusing folders, devices and files over [`MAX_MESH_FILE_BYTES`]
/// before reading.
pub fn read_mesh_bytes(path: &Path) -> Result<Vec<u8>, MeshFileError> {
    use std::io::Read;
    let name = path.display().to_string();
    let fail = |message: String| MeshFileError::new(&name, "file", message);
    let metadata = std::fs::metadata(path).map_err(|e| fail(e.to_string()))?;
    if !metadata.is_file() {
        return Err(fail("it is not a regular file".into()));
    }
    if metadata.len() > MAX_MESH_FILE_BYTES {
        return Err(fail(format!(
            "it is larger than {} MiB, the most a mesh file may take",
            MAX_MESH_FILE_BYTES >> 20
        )));
    }
    let mut bytes = Vec::with_capacity(metadata.len() as usize);
    std::fs::File::open(path)
        .and_then(|f| f.take(MAX_MESH_FILE_BYTES + 1).read_to_end(&mut bytes))
        .map_err(|e| fail(e.to_string()))?;
    if bytes.len() as u64 > MAX_MESH_FILE_BYTES {
        return Err(fail(format!(
            "it is larger than {} MiB, the most a mesh file may take",
            MAX_MESH_FILE_BYTES >> 20
        )));
    }
    Ok(bytes)
}

/// Checks that every triangle's indices are below the vertex count; the error names the first
/// face that is not.
pub(crate) fn check_indices(mesh: &MeshData, file: &str) -> Result<(), MeshFileError> {
    let n = mesh.positions.len();
    match mesh.triangles.iter().position(|t| t.iter().any(|&i| i as usize >= n)) {
        Some(face) => Err(MeshFileError::new(
            file,
            format!("face {face}"),
            format!("a vertex index is out of range (the mesh has {n} vertices)"),
        )),
        None => Ok(()),
    }
}
