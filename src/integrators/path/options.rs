//! The `path` integrator's options ([`PathOptions`]) and the Russian
//! roulette's constants, which the scalar, eight-lane and volumetric path
//! tracers share.

use super::direct::DirectSamples;
use super::samples::SamplerKind;

/// Bounces after which Russian roulette may end a path.
pub const RR_DEPTH: u32 = 3;
/// Russian roulette keeps a path with probability `min(RR_SCALE · max(β), 0.95)`
/// (β the path throughput): only paths whose throughput has fallen below
/// `1/RR_SCALE` face it at all. Mitsuba's rule is `RR_SCALE = 1`; on the lab box 5
/// reaches a given relMSE in about a third less time (docs/path-tracing.md), and
/// the 0.95 cap still ends paths between perfect mirrors.
pub const RR_SCALE: f32 = 5.0;

/// Whether the camera sees emitters: Mitsuba's `hide_emitters`, as its
/// `path` and `direct` integrators (3.7.1) define it. Hidden, the camera
/// ray passes through every emitting surface it meets first (as through
/// glass without refraction) and an environment it escapes to is black; a
/// path's value then counts only once the path has met a surface that
/// Mitsuba counts as the path's own.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum HideEmitters {
    /// Emitters are seen (raylab's own integrators, Mitsuba's default).
    #[default]
    No,
    /// Mitsuba's `path`: a path counts once it scatters off a surface other
    /// than a `null` one (raylab's dielectric of index 1,
    /// [`crate::materials::Material::is_null`]); seen only through `null`
    /// surfaces, light and sky are black.
    Path,
    /// Mitsuba's `direct`: a path counts once the camera ray (past the
    /// emitters) hits any surface; what a `null` surface lets through
    /// stays seen.
    Direct,
}

/// Options of the `path` integrator.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct PathOptions {
    /// Longest path in segments, as in Mitsuba: 1 sees only emitters, 2 adds
    /// direct light, ...; `u32::MAX` leaves it to Russian roulette.
    pub max_depth: u32,
    /// Sample points.
    pub sampler: SamplerKind,
    /// How each pixel weighs the image around it (its samples' image points
    /// are drawn from it; the box by default).
    pub filter: crate::sampling::filter::PixelFilter,
    /// Whether samples are drawn from the filter or splatted through it.
    pub reconstruction: crate::sampling::filter::Reconstruction,
    /// Whether the camera sees emitters (Mitsuba's `hide_emitters`).
    pub hide_emitters: HideEmitters,
    /// The light and BSDF samples a path of depth 2 takes at its one
    /// vertex (Mitsuba's `direct`); other depths take one of each.
    pub direct: DirectSamples,
}

impl PathOptions {
    /// Whether paths are Mitsuba's `direct` with other counts than one light
    /// and one BSDF sample ([`PathOptions::direct`] at depth 2), which the
    /// eight-lane path tracer does not render.
    #[inline]
    pub fn counts_direct(&self) -> bool {
        self.max_depth == 2 && self.direct != DirectSamples::ONE_EACH
    }
}

impl Default for PathOptions {
    fn default() -> Self {
        Self {
            max_depth: u32::MAX,
            sampler: SamplerKind::DEFAULT,
            filter: crate::sampling::filter::PixelFilter::Box,
            reconstruction: crate::sampling::filter::Reconstruction::Sample,
            hide_emitters: HideEmitters::No,
            direct: DirectSamples::ONE_EACH,
        }
    }
}
