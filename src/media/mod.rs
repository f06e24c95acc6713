//! Participating media: what fills the space between surfaces (fog, smoke,
//! the inside of a glass of milk), as collision coefficients per colour
//! channel and a phase function ([`phase`]). A medium is bound to the
//! inside or the outside of shapes (`crate::scene::MediumInterface`); the
//! volumetric path tracer (`crate::integrators::path::volume`) samples
//! where a path collides in it ([`Medium::sample_flight`]) and how much of a
//! light sample reaches a point through it ([`Medium::transmittance`]).
//!
//! Coefficients are per unit of scene length, by RGB channel. A chromatic
//! medium (different extinction per channel) is sampled with the one-sample
//! spectral MIS of Miller, Georgiev and Jarosz (2019): a channel is chosen
//! uniformly, the distance drawn from its extinction (homogeneous) or its
//! extinction deciding every collision of delta tracking (heterogeneous),
//! and the sample is weighed by the mean of the three channels' pdfs, so no
//! channel's weight grows without bound.
//!
//! # Emission
//!
//! A medium may emit light ([`Homogeneous::emission`],
//! [`Heterogeneous::emission`]), as pbrt-v4's media do: its radiance `Le`
//! is that of the medium where it is optically thick, and the light it
//! emits per unit length is `σa · Le` (Kirchhoff's law: what absorbs,
//! emits), so a medium that absorbs nothing emits nothing. Along a flight
//! the emission is estimated with the flight ([`Flight`]'s `emitted`):
//! exactly for a homogeneous medium, by the collision estimator at delta
//! tracking's tentative collisions for a heterogeneous one (unbiased).

pub mod albedo;
pub mod expected;
pub mod grid;
pub mod majorant;
pub mod phase;
pub mod sparse;

use std::ops::ControlFlow;

use glam::{Affine3A, Vec3A};

pub use grid::{Field, FieldValues, Grid};
pub use phase::Phase;
pub use sparse::{SparseGrid, Tile};

use crate::geometry::ray::Ray;

/// A homogeneous medium: the same coefficients everywhere.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Homogeneous {
    /// Extinction `σt = σa + σs` per unit length, per channel (≥ 0).
    pub sigma_t: Vec3A,
    /// Scattering `σs ≤ σt` per unit length, per channel.
    pub sigma_s: Vec3A,
    /// How it scatters.
    pub phase: Phase,
    /// Whether paths scattered in it sample lights (Mitsuba's
    /// `sample_emitters`; without, they find them only by phase sampling).
    pub sample_emitters: bool,
    /// A subsurface medium ([`Medium::subsurface`]): paths cross it by a
    /// random walk (no light samples, scattering events not counted as
    /// bounces, the distance channel chosen once per walk).
    pub random_walk: bool,
    /// The box `(lo, hi)` the medium fills, if it does not fill all the
    /// space it is bound to (`--fog` and scene files' fog: the scene's
    /// bounding box, so that light from outside reaches in); nothing
    /// outside it.
    pub bounds: Option<(Vec3A, Vec3A)>,
    /// The radiance `Le` it emits with (light per unit length `σa · Le`;
    /// [module docs](self)); zero for none.
    pub emission: Vec3A,
}

impl Homogeneous {
    /// The stretch `[t0, t1]` of `ray` (unit direction) within `[0, t_max]`
    /// that lies in the medium; `None` if none does.
    #[inline]
    pub fn span(&self, ray: &Ray, t_max: f32) -> Option<(f32, f32)> {
        let Some((lo, hi)) = self.bounds else {
            return (t_max > 0.0).then_some((0.0, t_max));
        };
        box_span(lo, hi, ray, t_max)
    }

    /// `∫ T σa Le dt` over `length` of the medium, exactly: the light it
    /// emits towards the start of a segment that long (zero for a medium
    /// that emits nothing).
    #[inline]
    pub fn emitted_along(&self, length: f32) -> Vec3A {
        if self.emission == Vec3A::ZERO {
            return Vec3A::ZERO;
        }
        let sigma_a = (self.sigma_t - self.sigma_s).max(Vec3A::ZERO);
        let absorbed = Vec3A::ONE - transmit(self.sigma_t, length);
        Vec3A::select(
            self.sigma_t.cmpgt(Vec3A::ZERO),
            sigma_a / self.sigma_t * absorbed * self.emission,
            Vec3A::ZERO,
        )
    }

    /// The density per unit length with which [`Medium::sample_flight`]
    /// stops a flight along a ray at distance `t` of its span `[t0, t1]`
    /// ([`Homogeneous::span`]): the mean over the channels of
    /// `σt exp(−σt (t − t0))`, the one-sample spectral MIS pdf.
    #[inline]
    pub fn flight_pdf(&self, t0: f32, t: f32) -> f32 {
        let tr = (-self.sigma_t * (t - t0)).exp();
        (self.sigma_t * tr).element_sum() / 3.0
    }
}

/// The stretch of `ray` (unit direction) within `[0, t_max]` inside the box
/// `lo..hi`; `None` if it misses it.
#[inline]
fn box_span(lo: Vec3A, hi: Vec3A, ray: &Ray, t_max: f32) -> Option<(f32, f32)> {
    let inv = ray.dir.recip();
    let a = (lo - ray.origin) * inv;
    let b = (hi - ray.origin) * inv;
    // (NaN from 0·∞ on a face is dropped by max/min.)
    let t0 = a.min(b).max_element().max(0.0);
    let t1 = a.max(b).min_element().min(t_max);
    (t0 < t1).then_some((t0, t1))
}

