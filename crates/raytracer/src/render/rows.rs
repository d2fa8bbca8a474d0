//! Sets of whole rows of an image: what a render, a tile of one, or a chunk of either computes.

use std::ops::Range;

use crate::parts::{Split, tile_rows};

/// A set of whole rows of an image `width` pixels wide, as blocks of consecutive rows in
/// increasing order: what a render, or a tile of one ([`Rows::tile`]), computes.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Rows {
    width: u32,
    blocks: Vec<Range<u32>>,
}

impl Rows {
    /// Every row of a `width x height` image.
    pub fn full(width: u32, height: u32) -> Rows {
        Rows::from_blocks(width, std::iter::once(0..height).collect())
    }

    /// The rows of tile `tile` of a `width x height` image ([`crate::parts::tile_rows`]).
    pub fn tile(width: u32, height: u32, tile: Split) -> Result<Rows, String> {
        Ok(Rows { width, blocks: tile_rows(height, tile)? })
    }

    /// Blocks of `width`-pixel rows, increasing, not overlapping (empty blocks are dropped).
    pub fn from_blocks(width: u32, blocks: Vec<Range<u32>>) -> Rows {
        let blocks: Vec<Range<u32>> = blocks.into_iter().filter(|b| !b.is_empty()).collect();
        debug_assert!(blocks.windows(2).all(|w| w[0].end <= w[1].start), "{blocks:?}");
        Rows { width, blocks }
    }

    /// The width of a row in pixels.
    pub fn width(&self) -> u32 {
        self.width
    }

    /// The blocks of rows, top first.
    pub fn blocks(&self) -> &[Range<u32>] {
        &self.blocks
    }

    /// Every row, top first.
    pub fn ys(&self) -> impl Iterator<Item = u32> + '_ {
        self.blocks.iter().flat_map(|b| b.clone())
    }

    /// The number of pixels.
    pub fn len(&self) -> usize {
        self.blocks.iter().map(|b| b.len()).sum::<usize>() * self.width as usize
    }

    /// Whether there is no pixel.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Every row with the rows just above and below it that an image `height` rows high has,
    /// top first, each once.
    pub(crate) fn with_neighbours(&self, height: u32) -> Vec<u32> {
        let mut out: Vec<u32> = Vec::new();
        for b in &self.blocks {
            for y in b.start.saturating_sub(1)..(b.end + 1).min(height) {
                if out.last().is_none_or(|&last| last < y) {
                    out.push(y);
                }
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rows_with_their_neighbours() {
        let rows = Rows::from_blocks(4, vec![0..2, 5..6, 7..9]);
        assert_eq!(rows.with_neighbours(9), [0, 1, 2, 4, 5, 6, 7, 8]);
        assert_eq!(rows.ys().collect::<Vec<_>>(), [0, 1, 5, 7, 8]);
        assert_eq!(rows.len(), 20);
        assert_eq!(Rows::full(3, 5).with_neighbours(5), [0, 1, 2, 3, 4]);
    }
}
