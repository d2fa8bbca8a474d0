//! The reader: XML (through `roxmltree`) to the plugin tree, with includes, parameters, ids,
//! properties and transforms.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use glam::{DMat4, DVec3};

use super::error::MitsubaError;
use super::params::{Params, SubstituteError};
use super::spectrum::Spectrum;
use super::tree::{Child, Node, Plugin, PluginKind, Pos, Property, Value};
use super::upgrade::{Version, camel_to_snake, upgrade_plugin};
use super::{
    Document, MAX_ELEMENTS, MAX_INCLUDE_DEPTH, MAX_NESTING, MAX_SPD_FILE_BYTES, MAX_TOTAL_BYTES,
    MAX_XML_FILE_BYTES, numbers, transform,
};
use crate::scene::{Diagnostic, Location, Severity, SourceFile, Span};

type Result<T> = std::result::Result<T, MitsubaError>;

/// One attribute after `$name` substitution.
struct Attr<'a> {
    name: &'a str,
    value: String,
    /// The value's place (inside the quotes).
    pos: Pos,
}

/// The attributes of one element.
struct Attrs<'a> {
    list: Vec<Attr<'a>>,
}

impl<'a> Attrs<'a> {
    fn get(&self, name: &str) -> Option<&Attr<'a>> {
        self.list.iter().find(|a| a.name == name)
    }
}

/// What the reader knows about the file being read.
struct FileCtx {
    /// Index into `Reader::files`.
    index: u32,
    /// Whether the file's version is below 2.0.0.
    upgrade: bool,
    /// The folder of the file.
    dir: PathBuf,
    /// Mitsuba's file resolver while this file is read: folders tried in turn.
    resolver: Vec<PathBuf>,
    /// The canonical paths of the files that include this one, and this one (for cycles).
    chain: Vec<(PathBuf, String)>,
}

/// Where an id points: the plugin's serial number, and where the id was declared.
#[derive(Clone)]
struct IdEntry {
    serial: u32,
    pos: Pos,
}

/// A `<ref>` met, checked once the whole tree is read.
struct RefRecord {
    id: String,
    pos: Pos,
    /// The serial number of the plugin holding the reference.
    holder: u32,
}

/// The reader's state across all files of a document.
pub(super) struct Reader {
    files: Vec<SourceFile>,
    line_starts: Vec<Vec<usize>>,
    params: Params,
    ids: HashMap<String, IdEntry>,
    refs: Vec<RefRecord>,
    /// For each plugin, by serial number (the order plugins are met, which is the tree's
    /// preorder): its parent's serial number and its index among the parent's children.
    parents: Vec<(u32, u32)>,
    /// The parameter names given in each plugin (by serial number), with where.
    names: HashMap<(u32, String), Pos>,
    /// Per file, the last position computed: byte offset, line index and column (0-based, in
    /// characters), from which the next one is counted when it is further on the same line.
    last_pos: Vec<std::cell::Cell<(usize, usize, usize)>>,
    elements: usize,
    total_bytes: u64,
    warnings: Vec<Diagnostic>,
}

/// The parameters of an element's read.
#[derive(Clone, Copy)]
struct Here {
    /// The serial number of the plugin the element belongs to.
    serial: u32,
    /// Elements above this one (in all files).
    depth: usize,
    /// Whether the parent is the root element of its file (where `<path>` may be).
    at_file_root: bool,
}

impl Reader {
    pub(super) fn new(defines: &[(String, String)]) -> Reader {
        Reader {
            files: Vec::new(),
            line_starts: Vec::new(),
            params: Params::from_defines(defines),
            ids: HashMap::new(),
            refs: Vec::new(),
            parents: Vec::new(),
            names: HashMap::new(),
            last_pos: Vec::new(),
            elements: 0,
            total_bytes: 0,
            warnings: Vec::new(),
        }
    }

    // ----- positions -----

    fn add_file(&mut self, source: SourceFile) -> u32 {
        let text = source.text();
        let mut starts = vec![0];
        starts.extend(memchr::memchr_iter(b'\n', text.as_bytes()).map(|i| i + 1));
        self.line_starts.push(starts);
        self.last_pos.push(std::cell::Cell::new((0, 0, 0)));
        self.files.push(source);
        (self.files.len() - 1) as u32
    }

    /// The position of bytes `range` of file `file`, marked up to the end of their first line.
    fn pos(&self, file: u32, range: std::ops::Range<usize>) -> Pos {
        let text = self.files[file as usize].text();
        let starts = &self.line_starts[file as usize];
        let start = range.start.min(text.len());
        let line = starts.partition_point(|&s| s <= start).max(1);
        let line_start = starts[line - 1];
        let line_end = starts.get(line).map_or(text.len(), |&s| s - 1);
        // Counted on from the last position when it is earlier on the same line: elements and
        // attributes are met in file order, so a long line is not counted again for each.
        let cache = &self.last_pos[file as usize];
        let (from, from_column) = match cache.get() {
            (offset, l, c) if l == line - 1 && offset <= start => (offset, c),
            _ => (line_start, 0),
        };
        let column = text.get(from..start).map_or(0, |t| t.chars().count()) + from_column;
        cache.set((start, line - 1, column));
        let column = column + 1;
        let end = range.end.clamp(start, line_end.max(start));
        let len = text.get(start..end).map_or(1, |t| t.chars().count().max(1));
        Pos { file, span: Span { line: line as u32, column: column as u32, len: len as u32 } }
    }