/// A heterogeneous medium (Mitsuba's `heterogeneous`): extinction
/// `scale · sigma_t(p)` and albedo `albedo(p)` from fields, within the
/// extinction field's bounds (nothing outside them). Flights are sampled by
/// delta tracking against majorants (per cell of a coarse grid over a
/// grid-valued extinction placed without rotation, else `scale · max
/// sigma_t`) and shadow
/// rays' transmittance estimated by ratio tracking (Novák et al. 2014), both
/// unbiased.
#[derive(Clone, Debug, PartialEq)]
pub struct Heterogeneous {
    /// Extinction per unit length before `scale`.
    pub sigma_t: Field,
    /// Single-scattering albedo.
    pub albedo: Field,
    /// Factor of the extinction.
    pub scale: f32,
    /// How it scatters.
    pub phase: Phase,
    /// Whether paths scattered in it sample lights.
    pub sample_emitters: bool,
    /// What it emits, if anything.
    pub emission: Option<Emission>,
}

/// The radiance `Le(p)` a heterogeneous medium emits with (light per unit
/// length `σa(p) · Le(p)`; [module docs](self)).
#[derive(Clone, Debug, PartialEq)]
pub enum Emission {
    /// `scale · le(p)` (RGB).
    Radiance {
        /// The radiance before `scale`.
        le: Field,
        /// Its factor.
        scale: f32,
    },
    /// A blackbody at a temperature from a field: `scale · B((T(p) −
    /// offset) · t_scale)`, `B` the radiance of pbrt-v4's peak-normalised
    /// blackbody ([`crate::materials::blackbody::blackbody_rgb`]), as
    /// pbrt-v4's `nanovdb` and `uniformgrid` media's `Lescale`,
    /// `temperatureoffset` and `temperaturescale`.
    Temperature {
        /// The temperature before `offset` and `t_scale` (its first
        /// channel).
        temperature: Field,
        /// Subtracted from the temperature.
        offset: f32,
        /// Multiplies the temperature after `offset`, to kelvin.
        t_scale: f32,
        /// Factor of the radiance.
        scale: f32,
    },
}

impl Emission {
    /// `Le` at `p`.
    #[inline]
    pub fn eval(&self, p: Vec3A) -> Vec3A {
        match self {
            Emission::Radiance { le, scale } => *scale * le.eval(p),
            Emission::Temperature {
                temperature,
                offset,
                t_scale,
                scale,
            } => {
                let kelvin = (temperature.eval(p).x - offset) * t_scale;
                *scale * crate::materials::blackbody::blackbody_rgb(kelvin)
            }
        }
    }

    fn transform(&mut self, to_world: Affine3A) {
        match self {
            Emission::Radiance { le: f, .. } | Emission::Temperature { temperature: f, .. } => {
                f.transform(to_world)
            }
        }
    }

    fn check(&self) -> Result<(), String> {
        let finite = |name: &str, v: f32| {
            if v.is_finite() && v >= 0.0 {
                Ok(())
            } else {
                Err(format!(
                    "a medium's {name} must be finite and >= 0 (got {v})"
                ))
            }
        };
        let (field, scale) = match self {
            Emission::Radiance { le, scale } => (le, scale),
            Emission::Temperature {
                temperature, scale, ..
            } => (temperature, scale),
        };
        finite("emission scale", *scale)?;
        finite("emission", field.max())?;
        if let Emission::Temperature {
            offset, t_scale, ..
        } = self
        {
            finite("temperature scale", *t_scale)?;
            if !offset.is_finite() {
                return Err(format!(
                    "a medium's temperature offset must be finite (got {offset})"
                ));
            }
        }
        Ok(())
    }
}

impl Heterogeneous {
    /// The majorant: an upper bound of the extinction anywhere.
    #[inline]
    fn majorant(&self) -> f32 {
        self.scale * self.sigma_t.max()
    }

    /// The stretches of `ray` from `t0` to `t1` (within its span) with an
    /// upper bound of `sigma_t` on each (before `scale`): the majorant
    /// grid's cells, or the whole span under the largest value.
    #[inline]
    fn walk(&self, ray: &Ray, t0: f32, t1: f32) -> Walk<'_> {
        match self.sigma_t.segments(ray, t0, t1) {
            Some(s) => Walk::Cells(s),
            None => Walk::Once(Some((t0, t1, self.sigma_t.max()))),
        }
    }

    /// Walks `ray` from `t0` to `t1` by exponential steps against the
    /// majorants ([`Heterogeneous::walk`]; numbers from `u`), calling
    /// `collide(t, majorant, u)` at every tentative collision until it
    /// breaks; `None` if the walk reaches `t1` first. The one tracking loop
    /// of delta tracking (flights) and ratio tracking (transmittance).
    #[inline]
    fn track<R, U: FnMut() -> f32>(
        &self,
        ray: &Ray,
        t0: f32,
        t1: f32,
        u: &mut U,
        mut collide: impl FnMut(f32, f32, &mut U) -> ControlFlow<R>,
    ) -> Option<R> {
        // The optical depth (against the majorants) left before the next
        // tentative collision.
        let mut tau = -(1.0 - u()).ln();
        for (ta, tb, m) in self.walk(ray, t0, t1) {
            let mu = self.scale * m;
            if mu <= 0.0 {
                continue;
            }
            let mut t = ta;
            loop {
                let dt = tau / mu;
                if t + dt >= tb {
                    tau = (tau - (tb - t) * mu).max(0.0);
                    break;
                }
                t += dt;
                if let ControlFlow::Break(r) = collide(t, mu, u) {
                    return Some(r);
                }
                tau = -(1.0 - u()).ln();
            }
        }
        None
    }

    /// The part `(t0, t1)` of `ray` within `[0, t_max]` that lies in the
    /// medium's bounds, if any.
    #[inline]
    fn span(&self, ray: &Ray, t_max: f32) -> Option<(f32, f32)> {
        let (lo, hi) = self.sigma_t.bounds;
        box_span(lo, hi, ray, t_max)
    }
}

