//! What a BSDF gives back: a direction it drew, with the weight a path's
//! throughput is multiplied by ([`BsdfSample`]), and for the denoiser's
//! guides its specular lobes and the albedo of the rest ([`GuideLobes`]).

use glam::Vec3A;

/// The largest GGX `α` at which a lobe counts as specular for the denoiser's
/// guides ([`Material::guide_lobes`]): Cycles' threshold for its denoising
/// features (`α ≤ 0.075`, glTF roughness up to about 0.27). Below it a
/// reflection is sharp enough that the denoiser should see what is reflected.
///
/// [`Material::guide_lobes`]: super::Material::guide_lobes
pub const GUIDE_ALPHA: f32 = 0.075;

/// A BSDF as the denoiser's guides see it from one direction
/// ([`Material::guide_lobes`]): its specular lobes (delta, or GGX with
/// `α ≤` [`GUIDE_ALPHA`]) as the one direction each sends light along, with
/// their values, and the albedo of everything else. The three values add up
/// to about [`Material::albedo`].
///
/// [`Material::guide_lobes`]: super::Material::guide_lobes
/// [`Material::albedo`]: super::Material::albedo
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GuideLobes {
    /// Albedo of the lobes that are not specular (diffuse, rough), per
    /// channel.
    pub rough: Vec3A,
    /// The specular reflection: its direction (local frame) and value.
    pub reflect: Option<(Vec3A, Vec3A)>,
    /// The specular transmission (refraction, or straight through a thin
    /// wall): its direction (local frame) and value.
    pub transmit: Option<(Vec3A, Vec3A)>,
}

impl GuideLobes {
    /// Nothing scattered.
    pub const NONE: GuideLobes = GuideLobes {
        rough: Vec3A::ZERO,
        reflect: None,
        transmit: None,
    };

    /// Only a rough part of albedo `rough`.
    pub fn rough(rough: Vec3A) -> GuideLobes {
        GuideLobes {
            rough: unit_range(rough),
            ..GuideLobes::NONE
        }
    }

    /// A lobe's direction and value if it carries anything.
    pub(super) fn lobe(wi: Vec3A, value: Vec3A) -> Option<(Vec3A, Vec3A)> {
        let value = unit_range(value);
        (wi.is_finite() && value.max_element() > 0.0).then_some((wi, value))
    }
}

/// `v` clamped to `[0, 1]`, zero if not finite.
#[inline]
pub(super) fn unit_range(v: Vec3A) -> Vec3A {
    finite_or_zero(v).clamp(Vec3A::ZERO, Vec3A::ONE)
}

/// One direction drawn by [`Material::sample`](super::Material::sample).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BsdfSample {
    /// The sampled incident direction, in the local frame (unit length).
    pub wi: Vec3A,
    /// `f(wo, wi) |cos θi| / pdf`: what the path throughput is multiplied by.
    pub weight: Vec3A,
    /// Solid-angle density of `wi`; for a delta lobe (`specular`), the discrete
    /// probability with which that lobe was chosen.
    pub pdf: f32,
    /// Whether `wi` came from a delta lobe (no MIS with light sampling possible).
    pub specular: bool,
}

/// Returns `v` if every component is finite, else zero.
#[inline]
pub(super) fn finite_or_zero(v: Vec3A) -> Vec3A {
    if v.is_finite() { v } else { Vec3A::ZERO }
}
