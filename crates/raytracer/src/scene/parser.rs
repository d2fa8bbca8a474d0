//! The parser of the course scene language (spec section 2 and 3).
//!
//! The file is read line by line. A line is cut at the first `#` or `//` (a comment), split into
//! whitespace-separated tokens, and then is either a block header (`background`, `camera`,
//! `light TYPE`, `primitive TYPE`), a key line (`key= value ...`) inside a block, or `end`. Every
//! problem becomes a [`Diagnostic`] with its line and column; parsing goes on after an error so one
//! run reports them all.

use std::collections::HashMap;
use std::fmt;

use glam::DVec3;

use super::diagnostic::{Diagnostic, Severity};
use super::source::{SourceFile, Span};
use super::{Algorithm, Background, CameraSettings, Gradient, PhotonSettings, Primitive, Scene};
use crate::error::GeometryError;
use crate::geometry::{Cylinder, Plane, Shape, Sphere, Square};
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
    let mut parser = Parser {
        source,
        diagnostics: Vec::new(),
        kept: Omitted::default(),
        omitted: Omitted::default(),
        scratch: Diagnostic::general(Severity::Note, ""),
        scene: Scene::empty(),
        seen: Seen::default(),
    };
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

/// Splits a line into tokens, dropping the comment (from the first `#` or `//`).
fn tokenize(line: &str) -> Vec<Token<'_>> {
    let mut tokens = Vec::new();
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
        tokens.push(Token { text, column: c, len: text.chars().count() as u32 });
    }
    tokens
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
}

impl fmt::Display for BlockKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            BlockKind::Background => "background",
            BlockKind::Camera => "camera",
            BlockKind::Light(LightKind::Point) => "light point",
            BlockKind::Light(LightKind::Square) => "light square",
            BlockKind::Light(LightKind::Sphere) => "light sphere",
            BlockKind::Primitive(PrimitiveKind::Sphere) => "primitive sphere",
            BlockKind::Primitive(PrimitiveKind::Plane) => "primitive plane",
            BlockKind::Primitive(PrimitiveKind::Square) => "primitive square",
            BlockKind::Primitive(PrimitiveKind::Cylinder) => "primitive cylinder",
        })
    }
}

/// Keys every primitive accepts (material keys).
const MATERIAL_KEYS: [&str; 10] =
    ["color", "texture", "diff", "spec", "refl", "drefl", "blur", "refr", "rindex", "absor"];

/// Primitive types of the same family that this version does not draw (spec section 9).
const LATER_PRIMITIVES: [&str; 5] = ["triangle", "mesh", "polyhedron", "bezier", "obj"];

/// One `key= values` line of a block.
#[derive(Clone, Debug)]
struct Entry {
    key: String,
    key_span: Span,
    /// The value tokens (the text after `=` when glued to the key counts as the first), at most
    /// [`MAX_VALUES_KEPT`] of them.
    values: Vec<(String, Span)>,
    /// How many values the line has, kept or not.
    value_count: usize,
    /// The span of all the values, or of the key when there are none.
    all_values: Span,
}

/// Most values kept from one key line: no key takes more than a few, and a hostile line may hold
/// millions (the rest are counted, not copied).
const MAX_VALUES_KEPT: usize = 16;

impl Entry {
    /// The span of all values, or of the key when there are none.
    fn values_span(&self) -> Span {
        self.all_values
    }
}

/// A block being read: its kind, header position and key lines.
struct OpenBlock {
    kind: BlockKind,
    header: Span,
    entries: Vec<Entry>,
    /// The line each key was last given on (a hostile file may repeat a key a million times).
    last_line: HashMap<String, u32>,
}

/// Parser state between lines.
enum State {
    TopLevel,
    InBlock(OpenBlock),
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
}