/// The stretches a ray crosses a heterogeneous medium in, each with an
/// upper bound of the extinction.
enum Walk<'a> {
    Cells(majorant::Segments<'a>),
    Once(Option<(f32, f32, f32)>),
}

impl Iterator for Walk<'_> {
    type Item = (f32, f32, f32);

    #[inline]
    fn next(&mut self) -> Option<(f32, f32, f32)> {
        match self {
            Walk::Cells(s) => s.next(),
            Walk::Once(o) => o.take(),
        }
    }
}

/// A participating medium.
#[derive(Clone, Debug, PartialEq)]
pub enum Medium {
    /// The same everywhere.
    Homogeneous(Homogeneous),
    /// Varying through space.
    Heterogeneous(Box<Heterogeneous>),
}

/// Where a path's flight through a medium ends ([`Medium::sample_flight`]).
/// Both carry `emitted`: an estimate of the light the medium emits towards
/// the ray's origin along the whole segment (`∫ T σa Le dt`; zero for a
/// medium that emits nothing), to add times the throughput before `weight`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Flight {
    /// It scatters at distance `t`; the throughput is multiplied by `weight`
    /// (`σs · T(t)` over the flight's pdf there).
    Scatter {
        /// Distance along the ray.
        t: f32,
        /// Factor for the path's throughput.
        weight: Vec3A,
        /// Emitted light ([`Flight`]).
        emitted: Vec3A,
    },
    /// It reaches the end of the segment (the next surface, or infinity);
    /// the throughput is multiplied by `weight` (`T` over the probability of
    /// getting that far).
    Pass {
        /// Factor for the path's throughput.
        weight: Vec3A,
        /// Emitted light ([`Flight`]).
        emitted: Vec3A,
    },
}

impl Flight {
    /// The light emitted along the segment ([`Flight`]).
    #[inline]
    pub fn emitted(&self) -> Vec3A {
        match self {
            Flight::Scatter { emitted, .. } | Flight::Pass { emitted, .. } => *emitted,
        }
    }
}

/// A flight that passes with weight 1 and no emission.
const CLEAR: Flight = Flight::Pass {
    weight: Vec3A::ONE,
    emitted: Vec3A::ZERO,
};

impl Medium {
    /// A homogeneous medium of extinction `sigma_t` and single-scattering
    /// albedo `albedo` (`σs = albedo · σt`).
    pub fn homogeneous(sigma_t: Vec3A, albedo: Vec3A, phase: Phase) -> Medium {
        Medium::Homogeneous(Homogeneous {
            sigma_t,
            sigma_s: albedo * sigma_t,
            phase,
            sample_emitters: true,
            random_walk: false,
            bounds: None,
            emission: Vec3A::ZERO,
        })
    }

    /// [`Medium::homogeneous`] filling only the box `lo..hi`
    /// ([`Homogeneous::bounds`]).
    pub fn homogeneous_box(
        sigma_t: Vec3A,
        albedo: Vec3A,
        phase: Phase,
        lo: Vec3A,
        hi: Vec3A,
    ) -> Medium {
        let mut m = Self::homogeneous(sigma_t, albedo, phase);
        if let Medium::Homogeneous(h) = &mut m {
            h.bounds = Some((lo, hi));
        }
        m
    }

    /// The inside of a subsurface-scattering object (Cycles' random walk,
    /// glTF's `KHR_materials_volume_scatter`): extinction `sigma_t`, and the
    /// single-scattering albedo whose half-space shows the colour `rho`
    /// ([`albedo::single_scattering_albedo`]), scattering with mean cosine
    /// `g`. Paths inside walk from boundary to boundary
    /// ([`Homogeneous::random_walk`]).
    pub fn subsurface(sigma_t: Vec3A, rho: Vec3A, g: f32) -> Medium {
        let alpha = Vec3A::from(
            rho.to_array()
                .map(|r| albedo::single_scattering_albedo(r, g)),
        );
        let phase = Phase::of_mean_cosine(g);
        Medium::Homogeneous(Homogeneous {
            sigma_t,
            sigma_s: alpha * sigma_t,
            phase,
            sample_emitters: false,
            random_walk: true,
            bounds: None,
            emission: Vec3A::ZERO,
        })
    }

    /// The medium as a subsurface one, if paths cross it by a random walk.
    #[inline]
    pub fn random_walk(&self) -> Option<&Homogeneous> {
        match self {
            Medium::Homogeneous(h) if h.random_walk => Some(h),
            _ => None,
        }
    }

    /// Whether paths scattered in it sample lights (else only the phase
    /// function finds them, with full weight).
    #[inline]
    pub fn sample_emitters(&self) -> bool {
        match self {
            Medium::Homogeneous(h) => h.sample_emitters,
            Medium::Heterogeneous(h) => h.sample_emitters,
        }
    }

    /// Whether it emits light ([module docs](self)).
    pub fn emits(&self) -> bool {
        match self {
            Medium::Homogeneous(h) => {
                h.emission != Vec3A::ZERO && (h.sigma_t - h.sigma_s).max_element() > 0.0
            }
            Medium::Heterogeneous(h) => h.emission.is_some(),
        }
    }

