//! The base's microfacet distribution at one hit, [`Ggx`]: GGX of one width,
//! or of two, along a direction of the tangent plane and across it
//! (`KHR_materials_anisotropy`, see [`pbr`](super)'s "Anisotropy"), and how a
//! [`PbrBsdf`] gets it and its direction in the shading frame.

use super::params::PbrBsdf;
use crate::materials::frame::Frame;
use crate::materials::microfacet::{
    ggx_d, ggx_lambda, ggx_sample_visible_normal, ggx_sample_visible_normal_xy,
};
use glam::{Vec2, Vec3A};
use std::f32::consts::PI;

/// The base's GGX distribution at one hit (the metal's and the dielectric's
/// specular reflection and the transmission; not the coat's).
#[derive(Clone, Copy, Debug)]
pub(super) enum Ggx {
    /// Width `α` in every direction: the isotropic functions (`ggx_d`,
    /// `ggx_lambda`, ...) of `materials/microfacet.rs`, so that a material
    /// without `KHR_materials_anisotropy` is evaluated and sampled exactly as
    /// before it existed.
    Isotropic(f32),
    /// Width `at` along the unit direction `dir = (cos φ, sin φ)` of the
    /// local tangent plane and `ab` across it: `D(m) = 1 / (π at ab ((m_t /
    /// at)² + (m_b / ab)² + m_z²)²)` and `Λ(w) = (√(1 + (at² w_t² + ab²
    /// w_b²) / w_z²) − 1) / 2`, with `m_t = m·t`, `m_b = m·b`, `t = (cos φ,
    /// sin φ, 0)` and `b = n × t` (Heitz 2014, "Understanding the
    /// Masking-Shadowing Function", §5.4), as `KHR_materials_anisotropy`'s
    /// `D_GGX_anisotropic` and `V_GGX_anisotropic` write them.
    Anisotropic { at: f32, ab: f32, dir: Vec2 },
}

impl Ggx {
    /// `w` with its tangent-plane part turned into `(t, b)` coordinates.
    #[inline]
    fn to_tb(dir: Vec2, w: Vec3A) -> Vec3A {
        Vec3A::new(dir.x * w.x + dir.y * w.y, dir.x * w.y - dir.y * w.x, w.z)
    }

    /// The inverse of [`Ggx::to_tb`].
    #[inline]
    fn from_tb(dir: Vec2, w: Vec3A) -> Vec3A {
        Vec3A::new(dir.x * w.x - dir.y * w.y, dir.y * w.x + dir.x * w.y, w.z)
    }

    /// The microfacet density `D(m)` (zero below the horizon).
    #[inline]
    pub(super) fn d(&self, m: Vec3A) -> f32 {
        match *self {
            Ggx::Isotropic(a) => ggx_d(a, m),
            Ggx::Anisotropic { at, ab, dir } => {
                if m.z <= 0.0 {
                    return 0.0;
                }
                let m = Self::to_tb(dir, m);
                let (x, y) = (m.x / at, m.y / ab);
                let s = x * x + y * y + m.z * m.z;
                1.0 / (PI * at * ab * s * s)
            }
        }
    }

    /// Smith's `Λ(w)`; infinite at the horizon.
    #[inline]
    pub(super) fn lambda(&self, w: Vec3A) -> f32 {
        match *self {
            Ggx::Isotropic(a) => ggx_lambda(a, w),
            Ggx::Anisotropic { at, ab, dir } => {
                let z2 = w.z * w.z;
                if z2 == 0.0 {
                    return f32::INFINITY;
                }
                let w = Self::to_tb(dir, w);
                let (x, y) = (at * w.x, ab * w.y);
                let a2_tan2 = (x * x + y * y) / z2;
                a2_tan2 / (2.0 * ((1.0 + a2_tan2).sqrt() + 1.0))
            }
        }
    }

