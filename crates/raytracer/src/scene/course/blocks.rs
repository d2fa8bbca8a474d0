//! The block state machine: block headers, key lines and `end`, the blocks' kinds and the
//! keys each knows, and the parser's state across lines.

use std::collections::HashMap;
use std::fmt;
use std::sync::Arc;

use super::super::{PhotonSettings, Scene};
use super::lexer::{Token, char_count, tokenize};
use super::{MAX_KEPT_DIAGNOSTICS, Omitted, parser_has_errors};
use crate::base::diagnostic::{Diagnostic, Severity, clip};
use crate::base::source::{SourceFile, Span, numbered_lines};
use crate::material::{CourseMaterial, Material};

/// The kinds of block.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum BlockKind {
    Background,
    Camera,
    Light(LightKind),
    Primitive(PrimitiveKind),
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum LightKind {
    Point,
    Square,
    Sphere,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum PrimitiveKind {
    Sphere,
    Plane,
    Square,
    Cylinder,
    Triangle,
    /// `primitive mesh` (`file=`, `scale=`, `rotation=` in radians).
    Mesh,
    /// `primitive polyhedron` (`mesh=`, `size=`, `angles=` in degrees).
    Polyhedron,
    Bezier,
}

impl PrimitiveKind {
    /// The kind a `primitive` (or `obj`) header names.
    pub(super) fn from_name(name: &str) -> Option<PrimitiveKind> {
        Some(match name {
            "sphere" => PrimitiveKind::Sphere,
            "plane" => PrimitiveKind::Plane,
            "square" => PrimitiveKind::Square,
            "cylinder" => PrimitiveKind::Cylinder,
            "triangle" => PrimitiveKind::Triangle,
            "mesh" => PrimitiveKind::Mesh,
            "polyhedron" => PrimitiveKind::Polyhedron,
            "bezier" => PrimitiveKind::Bezier,
            _ => return None,
        })
    }

    pub(super) fn name(self) -> &'static str {
        match self {
            PrimitiveKind::Sphere => "sphere",
            PrimitiveKind::Plane => "plane",
            PrimitiveKind::Square => "square",
            PrimitiveKind::Cylinder => "cylinder",
            PrimitiveKind::Triangle => "triangle",
            PrimitiveKind::Mesh => "mesh",
            PrimitiveKind::Polyhedron => "polyhedron",
            PrimitiveKind::Bezier => "bezier",
        }
    }
}

impl fmt::Display for BlockKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            BlockKind::Background => "background",
            BlockKind::Camera => "camera",
            BlockKind::Light(LightKind::Point) => "light point",
            BlockKind::Light(LightKind::Square) => "light square",
            BlockKind::Light(LightKind::Sphere) => "light sphere",
            BlockKind::Primitive(kind) => return write!(f, "primitive {}", kind.name()),
        })
    }
}

/// Keys every primitive accepts (material keys).
pub(super) const MATERIAL_KEYS: [&str; 12] =
    ["color", "texture", "bump", "NT", "diff", "spec", "refl", "drefl", "blur", "refr", "rindex", "absor"];

/// The types of `primitive` blocks, as the error for a missing type lists them.
pub(super) const PRIMITIVE_TYPES: &str =
    "`sphere`, `plane`, `square`, `cylinder`, `triangle`, `mesh`, `polyhedron` or `bezier`";

/// Primitive types that some students' renderers had and that their own parsers ignored too
/// (spec section 9): skipped with a warning that says so.
pub(super) const IGNORED_PRIMITIVES: [&str; 2] = ["torus", "cube"];

/// Primitive types of LuChengTHU's renderer of the course that are other names of ours: its
/// normal-mapped sphere and plane (`NT=` the normal map; spelled so), read as `sphere` and `plane`
/// with a note.
pub(super) const ALIAS_PRIMITIVES: [(&str, PrimitiveKind); 2] =
    [("NomalBall", PrimitiveKind::Sphere), ("NomalPlane", PrimitiveKind::Plane)];

/// The key a `primitive bezier` block repeats, one control point a line (`P= z r`).
pub(super) const BEZIER_POINT_KEY: &str = "P";

/// One `key= values` line of a block, borrowing the file's text.
#[derive(Clone, Debug)]
pub(super) struct Entry<'s> {
    pub(super) key: &'s str,
    pub(super) key_span: Span,
    /// The value tokens (the text after `=` when glued to the key counts as the first), at most
    /// [`MAX_VALUES_KEPT`] of them.
    pub(super) values: Values<'s>,
    /// How many values the line has, kept or not.
    pub(super) value_count: usize,
    /// The span of all the values, or of the key when there are none.
    pub(super) all_values: Span,
}

