//! The parts of an image: its row tiles ([`TILE_ROWS`] rows each), and which
//! of them a render takes ([`Split`]) when an image is rendered in parts
//! and merged.

/// Rows per tile: small enough to balance two cores on small images, large enough
/// that scheduling costs nothing; even, so that tiles hold whole pixel quads.
pub const TILE_ROWS: usize = 4;

/// Which rows of the image a render takes: the `index`-th of `count` parts,
/// made of the image's row tiles ([`TILE_ROWS`] rows each, from the top)
/// `index`, `index + count`, `index + 2·count`, ...: interleaved, so that every
/// part has rows from all over the image and costs about the same. The whole
/// image is part 0 of 1.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Split {
    /// Which part (from 0).
    pub index: u32,
    /// Parts in all (at least 1).
    pub count: u32,
}

impl Split {
    /// The whole image.
    pub const WHOLE: Split = Split { index: 0, count: 1 };

    /// Row tiles of an image `height` pixels high.
    pub fn row_tiles(height: u32) -> u32 {
        height.div_ceil(TILE_ROWS as u32)
    }

    /// Part `index` of `count` of an image `height` rows high, if every part
    /// gets at least one row tile.
    pub fn new(index: u32, count: u32, height: u32) -> Result<Split, String> {
        if count == 0 || index >= count {
            return Err(format!(
                "tile {index}/{count}: the tile number must be below the number of tiles"
            ));
        }
        let tiles = Self::row_tiles(height);
        if count > tiles {
            return Err(format!(
                "tile {index}/{count}: an image {height} pixels high has at most {tiles} tiles (one per {TILE_ROWS} rows)"
            ));
        }
        Ok(Split { index, count })
    }

    /// Whether row tile `tile` is in this part.
    pub fn has_tile(&self, tile: u32) -> bool {
        tile % self.count == self.index
    }

    /// Whether this is the whole image.
    pub fn is_whole(&self) -> bool {
        self.count == 1
    }
}

impl std::fmt::Display for Split {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}/{}", self.index, self.count)
    }
}
