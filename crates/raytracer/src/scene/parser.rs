//! The parser of the course scene language (spec section 2 and 3).
//!
//! The file is read line by line. A line is cut at the first `#` or `//` (a comment), split into
//! whitespace-separated tokens, and then is either a block header (`background`, `camera`,
//! `light TYPE`, `primitive TYPE`), a key line (`key= value ...`) inside a block, or `end`. Every
//! problem becomes a [`Diagnostic`] with its line and column; parsing goes on after an error so one
//! run reports them all.

use std::collections::HashMap;
use std::fmt;
use std::sync::Arc;

use glam::{DVec2, DVec3};

use super::diagnostic::{Diagnostic, Severity};
use super::source::{SourceFile, Span, count_line_ends, numbered_lines};
use super::{Algorithm, Background, CameraSettings, Gradient, PhotonSettings, Primitive, Scene};
use crate::error::GeometryError;
use crate::geometry::{Bezier, Cylinder, MeshFile, MeshTransform, Plane, Shape, Sphere, Square, Triangle};
use crate::light::Light;
use crate::material::Material;
use crate::texture::{BUILTIN_PREFIX, Builtin, TextureRef, TextureSource};

/// Largest image side accepted, in pixels.
pub const MAX_IMAGE_SIDE: u32 = 32_768;
/// Largest image area accepted, in pixels (8192 x 8192; about 0.8 GB of linear RGB).
pub const MAX_IMAGE_PIXELS: u64 = 8192 * 8192;
/// Largest `shade_quality=` and `drefl_quality=` (16 times that many samples per hit).
pub const MAX_QUALITY: u32 = 256;
/// Largest `max_photons=` and `max_hitpoints=` the parser accepts; the memory they need is checked
/// against the memory limit before a render.
pub const MAX_STORED_PHOTONS: u64 = 1 << 40;
/// Largest `emit_photons=` (ten billion: hours of tracing on one machine).
pub const MAX_EMITTED_PHOTONS: u64 = 10_000_000_000;
/// Largest `sample_photons=`.
pub const MAX_SAMPLE_PHOTONS: u64 = 100_000;
/// Largest `iterations=`.
pub const MAX_ITERATIONS: u64 = 1_000_000;

/// Most errors, and most warnings and notes, kept from one file: a hostile file can hold
/// millions of mistakes, and nobody reads past the first few. The rest are only counted.
pub const MAX_KEPT_DIAGNOSTICS: usize = 50;

/// Diagnostics counted but not kept, beyond [`MAX_KEPT_DIAGNOSTICS`] of their kind.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Omitted {
    /// Errors not kept.
    pub errors: usize,
    /// Warnings and notes not kept.
    pub others: usize,
}

/// A successfully parsed scene with the warnings and notes found on the way.
#[derive(Clone, Debug)]
pub struct Parsed {
    /// The scene.
    pub scene: Scene,
    /// Warnings and notes, in file order (the first [`MAX_KEPT_DIAGNOSTICS`]).
    pub diagnostics: Vec<Diagnostic>,
    /// Warnings and notes past those kept.
    pub omitted: Omitted,
}

/// A scene file with at least one error. Holds the diagnostics (errors and warnings) in file
/// order, at most [`MAX_KEPT_DIAGNOSTICS`] errors and as many others, and counts the rest.
#[derive(Clone, Debug, thiserror::Error)]
pub struct SceneError {
    /// The diagnostics kept, in file order.
    pub diagnostics: Vec<Diagnostic>,
    /// Diagnostics past those kept.
    pub omitted: Omitted,
}

impl SceneError {
    /// The number of errors, kept or not.
    pub fn error_count(&self) -> usize {
        self.diagnostics.iter().filter(|d| d.is_error()).count() + self.omitted.errors
    }
}

impl fmt::Display for SceneError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for d in &self.diagnostics {
            writeln!(f, "{d}")?;
        }
        let more = self.omitted.errors + self.omitted.others;
        if more > 0 {
            writeln!(f, "... and {more} more")?;
        }
        let n = self.error_count();
        write!(f, "{n} error{}", if n == 1 { "" } else { "s" })
    }
}

/// Parses a scene file. Returns the scene and its warnings, or every diagnostic when there is an
/// error. Never panics, whatever the input.
pub fn parse(source: &SourceFile) -> Result<Parsed, SceneError> {
    match parse_in_pieces(source) {
        Some(parsed) => Ok(parsed),
        None => parse_line_by_line(source),
    }
}

/// [`parse`], one line after the other.
fn parse_line_by_line(source: &SourceFile) -> Result<Parsed, SceneError> {
    let mut parser = Parser::new(source);
    parser.run();
    let Parser { mut diagnostics, omitted, scene, .. } = parser;
    // File order; diagnostics about the whole file last.
    diagnostics.sort_by_key(|d| d.location.as_ref().map_or((u32::MAX, 0), |l| (l.span.line, l.span.column)));
    if parser_has_errors(&diagnostics, omitted) {
        Err(SceneError { diagnostics, omitted })
    } else {
        Ok(Parsed { scene, diagnostics, omitted })
    }
}

/// Files of at least twice this many bytes are parsed in pieces of about this many bytes, in
/// parallel (see [`parse_in_pieces`]).
const PIECE_BYTES: usize = 1 << 19;

/// A piece of a scene file to parse: whole lines (without the line end after the last) and the
/// number of the first.
#[derive(Debug)]
struct Piece<'s> {
    first_line: u32,
    text: &'s str,
}

/// Cuts `text` into pieces of about [`PIECE_BYTES`], each but the first starting at a line that
/// opens a block. The cuts depend on the text only. The lines are counted on all threads.
fn pieces(text: &str) -> Vec<Piece<'_>> {
    use rayon::prelude::*;
    let bytes = text.as_bytes();
    let mut starts = vec![0];
    let mut tokens = Vec::new();
    let mut next = PIECE_BYTES;
    // The next piece starts at the first line that opens a block among those starting at or
    // after byte `next` (a line starts after a line end).
    'cut: while let Some(skip) = bytes.get(next - 1..).and_then(|rest| memchr::memchr(b'\n', rest)) {
        let mut line_start = next + skip;
        while line_start < bytes.len() {
            let line_end =
                memchr::memchr(b'\n', &bytes[line_start..]).map_or(bytes.len(), |n| line_start + n);
            tokenize(super::source::without_return(&text[line_start..line_end]), &mut tokens);
            if tokens.first().is_some_and(|t| is_block_keyword(t.text)) {
                starts.push(line_start);
                next = line_start + PIECE_BYTES;
                continue 'cut;
            }
            line_start = line_end + 1;
        }
        break;
    }
    let texts: Vec<&str> = starts
        .iter()
        .zip(starts.iter().skip(1).map(|&s| s - 1).chain([text.len()]))
        .map(|(&a, b)| &text[a..b])
        .collect();
    let line_ends: Vec<usize> = texts.par_iter().map(|t| count_line_ends(t)).collect();
    let mut first_line = 1;
    texts
        .into_iter()
        .zip(line_ends)
        .map(|(text, ends)| {
            let piece = Piece { first_line, text };
            first_line += ends as u32 + 1;
            piece
        })
        .collect()
}

