//! The path tracer's sample values: which points ([`SamplerKind`]), the
//! stream a path draws from ([`PathSampler`]) and the Sobol' one ([`SobolSampler`]).

use glam::Vec2;

use crate::sampling::sampler::Rng;
use crate::sampling::sobol;

/// Which sample points the path tracer uses.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum SamplerKind {
    /// Owen-scrambled Sobol' points ([`crate::sampling::sobol`]), a 2D pair per decision.
    Sobol,
    /// Independent uniform random numbers (PCG32 keyed by seed, pixel, sample).
    Independent,
}

impl SamplerKind {
    /// Every kind, for the command line.
    pub const ALL: [SamplerKind; 2] = [SamplerKind::Sobol, SamplerKind::Independent];

    /// The default, usable in constants.
    pub const DEFAULT: SamplerKind = SamplerKind::Sobol;

    /// The name used on the command line.
    pub fn name(self) -> &'static str {
        match self {
            SamplerKind::Sobol => "sobol",
            SamplerKind::Independent => "independent",
        }
    }
}

/// A stream of sample values for one path (one pixel sample). The path tracer
/// asks for a 2D pair for the pixel position, then per bounce a pair for the
/// point on the light, a pair for the BSDF direction, a "minor" pair for the
/// choices of light and lobe (only when there is a choice), and one number for
/// Russian roulette (only where it may end the path); a path that meets a
/// dispersive surface (`KHR_materials_dispersion`) takes one more number there,
/// once, for its wavelength.
pub trait PathSampler {
    /// The next two values in `[0, 1)` for a decision that gains little from
    /// stratification (which light, which lobe).
    #[inline]
    fn next_2d_minor(&mut self) -> Vec2 {
        self.next_2d()
    }
    /// The next value in `[0, 1)`.
    fn next_1d(&mut self) -> f32;
    /// The next two values in `[0, 1)`.
    #[inline]
    fn next_2d(&mut self) -> Vec2 {
        let x = self.next_1d();
        Vec2::new(x, self.next_1d())
    }
}

impl PathSampler for Rng {
    #[inline]
    fn next_1d(&mut self) -> f32 {
        self.next_f32()
    }
}

/// Pairs taken from Sobol' before [`SobolSampler`] goes on with independent
/// numbers: the pixel position and the first [`SOBOL_BOUNCES`] bounces' light
/// and BSDF pairs, where stratification pays.
pub const SOBOL_PAIRS: u32 = 1 + 2 * SOBOL_BOUNCES;
/// Bounces whose 2D decisions use Sobol' points. The first eight pairs cost the
/// same however many are used ([`sobol::first_pairs`]); on the lab box two
/// bounces give 3–4 % less relMSE than one at the same samples, three no more
/// than two (docs/path-tracing.md).
pub const SOBOL_BOUNCES: u32 = 2;

/// Owen-scrambled Sobol' pairs ([`crate::sampling::sobol`]) for the first
/// [`SOBOL_PAIRS`] 2D decisions, then independent numbers from the sample's own
/// PCG stream; single numbers (Russian roulette) and minor pairs (light and lobe
/// choices) are always independent.
#[derive(Clone, Debug)]
pub struct SobolSampler {
    /// The first pairs, made together when the sampler is ([`sobol::first_pairs`]).
    xs: [f32; sobol::FIRST_PAIRS],
    ys: [f32; sobol::FIRST_PAIRS],
    rng: Rng,
    next_pair: u32,
}

const _: () = assert!(SOBOL_PAIRS as usize <= sobol::FIRST_PAIRS);

/// The Sobol' pair a thin lens takes its point from: the first after the
/// path's, made with them at no cost ([`sobol::first_pairs`]), so that the
/// lens is stratified as the pixel is and the path's own pairs stay as they
/// are with a pinhole.
pub const LENS_PAIR: usize = SOBOL_PAIRS as usize;
const _: () = assert!(LENS_PAIR < sobol::FIRST_PAIRS);

impl SobolSampler {
    /// The sampler of sample `index` of pixel `pixel` in a render seeded `seed`.
    #[inline]
    pub fn new(pixel: u64, index: u32, seed: u64) -> Self {
        let (xs, ys) = sobol::first_pairs(index, sobol::pixel_seed(pixel, seed));
        Self {
            xs,
            ys,
            rng: Rng::for_sample(seed, pixel, index),
            next_pair: 0,
        }
    }

    /// The point of the camera's thin lens (the Sobol' pair `LENS_PAIR`);
    /// the path's pairs are left as they are.
    #[inline]
    pub fn lens_2d(&self) -> Vec2 {
        Vec2::new(self.xs[LENS_PAIR], self.ys[LENS_PAIR])
    }
}

impl PathSampler for SobolSampler {
    #[inline]
    fn next_1d(&mut self) -> f32 {
        self.rng.next_f32()
    }
    #[inline]
    fn next_2d_minor(&mut self) -> Vec2 {
        Vec2::new(self.rng.next_f32(), self.rng.next_f32())
    }
    #[inline]
    fn next_2d(&mut self) -> Vec2 {
        let k = self.next_pair as usize;
        if k < SOBOL_PAIRS as usize {
            self.next_pair += 1;
            Vec2::new(self.xs[k], self.ys[k])
        } else {
            Vec2::new(self.rng.next_f32(), self.rng.next_f32())
        }
    }
}
