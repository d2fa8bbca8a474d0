//! PLY meshes (ASCII and binary, both byte orders) through the `ply-rs-bw` crate: the `vertex`
//! element's `x`, `y`, `z`, its normals `nx`, `ny`, `nz` and texture coordinates (`u`/`v`, `s`/`t`
//! or `texture_u`/`texture_v`) when all of a set are declared, and the `face` element's
//! `vertex_indices` (or `vertex_index`) lists, polygons split into fans. The other scalar
//! properties of vertices and faces become mesh attributes as Mitsuba 3 names them
//! ([`MeshAttribute`]); other elements are read past.
//!
//! Attributes (Mitsuba's `ply.cpp`): `r`, `g`, `b` (or `red`, `green`, `blue`) are `vertex_color`
//! (`face_color` on faces), as stored (8-bit values are not scaled to [0, 1], as in Mitsuba);
//! then consecutive properties `PREFIX_S` with one-letter suffixes of one series, `x y z`,
//! `r g b`, `0 1 2` or `1 2 3`, are `vertex_PREFIX` (`vertex_PREFIX_color` for `r g b`), of one
//! or three values. Properties that fit no attribute (no suffix, two or four values, a
//! colour with alpha) are read past.
//!
//! The counts of the header are checked against the file's size before any element is read
//! (each element takes at least one byte a property in binary, two in ASCII), and the crate
//! caps what it allocates ahead of the data, so a file that lies about its counts is refused
//! without allocating what it claims.

use std::io::{BufRead, Cursor};
use std::path::Path;

use ply_rs_bw::parser::{Parser, Reader};
use ply_rs_bw::ply::{
    ElementDef, Encoding, Header, Property, PropertyAccess, PropertyAccessResult, PropertyType, ScalarType,
};

use super::mesh_file::{MeshAttribute, MeshData, MeshFileError, check_indices, read_mesh_bytes};

/// Most triangles in one mesh (as for OBJ meshes).
pub const MAX_PLY_TRIANGLES: usize = super::obj::MAX_TRIANGLES;

/// Reads a PLY mesh file.
pub fn read_ply(path: &Path) -> Result<MeshData, MeshFileError> {
    let bytes = read_mesh_bytes(path)?;
    parse_ply(&bytes, &path.display().to_string())
}

/// A property's value as a number (lists give `None`).
fn number(p: &Property) -> Option<f64> {
    Some(match *p {
        Property::Char(v) => v.into(),
        Property::UChar(v) => v.into(),
        Property::Short(v) => v.into(),
        Property::UShort(v) => v.into(),
        Property::Int(v) => v.into(),
        Property::UInt(v) => v.into(),
        Property::Float(v) => v.into(),
        Property::Double(v) => v,
        _ => return None,
    })
}

/// One vertex: the geometry read, by slot (x y z nx ny nz u v), and the other scalar
/// properties in the header's order (the attributes' columns).
struct Vertex([f32; 8], Vec<f32>);

impl PropertyAccess for Vertex {
    fn new() -> Self {
        Vertex([0.0; 8], Vec::new())
    }

    fn set_property(&mut self, name: &str, property: Property) -> PropertyAccessResult {
        let Some(slot) = vertex_slot(name) else {
            return match number(&property) {
                Some(v) => {
                    self.1.push(v as f32);
                    PropertyAccessResult::Set
                }
                None => PropertyAccessResult::Ignored,
            };
        };
        match number(&property) {
            Some(v) => {
                self.0[slot] = v as f32;
                PropertyAccessResult::Set
            }
            None => PropertyAccessResult::UnsupportedType,
        }
    }
}

/// The slot of a vertex property we read.
fn vertex_slot(name: &str) -> Option<usize> {
    Some(match name {
        "x" => 0,
        "y" => 1,
        "z" => 2,
        "nx" => 3,
        "ny" => 4,
        "nz" => 5,
        "u" | "s" | "texture_u" | "texture_s" => 6,
        "v" | "t" | "texture_v" | "texture_t" => 7,
        _ => return None,
    })
}

