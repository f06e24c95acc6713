//! Subsurface scattering as a random walk (Cycles' "Random Walk"): a path
//! that enters a subsurface medium ([`crate::media::Medium::subsurface`])
//! scatters inside it until it reaches a surface again, where the
//! volumetric path tracer ([`super::volume`]) shades the boundary from
//! within as any other hit (for a diffusely transmitting glTF boundary: out
//! by a Lambertian lobe, or back in for another walk).
//!
//! It is the volumetric path tracer's scattering with three differences,
//! which make dense media (thousands of collisions per metre, albedos near
//! 1) affordable and well-behaved:
//! - **No light samples** inside: the boundary is opaque to shadow rays, so
//!   they could only be blocked. Emission a walk reaches (a light inside
//!   the object) counts in full.
//! - **Collisions are not bounces.** `max_depth` counts the path's surface
//!   vertices; a walk ends at [`MAX_WALK_STEPS`] collisions (Cycles stops at
//!   256) or by Russian roulette on its throughput.
//! - **One channel per walk.** The channel whose extinction draws every
//!   distance of the walk is chosen once, uniformly, and the walk's value is
//!   weighed by the balance heuristic over the three channels' pdfs of the
//!   *whole* walk (Miller, Georgiev and Jarosz 2019, as Cycles' walk and
//!   Mitsuba's `volpathmis` do): per-collision weights of a chromatic medium
//!   would multiply into a variance that grows with the walk's length; this
//!   weight is at most 3 / (the chosen channel's share).

use glam::{DVec3, Vec3A};

use super::samples::PathSampler;
use crate::geometry::ray::{Hit, Ray};
use crate::media::Homogeneous;
use crate::scene::Scene;

/// The most collisions a walk makes; one that would make more is lost (its
/// light is missing from the image). The white furnace of
/// `tests/subsurface.rs`, a box 8 mean free paths across that absorbs
/// nothing, loses no measurable light (0.9998 ± 0.0013 of the sky).
pub const MAX_WALK_STEPS: u32 = 1024;

/// Collisions before Russian roulette may end a walk.
const WALK_RR_STEPS: u32 = 16;

/// The end of a walk that reached a surface.
#[derive(Clone, Copy, Debug)]
pub(super) struct WalkExit {
    /// The last segment of the walk, which ends at `hit`.
    pub ray: Ray,
    /// The surface reached.
    pub hit: Hit,
    /// The walk's weight (what multiplies the path's throughput).
    pub weight: Vec3A,
    /// Whether the walk collided at all (else it went straight across and
    /// the last surface vertex's light sampling still applies).
    pub scattered: bool,
}

/// Walks through `medium` from `ray` (in it; `hit` its closest hit) until a
/// surface is reached; `None` if the walk is lost (absorbed by roulette,
/// longer than [`MAX_WALK_STEPS`], or leaving the scene: an open object).
/// Counts the rays it casts.
pub(super) fn walk(
    scene: &Scene,
    medium: &Homogeneous,
    mut ray: Ray,
    mut hit: Option<Hit>,
    sampler: &mut impl PathSampler,
    rays: &mut u64,
) -> Option<WalkExit> {
    let hero = ((sampler.next_1d() * 3.0) as usize).min(2);
    let sigma_t = DVec3::from(medium.sigma_t.to_array().map(f64::from));
    let sigma_s = DVec3::from(medium.sigma_s.to_array().map(f64::from));
    let sigma = sigma_t[hero];
    // The walk's value and its pdf under each channel's distances, both
    // divided by the chosen channel's pdf after every step (their ratio is
    // what counts; this keeps them in range over long walks).
    let mut f = DVec3::ONE;
    let mut pdf = DVec3::ONE;
    let phase = medium.phase;
    for step in 0..MAX_WALK_STEPS {
        let t_surface = hit.map_or(f64::INFINITY, |h| f64::from(h.t));
        let u = f64::from(sampler.next_1d());
        let t = if sigma > 0.0 {
            -(1.0 - u).ln() / sigma
        } else {
            f64::INFINITY
        };
        if t >= t_surface {
            let hit = hit?;
            let tr = (-sigma_t * t_surface).exp();
            f *= tr;
            pdf *= tr;
            let weight = f / (pdf.element_sum() / 3.0);
            if !weight.is_finite() {
                return None;
            }
            return Some(WalkExit {
                ray,
                hit,
                weight: Vec3A::from(weight.as_vec3()),
                scattered: step > 0,
            });
        }
        let tr = (-sigma_t * t).exp();
        f *= sigma_s * tr;
        pdf *= sigma_t * tr;
        let norm = pdf[hero];
        if !(norm > 0.0 && norm.is_finite()) {
            return None;
        }
        f /= norm;
        pdf /= norm;
        if step + 1 >= WALK_RR_STEPS {
            // The walk's value so far, when below 1, is the chance it goes
            // on (pbrt's rule: a walk at full value is never played, or
            // the survivors of hundreds of collisions would carry huge
            // weights).
            let estimate = (f / (pdf.element_sum() / 3.0)).max_element();
            if estimate.is_nan() {
                return None;
            }
            if estimate < 1.0 {
                if f64::from(sampler.next_1d()) >= estimate {
                    return None;
                }
                f /= estimate;
            }
        }
        let p = ray.origin + ray.dir * (t as f32);
        let (dir, _) = phase.sample(ray.dir, sampler.next_2d());
        ray = Ray::new(p, dir);
        *rays += 1;
        hit = scene.intersect(&ray, f32::INFINITY);
    }
    None
}
