//! Light from points scattered along a ray in a homogeneous medium
//! ([`Segment`]): the stretch of a ray in the medium chooses one of the
//! scene's lights at points ([`Scene::positional_lights`]) by what it can
//! send into the stretch, and a point on the stretch by equiangular sampling
//! towards it ([`crate::sampling::equiangular`]). Point lights' `1/r²` then
//! no longer shows as speckles in fog, which free-flight sampling alone
//! leaves near every light.
//!
//! This is a second strategy beside next-event estimation at the point where
//! the flight collides (free-flight distance, light chosen there by the
//! scene's selection); both are weighed by the power heuristic over the
//! joint density of light and point each gives, so the two together are
//! unbiased and each takes over where it is better: equiangular near the
//! light, free flight where the medium's attenuation matters more than the
//! light's distance.

use glam::Vec3A;

use crate::geometry::ray::Ray;
use crate::media::Homogeneous;
use crate::sampling::equiangular;
use crate::scene::{PositionalLight, Scene};

/// The most lights a stretch weighs one by one; with more they are chosen
/// uniformly (each weighing is a loop over them).
const MAX_WEIGHED: usize = crate::scene::MAX_IMPORTANCE_LIGHTS;

/// The stretch `[t0, t1]` of a ray in a homogeneous medium and the choice
/// among the lights at points it makes.
#[derive(Clone, Copy, Debug)]
pub(super) struct Segment {
    /// The ray's origin and unit direction.
    pub origin: Vec3A,
    /// Unit direction.
    pub dir: Vec3A,
    /// Where the ray enters the medium.
    pub t0: f32,
    /// Where it leaves it (the next surface, the medium's box; may be
    /// infinite).
    pub t1: f32,
    /// The sum of the lights' weights ([`Segment::weight`]); 0: chosen
    /// uniformly.
    total: f32,
}

impl Segment {
    /// The stretch `[t0, t1]` of `ray`, if some light at a point can send
    /// light into it.
    #[inline]
    pub fn new(scene: &Scene, ray: &Ray, t0: f32, t1: f32) -> Option<Self> {
        let lights = scene.positional_lights();
        if lights.is_empty() || t1.is_nan() || t1 <= t0 {
            return None;
        }
        let mut segment = Self {
            origin: ray.origin,
            dir: ray.dir,
            t0,
            t1,
            total: 0.0,
        };
        if lights.len() <= MAX_WEIGHED {
            segment.total = lights.iter().map(|l| segment.weight(l)).sum();
            if !(segment.total > 0.0 && segment.total.is_finite()) {
                return None;
            }
        }
        Some(segment)
    }

    /// What light `l` can send into the stretch: its greatest intensity times
    /// `∫ dt / r²` over it.
    #[inline]
    fn weight(&self, l: &PositionalLight) -> f32 {
        let w = l.intensity
            * equiangular::inverse_square_integral(
                l.position,
                self.origin,
                self.dir,
                self.t0,
                self.t1,
            );
        if w.is_finite() { w } else { 0.0 }
    }

    /// A light chosen with `u` in `[0, 1)` and the probability of that
    /// choice.
    #[inline]
    pub fn choose<'s>(&self, scene: &'s Scene, u: f32) -> Option<(&'s PositionalLight, f32)> {
        let lights = scene.positional_lights();
        if self.total == 0.0 {
            let k = ((u * lights.len() as f32) as usize).min(lights.len() - 1);
            return Some((&lights[k], 1.0 / lights.len() as f32));
        }
        let target = u * self.total;
        let mut run = 0.0;
        let mut last = None;
        for l in lights {
            let w = self.weight(l);
            if w <= 0.0 {
                continue;
            }
            run += w;
            last = Some((l, w));
            if target < run {
                break;
            }
        }
        last.map(|(l, w)| (l, w / self.total))
    }

    /// The probability that [`Segment::choose`] picks light `light`
    /// ([`PositionalLight::light`]).
    #[inline]
    pub fn pmf(&self, scene: &Scene, light: u32) -> f32 {
        let lights = scene.positional_lights();
        let Some(l) = lights.iter().find(|l| l.light == light) else {
            return 0.0;
        };
        if self.total == 0.0 {
            return 1.0 / lights.len() as f32;
        }
        self.weight(l) / self.total
    }

    /// The density of the point at `t` under this strategy for the light at
    /// `position`, chosen with probability `pmf`.
    #[inline]
    pub fn pdf(&self, pmf: f32, position: Vec3A, t: f32) -> f32 {
        pmf * equiangular::pdf(position, self.origin, self.dir, self.t0, self.t1, t)
    }

    /// The density with which free flight in `medium` stops at `t` and the
    /// scene's light selection there picks light `light`: the other
    /// strategy's joint density.
    #[inline]
    pub fn flight_pdf(&self, scene: &Scene, medium: &Homogeneous, light: u32, t: f32) -> f32 {
        let p = self.origin + self.dir * t;
        medium.flight_pdf(self.t0, t) * scene.point_light_pmf(light, p)
    }
}