    /// Its phase function.
    #[inline]
    pub fn phase(&self) -> Phase {
        match self {
            Medium::Homogeneous(h) => h.phase,
            Medium::Heterogeneous(h) => h.phase,
        }
    }

    /// Where a flight along `ray` (unit direction) ends before the
    /// segment's end `t_max` (the next surface; infinite if none), drawn
    /// with numbers uniform in `[0, 1)` from `u`. Homogeneous: the first
    /// picks the channel whose extinction draws the distance, the second the
    /// distance. Heterogeneous: delta tracking, two numbers a tentative
    /// collision. For a chromatic extinction a first number picks the hero
    /// channel whose extinction decides every collision of the flight (real
    /// with probability `σt[hero]/μ̄`), and the flight is weighed by the
    /// balance heuristic over the three channels' strategies (one-sample
    /// spectral MIS, Miller, Georgiev and Jarosz 2019, as pbrt-v4's
    /// `volpath` does with its hero wavelength): its contribution over the
    /// mean of the channels' pdfs, so every channel's weight stays below
    /// 3 however many null collisions the flight crosses. A grey
    /// extinction decides by its one value and draws no hero; its weights
    /// are the albedo at a real collision and 1 at a null one.
    #[inline]
    pub fn sample_flight(&self, ray: &Ray, t_max: f32, u: &mut impl FnMut() -> f32) -> Flight {
        match self {
            Medium::Heterogeneous(h) => {
                let Some((t0, t1)) = h.span(ray, t_max).filter(|_| h.majorant() > 0.0) else {
                    return CLEAR;
                };
                // The hero channel whose extinction decides real and null
                // collisions for the whole flight (none for a grey
                // extinction: every channel decides alike).
                let hero = (!h.sigma_t.is_grey()).then(|| ((u() * 3.0) as usize).min(2));
                // Per channel, the probability that channel's strategy
                // gives the collisions so far, scaled to mean 1: the
                // throughput's factor (`Π σn/μ̄` over its mean).
                let mut weight = Vec3A::ONE;
                let mut emitted = Vec3A::ZERO;
                let end = h.track(ray, t0, t1, u, |t, mu, u| {
                    let p = ray.origin + ray.dir * t;
                    let sigma_t = (h.scale * h.sigma_t.eval(p)).min(Vec3A::splat(mu));
                    let sigma_s = sigma_t * h.albedo.eval(p);
                    if let Some(e) = &h.emission {
                        // The collision estimator: every tentative
                        // collision (density μ̄ times what `weight` stands
                        // for) adds σa Le over μ̄.
                        emitted += weight * (sigma_t - sigma_s).max(Vec3A::ZERO) * e.eval(p) / mu;
                    }
                    let decider = match hero {
                        Some(c) => sigma_t[c],
                        None => sigma_t.element_sum() / 3.0,
                    };
                    if u() * mu < decider {
                        // Real: `weight σs / μ̄` over the channels' mean
                        // pdf `mean(weight σt) / μ̄`.
                        let pdf = (weight * sigma_t).element_sum() / 3.0;
                        return ControlFlow::Break(Flight::Scatter {
                            t,
                            weight: if pdf > 0.0 {
                                weight * sigma_s / pdf
                            } else {
                                Vec3A::ZERO
                            },
                            emitted,
                        });
                    }
                    // Null: each channel's pdf times `σn/μ̄`, then scaled
                    // back to mean 1 (the ratio is what weighs).
                    let next = weight * (Vec3A::splat(mu) - sigma_t);
                    let mean = next.element_sum() / 3.0;
                    if mean.is_nan() || mean <= 0.0 {
                        return ControlFlow::Break(Flight::Pass {
                            weight: Vec3A::ZERO,
                            emitted,
                        });
                    }
                    weight = next / mean;
                    ControlFlow::Continue(())
                });
                end.unwrap_or(Flight::Pass { weight, emitted })
            }
            Medium::Homogeneous(h) => {
                let Some((t0, t1)) = h.span(ray, t_max) else {
                    return CLEAR;
                };
                // ∫ T σa Le over the span, exactly.
                let emitted = h.emitted_along(t1 - t0);
                let channel = ((u() * 3.0) as usize).min(2);
                let sigma = h.sigma_t[channel];
                let ud = u();
                let t = if sigma > 0.0 {
                    t0 + -(1.0 - ud).ln() / sigma
                } else {
                    f32::INFINITY
                };
                if t < t1 {
                    let tr = (-h.sigma_t * (t - t0)).exp();
                    let pdf = (h.sigma_t * tr).element_sum() / 3.0;
                    return Flight::Scatter {
                        t,
                        weight: if pdf > 0.0 {
                            h.sigma_s * tr / pdf
                        } else {
                            Vec3A::ZERO
                        },
                        emitted,
                    };
                }
                let tr = transmit(h.sigma_t, t1 - t0);
                let p = tr.element_sum() / 3.0;
                Flight::Pass {
                    weight: if p > 0.0 { tr / p } else { Vec3A::ZERO },
                    emitted,
                }
            }
        }
    }