/// Whether a face property holds the corners.
fn is_corner_list(name: &str) -> bool {
    name == "vertex_indices" || name == "vertex_index"
}

/// One face: its corner indices, or why they are unusable, and its other scalar properties in
/// the header's order.
struct Face {
    corners: Vec<u32>,
    bad: bool,
    extra: Vec<f32>,
}

impl PropertyAccess for Face {
    fn new() -> Self {
        Face { corners: Vec::new(), bad: false, extra: Vec::new() }
    }

    fn set_property(&mut self, name: &str, property: Property) -> PropertyAccessResult {
        if !is_corner_list(name) {
            return match number(&property) {
                Some(v) => {
                    self.extra.push(v as f32);
                    PropertyAccessResult::Set
                }
                None => PropertyAccessResult::Ignored,
            };
        }
        fn convert<T: TryInto<u32> + Copy>(list: &[T], out: &mut Vec<u32>) -> bool {
            out.clear();
            out.extend(list.iter().filter_map(|&i| i.try_into().ok()));
            out.len() == list.len()
        }
        let ok = match &property {
            Property::ListChar(l) => convert(l, &mut self.corners),
            Property::ListUChar(l) => convert(l, &mut self.corners),
            Property::ListShort(l) => convert(l, &mut self.corners),
            Property::ListUShort(l) => convert(l, &mut self.corners),
            Property::ListInt(l) => convert(l, &mut self.corners),
            Property::ListUInt(l) => convert(l, &mut self.corners),
            _ => return PropertyAccessResult::UnsupportedType,
        };
        // A negative index: remembered, reported with the face's number.
        self.bad |= !ok;
        PropertyAccessResult::Set
    }
}

/// An element we read past.
struct Skip;

impl PropertyAccess for Skip {
    fn new() -> Self {
        Skip
    }
}

/// An attribute found in a header: its name and the columns (indices among the element's
/// other scalar properties, in the header's order) of its values.
#[derive(Debug, PartialEq)]
struct Layout {
    name: String,
    columns: Vec<usize>,
}

/// An attribute being read: its prefix, its suffix series, its columns so far.
type Series<'n> = (&'n str, usize, Vec<usize>);

/// The suffix series of an attribute's values: `SERIES[k][s]` is the `k`-th value's suffix of
/// series `s` (`x y z`, `r g b`, `0 1 2`, `1 2 3`).
const SERIES: [&[u8; 4]; 3] = [b"xr01", b"yg12", b"zb23"];

