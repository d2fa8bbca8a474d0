//! Printing that never panics: `println!` and `eprintln!` panic when the stream is closed
//! (`rayterra render | head -1`, `2>&- `), which would stop a render before its image is written.
//! A closed or failing stream is not an error of the work: the messages are dropped and the work
//! goes on, and the exit status is the work's (0 when its output file is written), as tools
//! such as ripgrep do.

use std::io::Write;

/// Writes a line to standard output; a closed or failing stream is ignored.
pub fn stdout_line(args: std::fmt::Arguments<'_>) {
    let text = plain(&args.to_string()).into_owned();
    let mut out = std::io::stdout().lock();
    let _ = out.write_all(text.as_bytes()).and_then(|()| out.write_all(b"\n")).and_then(|()| out.flush());
}

/// Writes a line to standard error; a closed or failing stream is ignored.
pub fn stderr_line(args: std::fmt::Arguments<'_>) {
    stderr_text(format_args!("{args}\n"));
}

/// Writes text to standard error; a closed or failing stream is ignored.
pub fn stderr_text(args: std::fmt::Arguments<'_>) {
    let text = args.to_string();
    let _ = std::io::stderr().lock().write_all(plain(&text).as_bytes());
}

/// The start of the `png` crate's debug form of a chunk type, which its error messages show
/// (`ChunkType { type: IDAT, critical: true, private: false, reserved: false, safecopy: false }`).
const CHUNK_TYPE: &str = "ChunkType { type: ";

/// `text` with the debug forms that libraries put in their error messages made plain: a PNG
/// chunk type becomes its four-letter name (`IDAT`).
pub fn plain(text: &str) -> std::borrow::Cow<'_, str> {
    if !text.contains(CHUNK_TYPE) {
        return text.into();
    }
    let mut out = String::with_capacity(text.len());
    let mut rest = text;
    while let Some(start) = rest.find(CHUNK_TYPE) {
        out.push_str(&rest[..start]);
        let after = &rest[start + CHUNK_TYPE.len()..];
        match (after.find(','), after.find('}')) {
            (Some(comma), Some(end)) if comma < end => {
                out.push_str(&after[..comma]);
                rest = &after[end + 1..];
            }
            _ => {
                out.push_str(&rest[start..start + CHUNK_TYPE.len()]);
                rest = after;
            }
        }
    }
    out.push_str(rest);
    out.into()
}

/// `println!` that never panics (see the module).
macro_rules! outln {
    ($($arg:tt)*) => { $crate::say::stdout_line(format_args!($($arg)*)) };
}

/// `eprintln!` that never panics (see the module).
macro_rules! errln {
    ($($arg:tt)*) => { $crate::say::stderr_line(format_args!($($arg)*)) };
}

/// `eprint!` that never panics (see the module).
macro_rules! err {
    ($($arg:tt)*) => { $crate::say::stderr_text(format_args!($($arg)*)) };
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn png_chunk_types_are_named_plainly() {
        let message = "Format error decoding Png: Chunk ChunkType { type: IDAT, critical: true, private: false, \
                       reserved: false, safecopy: false } must appear at most once.";
        assert_eq!(plain(message), "Format error decoding Png: Chunk IDAT must appear at most once.");
        assert_eq!(plain("nothing to do"), "nothing to do");
        assert_eq!(plain("ChunkType { type: x"), "ChunkType { type: x");
    }
}