    /// The fraction of light that crosses the medium along `ray` (unit
    /// direction) from its origin to `t_max`, per channel: exact for a
    /// homogeneous medium, estimated without bias by ratio tracking (with
    /// numbers from `u`) for a heterogeneous one.
    #[inline]
    pub fn transmittance(&self, ray: &Ray, t_max: f32, u: &mut impl FnMut() -> f32) -> Vec3A {
        match self {
            Medium::Homogeneous(h) => h
                .span(ray, t_max)
                .map_or(Vec3A::ONE, |(t0, t1)| transmit(h.sigma_t, t1 - t0)),
            Medium::Heterogeneous(h) => {
                let Some((t0, t1)) = h.span(ray, t_max).filter(|_| h.majorant() > 0.0) else {
                    return Vec3A::ONE;
                };
                let mut tr = Vec3A::ONE;
                let end = h.track(ray, t0, t1, u, |t, mu, u| {
                    let sigma_t = h.scale * h.sigma_t.eval(ray.origin + ray.dir * t);
                    tr *= (Vec3A::ONE - sigma_t / mu).max(Vec3A::ZERO);
                    // Russian roulette once little is left (unbiased).
                    let m = tr.max_element();
                    if m < 0.1 {
                        if u() >= m * 10.0 {
                            return ControlFlow::Break(Vec3A::ZERO);
                        }
                        tr /= m * 10.0;
                    }
                    ControlFlow::Continue(())
                });
                end.unwrap_or(tr)
            }
        }
    }

    /// Moves the medium with the scene it is in, placed by `to_world`
    /// whose scale is `s` (a similarity's; coefficients are per unit
    /// length, so they divide by it).
    pub fn transform(&mut self, to_world: Affine3A, s: f32) {
        match self {
            Medium::Homogeneous(h) => {
                h.sigma_t /= s;
                h.sigma_s /= s;
                // (The box of the corners moved: exact for the placements
                // without rotation that bounded media get.)
                if let Some((lo, hi)) = h.bounds {
                    h.bounds = Some(grid::world_box(lo, hi, to_world));
                }
            }
            Medium::Heterogeneous(h) => {
                h.scale /= s;
                h.sigma_t.transform(to_world);
                h.albedo.transform(to_world);
                if let Some(e) = &mut h.emission {
                    e.transform(to_world);
                }
            }
        }
    }

    /// Why the medium cannot be rendered, if it cannot: a negative or
    /// non-finite coefficient, or more scattering than extinction.
    pub fn check(&self) -> Result<(), String> {
        match self {
            Medium::Homogeneous(h) => {
                let ok = |v: Vec3A| v.is_finite() && v.min_element() >= 0.0;
                if !ok(h.sigma_t) || !ok(h.sigma_s) {
                    return Err(format!(
                        "medium coefficients must be finite and >= 0 (sigma_t {:?}, sigma_s {:?})",
                        h.sigma_t.to_array(),
                        h.sigma_s.to_array()
                    ));
                }
                if h.sigma_s.cmpgt(h.sigma_t * 1.000_001).any() {
                    return Err("a medium's albedo must be at most 1".into());
                }
                if !ok(h.emission) {
                    return Err(format!(
                        "a medium's emission must be finite and >= 0 (got {:?})",
                        h.emission.to_array()
                    ));
                }
                if let Phase::HenyeyGreenstein { g } = h.phase
                    && (g.is_nan() || g.abs() > phase::MAX_G)
                {
                    return Err(format!(
                        "a Henyey-Greenstein phase function needs |g| <= {} (got {g})",
                        phase::MAX_G
                    ));
                }
                Ok(())
            }
            Medium::Heterogeneous(h) => {
                if !(h.scale.is_finite() && h.scale >= 0.0) {
                    return Err(format!(
                        "a medium's scale must be finite and >= 0 (got {})",
                        h.scale
                    ));
                }
                if h.albedo.max() > 1.000_001 {
                    return Err("a medium's albedo must be at most 1".into());
                }
                if !h.majorant().is_finite() {
                    return Err("a medium's extinction must be finite".into());
                }
                h.emission.as_ref().map_or(Ok(()), Emission::check)
            }
        }
    }
}

