//! Errors, warnings and notes about a scene file, shown with the offending text underlined.

use std::fmt;

/// A position in a scene file: 1-based line and column (counted in characters; a tab is one
/// column) and the length of the marked text in characters.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct Span {
    /// 1-based line number.
    pub line: u32,
    /// 1-based column of the first marked character.
    pub column: u32,
    /// Number of marked characters (at least 1 when displayed).
    pub len: u32,
}

/// How serious a diagnostic is.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Severity {
    /// The scene cannot be rendered.
    Error,
    /// The scene renders, but probably not as meant.
    Warning,
    /// Information only.
    Note,
}

impl fmt::Display for Severity {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Severity::Error => "error",
            Severity::Warning => "warning",
            Severity::Note => "note",
        })
    }
}

/// Where a diagnostic points: the file, the span and a copy of the line's text around it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Location {
    /// File name as shown to the user.
    pub file: String,
    /// Line, column and length of the marked text.
    pub span: Span,
    /// The text of the line (for the excerpt): the whole line, or for a line longer than
    /// [`MAX_KEPT_LINE_CHARS`] characters the characters around the marked text.
    pub line_text: String,
    /// The 1-based column of the line where `line_text` starts: 1, unless a long line was cut.
    pub text_column: u32,
}

/// Most characters of a line a [`Location`] keeps: a longer line keeps the characters around the
/// marked text (more than an excerpt shows), so that a diagnostic about a line of 100 MB does
/// not copy it.
pub const MAX_KEPT_LINE_CHARS: usize = 1024;

impl Location {
    /// The place `span` marks in line `line` of file `file`, keeping at most
    /// [`MAX_KEPT_LINE_CHARS`] characters of the line.
    pub fn new(file: impl Into<String>, span: Span, line: &str) -> Location {
        let file = file.into();
        if line.len() <= MAX_KEPT_LINE_CHARS {
            return Location { file, span, line_text: line.to_owned(), text_column: 1 };
        }
        let half = MAX_KEPT_LINE_CHARS / 2;
        let skip = (span.column as usize).saturating_sub(1).saturating_sub(half);
        let line_text: String = line.chars().skip(skip).take(MAX_KEPT_LINE_CHARS).collect();
        Location { file, span, line_text, text_column: skip as u32 + 1 }
    }

    /// The marked text as the line holds it (cut to the part of the line kept).
    pub fn marked_text(&self) -> String {
        let skip = (self.span.column.saturating_sub(self.text_column)) as usize;
        self.line_text.chars().skip(skip).take(self.span.len as usize).collect()
    }
}

/// Most characters of a piece of input (a name, a number, a key, a path) quoted in a message;
/// a longer one is cut, with `...` (see [`clip`]).
pub const MAX_QUOTED_CHARS: usize = 64;

/// Most characters of a message, a note or a file name as printed (after escaping): a safety net
/// behind [`clip`], so that no diagnostic prints more than a few kilobytes.
pub const MAX_PRINTED_CHARS: usize = 1000;

/// A piece of input to quote in a message, cut to [`MAX_QUOTED_CHARS`] characters with `...`
/// after it when longer: `format!("unknown block `{}`", clip(name))`. Allocates nothing.
pub fn clip(text: &str) -> Clipped<'_> {
    Clipped(text)
}

/// A path to quote in a message, cut as [`clip`] cuts text.
pub fn clip_path(path: &std::path::Path) -> Clipped<'_> {
    Clipped(path.to_str().unwrap_or("(a path that is not UTF-8)"))
}

/// Text shown cut to [`MAX_QUOTED_CHARS`] characters (made by [`clip`]).
#[derive(Clone, Copy, Debug)]
pub struct Clipped<'a>(&'a str);

impl fmt::Display for Clipped<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.0.char_indices().nth(MAX_QUOTED_CHARS) {
            None => f.write_str(self.0),
            Some((end, _)) => write!(f, "{}...", &self.0[..end]),
        }
    }
}

/// `text` cut to `max` characters, with `...` after it when longer.
fn bounded(text: &str, max: usize) -> std::borrow::Cow<'_, str> {
    match text.char_indices().nth(max) {
        None => std::borrow::Cow::Borrowed(text),
        Some((end, _)) => std::borrow::Cow::Owned(format!("{}...", &text[..end])),
    }
}

