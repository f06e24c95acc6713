//! What depends on `wo` alone, [`Local`]: the canonical frame (`wo` mirrored
//! to `+z`), the side of a volume `wo` is on, and the probabilities with
//! which [`PbrBsdf::sample`] chooses a lobe, from estimates of the lobes'
//! weights at `wo` (see [`pbr`](super)'s "Sampling"); and whether every lobe is
//! a delta.

use super::coat::CoatLocal;
use super::ggx::Ggx;
use super::params::{PbrBsdf, luminance};
use crate::materials::microfacet::is_smooth;
use crate::materials::sheen;
use glam::Vec3A;

/// Floor of the Fresnel estimates that choose the rough specular lobe: keeps its
/// probability positive wherever it can scatter (a black metal seen head-on).
const SPEC_FLOOR: f32 = 1e-3;

/// Floor, relative to its largest value `1 − s max(F0)`, of the `1 − s max(F)`
/// estimate that chooses the rough transmission and the diffuse lobes: near
/// grazing and under total internal reflection at `cos θo` it would vanish,
/// while the pairs' own half vectors still let light through.
const KD_FLOOR: f32 = 0.1;

/// Floor of the sheen's albedo estimate that chooses its lobe: a narrow
/// sheen seen head-on reflects little, but still at grazing `wi`.
const SHEEN_FLOOR: f32 = 0.02;

/// Which lobe [`PbrBsdf::sample`] draws from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Lobe {
    Specular,
    Diffuse,
    Transmission,
    Sheen,
    /// `KHR_materials_diffuse_transmission`'s Lambertian lobe on the far side.
    DiffuseTransmission,
    Coat,
}

/// What depends on `wo` only: the canonical frame and the lobe probabilities.
#[derive(Clone, Copy, Debug)]
pub struct Local {
    /// `wo` mirrored to `+z` if it was below.
    pub(super) wo: Vec3A,
    /// Whether directions are mirrored (`wo.z < 0` originally).
    pub(super) flip: bool,
    /// Whether `wo` is inside a refracting volume (index `ior`).
    pub(super) inside: bool,
    /// Whether the transmission refracts (a volume) rather than passing straight.
    pub(super) volume: bool,
    /// Whether the specular and transmission lobes are deltas.
    pub(super) smooth: bool,
    /// The base's microfacet distribution.
    pub(super) ggx: Ggx,
    /// The dielectric's `F0` per channel.
    pub(super) f0: Vec3A,
    /// Lobe selection probabilities (summing to 1).
    pub(super) p_spec: f32,
    pub(super) p_diff: f32,
    pub(super) p_trans: f32,
    pub(super) p_sheen: f32,
    pub(super) p_dtrans: f32,
    pub(super) p_coat: f32,
    /// Whether there is a sheen (`wo` may be inside a volume: see
    /// [`PbrBsdf::add_sheen`]).
    pub(super) sheen: bool,
    /// `max(C) E(μo)`: the sheen's share at `wo`, `1 − max(C) E(μo)` the
    /// base's largest (0 without a sheen).
    pub(super) sheen_o: f32,
    /// The clear coat, where there is one and `wo` is above it.
    pub(super) coat: Option<CoatLocal>,
}

impl Local {
    /// A direction in (or out of) the canonical frame: the mirror is its own
    /// inverse.
    #[inline]
    pub(super) fn map(&self, w: Vec3A) -> Vec3A {
        if self.flip {
            Vec3A::new(w.x, w.y, -w.z)
        } else {
            w
        }
    }