/// Parses a large file in pieces of about [`PIECE_BYTES`] bytes, each starting at a line that
/// opens a block, on all threads; returns the scene only when it is certainly the one the parse
/// line by line gives: every piece ends outside any block (so each next piece starts where the
/// whole-file parse is at the top level), no piece has anything to report, and the file has at
/// most one `background` and one `camera` block and describes something. Otherwise `None`: the
/// file is then parsed line by line, which reports its problems in order. The pieces depend on
/// the text only, so the scene does not depend on the thread count. Equal untextured materials
/// are shared within a piece, not across pieces: each piece keeps its own copy of each (a few
/// hundred copies for a million spheres), so that the threads neither wait for one lock nor
/// contend for the reference counts of the same few copies.
fn parse_in_pieces(source: &SourceFile) -> Option<Parsed> {
    use rayon::prelude::*;
    if source.text().len() < 2 * PIECE_BYTES {
        return None;
    }
    let pieces: Vec<Option<Parser>> = pieces(source.text())
        .into_par_iter()
        .map(|piece| {
            let mut parser = Parser::new(source);
            let state = parser.run_lines(piece.first_line, piece.text);
            let clean = matches!(state, State::TopLevel)
                && parser.diagnostics.is_empty()
                && parser.omitted == Omitted::default();
            clean.then_some(parser)
        })
        .collect();
    let mut scene = Scene::empty();
    scene.primitives.reserve_exact(pieces.iter().flatten().map(|p| p.scene.primitives.len()).sum());
    let (mut background, mut camera) = (false, false);
    for piece in pieces {
        let piece = piece?;
        if piece.seen.background.is_some() {
            if background {
                return None;
            }
            background = true;
            scene.background = piece.scene.background;
        }
        if piece.seen.camera.is_some() {
            if camera {
                return None;
            }
            camera = true;
            scene.camera = piece.scene.camera;
        }
        scene.lights.extend(piece.scene.lights);
        scene.primitives.extend(piece.scene.primitives);
    }
    if scene.primitives.is_empty() && scene.lights.is_empty() {
        return None;
    }
    Some(Parsed { scene, diagnostics: Vec::new(), omitted: Omitted::default() })
}

fn parser_has_errors(diagnostics: &[Diagnostic], omitted: Omitted) -> bool {
    omitted.errors > 0 || diagnostics.iter().any(Diagnostic::is_error)
}

impl Scene {
    /// A scene with default background and camera and nothing in it.
    fn empty() -> Scene {
        Scene {
            background: Background::default(),
            camera: CameraSettings::default(),
            lights: Vec::new(),
            primitives: Vec::new(),
        }
    }
}

/// A whitespace-separated word of a line, with its position.
#[derive(Clone, Copy, Debug)]
struct Token<'a> {
    text: &'a str,
    /// 1-based character column.
    column: u32,
    /// Length in characters.
    len: u32,
}

impl Token<'_> {
    fn span(&self, line: u32) -> Span {
        Span { line, column: self.column, len: self.len }
    }
}

/// Splits a line into `tokens` (cleared first), dropping the comment (from the first `#` or `//`).
fn tokenize<'a>(line: &'a str, tokens: &mut Vec<Token<'a>>) {
    tokens.clear();
    if !line.is_ascii() {
        tokenize_chars(line, tokens);
        return;
    }
    // ASCII (nearly every line of a scene file): a column is a byte. `u8::is_ascii_whitespace`
    // leaves out the vertical tab, which `char::is_whitespace` counts.
    let bytes = line.as_bytes();
    let blank = |b: u8| b.is_ascii_whitespace() || b == 0x0B;
    let comment = |i: usize| bytes[i] == b'#' || (bytes[i] == b'/' && bytes.get(i + 1) == Some(&b'/'));
    let mut i = 0;
    while i < bytes.len() {
        if blank(bytes[i]) {
            i += 1;
            continue;
        }
        let start = i;
        while i < bytes.len() && !blank(bytes[i]) && !comment(i) {
            i += 1;
        }
        if i > start {
            tokens.push(Token { text: &line[start..i], column: start as u32 + 1, len: (i - start) as u32 });
        }
        if i < bytes.len() && comment(i) {
            break;
        }
    }
}

/// [`tokenize`] for a line with characters beyond ASCII: columns count characters.
fn tokenize_chars<'a>(line: &'a str, tokens: &mut Vec<Token<'a>>) {
    let mut start: Option<(usize, u32)> = None;
    let mut column = 0u32;
    let mut chars = line.char_indices().peekable();
    let mut end_of_code = line.len();
    while let Some((i, ch)) = chars.next() {
        column += 1;
        let comment = ch == '#' || (ch == '/' && chars.peek().is_some_and(|&(_, c)| c == '/'));
        if comment {
            end_of_code = i;
            break;
        }
        if ch.is_whitespace() {
            if let Some((s, c)) = start.take() {
                tokens.push(Token { text: &line[s..i], column: c, len: column - c });
            }
        } else if start.is_none() {
            start = Some((i, column));
        }
    }
    if let Some((s, c)) = start {
        let text = &line[s..end_of_code];
        tokens.push(Token { text, column: c, len: char_count(text) });
    }
}

/// The number of characters of `text` (its length when it is ASCII, as scene text nearly always is).
fn char_count(text: &str) -> u32 {
    if text.is_ascii() { text.len() as u32 } else { text.chars().count() as u32 }
}