/// Text to print: escaped ([`escape_for_terminal`]), then cut to [`MAX_PRINTED_CHARS`].
fn printable(text: &str) -> String {
    // Cut before escaping too (an escape is at most 10 characters), so that the escaped copy of
    // a huge text is never made.
    let cut = bounded(text, MAX_PRINTED_CHARS);
    bounded(&escape_for_terminal(&cut), MAX_PRINTED_CHARS).into_owned()
}

/// One message about a scene file.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Diagnostic {
    /// Error, warning or note.
    pub severity: Severity,
    /// One line explaining the problem.
    pub message: String,
    /// Where in the file, when the problem has a place.
    pub location: Option<Location>,
    /// Extra lines of help shown below the excerpt.
    pub notes: Vec<String>,
}

impl Diagnostic {
    /// A diagnostic without a place in a file.
    pub fn general(severity: Severity, message: impl Into<String>) -> Diagnostic {
        Diagnostic { severity, message: message.into(), location: None, notes: Vec::new() }
    }

    /// Adds a line of help.
    pub fn with_note(mut self, note: impl Into<String>) -> Diagnostic {
        self.notes.push(note.into());
        self
    }

    /// Whether this is an error.
    pub fn is_error(&self) -> bool {
        self.severity == Severity::Error
    }
}

/// Tab stops used when echoing a line.
const TAB_WIDTH: usize = 4;
/// Widest excerpt echoed, in columns: a longer line is cut around the marked text, with `...`
/// where text is left out.
const MAX_EXCERPT_WIDTH: usize = 100;
/// Columns of context kept before the marked text when a long line is cut.
const CONTEXT_BEFORE: usize = 32;

/// Whether a character is shown escaped: control characters (NUL, escape sequences...) and the
/// bidirectional formatting characters, which could make the echoed text read differently from
/// the file (U+202E turns the rest of the line around).
fn needs_escape(ch: char) -> bool {
    ch.is_control()
        || matches!(ch, '\u{061C}' | '\u{200E}' | '\u{200F}' | '\u{202A}'..='\u{202E}' | '\u{2066}'..='\u{2069}')
}

/// Text from a scene file (or its name) made safe to print: control and bidirectional characters
/// are shown as escapes such as `\u{202e}`; newlines and tabs of the message itself stay.
pub(crate) fn escape_for_terminal(text: &str) -> std::borrow::Cow<'_, str> {
    if !text.chars().any(|c| needs_escape(c) && c != '\n' && c != '\t') {
        return std::borrow::Cow::Borrowed(text);
    }
    let mut out = String::with_capacity(text.len() + 8);
    for ch in text.chars() {
        if needs_escape(ch) && ch != '\n' && ch != '\t' {
            out.extend(ch.escape_unicode());
        } else {
            out.push(ch);
        }
    }
    std::borrow::Cow::Owned(out)
}

/// How character `ch` of a line is echoed when it starts at display column `at` (0-based): tabs
/// become spaces up to the next tab stop, control and bidirectional characters escapes.
fn echo_piece(ch: char, at: usize, out: &mut String) {
    if ch == '\t' {
        out.extend(std::iter::repeat_n(' ', TAB_WIDTH - at % TAB_WIDTH));
    } else if needs_escape(ch) {
        out.extend(ch.escape_unicode());
    } else {
        out.push(ch);
    }
}

/// The width in columns of [`echo_piece`]'s output.
fn piece_width(ch: char, at: usize) -> usize {
    if ch == '\t' {
        TAB_WIDTH - at % TAB_WIDTH
    } else if needs_escape(ch) {
        ch.escape_unicode().count()
    } else {
        1
    }
}

