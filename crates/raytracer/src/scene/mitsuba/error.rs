//! Errors of the Mitsuba reader: each names the file, line and column it is about.

use crate::base::diagnostic::escape_for_terminal;
use crate::scene::{Diagnostic, Location, Severity};

/// `file:line:column` of a location, as error messages start.
fn place(at: &Location) -> String {
    format!("{}:{}:{}", escape_for_terminal(&at.file), at.span.line, at.span.column)
}

/// A Mitsuba scene file that cannot be read. Its `Display` is one line,
/// `file:line:column: message`; [`MitsubaError::diagnostic`] gives the compiler-style message
/// with the line's text underlined, as the course parser prints.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum MitsubaError {
    /// The first file could not be read (missing, a folder, a device, too large).
    #[error("{}: {message}", escape_for_terminal(.file))]
    Read {
        /// The path as given.
        file: String,
        /// What went wrong.
        message: String,
    },
    /// An included or referenced file (`<include>`, a `.spd` spectrum) could not be read.
    #[error("{}: cannot read `{}`: {message}", place(.at), escape_for_terminal(.file))]
    ReadAt {
        /// The element that names the file.
        at: Location,
        /// The file's path.
        file: String,
        /// What went wrong.
        message: String,
    },
    /// The text is not well-formed XML.
    #[error("{}: malformed XML: {message}", place(.at))]
    Xml {
        /// Where the XML parser stopped.
        at: Location,
        /// The XML parser's message.
        message: String,
    },
    /// An element Mitsuba does not know.
    #[error("{}: unknown element <{}>", place(.at), escape_for_terminal(.tag))]
    UnknownTag {
        /// The element.
        at: Location,
        /// Its name.
        tag: String,
    },
    /// An attribute the element does not take.
    #[error("{}: unexpected attribute `{}` in <{element}>", place(.at), escape_for_terminal(.attribute))]
    UnexpectedAttribute {
        /// The attribute.
        at: Location,
        /// Its name.
        attribute: String,
        /// The element's name.
        element: String,
    },
    /// A required attribute is missing.
    #[error("{}: <{element}> needs the attribute `{attribute}`", place(.at))]
    MissingAttribute {
        /// The element.
        at: Location,
        /// The attribute's name.
        attribute: &'static str,
        /// The element's name.
        element: String,
    },
    /// An element where it may not be (a property outside a plugin, `<path>` below the root...).
    #[error("{}: {message}", place(.at))]
    Misplaced {
        /// The element.
        at: Location,
        /// Why it may not be there.
        message: String,
    },
    /// A value that does not parse as the number (or boolean) it must be.
    #[error("{}: `{}` is not {expected}", place(.at), escape_for_terminal(.value))]
    Number {
        /// The attribute's value.
        at: Location,
        /// The text found.
        value: String,
        /// What was expected ("a finite number", "an integer"...).
        expected: &'static str,
    },
    /// A value with the wrong number of components, or otherwise malformed.
    #[error("{}: {message}", place(.at))]
    Value {
        /// The attribute or element.
        at: Location,
        /// What is wrong.
        message: String,
    },
    /// `$name` in an attribute with no `<default>` or `-D` for `name`.
    #[error("{}: undefined parameter `${}` (give it with -D {}=... or a <default>)", place(.at), escape_for_terminal(.name), escape_for_terminal(.name))]
    UndefinedParameter {
        /// The attribute.
        at: Location,
        /// The parameter's name.
        name: String,
    },
    /// A `version` attribute that is not `major.minor.patch`.
    #[error("{}: `{}` is not a version (major.minor.patch, e.g. 3.0.0)", place(.at), escape_for_terminal(.value))]
    Version {
        /// The attribute.
        at: Location,
        /// The text found.
        value: String,
    },
    /// Two plugins with the same `id`.
    #[error("{}: duplicate id `{}` (first declared at {previous})", place(.at), escape_for_terminal(.id))]
    DuplicateId {
        /// The second declaration.
        at: Location,
        /// The id.
        id: String,
        /// `file:line:column` of the first.
        previous: String,
    },
    /// Two properties (or nested plugins) of one plugin with the same name.
    #[error("{}: duplicate property `{}` (first given at {previous})", place(.at), escape_for_terminal(.name))]
    DuplicateProperty {
        /// The second one.
        at: Location,
        /// The name.
        name: String,
        /// `file:line:column` of the first.
        previous: String,
    },
    /// A `<ref>` (or `<alias>`) to an id that no plugin has.
    #[error("{}: reference to unknown id `{}`", place(.at), escape_for_terminal(.id))]
    UnknownId {
        /// The reference.
        at: Location,
        /// The id.
        id: String,
    },
    /// Plugins that refer to each other in a loop.
    #[error("{}: circular reference: {}", place(.at), escape_for_terminal(.chain))]
    CircularReference {
        /// The reference that closes the loop.
        at: Location,
        /// The ids around the loop, `a -> b -> a`.
        chain: String,
    },
    /// `<include>` of a file that does not exist.
    #[error("{}: included file `{}` not found", place(.at), escape_for_terminal(.file))]
    IncludeNotFound {
        /// The `<include>`.
        at: Location,
        /// The `filename` as written.
        file: String,
    },
    /// A file that includes itself, directly or through others.
    #[error("{}: recursive include: {}", place(.at), escape_for_terminal(.chain))]
    RecursiveInclude {
        /// The `<include>` that closes the loop.
        at: Location,
        /// The files around the loop, `a.xml -> b.xml -> a.xml`.
        chain: String,
    },
    /// A `<path>` folder that does not exist.
    #[error("{}: folder `{}` not found", place(.at), escape_for_terminal(.folder))]
    PathNotFound {
        /// The `<path>`.
        at: Location,
        /// The folder as written.
        folder: String,
    },
    /// A transform whose matrix cannot be inverted (a zero scale, a degenerate `lookat`...).
    #[error("{}: {message}", place(.at))]
    SingularTransform {
        /// The element that made it singular.
        at: Location,
        /// What is singular.
        message: String,
    },
    /// A limit that keeps memory bounded (file size, elements, include depth, nesting).
    #[error("{}: {message}", place(.at))]
    Limit {
        /// Where the limit was reached.
        at: Location,
        /// Which limit.
        message: String,
    },
}

