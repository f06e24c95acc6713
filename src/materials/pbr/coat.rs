//! The clear coat (`KHR_materials_clearcoat`, see [`pbr`](super)'s "Clear
//! coat"): its Fresnel term, its normal in the shading frame, its frame and
//! share at one `wo`, and its GGX reflection's value and density.

use super::fresnel::schlick_grey;
use super::params::PbrBsdf;
use crate::materials::frame::Frame;
use crate::materials::microfacet::{ggx_d, ggx_lambda, is_smooth};
use glam::Vec3A;

/// The clear coat's `F0`: an index of 1.5, `((1.5 − 1)/(1.5 + 1))²`.
pub const COAT_F0: f32 = 0.04;

/// The clear coat's Fresnel term `F_c` at `cos = |wo·n_c|`.
#[inline]
pub fn coat_fresnel(cos: f32) -> f32 {
    schlick_grey(COAT_F0, cos)
}

/// What the clear coat needs at one `wo` (see [`pbr`](super)'s "Clear coat").
#[derive(Clone, Copy, Debug)]
pub(super) struct CoatLocal {
    /// The coat's frame (its normal as `+z`) in the canonical frame.
    pub(super) frame: Frame,
    /// `wo` in the coat's frame.
    pub(super) wo: Vec3A,
    /// `w F_c`: the coat's share, `1 − w F_c` the base's.
    pub(super) weight: f32,
}

/// Smith's height-correlated masking–shadowing `G2 = 1 / (1 + Λ(wo) + Λ(wi))`.
#[inline]
fn g2(alpha: f32, wo: Vec3A, wi: Vec3A) -> f32 {
    1.0 / (1.0 + ggx_lambda(alpha, wo) + ggx_lambda(alpha, wi))
}

/// Smith's masking `G1(wo) = 1 / (1 + Λ(wo))`.
#[inline]
fn g1(alpha: f32, wo: Vec3A) -> f32 {
    1.0 / (1.0 + ggx_lambda(alpha, wo))
}

impl PbrBsdf {
    /// Sets the coat's normal from `n_c`, in the coordinates of the shading
    /// frame `frame` (`n_c` on the same side as its normal); a normal at or
    /// below the shading horizon (or not finite) becomes the shading normal.
    #[inline]
    pub fn orient_coat(&mut self, frame: &Frame, n_c: Vec3A) {
        if self.coat > 0.0 {
            let n = frame.to_local(n_c).normalize_or_zero();
            self.coat_normal = if n.z > 0.0 && n.is_finite() {
                n
            } else {
                Vec3A::Z
            };
        }
    }

    /// Whether the coat is a delta lobe.
    #[inline]
    pub(super) fn coat_smooth(&self) -> bool {
        is_smooth(self.coat_alpha)
    }

    /// The coat at `wo` (canonical, mirrored if `flip`): none without a coat,
    /// seen from inside a volume, or with `wo` below the coat's horizon.
    #[inline]
    pub(super) fn coat_local(&self, wo: Vec3A, flip: bool, inside: bool) -> Option<CoatLocal> {
        // (`coat` may be NaN: no coat then either.)
        if self.coat.is_nan() || self.coat <= 0.0 || inside {
            return None;
        }
        // Mirrored with the rest, the back's coat normal is −n_c seen from
        // the mirrored side: (−x, −y, z).
        let n = self.coat_normal;
        let n = if flip { Vec3A::new(-n.x, -n.y, n.z) } else { n };
        let frame = Frame::from_normal(n);
        let wo_c = frame.to_local(wo);
        (wo_c.z > 0.0 && wo_c.is_finite()).then(|| CoatLocal {
            frame,
            wo: wo_c,
            weight: self.coat.min(1.0) * schlick_grey(COAT_F0, wo_c.z.min(1.0)),
        })
    }

    /// The rough coat's `f |cos θi|` (about its normal, times `w F_c`) and
    /// its density for `wi` (canonical frame); zero for a smooth coat, or
    /// `wi` below the shading or the coat's horizon.
    #[inline]
    pub(super) fn coat_eval_pdf(&self, c: &CoatLocal, wi: Vec3A) -> (f32, f32) {
        if wi.z <= 0.0 || self.coat_smooth() {
            return (0.0, 0.0);
        }
        let wi_c = c.frame.to_local(wi);
        if wi_c.z <= 0.0 {
            return (0.0, 0.0);
        }
        let a = self.coat_alpha;
        let h = (c.wo + wi_c).normalize();
        let d = ggx_d(a, h);
        let f = c.weight * ((d * g2(a, c.wo, wi_c)) / (4.0 * c.wo.z));
        let p = (g1(a, c.wo) * d) / (4.0 * c.wo.z);
        (f, p)
    }
}