/// The echoed line and the caret line's offset and width, for `span`'s columns (1-based,
/// counted in characters) of `line`. Linear in the line's length, and at most about
/// [`MAX_EXCERPT_WIDTH`] columns wide whatever the line's length.
fn excerpt(line: &str, column: u32, len: u32) -> (String, usize, usize) {
    let first = column as usize;
    let last = first + len.max(1) as usize; // one past the last marked character
    // Pass 1: the display columns of the marked text and of the whole line.
    let (mut caret_start, mut caret_end, mut width) = (None, None, 0usize);
    for (i, ch) in line.chars().enumerate() {
        let col = i + 1;
        if col == first {
            caret_start = Some(width);
        }
        width += piece_width(ch, width);
        if col >= first && col < last {
            caret_end = Some(width);
        }
    }
    let caret_start = caret_start.unwrap_or(width);
    let caret_end = caret_end.unwrap_or(caret_start + 1).max(caret_start + 1);
    // The window of display columns to show.
    let (lo, hi) = if width <= MAX_EXCERPT_WIDTH {
        (0, width)
    } else {
        let lo = caret_start.saturating_sub(CONTEXT_BEFORE).min(width.saturating_sub(MAX_EXCERPT_WIDTH));
        (lo, (lo + MAX_EXCERPT_WIDTH).min(width))
    };
    // Pass 2: the characters wholly inside the window.
    let mut echoed = String::new();
    if lo > 0 {
        echoed.push_str("...");
    }
    let (mut shown_from, mut shown_to, mut at) = (None, lo, 0usize);
    for ch in line.chars() {
        let w = piece_width(ch, at);
        if at >= hi {
            break;
        }
        if at >= lo && at + w <= hi {
            shown_from.get_or_insert(at);
            echo_piece(ch, at, &mut echoed);
            shown_to = at + w;
        }
        at += w;
    }
    let shown_from = shown_from.unwrap_or(lo);
    if shown_to < width {
        echoed.push_str("...");
    }
    let prefix = if lo > 0 { 3 } else { 0 };
    let offset = prefix + caret_start.clamp(shown_from, shown_to.max(shown_from)) - shown_from;
    let visible_end = if caret_start >= width { caret_end } else { caret_end.min(shown_to) };
    let caret_width = visible_end.saturating_sub(caret_start.max(shown_from)).max(1);
    (echoed, offset, caret_width)
}