/// `exp(−σ t)` per channel, 1 where `σ` is 0 (also for infinite `t`).
#[inline]
fn transmit(sigma_t: Vec3A, t: f32) -> Vec3A {
    let tr = (-sigma_t * t).exp();
    Vec3A::select(sigma_t.cmpeq(Vec3A::ZERO), Vec3A::ONE, tr)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::sampler::Rng;

    fn ray() -> Ray {
        Ray::new(Vec3A::new(0.1, 0.2, 0.3), Vec3A::new(0.6, 0.0, 0.8))
    }

    /// The flight's weights are unbiased: over a segment of length `L`, the
    /// mean of `Pass` weights (times their share) is `T(L)`, and the mean
    /// of `f(t)·weight` over scatters is `∫₀ᴸ σs T(t) f(t) dt` for a test
    /// function `f`; per channel, for a chromatic medium with one channel
    /// of zero extinction.
    #[test]
    fn flights_estimate_transmittance_and_scattering() {
        let m = Medium::homogeneous(
            Vec3A::new(2.0, 0.5, 0.0),
            Vec3A::new(0.9, 0.3, 1.0),
            Phase::Isotropic,
        );
        let Medium::Homogeneous(h) = m.clone() else {
            unreachable!()
        };
        let l = 1.3f32;
        let f = |t: f32| 1.0 + t * t;
        let n = 2_000_000u32;
        let mut rng = Rng::new(11, 0);
        // (Summed in f64: two million f32 additions would lose digits.)
        let (mut pass, mut scatter) = (glam::DVec3::ZERO, glam::DVec3::ZERO);
        for _ in 0..n {
            match m.sample_flight(&ray(), l, &mut || rng.next_f32()) {
                Flight::Pass { weight, .. } => pass += weight.as_dvec3(),
                Flight::Scatter { t, weight, .. } => {
                    assert!(t < l);
                    scatter += (weight * f(t)).as_dvec3()
                }
            }
        }
        let (pass, scatter) = (
            (pass / f64::from(n)).as_vec3a(),
            (scatter / f64::from(n)).as_vec3a(),
        );
        // ∫₀ᴸ σs e^{−σt t} (1 + t²) dt by the midpoint rule.
        let steps = 100_000;
        let mut want = Vec3A::ZERO;
        for i in 0..steps {
            let t = (i as f32 + 0.5) * l / steps as f32;
            want += h.sigma_s * (-h.sigma_t * t).exp() * f(t) * (l / steps as f32);
        }
        let tr = m.transmittance(&ray(), l, &mut || 0.5);
        assert_eq!(tr.z, 1.0);
        for c in 0..3 {
            assert!((pass[c] - tr[c]).abs() < 2e-3, "pass {pass:?} vs T {tr:?}");
            assert!(
                (scatter[c] - want[c]).abs() < 3e-3 * want[c].max(0.1),
                "scatter {scatter:?} vs {want:?}"
            );
        }
    }

    /// A segment to infinity in a medium with some clear channel: only
    /// that channel's light gets through, with weight 1 in expectation.
    #[test]
    fn an_infinite_flight_keeps_only_the_clear_channels() {
        let m = Medium::homogeneous(Vec3A::new(1.0, 0.0, 1.0), Vec3A::ZERO, Phase::Isotropic);
        assert_eq!(
            m.transmittance(&ray(), f32::INFINITY, &mut || 0.5),
            Vec3A::new(0.0, 1.0, 0.0)
        );
        let mut rng = Rng::new(3, 0);
        let n = 300_000;
        let mut pass = Vec3A::ZERO;
        for _ in 0..n {
            if let Flight::Pass { weight, .. } =
                m.sample_flight(&ray(), f32::INFINITY, &mut || rng.next_f32())
            {
                assert!(weight.is_finite());
                pass += weight;
            }
        }
        let pass = pass / n as f32;
        assert!(
            pass.x == 0.0 && pass.z == 0.0 && (pass.y - 1.0).abs() < 1e-2,
            "{pass:?}"
        );
    }

    /// Delta and ratio tracking through a majorant grid (a sparse-ish
    /// random grid placed without rotation) are unbiased: their mean
    /// transmittance along rays matches `exp(−∫σt)` by quadrature.
    #[test]
    fn tracking_through_majorant_cells_is_unbiased() {
        let grid = std::sync::Arc::new(grid::random_grid([9, 6, 7], 17, 0.6, 3.0));
        let to_world = grid_placement();
        let field = |values| Field::new(values, to_world);
        let sigma_t = field(FieldValues::Grid {
            grid,
            nearest: false,
        });
        assert!(sigma_t.majorants.is_some());
        let m = Medium::Heterogeneous(Box::new(Heterogeneous {
            sigma_t: sigma_t.clone(),
            albedo: field(FieldValues::Constant(Vec3A::splat(0.5))),
            scale: 1.0,
            phase: Phase::Isotropic,
            sample_emitters: true,
            emission: None,
        }));
        let mut rng = Rng::new(5, 0);
        for r in 0..4 {
            let origin = Vec3A::new(-2.0, -0.3 + 0.2 * r as f32, -0.2);
            let ray = Ray::new(origin, Vec3A::new(1.0, 0.1, 0.15 * r as f32).normalize());
            let l = 4.0;
            let steps = 20_000;
            // (The medium ends at the field's box; lookups beyond it clamp.)
            let (lo, hi) = sigma_t.bounds;
            let depth: f32 = (0..steps)
                .map(|i| ray.origin + ray.dir * ((i as f32 + 0.5) * l / steps as f32))
                .filter(|p| p.cmpge(lo).all() && p.cmple(hi).all())
                .map(|p| sigma_t.eval(p).x)
                .sum::<f32>()
                * l
                / steps as f32;
            let want = (-depth).exp();
            let runs = 200_000;
            let (mut ratio, mut pass) = (0.0f64, 0.0f64);
            for _ in 0..runs {
                ratio += f64::from(m.transmittance(&ray, l, &mut || rng.next_f32()).x);
                if let Flight::Pass { weight, .. } =
                    m.sample_flight(&ray, l, &mut || rng.next_f32())
                {
                    pass += f64::from(weight.x);
                }
            }
            let (ratio, pass) = (ratio / runs as f64, pass / runs as f64);
            assert!(
                (ratio - f64::from(want)).abs() < 4e-3,
                "ray {r}: ratio {ratio} vs {want}"
            );
            assert!(
                (pass - f64::from(want)).abs() < 4e-3,
                "ray {r}: delta {pass} vs {want}"
            );
        }
    }

    /// `∫₀ᴸ T(t) σa(t) Le(t) dt` per channel along `ray` through `m` (a
    /// heterogeneous medium), by the midpoint rule in f64.
    fn emitted_by_quadrature(m: &Heterogeneous, ray: &Ray, l: f32) -> glam::DVec3 {
        let steps = 40_000;
        let dt = f64::from(l) / f64::from(steps);
        let (lo, hi) = m.sigma_t.bounds;
        let (mut depth, mut sum) = (glam::DVec3::ZERO, glam::DVec3::ZERO);
        for i in 0..steps {
            let p = ray.origin + ray.dir * ((i as f32 + 0.5) * l / steps as f32);
            if !(p.cmpge(lo).all() && p.cmple(hi).all()) {
                continue;
            }
            let sigma_t = (m.scale * m.sigma_t.eval(p)).as_dvec3();
            let sigma_a = sigma_t * (glam::DVec3::ONE - m.albedo.eval(p).as_dvec3());
            let le = m.emission.as_ref().unwrap().eval(p).as_dvec3();
            // (T at the step's middle: half its own depth.)
            let tr = (-(depth + 0.5 * sigma_t * dt)).exp();
            sum += tr * sigma_a * le * dt;
            depth += sigma_t * dt;
        }
        sum
    }

    /// A homogeneous medium's emission along a flight is exact:
    /// `σa Le (1 − e^{−σt L}) / σt` per channel, in a chromatic medium with
    /// a clear channel (which emits nothing), on every flight; and the
    /// segment to infinity gives the thick medium's `σa/σt Le`.
    #[test]
    fn homogeneous_emission_is_the_exact_integral() {
        let mut m = Medium::homogeneous(
            Vec3A::new(2.0, 0.5, 0.0),
            Vec3A::new(0.25, 0.5, 1.0),
            Phase::Isotropic,
        );
        let Medium::Homogeneous(h) = &mut m else {
            unreachable!()
        };
        h.emission = Vec3A::new(3.0, 2.0, 5.0);
        let l = 1.3f32;
        let mut rng = Rng::new(1, 0);
        for _ in 0..100 {
            let e = m.sample_flight(&ray(), l, &mut || rng.next_f32()).emitted();
            let want = [
                0.75 * 3.0 * (1.0 - (-2.6f32).exp()),
                0.5 * 2.0 * (1.0 - (-0.65f32).exp()),
                0.0,
            ];
            for c in 0..3 {
                assert!((e[c] - want[c]).abs() < 1e-5, "{e:?} vs {want:?}");
            }
        }
        let thick = m
            .sample_flight(&ray(), f32::INFINITY, &mut || rng.next_f32())
            .emitted();
        assert!((thick - Vec3A::new(2.25, 1.0, 0.0)).abs().max_element() < 1e-6);
    }

    /// Where the tests' random grids sit: a 2 × 1 × 1.5 box from
    /// (−1, −0.5, −0.75), without rotation (so with a majorant grid).
    fn grid_placement() -> Affine3A {
        Affine3A::from_scale_rotation_translation(
            glam::Vec3::new(2.0, 1.0, 1.5),
            glam::Quat::IDENTITY,
            glam::Vec3::new(-1.0, -0.5, -0.75),
        )
    }

    /// Three random grids (with empty cells, of peaks 3, 1 and 4) as the
    /// three channels of one: an extinction whose channels differ
    /// everywhere.
    fn chromatic_grid(n: [u32; 3]) -> Grid {
        let grid = |seed: u32, empty, scale| grid::random_grid(n, seed, empty, scale);
        let (r, g, b) = (grid(17, 0.4, 3.0), grid(19, 0.3, 1.0), grid(21, 0.4, 4.0));
        let mut rgb = Vec::new();
        for z in 0..n[2] {
            for y in 0..n[1] {
                for x in 0..n[0] {
                    rgb.extend([
                        r.sample(x, y, z).x,
                        g.sample(x, y, z).x,
                        b.sample(x, y, z).x,
                    ]);
                }
            }
        }
        Grid::new(n, 3, rgb).unwrap()
    }

    /// Delta tracking with spectral MIS through a chromatic grid is
    /// unbiased per channel, and its weights stay bounded: the mean `Pass`
    /// weight is the transmittance `exp(−∫σt)` and the mean of
    /// `f(t)·weight` over scatters is `∫ σs T f dt` (both by quadrature,
    /// within four standard errors plus 0.3 %), and no channel's weight
    /// exceeds 3 (Mitsuba's per-collision `σn/mean(σn)` compounds past it).
    #[test]
    fn chromatic_flights_are_unbiased_with_bounded_weights() {
        let to_world = grid_placement();
        let values = FieldValues::Grid {
            grid: std::sync::Arc::new(chromatic_grid([9, 6, 7])),
            nearest: false,
        };
        let sigma_t = Field::new(values, to_world);
        assert!(!sigma_t.is_grey());
        let albedo = Vec3A::new(0.9, 0.5, 0.7);
        let m = Medium::Heterogeneous(Box::new(Heterogeneous {
            sigma_t: sigma_t.clone(),
            albedo: Field::new(FieldValues::Constant(albedo), Affine3A::IDENTITY),
            scale: 1.0,
            phase: Phase::Isotropic,
            sample_emitters: true,
            emission: None,
        }));
        let f = |t: f32| 1.0 + t * t;
        let mut rng = Rng::new(13, 0);
        let mut largest = 0.0f32;
        for r in 0..3 {
            let origin = Vec3A::new(-2.0, -0.3 + 0.25 * r as f32, -0.2);
            let ray = Ray::new(origin, Vec3A::new(1.0, 0.1, 0.15 * r as f32).normalize());
            let l = 4.0f32;
            // T and ∫ σs T f by the midpoint rule (f64; σt is 0 outside
            // the field's box).
            let (lo, hi) = sigma_t.bounds;
            let steps = 40_000;
            let dt = f64::from(l) / f64::from(steps);
            let (mut depth, mut want_scatter) = (glam::DVec3::ZERO, glam::DVec3::ZERO);
            for i in 0..steps {
                let t = (f64::from(i) + 0.5) * dt;
                let p = ray.origin + ray.dir * t as f32;
                let s = if p.cmpge(lo).all() && p.cmple(hi).all() {
                    sigma_t.eval(p).as_dvec3()
                } else {
                    glam::DVec3::ZERO
                };
                let tr = (-(depth + s * dt / 2.0)).exp();
                want_scatter += s * albedo.as_dvec3() * tr * f64::from(f(t as f32)) * dt;
                depth += s * dt;
            }
            let want_pass = (-depth).exp();
            let runs = 400_000;
            let (mut pass, mut pass_sq) = (glam::DVec3::ZERO, glam::DVec3::ZERO);
            let (mut scatter, mut scatter_sq) = (glam::DVec3::ZERO, glam::DVec3::ZERO);
            for _ in 0..runs {
                match m.sample_flight(&ray, l, &mut || rng.next_f32()) {
                    Flight::Pass { weight, .. } => {
                        largest = largest.max(weight.max_element());
                        let w = weight.as_dvec3();
                        pass += w;
                        pass_sq += w * w;
                    }
                    Flight::Scatter { t, weight, .. } => {
                        assert!(t < l);
                        largest = largest.max((weight / albedo).max_element());
                        let w = (weight * f(t)).as_dvec3();
                        scatter += w;
                        scatter_sq += w * w;
                    }
                }
            }
            let n = f64::from(runs);
            for (sum, sq, want, what) in [
                (pass, pass_sq, want_pass, "pass"),
                (scatter, scatter_sq, want_scatter, "scatter"),
            ] {
                let got = sum / n;
                let se = ((sq / n - got * got) / n).map(f64::sqrt);
                for c in 0..3 {
                    assert!(
                        (got[c] - want[c]).abs() <= 4.0 * se[c] + 3e-3 * want[c],
                        "ray {r}, {what}: {got} vs quadrature {want} (standard errors {se})"
                    );
                }
            }
        }
        assert!(largest <= 3.0 * (1.0 + 1e-5), "a weight of {largest}");
        assert!(largest > 1.5, "the channels' weights differ ({largest})");
    }

    /// Delta tracking's collision estimator of a heterogeneous medium's
    /// emission is unbiased: over a random grid of chromatic extinction
    /// (empty cells, a majorant grid, null weights other than 1), a
    /// chromatic albedo and a grid of emitted radiance, the mean `emitted`
    /// of many flights matches the quadrature of `∫ T σa Le` per channel
    /// within four standard errors (and 0.3 % of the quadrature for its own
    /// error), also for a blackbody temperature field.
    #[test]
    fn heterogeneous_emission_is_unbiased() {
        let to_world = grid_placement();
        let n = [9, 6, 7];
        let grid = |seed: u32, empty, scale| grid::random_grid(n, seed, empty, scale);
        let field = |g: Grid| {
            Field::new(
                FieldValues::Grid {
                    grid: std::sync::Arc::new(g),
                    nearest: false,
                },
                to_world,
            )
        };
        let sigma_t = field(chromatic_grid(n));
        let constant = |c| Field::new(FieldValues::Constant(c), Affine3A::IDENTITY);
        for emission in [
            Emission::Radiance {
                le: field(grid(23, 0.0, 2.0)),
                scale: 1.5,
            },
            Emission::Temperature {
                temperature: field(grid(29, 0.0, 3000.0)),
                offset: 200.0,
                t_scale: 1.2,
                scale: 4.0,
            },
        ] {
            let m = Heterogeneous {
                sigma_t: sigma_t.clone(),
                albedo: constant(Vec3A::new(0.2, 0.5, 0.9)),
                scale: 1.0,
                phase: Phase::Isotropic,
                sample_emitters: true,
                emission: Some(emission),
            };
            let medium = Medium::Heterogeneous(Box::new(m.clone()));
            let mut rng = Rng::new(9, 0);
            for r in 0..3 {
                let origin = Vec3A::new(-2.0, -0.3 + 0.25 * r as f32, -0.2);
                let ray = Ray::new(origin, Vec3A::new(1.0, 0.1, 0.15 * r as f32).normalize());
                let l = 4.0;
                let want = emitted_by_quadrature(&m, &ray, l);
                let runs = 200_000;
                let (mut sum, mut sq) = (glam::DVec3::ZERO, glam::DVec3::ZERO);
                for _ in 0..runs {
                    let f = medium.sample_flight(&ray, l, &mut || rng.next_f32());
                    let e = f.emitted().as_dvec3();
                    sum += e;
                    sq += e * e;
                }
                let got = sum / f64::from(runs);
                let se = ((sq / f64::from(runs) - got * got) / f64::from(runs)).map(f64::sqrt);
                for c in 0..3 {
                    assert!(
                        (got[c] - want[c]).abs() <= 4.0 * se[c] + 3e-3 * want[c],
                        "ray {r}: emitted {got} vs quadrature {want} (standard errors {se})"
                    );
                    assert!(want[c] > 0.0);
                }
            }
        }
    }

    #[test]
    fn bad_coefficients_are_refused() {
        let bad = Medium::homogeneous(Vec3A::new(-1.0, 0.0, 0.0), Vec3A::ONE, Phase::Isotropic);
        assert!(bad.check().is_err());
        let nan = Medium::homogeneous(Vec3A::splat(f32::NAN), Vec3A::ONE, Phase::Isotropic);
        assert!(nan.check().is_err());
        let bright = Medium::homogeneous(Vec3A::ONE, Vec3A::splat(1.5), Phase::Isotropic);
        assert!(bright.check().is_err());
        let g = Medium::homogeneous(Vec3A::ONE, Vec3A::ONE, Phase::HenyeyGreenstein { g: 1.0 });
        assert!(g.check().is_err());
        let ok = Medium::homogeneous(Vec3A::ONE, Vec3A::ONE, Phase::HenyeyGreenstein { g: 0.7 });
        assert!(ok.check().is_ok());
    }
}
