//! Sampling (see [`pbr`](super)'s "Sampling"): the lobe `u_lobe` chooses, a
//! direction drawn from it, and its weight: a delta lobe's value over its
//! probability, or `eval / pdf` with the mixture density of the non-delta
//! lobes (one-sample MIS).

use super::lobes::{Lobe, Local};
use super::params::PbrBsdf;
use super::transmission::refract;
use crate::materials::bsdf::BsdfSample;
use crate::materials::disk::concentric_disk;
use crate::materials::frame::reflect_z;
use crate::materials::microfacet::ggx_sample_visible_normal;
use crate::materials::sheen;
use glam::{Vec2, Vec3A};

impl PbrBsdf {
    /// Draws `wi` for `wo`: `u_lobe` chooses the lobe, `u ∈ [0, 1)²` the
    /// direction. `None` for a degenerate `wo`, a black material, or a draw that
    /// leaves the lobe's side of the surface (or totally internally reflects).
    pub fn sample(&self, wo: Vec3A, u_lobe: f32, u: Vec2) -> Option<BsdfSample> {
        self.sample_at(self.local(wo), u_lobe, u)
    }

    /// [`PbrBsdf::sample`] with `local` = [`PbrBsdf::local`]`(wo)` already
    /// worked out.
    #[inline]
    pub fn sample_at(&self, local: Option<Local>, u_lobe: f32, u: Vec2) -> Option<BsdfSample> {
        let l = local?;
        let wo_l = l.wo;
        let (m, s, c) = (self.metallic, self.specular, self.base_color);
        let lobe = l.choose(u_lobe);
        // The base's share under the coat and the sheen (a delta's `wi` has
        // `wo`'s cosine, so the sheen's scaling is `1 − max(C) E(μo)`).
        let under = l.coat.map_or(1.0, |coat| 1.0 - coat.weight);
        let under = if l.sheen {
            under * (1.0 - l.sheen_o)
        } else {
            under
        };
        let wi = match lobe {
            Lobe::Coat => {
                let coat = l.coat?;
                let wi_c = if self.coat_smooth() {
                    reflect_z(coat.wo)
                } else {
                    let h = ggx_sample_visible_normal(self.coat_alpha, coat.wo, u);
                    let cos_oh = coat.wo.dot(h);
                    if cos_oh.is_nan() || cos_oh <= 0.0 {
                        return None;
                    }
                    (2.0 * cos_oh * h - coat.wo).normalize()
                };
                let wi = coat.frame.to_world(wi_c);
                if wi_c.z <= 0.0 || wi.z <= 0.0 {
                    return None;
                }
                if self.coat_smooth() {
                    return Self::delta(l.map(wi), Vec3A::splat(coat.weight), l.p_coat);
                }
                wi
            }
            Lobe::Specular if l.smooth => {
                let cos_o = wo_l.z.min(1.0);
                let value = m * self.fresnel_m(cos_o)
                    + (1.0 - m) * s * self.fresnel_d(l.f0, cos_o, l.inside);
                return Self::delta(l.map(reflect_z(wo_l)), value * under, l.p_spec);
            }
            Lobe::Transmission if l.smooth => {
                let cos_o = wo_l.z.min(1.0);
                let wi = if l.volume {
                    refract(wo_l, Vec3A::Z, self.eta(&l))?
                } else {
                    -wo_l
                };
                let kd = 1.0 - s * self.fresnel_d(l.f0, cos_o, l.inside).max_element();
                // Out of a volume, through the outside's sheen.
                let under = if l.sheen && l.inside {
                    let e = sheen::albedo(wi.z.abs(), self.sheen_roughness);
                    under * (1.0 - self.sheen_color.max_element() * e)
                } else {
                    under
                };
                let value = c * (self.transmission_scale() * kd * under);
                return Self::delta(l.map(wi), value, l.p_trans);
            }
            Lobe::Specular => {
                let h = l.ggx.sample_visible_normal(wo_l, u);
                let cos_oh = wo_l.dot(h);
                if cos_oh.is_nan() || cos_oh <= 0.0 {
                    return None;
                }
                (2.0 * cos_oh * h - wo_l).normalize()
            }
            Lobe::Diffuse | Lobe::Sheen => {
                let d = concentric_disk(u);
                Vec3A::new(d.x, d.y, (1.0 - d.length_squared()).max(0.0).sqrt())
            }
            Lobe::DiffuseTransmission => {
                let d = concentric_disk(u);
                Vec3A::new(d.x, d.y, -(1.0 - d.length_squared()).max(0.0).sqrt())
            }
            Lobe::Transmission => {
                let h = l.ggx.sample_visible_normal(wo_l, u);
                let cos_oh = wo_l.dot(h);
                if cos_oh.is_nan() || cos_oh <= 0.0 {
                    return None;
                }
                if l.volume {
                    refract(wo_l, h, self.eta(&l))?
                } else {
                    let wr = (2.0 * cos_oh * h - wo_l).normalize();
                    Vec3A::new(wr.x, wr.y, -wr.z)
                }
            }
        };
        // The lobe's side: a draw across the horizon is lost (the pdf of the
        // other side does not include it).
        let side_ok = match lobe {
            Lobe::Transmission | Lobe::DiffuseTransmission => wi.z < 0.0,
            _ => wi.z > 0.0,
        };
        if !side_ok || !wi.is_finite() {
            return None;
        }
        // The same computation as pdf() and eval(): the returned pdf is
        // bit-identical to pdf(wo, wi) (MIS) and weight = eval / pdf.
        let pdf = self.pdf_local(&l, wi);
        if !(pdf > 0.0 && pdf.is_finite()) {
            return None;
        }
        let weight = self.eval_local(&l, wi) / pdf;
        if !weight.is_finite() {
            return None;
        }
        Some(BsdfSample {
            wi: l.map(wi),
            weight,
            pdf,
            specular: false,
        })
    }

