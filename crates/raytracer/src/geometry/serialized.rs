//! Mitsuba's `serialized` mesh format (versions 3 and 4), as its documentation and its reader
//! (`src/shapes/serialized.cpp`) define it. All numbers are little-endian.
//!
//! A file holds one or more meshes, one after the other, each:
//!
//! - `u16` format identifier `0x041C`, `u16` version (3 or 4);
//! - a zlib stream holding: `u32` flags (`0x0001` per-vertex normals, `0x0002` texture
//!   coordinates, `0x0008` vertex colours, `0x0010` face normals, `0x1000` single precision,
//!   `0x2000` double precision); in version 4 the mesh's name, UTF-8, ending in a zero byte;
//!   `u64` vertex count, `u64` triangle count; the positions (3 numbers a vertex), the normals
//!   (3), the texture coordinates (2), the colours (3), each when its flag is set, in `f32` or
//!   `f64`; the triangles, three `u32` vertex indices each.
//!
//! The file ends with a dictionary: the offset of each mesh from the file's start (`u64` in
//! version 4, `u32` in version 3), then the number of meshes (`u32`). A mesh other than the first
//! (`shape_index`) is found through it.
//!
//! Counts are never trusted before use: what they imply must fit in the compressed data (deflate
//! expands at most 1032 times) and is read in pieces, so a file that lies about its counts is
//! refused for being short, not after gigabytes are allocated.

use std::io::Read;
use std::path::Path;

use super::mesh_file::{MeshData, MeshFileError, check_indices, read_mesh_bytes};

/// The format identifier that starts each mesh.
pub const SERIALIZED_MAGIC: u16 = 0x041C;
/// Most triangles in one mesh (as for OBJ meshes).
pub const MAX_SERIALIZED_TRIANGLES: u64 = super::obj::MAX_TRIANGLES as u64;
/// The most bytes deflate can expand one compressed byte to (its 258-byte matches of 2 bits).
const DEFLATE_MAX_RATIO: u64 = 1032;
/// Longest mesh name read (version 4).
const MAX_NAME_BYTES: usize = 4096;

const HAS_NORMALS: u32 = 0x0001;
const HAS_TEXCOORDS: u32 = 0x0002;
const HAS_COLORS: u32 = 0x0008;
const FACE_NORMALS: u32 = 0x0010;
const DOUBLE_PRECISION: u32 = 0x2000;

/// Reads mesh number `shape_index` (from 0) of a `serialized` file.
pub fn read_serialized(path: &Path, shape_index: u32) -> Result<MeshData, MeshFileError> {
    let bytes = read_mesh_bytes(path)?;
    parse_serialized(&bytes, &path.display().to_string(), shape_index)
}

fn u16_at(bytes: &[u8], at: usize) -> Option<u16> {
    Some(u16::from_le_bytes(bytes.get(at..at.checked_add(2)?)?.try_into().ok()?))
}

fn u32_at(bytes: &[u8], at: usize) -> Option<u32> {
    Some(u32::from_le_bytes(bytes.get(at..at.checked_add(4)?)?.try_into().ok()?))
}

fn u64_at(bytes: &[u8], at: usize) -> Option<u64> {
    Some(u64::from_le_bytes(bytes.get(at..at.checked_add(8)?)?.try_into().ok()?))
}

/// The number of meshes a `serialized` file's dictionary lists.
pub fn serialized_mesh_count(bytes: &[u8], file: &str) -> Result<u32, MeshFileError> {
    let count = bytes.len().checked_sub(4).and_then(|at| u32_at(bytes, at));
    count.ok_or_else(|| MeshFileError::new(file, "dictionary", "the file is too short to hold one"))
}

/// The version of the mesh starting at `offset`, checked.
fn header(bytes: &[u8], offset: usize, file: &str, mesh: &str) -> Result<u16, MeshFileError> {
    let (Some(magic), Some(version)) = (u16_at(bytes, offset), u16_at(bytes, offset + 2)) else {
        return Err(MeshFileError::new(file, mesh, "the file ends before the mesh's header"));
    };
    if magic != SERIALIZED_MAGIC {
        return Err(MeshFileError::new(
            file,
            mesh,
            format!("not a Mitsuba serialized mesh (format identifier {magic:#06x}, expected 0x041c)"),
        ));
    }
    if version != 3 && version != 4 {
        return Err(MeshFileError::new(
            file,
            mesh,
            format!("unsupported version {version} (3 and 4 are read)"),
        ));
    }
    Ok(version)
}

