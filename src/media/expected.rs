//! What a medium does to the light along a ray in expectation, without
//! random numbers: the fraction that crosses it, the albedo a path finds
//! where it first scatters in it, and the light it emits towards the ray's
//! origin. The denoiser's guides see media through these
//! (`crate::aov::guides`): Cycles gives its denoiser a volume's albedo where
//! a path first scatters, from one sample and so with noise; this is that
//! albedo's mean, so the guides stay free of noise.
//!
//! Homogeneous media in closed form. Heterogeneous ones by the midpoint rule
//! (each step's coefficients taken as constant over it) over the cells of
//! the majorant grid the ray crosses, skipping empty ones, in steps of
//! optical depth at most [`STEP_DEPTH`] against each cell's bound, until the
//! light left is below [`OPAQUE`]: a guide needs the picture, not the last
//! digit, and the same point always gets the same guide.

use glam::Vec3A;

use super::{Heterogeneous, Homogeneous, Medium, transmit};
use crate::geometry::ray::Ray;

/// The optical depth (against the majorant) of a step of the midpoint rule
/// in a heterogeneous medium.
pub const STEP_DEPTH: f32 = 2.0;

/// The most steps a stretch of constant majorant takes (a medium without a
/// majorant grid is one stretch).
pub const MAX_STEPS: u32 = 16;

/// The transmittance below which the rest of a heterogeneous medium is not
/// looked at (it could add at most this much).
pub const OPAQUE: f32 = 1e-3;

/// A medium's effect along a ray in expectation ([module docs](self)).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Expected {
    /// The fraction of light that crosses it, per channel.
    pub transmittance: Vec3A,
    /// `∫ T σs dt`: the chance of scattering in it times the albedo there,
    /// per channel (a homogeneous medium's `(1 − T) σs/σt`).
    pub scattered: Vec3A,
    /// `∫ T σa Le dt`: the radiance it emits along the ray.
    pub emitted: Vec3A,
}

impl Expected {
    /// Nothing in the way.
    pub const CLEAR: Expected = Expected {
        transmittance: Vec3A::ONE,
        scattered: Vec3A::ZERO,
        emitted: Vec3A::ZERO,
    };
}

/// What `medium` does along `ray` (unit direction) from its origin to
/// `t_max` ([`Expected`]); [`Expected::CLEAR`] for a subsurface medium,
/// whose walk shows through the surface's own guides.
pub fn along(medium: &Medium, ray: &Ray, t_max: f32) -> Expected {
    match medium {
        Medium::Homogeneous(h) if !h.random_walk => homogeneous(h, ray, t_max),
        Medium::Homogeneous(_) => Expected::CLEAR,
        Medium::Heterogeneous(h) => heterogeneous(h, ray, t_max),
    }
}

fn homogeneous(h: &Homogeneous, ray: &Ray, t_max: f32) -> Expected {
    let Some((t0, t1)) = h.span(ray, t_max) else {
        return Expected::CLEAR;
    };
    let tr = transmit(h.sigma_t, t1 - t0);
    let scattered = Vec3A::select(
        h.sigma_t.cmpgt(Vec3A::ZERO),
        h.sigma_s / h.sigma_t * (Vec3A::ONE - tr),
        Vec3A::ZERO,
    );
    Expected {
        transmittance: tr,
        scattered,
        emitted: h.emitted_along(t1 - t0),
    }
}

