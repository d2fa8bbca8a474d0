//! The course scene language's front end (spec sections 2 and 3): its text in, the scene
//! description ([`super::Scene`]) out.
//!
//! The file is read line by line. A line is cut at the first `#` or `//` (a comment), split into
//! whitespace-separated tokens, and then is either a block header (`background`, `camera`,
//! `light TYPE`, `primitive TYPE`), a key line (`key= value ...`) inside a block, or `end`. Every
//! problem becomes a [`Diagnostic`] with its line and column; parsing goes on after an error so one
//! run reports them all.

//!
//! - `pieces`: the parallel piece cutter (large files);
//! - `lexer`: lines into tokens;
//! - `blocks`: the block state machine;
//! - `keys`: the typed key reader;
//! - `build`: the camera, lights, materials and primitives built from a block's keys.

mod blocks;
mod build;
mod keys;
mod lexer;
mod pieces;

use std::fmt;

use super::{Background, CameraSettings, Scene, SceneRender};
use crate::base::diagnostic::Diagnostic;
use crate::base::source::SourceFile;
use blocks::Parser;
use pieces::parse_in_pieces;

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

pub(super) fn parser_has_errors(diagnostics: &[Diagnostic], omitted: Omitted) -> bool {
    omitted.errors > 0 || diagnostics.iter().any(Diagnostic::is_error)
}

impl Scene {
    /// A scene with default background and camera and nothing in it.
    pub(super) fn empty() -> Scene {
        Scene {
            background: Background::default(),
            camera: CameraSettings::default(),
            lights: Vec::new(),
            primitives: Vec::new(),
            meshes: Vec::new(),
            emitters: Vec::new(),
            render: SceneRender::default(),
        }
    }
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
mod tests;