/// The kinds of block.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum BlockKind {
    Background,
    Camera,
    Light(LightKind),
    Primitive(PrimitiveKind),
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum LightKind {
    Point,
    Square,
    Sphere,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum PrimitiveKind {
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
    fn from_name(name: &str) -> Option<PrimitiveKind> {
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

    fn name(self) -> &'static str {
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
const MATERIAL_KEYS: [&str; 12] =
    ["color", "texture", "bump", "NT", "diff", "spec", "refl", "drefl", "blur", "refr", "rindex", "absor"];

/// The types of `primitive` blocks, as the error for a missing type lists them.
const PRIMITIVE_TYPES: &str =
    "`sphere`, `plane`, `square`, `cylinder`, `triangle`, `mesh`, `polyhedron` or `bezier`";

/// Primitive types that some students' renderers had and that their own parsers ignored too
/// (spec section 9): skipped with a warning that says so.
const IGNORED_PRIMITIVES: [&str; 2] = ["torus", "cube"];

/// The key a `primitive bezier` block repeats, one control point a line (`P= z r`).
const BEZIER_POINT_KEY: &str = "P";

/// One `key= values` line of a block, borrowing the file's text.
#[derive(Clone, Debug)]
struct Entry<'s> {
    key: &'s str,
    key_span: Span,
    /// The value tokens (the text after `=` when glued to the key counts as the first), at most
    /// [`MAX_VALUES_KEPT`] of them.
    values: Values<'s>,
    /// How many values the line has, kept or not.
    value_count: usize,
    /// The span of all the values, or of the key when there are none.
    all_values: Span,
}

/// Most values kept from one key line: no key takes more than a few, and a hostile line may hold
/// millions (the rest are counted, not kept).
const MAX_VALUES_KEPT: usize = 16;

/// The values of a key line: up to four inline (a scene of a million spheres allocates nothing
/// per line), more on the heap.
#[derive(Clone, Debug)]
enum Values<'s> {
    Inline([(&'s str, Span); 4], u8),
    Heap(Vec<(&'s str, Span)>),
}

impl<'s> Values<'s> {
    fn new() -> Values<'s> {
        Values::Inline([("", Span { line: 0, column: 0, len: 0 }); 4], 0)
    }

    fn push(&mut self, v: (&'s str, Span)) {
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
    fn values_span(&self) -> Span {
        self.all_values
    }
}

/// A block being read: its kind, header position and key lines (the last of each key, and every
/// `P=` line of a Bezier block).
struct OpenBlock<'s> {
    kind: BlockKind,
    header: Span,
    entries: Vec<Entry<'s>>,
    /// The entry of each key, once there are more than [`INDEXED_ENTRIES`] (a hostile block may
    /// hold a million keys); smaller blocks are searched in order.
    index: HashMap<&'s str, usize>,
}

/// Blocks with more key lines than this find their keys through an index.
const INDEXED_ENTRIES: usize = 16;

impl<'s> OpenBlock<'s> {
    /// The position in `entries` of the entry of `key` (for a repeatable key, of one of them).
    fn position(&self, key: &str) -> Option<usize> {
        if self.entries.len() > INDEXED_ENTRIES {
            self.index.get(key).copied()
        } else {
            self.entries.iter().position(|e| e.key == key)
        }
    }

    /// Adds the entry of a key not seen before, or of a repeatable key.
    fn push(&mut self, entry: Entry<'s>) {
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
enum State<'s> {
    TopLevel,
    InBlock(OpenBlock<'s>),
    /// Skipping an unknown block up to its `end`; the span of its header.
    Skipping(Span),
}

/// Which single blocks have been seen (a second one replaces the first, with a warning).
#[derive(Default)]
struct Seen {
    background: Option<u32>,
    camera: Option<u32>,
}

struct Parser<'s> {
    source: &'s SourceFile,
    diagnostics: Vec<Diagnostic>,
    /// How many errors and others are in `diagnostics`.
    kept: Omitted,
    /// How many were reported past [`MAX_KEPT_DIAGNOSTICS`] and dropped.
    omitted: Omitted,
    /// Where a dropped diagnostic is built (its notes are added to it, then it is overwritten).
    scratch: Diagnostic,
    scene: Scene,
    seen: Seen,
    /// Untextured materials seen so far, by their numbers' bits (see [`Parser::share`]).
    materials: HashMap<[u64; 12], Arc<Material>, foldhash::fast::FixedState>,
    /// The emptied entry list of the last block read, for the next block to fill (a scene of a
    /// million spheres then allocates no list per block).
    spare_entries: Vec<Entry<'s>>,
}

impl<'s> Parser<'s> {
    fn new(source: &'s SourceFile) -> Parser<'s> {
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
    fn share(&mut self, m: Material) -> Arc<Material> {
        if m.texture.is_some() || m.bump.is_some() {
            return Arc::new(m);
        }
        let key = [
            m.color.x, m.color.y, m.color.z, m.diff, m.spec, m.refl, m.drefl, m.refr, m.rindex, m.absor.x,
            m.absor.y, m.absor.z,
        ]
        .map(f64::to_bits);
        if let Some(shared) = self.materials.get(&key) {
            return shared.clone();
        }
        let shared = Arc::new(m);
        self.materials.insert(key, shared.clone());
        shared
    }

    fn report(&mut self, severity: Severity, span: Span, message: impl Into<String>) -> &mut Diagnostic {
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

    fn error(&mut self, span: Span, message: impl Into<String>) -> &mut Diagnostic {
        self.report(Severity::Error, span, message)
    }

    fn warning(&mut self, span: Span, message: impl Into<String>) -> &mut Diagnostic {
        self.report(Severity::Warning, span, message)
    }

    fn run(&mut self) {
        let state = self.run_lines(1, self.source.text());
        self.finish_file(state);
    }

    /// Reads the lines of `text`, numbered from `first`, from the top level; returns the state
    /// after them.
    fn run_lines(&mut self, first: u32, text: &'s str) -> State<'s> {
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
    fn finish_file(&mut self, state: State<'s>) {
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
        if self.scene.primitives.is_empty() && self.scene.lights.is_empty() && !has_errors {
            self.diagnostics.push(Diagnostic::general(
                Severity::Warning,
                format!("`{}` describes no lights and no primitives", self.source.name()),
            ));
        }
    }

    /// Handles a line outside any block; returns the state after it.
    fn top_level_line(&mut self, line: u32, tokens: &[Token<'s>]) -> State<'s> {
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
                    self.error(span, format!("`{}` needs a type: {choices}", first.text));
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
                match kind {
                    Some(kind) => {
                        self.warn_trailing(line, &tokens[2..], "after the block type");
                        start(kind, ty_span)
                    }
                    None => {
                        let message = if first.text != "light" && IGNORED_PRIMITIVES.contains(&ty.text) {
                            format!(
                                "`{} {}` is not part of the scene language (the renderers that read it ignored it too); the block is skipped",
                                first.text, ty.text
                            )
                        } else {
                            format!("unknown {} type `{}`; the block is skipped", first.text, ty.text)
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
                self.warning(span, format!("`{}` is outside any block; the line is ignored", text));
                State::TopLevel
            }
            text => {
                self.warning(span, format!("unknown block `{text}`; its lines up to `end` are skipped"));
                State::Skipping(span)
            }
        }
    }

    fn warn_trailing(&mut self, line: u32, rest: &[Token<'_>], place: &str) {
        if let (Some(first), Some(last)) = (rest.first(), rest.last()) {
            let span = Span { line, column: first.column, len: last.column + last.len - first.column };
            self.warning(span, format!("unexpected text {place}; ignored"));
        }
    }

    /// Reads a `key= values` line into the open block.
    fn key_line(&mut self, line: u32, tokens: &[Token<'s>], block: &mut OpenBlock<'s>) {
        let first = tokens[0];
        let (key, key_len, glued, rest) = match first.text.split_once('=') {
            Some((key, after)) => (key, char_count(key) + 1, after, &tokens[1..]),
            None => match tokens.get(1) {
                Some(second) if second.text.starts_with('=') => {
                    self.warning(
                        Span { line, column: first.column, len: second.column + 1 - first.column },
                        format!("write `{}=` with no space before `=`", first.text),
                    );
                    (first.text, first.len, &second.text[1..], &tokens[2..])
                }
                _ => {
                    self.error(first.span(line), format!("expected `key= value`, found `{}`", first.text))
                        .notes
                        .push(format!(
                            "inside the `{}` block opened at line {}",
                            block.kind, block.header.line
                        ));
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
                    format!("`{key}=` is given again; this value replaces the one on line {earlier}"),
                );
                block.entries[previous] = entry;
            }
            None => block.push(entry),
        }
    }

    /// Turns a complete block into scene data.
    fn finish_block(&mut self, block: OpenBlock<'s>) {
        let mut reader = BlockReader::new(block, self);
        match reader.kind {
            BlockKind::Background => reader.background(),
            BlockKind::Camera => reader.camera(),
            BlockKind::Light(kind) => reader.light(kind),
            BlockKind::Primitive(kind) => reader.primitive(kind),
        }
        reader.finish();
    }
}

fn is_block_keyword(word: &str) -> bool {
    matches!(word, "background" | "camera" | "light" | "primitive" | "obj")
}

/// A key's value could not be used; the error has been reported.
#[derive(Debug)]
struct Reported;

/// The result of looking up a key: absent, present and valid, or present and invalid (already
/// reported).
type Lookup<T> = Result<Option<T>, Reported>;

/// Reads typed values out of a finished block, reporting problems.
struct BlockReader<'p, 's> {
    kind: BlockKind,
    header: Span,
    /// The last entry of each key (later lines win), in file order of their first line.
    entries: Vec<Entry<'s>>,
    /// Whether each entry was read.
    used: smallvec::SmallVec<[bool; 32]>,
    /// The control points of a `primitive bezier` block (`P=` lines), in file order.
    points: Vec<Entry<'s>>,
    parser: &'p mut Parser<'s>,
}

impl<'p, 's> BlockReader<'p, 's> {
    fn new(block: OpenBlock<'s>, parser: &'p mut Parser<'s>) -> Self {
        let bezier = block.kind == BlockKind::Primitive(PrimitiveKind::Bezier);
        let (points, entries): (Vec<Entry<'s>>, Vec<Entry<'s>>) = if bezier {
            block.entries.into_iter().partition(|e| e.key == BEZIER_POINT_KEY)
        } else {
            (Vec::new(), block.entries)
        };
        let used = smallvec::smallvec![false; entries.len()];
        BlockReader { kind: block.kind, header: block.header, entries, used, points, parser }
    }

    /// The position of the entry of `key`, if the block has one.
    fn position(&self, key: &str) -> Option<usize> {
        // The first bytes compared before the whole keys: most keys differ there.
        let first = key.as_bytes().first();
        self.entries.iter().position(|e| e.key.as_bytes().first() == first && e.key == key)
    }

    /// The entry of `key`, if the block has one.
    fn find(&self, key: &str) -> Option<&Entry<'s>> {
        self.position(key).map(|i| &self.entries[i])
    }

    /// Whether the block sets `key=`.
    fn has(&self, key: &str) -> bool {
        self.find(key).is_some()
    }

    /// The entry of `key`, marked as used.
    fn entry(&mut self, key: &str) -> Option<Entry<'s>> {
        let i = self.position(key)?;
        self.used[i] = true;
        Some(self.entries[i].clone())
    }

    fn span_of(&self, key: &str) -> Span {
        self.find(key).map_or(self.header, Entry::values_span)
    }

    fn error(&mut self, span: Span, message: impl Into<String>) -> &mut Diagnostic {
        self.parser.error(span, message)
    }

    fn warning(&mut self, span: Span, message: impl Into<String>) -> &mut Diagnostic {
        self.parser.warning(span, message)
    }

    /// Parses the `N` numbers of `key`.
    fn numbers<const N: usize>(&mut self, key: &str) -> Lookup<[f64; N]> {
        let Some(i) = self.position(key) else { return Ok(None) };
        self.used[i] = true;
        let what = || if N == 1 { "a number".to_owned() } else { format!("{N} numbers") };
        let entry = &self.entries[i];
        if entry.value_count != N {
            let found = entry.value_count;
            let span = entry.values_span();
            let message = if found == 0 {
                format!("`{key}=` expects {}", what())
            } else {
                format!(
                    "`{key}=` expects {}, found {found} value{}",
                    what(),
                    if found == 1 { "" } else { "s" }
                )
            };
            self.error(span, message);
            return Err(Reported);
        }
        let mut out = [0.0; N];
        let mut bad = false;
        let values: [(&str, Span); N] = std::array::from_fn(|k| self.entries[i].values[k]);
        for (slot, (text, span)) in out.iter_mut().zip(values) {
            match text.parse::<f64>() {
                Ok(v) if v.is_finite() => *slot = v,
                Ok(_) => {
                    self.error(span, format!("`{text}` is not a finite number"));
                    bad = true;
                }
                Err(_) => {
                    self.error(span, format!("`{key}=` expects {}; `{text}` is not a number", what()));
                    bad = true;
                }
            }
        }
        if bad { Err(Reported) } else { Ok(Some(out)) }
    }

    fn number(&mut self, key: &str) -> Lookup<f64> {
        Ok(self.numbers::<1>(key)?.map(|[v]| v))
    }

    fn vec3(&mut self, key: &str) -> Lookup<DVec3> {
        Ok(self.numbers::<3>(key)?.map(DVec3::from_array))
    }

    /// A whole number in `min..=max`.
    fn integer(&mut self, key: &str, min: u64, max: u64) -> Lookup<u64> {
        let Some(v) = self.number(key)? else { return Ok(None) };
        if v.fract() != 0.0 || v < min as f64 || v > max as f64 {
            let span = self.span_of(key);
            self.error(span, format!("`{key}=` must be a whole number from {min} to {max}, not {v}"));
            return Err(Reported);
        }
        Ok(Some(v as u64))
    }

    /// The raw text after `key=` (for words and paths, which may contain spaces).
    fn text(&mut self, key: &str) -> Lookup<(String, Span)> {
        let Some(entry) = self.entry(key) else { return Ok(None) };
        if entry.value_count == 0 {
            self.error(entry.key_span, format!("`{key}=` needs a value"));
            return Err(Reported);
        }
        let span = entry.values_span();
        let line = self.parser.source.line(span.line);
        let text: String = line.chars().skip(span.column as usize - 1).take(span.len as usize).collect();
        Ok(Some((text, span)))
    }

    /// A required value: reports a missing key at the block header.
    fn required<T>(&mut self, key: &str, value: Lookup<T>, meaning: &str) -> Option<T> {
        match value {
            Ok(Some(v)) => Some(v),
            Ok(None) => {
                let header = self.header;
                self.error(header, format!("`{}` needs `{key}=` ({meaning})", self.kind));
                None
            }
            Err(Reported) => None,
        }
    }

    /// A required vector (see [`BlockReader::required`]).
    fn required_vec3(&mut self, key: &str, meaning: &str) -> Option<DVec3> {
        let value = self.vec3(key);
        self.required(key, value, meaning)
    }

    /// A required number (see [`BlockReader::required`]).
    fn required_number(&mut self, key: &str, meaning: &str) -> Option<f64> {
        let value = self.number(key);
        self.required(key, value, meaning)
    }

    /// A weight that should not be negative; negative values are kept, with a warning.
    fn weight(&mut self, key: &str) -> f64 {
        match self.number(key) {
            Ok(Some(v)) => {
                if v < 0.0 {
                    let span = self.span_of(key);
                    self.warning(span, format!("`{key}=` is negative"));
                }
                v
            }
            _ => 0.0,
        }
    }

    /// A colour; components outside [0, 1] get a warning unless `lights` (light colours may
    /// exceed 1).
    fn color(&mut self, key: &str, allow_bright: bool) -> Lookup<DVec3> {
        let c = self.vec3(key)?;
        if let Some(c) = c {
            let out_of_range = c.min_element() < 0.0 || (!allow_bright && c.max_element() > 1.0);
            if out_of_range {
                let span = self.span_of(key);
                let range = if allow_bright { "not be negative" } else { "lie in [0, 1]" };
                self.warning(span, format!("colour components of `{key}=` should {range}"));
            }
        }
        Ok(c)
    }

    fn geometry_error(&mut self, err: GeometryError) {
        let key = match &err {
            GeometryError::NonPositiveRadius(_) => "R",
            GeometryError::ZeroVector(k)
            | GeometryError::ParallelAxes(k, _)
            | GeometryError::TooLarge(k)
            | GeometryError::TooSmall(k) => k,
            GeometryError::ZeroAxis | GeometryError::AxisTooLong | GeometryError::AxisTooShort => "O2",
            GeometryError::Degenerate(_) | GeometryError::ControlPoints(_) => "",
        };
        let span = self.span_of(key);
        let kind = self.kind;
        self.error(span, format!("in `{kind}`, {err}"));
    }

    fn background(&mut self) {
        if let Some(line) = self.parser.seen.background.replace(self.header.line) {
            let header = self.header;
            self.warning(header, format!("a second `background` block replaces the one on line {line}"));
        }
        let mut bg = Background::default();
        if let Ok(Some(c)) = self.color("color", false) {
            bg.color = c;
        }
        let top = self.color("top", true).ok().flatten();
        let bottom = self.color("bottom", true).ok().flatten();
        if top.is_some() || bottom.is_some() {
            bg.gradient =
                Some(Gradient { bottom: bottom.unwrap_or(DVec3::ONE), top: top.unwrap_or(DVec3::ONE) });
        }
        self.parser.scene.background = bg;
    }

    fn camera(&mut self) {
        if let Some(line) = self.parser.seen.camera.replace(self.header.line) {
            let header = self.header;
            self.warning(header, format!("a second `camera` block replaces the one on line {line}"));
        }
        let mut cam = CameraSettings::default();
        if let Ok(Some(o)) = self.vec3("O") {
            cam.eye = o;
        }
        if let Ok(Some(n)) = self.vec3("N") {
            match crate::error::unit_direction(n, "N") {
                Ok(n) => cam.dir = n,
                Err(_) => {
                    let span = self.span_of("N");
                    self.error(span, "the view direction `N=` must not be the zero vector");
                }
            }
        }
        // Whether the lens and image sizes all read; the aspect is compared only then (an error
        // in one of them is not also a stretched picture).
        let mut sizes_read = true;
        for (key, slot) in [("lens_W", &mut cam.lens_width), ("lens_H", &mut cam.lens_height)] {
            match self.number(key) {
                Ok(Some(v)) if v > 0.0 => *slot = v,
                Ok(Some(_)) => {
                    let span = self.span_of(key);
                    self.error(span, format!("`{key}=` must be positive"));
                    sizes_read = false;
                }
                Ok(None) => {}
                Err(Reported) => sizes_read = false,
            }
        }
        let side = MAX_IMAGE_SIDE as u64;
        match self.integer("image_W", 1, side) {
            Ok(Some(w)) => cam.image_width = w as u32,
            Ok(None) => {}
            Err(Reported) => sizes_read = false,
        }
        match self.integer("image_H", 1, side) {
            Ok(Some(h)) => cam.image_height = h as u32,
            Ok(None) => {}
            Err(Reported) => sizes_read = false,
        }
        if let Err(message) = check_image_size(cam.image_width, cam.image_height) {
            let span = self.span_of("image_W");
            self.error(span, message);
            sizes_read = false;
        }
        let q = MAX_QUALITY as u64;
        if let Ok(Some(v)) = self.integer("shade_quality", 1, q) {
            cam.shade_quality = v as u32;
        }
        if let Ok(Some(v)) = self.integer("drefl_quality", 1, q) {
            cam.drefl_quality = v as u32;
        }
        cam.photons = self.photon_settings();
        if let Ok(Some((name, span))) = self.text("algorithm") {
            match Algorithm::from_name(&name) {
                Some(a) => cam.algorithm = Some((a, self.parser.source.location(span))),
                None => {
                    let expected = Algorithm::NAMES.map(|n| format!("`{n}`")).join(", ");
                    self.error(span, format!("unknown `algorithm=` `{name}`"))
                        .notes
                        .push(format!("expected one of {expected}"));
                }
            }
        }
        if let Ok(Some(a)) = self.number("aperture") {
            if a >= 0.0 {
                cam.aperture = a;
            } else {
                let span = self.span_of("aperture");
                self.error(span, "`aperture=` must not be negative");
            }
        }
        if let Ok(Some(f)) = self.number("focal_dist") {
            if f > 0.0 {
                cam.focal_distance = Some(f);
            } else {
                let span = self.span_of("focal_dist");
                self.error(span, "`focal_dist=` must be positive");
            }
        }
        if let Some(message) = aspect_mismatch(&cam, cam.image_width, cam.image_height).filter(|_| sizes_read)
        {
            let span = self.span_of("lens_W");
            self.warning(span, message);
        }
        self.parser.scene.camera = cam;
    }

    /// The photon-mapping keys of the camera block, validated (spec section 10).
    fn photon_settings(&mut self) -> PhotonSettings {
        let mut photons = PhotonSettings::default();
        let mut keys: Vec<(&'static str, Span)> =
            PhotonSettings::KEYS.iter().filter_map(|&k| self.find(k).map(|e| (k, e.key_span))).collect();
        keys.sort_by_key(|(_, span)| (span.line, span.column));
        photons.keys = keys.into_iter().map(|(k, span)| (k, self.parser.source.location(span))).collect();
        for (key, slot, max) in [
            ("max_photons", &mut photons.max_photons, MAX_STORED_PHOTONS),
            ("emit_photons", &mut photons.emit_photons, MAX_EMITTED_PHOTONS),
            ("sample_photons", &mut photons.sample_photons, MAX_SAMPLE_PHOTONS),
            ("iterations", &mut photons.iterations, MAX_ITERATIONS),
        ] {
            if let Ok(Some(v)) = self.integer(key, 1, max) {
                *slot = v;
            }
        }
        if let Ok(Some(v)) = self.integer("max_hitpoints", 1, MAX_STORED_PHOTONS) {
            photons.max_hitpoints = Some(v);
        }
        if let Ok(Some(v)) = self.number("sample_dist") {
            if v > 0.0 {
                photons.sample_dist = v;
            } else {
                let span = self.span_of("sample_dist");
                self.error(span, "`sample_dist=` (the gathering radius) must be positive");
            }
        }
        if let Ok(Some(v)) = self.number("reduction") {
            if v > 0.0 && v <= 1.0 {
                photons.reduction = v;
            } else {
                let span = self.span_of("reduction");
                self.error(span, "`reduction=` (the radius reduction alpha) must lie in (0, 1]")
                    .notes
                    .push("2/3, the default, is the usual choice".into());
            }
        }
        photons
    }

    fn light(&mut self, kind: LightKind) {
        let color = match self.color("color", true) {
            Ok(Some(c)) => c,
            Ok(None) => {
                let header = self.header;
                self.warning(header, "this light has no `color=`, so it gives no light");
                DVec3::ZERO
            }
            Err(Reported) => DVec3::ZERO,
        };
        let o = self.required_vec3("O", "the light's position");
        let light = match kind {
            LightKind::Point => o.map(|position| Light::Point { position, color }),
            LightKind::Square => {
                let dx = self.required_vec3("Dx", "the first half axis");
                let dy = self.required_vec3("Dy", "the second half axis");
                match (o, dx, dy) {
                    (Some(o), Some(dx), Some(dy)) => {
                        self.built(Square::new(o, dx, dy)).map(|shape| Light::Square { shape, color })
                    }
                    _ => None,
                }
            }
            LightKind::Sphere => {
                let r = self.required_number("R", "the radius");
                match (o, r) {
                    (Some(o), Some(r)) => {
                        self.built(Sphere::new(o, r)).map(|shape| Light::Sphere { shape, color })
                    }
                    _ => None,
                }
            }
        };
        if let Some(light) = light {
            self.parser.scene.lights.push(light);
        }
    }

    fn material(&mut self) -> Material {
        let mut m = Material::default();
        if let Ok(Some(c)) = self.color("color", false) {
            m.color = c;
        }
        m.diff = self.weight("diff");
        m.spec = self.weight("spec");
        m.refl = self.weight("refl");
        m.drefl = self.weight("drefl");
        m.refr = self.weight("refr");
        if let Ok(Some(a)) = self.vec3("absor") {
            if a.min_element() < 0.0 {
                let span = self.span_of("absor");
                self.warning(span, "`absor=` is negative: light would grow inside the object");
            }
            m.absor = a;
        }
        match self.number("rindex") {
            Ok(Some(n)) if n > 0.0 => m.rindex = n,
            Ok(Some(_)) => {
                let span = self.span_of("rindex");
                self.error(span, "`rindex=` must be positive");
            }
            Ok(None) if m.refr > 0.0 => {
                let span = self.span_of("refr");
                self.error(span, "`refr=` is positive, so `rindex=` (the refractive index) is required");
            }
            _ => {}
        }
        if let Ok(Some((blur, span))) = self.text("blur")
            && blur != "exp"
        {
            self.warning(
                span,
                format!("unknown `blur= {blur}`; `exp` is the only distribution, and it is used"),
            );
        }
        m.texture = self.texture_ref("texture");
        // A normal map: `bump=`, or `NT=` (LuChengTHU's name for it); `bump=` wins if both are given.
        let nt = self.texture_ref("NT");
        m.bump = self.texture_ref("bump").or(nt);
        m
    }

    /// A texture named by `key=`: a file or a built-in texture.
    fn texture_ref(&mut self, key: &str) -> Option<TextureRef> {
        let Ok(Some((path, span))) = self.text(key) else { return None };
        let location = self.parser.source.location(span);
        let source = match path.strip_prefix(BUILTIN_PREFIX) {
            Some(name) => match Builtin::parse(name) {
                Ok(b) => TextureSource::Builtin(b),
                Err(message) => {
                    self.error(span, message);
                    return None;
                }
            },
            None => TextureSource::File(path),
        };
        Some(TextureRef { source, location })
    }

    fn primitive(&mut self, kind: PrimitiveKind) {
        let material = self.material();
        let shape = match kind {
            PrimitiveKind::Triangle => self.triangle(),
            PrimitiveKind::Mesh => self.mesh("file", "scale", "rotation", 1.0),
            PrimitiveKind::Polyhedron => self.mesh("mesh", "size", "angles", std::f64::consts::PI / 180.0),
            PrimitiveKind::Bezier => self.bezier(),
            PrimitiveKind::Sphere => {
                let o = self.required_vec3("O", "the centre");
                let r = self.required_number("R", "the radius");
                let pole = self.vec3("De").ok().flatten().unwrap_or(DVec3::Z);
                let seam = self.vec3("Dc").ok().flatten().unwrap_or(DVec3::Y);
                match (o, r) {
                    (Some(o), Some(r)) => self.built(Sphere::with_frame(o, r, pole, seam).map(Shape::Sphere)),
                    _ => None,
                }
            }
            PrimitiveKind::Plane => {
                let n = self.required_vec3("N", "the normal");
                let r = self.required_number("R", "the offset from the origin along the normal");
                let dx = self.vec3("Dx");
                let dy = self.vec3("Dy");
                let (n, r) = match (n, r) {
                    (Some(n), Some(r)) => (n, r),
                    _ => return,
                };
                let Some(plane) = self.built(Plane::new(n, r)) else { return };
                match (dx, dy) {
                    (Ok(Some(dx)), Ok(Some(dy))) => {
                        self.built(plane.with_texture_axes(dx, dy).map(Shape::Plane))
                    }
                    (Ok(None), _) | (_, Ok(None)) if material.texture.is_some() => {
                        let header = self.header;
                        self.error(header, "a textured `primitive plane` needs `Dx=` and `Dy=`")
                            .notes
                            .push("their lengths are the world size of one texture tile".into());
                        None
                    }
                    (Err(Reported), _) | (_, Err(Reported)) => None,
                    _ => Some(Shape::Plane(plane)),
                }
            }
            PrimitiveKind::Square => {
                let o = self.required_vec3("O", "the centre");
                let dx = self.required_vec3("Dx", "the first half axis");
                let dy = self.required_vec3("Dy", "the second half axis");
                match (o, dx, dy) {
                    (Some(o), Some(dx), Some(dy)) => {
                        self.built(Square::new(o, dx, dy).map(|s| Shape::Square(Box::new(s))))
                    }
                    _ => None,
                }
            }
            PrimitiveKind::Cylinder => {
                let o1 = self.required_vec3("O1", "the bottom cap centre");
                let o2 = self.required_vec3("O2", "the top cap centre");
                let r = self.required_number("R", "the radius");
                for key in ["De", "Dc"] {
                    if let Some(e) = self.entry(key) {
                        self.parser
                            .report(
                                Severity::Note,
                                e.key_span,
                                format!("`{key}=` has no effect on a cylinder"),
                            )
                            .notes
                            .push("the side texture's seam follows the axis (spec 5.6)".into());
                    }
                }
                match (o1, o2, r) {
                    (Some(o1), Some(o2), Some(r)) => {
                        self.built(Cylinder::new(o1, o2, r).map(|c| Shape::Cylinder(Box::new(c))))
                    }
                    _ => None,
                }
            }
        };
        if let Some(shape) = shape {
            let material = self.parser.share(material);
            self.parser.scene.primitives.push(Primitive { shape, material });
        }
    }

    /// `primitive triangle`: corners `P0= P1= P2=`, or `O1= O2= O3=`.
    fn triangle(&mut self) -> Option<Shape> {
        let form = if ["O1", "O2", "O3"].iter().any(|k| self.has(k))
            && !["P0", "P1", "P2"].iter().any(|k| self.has(k))
        {
            ["O1", "O2", "O3"]
        } else {
            ["P0", "P1", "P2"]
        };
        let corners = form.map(|k| self.vec3(k));
        if corners.iter().any(|c| c.is_err()) {
            return None;
        }
        let missing: Vec<&str> =
            form.iter().zip(&corners).filter(|(_, c)| matches!(c, Ok(None))).map(|(k, _)| *k).collect();
        if !missing.is_empty() {
            let header = self.header;
            let list = missing.iter().map(|k| format!("`{k}=`")).collect::<Vec<_>>().join(", ");
            self.error(header, format!("`primitive triangle` needs {list} (its corners)"))
                .notes
                .push("give the corners as `P0= P1= P2=` or as `O1= O2= O3=`".into());
            return None;
        }
        let [a, b, c] = corners.map(|c| c.ok().flatten().unwrap_or_default());
        match Triangle::new(a, b, c) {
            Ok(t) => Some(Shape::Triangle(Box::new(t))),
            Err(e) => {
                let span = self.span_of(form[2]);
                self.error(span, format!("in `primitive triangle`, {e}"));
                None
            }
        }
    }

    /// `primitive mesh` (`file=`, `O=`, `scale=`, `rotation=` in radians) and `primitive
    /// polyhedron` (`mesh=`, `O=`, `size=`, `angles=` in degrees): the file is loaded when the
    /// scene is prepared.
    fn mesh(
        &mut self,
        file_key: &str,
        scale_key: &str,
        rotation_key: &str,
        to_radians: f64,
    ) -> Option<Shape> {
        let file = match self.text(file_key) {
            Ok(Some(f)) => Some(f),
            Ok(None) => {
                let header = self.header;
                self.error(header, format!("`{}` needs `{file_key}=` (the OBJ file)", self.kind));
                None
            }
            Err(Reported) => None,
        };
        let origin = self.vec3("O");
        let scale = match self.numbers_1_or_3(scale_key) {
            Ok(Some(s)) if s.x == 0.0 || s.y == 0.0 || s.z == 0.0 => {
                let span = self.span_of(scale_key);
                self.error(
                    span,
                    format!("`{scale_key}=` must not have a zero component (the mesh would be flat)"),
                );
                Err(Reported)
            }
            other => other,
        };
        let rotation = self.vec3(rotation_key);
        let (Some((path, span)), Ok(origin), Ok(scale), Ok(rotation)) = (file, origin, scale, rotation)
        else {
            return None;
        };
        let transform = MeshTransform {
            origin: origin.unwrap_or(DVec3::ZERO),
            scale: scale.unwrap_or(DVec3::ONE),
            rotation: rotation.unwrap_or(DVec3::ZERO) * to_radians,
        };
        let location = self.parser.source.location(span);
        Some(Shape::MeshFile(Box::new(MeshFile { path, location, transform })))
    }

    /// A vector of 3 numbers, or 1 number for all three components.
    fn numbers_1_or_3(&mut self, key: &str) -> Lookup<DVec3> {
        match self.find(key).map(|e| e.values.len()) {
            Some(1) => Ok(self.number(key)?.map(DVec3::splat)),
            _ => self.vec3(key),
        }
    }

    /// `primitive bezier`: axis `O1=` to `O2=` with profile points `P= z r` (one a line), or
    /// `center=` with `V0= .. V3=` (abcbdf's form: a cubic about the vertical through `center`).
    fn bezier(&mut self) -> Option<Shape> {
        if self.has("center") {
            let center = self.required_vec3("center", "the point the vertical axis passes through");
            let v = ["V0", "V1", "V2", "V3"].map(|k| self.required_vec3(k, "a control point of the cubic"));
            let center = center?;
            if v.iter().any(Option::is_none) {
                return None;
            }
            let profile: Vec<DVec2> =
                v.iter().flatten().map(|p| DVec2::new(p.z, (p.x - center.x).abs())).collect();
            let base = DVec3::new(center.x, center.y, 0.0);
            return self.built(Bezier::new(base, DVec3::Z, profile).map(|b| Shape::Bezier(Box::new(b))));
        }
        let o1 = self.required_vec3("O1", "the bottom of the axis");
        let o2 = self.required_vec3("O2", "a point up the axis");
        let points = std::mem::take(&mut self.points);
        let mut profile = Vec::with_capacity(points.len());
        let mut bad = false;
        for e in &points {
            let mut values = Vec::with_capacity(2);
            for (text, span) in e.values.iter() {
                match text.parse::<f64>() {
                    Ok(v) if v.is_finite() => values.push(v),
                    _ => {
                        self.error(*span, format!("`P=` expects 2 numbers (z r); `{text}` is not a number"));
                        bad = true;
                    }
                }
            }
            if values.len() == 2 {
                profile.push(DVec2::new(values[0], values[1]));
            } else if !bad {
                let found = e.values.len();
                self.error(e.values_span(), format!("`P=` expects 2 numbers (z r), found {found}"));
                bad = true;
            }
        }
        let (o1, o2) = (o1?, o2?);
        if bad {
            return None;
        }
        if profile.len() < 2 || profile.len() > crate::geometry::bezier::MAX_CONTROL_POINTS {
            let header = self.header;
            self.error(
                header,
                format!(
                    "`primitive bezier` needs 2 to 32 `P= z r` lines (its profile), not {}",
                    profile.len()
                ),
            )
            .notes
            .push("one line per control point, in order; or give `center=` and `V0=` .. `V3=`".into());
            return None;
        }
        if profile.iter().any(|p| p.y < 0.0) {
            let span = points.iter().find(|e| e.values.get(1).is_some_and(|v| v.0.starts_with('-')));
            let span = span.map_or(self.header, Entry::values_span);
            self.warning(span, "a negative `r` in `P= z r` is a distance from the axis; its size is used");
        }
        self.built(Bezier::new(o1, o2 - o1, profile).map(|b| Shape::Bezier(Box::new(b))))
    }

    /// The constructed value, or `None` after reporting why it could not be built.
    fn built<T>(&mut self, value: Result<T, GeometryError>) -> Option<T> {
        value.map_err(|e| self.geometry_error(e)).ok()
    }

    /// Warns about keys the block does not know.
    fn finish(self) {
        let BlockReader { kind, mut entries, used, parser, .. } = self;
        let mut unknown: Vec<&Entry> =
            entries.iter().zip(&used).filter(|(_, u)| !**u).map(|(e, _)| e).collect();
        unknown.sort_by_key(|e| (e.key_span.line, e.key_span.column));
        for e in unknown {
            let known = known_keys(kind);
            let d = parser.warning(e.key_span, format!("unknown key `{}=` in `{kind}`; ignored", e.key));
            if let Some(k) = known.iter().find(|k| k.eq_ignore_ascii_case(e.key)) {
                d.notes.push(format!("did you mean `{k}=`? keys are case-sensitive"));
            } else {
                d.notes.push(format!(
                    "`{kind}` knows {}",
                    known.iter().map(|k| format!("`{k}=`")).collect::<Vec<_>>().join(", ")
                ));
            }
        }
        entries.clear();
        parser.spare_entries = entries;
    }
}

/// The keys a block kind understands.
fn known_keys(kind: BlockKind) -> Vec<&'static str> {
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

/// Checks an image size against [`MAX_IMAGE_SIDE`] and [`MAX_IMAGE_PIXELS`].
pub fn check_image_size(width: u32, height: u32) -> Result<(), String> {
    if width == 0 || height == 0 {
        return Err(format!("the image size {width}x{height} is empty"));
    }
    if width > MAX_IMAGE_SIDE || height > MAX_IMAGE_SIDE || width as u64 * height as u64 > MAX_IMAGE_PIXELS {
        return Err(format!(
            "the image size {width}x{height} is too large: at most {MAX_IMAGE_SIDE} pixels a side and {} megapixels",
            MAX_IMAGE_PIXELS / 1_000_000
        ));
    }
    Ok(())
}

/// A warning text when the lens aspect `lens_W / lens_H` differs from the image aspect by more
/// than 1% (the picture would be stretched).
pub fn aspect_mismatch(camera: &CameraSettings, width: u32, height: u32) -> Option<String> {
    let lens = camera.lens_width / camera.lens_height;
    let image = width as f64 / height as f64;
    ((lens / image - 1.0).abs() > 0.01).then(|| {
        format!(
            "the lens aspect lens_W/lens_H = {lens:.4} differs from the image aspect {width}/{height} = {image:.4}: the picture will be stretched"
        )
    })
}

#[cfg(test)]
#[path = "parser_tests.rs"]
mod tests;