impl MitsubaError {
    /// The place the error is about, if it has one in a file's text.
    pub fn location(&self) -> Option<&Location> {
        match self {
            MitsubaError::Read { .. } => None,
            MitsubaError::ReadAt { at, .. }
            | MitsubaError::Xml { at, .. }
            | MitsubaError::UnknownTag { at, .. }
            | MitsubaError::UnexpectedAttribute { at, .. }
            | MitsubaError::MissingAttribute { at, .. }
            | MitsubaError::Misplaced { at, .. }
            | MitsubaError::Number { at, .. }
            | MitsubaError::Value { at, .. }
            | MitsubaError::UndefinedParameter { at, .. }
            | MitsubaError::Version { at, .. }
            | MitsubaError::DuplicateId { at, .. }
            | MitsubaError::DuplicateProperty { at, .. }
            | MitsubaError::UnknownId { at, .. }
            | MitsubaError::CircularReference { at, .. }
            | MitsubaError::IncludeNotFound { at, .. }
            | MitsubaError::RecursiveInclude { at, .. }
            | MitsubaError::PathNotFound { at, .. }
            | MitsubaError::SingularTransform { at, .. }
            | MitsubaError::Limit { at, .. } => Some(at),
        }
    }

    /// The error as a compiler-style diagnostic (the message, `--> file:line:column`, the line
    /// with the place underlined).
    pub fn diagnostic(&self) -> Diagnostic {
        let full = self.to_string();
        match self.location() {
            Some(at) => {
                // The message without its `file:line:column: ` prefix, which the excerpt shows.
                let prefix = format!("{}: ", place(at));
                let message = full.strip_prefix(&prefix).unwrap_or(&full).to_owned();
                Diagnostic {
                    severity: Severity::Error,
                    message,
                    location: Some(at.clone()),
                    notes: Vec::new(),
                }
            }
            None => Diagnostic::general(Severity::Error, full),
        }
    }
}