    /// The position of an element: its `<` and name.
    fn element_pos(&self, file: u32, node: roxmltree::Node) -> Pos {
        let start = node.range().start;
        self.pos(file, start..start + 1 + node.tag_name().name().len())
    }

    pub(super) fn location(&self, pos: Pos) -> Location {
        self.files[pos.file as usize].location(pos.span)
    }

    fn place(&self, pos: Pos) -> String {
        format!("{}:{}:{}", self.files[pos.file as usize].name(), pos.span.line, pos.span.column)
    }

    // ----- files -----

    /// Reads a file's bytes, refusing folders, devices and files over the limits.
    fn read_bytes(&mut self, path: &Path) -> std::result::Result<Vec<u8>, String> {
        use std::io::Read;
        let metadata = std::fs::metadata(path).map_err(|e| e.to_string())?;
        if metadata.is_dir() {
            return Err("it is a directory".into());
        }
        if !metadata.is_file() {
            return Err("it is not a regular file".into());
        }
        if metadata.len() > MAX_XML_FILE_BYTES {
            return Err(format!(
                "it is larger than {} MiB, the most a scene file may take",
                MAX_XML_FILE_BYTES >> 20
            ));
        }
        let file = std::fs::File::open(path).map_err(|e| e.to_string())?;
        let mut bytes = Vec::with_capacity(metadata.len() as usize);
        file.take(MAX_XML_FILE_BYTES + 1).read_to_end(&mut bytes).map_err(|e| e.to_string())?;
        if bytes.len() as u64 > MAX_XML_FILE_BYTES {
            return Err(format!(
                "it is larger than {} MiB, the most a scene file may take",
                MAX_XML_FILE_BYTES >> 20
            ));
        }
        self.total_bytes += bytes.len() as u64;
        if self.total_bytes > MAX_TOTAL_BYTES {
            return Err(format!(
                "the scene's files take more than {} MiB together, the most a scene may take",
                MAX_TOTAL_BYTES >> 20
            ));
        }
        Ok(bytes)
    }

    /// Reads the first file and the whole tree below it.
    pub(super) fn read_root_file(mut self, path: &Path) -> Result<Document> {
        let name = path.display().to_string();
        let bytes =
            self.read_bytes(path).map_err(|message| MitsubaError::Read { file: name.clone(), message })?;
        let dir = parent_dir(path);
        let source = SourceFile::from_bytes(name.clone(), Some(dir.clone()), bytes);
        let canonical = std::fs::canonicalize(path).unwrap_or_else(|_| path.to_path_buf());
        self.read_root(source, dir, vec![(canonical, name)])
    }

    /// Reads the tree of scene text already in memory; includes and `<path>`s are resolved
    /// against `source.dir()` (none without one).
    pub(super) fn read_root_source(mut self, source: SourceFile) -> Result<Document> {
        self.total_bytes += source.text().len() as u64;
        let dir = source.dir().map(Path::to_path_buf).unwrap_or_default();
        let chain = vec![(dir.join(source.name()), source.name().to_owned())];
        self.read_root(source, dir, chain)
    }

    fn read_root(
        mut self,
        source: SourceFile,
        dir: PathBuf,
        chain: Vec<(PathBuf, String)>,
    ) -> Result<Document> {
        let index = self.add_file(source);
        let text = self.files[index as usize].text().to_owned();
        let doc = self.parse_xml(index, &text)?;
        let root = doc.root_element();
        // Text without a folder resolves nothing relative (not against the current directory).
        let resolver = if dir.as_os_str().is_empty() { Vec::new() } else { vec![dir.clone()] };
        let mut ctx = FileCtx { index, upgrade: false, dir, resolver, chain };
        let version = self.file_version(&mut ctx, root)?;
        if PluginKind::from_tag(root.tag_name().name()).is_none() && !is_typed_spectrum(root) {
            let at = self.element_pos(index, root);
            return Err(MitsubaError::Misplaced {
                at: self.location(at),
                message: format!(
                    "the root element must be a plugin such as <scene>, not <{}>",
                    root.tag_name().name()
                ),
            });
        }
        let root_plugin = self.object(&mut ctx, root, 0, None, true)?;
        self.finish(root_plugin, version, ctx.resolver)
    }

