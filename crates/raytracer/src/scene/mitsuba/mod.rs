//! Mitsuba 3's XML scene format, read into a plugin tree: plain data, every item with its place
//! in its file, ready for the layers that build materials, lights and cameras from it.
//!
//! What is read (see `docs/mitsuba-format.md`):
//!
//! - `<scene version="...">` of versions 0.x to 3.x; files below 2.0.0 are upgraded as Mitsuba
//!   upgrades them ([`upgrade`]);
//! - `<default name value>`, `$name` in attribute values, and the caller's definitions (Mitsuba's
//!   `-D name=value`, see [`parse_define`]);
//! - `<include filename>` (resolved from the including file's folder first), `<path value>`
//!   search folders, `id` / `<ref id name>` / `<alias id as>`;
//! - the plugins (`<bsdf>`, `<texture>`, `<emitter>`, `<shape>`, `<sensor>`, `<film>`,
//!   `<rfilter>`, `<sampler>`, `<integrator>`, `<medium>`, `<phase>`, `<volume>`) as generic
//!   [`Plugin`] nodes, and their typed [`Property`] values, including `<transform>` matrices.
//!
//! Every error names the file, line and column ([`MitsubaError`]); no input panics, and the
//! files, their elements and their nesting are bounded ([`MAX_XML_FILE_BYTES`] and the others).
//!
//! ```
//! use raytracer::scene::SourceFile;
//! use raytracer::scene::mitsuba::{self, PluginKind, Value};
//!
//! let text = r#"<scene version="3.0.0">
//!     <default name="spp" value="64"/>
//!     <sensor type="perspective">
//!         <sampler type="independent"><integer name="sample_count" value="$spp"/></sampler>
//!     </sensor>
//!     <shape type="sphere"><float name="radius" value="0.5"/></shape>
//! </scene>"#;
//! let source = SourceFile::from_text("scene.xml", None, text.to_owned());
//! // As `mitsuba -D spp=16 scene.xml`; `mitsuba::read_file(path, &defines)` reads a file.
//! let defines = [mitsuba::parse_define("spp=16")?];
//! let doc = mitsuba::read_source(source, &defines)?;
//! let sampler = doc.plugins().find(|p| p.kind == PluginKind::Sampler).expect("a sampler");
//! assert_eq!(sampler.property("sample_count").map(|p| &p.value), Some(&Value::Integer(16)));
//! let shape = doc.plugins().find(|p| p.kind == PluginKind::Shape).expect("a shape");
//! assert_eq!(doc.place(shape.pos), "scene.xml:6:5");
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

pub mod build;
mod cie;
mod error;
mod numbers;
mod params;
mod reader;
mod spectrum;
pub mod transform;
mod tree;
pub mod upgrade;

#[cfg(test)]
mod tests;

use std::collections::HashMap;
use std::path::{Path, PathBuf};

pub use build::{Built, build};
pub use cie::{
    CIE_D65_NORMALIZATION, CIE_MAX, CIE_MIN, CIE_TABLE, CIE_Y_NORMALIZATION, cie_d65, cie1931_xyz,
    xyz_to_srgb,
};
pub use error::MitsubaError;
pub use params::{DefineError, MAX_PARAMETERS, MAX_SUBSTITUTED_BYTES, parse_define};
pub use spectrum::{MAX_SPECTRUM_SAMPLES, Spectrum, SpectrumUse, spectrum_list_to_srgb};
pub use tree::{Child, Node, Plugin, PluginKind, Pos, Property, Value};
pub use upgrade::Version;

use crate::scene::{Diagnostic, Location, SourceFile};

/// Largest Mitsuba scene file read, in bytes (64 MiB; the documentation's scenes take a few
/// kilobytes, geometry lives in mesh files).
pub const MAX_XML_FILE_BYTES: u64 = 64 << 20;
/// Largest total of all the files of one scene (the first and its includes), in bytes.
pub const MAX_TOTAL_BYTES: u64 = 256 << 20;
/// Most elements in one scene, all files together.
pub const MAX_ELEMENTS: usize = 1_000_000;
/// Deepest nesting of elements (plugins in plugins, across includes).
pub const MAX_NESTING: usize = 100;
/// Deepest chain of includes (Mitsuba's own limit is 15).
pub const MAX_INCLUDE_DEPTH: usize = 15;
/// Largest `.spd` spectrum file read, in bytes.
pub const MAX_SPD_FILE_BYTES: u64 = 4 << 20;