fn heterogeneous(h: &Heterogeneous, ray: &Ray, t_max: f32) -> Expected {
    let Some((t0, t1)) = h.span(ray, t_max) else {
        return Expected::CLEAR;
    };
    let mut e = Expected::CLEAR;
    // The stretches of the majorant grid (or the whole span): empty ones
    // cost nothing, the others steps of optical depth at most STEP_DEPTH
    // against their bound (at most MAX_STEPS).
    for (ta, tb, m) in h.walk(ray, t0, t1) {
        let mu = h.scale * m;
        if mu.is_nan() || mu <= 0.0 || tb <= ta {
            continue;
        }
        let n = ((tb - ta) * mu / STEP_DEPTH)
            .ceil()
            .clamp(1.0, MAX_STEPS as f32) as u32;
        let dt = (tb - ta) / n as f32;
        for i in 0..n {
            let p = ray.origin + ray.dir * (ta + (i as f32 + 0.5) * dt);
            let sigma_t = h.scale * h.sigma_t.eval(p);
            let step = transmit(sigma_t, dt);
            // Of the light entering the step, `1 − step` collides in it:
            // with the albedo it scatters, the rest is absorbed (and emits).
            let collides = e.transmittance * (Vec3A::ONE - step);
            let albedo = h.albedo.eval(p).clamp(Vec3A::ZERO, Vec3A::ONE);
            e.scattered += collides * albedo;
            if let Some(emission) = &h.emission {
                e.emitted += collides * (Vec3A::ONE - albedo) * emission.eval(p);
            }
            e.transmittance *= step;
            if e.transmittance.max_element() < OPAQUE {
                return e;
            }
        }
    }
    e
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::media::{Field, FieldValues, Phase};
    use glam::Affine3A;

    fn ray() -> Ray {
        Ray::new(Vec3A::new(-2.0, 0.1, 0.2), Vec3A::X)
    }

    /// A homogeneous medium: `T = e^{−σt L}`, `(1 − T) a`, `(1 − T)(1 − a)
    /// Le`, and a constant grid of the same coefficients gives the same
    /// within the midpoint rule's rounding; what crosses, scatters and is
    /// absorbed adds up to one.
    #[test]
    fn expectations_are_the_closed_forms() {
        let sigma_t = Vec3A::new(0.5, 1.0, 2.0);
        let albedo = Vec3A::new(0.9, 0.5, 0.2);
        let le = Vec3A::new(1.0, 2.0, 3.0);
        let Medium::Homogeneous(mut h) = Medium::homogeneous(sigma_t, albedo, Phase::Isotropic)
        else {
            unreachable!()
        };
        h.emission = le;
        h.bounds = Some((Vec3A::splat(-1.0), Vec3A::splat(1.0)));
        let e = along(&Medium::Homogeneous(h), &ray(), 10.0);
        // The ray crosses the box from x = −1 to 1.
        let tr = (-sigma_t * 2.0).exp();
        for (got, want) in [
            (e.transmittance, tr),
            (e.scattered, (Vec3A::ONE - tr) * albedo),
            (e.emitted, (Vec3A::ONE - tr) * (Vec3A::ONE - albedo) * le),
        ] {
            assert!((got - want).abs().max_element() < 1e-5, "{got} vs {want}");
        }
        let constant = |v| Field::new(FieldValues::Constant(v), Affine3A::IDENTITY);
        let mut sigma = constant(sigma_t);
        sigma.bounds = (Vec3A::splat(-1.0), Vec3A::splat(1.0));
        let grid = Medium::Heterogeneous(Box::new(Heterogeneous {
            sigma_t: sigma,
            albedo: constant(albedo),
            scale: 1.0,
            phase: Phase::Isotropic,
            sample_emitters: true,
            emission: Some(crate::media::Emission::Radiance {
                le: constant(le),
                scale: 1.0,
            }),
        }));
        let g = along(&grid, &ray(), 10.0);
        for (got, want) in [
            (g.transmittance, e.transmittance),
            (g.scattered, e.scattered),
            (g.emitted, e.emitted),
        ] {
            assert!((got - want).abs().max_element() < 1e-4, "{got} vs {want}");
        }
        let absorbed = (Vec3A::ONE - tr) * (Vec3A::ONE - albedo);
        let total = g.transmittance + g.scattered + absorbed;
        assert!((total - Vec3A::ONE).abs().max_element() < 1e-4, "{total}");
        // A ray that stops inside the box sees half the depth.
        let half = along(&Medium::Homogeneous(h), &ray(), 2.0);
        assert!((half.transmittance - (-sigma_t).exp()).abs().max_element() < 1e-5);
        // A subsurface medium is left to its surface's guides.
        let skin = Medium::subsurface(sigma_t, albedo, 0.0);
        assert_eq!(along(&skin, &ray(), 10.0), Expected::CLEAR);
    }
}
