//! Printing that never panics: `println!` and `eprintln!` panic when the stream is closed
//! (`rayterra render | head -1`, `2>&- `), which would stop a render before its image is written.
//! A closed or failing stream is not an error of the work: the messages are dropped and the work
//! goes on, and the exit status is the work's (0 when its output file is written), as tools
//! such as ripgrep do.

use std::io::Write;

/// Writes a line to standard output; a closed or failing stream is ignored.
pub fn stdout_line(args: std::fmt::Arguments<'_>) {
    let mut out = std::io::stdout().lock();
    let _ = out.write_fmt(args).and_then(|()| out.write_all(b"\n")).and_then(|()| out.flush());
}

/// Writes a line to standard error; a closed or failing stream is ignored.
pub fn stderr_line(args: std::fmt::Arguments<'_>) {
    stderr_text(format_args!("{args}\n"));
}

/// Writes text to standard error; a closed or failing stream is ignored.
pub fn stderr_text(args: std::fmt::Arguments<'_>) {
    let _ = std::io::stderr().lock().write_fmt(args);
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
