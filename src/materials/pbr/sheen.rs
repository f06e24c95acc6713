//! The sheen over the base (`KHR_materials_sheen`, see [`pbr`](super)'s
//! "Sheen"): the albedo scaling of what lies under it, the sheen's own
//! value and density, and its part of the denoiser's guides. The microfibre
//! BRDF itself is [`crate::materials::sheen`].

use super::lobes::Local;
use super::params::PbrBsdf;
use crate::materials::bsdf::{GuideLobes, unit_range};
use crate::materials::sheen;
use glam::Vec3A;
use std::f32::consts::FRAC_1_PI;

impl PbrBsdf {
    /// The sheen over the base's `f |cos θi|` and density `(f, p)` at `wi`
    /// (canonical frame): `f` scaled by the albedo scaling, the sheen's value
    /// and density added.
    #[inline]
    pub(super) fn add_sheen(&self, l: &Local, wi: Vec3A, f: Vec3A, p: f32) -> (Vec3A, f32) {
        let rho = self.sheen_roughness;
        let keep_i = || 1.0 - self.sheen_color.max_element() * sheen::albedo(wi.z.abs(), rho);
        if l.inside {
            // Out through the outside's sheen, or back into the volume.
            return (if wi.z < 0.0 { f * keep_i() } else { f }, p);
        }
        if wi.z <= 0.0 {
            let keep = if l.volume {
                1.0 - l.sheen_o
            } else {
                (1.0 - l.sheen_o).min(keep_i())
            };
            return (f * keep, p);
        }
        let scaling = (1.0 - l.sheen_o).min(keep_i());
        let value = self.sheen_color * sheen::eval(l.wo, wi, rho);
        (f * scaling + value, p + l.p_sheen * FRAC_1_PI * wi.z)
    }

    /// `base`'s guides under a sheen: scaled by `1 − max(C) E(μo)`, the
    /// sheen's albedo added to the rough part.
    pub(super) fn sheen_guide_lobes(&self, base: GuideLobes, l: &Local) -> GuideLobes {
        if !l.sheen {
            return base;
        }
        let keep = 1.0 - l.sheen_o;
        let scaled = |lobe: Option<(Vec3A, Vec3A)>| lobe.map(|(wi, v)| (wi, v * keep));
        let e = sheen::albedo(l.wo.z, self.sheen_roughness);
        GuideLobes {
            rough: unit_range(base.rough * keep + self.sheen_color * e),
            reflect: scaled(base.reflect),
            transmit: scaled(base.transmit),
        }
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
    fn chi2_sheen_sampling_matches_pdf() {
        let sheen = Vec3A::new(0.9, 0.4, 0.2);
        chi2_cases(
            &[
                (
                    sheened(PbrBsdf::new(COLOR, 0.0, 0.6), sheen, 0.5),
                    dir(70.0, 0.3),
                    "sheen over dielectric",
                ),
                (
                    sheened(PbrBsdf::new(COLOR, 1.0, 0.3), Vec3A::ONE, 0.25),
                    dir(50.0, 0.3),
                    "sheen over rough metal",
                ),
                (
                    coated(
                        sheened(PbrBsdf::new(COLOR, 0.0, 0.4), sheen, 0.8),
                        1.0,
                        0.3,
                        0.0,
                    ),
                    dir(30.0, 1.0),
                    "coat over sheen",
                ),
                (
                    sheened(thin(COLOR, 0.0, 0.5, 0.7), sheen, 0.3),
                    -dir(80.0, 2.0),
                    "sheen over a thin wall, back side",
                ),
            ],
            700,
        );
    }

    /// A sheen over a base that reflects nothing reflects exactly its
    /// colour times the tabulated albedo `E(μo, ρ)` (estimated here by
    /// sampling the BSDF, not from the table), per channel.
    #[test]
    fn sheen_over_black_reflects_its_tabulated_albedo() {
        let black = PbrBsdf {
            specular: 0.0,
            ..PbrBsdf::new(Vec3A::ZERO, 0.0, 0.5)
        };
        let color = Vec3A::new(1.0, 0.5, 0.25);
        for rho in [0.2f32, 0.5, 1.0] {
            for theta in [0.0f32, 50.0, 80.0] {
                let p = sheened(black, color, rho);
                let wo = dir(theta, 0.4);
                let (a, se) = albedo(Material::Pbr(p), wo, 200_000, 900);
                let e = sheen::albedo(wo.z, rho) as f64;
                assert!(
                    (a - e).abs() < 4.0 * se + 3e-3,
                    "ρ {rho} θo {theta}: sampled {a} ± {se}, table {e}"
                );
                // The other channels are the colour's share, sample by sample.
                let s = Material::Pbr(p)
                    .sample(wo, 0.5, Vec2::new(0.3, 0.7))
                    .unwrap();
                assert!((s.weight.y - 0.5 * s.weight.x).abs() <= 1e-6 * s.weight.x);
            }
        }
    }

    /// White furnaces: a white sheen over a white smooth metal (which loses
    /// nothing) never reflects more than it receives, at any angle and
    /// sheen roughness, grazing ones included (where the specification's
    /// Charlie BRDF alone would exceed 1); and it loses little.
    #[test]
    fn furnace_white_sheen_over_white_metal() {
        for rho in [0.0f32, 0.1, 0.3, 0.6, 1.0] {
            for theta in [0.0f32, 45.0, 80.0, 88.0] {
                let p = sheened(PbrBsdf::new(Vec3A::ONE, 1.0, 0.0), Vec3A::ONE, rho);
                let wo = dir(theta, 0.7);
                let (a, se) = albedo(Material::Pbr(p), wo, 60_000, 1000);
                let what = format!("sheen ρ={rho} θo={theta}");
                assert!(a < 1.0 + 4.0 * se + 1e-4, "{what}: albedo {a} ± {se}");
                assert!(a > 0.5, "{what}: albedo {a}");
                // A coat on top keeps it at most 1.
                let c = coated(p, 1.0, 0.3, 0.0);
                let (a, se) = albedo(Material::Pbr(c), wo, 60_000, 1001);
                assert!(
                    a < 1.0 + 4.0 * se + 1e-4,
                    "{what}, coated: albedo {a} ± {se}"
                );
            }
        }
    }
}