    /// Parses a file's text as XML (no DTD, a bounded number of nodes).
    fn parse_xml<'t>(&self, file: u32, text: &'t str) -> Result<roxmltree::Document<'t>> {
        let options = roxmltree::ParsingOptions {
            allow_dtd: false,
            nodes_limit: (4 * MAX_ELEMENTS) as u32,
            ..roxmltree::ParsingOptions::default()
        };
        roxmltree::Document::parse_with_options(text, options).map_err(|e| {
            let p = e.pos();
            let span = Span { line: p.row.max(1), column: p.col.max(1), len: 1 };
            // roxmltree's message ends with its own ` at line:column`, which the place shows.
            let message = e.to_string();
            let message = match message.rsplit_once(" at ") {
                Some((head, tail)) if tail.bytes().all(|b| b.is_ascii_digit() || b == b':') => {
                    head.to_owned()
                }
                _ => message,
            };
            MitsubaError::Xml { at: self.files[file as usize].location(span), message }
        })
    }

    /// Checks the root element's `version` and sets whether the file is upgraded.
    fn file_version(&mut self, ctx: &mut FileCtx, root: roxmltree::Node) -> Result<Version> {
        let Some(attr) = root.attribute_node("version") else {
            let at = self.element_pos(ctx.index, root);
            return Err(MitsubaError::MissingAttribute {
                at: self.location(at),
                attribute: "version",
                element: root.tag_name().name().to_owned(),
            });
        };
        let at = self.pos(ctx.index, attr.range_value());
        let version = Version::parse(attr.value())
            .ok_or_else(|| MitsubaError::Version { at: self.location(at), value: attr.value().to_owned() })?;
        ctx.upgrade = version.needs_upgrade();
        Ok(version)
    }

    /// After the tree is read: references resolved and checked for loops, unused `-D`
    /// definitions reported.
    fn finish(mut self, root: Plugin, version: Version, resolver: Vec<PathBuf>) -> Result<Document> {
        for r in &self.refs {
            if !self.ids.contains_key(&r.id) {
                return Err(MitsubaError::UnknownId { at: self.location(r.pos), id: r.id.clone() });
            }
        }
        self.check_cycles(&root)?;
        let parents = std::mem::take(&mut self.parents);
        let unused: Vec<String> =
            self.params.unused().map(|p| format!("{}={}", &p.key[1..], p.value)).collect();
        for define in unused {
            self.warnings.push(Diagnostic::general(
                Severity::Warning,
                format!("the definition -D {define} is not used by the scene"),
            ));
        }
        let ids = self.ids.into_iter().map(|(id, e)| (id, e.serial)).collect();
        Ok(Document { root, files: self.files, version, resolver, ids, parents, warnings: self.warnings })
    }

    /// Refuses plugins that need themselves: a plugin needs its nested plugins and the targets
    /// of its references; a loop through those is a circular reference.
    fn check_cycles(&self, root: &Plugin) -> Result<()> {
        // The plugins by serial number, and what each needs: its nested plugins (from
        // `parents`) and the targets of its references.
        let n = self.parents.len();
        let mut edges: Vec<Vec<(usize, Option<Pos>)>> = vec![Vec::new(); n];
        for (serial, &(parent, _)) in self.parents.iter().enumerate().skip(1) {
            if let Some(list) = edges.get_mut(parent as usize) {
                list.push((serial, None));
            }
        }
        for r in &self.refs {
            if let (Some(target), Some(list)) = (self.ids.get(&r.id), edges.get_mut(r.holder as usize)) {
                list.push((target.serial as usize, Some(r.pos)));
            }
        }
        // The plugins in preorder, which is their serial order, for messages.
        let nodes = || {
            let mut out = Vec::with_capacity(n);
            let mut stack = vec![root];
            while let Some(p) = stack.pop() {
                out.push(p);
                let at = stack.len();
                stack.extend(p.inline_children());
                stack[at..].reverse();
            }
            out
        };
        // Iterative depth-first search: 0 unseen, 1 on the stack, 2 done.
        let mut state = vec![0u8; n];
        for start in 0..n {
            if state[start] != 0 {
                continue;
            }
            let mut stack: Vec<(usize, usize)> = vec![(start, 0)];
            state[start] = 1;
            while let Some(&mut (node, ref mut next)) = stack.last_mut() {
                if let Some(&(target, pos)) = edges[node].get(*next) {
                    *next += 1;
                    match state[target] {
                        0 => {
                            state[target] = 1;
                            stack.push((target, 0));
                        }
                        1 => {
                            let nodes = nodes();
                            let name = |m: usize| nodes.get(m).map_or_else(String::new, |p| describe(p));
                            let from = stack.iter().position(|&(m, _)| m == target).unwrap_or(0);
                            let mut names: Vec<String> =
                                stack[from..].iter().map(|&(m, _)| name(m)).collect();
                            names.push(name(target));
                            let at = pos.or_else(|| nodes.get(node).map(|p| p.pos)).unwrap_or(root.pos);
                            return Err(MitsubaError::CircularReference {
                                at: self.location(at),
                                chain: names.join(" -> "),
                            });
                        }
                        _ => {}
                    }
                } else {
                    state[node] = 2;
                    stack.pop();
                }
            }
        }
        Ok(())
    }

    // ----- elements -----

    /// Counts an element against [`MAX_ELEMENTS`] and checks the nesting.
    fn count(&mut self, ctx: &FileCtx, node: roxmltree::Node, depth: usize) -> Result<()> {
        self.elements += 1;
        if self.elements > MAX_ELEMENTS {
            let at = self.element_pos(ctx.index, node);
            return Err(MitsubaError::Limit {
                at: self.location(at),
                message: format!("the scene has more than {MAX_ELEMENTS} elements, the most it may have"),
            });
        }
        if depth > MAX_NESTING {
            let at = self.element_pos(ctx.index, node);
            return Err(MitsubaError::Limit {
                at: self.location(at),
                message: format!("elements nested more than {MAX_NESTING} deep"),
            });
        }
        Ok(())
    }

    /// The element's attributes with `$name` substituted.
    fn attrs<'a>(&mut self, ctx: &FileCtx, node: roxmltree::Node<'a, '_>) -> Result<Attrs<'a>> {
        let mut list = Vec::new();
        for a in node.attributes() {
            let pos = self.pos(ctx.index, a.range_value());
            let value = match self.params.substitute(a.value()) {
                None => a.value().to_owned(),
                Some(Ok(v)) => v,
                Some(Err(SubstituteError::Undefined(name))) => {
                    return Err(MitsubaError::UndefinedParameter { at: self.location(pos), name });
                }
                Some(Err(SubstituteError::TooLong)) => {
                    return Err(MitsubaError::Limit {
                        at: self.location(pos),
                        message: format!(
                            "the value is longer than {} KiB after substitution",
                            super::params::MAX_SUBSTITUTED_BYTES >> 10
                        ),
                    });
                }
            };
            list.push(Attr { name: a.name(), value, pos });
        }
        Ok(Attrs { list })
    }

    /// Refuses attributes outside `allowed` and requires those of `required`.
    fn check_attrs(
        &self,
        ctx: &FileCtx,
        node: roxmltree::Node,
        attrs: &Attrs,
        allowed: &[&str],
        required: &[&'static str],
    ) -> Result<()> {
        if let Some(a) = attrs.list.iter().find(|a| !allowed.contains(&a.name) && !required.contains(&a.name))
        {
            // The attribute's name: just before its value, `name="`.
            let name_pos = node
                .attributes()
                .find(|x| x.name() == a.name)
                .map_or(a.pos, |x| self.pos(ctx.index, x.range_qname()));
            return Err(MitsubaError::UnexpectedAttribute {
                at: self.location(name_pos),
                attribute: a.name.to_owned(),
                element: node.tag_name().name().to_owned(),
            });
        }
        if let Some(missing) = required.iter().find(|r| attrs.get(r).is_none()) {
            let at = self.element_pos(ctx.index, node);
            return Err(MitsubaError::MissingAttribute {
                at: self.location(at),
                attribute: missing,
                element: node.tag_name().name().to_owned(),
            });
        }
        Ok(())
    }

    /// Reads an object element (`<bsdf>`, `<shape>`, the `<scene>`...) and its contents.
    /// `link` is the parent's serial number and the plugin's index among its children (none for
    /// the root); `is_root` whether the element is the root of its file.
    fn object(
        &mut self,
        ctx: &mut FileCtx,
        node: roxmltree::Node,
        depth: usize,
        link: Option<(u32, u32)>,
        is_root: bool,
    ) -> Result<Plugin> {
        self.count(ctx, node, depth)?;
        let serial = self.parents.len() as u32;
        self.parents.push(link.unwrap_or((u32::MAX, 0)));
        let tag = node.tag_name().name();
        let kind = PluginKind::from_tag(tag).unwrap_or(PluginKind::Texture);
        // The element's place first: positions are counted on from the last one.
        let pos = self.element_pos(ctx.index, node);
        let attrs = self.attrs(ctx, node)?;
        if is_root {
            self.check_attrs(ctx, node, &attrs, &["type", "id", "name"], &["version"])?;
        } else {
            self.check_attrs(ctx, node, &attrs, &["id", "name"], &["type"])?;
        }
        let type_name = attrs.get("type").map_or_else(|| tag.to_owned(), |a| a.value.clone());
        let id = attrs.get("id").map(|a| a.value.clone());
        if let Some(id) = &id {
            self.declare_id(id, serial, pos)?;
        }
        let name = attrs.get("name").map(|a| self.prop_name(ctx, &a.value));
        let mut plugin =
            Plugin { kind, type_name, id, name, properties: Vec::new(), children: Vec::new(), pos };
        for child in node.children().filter(roxmltree::Node::is_element) {
            let sub = Here { serial, depth: depth + 1, at_file_root: is_root };
            self.element(ctx, child, &mut plugin, sub)?;
        }
        if ctx.upgrade {
            upgrade_plugin(&mut plugin);
        }
        Ok(plugin)
    }

    fn declare_id(&mut self, id: &str, serial: u32, pos: Pos) -> Result<()> {
        if let Some(previous) = self.ids.get(id) {
            return Err(MitsubaError::DuplicateId {
                at: self.location(pos),
                id: id.to_owned(),
                previous: self.place(previous.pos),
            });
        }
        self.ids.insert(id.to_owned(), IdEntry { serial, pos });
        Ok(())
    }

    /// A parameter name as the tree keeps it: snake_case in files below 2.0.0.
    fn prop_name(&self, ctx: &FileCtx, name: &str) -> String {
        if ctx.upgrade { camel_to_snake(name) } else { name.to_owned() }
    }

    /// Refuses a second property or named child called `name` in the plugin of serial number
    /// `serial`, and remembers this one.
    fn check_unique(&mut self, serial: u32, name: &str, pos: Pos) -> Result<()> {
        match self.names.entry((serial, name.to_owned())) {
            std::collections::hash_map::Entry::Occupied(first) => {
                let previous = *first.get();
                Err(MitsubaError::DuplicateProperty {
                    at: self.location(pos),
                    name: name.to_owned(),
                    previous: self.place(previous),
                })
            }
            std::collections::hash_map::Entry::Vacant(slot) => {
                slot.insert(pos);
                Ok(())
            }
        }
    }

    /// Reads one child element of `parent`.
    fn element(
        &mut self,
        ctx: &mut FileCtx,
        node: roxmltree::Node,
        parent: &mut Plugin,
        here: Here,
    ) -> Result<()> {
        let tag = node.tag_name().name();
        if node.tag_name().namespace().is_some() {
            let at = self.element_pos(ctx.index, node);
            return Err(MitsubaError::UnknownTag { at: self.location(at), tag: tag.to_owned() });
        }
        if PluginKind::from_tag(tag).is_some() || is_typed_spectrum(node) {
            let index = parent.children.len() as u32;
            let plugin = self.object(ctx, node, here.depth, Some((here.serial, index)), false)?;
            if let Some(name) = &plugin.name {
                self.check_unique(here.serial, name, plugin.pos)?;
            }
            parent.children.push(Child {
                name: plugin.name.clone(),
                pos: plugin.pos,
                node: Node::Plugin(plugin),
            });
            return Ok(());
        }
        self.count(ctx, node, here.depth)?;
        let pos = self.element_pos(ctx.index, node);
        let attrs = self.attrs(ctx, node)?;
        match tag {
            "ref" => {
                self.check_attrs(ctx, node, &attrs, &["name"], &["id"])?;
                self.no_children(ctx, node)?;
                let name = attrs.get("name").map(|a| self.prop_name(ctx, &a.value));
                if let Some(name) = &name {
                    self.check_unique(here.serial, name, pos)?;
                }
                let id = attrs.get("id").map(|a| a.value.clone()).unwrap_or_default();
                self.refs.push(RefRecord { id: id.clone(), pos, holder: here.serial });
                parent.children.push(Child { name, node: Node::Reference(id), pos });
            }
            "alias" => {
                self.check_attrs(ctx, node, &attrs, &[], &["id", "as"])?;
                self.no_children(ctx, node)?;
                let (Some(src), Some(dst)) = (attrs.get("id"), attrs.get("as")) else { return Ok(()) };
                let Some(entry) = self.ids.get(&src.value).cloned() else {
                    return Err(MitsubaError::UnknownId {
                        at: self.location(src.pos),
                        id: src.value.clone(),
                    });
                };
                self.declare_id(&dst.value, entry.serial, pos)?;
            }
            "default" => {
                self.check_attrs(ctx, node, &attrs, &[], &["name", "value"])?;
                self.no_children(ctx, node)?;
                let (Some(name), Some(value)) = (attrs.get("name"), attrs.get("value")) else {
                    return Ok(());
                };
                if name.value.is_empty() {
                    return Err(MitsubaError::Value {
                        at: self.location(name.pos),
                        message: "a <default> needs a name".into(),
                    });
                }
                if !self.params.set_default(&name.value, &value.value) {
                    return Err(MitsubaError::Limit {
                        at: self.location(pos),
                        message: format!("more than {} parameters", super::params::MAX_PARAMETERS),
                    });
                }
            }
            "path" => {
                self.check_attrs(ctx, node, &attrs, &[], &["value"])?;
                self.no_children(ctx, node)?;
                if !here.at_file_root {
                    return Err(MitsubaError::Misplaced {
                        at: self.location(pos),
                        message: "<path> may only be a child of the root element".into(),
                    });
                }
                let Some(value) = attrs.get("value") else { return Ok(()) };
                let folder = Path::new(&value.value);
                let mut resolved = if folder.is_absolute() {
                    Some(folder.to_path_buf())
                } else if ctx.dir.as_os_str().is_empty() {
                    None
                } else {
                    Some(ctx.dir.join(folder))
                };
                if !resolved.as_ref().is_some_and(|r| r.exists()) {
                    resolved = resolve(&ctx.resolver, &value.value);
                }
                let Some(resolved) = resolved.filter(|r| r.is_dir()) else {
                    return Err(MitsubaError::PathNotFound {
                        at: self.location(value.pos),
                        folder: value.value.clone(),
                    });
                };
                ctx.resolver.insert(0, resolved);
            }
            "include" => {
                self.check_attrs(ctx, node, &attrs, &["name"], &["filename"])?;
                self.no_children(ctx, node)?;
                self.include(ctx, &attrs, pos, parent, here)?;
            }
            "transform" => {
                self.check_attrs(ctx, node, &attrs, &[], &["name"])?;
                let matrix = self.transform(ctx, node, &here)?;
                let name = self.attr_name(ctx, &attrs);
                self.check_unique(here.serial, &name, pos)?;
                parent.properties.push(Property { name, value: Value::Transform(matrix), pos });
            }
            "translate" | "rotate" | "scale" | "lookat" | "matrix" => {
                return Err(MitsubaError::Misplaced {
                    at: self.location(pos),
                    message: format!("<{tag}> may only be inside a <transform>"),
                });
            }
            "lookAt" if ctx.upgrade => {
                return Err(MitsubaError::Misplaced {
                    at: self.location(pos),
                    message: format!("<{tag}> may only be inside a <transform>"),
                });
            }
            _ => {
                let value = self.property_value(ctx, node, tag, &attrs, pos)?;
                self.no_children(ctx, node)?;
                let name = self.attr_name(ctx, &attrs);
                self.check_unique(here.serial, &name, pos)?;
                parent.properties.push(Property { name, value, pos });
            }
        }
        Ok(())
    }

    /// The upgraded `name` attribute (checked present by the caller).
    fn attr_name(&self, ctx: &FileCtx, attrs: &Attrs) -> String {
        attrs.get("name").map(|a| self.prop_name(ctx, &a.value)).unwrap_or_default()
    }

    /// Refuses child elements of a property.
    fn no_children(&self, ctx: &FileCtx, node: roxmltree::Node) -> Result<()> {
        match node.children().find(roxmltree::Node::is_element) {
            Some(child) => {
                let at = self.element_pos(ctx.index, child);
                Err(MitsubaError::Misplaced {
                    at: self.location(at),
                    message: format!(
                        "<{}> cannot be inside <{}>, which is a property",
                        child.tag_name().name(),
                        node.tag_name().name()
                    ),
                })
            }
            None => Ok(()),
        }
    }

    /// A finite number from an attribute.
    fn float(&self, attr: &Attr) -> Result<f64> {
        numbers::float(&attr.value).ok_or_else(|| MitsubaError::Number {
            at: self.location(attr.pos),
            value: attr.value.clone(),
            expected: "a finite number",
        })
    }

    /// Finite numbers from a list attribute.
    fn floats(&self, attr: &Attr) -> Result<Vec<f64>> {
        numbers::tokens(&attr.value)
            .map(|t| {
                numbers::float(t).ok_or_else(|| MitsubaError::Number {
                    at: self.location(attr.pos),
                    value: t.to_owned(),
                    expected: "a finite number",
                })
            })
            .collect()
    }

    /// The value of a property element (`<float>`, `<rgb>`...).
    fn property_value(
        &mut self,
        ctx: &FileCtx,
        node: roxmltree::Node,
        tag: &str,
        attrs: &Attrs,
        pos: Pos,
    ) -> Result<Value> {
        Ok(match tag {
            "integer" | "float" | "boolean" | "string" | "rgb" => {
                self.check_attrs(ctx, node, attrs, &[], &["name", "value"])?;
                let Some(v) = attrs.get("value") else { return Err(self.internal(pos)) };
                match tag {
                    "integer" => {
                        Value::Integer(numbers::integer(&v.value).ok_or_else(|| MitsubaError::Number {
                            at: self.location(v.pos),
                            value: v.value.clone(),
                            expected: "an integer",
                        })?)
                    }
                    "float" => Value::Float(self.float(v)?),
                    "boolean" => {
                        Value::Boolean(numbers::boolean(&v.value).ok_or_else(|| MitsubaError::Number {
                            at: self.location(v.pos),
                            value: v.value.clone(),
                            expected: "`true` or `false`",
                        })?)
                    }
                    "string" => Value::String(v.value.clone()),
                    _ => {
                        let c = self.floats(v)?;
                        match c[..] {
                            [g] => Value::Rgb(DVec3::splat(g)),
                            [r, g, b] => Value::Rgb(DVec3::new(r, g, b)),
                            _ => {
                                return Err(MitsubaError::Value {
                                    at: self.location(v.pos),
                                    message: format!("<rgb> takes one or three values, found {}", c.len()),
                                });
                            }
                        }
                    }
                }
            }
            "point" | "vector" => {
                let v = self.xyz(ctx, node, attrs, &["name"], 0.0, true)?;
                if tag == "point" { Value::Point(v) } else { Value::Vector(v) }
            }
            "spectrum" => {
                self.check_attrs(ctx, node, attrs, &["value", "filename"], &["name"])?;
                Value::Spectrum(self.spectrum(ctx, attrs, pos)?)
            }
            _ => {
                return Err(MitsubaError::UnknownTag { at: self.location(pos), tag: tag.to_owned() });
            }
        })
    }

    /// An error for a state the checks before exclude (kept instead of a panic).
    fn internal(&self, pos: Pos) -> MitsubaError {
        MitsubaError::Value {
            at: self.location(pos),
            message: "internal error: attribute checked but missing".into(),
        }
    }

    /// `x`, `y`, `z` attributes, or `value` with one or three numbers (not both), missing
    /// components `default`; with `required`, all three must be given.
    fn xyz(
        &self,
        ctx: &FileCtx,
        node: roxmltree::Node,
        attrs: &Attrs,
        extra: &[&str],
        default: f64,
        required: bool,
    ) -> Result<DVec3> {
        let mut allowed: Vec<&str> = vec!["x", "y", "z", "value"];
        allowed.extend_from_slice(extra);
        let required_attrs: &[&'static str] = if extra.contains(&"name") { &["name"] } else { &[] };
        self.check_attrs(ctx, node, attrs, &allowed, required_attrs)?;
        let pos = self.element_pos(ctx.index, node);
        if let Some(v) = attrs.get("value") {
            if let Some(a) = ["x", "y", "z"].iter().find_map(|n| attrs.get(n)) {
                return Err(MitsubaError::Value {
                    at: self.location(a.pos),
                    message: "`value` and `x`/`y`/`z` cannot both be given".into(),
                });
            }
            let c = self.floats(v)?;
            return match c[..] {
                [a] => Ok(DVec3::splat(a)),
                [x, y, z] => Ok(DVec3::new(x, y, z)),
                _ => Err(MitsubaError::Value {
                    at: self.location(v.pos),
                    message: format!("`value` takes one or three numbers, found {}", c.len()),
                }),
            };
        }
        let mut out = DVec3::splat(default);
        for (i, n) in ["x", "y", "z"].iter().enumerate() {
            match attrs.get(n) {
                Some(a) => out[i] = self.float(a)?,
                None if required => {
                    return Err(MitsubaError::MissingAttribute {
                        at: self.location(pos),
                        attribute: ["x", "y", "z"][i],
                        element: node.tag_name().name().to_owned(),
                    });
                }
                None => {}
            }
        }
        Ok(out)
    }

    /// A `<spectrum>`'s value: `value` or `filename` (a `.spd` file), exactly one.
    fn spectrum(&mut self, ctx: &FileCtx, attrs: &Attrs, pos: Pos) -> Result<Spectrum> {
        let value = attrs.get("value").filter(|a| !a.value.is_empty());
        let filename = attrs.get("filename").filter(|a| !a.value.is_empty());
        match (value, filename) {
            (Some(v), None) => Spectrum::parse(&v.value)
                .map_err(|message| MitsubaError::Value { at: self.location(v.pos), message }),
            (None, Some(f)) => {
                let Some(path) = resolve(&ctx.resolver, &f.value) else {
                    return Err(MitsubaError::ReadAt {
                        at: self.location(f.pos),
                        file: f.value.clone(),
                        message: "file not found".into(),
                    });
                };
                let read_error = |message: String| MitsubaError::ReadAt {
                    at: self.location(f.pos),
                    file: path.display().to_string(),
                    message,
                };
                let text = read_text(&path, MAX_SPD_FILE_BYTES).map_err(read_error)?;
                Spectrum::parse_spd(&text).map_err(read_error)
            }
            _ => Err(MitsubaError::Value {
                at: self.location(pos),
                message: "<spectrum> needs either `value` or `filename` (one of them)".into(),
            }),
        }
    }

    /// A `<transform>`'s operations, composed in Mitsuba's order (each on the left).
    fn transform(&mut self, ctx: &FileCtx, node: roxmltree::Node, here: &Here) -> Result<DMat4> {
        let mut m = DMat4::IDENTITY;
        for op in node.children().filter(roxmltree::Node::is_element) {
            self.count(ctx, op, here.depth + 1)?;
            let pos = self.element_pos(ctx.index, op);
            let attrs = self.attrs(ctx, op)?;
            self.no_children(ctx, op)?;
            let tag = op.tag_name().name();
            let step = match tag {
                "translate" => transform::translate(self.xyz(ctx, op, &attrs, &[], 0.0, false)?),
                "scale" => transform::scale(self.xyz(ctx, op, &attrs, &[], 1.0, false)?),
                "rotate" => {
                    let axis = self.xyz(ctx, op, &attrs, &["angle"], 0.0, false)?;
                    let Some(angle) = attrs.get("angle") else {
                        return Err(MitsubaError::MissingAttribute {
                            at: self.location(pos),
                            attribute: "angle",
                            element: tag.to_owned(),
                        });
                    };
                    let angle = self.float(angle)?;
                    transform::rotate(axis, angle).ok_or_else(|| MitsubaError::SingularTransform {
                        at: self.location(pos),
                        message: "the rotation axis is zero".into(),
                    })?
                }
                "lookat" | "lookAt" if tag == "lookat" || ctx.upgrade => {
                    self.check_attrs(ctx, op, &attrs, &["up"], &["origin", "target"])?;
                    let vector = |name: &str| -> Result<DVec3> {
                        let Some(a) = attrs.get(name) else { return Ok(DVec3::ZERO) };
                        let c = self.floats(a)?;
                        match c[..] {
                            [x, y, z] => Ok(DVec3::new(x, y, z)),
                            _ => Err(MitsubaError::Value {
                                at: self.location(a.pos),
                                message: format!("`{name}` takes three numbers, found {}", c.len()),
                            }),
                        }
                    };
                    let (origin, target, up) = (vector("origin")?, vector("target")?, vector("up")?);
                    transform::look_at(origin, target, up).ok_or_else(|| MitsubaError::SingularTransform {
                        at: self.location(pos),
                        message:
                            "degenerate <lookat>: the target is at the origin, or `up` is along the view"
                                .into(),
                    })?
                }
                "matrix" => {
                    self.check_attrs(ctx, op, &attrs, &[], &["value"])?;
                    let Some(v) = attrs.get("value") else { return Err(self.internal(pos)) };
                    let values = self.floats(v)?;
                    transform::matrix(&values).ok_or_else(|| MitsubaError::Value {
                        at: self.location(v.pos),
                        message: format!("<matrix> takes 16 or 9 numbers, found {}", values.len()),
                    })?
                }
                _ => {
                    return Err(MitsubaError::Misplaced {
                        at: self.location(pos),
                        message: format!("<{tag}> cannot be inside a <transform>"),
                    });
                }
            };
            if transform::is_singular(&step) {
                return Err(MitsubaError::SingularTransform {
                    at: self.location(pos),
                    message: format!("<{tag}> makes the transform singular (it cannot be inverted)"),
                });
            }
            m = step * m;
            if transform::is_singular(&m) {
                return Err(MitsubaError::SingularTransform {
                    at: self.location(pos),
                    message: "the transform is singular (it cannot be inverted)".into(),
                });
            }
        }
        Ok(m)
    }

    /// `<include filename="..."/>`: the file's root `<scene>`'s children join `parent` in its
    /// place; another root element becomes one child (named by the include's `name`).
    fn include(
        &mut self,
        ctx: &mut FileCtx,
        attrs: &Attrs,
        pos: Pos,
        parent: &mut Plugin,
        here: Here,
    ) -> Result<()> {
        let Some(filename) = attrs.get("filename") else { return Ok(()) };
        // Mitsuba: the resolver of the including file, its folder first.
        let mut resolver = ctx.resolver.clone();
        if !ctx.dir.as_os_str().is_empty() {
            resolver.insert(0, ctx.dir.clone());
        }
        let Some(path) = resolve(&resolver, &filename.value) else {
            return Err(MitsubaError::IncludeNotFound {
                at: self.location(filename.pos),
                file: filename.value.clone(),
            });
        };
        let name = path.display().to_string();
        let canonical = std::fs::canonicalize(&path).unwrap_or_else(|_| path.clone());
        if let Some(first) = ctx.chain.iter().position(|(c, _)| *c == canonical) {
            let mut names: Vec<&str> = ctx.chain[first..].iter().map(|(_, n)| n.as_str()).collect();
            names.push(&name);
            return Err(MitsubaError::RecursiveInclude { at: self.location(pos), chain: names.join(" -> ") });
        }
        // The chain holds the first file and each include below it.
        if ctx.chain.len() > MAX_INCLUDE_DEPTH {
            return Err(MitsubaError::Limit {
                at: self.location(pos),
                message: format!("includes nested more than {MAX_INCLUDE_DEPTH} deep"),
            });
        }
        let bytes = self.read_bytes(&path).map_err(|message| MitsubaError::ReadAt {
            at: self.location(filename.pos),
            file: name.clone(),
            message,
        })?;
        let dir = parent_dir(&path);
        let index = self.add_file(SourceFile::from_bytes(name.clone(), Some(dir.clone()), bytes));
        let text = self.files[index as usize].text().to_owned();
        let doc = self.parse_xml(index, &text)?;
        let root = doc.root_element();
        let mut chain = ctx.chain.clone();
        chain.push((canonical, name));
        let mut inner = FileCtx { index, upgrade: false, dir, resolver, chain };
        self.file_version(&mut inner, root)?;
        if root.tag_name().name() == "scene" {
            let attrs = self.attrs(&inner, root)?;
            self.check_attrs(&inner, root, &attrs, &["type", "id", "name"], &["version"])?;
            for child in root.children().filter(roxmltree::Node::is_element) {
                let sub = Here { serial: here.serial, depth: here.depth + 1, at_file_root: true };
                self.element(&mut inner, child, parent, sub)?;
            }
            return Ok(());
        }
        if PluginKind::from_tag(root.tag_name().name()).is_none() && !is_typed_spectrum(root) {
            let at = self.element_pos(index, root);
            return Err(MitsubaError::Misplaced {
                at: self.location(at),
                message: format!(
                    "the root element of an included file must be a plugin, not <{}>",
                    root.tag_name().name()
                ),
            });
        }
        let child_index = parent.children.len() as u32;
        let mut plugin =
            self.object(&mut inner, root, here.depth + 1, Some((here.serial, child_index)), true)?;
        plugin.name = attrs.get("name").map(|a| self.prop_name(ctx, &a.value));
        if let Some(name) = &plugin.name {
            self.check_unique(here.serial, name, pos)?;
        }
        parent.children.push(Child {
            name: plugin.name.clone(),
            pos: plugin.pos,
            node: Node::Plugin(plugin),
        });
        Ok(())
    }
}

/// Whether `node` is `<spectrum type="...">`, which Mitsuba reads as a texture plugin.
fn is_typed_spectrum(node: roxmltree::Node) -> bool {
    node.tag_name().name() == "spectrum" && node.has_attribute("type")
}

/// A plugin as cycle messages name it: its id, or its element and type.
fn describe(p: &Plugin) -> String {
    match &p.id {
        Some(id) => id.clone(),
        None => format!("<{} type=\"{}\">", p.kind.tag(), p.type_name),
    }
}

/// The folder of a file (`.` for a bare file name).
fn parent_dir(path: &Path) -> PathBuf {
    match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    }
}