/// A Mitsuba scene read: the root plugin (normally the `<scene>`), the files it was read from,
/// and how the rest of its file names resolve.
#[derive(Clone, Debug)]
pub struct Document {
    /// The root element's plugin, with includes spliced in.
    pub root: Plugin,
    /// The files read, the first one first, then each include in the order met; a [`Pos`]'s
    /// `file` indexes this list.
    pub files: Vec<SourceFile>,
    /// The first file's `version`.
    pub version: Version,
    /// The folders a relative file name of a plugin (`filename` of a mesh or a texture) is
    /// looked up in, in order: the first file's `<path>` folders (the last one first), then its
    /// own folder (Mitsuba's file resolver after reading the scene).
    pub resolver: Vec<PathBuf>,
    /// Each id's plugin, by serial number (the tree's preorder).
    ids: HashMap<String, u32>,
    /// Each plugin's parent (serial number) and index among the parent's children, by serial
    /// number; the root's parent is `u32::MAX`.
    parents: Vec<(u32, u32)>,
    /// Warnings about the scene (unused `-D` definitions).
    pub warnings: Vec<Diagnostic>,
}

impl Document {
    /// The plugin declared with `id` (or an alias of it).
    pub fn get(&self, id: &str) -> Option<&Plugin> {
        // The child indices from the root, found upwards from the plugin.
        let mut path = Vec::new();
        let mut serial = *self.ids.get(id)?;
        while serial != 0 {
            let &(parent, index) = self.parents.get(serial as usize)?;
            path.push(index);
            serial = parent;
        }
        let mut p = &self.root;
        for &i in path.iter().rev() {
            match &p.children.get(i as usize)?.node {
                Node::Plugin(child) => p = child,
                Node::Reference(_) => return None,
            }
        }
        Some(p)
    }

    /// The plugin a child stands for: itself, or the target of its reference (which the reader
    /// checked to exist).
    pub fn target<'a>(&'a self, child: &'a Child) -> Option<&'a Plugin> {
        match &child.node {
            Node::Plugin(p) => Some(p),
            Node::Reference(id) => self.get(id),
        }
    }

    /// The plugins `plugin` holds, in file order, references followed: each child with the
    /// plugin it stands for.
    pub fn children<'a>(&'a self, plugin: &'a Plugin) -> impl Iterator<Item = (&'a Child, &'a Plugin)> {
        plugin.children.iter().filter_map(move |c| Some((c, self.target(c)?)))
    }

    /// Every plugin declared in the scene, the root first, depth first in file order (each
    /// once, however often it is referenced).
    pub fn plugins(&self) -> impl Iterator<Item = &Plugin> {
        self.root.descendants().into_iter()
    }

    /// The place `pos` marks, for a diagnostic.
    pub fn location(&self, pos: Pos) -> Location {
        match self.files.get(pos.file as usize) {
            Some(file) => file.location(pos.span),
            None => Location::new(String::new(), pos.span, ""),
        }
    }

    /// `file:line:column` of `pos`.
    pub fn place(&self, pos: Pos) -> String {
        let file = self.files.get(pos.file as usize).map_or("", |f| f.name());
        format!("{file}:{}:{}", pos.span.line, pos.span.column)
    }

    /// A plugin's file name resolved as Mitsuba resolves it: an absolute path as it is, a
    /// relative one in the first folder of [`Document::resolver`] that has it. `None` when none
    /// has it.
    pub fn resolve_file(&self, name: &str) -> Option<PathBuf> {
        reader::resolve(&self.resolver, name)
    }
}

/// Reads a Mitsuba scene file and the files it includes. `defines` are the caller's parameter
/// values (Mitsuba's `-D name=value`, see [`parse_define`]): they win over the file's
/// `<default>`s.
pub fn read_file(path: &Path, defines: &[(String, String)]) -> Result<Document, MitsubaError> {
    reader::Reader::new(defines).read_root_file(path)
}

/// Reads Mitsuba scene text already in memory (the name and folder of `source` are used for
/// messages and to resolve includes; without a folder, relative includes are not found).
pub fn read_source(source: SourceFile, defines: &[(String, String)]) -> Result<Document, MitsubaError> {
    reader::Reader::new(defines).read_root_source(source)
}
