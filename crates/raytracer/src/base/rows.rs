//! Sets of whole rows of an image, and how an image's rows are cut into tiles: what a render, a
//! tile of one, or a chunk of either computes.

use std::fmt;
use std::ops::Range;

/// The most rows in one block of a tile.
pub const MAX_TILE_BLOCK_ROWS: u32 = 16;
/// The fewest rows in one block of a tile when the tile has that many rows.
pub const MIN_TILE_BLOCK_ROWS: u32 = 8;
/// The blocks a tile gets when the image is high enough and blocks are not too small.
pub const BLOCKS_PER_TILE: u32 = 6;

/// The rows in each block of an image `height` rows high cut into `tiles` tiles: as many as make
/// [`BLOCKS_PER_TILE`] blocks a tile, from [`MIN_TILE_BLOCK_ROWS`] (or a tile's share of the rows,
/// if less) to [`MAX_TILE_BLOCK_ROWS`].
///
/// Chosen by measurement (`cargo bench -p raytracer --bench tiles`, rays traced by each tile of
/// four scenes; docs/cluster.md has the table): smaller blocks share the work more evenly, but with
/// adaptive anti-aliasing each block traces the rows above and below it again (its first pass
/// compares every pixel with its neighbours), and the first pass is most of a render's rays.
/// About six blocks a tile is where the largest tile's work is least for 4 and 8 tiles; with more
/// tiles, blocks under 8 rows lose more to the rows traced again than they gain in balance.
pub fn tile_block_rows(height: u32, tiles: u32) -> u32 {
    let tiles = tiles.max(1);
    let least = MIN_TILE_BLOCK_ROWS.min(height / tiles).max(1);
    (height / (BLOCKS_PER_TILE * tiles)).clamp(least, MAX_TILE_BLOCK_ROWS)
}

/// Part `index` of `count` (`K/N` on the command line, `K` from 0).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct Split {
    /// Which part, from 0.
    pub index: u32,
    /// How many parts in all (at least 1).
    pub count: u32,
}

impl Split {
    /// The whole: part 0 of 1.
    pub const WHOLE: Split = Split { index: 0, count: 1 };

    /// Part `index` of `count`, if `index < count`.
    pub fn new(index: u32, count: u32) -> Option<Split> {
        (index < count).then_some(Split { index, count })
    }

    /// Parses `K/N`.
    pub fn parse(text: &str) -> Result<Split, String> {
        let full = text;
        let text = super::diagnostic::clip(full);
        let (k, n) =
            full.split_once('/').ok_or_else(|| format!("expected K/N (such as 3/8), not `{text}`"))?;
        let parse = |s: &str, what: &str| {
            s.trim()
                .parse::<u32>()
                .map_err(|_| format!("`{}` in `{text}` is not a valid {what}", super::diagnostic::clip(s)))
        };
        let (index, count) = (parse(k, "part number")?, parse(n, "part count")?);
        if count == 0 {
            return Err(format!("`{text}`: the number of parts must be at least 1"));
        }
        Split::new(index, count)
            .ok_or_else(|| format!("`{text}`: parts are numbered from 0 to {}", count - 1))
    }
}

impl fmt::Display for Split {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}/{}", self.index, self.count)
    }
}

/// The blocks of rows tile `tile` of an image `height` rows high owns, top first, in blocks of
/// [`tile_block_rows`] rows. A tile count above the height is refused.
pub fn tile_rows(height: u32, tile: Split) -> Result<Vec<Range<u32>>, String> {
    tile_rows_in_blocks(height, tile, tile_block_rows(height, tile.count))
}

/// [`tile_rows`] with blocks of `block_rows` rows (fewer when a tile would get no row).
pub fn tile_rows_in_blocks(height: u32, tile: Split, block_rows: u32) -> Result<Vec<Range<u32>>, String> {
    if tile.count > height {
        return Err(format!(
            "an image {height} rows high can be cut into at most {height} tiles, not {}",
            tile.count
        ));
    }
    let block = (height / tile.count).clamp(1, block_rows.max(1));
    let blocks = height.div_ceil(block);
    Ok((tile.index..blocks)
        .step_by(tile.count as usize)
        .map(|b| b * block..((b + 1) * block).min(height))
        .collect())
}

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
    fn splits_parse_and_refuse_nonsense() {
        assert_eq!(Split::parse("3/8"), Ok(Split { index: 3, count: 8 }));
        for bad in ["8/8", "1/0", "x/2", "3", "-1/4", "1/2/3"] {
            assert!(Split::parse(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn tiles_cover_every_row_once_in_interleaved_blocks() {
        for height in [1, 7, 8, 9, 100, 380, 760, 4321] {
            for count in [1, 2, 3, 4, 7, 16, 100] {
                let Ok(first) = tile_rows(height, Split { index: 0, count }) else {
                    assert!(count > height);
                    continue;
                };
                assert!(!first.is_empty());
                let mut seen = vec![0u32; height as usize];
                for index in 0..count {
                    let rows = tile_rows(height, Split { index, count }).expect("tiles");
                    assert!(!rows.is_empty(), "tile {index}/{count} of {height} rows is empty");
                    for r in rows {
                        assert!(r.len() as u32 <= MAX_TILE_BLOCK_ROWS);
                        for y in r {
                            seen[y as usize] += 1;
                        }
                    }
                }
                assert!(seen.iter().all(|&n| n == 1), "{height} rows, {count} tiles");
            }
        }
        assert!(tile_rows(10, Split { index: 0, count: 11 }).is_err());
    }

    #[test]
    fn rows_with_their_neighbours() {
        let rows = Rows::from_blocks(4, vec![0..2, 5..6, 7..9]);
        assert_eq!(rows.with_neighbours(9), [0, 1, 2, 4, 5, 6, 7, 8]);
        assert_eq!(rows.ys().collect::<Vec<_>>(), [0, 1, 5, 7, 8]);
        assert_eq!(rows.len(), 20);
        assert_eq!(Rows::full(3, 5).with_neighbours(5), [0, 1, 2, 3, 4]);
    }
}
