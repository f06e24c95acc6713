//! What renders give back: the image with its AOVs and costs ([`Rendered`]),
//! and what one call of the tiles' loops cost ([`Tally`]).

use crate::aov::AovImage;
use crate::film::Film;

/// A rendered image and what it cost.
#[derive(Clone, Debug)]
pub struct Rendered {
    /// Pixel values (box-filtered averages).
    pub film: Film,
    /// Rays cast (camera and shadow rays).
    pub rays: u64,
    /// Samples that came out NaN or infinite and were dropped (counted as black).
    pub dropped: u64,
    /// The AOVs asked for ([`render_with_aovs`](super::render_with_aovs)),
    /// averaged over the same samples; `None` when none were.
    pub aovs: Option<AovImage>,
}

/// What a call of [`accumulate`](super::accumulate) cost and found.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Tally {
    /// Rays cast (closest-hit and shadow rays).
    pub rays: u64,
    /// Samples that came out NaN or infinite: counted here and left out of the
    /// sums (so they count as black).
    pub dropped: u64,
}

impl std::ops::Add for Tally {
    type Output = Tally;
    fn add(self, o: Tally) -> Tally {
        Tally {
            rays: self.rays + o.rays,
            dropped: self.dropped + o.dropped,
        }
    }
}

impl std::iter::Sum for Tally {
    fn sum<I: Iterator<Item = Tally>>(iter: I) -> Tally {
        iter.fold(Tally::default(), |a, b| a + b)
    }
}