/// Parses mesh number `shape_index` of a `serialized` file held in `bytes` (`file` names it in
/// errors).
pub fn parse_serialized(bytes: &[u8], file: &str, shape_index: u32) -> Result<MeshData, MeshFileError> {
    let mesh = format!("mesh {shape_index}");
    let first_version = header(bytes, 0, file, "mesh 0")?;
    let offset = if shape_index == 0 {
        0
    } else {
        let count = serialized_mesh_count(bytes, file)?;
        if shape_index >= count {
            return Err(MeshFileError::new(
                file,
                &mesh,
                format!("the file holds {count} meshes (shape_index 0 to {})", count.saturating_sub(1)),
            ));
        }
        let back = (count - shape_index) as usize;
        let entry = if first_version >= 4 {
            bytes.len().checked_sub(8 * back + 4).and_then(|at| u64_at(bytes, at))
        } else {
            bytes.len().checked_sub(4 * (back + 1)).and_then(|at| u32_at(bytes, at)).map(u64::from)
        };
        match entry {
            Some(o) if o < bytes.len() as u64 => o as usize,
            _ => return Err(MeshFileError::new(file, "dictionary", format!("no valid offset for {mesh}"))),
        }
    };
    let version = header(bytes, offset, file, &mesh)?;
    let compressed = &bytes[offset + 4..];
    let mut stream = Stream { inner: flate2::read::ZlibDecoder::new(compressed), file, mesh: &mesh };

    let flags = u32::from_le_bytes(stream.array("flags")?);
    let name = if version == 4 { Some(stream.name()?) } else { None };
    let vertex_count = u64::from_le_bytes(stream.array("vertex count")?);
    let face_count = u64::from_le_bytes(stream.array("triangle count")?);
    if vertex_count > u64::from(u32::MAX) || face_count > MAX_SERIALIZED_TRIANGLES {
        return Err(stream.fail(format!(
            "{vertex_count} vertices and {face_count} triangles: at most {} vertices and {MAX_SERIALIZED_TRIANGLES} triangles are read",
            u32::MAX
        )));
    }
    let size = if flags & DOUBLE_PRECISION != 0 { 8 } else { 4 };
    let has = |flag: u32| u64::from(flags & flag != 0);
    let per_vertex = size * (3 + 3 * has(HAS_NORMALS) + 2 * has(HAS_TEXCOORDS) + 3 * has(HAS_COLORS));
    // What the counts imply must fit in what deflate can expand the compressed bytes to.
    let implied =
        vertex_count.checked_mul(per_vertex).and_then(|v| v.checked_add(face_count.checked_mul(12)?));
    let available = (compressed.len() as u64).saturating_mul(DEFLATE_MAX_RATIO);
    if implied.is_none_or(|b| b > available) {
        return Err(stream.fail(format!(
            "it declares {vertex_count} vertices and {face_count} triangles, more than its {} compressed bytes can hold",
            compressed.len()
        )));
    }
    let n = vertex_count as usize;
    let positions = stream.records::<3>(n, size, "positions")?;
    let normals =
        if flags & HAS_NORMALS != 0 { Some(stream.records::<3>(n, size, "normals")?) } else { None };
    let uvs = if flags & HAS_TEXCOORDS != 0 {
        Some(stream.records::<2>(n, size, "texture coordinates")?)
    } else {
        None
    };
    if flags & HAS_COLORS != 0 {
        stream.records::<3>(n, size, "colours")?;
    }
    let triangles = stream.indices(face_count as usize)?;
    let data = MeshData {
        name,
        positions,
        normals,
        uvs,
        triangles,
        face_normals: flags & FACE_NORMALS != 0,
        attributes: Vec::new(),
    };
    check_indices(&data, file)
        .map_err(|e| MeshFileError::new(file, format!("{mesh}, {}", e.element), e.message))?;
    Ok(data)
}

/// The decompressed stream of one mesh, read in pieces.
struct Stream<'a, R: Read> {
    inner: R,
    file: &'a str,
    mesh: &'a str,
}