    /// Smith's height-correlated `G2 = 1 / (1 + Λ(wo) + Λ(wi))`.
    #[inline]
    pub(super) fn g2(&self, wo: Vec3A, wi: Vec3A) -> f32 {
        1.0 / (1.0 + self.lambda(wo) + self.lambda(wi))
    }

    /// Smith's masking `G1(wo) = 1 / (1 + Λ(wo))`.
    #[inline]
    pub(super) fn g1(&self, wo: Vec3A) -> f32 {
        1.0 / (1.0 + self.lambda(wo))
    }

    /// A normal visible from `wo` (`wo.z > 0`), of density `G1(wo) max(0,
    /// wo·m) D(m) / cos θo` (Heitz 2018: the view stretched by `(at, ab)` in
    /// the `(t, b)` frame).
    #[inline]
    pub(super) fn sample_visible_normal(&self, wo: Vec3A, u: Vec2) -> Vec3A {
        match *self {
            Ggx::Isotropic(a) => ggx_sample_visible_normal(a, wo, u),
            Ggx::Anisotropic { at, ab, dir } => {
                let m = ggx_sample_visible_normal_xy(at, ab, Self::to_tb(dir, wo), u);
                Self::from_tb(dir, m)
            }
        }
    }
}

impl PbrBsdf {
    /// Turns [`PbrBsdf::anisotropy_direction`] from the mesh's tangent space
    /// into the shading frame `frame`, given the unit tangent `t` and
    /// bitangent `b` there (world space): `dx t + dy b` projected onto the
    /// shading plane. Without anisotropy nothing changes; where there is no
    /// tangent frame (`t` or `b` zero) or the direction is degenerate (along
    /// the shading normal), the material is isotropic at that hit: the
    /// extension gives no direction to stretch along.
    #[inline]
    pub fn orient_anisotropy(&mut self, frame: &Frame, t: Vec3A, b: Vec3A) {
        if self.anisotropy.is_nan() || self.anisotropy <= 0.0 {
            return;
        }
        let d = self.anisotropy_direction;
        let local = frame.to_local(d.x * t + d.y * b);
        let dir = Vec2::new(local.x, local.y).normalize_or_zero();
        if dir != Vec2::ZERO && dir.is_finite() {
            self.anisotropy_direction = dir;
        } else {
            self.anisotropy = 0.0;
        }
    }

    /// The GGX width along the direction of increased roughness:
    /// `mix(α, 1, strength²)` (`KHR_materials_anisotropy`), `α` without
    /// anisotropy; the larger of the two widths.
    #[inline]
    pub(super) fn alpha_t(&self) -> f32 {
        if self.anisotropy > 0.0 {
            let k = self.anisotropy.min(1.0);
            self.alpha + (1.0 - self.alpha) * (k * k)
        } else {
            self.alpha
        }
    }