/// The attributes of an element (Mitsuba's grouping, see the module's documentation): `kind` is
/// `vertex_` or `face_`; `reserved` tells the properties read otherwise.
fn attribute_layout(element: &ElementDef, kind: &str, reserved: &dyn Fn(&str) -> bool) -> Vec<Layout> {
    let columns: Vec<&str> = element
        .properties
        .iter()
        .filter(|(name, p)| matches!(p.data_type, PropertyType::Scalar(_)) && !reserved(name))
        .map(|(name, _)| name.as_str())
        .collect();
    let column = |name: &str| columns.iter().position(|c| *c == name);
    let mut out = Vec::new();
    // The colour: `r g b` or `red green blue` (with an alpha it has four values, which Mitsuba
    // cannot evaluate: left out).
    let mut colour_names: Vec<&str> = vec!["r", "g", "b", "a"];
    for names in [["r", "g", "b", "a"], ["red", "green", "blue", "alpha"]] {
        let found: Vec<usize> = names[..3].iter().filter_map(|n| column(n)).collect();
        if found.len() == 3 {
            if column(names[3]).is_none() {
                out.push(Layout { name: format!("{kind}color"), columns: found });
            }
            colour_names.extend(names);
            break;
        }
    }
    // `PREFIX_S` series.
    let mut seen: Vec<&str> = Vec::new();
    let mut current: Option<Series<'_>> = None;
    /// The attribute being read, if it has one or three values.
    fn flush<'n>(
        current: &mut Option<Series<'n>>,
        kind: &str,
        out: &mut Vec<Layout>,
        seen: &mut Vec<&'n str>,
    ) {
        if let Some((prefix, series, cols)) = current.take()
            && (cols.len() == 1 || cols.len() == 3)
        {
            let suffix = if series == 1 { "_color" } else { "" };
            out.push(Layout { name: format!("{kind}{prefix}{suffix}"), columns: cols });
            seen.push(prefix);
        }
    }
    let mut i = 0;
    while i < columns.len() {
        let name = columns[i];
        i += 1;
        if colour_names.contains(&name) {
            continue;
        }
        let Some((prefix, suffix)) = name.rsplit_once('_') else {
            flush(&mut current, kind, &mut out, &mut seen);
            continue;
        };
        let &[letter] = suffix.as_bytes() else {
            flush(&mut current, kind, &mut out, &mut seen);
            continue;
        };
        if current.as_ref().is_some_and(|c| c.0 != prefix) {
            flush(&mut current, kind, &mut out, &mut seen);
        }
        let skip_prefix = |i: &mut usize| {
            while *i < columns.len() && columns[*i].starts_with(prefix) {
                *i += 1;
            }
        };
        match &mut current {
            None => {
                if seen.contains(&prefix) {
                    skip_prefix(&mut i);
                    continue;
                }
                if let Some(series) = SERIES[0].iter().position(|&c| c == letter) {
                    current = Some((prefix, series, vec![i - 1]));
                }
            }
            Some((_, series, cols)) => {
                if cols.len() < SERIES.len() && SERIES[cols.len()][*series] == letter {
                    cols.push(i - 1);
                } else {
                    // Out of series (or a fourth value): the attribute is dropped.
                    current = None;
                    skip_prefix(&mut i);
                }
            }
        }
    }
    flush(&mut current, kind, &mut out, &mut seen);
    out
}

/// The values of the attributes of `layouts` over elements whose other scalar properties are
/// `rows`, each element's values repeated `repeat(element)` times (a polygon's triangles).
fn attribute_values<'r>(
    layouts: &[Layout],
    kind_is_face: bool,
    rows: impl Iterator<Item = (&'r [f32], usize)> + Clone,
) -> Vec<MeshAttribute> {
    layouts
        .iter()
        .map(|l| {
            let mut values = Vec::new();
            for (row, repeat) in rows.clone() {
                for _ in 0..repeat {
                    values.extend(l.columns.iter().map(|&c| row.get(c).copied().unwrap_or(0.0)));
                }
            }
            MeshAttribute {
                name: l.name.clone(),
                per_face: kind_is_face,
                components: l.columns.len(),
                values,
            }
        })
        .collect()
}

/// The fewest bytes one element of `properties` takes in `encoding`.
fn min_element_bytes(properties: impl Iterator<Item = PropertyType>, encoding: Encoding) -> u64 {
    let scalar = |t: &ScalarType| match t {
        ScalarType::Char | ScalarType::UChar => 1,
        ScalarType::Short | ScalarType::UShort => 2,
        ScalarType::Int | ScalarType::UInt | ScalarType::Float => 4,
        ScalarType::Double => 8,
    };
    properties
        .map(|p| match (encoding, &p) {
            (Encoding::Ascii, _) => 2,
            (_, PropertyType::Scalar(t)) => scalar(t),
            (_, PropertyType::List(count, _)) => scalar(count),
        })
        .sum()
}