/// Mitsuba's file resolver: an absolute path as it is; a relative one in the first folder of
/// `folders` that has it. `None` when no folder has it.
pub(super) fn resolve(folders: &[PathBuf], name: &str) -> Option<PathBuf> {
    let path = Path::new(name);
    if path.is_absolute() {
        return path.exists().then(|| path.to_path_buf());
    }
    folders.iter().map(|f| f.join(path)).find(|p| p.exists())
}

/// Reads a small text file (a `.spd` spectrum), refusing it over `limit` bytes.
fn read_text(path: &Path, limit: u64) -> std::result::Result<String, String> {
    use std::io::Read;
    let metadata = std::fs::metadata(path).map_err(|e| e.to_string())?;
    if !metadata.is_file() {
        return Err("it is not a regular file".into());
    }
    if metadata.len() > limit {
        return Err(format!("it is larger than {} KiB", limit >> 10));
    }
    let mut bytes = Vec::new();
    std::fs::File::open(path)
        .and_then(|f| f.take(limit + 1).read_to_end(&mut bytes))
        .map_err(|e| e.to_string())?;
    if bytes.len() as u64 > limit {
        return Err(format!("it is larger than {} KiB", limit >> 10));
    }
    String::from_utf8(bytes).map_err(|_| "it is not UTF-8 text".into())
}