    /// The base's microfacet distribution: anisotropic only where the
    /// strength is positive.
    #[inline]
    pub(super) fn ggx(&self) -> Ggx {
        if self.anisotropy > 0.0 {
            Ggx::Anisotropic {
                at: self.alpha_t(),
                ab: self.alpha,
                dir: self.anisotropy_direction,
            }
        } else {
            Ggx::Isotropic(self.alpha)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::test_util::*;
    use super::*;
    use crate::materials::material::Material;
    use crate::materials::test_util::*;

    // ------------------------------------------------------ anisotropy

    #[test]
    fn chi2_anisotropic_sampling_matches_pdf() {
        let mut cases = Vec::new();
        // (metallic, roughness, strength, rotation, θo, φo): widths from
        // (α_t, α_b) = (0.52, 0.04) to (1, 0.25), directions along, across
        // and oblique to wo's azimuth.
        for (m, r, k, rot, theta, phi) in [
            (1.0f32, 0.2f32, 0.7f32, 0.0f32, 45.0f32, 0.0f32),
            (1.0, 0.5, 1.0, 0.8, 70.0, 2.0),
            (1.0, 0.3, 0.5, 1.6, 15.0, 0.3),
            (0.0, 0.4, 0.9, -0.5, 60.0, 1.0),
            (0.0, 0.2, 0.6, 2.5, 30.0, 4.0),
            (0.5, 0.35, 0.8, 0.4, 80.0, 0.4),
        ] {
            let p = aniso(PbrBsdf::new(COLOR, m, r), k, rot);
            let what = format!("aniso m={m} r={r} k={k} rot={rot} θo={theta}");
            cases.push((p, dir(theta, phi), what));
        }
        for (p, wo, what) in [
            (
                volume(Vec3A::ONE, 0.0, 0.4, 1.0),
                dir(40.0, 0.7),
                "volume outside",
            ),
            (
                volume(COLOR, 0.0, 0.3, 0.8),
                -dir(30.0, 2.2),
                "volume inside",
            ),
            (thin(COLOR, 0.0, 0.3, 1.0), dir(50.0, 1.1), "thin-walled"),
            (
                thin(COLOR, 0.3, 0.5, 0.6),
                -dir(70.0, 3.0),
                "thin back side",
            ),
        ] {
            cases.push((aniso(p, 0.8, 0.9), wo, format!("aniso {what}")));
        }
        let cases: Vec<_> = cases.iter().map(|(p, w, s)| (*p, *w, s.as_str())).collect();
        chi2_cases(&cases, 700);
    }

    #[test]
    fn chi2_detects_a_wrong_anisotropic_pdf() {
        // The sampler of one direction against the pdf of another (and of
        // the isotropic material) is rejected.
        let p = aniso(PbrBsdf::new(COLOR, 1.0, 0.3), 0.8, 0.0);
        let wo = dir(45.0, 0.7);
        for (i, claimed) in [
            aniso(p, 0.8, 0.4),
            PbrBsdf {
                anisotropy: 0.0,
                ..p
            },
        ]
        .into_iter()
        .enumerate()
        {
            let pv = chi2_p_value_of(Material::Pbr(p), Material::Pbr(claimed), wo, 720 + i as u64);
            eprintln!("chi2 wrong anisotropic pdf {i}: p = {pv:e}");
            assert!(pv < 1e-6, "wrong pdf not detected: p = {pv}");
        }
    }

    /// The anisotropic distribution of every test below.
    fn ggx_of(roughness: f32, strength: f32, angle: f32) -> Ggx {
        let p = aniso(PbrBsdf::new(COLOR, 1.0, roughness), strength, angle);
        let g = p.ggx();
        assert!(matches!(g, Ggx::Anisotropic { .. }));
        g
    }

    /// `∫ f(m) dω_m` over the upper hemisphere by the midpoint rule in
    /// `(θ, φ)`, in f64.
    fn hemisphere_integral(f: impl Fn(Vec3A) -> f64) -> f64 {
        let (nt, np) = (3000, 1000);
        let (dt, dp) = (
            std::f64::consts::FRAC_PI_2 / nt as f64,
            std::f64::consts::TAU / np as f64,
        );
        let phis: Vec<(f64, f64)> = (0..np).map(|j| ((j as f64 + 0.5) * dp).sin_cos()).collect();
        let mut sum = 0.0;
        for i in 0..nt {
            let t = (i as f64 + 0.5) * dt;
            let (st, ct) = t.sin_cos();
            let mut row = 0.0;
            for &(sp, cp) in &phis {
                row += f(Vec3A::new((st * cp) as f32, (st * sp) as f32, ct as f32));
            }
            sum += row * st;
        }
        sum * dt * dp
    }

    #[test]
    fn anisotropic_d_is_normalized_and_lambda_matches_it() {
        // ∫ D(m) (n·m) dm = 1, and the projected area seen from wo,
        // ∫ D(m) max(0, wo·m) dm = cos θo (1 + Λ(wo)): Λ is the Smith
        // function of this D (so the visible normals' density integrates to 1).
        for (r, k, angle) in [(0.2f32, 0.8f32, 0.3f32), (0.5, 0.5, -1.0), (0.3, 1.0, 2.0)] {
            let g = ggx_of(r, k, angle);
            let norm = hemisphere_integral(|m| g.d(m) as f64 * m.z as f64);
            eprintln!("aniso D r={r} k={k}: ∫ D cos = {norm:.6}");
            assert!((norm - 1.0).abs() < 2e-3, "r={r} k={k}: {norm}");
            for (theta, phi) in [(30.0f32, 0.3f32), (70.0, 1.9), (85.0, 0.3 + angle)] {
                let wo = dir(theta, phi);
                let area = hemisphere_integral(|m| g.d(m) as f64 * wo.dot(m).max(0.0) as f64);
                let expected = wo.z as f64 * (1.0 + g.lambda(wo) as f64);
                eprintln!("aniso r={r} k={k} θo={theta}: projected {area:.6} vs {expected:.6}");
                assert!(
                    (area / expected - 1.0).abs() < 3e-3,
                    "r={r} k={k} θo={theta}: {area} vs {expected}"
                );
            }
        }
    }

    #[test]
    fn anisotropic_formulas_reduce_to_the_isotropic_ones() {
        // Equal widths: the anisotropic D, Λ and visible-normal samples are
        // the isotropic ones (to rounding), whatever the direction.
        let mut r = rng(31);
        for alpha in [0.01f32, 0.2, 0.7] {
            for angle in [0.0f32, 0.7, 2.5] {
                let dir2 = Vec2::new(angle.cos(), angle.sin());
                let a = Ggx::Anisotropic {
                    at: alpha,
                    ab: alpha,
                    dir: dir2,
                };
                let i = Ggx::Isotropic(alpha);
                for _ in 0..2000 {
                    let w = sphere(&mut r);
                    let w = Vec3A::new(w.x, w.y, w.z.abs().max(1e-3)).normalize();
                    let close = |x: f32, y: f32| (x - y).abs() <= 2e-5 * y.abs().max(1e-3);
                    assert!(close(a.d(w), i.d(w)), "{alpha} {w}: {} {}", a.d(w), i.d(w));
                    assert!(close(a.lambda(w), i.lambda(w)));
                    let u = u2(&mut r);
                    let (ma, mi) = (a.sample_visible_normal(w, u), i.sample_visible_normal(w, u));
                    assert!((ma - mi).length() < 1e-4, "{ma} vs {mi}");
                }
            }
        }
        // Strength 0 is no anisotropy at all: the isotropic path itself.
        let p = aniso(PbrBsdf::new(COLOR, 0.5, 0.4), 0.0, 1.0);
        assert!(matches!(p.ggx(), Ggx::Isotropic(a) if a == p.alpha));
        let plain = PbrBsdf::new(COLOR, 0.5, 0.4);
        for _ in 0..1000 {
            let (wo, wi) = (sphere(&mut r), sphere(&mut r));
            assert_eq!(p.eval_pdf(wo, wi), plain.eval_pdf(wo, wi));
            let (ul, u) = (r.next_f32(), u2(&mut r));
            assert_eq!(p.sample(wo, ul, u), plain.sample(wo, ul, u));
        }
    }

    #[test]
    fn anisotropic_metal_matches_the_specifications_formulas() {
        // BRDF_specularAnisotropicGGX of the extension's text, written out
        // in f64: F V D with at = mix(α, 1, k²), ab = α, on the pair
        // below; raylab's f cos θi over cos θi must equal it.
        let (r, k, angle) = (0.4f64, 0.7f64, 0.6f64);
        let c = Vec3A::new(0.9, 0.6, 0.3);
        let p = aniso(PbrBsdf::new(c, 1.0, r as f32), k as f32, angle as f32);
        let (wo, wi) = (dir(50.0, 0.2), dir(35.0, 2.9));
        let v = |w: Vec3A| [w.x as f64, w.y as f64, w.z as f64];
        let (l, vv) = (v(wi), v(wo));
        let hs = [l[0] + vv[0], l[1] + vv[1], l[2] + vv[2]];
        let hl = (hs[0] * hs[0] + hs[1] * hs[1] + hs[2] * hs[2]).sqrt();
        let h = hs.map(|x| x / hl);
        let t = [angle.cos(), angle.sin(), 0.0];
        let b = [-angle.sin(), angle.cos(), 0.0];
        let dot = |a: [f64; 3], b: [f64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
        let alpha = r * r;
        let at = alpha * (1.0 - k * k) + k * k;
        let ab = alpha;
        // D_GGX_anisotropic.
        let a2 = at * ab;
        let f = [ab * dot(t, h), at * dot(b, h), a2 * h[2]];
        let w2 = a2 / dot(f, f);
        let d = a2 * w2 * w2 / std::f64::consts::PI;
        // V_GGX_anisotropic.
        let len = |x: f64, y: f64, z: f64| (x * x + y * y + z * z).sqrt();
        let ggxv = l[2] * len(at * dot(t, vv), ab * dot(b, vv), vv[2]);
        let ggxl = vv[2] * len(at * dot(t, l), ab * dot(b, l), l[2]);
        let vis = 0.5 / (ggxv + ggxl);
        let x5 = (1.0 - dot(vv, h)).powi(5);
        let expected = Vec3A::new(
            ((c.x as f64 + (1.0 - c.x as f64) * x5) * vis * d) as f32,
            ((c.y as f64 + (1.0 - c.y as f64) * x5) * vis * d) as f32,
            ((c.z as f64 + (1.0 - c.z as f64) * x5) * vis * d) as f32,
        );
        let got = p.eval(wo, wi) / wi.z;
        eprintln!("anisotropic metal: {got} against the specification's {expected}");
        assert!(rel_err(got, expected) < 1e-4, "{got} vs {expected}");
        // And the isotropic value differs (the test sees the anisotropy).
        let iso = PbrBsdf::new(c, 1.0, r as f32).eval(wo, wi) / wi.z;
        assert!(rel_err(iso, expected) > 0.05, "{iso} vs {expected}");
    }

    #[test]
    fn the_highlight_widens_along_the_anisotropy_direction() {
        // Seen head-on, a light 15° off the mirror direction towards the
        // direction t is reflected far more than one 15° off towards b
        // (the lobe is wider along t), and turning the direction by 90°
        // swaps the two; on a ring, the widest azimuth is ±t.
        use std::f32::consts::FRAC_PI_2;
        let wo = Vec3A::Z;
        for angle in [0.0f32, 0.5, 1.2] {
            let p = aniso(PbrBsdf::new(Vec3A::ONE, 1.0, 0.2), 0.8, angle);
            let along = p.eval(wo, dir(15.0, angle)).x;
            let across = p.eval(wo, dir(15.0, angle + FRAC_PI_2)).x;
            eprintln!("aniso highlight at {angle}: along t {along:.4}, along b {across:.4}");
            assert!(along > 5.0 * across, "{angle}: {along} vs {across}");
            let turned = aniso(p, 0.8, angle + FRAC_PI_2);
            let (a2, c2) = (
                turned.eval(wo, dir(15.0, angle)).x,
                turned.eval(wo, dir(15.0, angle + FRAC_PI_2)).x,
            );
            assert!(
                (a2 - across).abs() < 1e-4 * across.max(1e-3) && (c2 - along).abs() < 1e-4 * along
            );
            // The azimuth of the widest point on a 15° ring is ±t.
            let best = (0..360)
                .map(|i| (i as f32).to_radians())
                .max_by(|&x, &y| {
                    p.eval(wo, dir(15.0, x))
                        .x
                        .total_cmp(&p.eval(wo, dir(15.0, y)).x)
                })
                .unwrap();
            let x = (best - angle).rem_euclid(PI);
            let off = x.min(PI - x);
            assert!(off < 0.02, "{angle}: widest at {best}");
        }
    }

    /// White furnaces for anisotropic lobes: never more than is received,
    /// and between the isotropic materials of widths `α_t` and `α_b` (the
    /// single-scattering loss grows with roughness).
    #[test]
    fn furnace_anisotropic_white_metal_and_glass() {
        let n = 60_000;
        for (r, k) in [(0.1f32, 0.5f32), (0.3, 0.8), (0.5, 1.0), (0.05, 1.0)] {
            let p = aniso(PbrBsdf::new(Vec3A::ONE, 1.0, r), k, 0.7);
            let at = p.alpha_t().sqrt();
            for theta in [0.0f32, 45.0, 80.0] {
                let wo = dir(theta, 0.2);
                let (a, se) = albedo(Material::Pbr(p), wo, n, 900);
                let wide = albedo(Material::Pbr(PbrBsdf::new(Vec3A::ONE, 1.0, at)), wo, n, 901);
                let narrow = albedo(Material::Pbr(PbrBsdf::new(Vec3A::ONE, 1.0, r)), wo, n, 902);
                eprintln!(
                    "furnace aniso metal r={r} k={k} θo={theta}: {a:.5} ± {se:.5} (iso α_t {:.5}, α_b {:.5})",
                    wide.0, narrow.0
                );
                assert!(
                    a <= 1.0 + 3.0 * se + 1e-6,
                    "r={r} k={k} θo={theta}: {a} ± {se}"
                );
                assert!(
                    a >= wide.0 - 4.0 * (se + wide.1) && a <= narrow.0 + 4.0 * (se + narrow.1),
                    "r={r} k={k} θo={theta}: {a} not between {} and {}",
                    wide.0,
                    narrow.0
                );
            }
        }
        // Clear rough glass (reflection and refraction, Schlick): from
        // either side, no gain.
        for (r, k) in [(0.2f32, 0.8f32), (0.5, 1.0)] {
            let p = aniso(volume(Vec3A::ONE, 0.0, r, 1.0), k, -0.4);
            for wo in [
                dir(0.0, 0.0),
                dir(45.0, 1.0),
                dir(80.0, 0.3),
                -dir(30.0, 2.0),
            ] {
                let (a, se) = albedo(Material::Pbr(p), wo, n, 903);
                eprintln!("furnace aniso glass r={r} k={k} wo={wo}: {a:.5} ± {se:.5}");
                assert!(a <= 1.0 + 3.0 * se + 1e-6, "r={r} k={k} {wo}: {a} ± {se}");
                assert!(a > 0.5, "r={r} k={k} {wo}: {a}");
            }
        }
    }

    #[test]
    fn orienting_takes_the_tangent_frame_into_the_shading_frame() {
        // Direction (cos 30°, sin 30°) in a tangent frame turned 90° about
        // the normal: 120° in the shading frame; no tangent: isotropic.
        let frame = Frame::from_normal(Vec3A::Z);
        let (t, b) = (frame.b, -frame.t);
        let mut p = aniso(PbrBsdf::new(COLOR, 1.0, 0.3), 0.6, 30f32.to_radians());
        let mut q = p;
        p.orient_anisotropy(&frame, t, b);
        let expected = Vec2::new(120f32.to_radians().cos(), 120f32.to_radians().sin());
        assert!((p.anisotropy_direction - expected).length() < 1e-6, "{p:?}");
        q.orient_anisotropy(&frame, Vec3A::ZERO, Vec3A::ZERO);
        assert_eq!(q.anisotropy, 0.0);
        assert!(matches!(q.ggx(), Ggx::Isotropic(_)));
    }
}