/// Most values kept from one key line: no key takes more than a few, and a hostile line may hold
/// millions (the rest are counted, not kept).
pub(super) const MAX_VALUES_KEPT: usize = 16;

/// The values of a key line: up to four inline (a scene of a million spheres allocates nothing
/// per line), more on the heap.
#[derive(Clone, Debug)]
pub(super) enum Values<'s> {
    Inline([(&'s str, Span); 4], u8),
    Heap(Vec<(&'s str, Span)>),
}

impl<'s> Values<'s> {
    pub(super) fn new() -> Values<'s> {
        Values::Inline([("", Span { line: 0, column: 0, len: 0 }); 4], 0)
    }

    pub(super) fn push(&mut self, v: (&'s str, Span)) {
        match self {
            Values::Inline(items, n) if (*n as usize) < items.len() => {
                items[*n as usize] = v;
                *n += 1;
            }
            Values::Inline(items, _) => {
                let mut heap = items.to_vec();
                heap.push(v);
                *self = Values::Heap(heap);
            }
            Values::Heap(h) => h.push(v),
        }
    }
}

impl<'s> std::ops::Deref for Values<'s> {
    type Target = [(&'s str, Span)];
    fn deref(&self) -> &Self::Target {
        match self {
            Values::Inline(items, n) => &items[..*n as usize],
            Values::Heap(h) => h,
        }
    }
}

impl Entry<'_> {
    /// The span of all values, or of the key when there are none.
    pub(super) fn values_span(&self) -> Span {
        self.all_values
    }
}

/// A block being read: its kind, header position and key lines (the last of each key, and every
/// `P=` line of a Bezier block).
pub(super) struct OpenBlock<'s> {
    pub(super) kind: BlockKind,
    pub(super) header: Span,
    pub(super) entries: Vec<Entry<'s>>,
    /// The entry of each key, once there are more than [`INDEXED_ENTRIES`] (a hostile block may
    /// hold a million keys); smaller blocks are searched in order.
    pub(super) index: HashMap<&'s str, usize>,
}

/// Blocks with more key lines than this find their keys through an index.
pub(super) const INDEXED_ENTRIES: usize = 16;

impl<'s> OpenBlock<'s> {
    /// The position in `entries` of the entry of `key` (for a repeatable key, of one of them).
    pub(super) fn position(&self, key: &str) -> Option<usize> {
        if self.entries.len() > INDEXED_ENTRIES {
            self.index.get(key).copied()
        } else {
            self.entries.iter().position(|e| e.key == key)
        }
    }

    /// Adds the entry of a key not seen before, or of a repeatable key.
    pub(super) fn push(&mut self, entry: Entry<'s>) {
        let key = entry.key;
        self.entries.push(entry);
        let n = self.entries.len();
        if n == INDEXED_ENTRIES + 1 {
            for (i, e) in self.entries.iter().enumerate() {
                self.index.insert(e.key, i);
            }
        } else if n > INDEXED_ENTRIES {
            self.index.insert(key, n - 1);
        }
    }
}

/// Parser state between lines.
pub(super) enum State<'s> {
    TopLevel,
    InBlock(OpenBlock<'s>),
    /// Skipping an unknown block up to its `end`; the span of its header.
    Skipping(Span),
}

/// Which single blocks have been seen (a second one replaces the first, with a warning).
#[derive(Default)]
pub(super) struct Seen {
    pub(super) background: Option<u32>,
    pub(super) camera: Option<u32>,
}

pub(super) struct Parser<'s> {
    pub(super) source: &'s SourceFile,
    pub(super) diagnostics: Vec<Diagnostic>,
    /// How many errors and others are in `diagnostics`.
    pub(super) kept: Omitted,
    /// How many were reported past [`MAX_KEPT_DIAGNOSTICS`] and dropped.
    pub(super) omitted: Omitted,
    /// Where a dropped diagnostic is built (its notes are added to it, then it is overwritten).
    pub(super) scratch: Diagnostic,
    pub(super) scene: Scene,
    pub(super) seen: Seen,
    /// Untextured materials seen so far, by their numbers' bits (see [`Parser::share`]).
    pub(super) materials: HashMap<[u64; 12], Arc<Material>, foldhash::fast::FixedState>,
    /// The emptied entry list of the last block read, for the next block to fill (a scene of a
    /// million spheres then allocates no list per block).
    pub(super) spare_entries: Vec<Entry<'s>>,
}

impl<'s> Parser<'s> {
    pub(super) fn new(source: &'s SourceFile) -> Parser<'s> {
        Parser {
            source,
            diagnostics: Vec::new(),
            kept: Omitted::default(),
            omitted: Omitted::default(),
            scratch: Diagnostic::general(Severity::Note, ""),
            scene: Scene::empty(),
            seen: Seen::default(),
            materials: HashMap::default(),
            spare_entries: Vec::new(),
        }
    }

    /// The shared copy of an untextured material equal to `m` (a scene of a million spheres in a
    /// handful of materials keeps a handful per piece, see [`parse_in_pieces`]); textured
    /// materials stay their own (their texture reference names the line that set it).
    pub(super) fn share(&mut self, m: CourseMaterial) -> Arc<Material> {
        if m.texture.is_some() || m.bump.is_some() {
            return Arc::new(Material::Course(m));
        }
        let key = [
            m.color.x, m.color.y, m.color.z, m.diff, m.spec, m.refl, m.drefl, m.refr, m.rindex, m.absor.x,
            m.absor.y, m.absor.z,
        ]
        .map(f64::to_bits);
        if let Some(shared) = self.materials.get(&key) {
            return shared.clone();
        }
        let shared = Arc::new(Material::Course(m));
        self.materials.insert(key, shared.clone());
        shared
    }

    pub(super) fn report(
        &mut self,
        severity: Severity,
        span: Span,
        message: impl Into<String>,
    ) -> &mut Diagnostic {
        let error = severity == Severity::Error;
        let (kept, omitted) = if error {
            (&mut self.kept.errors, &mut self.omitted.errors)
        } else {
            (&mut self.kept.others, &mut self.omitted.others)
        };
        if *kept >= MAX_KEPT_DIAGNOSTICS {
            // Counted, not kept; not even its text is made (the line may be huge).
            *omitted += 1;
            self.scratch = Diagnostic::general(severity, "");
            return &mut self.scratch;
        }
        *kept += 1;
        let d = self.source.diagnostic(severity, span, message);
        self.diagnostics.push(d);
        let last = self.diagnostics.len() - 1;
        &mut self.diagnostics[last]
    }

    pub(super) fn error(&mut self, span: Span, message: impl Into<String>) -> &mut Diagnostic {
        self.report(Severity::Error, span, message)
    }

    pub(super) fn warning(&mut self, span: Span, message: impl Into<String>) -> &mut Diagnostic {
        self.report(Severity::Warning, span, message)
    }

    pub(super) fn run(&mut self) {
        let state = self.run_lines(1, self.source.text());
        self.finish_file(state);
    }

    /// Reads the lines of `text`, numbered from `first`, from the top level; returns the state
    /// after them.
    pub(super) fn run_lines(&mut self, first: u32, text: &'s str) -> State<'s> {
        let mut state = State::TopLevel;
        let mut tokens = Vec::new();
        for (number, line) in numbered_lines(first, text) {
            tokenize(line, &mut tokens);
            let Some(first) = tokens.first() else { continue };
            // The common lines first, without moving the state: a key line of an open block, and
            // a line of a block being skipped.
            match &mut state {
                State::InBlock(block) if first.text != "end" && !is_block_keyword(first.text) => {
                    self.key_line(number, &tokens, block);
                    continue;
                }
                State::Skipping(_) if first.text != "end" => continue,
                _ => {}
            }
            state = match state {
                State::TopLevel => self.top_level_line(number, &tokens),
                State::Skipping(header) => {
                    if first.text == "end" {
                        State::TopLevel
                    } else {
                        State::Skipping(header)
                    }
                }
                State::InBlock(mut block) => {
                    if first.text == "end" {
                        self.warn_trailing(number, &tokens[1..], "after `end`");
                        self.finish_block(block);
                        State::TopLevel
                    } else if is_block_keyword(first.text) {
                        let open = block.header;
                        self.error(open, format!("the `{}` block has no `end`", block.kind))
                            .notes
                            .push(format!("a new block starts at line {number} before this one is closed"));
                        self.finish_block(block);
                        self.top_level_line(number, &tokens)
                    } else {
                        self.key_line(number, &tokens, &mut block);
                        State::InBlock(block)
                    }
                }
            };
        }
        state
    }

    /// Closes what the end of the file leaves open, and notes a file that describes nothing.
    pub(super) fn finish_file(&mut self, state: State<'s>) {
        match state {
            State::TopLevel => {}
            State::InBlock(block) => {
                self.error(block.header, format!("the `{}` block has no `end`", block.kind))
                    .notes
                    .push("the file ends before the block is closed".into());
                self.finish_block(block);
            }
            State::Skipping(header) => {
                self.error(header, "this block has no `end`")
                    .notes
                    .push("the file ends before the block is closed".into());
            }
        }
        let has_errors = parser_has_errors(&self.diagnostics, self.omitted);
        if self.scene.primitives.is_empty()
            && self.scene.meshes.is_empty()
            && self.scene.lights.is_empty()
            && !has_errors
        {
            self.diagnostics.push(Diagnostic::general(
                Severity::Warning,
                format!("`{}` describes no lights and no primitives", clip(self.source.name())),
            ));
        }
    }

    /// Handles a line outside any block; returns the state after it.
    pub(super) fn top_level_line(&mut self, line: u32, tokens: &[Token<'s>]) -> State<'s> {
        let first = tokens[0];
        let span = first.span(line);
        let entries = std::mem::take(&mut self.spare_entries);
        let start = |kind: BlockKind, header: Span| {
            State::InBlock(OpenBlock { kind, header, entries, index: HashMap::new() })
        };
        match first.text {
            "background" | "camera" => {
                self.warn_trailing(line, &tokens[1..], "after the block name");
                let kind = if first.text == "camera" { BlockKind::Camera } else { BlockKind::Background };
                start(kind, span)
            }
            "light" | "primitive" | "obj" => {
                let Some(&ty) = tokens.get(1) else {
                    let choices = if first.text == "light" {
                        "`point`, `square`, `area` or `sphere`"
                    } else {
                        PRIMITIVE_TYPES
                    };
                    self.error(span, format!("`{}` needs a type: {choices}", clip(first.text)));
                    return State::Skipping(span);
                };
                let ty_span = ty.span(line);
                let kind = match (first.text, ty.text) {
                    ("light", "point") => Some(BlockKind::Light(LightKind::Point)),
                    ("light", "square" | "area") => Some(BlockKind::Light(LightKind::Square)),
                    ("light", "sphere") => Some(BlockKind::Light(LightKind::Sphere)),
                    // `obj` is another name of `primitive` (spec section 9).
                    ("primitive" | "obj", ty) => PrimitiveKind::from_name(ty).map(BlockKind::Primitive),
                    _ => None,
                };
                let alias =
                    ALIAS_PRIMITIVES.iter().find(|(name, _)| first.text != "light" && *name == ty.text);
                let kind = match (kind, alias) {
                    (None, Some(&(name, alias))) => {
                        self.report(
                            Severity::Note,
                            ty_span,
                            format!("`{} {name}` is read as `primitive {}`", first.text, alias.name()),
                        )
                        .notes
                        .push(format!(
                            "`{name}` is another name of `{}` with its normal map `NT=` (LuChengTHU's renderer)",
                            alias.name()
                        ));
                        Some(BlockKind::Primitive(alias))
                    }
                    (kind, _) => kind,
                };
                match kind {
                    Some(kind) => {
                        self.warn_trailing(line, &tokens[2..], "after the block type");
                        start(kind, ty_span)
                    }
                    None => {
                        let message = if first.text != "light" && IGNORED_PRIMITIVES.contains(&ty.text) {
                            format!(
                                "`{} {}` is not part of the scene language (the renderers that read it ignored it too); the block is skipped",
                                clip(first.text),
                                clip(ty.text)
                            )
                        } else {
                            format!(
                                "unknown {} type `{}`; the block is skipped",
                                clip(first.text),
                                clip(ty.text)
                            )
                        };
                        self.warning(ty_span, message);
                        State::Skipping(ty_span)
                    }
                }
            }
            "end" => {
                self.warning(span, "`end` without an open block; ignored");
                State::TopLevel
            }
            text if text.contains('=') => {
                self.warning(span, format!("`{}` is outside any block; the line is ignored", clip(text)));
                State::TopLevel
            }
            text => {
                self.warning(
                    span,
                    format!("unknown block `{}`; its lines up to `end` are skipped", clip(text)),
                );
                State::Skipping(span)
            }
        }
    }

    pub(super) fn warn_trailing(&mut self, line: u32, rest: &[Token<'_>], place: &str) {
        if let (Some(first), Some(last)) = (rest.first(), rest.last()) {
            let span = Span { line, column: first.column, len: last.column + last.len - first.column };
            self.warning(span, format!("unexpected text {place}; ignored"));
        }
    }

    /// Reads a `key= values` line into the open block.
    pub(super) fn key_line(&mut self, line: u32, tokens: &[Token<'s>], block: &mut OpenBlock<'s>) {
        let first = tokens[0];
        let (key, key_len, glued, rest) = match first.text.split_once('=') {
            Some((key, after)) => (key, char_count(key) + 1, after, &tokens[1..]),
            None => match tokens.get(1) {
                Some(second) if second.text.starts_with('=') => {
                    self.warning(
                        Span { line, column: first.column, len: second.column + 1 - first.column },
                        format!("write `{}=` with no space before `=`", clip(first.text)),
                    );
                    (first.text, first.len, &second.text[1..], &tokens[2..])
                }
                _ => {
                    self.error(
                        first.span(line),
                        format!("expected `key= value`, found `{}`", clip(first.text)),
                    )
                    .notes
                    .push(format!("inside the `{}` block opened at line {}", block.kind, block.header.line));
                    return;
                }
            },
        };
        let key_span = Span { line, column: first.column, len: key_len };
        if key.is_empty() {
            self.error(key_span, "a key is missing before `=`");
            return;
        }
        let glued_value = (!glued.is_empty()).then(|| {
            let column = first.column + key_len;
            (glued, Span { line, column, len: char_count(glued) })
        });
        let mut values = Values::new();
        for v in
            glued_value.into_iter().chain(rest.iter().map(|t| (t.text, t.span(line)))).take(MAX_VALUES_KEPT)
        {
            values.push(v);
        }
        let value_count = glued_value.is_some() as usize + rest.len();
        let last_span = rest.last().map(|t| t.span(line)).or(glued_value.map(|(_, span)| span));
        let all_values = match (values.first(), last_span) {
            (Some((_, first)), Some(last)) => {
                Span { line, column: first.column, len: last.column + last.len - first.column }
            }
            _ => key_span,
        };
        let repeatable = block.kind == BlockKind::Primitive(PrimitiveKind::Bezier) && key == BEZIER_POINT_KEY;
        let entry = Entry { key, key_span, values, value_count, all_values };
        match block.position(key).filter(|_| !repeatable) {
            Some(previous) => {
                let earlier = block.entries[previous].key_span.line;
                self.warning(
                    key_span,
                    format!("`{}=` is given again; this value replaces the one on line {earlier}", clip(key)),
                );
                block.entries[previous] = entry;
            }
            None => block.push(entry),
        }
    }
}

pub(super) fn is_block_keyword(word: &str) -> bool {
    matches!(word, "background" | "camera" | "light" | "primitive" | "obj")
}

/// The keys a block kind understands.
pub(super) fn known_keys(kind: BlockKind) -> Vec<&'static str> {
    let specific: &[&str] = match kind {
        BlockKind::Background => &["color", "top", "bottom"],
        BlockKind::Camera => &[
            "O",
            "N",
            "lens_W",
            "lens_H",
            "image_W",
            "image_H",
            "shade_quality",
            "drefl_quality",
            "algorithm",
            "aperture",
            "focal_dist",
        ],
        BlockKind::Light(LightKind::Point) => &["O", "color"],
        BlockKind::Light(LightKind::Square) => &["O", "Dx", "Dy", "color"],
        BlockKind::Light(LightKind::Sphere) => &["O", "R", "color"],
        BlockKind::Primitive(PrimitiveKind::Sphere) => &["O", "R", "De", "Dc"],
        BlockKind::Primitive(PrimitiveKind::Plane) => &["N", "R", "Dx", "Dy"],
        BlockKind::Primitive(PrimitiveKind::Square) => &["O", "Dx", "Dy"],
        BlockKind::Primitive(PrimitiveKind::Cylinder) => &["O1", "O2", "R", "De", "Dc"],
        BlockKind::Primitive(PrimitiveKind::Triangle) => &["P0", "P1", "P2", "O1", "O2", "O3"],
        BlockKind::Primitive(PrimitiveKind::Mesh) => &["file", "O", "scale", "rotation"],
        BlockKind::Primitive(PrimitiveKind::Polyhedron) => &["mesh", "O", "size", "angles"],
        BlockKind::Primitive(PrimitiveKind::Bezier) => &["O1", "O2", "P", "center", "V0", "V1", "V2", "V3"],
    };
    let mut keys = specific.to_vec();
    match kind {
        BlockKind::Primitive(_) => keys.extend(MATERIAL_KEYS),
        BlockKind::Camera => keys.extend(PhotonSettings::KEYS),
        _ => {}
    }
    keys
}
