//! Mitsuba 3's `roughplastic`: a diffuse base under a rough dielectric
//! coating, [`RoughPlastic`], with the table of the coating's transmittance
//! it needs, [`RoughPlasticTable`].

use super::super::bsdf::{BsdfSample, GUIDE_ALPHA, GuideLobes, finite_or_zero};
use super::super::disk::concentric_disk;
use super::super::frame::{above, reflect_z};
use super::super::fresnel::{fresnel_diffuse_reflectance, fresnel_mitsuba};
use super::super::microfacet::{MicrofacetDistribution, MicrofacetKind, gauss_legendre};
use super::common::positive;
use super::plastic::{base_reflectance, mean, specular_sampling_weight};
use glam::{Vec2, Vec3A};
use std::f32::consts::FRAC_1_PI;
use std::sync::Mutex;

/// Entries of [`RoughPlasticTable::external_transmittance`] (Mitsuba's
/// `MI_ROUGH_TRANSMITTANCE_RES`).
pub const TRANSMITTANCE_RES: usize = 64;

/// What Mitsuba's `roughplastic` precomputes for its distribution, alpha
/// and index (its `parameters_changed`): the rough interface's directional
/// transmittance `T(μ)` at `μ = j / 63` and its internal diffuse
/// reflectance, each by Mitsuba's own quadrature (Gauss–Legendre in the
/// visible-normal sample space: 32² nodes for `η > 1`, 128² otherwise).
/// Shared: [`RoughPlasticTable::get`] builds each table once, on first use,
/// and keeps it for the life of the process (a table is 260 bytes; a scene
/// has a few).
#[derive(Clone, Debug, PartialEq)]
pub struct RoughPlasticTable {
    /// `T(μ_j)`: the fraction of light arriving at cosine `μ_j` from
    /// outside that the rough interface transmits (single scattering).
    pub external_transmittance: [f32; TRANSMITTANCE_RES],
    /// `2 mean_j(R_int(μ_j) μ_j)`: the fraction of diffuse light inside that
    /// the interface reflects back down.
    pub internal_reflectance: f32,
}

/// The tables built so far, by (distribution, alpha, eta) bits.
type TableCache = Vec<((MicrofacetKind, u32, u32), &'static RoughPlasticTable)>;
static TABLES: Mutex<TableCache> = Mutex::new(Vec::new());

impl RoughPlasticTable {
    /// The table of distribution `kind`, width `alpha` (clamped to
    /// `1e-4`) and relative index `eta`, built on first use and shared.
    pub fn get(kind: MicrofacetKind, alpha: f32, eta: f32) -> &'static RoughPlasticTable {
        let alpha = MicrofacetDistribution::new(kind, alpha, alpha).alpha_u;
        let key = (kind, alpha.to_bits(), eta.to_bits());
        let mut tables = TABLES.lock().unwrap_or_else(|e| e.into_inner());
        if let Some(&(_, t)) = tables.iter().find(|(k, _)| *k == key) {
            return t;
        }
        let t: &'static RoughPlasticTable = Box::leak(Box::new(Self::compute(kind, alpha, eta)));
        tables.push((key, t));
        t
    }

    /// Computes the table (Mitsuba's `eval_transmittance` and
    /// `eval_reflectance`, in f32 with f64 sums).
    pub fn compute(kind: MicrofacetKind, alpha: f32, eta: f32) -> RoughPlasticTable {
        use rayon::prelude::*;
        let distr = MicrofacetDistribution::new(kind, alpha, alpha);
        // The 64 cosines' quadratures in parallel (about 1.1 million BSDF
        // evaluations: half a second on one core), summed in order.
        let columns: Vec<(f32, f64)> = (0..TRANSMITTANCE_RES)
            .into_par_iter()
            .map(|j| {
                let mu = (j as f32 / (TRANSMITTANCE_RES - 1) as f32).max(1e-6);
                let wi = Vec3A::new((1.0 - mu * mu).sqrt(), 0.0, mu);
                (
                    quadrature(&distr, wi, eta, false) as f32,
                    quadrature(&distr, wi, 1.0 / eta, true) * mu as f64,
                )
            })
            .collect();
        let mut external_transmittance = [0.0; TRANSMITTANCE_RES];
        let mut internal = 0.0f64;
        for (t, &(transmittance, reflected)) in external_transmittance.iter_mut().zip(&columns) {
            *t = transmittance;
            internal += reflected;
        }
        RoughPlasticTable {
            external_transmittance,
            internal_reflectance: (2.0 * internal / TRANSMITTANCE_RES as f64) as f32,
        }
    }

    /// `T(μ)` by linear interpolation in the table (Mitsuba's `lerp_gather`).
    #[inline]
    pub fn transmittance(&self, mu: f32) -> f32 {
        let x = mu * (TRANSMITTANCE_RES - 1) as f32;
        let i = (x as usize).min(TRANSMITTANCE_RES - 2);
        let (a, b) = (
            self.external_transmittance[i],
            self.external_transmittance[i + 1],
        );
        a + (b - a) * (x - i as f32)
    }
}