    pub(super) fn choose(&self, u: f32) -> Lobe {
        // The sheen's, the diffuse transmission's and the coat's shares are
        // taken from the top of `[0, 1)` (the coat's highest, the sheen's
        // lowest), so that the other lobes' choices are those of the
        // material without them.
        let base = self.p_spec + self.p_diff + self.p_trans;
        let below_dtrans = base + self.p_sheen;
        if self.p_coat > 0.0 && u >= below_dtrans + self.p_dtrans {
            return Lobe::Coat;
        }
        if self.p_dtrans > 0.0 && u >= below_dtrans {
            return Lobe::DiffuseTransmission;
        }
        if self.p_sheen > 0.0 && u >= base {
            return Lobe::Sheen;
        }
        if u < self.p_spec || (self.p_diff <= 0.0 && self.p_trans <= 0.0) {
            Lobe::Specular
        } else if self.p_trans <= 0.0 || (self.p_diff > 0.0 && u < self.p_spec + self.p_diff) {
            Lobe::Diffuse
        } else {
            Lobe::Transmission
        }
    }
}

impl PbrBsdf {
    /// Whether every lobe is a delta (the surface is smooth and the diffuse part
    /// has zero weight, e.g. a smooth metal or smooth full transmission): next
    /// event estimation cannot hit it.
    pub fn is_specular(&self) -> bool {
        is_smooth(self.alpha_t())
            && !self.has_diffuse()
            && !self.has_sheen()
            && (self.coat <= 0.0 || self.coat_smooth())
    }

    /// Whether the diffuse part can be non-zero anywhere: `(1 − m)(1 − tr)` and the
    /// base colour positive and `s max(F0) < 1` (`1 − s max(F)` is largest at
    /// normal incidence on the microfacet, where `F = F0`).
    #[inline]
    fn has_diffuse(&self) -> bool {
        (self.diffuse_scale() * luminance(self.base_color) > 0.0 || self.transmits_diffusely())
            && self.kd_max() > 0.0
    }