impl<R: Read> Stream<'_, R> {
    fn fail(&self, message: String) -> MeshFileError {
        MeshFileError::new(self.file, self.mesh, message)
    }

    fn read_error(&self, what: &str, e: std::io::Error) -> MeshFileError {
        if e.kind() == std::io::ErrorKind::UnexpectedEof {
            self.fail(format!("the data ends in the {what} (truncated, or the counts are wrong)"))
        } else {
            self.fail(format!("corrupt compressed data in the {what}: {e}"))
        }
    }

    fn array<const N: usize>(&mut self, what: &str) -> Result<[u8; N], MeshFileError> {
        let mut out = [0u8; N];
        self.inner.read_exact(&mut out).map_err(|e| self.read_error(what, e))?;
        Ok(out)
    }

    /// A zero-terminated UTF-8 name (version 4).
    fn name(&mut self) -> Result<String, MeshFileError> {
        let mut bytes = Vec::new();
        loop {
            let [b] = self.array::<1>("name")?;
            if b == 0 {
                break;
            }
            if bytes.len() >= MAX_NAME_BYTES {
                return Err(self.fail(format!("the mesh name is longer than {MAX_NAME_BYTES} bytes")));
            }
            bytes.push(b);
        }
        Ok(String::from_utf8_lossy(&bytes).into_owned())
    }

    /// `count` records of `D` numbers of `size` bytes (4: `f32`, 8: `f64`), as `f32`.
    fn records<const D: usize>(
        &mut self,
        count: usize,
        size: u64,
        what: &str,
    ) -> Result<Vec<[f32; D]>, MeshFileError> {
        const CHUNK_RECORDS: usize = 1 << 14;
        let record = D * size as usize;
        let mut buf = vec![0u8; CHUNK_RECORDS * record];
        let mut out = Vec::new();
        let mut left = count;
        while left > 0 {
            let n = left.min(CHUNK_RECORDS);
            let piece = &mut buf[..n * record];
            self.inner.read_exact(piece).map_err(|e| self.read_error(what, e))?;
            out.extend(piece.chunks_exact(record).map(|r| {
                std::array::from_fn(|k| {
                    if size == 8 {
                        f64::from_le_bytes(r[8 * k..8 * k + 8].try_into().unwrap_or_default()) as f32
                    } else {
                        f32::from_le_bytes(r[4 * k..4 * k + 4].try_into().unwrap_or_default())
                    }
                })
            }));
            left -= n;
        }
        Ok(out)
    }

    /// `count` triangles of three `u32` indices.
    fn indices(&mut self, count: usize) -> Result<Vec<[u32; 3]>, MeshFileError> {
        const CHUNK: usize = 1 << 14;
        let mut buf = vec![0u8; CHUNK * 12];
        let mut out = Vec::new();
        let mut left = count;
        while left > 0 {
            let n = left.min(CHUNK);
            let piece = &mut buf[..n * 12];
            self.inner.read_exact(piece).map_err(|e| self.read_error("triangles", e))?;
            out.extend(piece.chunks_exact(12).map(|t| {
                std::array::from_fn(|k| {
                    u32::from_le_bytes(t[4 * k..4 * k + 4].try_into().unwrap_or_default())
                })
            }));
            left -= n;
        }
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::Write;

    /// One mesh in the format: header, then the zlib stream of `payload`.
    fn mesh_bytes(version: u16, payload: &[u8]) -> Vec<u8> {
        let mut out = Vec::new();
        out.extend(SERIALIZED_MAGIC.to_le_bytes());
        out.extend(version.to_le_bytes());
        let mut z = flate2::write::ZlibEncoder::new(Vec::new(), flate2::Compression::default());
        z.write_all(payload).expect("compress");
        out.extend(z.finish().expect("compress"));
        out
    }

    /// The payload of a mesh: a quad (two triangles) with normals and texture coordinates.
    fn quad_payload(version: u16, double: bool) -> Vec<u8> {
        let mut p = Vec::new();
        let flags = HAS_NORMALS | HAS_TEXCOORDS | if double { DOUBLE_PRECISION } else { 0x1000 };
        p.extend(flags.to_le_bytes());
        if version == 4 {
            p.extend(b"quad\0");
        }
        p.extend(4u64.to_le_bytes());
        p.extend(2u64.to_le_bytes());
        let num = |v: f64, p: &mut Vec<u8>| {
            if double { p.extend(v.to_le_bytes()) } else { p.extend((v as f32).to_le_bytes()) }
        };
        for v in [[0., 0., 0.], [1., 0., 0.], [1., 1., 0.], [0., 1., 0.]] {
            v.iter().for_each(|&x| num(x, &mut p));
        }
        for _ in 0..4 {
            [0., 0., 1.].iter().for_each(|&x| num(x, &mut p));
        }
        for uv in [[0., 0.], [1., 0.], [1., 1.], [0., 1.]] {
            uv.iter().for_each(|&x| num(x, &mut p));
        }
        for i in [0u32, 1, 2, 0, 2, 3] {
            p.extend(i.to_le_bytes());
        }
        p
    }

    #[test]
    fn meshes_of_both_versions_and_precisions_read() {
        for (version, double) in [(3, false), (4, false), (4, true)] {
            let bytes = mesh_bytes(version, &quad_payload(version, double));
            let mesh = parse_serialized(&bytes, "q.serialized", 0).expect("reads");
            assert_eq!(mesh.positions[2], [1.0, 1.0, 0.0]);
            assert_eq!(mesh.normals.as_ref().map(Vec::len), Some(4));
            assert_eq!(mesh.uvs.as_ref().map(|u| u[3]), Some([0.0, 1.0]));
            assert_eq!(mesh.triangles, [[0, 1, 2], [0, 2, 3]]);
            assert_eq!(mesh.name.as_deref(), if version == 4 { Some("quad") } else { None });
        }
    }

    /// Two meshes and a version 4 dictionary.
    fn two_meshes() -> Vec<u8> {
        let first = mesh_bytes(4, &quad_payload(4, false));
        let mut payload = quad_payload(4, false);
        payload[4..8].copy_from_slice(b"seco"); // another name, same length
        let second = mesh_bytes(4, &payload);
        let mut bytes = first.clone();
        bytes.extend(&second);
        bytes.extend(0u64.to_le_bytes());
        bytes.extend((first.len() as u64).to_le_bytes());
        bytes.extend(2u32.to_le_bytes());
        bytes
    }

    #[test]
    fn the_dictionary_finds_later_meshes() {
        let bytes = two_meshes();
        assert_eq!(serialized_mesh_count(&bytes, "t").expect("count"), 2);
        assert_eq!(parse_serialized(&bytes, "t", 1).expect("second").name.as_deref(), Some("seco"));
        let e = parse_serialized(&bytes, "t", 2).expect_err("no third");
        assert_eq!(e.to_string(), "t: mesh 2: the file holds 2 meshes (shape_index 0 to 1)");
    }

    #[test]
    fn truncated_files_and_lying_counts_are_refused() {
        let bytes = mesh_bytes(3, &quad_payload(3, false));
        for cut in [2, 4, 10, bytes.len() - 6] {
            let e = parse_serialized(&bytes[..cut], "q.serialized", 0).expect_err("truncated");
            assert!(e.to_string().starts_with("q.serialized: mesh 0: "), "{e}");
        }
        // The payload cut short: named by the part it ends in.
        let mut payload = quad_payload(3, false);
        payload.truncate(payload.len() - 8);
        let e = parse_serialized(&mesh_bytes(3, &payload), "q", 0).expect_err("short");
        assert_eq!(
            e.to_string(),
            "q: mesh 0: the data ends in the triangles (truncated, or the counts are wrong)"
        );
        // A vertex count of a billion in a few bytes: refused before anything is allocated.
        let mut payload = quad_payload(3, false);
        payload[4..12].copy_from_slice(&1_000_000_000u64.to_le_bytes());
        let e = parse_serialized(&mesh_bytes(3, &payload), "q", 0).expect_err("lying count");
        assert!(e.to_string().contains("more than its"), "{e}");
        // An index past the vertices.
        let mut payload = quad_payload(3, false);
        let n = payload.len();
        payload[n - 4..].copy_from_slice(&9u32.to_le_bytes());
        let e = parse_serialized(&mesh_bytes(3, &payload), "q", 0).expect_err("bad index");
        assert_eq!(
            e.to_string(),
            "q: mesh 0, face 1: a vertex index is out of range (the mesh has 4 vertices)"
        );
        // Not the format, or another version.
        assert!(parse_serialized(b"PK\x03\x04rest", "q", 0).is_err());
        let mut v5 = bytes.clone();
        v5[2] = 5;
        assert!(parse_serialized(&v5, "q", 0).expect_err("v5").to_string().contains("unsupported version 5"));
    }

    mod no_panics {
        use super::*;
        use proptest::prelude::*;

        proptest! {
            #![proptest_config(ProptestConfig::with_cases(512))]

            /// A file of two meshes with bytes changed and cut: an error or a mesh with its
            /// indices in range, never a panic.
            #[test]
            fn changed_files_never_panic(
                changes in proptest::collection::vec((any::<prop::sample::Index>(), any::<u8>()), 0..6),
                cut in any::<prop::sample::Index>(),
                shape_index in 0..3u32,
            ) {
                let mut bytes = two_meshes();
                for (at, b) in changes {
                    let i = at.index(bytes.len());
                    bytes[i] = b;
                }
                bytes.truncate(cut.index(bytes.len() + 1));
                if let Ok(mesh) = parse_serialized(&bytes, "s", shape_index) {
                    let n = mesh.positions.len();
                    prop_assert!(mesh.triangles.iter().all(|t| t.iter().all(|&i| (i as usize) < n)));
                }
            }
        }
    }
}