/// The rough interface's single-scattering reflectance (`reflect`) or
/// transmittance for light at `wi`, relative index `eta`: `∫ F G1(wo)` or
/// `∫ (1 − F) G1(wo)` over the normals visible from `wi`, by Gauss–Legendre
/// in their sample space.
fn quadrature(distr: &MicrofacetDistribution, wi: Vec3A, eta: f32, reflect: bool) -> f64 {
    let rule = gauss_legendre(if eta > 1.0 { 32 } else { 128 });
    let mut sum = 0.0f64;
    for &(xa, wa) in &rule {
        for &(xb, wb) in &rule {
            let u = Vec2::new((xa * 0.5 + 0.5) as f32, (xb * 0.5 + 0.5) as f32);
            let m = distr.sample(wi, u).0;
            let im = wi.dot(m);
            let (f, cos_t, _, eta_ti) = fresnel_mitsuba(im, eta);
            let value = if reflect {
                let wo = (2.0 * im) * m - wi;
                if wo.z <= 0.0 || wi.z <= 0.0 {
                    continue;
                }
                distr.g1(wo, m) * f
            } else {
                let wo = m * (im * eta_ti + cos_t) - wi * eta_ti;
                if wo.z * wi.z >= 0.0 {
                    continue;
                }
                distr.g1(wo, m) * (1.0 - f)
            };
            sum += value as f64 * wa * wb * 0.25;
        }
    }
    sum
}

/// Mitsuba's `roughplastic`: a rough specular reflection
/// `F D G / (4 cos θo) · specular_reflectance` (isotropic Beckmann or GGX,
/// separable `G`) over a Lambertian base seen through the rough interface,
/// `ρ' cos θi / π · T(cos θo) T(cos θi) / η²` with `ρ'` the base after its
/// internal reflections ([`RoughPlasticTable::internal_reflectance`]). The
/// specular lobe is sampled (visible normals) with probability
/// `(1 − T) w / ((1 − T) w + T (1 − w))`, `T = T(cos θo)` and `w` the
/// specular sampling weight; the pdf is the mixture. One-sided.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RoughPlastic {
    /// The microfacets, isotropic (defaults: Beckmann, 0.1).
    pub distribution: MicrofacetDistribution,
    /// Relative index `int_ior / ext_ior` (default 1.49; must differ from 1).
    pub eta: f32,
    /// The base's reflectance ρ (`diffuse_reflectance`, default 0.5).
    pub diffuse_reflectance: Vec3A,
    /// Tint of the specular reflection (`specular_reflectance`, default 1).
    pub specular_reflectance: Vec3A,
    /// Mitsuba's `nonlinear` (default false).
    pub nonlinear: bool,
    /// The probability weight of the specular lobe (see
    /// [`super::Plastic::specular_sampling_weight`]).
    pub specular_sampling_weight: f32,
    /// The interface's precomputed transmittance.
    pub table: &'static RoughPlasticTable,
}

impl RoughPlastic {
    /// The rough plastic of microfacets `kind` of width `alpha`, relative
    /// index `eta = int_ior / ext_ior`, base `diffuse_reflectance`, tint
    /// `specular_reflectance` and `nonlinear`, with the specular sampling
    /// weight of these constants. Looks up (or, the first time, computes:
    /// a few tens of milliseconds) the shared table of `(kind, alpha, eta)`:
    /// build it once per scene material, and per hit only change the
    /// reflectances of a copy.
    pub fn new(
        kind: MicrofacetKind,
        alpha: f32,
        eta: f32,
        diffuse_reflectance: Vec3A,
        specular_reflectance: Vec3A,
        nonlinear: bool,
    ) -> Self {
        Self {
            distribution: MicrofacetDistribution::new(kind, alpha, alpha),
            eta,
            diffuse_reflectance,
            specular_reflectance,
            nonlinear,
            specular_sampling_weight: specular_sampling_weight(
                mean(diffuse_reflectance),
                mean(specular_reflectance),
            ),
            table: RoughPlasticTable::get(kind, alpha, eta),
        }
    }