    /// The canonical frame and lobe probabilities for `wo`; `None` for a
    /// degenerate `wo` or a material that scatters nothing.
    pub fn local(&self, wo: Vec3A) -> Option<Local> {
        if !wo.is_finite() || wo.z == 0.0 {
            return None;
        }
        let flip = wo.z < 0.0;
        let volume = self.transmission > 0.0 && !self.thin_walled;
        let inside = volume && flip;
        let wo = if flip {
            Vec3A::new(wo.x, wo.y, -wo.z)
        } else {
            wo
        };
        let smooth = is_smooth(self.alpha_t());
        let (m, s, c) = (self.metallic, self.specular, self.base_color);
        let f0 = self.f0();
        let kd_max = self.kd_max_of(f0);
        let cos_o = wo.z.min(1.0);
        let air = self.air_cos(cos_o, inside);
        let fd = air.map_or(1.0, |a| self.fresnel_air(f0, a).max_element());
        let fm = self.fresnel_m(cos_o).max_element();
        let lum = luminance(c);
        let kd = 1.0 - s * fd;
        let (w_spec, w_trans) = if smooth {
            // Delta lobes: probabilities proportional to their exact values
            // (no transmission under total internal reflection).
            let tir = volume && air.is_none();
            let w_trans = if tir {
                0.0
            } else {
                self.transmission_scale() * lum * kd
            };
            (m * fm + (1.0 - m) * s * fd, w_trans)
        } else {
            let w_trans = if kd_max > 0.0 {
                self.transmission_scale() * lum * kd.max(KD_FLOOR * kd_max)
            } else {
                0.0
            };
            (
                m * fm.max(SPEC_FLOOR) + (1.0 - m) * s * fd.max(SPEC_FLOOR),
                w_trans,
            )
        };
        // As has_diffuse(), with what is at hand.
        let w_diff = if self.diffuse_scale() * lum > 0.0 && kd_max > 0.0 {
            self.diffuse_scale() * lum * kd.max(KD_FLOOR * kd_max)
        } else {
            0.0
        };
        // The diffuse part's transmitted share takes its weight from the
        // reflected one's (which is then the same number for dt = 0).
        let dt = self.diffuse_transmission;
        let (w_diff, w_dtrans) = if self.transmits_diffusely() && kd_max > 0.0 {
            let lum_t = luminance(self.diffuse_transmission_color);
            let w = self.diffuse_scale() * kd.max(KD_FLOOR * kd_max);
            (w_diff * (1.0 - dt), w * lum_t * dt)
        } else {
            (w_diff, 0.0)
        };
        // Negative inputs (out of range) count as absent lobes.
        let (mut w_spec, mut w_diff, mut w_trans, mut w_dtrans) = (
            w_spec.max(0.0),
            w_diff.max(0.0),
            w_trans.max(0.0),
            w_dtrans.max(0.0),
        );
        let sheen = self.has_sheen();
        let (mut w_sheen, mut sheen_o) = (0.0, 0.0);
        if sheen && !inside {
            let e = sheen::albedo(cos_o, self.sheen_roughness);
            sheen_o = self.sheen_color.max_element() * e;
            let keep = 1.0 - sheen_o;
            (w_spec, w_diff, w_trans, w_dtrans) = (
                w_spec * keep,
                w_diff * keep,
                w_trans * keep,
                w_dtrans * keep,
            );
            // Floored: the lobe reflects somewhere wherever its colour is
            // not black, and may be the only non-delta lobe.
            w_sheen = luminance(self.sheen_color).max(SPEC_FLOOR) * e.max(SHEEN_FLOOR);
        }
        let coat = self.coat_local(wo, flip, inside);
        let mut w_coat = 0.0;
        if let Some(c) = &coat {
            let base = 1.0 - c.weight;
            (w_spec, w_diff, w_trans, w_dtrans) = (
                w_spec * base,
                w_diff * base,
                w_trans * base,
                w_dtrans * base,
            );
            w_sheen *= base;
            w_coat = c.weight;
        }
        let total = w_spec + w_diff + w_trans + w_dtrans + w_sheen + w_coat;
        if !(total > 0.0 && total.is_finite()) {
            return None;
        }
        let inv = total.recip();
        Some(Local {
            wo,
            flip,
            inside,
            volume,
            smooth,
            ggx: self.ggx(),
            f0,
            p_spec: w_spec * inv,
            p_diff: w_diff * inv,
            p_trans: w_trans * inv,
            p_sheen: w_sheen * inv,
            p_dtrans: w_dtrans * inv,
            p_coat: w_coat * inv,
            sheen,
            sheen_o,
            coat,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::super::params::MIN_ALPHA;
    use super::super::test_util::*;
    use super::*;
    use crate::materials::frame::reflect_z;
    use crate::materials::material::Material;
    use crate::materials::test_util::*;

    #[test]
    fn is_specular_only_without_a_non_delta_part() {
        assert!(PbrBsdf::new(COLOR, 1.0, 0.0).is_specular());
        assert!(!PbrBsdf::new(COLOR, 0.0, 0.0).is_specular());
        assert!(!PbrBsdf::new(COLOR, 0.999, 0.0).is_specular());
        assert!(!PbrBsdf::new(COLOR, 1.0, 0.1).is_specular());
        assert!(volume(COLOR, 0.0, 0.0, 1.0).is_specular());
        assert!(thin(COLOR, 0.0, 0.0, 1.0).is_specular());
        assert!(!thin(COLOR, 0.0, 0.0, 0.9).is_specular());
        assert!(!volume(COLOR, 0.0, 0.1, 1.0).is_specular());
        // No diffuse colour: only the delta reflection is left.
        assert!(PbrBsdf::new(Vec3A::ZERO, 0.0, 0.0).is_specular());
        assert!(Material::Pbr(PbrBsdf::new(COLOR, 1.0, 0.0)).is_specular());
        // A smooth surface's eval and pdf see only the diffuse part: zero for a
        // smooth metal even at the mirror direction.
        let wo = dir(30.0, 0.5);
        let metal = Material::Pbr(PbrBsdf::new(COLOR, 1.0, 0.0));
        assert_eq!(metal.eval(wo, reflect_z(wo)), Vec3A::ZERO);
        assert_eq!(metal.pdf(wo, reflect_z(wo)), 0.0);
        assert_eq!(PbrBsdf::alpha_from_roughness(0.0), MIN_ALPHA);
        assert_eq!(PbrBsdf::alpha_from_roughness(0.5), 0.25);
    }
}