    /// A delta lobe's sample: `weight = value / probability`.
    #[inline]
    fn delta(wi: Vec3A, value: Vec3A, prob: f32) -> Option<BsdfSample> {
        let weight = value / prob;
        if !(prob > 0.0 && weight.is_finite() && wi.is_finite()) {
            return None;
        }
        Some(BsdfSample {
            wi,
            weight,
            pdf: prob,
            specular: true,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::super::test_util::*;
    use super::*;
    use crate::materials::material::Material;
    use crate::materials::microfacet::ALPHA_SMOOTH;
    use crate::materials::test_util::*;

    // ------------------------------------------------- χ² goodness of fit

    fn chi2_opaque(metallic: f32, key: u64) {
        let mut cases = Vec::new();
        for roughness in [0.2f32, 0.5, 1.0] {
            for theta in [10.0f32, 45.0, 80.0] {
                let p = PbrBsdf::new(COLOR, metallic, roughness);
                let what = format!("m={metallic} r={roughness} θo={theta}");
                cases.push((p, dir(theta, 0.3), what));
            }
        }
        let cases: Vec<_> = cases.iter().map(|(p, w, s)| (*p, *w, s.as_str())).collect();
        chi2_cases(&cases, key);
    }

    #[test]
    fn chi2_dielectric_sampling_matches_pdf() {
        chi2_opaque(0.0, 300);
    }

    #[test]
    fn chi2_metal_sampling_matches_pdf() {
        chi2_opaque(1.0, 400);
    }

    #[test]
    fn chi2_detects_wrong_pbr_pdfs() {
        // Sampling against the pdf of a slightly different material is rejected:
        // other lobe probabilities, and another roughness of the refraction lobe.
        let cases = [
            (
                PbrBsdf::new(COLOR, 0.5, 0.5),
                PbrBsdf::new(COLOR, 0.6, 0.5),
                dir(45.0, 0.3),
            ),
            (
                volume(Vec3A::ONE, 0.0, 0.5, 1.0),
                volume(Vec3A::ONE, 0.0, 0.55, 1.0),
                dir(45.0, 0.3),
            ),
            // The far side's share, claimed a little smaller.
            (
                translucent(PbrBsdf::new(COLOR, 0.0, 0.5), 0.5, Vec3A::ONE),
                translucent(PbrBsdf::new(COLOR, 0.0, 0.5), 0.45, Vec3A::ONE),
                dir(45.0, 0.3),
            ),
        ];
        for (i, (m, claimed, wo)) in cases.into_iter().enumerate() {
            let p = chi2_p_value_of(Material::Pbr(m), Material::Pbr(claimed), wo, 600 + i as u64);
            eprintln!("chi2 wrong pdf {i}: p = {p:e}");
            assert!(p < 1e-6, "wrong pdf not detected: p = {p}");
        }
    }

    // ---------------------------------------------- weights and densities

    #[test]
    fn sample_weight_is_eval_over_pdf_and_pdf_matches() {
        let mut r = rng(3);
        let mut worst = 0.0f32;
        for p in every_test_material() {
            let m = Material::Pbr(p);
            let (mut hits, mut deltas) = (0, 0);
            for _ in 0..20_000 {
                let wo = sphere(&mut r);
                if wo.z.abs() < 1e-3 {
                    continue;
                }
                let Some(s) = m.sample(wo, r.next_f32(), u2(&mut r)) else {
                    continue;
                };
                assert!((s.wi.length() - 1.0).abs() < 1e-5, "{p:?}: {s:?}");
                assert!(s.weight.is_finite() && s.weight.min_element() >= 0.0);
                if s.specular {
                    // A delta lobe: its selection probability, and a direction
                    // eval/pdf cannot see (a mixed material's diffuse part aside).
                    deltas += 1;
                    let smooth =
                        p.alpha < ALPHA_SMOOTH || (p.coat > 0.0 && p.coat_alpha < ALPHA_SMOOTH);
                    assert!(smooth && s.pdf > 0.0 && s.pdf <= 1.0);
                    continue;
                }
                hits += 1;
                let pdf = m.pdf(wo, s.wi);
                assert_eq!(s.pdf, pdf, "{p:?} wo {wo:?}: pdf {} vs {pdf}", s.pdf);
                let f = m.eval(wo, s.wi);
                let e = rel_err(s.weight, f / pdf);
                assert!(e < 1e-5, "{p:?} wo {wo:?}: {:?} vs {:?}", s.weight, f / pdf);
                worst = worst.max(e);
            }
            assert!(
                hits + deltas > 10_000,
                "{p:?}: only {hits} + {deltas} samples"
            );
            assert!(hits > 1000, "{p:?}: only {hits} non-delta samples");
            // Wherever eval is positive, so is pdf (else sampling would miss it).
            for _ in 0..20_000 {
                let (wo, wi) = (sphere(&mut r), sphere(&mut r));
                let (f, pdf) = (m.eval(wo, wi), m.pdf(wo, wi));
                assert!(f.is_finite() && f.min_element() >= 0.0 && pdf.is_finite());
                assert!(f.max_element() == 0.0 || pdf > 0.0, "{p:?}: {wo} {wi}");
            }
        }
        eprintln!("pbr weight vs eval/pdf: worst relative error {worst:e}");
    }

    #[test]
    fn degenerate_inputs_are_safe() {
        let mut all = every_test_material();
        all.push(filmed(PbrBsdf::new(COLOR, 0.5, 0.5), 1.0, f32::NAN, 300.0));
        all.push(filmed(
            PbrBsdf::new(COLOR, 0.5, 0.0),
            1.0,
            1.3,
            f32::INFINITY,
        ));
        all.push(filmed(PbrBsdf::new(COLOR, 0.5, 0.3), f32::NAN, 1.3, 300.0));
        all.push(PbrBsdf {
            coat_normal: Vec3A::NAN,
            ..coated(PbrBsdf::new(COLOR, 0.0, 0.5), 1.0, 0.3, 0.0)
        });
        all.push(PbrBsdf {
            anisotropy_direction: Vec2::NAN,
            ..aniso(PbrBsdf::new(COLOR, 1.0, 0.5), 0.5, 0.0)
        });
        all.push(PbrBsdf {
            anisotropy_direction: Vec2::ZERO,
            ..aniso(volume(COLOR, 0.0, 0.5, 1.0), 1.0, 0.0)
        });
        all.push(aniso(PbrBsdf::new(COLOR, 1.0, 0.5), f32::NAN, 0.0));
        all.push(aniso(PbrBsdf::new(COLOR, 1.0, 0.5), f32::INFINITY, 0.0));
        all.extend([
            PbrBsdf {
                alpha: f32::NAN,
                ..PbrBsdf::new(COLOR, 0.5, 0.5)
            },
            PbrBsdf::new(Vec3A::ZERO, 0.0, 0.5),
            PbrBsdf::new(Vec3A::ZERO, 0.0, 0.0),
            PbrBsdf {
                specular: 0.0,
                ..PbrBsdf::new(Vec3A::ZERO, 0.0, 0.5)
            },
            PbrBsdf {
                ior: 1.0,
                ..volume(Vec3A::ONE, 0.0, 0.5, 1.0)
            },
            PbrBsdf {
                ior: 1.0,
                ..volume(Vec3A::ONE, 0.0, 0.0, 1.0)
            },
            PbrBsdf {
                specular_color: Vec3A::splat(100.0),
                ..PbrBsdf::new(COLOR, 0.0, 0.5)
            },
        ]);
        for p in all {
            let m = Material::Pbr(p);
            for wo in [
                Vec3A::Z,
                -Vec3A::Z,
                dir(89.99, 0.1),
                -dir(89.99, 0.1),
                Vec3A::new(1.0, 0.0, 1e-30).normalize(),
                Vec3A::new(1.0, 0.0, -1e-7).normalize(),
                Vec3A::X,
                Vec3A::ZERO,
                Vec3A::NAN,
            ] {
                for u in [
                    Vec2::ZERO,
                    Vec2::new(0.999_999_9, 0.999_999_9),
                    Vec2::new(0.5, 0.0),
                ] {
                    for wi in [
                        Vec3A::Z,
                        -Vec3A::Z,
                        -wo,
                        flip(wo),
                        Vec3A::new(-wo.x, -wo.y, wo.z),
                        dir(89.99, 3.0),
                    ] {
                        let (f, pdf) = (m.eval(wo, wi), m.pdf(wo, wi));
                        assert!(f.is_finite() && pdf.is_finite(), "{p:?} {wo} {wi}");
                        assert!(f.min_element() >= 0.0 && pdf >= 0.0);
                    }
                    for ul in [0.0, 0.3, 0.7, 0.999_999_9] {
                        if let Some(s) = m.sample(wo, ul, u) {
                            assert!(
                                s.weight.is_finite() && s.pdf.is_finite() && s.pdf > 0.0,
                                "{p:?} {s:?}"
                            );
                            assert!(s.weight.min_element() >= 0.0);
                            assert!(s.wi.is_finite() && (s.wi.length() - 1.0).abs() < 1e-4);
                        }
                    }
                }
            }
        }
    }

    // ------------------------------------------------------------ furnaces

    #[test]
    fn furnace_white_metal() {
        // Smooth: the delta weight is exactly 1 at every angle, from both sides.
        let smooth = Material::Pbr(PbrBsdf::new(Vec3A::ONE, 1.0, 0.0));
        assert!(smooth.is_specular());
        for theta in [0.0, 30.0, 60.0, 85.0, 89.9] {
            for wo in [dir(theta, 0.7), -dir(theta, 0.7)] {
                for ul in [0.0, 0.5, 0.999_999] {
                    let s = smooth.sample(wo, ul, Vec2::new(0.3, 0.6)).unwrap();
                    assert!(s.specular && s.pdf == 1.0);
                    assert_eq!(s.weight, Vec3A::ONE, "θo = {theta}");
                    assert!((s.wi - reflect_z(wo)).length() < 1e-6);
                }
            }
        }
        // Rough: single scattering loses energy but never gains any.
        let n = 100_000;
        for roughness in [0.1f32, 0.3, 0.5, 0.7, 1.0] {
            let m = Material::Pbr(PbrBsdf::new(Vec3A::ONE, 1.0, roughness));
            for theta in [0.0, 45.0, 80.0] {
                let (a, se) = albedo(m, dir(theta, 0.7), n, 700);
                eprintln!("furnace white metal r={roughness} θo={theta}: {a:.5} ± {se:.5}");
                assert!(a <= 1.0 + 3.0 * se + 1e-6, "r = {roughness}: {a} ± {se}");
                if roughness == 0.1 {
                    assert!(a > 0.99, "r = 0.1, θo = {theta}: {a}");
                }
            }
        }
    }
}