    /// The probability of the specular lobe given `T(cos θo)`.
    #[inline]
    fn prob_specular(&self, t_o: f32) -> f32 {
        let w = self.specular_sampling_weight;
        let s = (1.0 - t_o) * w;
        let d = t_o * (1.0 - w);
        s / (s + d)
    }

    /// `f(wo, wi) cos θi`, both lobes.
    #[inline]
    pub fn eval(&self, wo: Vec3A, wi: Vec3A) -> Vec3A {
        if !above(wo) || !above(wi) {
            return Vec3A::ZERO;
        }
        let distr = &self.distribution;
        let h = (wo + wi).normalize();
        let f = fresnel_mitsuba(wo.dot(h), self.eta).0;
        let spec = self.specular_reflectance * (f * distr.d(h) * distr.g(wo, wi, h) / (4.0 * wo.z));
        let t = self.table;
        let rho = base_reflectance(
            self.diffuse_reflectance,
            t.internal_reflectance,
            self.nonlinear,
        );
        let diff = rho
            * (FRAC_1_PI / (self.eta * self.eta)
                * wi.z
                * t.transmittance(wo.z)
                * t.transmittance(wi.z));
        finite_or_zero(spec + diff)
    }

    /// The density of [`RoughPlastic::sample`] (the mixture of the lobes').
    #[inline]
    pub fn pdf(&self, wo: Vec3A, wi: Vec3A) -> f32 {
        if !above(wo) || !above(wi) {
            return 0.0;
        }
        let p_spec = self.prob_specular(self.table.transmittance(wo.z));
        let distr = &self.distribution;
        let h = (wo + wi).normalize();
        let spec = distr.d(h) * distr.g1(wo, h) / (4.0 * wo.z);
        let p = p_spec * spec + (1.0 - p_spec) * wi.z * FRAC_1_PI;
        if p.is_finite() { p } else { 0.0 }
    }

    /// Reflects `wo` about a visible normal (`u_lobe < P_spec`) or draws a
    /// cosine-distributed direction; the weight is eval / pdf.
    #[inline]
    pub fn sample(&self, wo: Vec3A, u_lobe: f32, u: Vec2) -> Option<BsdfSample> {
        if !above(wo) {
            return None;
        }
        let p_spec = self.prob_specular(self.table.transmittance(wo.z));
        let wi = if u_lobe < p_spec {
            let m = self.distribution.sample(wo, u).0;
            (2.0 * wo.dot(m)) * m - wo
        } else {
            let p = concentric_disk(u);
            Vec3A::new(p.x, p.y, (1.0 - p.length_squared()).max(0.0).sqrt())
        };
        let pdf = self.pdf(wo, wi);
        if !positive(pdf) {
            return None;
        }
        let weight = self.eval(wo, wi) / pdf;
        weight.is_finite().then_some(BsdfSample {
            wi,
            weight,
            pdf,
            specular: false,
        })
    }

    /// The albedo guide at cosine `cos`: `(1 − T) · specular_reflectance`
    /// plus the base's `ρ' T (1 − F_dr(η)) / η²` (the outgoing side's
    /// transmittance approximated by the smooth interface's).
    pub fn albedo(&self, cos: f32) -> Vec3A {
        let t_o = self.table.transmittance(cos.clamp(0.0, 1.0));
        let rho = base_reflectance(
            self.diffuse_reflectance,
            self.table.internal_reflectance,
            self.nonlinear,
        );
        (1.0 - t_o) * self.specular_reflectance
            + rho * (t_o * (1.0 - fresnel_diffuse_reflectance(self.eta)) / (self.eta * self.eta))
    }

    /// The denoiser's guides: the mirror reflection of the coating when
    /// alpha is at most [`GUIDE_ALPHA`], and the base as the rough part.
    pub fn guide_lobes(&self, wo: Vec3A) -> GuideLobes {
        if !above(wo) {
            return GuideLobes::NONE;
        }
        let all = self.albedo(wo.z);
        if self.distribution.alpha_u > GUIDE_ALPHA {
            return GuideLobes::rough(all);
        }
        let spec = (1.0 - self.table.transmittance(wo.z)) * self.specular_reflectance;
        GuideLobes {
            reflect: GuideLobes::lobe(reflect_z(wo), spec),
            ..GuideLobes::rough(all - spec)
        }
    }
}