impl<'s> Parser<'s> {
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
        let mut state = State::TopLevel;
        let source = self.source;
        for (number, line) in source.lines() {
            let tokens = tokenize(line);
            let Some(first) = tokens.first() else { continue };
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
    fn top_level_line(&mut self, line: u32, tokens: &[Token<'_>]) -> State {
        let first = tokens[0];
        let span = first.span(line);
        let start = |kind: BlockKind, header: Span| {
            State::InBlock(OpenBlock { kind, header, entries: Vec::new(), last_line: HashMap::new() })
        };
        match first.text {
            "background" | "camera" => {
                self.warn_trailing(line, &tokens[1..], "after the block name");
                let kind = if first.text == "camera" { BlockKind::Camera } else { BlockKind::Background };
                start(kind, span)
            }
            "light" | "primitive" => {
                let Some(&ty) = tokens.get(1) else {
                    let choices = if first.text == "light" {
                        "`point`, `square`, `area` or `sphere`"
                    } else {
                        "`sphere`, `plane`, `square` or `cylinder`"
                    };
                    self.error(span, format!("`{}` needs a type: {choices}", first.text));
                    return State::Skipping(span);
                };
                let ty_span = ty.span(line);
                let kind = match (first.text, ty.text) {
                    ("light", "point") => Some(BlockKind::Light(LightKind::Point)),
                    ("light", "square" | "area") => Some(BlockKind::Light(LightKind::Square)),
                    ("light", "sphere") => Some(BlockKind::Light(LightKind::Sphere)),
                    ("primitive", "sphere") => Some(BlockKind::Primitive(PrimitiveKind::Sphere)),
                    ("primitive", "plane") => Some(BlockKind::Primitive(PrimitiveKind::Plane)),
                    ("primitive", "square") => Some(BlockKind::Primitive(PrimitiveKind::Square)),
                    ("primitive", "cylinder") => Some(BlockKind::Primitive(PrimitiveKind::Cylinder)),
                    _ => None,
                };
                match kind {
                    Some(kind) => {
                        self.warn_trailing(line, &tokens[2..], "after the block type");
                        start(kind, ty_span)
                    }
                    None => {
                        let message = if first.text == "primitive" && LATER_PRIMITIVES.contains(&ty.text) {
                            format!("`primitive {}` is not supported yet; the block is skipped", ty.text)
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
    fn key_line(&mut self, line: u32, tokens: &[Token<'_>], block: &mut OpenBlock) {
        let first = tokens[0];
        let (key, key_len, glued, rest) = match first.text.split_once('=') {
            Some((key, after)) => (key, key.chars().count() as u32 + 1, after, &tokens[1..]),
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
        let mut values = Vec::with_capacity((rest.len() + 1).min(MAX_VALUES_KEPT));
        let glued_value = (!glued.is_empty()).then(|| {
            let column = first.column + key_len;
            (glued, Span { line, column, len: glued.chars().count() as u32 })
        });
        let all = glued_value.into_iter().chain(rest.iter().map(|t| (t.text, t.span(line))));
        values.extend(all.clone().take(MAX_VALUES_KEPT).map(|(text, span)| (text.to_owned(), span)));
        let value_count = glued_value.is_some() as usize + rest.len();
        let last_span = rest.last().map(|t| t.span(line)).or(glued_value.map(|(_, span)| span));
        let all_values = match (values.first(), last_span) {
            (Some((_, first)), Some(last)) => {
                Span { line, column: first.column, len: last.column + last.len - first.column }
            }
            _ => key_span,
        };
        if let Some(earlier) = block.last_line.insert(key.to_owned(), line) {
            self.warning(
                key_span,
                format!("`{key}=` is given again; this value replaces the one on line {earlier}"),
            );
        }
        block.entries.push(Entry { key: key.to_owned(), key_span, values, value_count, all_values });
    }

    /// Turns a complete block into scene data.
    fn finish_block(&mut self, block: OpenBlock) {
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
    matches!(word, "background" | "camera" | "light" | "primitive")
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
    /// The last entry of each key (later lines win).
    entries: HashMap<String, Entry>,
    used: Vec<String>,
    parser: &'p mut Parser<'s>,
}

impl<'p, 's> BlockReader<'p, 's> {
    fn new(block: OpenBlock, parser: &'p mut Parser<'s>) -> Self {
        let mut entries = HashMap::new();
        for e in block.entries {
            entries.insert(e.key.clone(), e);
        }
        BlockReader { kind: block.kind, header: block.header, entries, used: Vec::new(), parser }
    }

    /// The entry of `key`, marked as used.
    fn entry(&mut self, key: &str) -> Option<Entry> {
        let e = self.entries.get(key)?.clone();
        self.used.push(key.to_owned());
        Some(e)
    }

    fn span_of(&self, key: &str) -> Span {
        self.entries.get(key).map_or(self.header, Entry::values_span)
    }

    fn error(&mut self, span: Span, message: impl Into<String>) -> &mut Diagnostic {
        self.parser.error(span, message)
    }

    fn warning(&mut self, span: Span, message: impl Into<String>) -> &mut Diagnostic {
        self.parser.warning(span, message)
    }

    /// Parses `n` numbers of `key`.
    fn numbers(&mut self, key: &str, n: usize) -> Lookup<Vec<f64>> {
        let Some(entry) = self.entry(key) else { return Ok(None) };
        let what = if n == 1 { "a number".to_owned() } else { format!("{n} numbers") };
        if entry.value_count != n {
            let found = entry.value_count;
            let message = if found == 0 {
                format!("`{key}=` expects {what}")
            } else {
                format!("`{key}=` expects {what}, found {found} value{}", if found == 1 { "" } else { "s" })
            };
            self.error(entry.values_span(), message);
            return Err(Reported);
        }
        let mut out = Vec::with_capacity(n);
        let mut bad = false;
        for (text, span) in &entry.values {
            match text.parse::<f64>() {
                Ok(v) if v.is_finite() => out.push(v),
                Ok(_) => {
                    self.error(*span, format!("`{text}` is not a finite number"));
                    bad = true;
                }
                Err(_) => {
                    self.error(*span, format!("`{key}=` expects {what}; `{text}` is not a number"));
                    bad = true;
                }
            }
        }
        if bad { Err(Reported) } else { Ok(Some(out)) }
    }

    fn number(&mut self, key: &str) -> Lookup<f64> {
        Ok(self.numbers(key, 1)?.map(|v| v[0]))
    }

    fn vec3(&mut self, key: &str) -> Lookup<DVec3> {
        Ok(self.numbers(key, 3)?.map(|v| DVec3::new(v[0], v[1], v[2])))
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
        let mut keys: Vec<(&'static str, Span)> = PhotonSettings::KEYS
            .iter()
            .filter_map(|&k| self.entries.get(k).map(|e| (k, e.key_span)))
            .collect();
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
        if let Ok(Some((path, span))) = self.text("texture") {
            let location = self.parser.source.diagnostic(Severity::Note, span, "").location;
            let source = match path.strip_prefix(BUILTIN_PREFIX) {
                Some(name) => match Builtin::parse(name) {
                    Ok(b) => Some(TextureSource::Builtin(b)),
                    Err(message) => {
                        self.error(span, message);
                        None
                    }
                },
                None => Some(TextureSource::File(path)),
            };
            if let (Some(source), Some(location)) = (source, location) {
                m.texture = Some(TextureRef { source, location });
            }
        }
        m
    }

    fn primitive(&mut self, kind: PrimitiveKind) {
        let material = self.material();
        let shape = match kind {
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
                    (Some(o), Some(dx), Some(dy)) => self.built(Square::new(o, dx, dy).map(Shape::Square)),
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
                        self.built(Cylinder::new(o1, o2, r).map(Shape::Cylinder))
                    }
                    _ => None,
                }
            }
        };
        if let Some(shape) = shape {
            self.parser.scene.primitives.push(Primitive { shape, material });
        }
    }

    /// The constructed value, or `None` after reporting why it could not be built.
    fn built<T>(&mut self, value: Result<T, GeometryError>) -> Option<T> {
        value.map_err(|e| self.geometry_error(e)).ok()
    }

    /// Warns about keys the block does not know.
    fn finish(self) {
        let BlockReader { kind, entries, used, parser, .. } = self;
        let mut unknown: Vec<&Entry> = entries.values().filter(|e| !used.contains(&e.key)).collect();
        unknown.sort_by_key(|e| (e.key_span.line, e.key_span.column));
        for e in unknown {
            let known = known_keys(kind);
            let d = parser.warning(e.key_span, format!("unknown key `{}=` in `{kind}`; ignored", e.key));
            if let Some(k) = known.iter().find(|k| k.eq_ignore_ascii_case(&e.key)) {
                d.notes.push(format!("did you mean `{k}=`? keys are case-sensitive"));
            } else {
                d.notes.push(format!(
                    "`{kind}` knows {}",
                    known.iter().map(|k| format!("`{k}=`")).collect::<Vec<_>>().join(", ")
                ));
            }
        }
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