impl fmt::Display for Diagnostic {
    /// Renders the diagnostic in the style of compiler messages:
    ///
    /// ```text
    /// error: `O=` expects 3 numbers, found 2
    ///  --> scene.txt:12:5
    ///    |
    /// 12 |     O= 1 2
    ///    |        ^^^
    ///    = note: ...
    /// ```
    ///
    /// Control and bidirectional characters are shown escaped; a line wider than 100 columns is
    /// cut around the marked text; a message, note or file name longer than
    /// [`MAX_PRINTED_CHARS`] characters is cut, with `...`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(f, "{}: {}", self.severity, printable(&self.message))?;
        let gutter = match &self.location {
            Some(loc) => {
                let number = loc.span.line.to_string();
                let pad = " ".repeat(number.len());
                let file = printable(&loc.file);
                writeln!(f, "{pad}--> {file}:{}:{}", loc.span.line, loc.span.column)?;
                writeln!(f, "{pad} |")?;
                // The columns within the text kept (the marked text may start before it only
                // when the location was made by hand).
                let column = loc.span.column.saturating_sub(loc.text_column.saturating_sub(1)).max(1);
                let (echoed, caret_start, caret_len) = excerpt(&loc.line_text, column, loc.span.len);
                writeln!(f, "{number} | {}", echoed.trim_end())?;
                writeln!(f, "{pad} | {}{}", " ".repeat(caret_start), "^".repeat(caret_len))?;
                pad
            }
            None => String::new(),
        };
        for note in &self.notes {
            writeln!(f, "{gutter} = note: {}", printable(note))?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn at(line_text: &str, column: u32, len: u32) -> Diagnostic {
        Diagnostic {
            severity: Severity::Error,
            message: "bad".into(),
            location: Some(Location::new("s.txt", Span { line: 7, column, len }, line_text)),
            notes: vec!["help text".into()],
        }
    }

    #[test]
    fn caret_underlines_the_span() {
        let text = at("    O= 1 2", 8, 3).to_string();
        assert_eq!(
            text,
            "error: bad\n --> s.txt:7:8\n  |\n7 |     O= 1 2\n  |        ^^^\n  = note: help text\n"
        );
    }

    #[test]
    fn tabs_are_expanded_consistently() {
        let text = at("\tR= x", 5, 1).to_string();
        assert!(text.contains("7 |     R= x\n  |        ^\n"), "{text}");
    }

    #[test]
    fn control_and_bidi_characters_are_escaped() {
        let mut d = at("O= a\u{202e}b\0", 4, 2);
        d.message = "bad `a\u{202e}b`".into();
        let text = d.to_string();
        assert!(!text.contains('\u{202e}') && !text.contains('\0'), "{text:?}");
        assert!(text.starts_with("error: bad `a\\u{202e}b`\n"), "{text}");
        // The caret still sits under the marked text, the escape counting as its printed width.
        assert!(text.contains("7 | O= a\\u{202e}b\\u{0}\n  |    ^^^^^^^^^\n"), "{text}");
    }

    #[test]
    fn long_lines_are_cut_around_the_span() {
        let mut line = "O= ".to_owned();
        line.push_str(&"1 ".repeat(5000));
        line.push('x');
        line.push_str(&" 2".repeat(5000));
        let column = 3 + 10_000 + 1;
        let text = at(&line, column as u32, 1).to_string();
        let echoed = text.lines().nth(3).expect("excerpt");
        let caret = text.lines().nth(4).expect("caret");
        assert!(echoed.len() < 120, "{echoed}");
        assert!(echoed.starts_with("7 | ...") && echoed.ends_with("..."), "{echoed}");
        let x = echoed.find('x').expect("the marked text is shown");
        assert_eq!(caret.find('^'), Some(x), "{echoed}\n{caret}");
        // A marked text longer than the window is cut too, and its caret with it.
        let text = at(&line, 4, 30_000).to_string();
        assert!(text.lines().all(|l| l.len() < 120), "{text}");
    }

    #[test]
    fn huge_lines_are_reported_in_linear_time() {
        // A million characters: counting the columns again for every character (the old code)
        // took minutes; one pass takes milliseconds.
        let line = "1 ".repeat(500_000);
        let started = std::time::Instant::now();
        let text = at(&line, 999_999, 1).to_string();
        assert!(text.len() < 400, "{text}");
        assert!(started.elapsed() < std::time::Duration::from_secs(10), "{:?}", started.elapsed());
    }

    #[test]
    fn clip_cuts_long_input_with_an_ellipsis() {
        assert_eq!(clip("sphere").to_string(), "sphere");
        let exact = "x".repeat(MAX_QUOTED_CHARS);
        assert_eq!(clip(&exact).to_string(), exact);
        let long = "\u{e9}".repeat(10 * MAX_QUOTED_CHARS);
        let cut = clip(&long).to_string();
        assert_eq!(cut.chars().count(), MAX_QUOTED_CHARS + 3, "{cut}");
        assert!(cut.ends_with("...") && cut.starts_with("\u{e9}\u{e9}"), "{cut}");
        let path = std::path::PathBuf::from("a/".repeat(1000));
        assert_eq!(clip_path(&path).to_string().len(), MAX_QUOTED_CHARS + 3);
    }

    #[test]
    fn a_huge_line_of_nuls_gives_a_small_diagnostic() {
        // A 10 MB line of NUL characters (one token): the location keeps a window of the line,
        // and a message quoting the whole token by mistake is still cut when printed.
        let line = "\0".repeat(10 << 20);
        let started = std::time::Instant::now();
        let span = Span { line: 1, column: 1, len: line.len() as u32 };
        let location = Location::new("n.txt", span, &line);
        assert!(location.line_text.len() <= MAX_KEPT_LINE_CHARS, "{}", location.line_text.len());
        let d = Diagnostic {
            severity: Severity::Error,
            message: format!("unknown block `{line}`"),
            location: Some(location),
            notes: vec![line.clone()],
        };
        let text = d.to_string();
        assert!(text.len() < 3 * MAX_PRINTED_CHARS + 1000, "{} bytes", text.len());
        assert!(text.starts_with("error: unknown block `\\u{0}\\u{0}"), "{}", &text[..100]);
        assert!(started.elapsed() < std::time::Duration::from_secs(10), "{:?}", started.elapsed());
    }

    #[test]
    fn a_cut_line_keeps_the_marked_text_and_its_column() {
        // The marked text 5000 characters into a line of 10000: the location keeps the text
        // around it, the arrow names the column in the file, the caret sits under the mark.
        let mut line = "a ".repeat(2500);
        line.push('X');
        line.push_str(&" b".repeat(2500));
        let d = at(&line, 5001, 1);
        let location = d.location.as_ref().expect("a location");
        assert!(location.text_column > 1 && location.line_text.chars().count() <= MAX_KEPT_LINE_CHARS);
        assert_eq!(location.marked_text(), "X");
        let text = d.to_string();
        assert!(text.contains(" --> s.txt:7:5001\n"), "{text}");
        let echoed = text.lines().nth(3).expect("excerpt");
        let caret = text.lines().nth(4).expect("caret");
        assert_eq!(caret.find('^'), echoed.find('X'), "{echoed}\n{caret}");
        assert!(echoed.starts_with("7 | ...") && echoed.ends_with("..."), "{echoed}");
    }

    #[test]
    fn span_past_the_end_marks_the_end() {
        let text = at("O=", 3, 1).to_string();
        assert!(text.contains("7 | O=\n  |   ^\n"), "{text}");
    }
}
