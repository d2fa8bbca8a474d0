//! The parallel piece cutter: a large file is cut into pieces at block boundaries, the pieces
//! are parsed in parallel, and their scenes joined in file order (when every piece parses cleanly;
//! otherwise the file is parsed line by line for its diagnostics).

use super::super::{MeshPrimitive, Scene};
use super::blocks::{Parser, State, is_block_keyword};
use super::lexer::tokenize;
use super::{Omitted, Parsed};
use crate::base::source::{SourceFile, count_line_ends};

/// Files of at least twice this many bytes are parsed in pieces of about this many bytes, in
/// parallel (see [`parse_in_pieces`]).
pub(super) const PIECE_BYTES: usize = 1 << 19;

/// A piece of a scene file to parse: whole lines (without the line end after the last) and the
/// number of the first.
#[derive(Debug)]
pub(super) struct Piece<'s> {
    pub(super) first_line: u32,
    pub(super) text: &'s str,
}

/// Cuts `text` into pieces of about [`PIECE_BYTES`], each but the first starting at a line that
/// opens a block. The cuts depend on the text only. The lines are counted on all threads.
pub(super) fn pieces(text: &str) -> Vec<Piece<'_>> {
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
            tokenize(crate::base::source::without_return(&text[line_start..line_end]), &mut tokens);
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
pub(super) fn parse_in_pieces(source: &SourceFile) -> Option<Parsed> {
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
        let before = scene.primitives.len();
        scene
            .meshes
            .extend(piece.scene.meshes.into_iter().map(|m| MeshPrimitive { index: m.index + before, ..m }));
        scene.primitives.extend(piece.scene.primitives);
    }
    if scene.primitives.is_empty() && scene.meshes.is_empty() && scene.lights.is_empty() {
        return None;
    }
    Some(Parsed { scene, diagnostics: Vec::new(), omitted: Omitted::default() })
}