#[cfg(test)]
mod tests {
    use super::super::test_util::*;
    use super::*;
    use crate::materials::material::Material;
    use crate::materials::test_util::*;
    use glam::Vec2;

    #[test]
    fn chi2_coat_sampling_matches_pdf() {
        chi2_cases(
            &[
                (
                    coated(PbrBsdf::new(COLOR, 0.0, 0.6), 1.0, 0.3, 0.0),
                    dir(40.0, 0.3),
                    "coat over dielectric",
                ),
                (
                    coated(PbrBsdf::new(COLOR, 1.0, 0.5), 0.8, 0.2, 25.0),
                    dir(70.0, 0.3),
                    "tilted coat over metal",
                ),
                (
                    coated(PbrBsdf::new(COLOR, 0.0, 0.4), 1.0, 0.5, 0.0),
                    -dir(30.0, 1.3),
                    "coat, back side",
                ),
                (
                    coated(thin(COLOR, 0.0, 0.5, 0.7), 0.6, 0.25, 10.0),
                    dir(60.0, 2.0),
                    "coat over a thin wall",
                ),
            ],
            600,
        );
    }

    /// Over a base that reflects nothing (black, no specular), a smooth coat
    /// is a mirror about its normal whose weight is exactly the coat weight
    /// times Schlick's Fresnel at `|wo·n_c|` with `F0` = 0.04 (written out
    /// here from the specification), from either side.
    #[test]
    fn smooth_coat_over_black_is_the_coats_fresnel() {
        let black = PbrBsdf {
            specular: 0.0,
            ..PbrBsdf::new(Vec3A::ZERO, 0.0, 0.0)
        };
        for (weight, tilt) in [(1.0f32, 0.0f32), (0.6, 0.0), (1.0, 25.0)] {
            let p = coated(black, weight, 0.0, tilt);
            let m = Material::Pbr(p);
            assert!(p.is_specular());
            for theta in [0.0f32, 30.0, 60.0, 80.0] {
                let wo = dir(theta, 1.1 + 0.3 * theta.to_radians());
                let n = p.coat_normal;
                let cos = wo.dot(n);
                let expected = weight * (0.04 + 0.96 * (1.0 - cos).powi(5));
                for ul in [0.0, 0.5, 0.999_999] {
                    let s = m.sample(wo, ul, Vec2::new(0.3, 0.6));
                    let Some(s) = s else {
                        // Only where the mirror about a tilted normal dips
                        // below the shading horizon.
                        assert!(tilt > 0.0 && (2.0 * cos * n - wo).z <= 0.0);
                        continue;
                    };
                    assert!(s.specular && (s.pdf - 1.0).abs() < 1e-6, "{s:?}");
                    let value = s.weight.x * s.pdf;
                    assert!(
                        (value - expected).abs() < 1e-6 && s.weight.x == s.weight.z,
                        "θo = {theta}, tilt {tilt}: {value} against {expected}"
                    );
                    assert!((s.wi - (2.0 * cos * n - wo)).length() < 1e-5);
                    // From the back, mirrored: the same Fresnel.
                    if tilt == 0.0 {
                        let back = m.sample(flip(wo), ul, Vec2::new(0.3, 0.6)).unwrap();
                        assert!((back.weight.x * back.pdf - expected).abs() < 1e-6);
                        assert!((back.wi - flip(s.wi)).length() < 1e-6);
                    }
                }
            }
        }
    }

    /// White furnaces: a clear coat over a white metal (which loses nothing
    /// when smooth) never reflects more than it receives, at any angle, coat
    /// roughness and tilt; smooth over smooth it loses nothing either.
    #[test]
    fn furnace_coat_over_white_metal() {
        let n = 60_000;
        for base_roughness in [0.0f32, 0.4] {
            for (coat_roughness, tilt) in [(0.0f32, 0.0f32), (0.1, 0.0), (0.5, 0.0), (0.3, 20.0)] {
                let p = coated(
                    PbrBsdf::new(Vec3A::ONE, 1.0, base_roughness),
                    1.0,
                    coat_roughness,
                    tilt,
                );
                for theta in [0.0f32, 45.0, 80.0] {
                    let (a, se) = albedo(Material::Pbr(p), dir(theta, 0.7), n, 800);
                    let what = format!(
                        "base r={base_roughness} coat r={coat_roughness} tilt {tilt} θo={theta}"
                    );
                    assert!(a < 1.0 + 4.0 * se + 1e-4, "{what}: albedo {a} ± {se}");
                    if base_roughness == 0.0 && coat_roughness == 0.0 && tilt == 0.0 {
                        assert!((a - 1.0).abs() < 1e-5, "{what}: {a}");
                    } else {
                        // Single scattering loses some, not most.
                        assert!(a > 0.6, "{what}: albedo {a}");
                    }
                }
            }
        }
    }
}
