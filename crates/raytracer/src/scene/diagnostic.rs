//! Errors, warnings and notes about a scene file, shown with the offending text underlined.

use std::fmt;

use super::source::Span;

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

/// Where a diagnostic points: the file, the span and a copy of the line's text.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Location {
    /// File name as shown to the user.
    pub file: String,
    /// Line, column and length of the marked text.
    pub span: Span,
    /// The full text of the line (for the excerpt).
    pub line_text: String,
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
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(f, "{}: {}", self.severity, self.message)?;
        let gutter = match &self.location {
            Some(loc) => {
                let number = loc.span.line.to_string();
                let pad = " ".repeat(number.len());
                writeln!(f, "{pad}--> {}:{}:{}", loc.file, loc.span.line, loc.span.column)?;
                writeln!(f, "{pad} |")?;
                // Expand tabs so the caret lines up with the echoed text.
                let mut echoed = String::new();
                let (mut caret_start, mut caret_len) = (None, 0);
                for (i, ch) in loc.line_text.chars().enumerate() {
                    let col = i as u32 + 1;
                    let start = echoed.chars().count();
                    if ch == '\t' {
                        echoed.push_str(&" ".repeat(TAB_WIDTH - start % TAB_WIDTH));
                    } else if ch.is_control() {
                        echoed.push(' ');
                    } else {
                        echoed.push(ch);
                    }
                    let width = echoed.chars().count() - start;
                    if col == loc.span.column {
                        caret_start = Some(start);
                    }
                    if col >= loc.span.column && col < loc.span.column + loc.span.len.max(1) {
                        caret_len += width;
                    }
                }
                let caret_start = caret_start.unwrap_or(echoed.chars().count());
                writeln!(f, "{number} | {}", echoed.trim_end())?;
                writeln!(f, "{pad} | {}{}", " ".repeat(caret_start), "^".repeat(caret_len.max(1)))?;
                pad
            }
            None => String::new(),
        };
        for note in &self.notes {
            writeln!(f, "{gutter} = note: {note}")?;
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
            location: Some(Location {
                file: "s.txt".into(),
                span: Span { line: 7, column, len },
                line_text: line_text.into(),
            }),
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
    fn span_past_the_end_marks_the_end() {
        let text = at("O=", 3, 1).to_string();
        assert!(text.contains("7 | O=\n  |   ^\n"), "{text}");
    }
}