/// Parses a PLY file held in `bytes` (`file` names it in errors).
pub fn parse_ply(bytes: &[u8], file: &str) -> Result<MeshData, MeshFileError> {
    let mut reader = Reader::new(Cursor::new(bytes));
    let header: Header = Parser::<Vertex>::new()
        .read_header(&mut reader)
        .map_err(|e| MeshFileError::new(file, "header", e.to_string()))?;
    // The counts against the bytes left.
    let left = bytes.len() as u64 - reader.get_mut().position().min(bytes.len() as u64);
    let mut needed = 0u64;
    for element in header.elements.values() {
        let each =
            min_element_bytes(element.properties.values().map(|p| p.data_type.clone()), header.encoding);
        needed = needed.saturating_add((element.count as u64).saturating_mul(each));
        if needed > left {
            return Err(MeshFileError::new(
                file,
                format!("element {}", element.name),
                format!(
                    "the header declares {} of them, more than the {left} bytes after it can hold (truncated, or the count is wrong)",
                    element.count
                ),
            ));
        }
    }
    let Some(vertex_def) = header.elements.get("vertex") else {
        return Err(MeshFileError::new(file, "header", "no `vertex` element"));
    };
    let declared = |names: &[&str]| names.iter().all(|n| vertex_def.properties.contains_key(*n));
    if !declared(&["x", "y", "z"]) {
        return Err(MeshFileError::new(file, "element vertex", "the vertices need `x`, `y` and `z`"));
    }
    let has_normals = declared(&["nx", "ny", "nz"]);
    let uv_names = [["u", "v"], ["s", "t"], ["texture_u", "texture_v"], ["texture_s", "texture_t"]];
    let has_uvs = uv_names.iter().any(|pair| declared(pair));

    let vertex_layout = attribute_layout(vertex_def, "vertex_", &|n| vertex_slot(n).is_some());
    let face_layout = header
        .elements
        .get("face")
        .map(|f| attribute_layout(f, "face_", &is_corner_list))
        .unwrap_or_default();

    let mut vertices: Vec<Vertex> = Vec::new();
    let mut faces: Vec<Face> = Vec::new();
    for element in header.elements.values() {
        let fail = |e: ply_rs_bw::parser::ParseError| {
            MeshFileError::new(file, format!("element {}", element.name), e.to_string())
        };
        match element.name.as_str() {
            "vertex" => {
                vertices = Parser::<Vertex>::new()
                    .read_payload_for_element(&mut reader, element, &header)
                    .map_err(fail)?
            }
            "face" => {
                if element.count > MAX_PLY_TRIANGLES {
                    return Err(MeshFileError::new(
                        file,
                        "element face",
                        format!("{} faces: at most {MAX_PLY_TRIANGLES} are read", element.count),
                    ));
                }
                faces = Parser::<Face>::new()
                    .read_payload_for_element(&mut reader, element, &header)
                    .map_err(fail)?
            }
            _ => {
                Parser::<Skip>::new()
                    .read_payload_for_element(&mut reader, element, &header)
                    .map_err(fail)?;
            }
        }
    }
    if vertices.len() > u32::MAX as usize {
        return Err(MeshFileError::new(file, "element vertex", "more than 2^32 vertices"));
    }
    let mut triangles = Vec::with_capacity(faces.len());
    for (i, f) in faces.iter().enumerate() {
        if f.bad {
            return Err(MeshFileError::new(file, format!("face {i}"), "a negative vertex index"));
        }
        if let [first, rest @ ..] = f.corners.as_slice() {
            triangles.extend(rest.windows(2).map(|w| [*first, w[0], w[1]]));
        }
        if triangles.len() > MAX_PLY_TRIANGLES {
            return Err(MeshFileError::new(
                file,
                "element face",
                format!("more than {MAX_PLY_TRIANGLES} triangles"),
            ));
        }
    }
    // Anything but white space after the last element means the counts were wrong.
    let mut rest = Vec::new();
    let _ = reader.get_mut().read_until(0xFF, &mut rest);
    if header.encoding == Encoding::Ascii && rest.iter().any(|b| !b.is_ascii_whitespace()) {
        return Err(MeshFileError::new(
            file,
            "payload",
            "data after the last element (the counts are wrong)",
        ));
    }
    let mut attributes =
        attribute_values(&vertex_layout, false, vertices.iter().map(|v| (v.1.as_slice(), 1)));
    attributes.extend(attribute_values(
        &face_layout,
        true,
        faces.iter().map(|f| (f.extra.as_slice(), f.corners.len().saturating_sub(2))),
    ));
    let data = MeshData {
        name: None,
        positions: vertices.iter().map(|v| [v.0[0], v.0[1], v.0[2]]).collect(),
        normals: has_normals.then(|| vertices.iter().map(|v| [v.0[3], v.0[4], v.0[5]]).collect()),
        uvs: has_uvs.then(|| vertices.iter().map(|v| [v.0[6], v.0[7]]).collect()),
        triangles,
        face_normals: false,
        attributes,
    };
    check_indices(&data, file)?;
    Ok(data)
}

#[cfg(test)]
mod tests {
    use super::*;

    const ASCII: &str = "ply\nformat ascii 1.0\ncomment a quad\nelement vertex 4\nproperty float x\nproperty float y\n\
property float z\nproperty float nx\nproperty float ny\nproperty float nz\nproperty float u\nproperty float v\n\
element face 1\nproperty list uchar int vertex_indices\nend_header\n\
0 0 0 0 0 1 0 0\n1 0 0 0 0 1 1 0\n1 1 0 0 0 1 1 1\n0 1 0 0 0 1 0 1\n4 0 1 2 3\n";

    fn binary(big_endian: bool) -> Vec<u8> {
        let order = if big_endian { "binary_big_endian" } else { "binary_little_endian" };
        let mut b = format!(
            "ply\nformat {order} 1.0\nelement vertex 3\nproperty double x\nproperty double y\nproperty double z\n\
property uchar red\nelement face 1\nproperty list uchar uint vertex_indices\nend_header\n"
        )
        .into_bytes();
        for v in [[0.0f64, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]] {
            for x in v {
                b.extend(if big_endian { x.to_be_bytes() } else { x.to_le_bytes() });
            }
            b.push(200);
        }
        b.push(3);
        for i in [0u32, 1, 2] {
            b.extend(if big_endian { i.to_be_bytes() } else { i.to_le_bytes() });
        }
        b
    }

    #[test]
    fn ascii_polygons_become_fans_with_normals_and_uvs() {
        let mesh = parse_ply(ASCII.as_bytes(), "q.ply").expect("reads");
        assert_eq!(mesh.positions.len(), 4);
        assert_eq!(mesh.triangles, [[0, 1, 2], [0, 2, 3]]);
        assert_eq!(mesh.normals.as_ref().map(|n| n[0]), Some([0.0, 0.0, 1.0]));
        assert_eq!(mesh.uvs.as_ref().map(|u| u[2]), Some([1.0, 1.0]));
    }

    #[test]
    fn binary_files_of_both_byte_orders_read() {
        for big in [false, true] {
            let mesh = parse_ply(&binary(big), "t.ply").expect("reads");
            assert_eq!(mesh.positions, [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]);
            assert_eq!(mesh.triangles, [[0, 1, 2]]);
            assert!(mesh.normals.is_none() && mesh.uvs.is_none());
        }
    }

    #[test]
    fn truncated_files_and_lying_counts_are_refused() {
        let full = binary(false);
        let e = parse_ply(&full[..full.len() - 3], "t.ply").expect_err("truncated");
        assert!(e.to_string().starts_with("t.ply: element face: "), "{e}");
        // A count of billions, refused from the header.
        let lying =
            String::from_utf8_lossy(&full).replacen("element vertex 3", "element vertex 3000000000", 1);
        let e = parse_ply(lying.as_bytes(), "t.ply").expect_err("lying count");
        assert!(e.to_string().starts_with("t.ply: element vertex: the header declares 3000000000"), "{e}");
        let short = ASCII.replacen("element vertex 4", "element vertex 5", 1);
        assert!(parse_ply(short.as_bytes(), "q.ply").is_err());
        let long = ASCII.replacen("element vertex 4", "element vertex 3", 1);
        assert!(parse_ply(long.as_bytes(), "q.ply").is_err());
        let out_of_range = ASCII.replacen("4 0 1 2 3", "4 0 1 2 9", 1);
        let e = parse_ply(out_of_range.as_bytes(), "q.ply").expect_err("index");
        assert_eq!(e.to_string(), "q.ply: face 1: a vertex index is out of range (the mesh has 4 vertices)");
        let negative = ASCII.replacen("4 0 1 2 3", "4 0 1 2 -1", 1);
        assert_eq!(parse_ply(negative.as_bytes(), "q.ply").expect_err("negative").element, "face 0");
        assert_eq!(parse_ply(b"not a ply", "x.ply").expect_err("header").element, "header");
    }

    #[test]
    fn other_properties_become_attributes_named_as_mitsuba_names_them() {
        // Checked against Mitsuba 3.9.1's reading of the same file (`mi.traverse` of the mesh).
        let text = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
property float z\nproperty uchar red\nproperty uchar green\nproperty uchar blue\nproperty float w_0\n\
property float q_x\nproperty float q_y\nproperty float q_z\nproperty float two_0\nproperty float two_1\n\
property float plain\nelement face 2\nproperty list uchar int vertex_indices\nproperty float k_r\n\
property float k_g\nproperty float k_b\nend_header\n\
0 0 0 255 128 0 0.5 1 2 3 0 0 7\n1 0 0 0 0 0 0.25 4 5 6 0 0 7\n0 1 0 10 20 30 0.125 7 8 9 0 0 7\n\
3 0 1 2 0.1 0.2 0.3\n4 0 1 2 0 0.4 0.5 0.6\n";
        let mesh = parse_ply(text.as_bytes(), "a.ply").expect("reads");
        let find = |name: &str| mesh.attributes.iter().find(|a| a.name == name);
        let names: Vec<&str> = mesh.attributes.iter().map(|a| a.name.as_str()).collect();
        assert_eq!(names, ["vertex_color", "vertex_w", "vertex_q", "face_k_color"]);
        let colour = find("vertex_color").expect("colour");
        // 8-bit values as stored, as Mitsuba keeps them.
        assert_eq!((colour.per_face, colour.components), (false, 3));
        assert_eq!(colour.values, [255.0, 128.0, 0.0, 0.0, 0.0, 0.0, 10.0, 20.0, 30.0]);
        assert_eq!(find("vertex_w").map(|a| a.rgb(2)), Some([0.125; 3]));
        assert_eq!(find("vertex_q").map(|a| a.rgb(1)), Some([4.0, 5.0, 6.0]));
        // The quad's two triangles both carry its values.
        let face = find("face_k_color").expect("face colour");
        assert!(face.per_face);
        assert_eq!(mesh.triangles.len(), 3);
        assert_eq!(
            [face.rgb(0), face.rgb(1), face.rgb(2)],
            [[0.1, 0.2, 0.3], [0.4, 0.5, 0.6], [0.4, 0.5, 0.6]]
        );
    }

    mod no_panics {
        use super::*;
        use proptest::prelude::*;

        proptest! {
            #![proptest_config(ProptestConfig::with_cases(512))]

            /// The test files with bytes changed, cut or repeated: an error or a mesh with its
            /// indices in range, never a panic.
            #[test]
            fn changed_files_never_panic(
                which in 0..3usize,
                changes in proptest::collection::vec((any::<prop::sample::Index>(), any::<u8>()), 0..6),
                cut in any::<prop::sample::Index>(),
            ) {
                let mut bytes = match which {
                    0 => ASCII.as_bytes().to_vec(),
                    1 => binary(false),
                    _ => binary(true),
                };
                for (at, b) in changes {
                    let i = at.index(bytes.len());
                    bytes[i] = b;
                }
                bytes.truncate(cut.index(bytes.len() + 1));
                if let Ok(mesh) = parse_ply(&bytes, "p.ply") {
                    let n = mesh.positions.len();
                    prop_assert!(mesh.triangles.iter().all(|t| t.iter().all(|&i| (i as usize) < n)));
                }
            }
        }
    }
}
