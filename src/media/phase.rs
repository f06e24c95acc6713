//! Phase functions: how a medium scatters light, as a distribution of the
//! direction a path leaves a scattering point by. Both are sampled exactly
//! (the sample's weight is 1), so a path through a medium is weighted by its
//! albedo alone.

use std::f32::consts::PI;

use glam::{Vec2, Vec3A};

use crate::materials::Frame;

/// `1/(4π)`.
const INV_FOUR_PI: f32 = 0.25 / PI;

/// A phase function. Directions are travel directions: `d_in` the way the
/// path arrived, `d_out` the way it leaves; `cos θ = d_in · d_out` is 1 for
/// light that goes straight on.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Phase {
    /// Every direction alike: `1/(4π)`.
    Isotropic,
    /// Henyey and Greenstein (1941) with mean cosine `g` in `(−1, 1)`:
    /// `(1 − g²) / (4π (1 + g² − 2g cos θ)^{3/2})`; `g > 0` scatters forwards
    /// (Mitsuba's `hg` and pbrt's convention).
    HenyeyGreenstein {
        /// The mean cosine of the scattering angle.
        g: f32,
    },
}

/// The largest `|g|` a Henyey–Greenstein phase function is given (its peak
/// is `(1+g)/(4π(1−g)²)`: finite).
pub const MAX_G: f32 = 0.999;

impl Phase {
    /// The phase function of mean cosine `g`: isotropic for 0, else
    /// Henyey–Greenstein (`g` clamped to [`MAX_G`]).
    pub fn of_mean_cosine(g: f32) -> Phase {
        if g == 0.0 {
            Phase::Isotropic
        } else {
            Phase::HenyeyGreenstein {
                g: g.clamp(-MAX_G, MAX_G),
            }
        }
    }

    /// The phase function's value for a path arriving along `d_in` and
    /// leaving along `d_out` (both unit), which is also the pdf of
    /// [`Phase::sample`] choosing `d_out`.
    #[inline]
    pub fn eval(self, d_in: Vec3A, d_out: Vec3A) -> f32 {
        match self {
            Phase::Isotropic => INV_FOUR_PI,
            Phase::HenyeyGreenstein { g } => hg(g, d_in.dot(d_out)),
        }
    }

    /// A direction to leave by, for a path arriving along `d_in`, drawn from
    /// the phase function with `u` uniform in `[0, 1)²`, and its pdf (equal
    /// to the value: the sample's weight is 1).
    #[inline]
    pub fn sample(self, d_in: Vec3A, u: Vec2) -> (Vec3A, f32) {
        let cos_theta = match self {
            Phase::Isotropic => 1.0 - 2.0 * u.x,
            Phase::HenyeyGreenstein { g } => hg_cos_theta(g, u.x),
        };
        let sin_theta = (1.0 - cos_theta * cos_theta).max(0.0).sqrt();
        let phi = 2.0 * PI * u.y;
        let local = Vec3A::new(sin_theta * phi.cos(), sin_theta * phi.sin(), cos_theta);
        let d_out = Frame::from_normal(d_in).to_world(local).normalize();
        (d_out, self.eval(d_in, d_out))
    }
}

/// The Henyey–Greenstein phase function at `cos θ`.
#[inline]
fn hg(g: f32, cos_theta: f32) -> f32 {
    let denom = 1.0 + g * g - 2.0 * g * cos_theta;
    INV_FOUR_PI * (1.0 - g * g) / (denom * denom.max(0.0).sqrt())
}

/// The inverse of Henyey–Greenstein's cumulative distribution in `cos θ`
/// at `u`: `cos θ = (1 + g² − ((1 − g²)/(1 − g + 2gu))²) / (2g)`; uniform
/// for `g` near 0, where that form loses its digits.
#[inline]
fn hg_cos_theta(g: f32, u: f32) -> f32 {
    if g.abs() < 1e-3 {
        return 1.0 - 2.0 * u;
    }
    let s = (1.0 - g * g) / (1.0 - g + 2.0 * g * u);
    ((1.0 + g * g - s * s) / (2.0 * g)).clamp(-1.0, 1.0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::sampler::Rng;

    fn phases() -> Vec<Phase> {
        let mut v = vec![Phase::Isotropic];
        for g in [-0.9, -0.5, -0.0005, 0.0, 0.3, 0.8, 0.95] {
            v.push(Phase::HenyeyGreenstein { g });
        }
        v
    }

    /// Each phase function integrates to 1 over the sphere (midpoint rule
    /// in cos θ, fine enough for g = 0.95's peak), and its mean cosine is g.
    #[test]
    fn phase_functions_are_normalised_with_mean_cosine_g() {
        let d_in = Vec3A::new(0.3, -0.5, 0.81).normalize();
        let frame = Frame::from_normal(d_in);
        let n = 200_000;
        for phase in phases() {
            let (mut total, mut mean) = (0.0f64, 0.0f64);
            for i in 0..n {
                let c = -1.0 + 2.0 * (i as f64 + 0.5) / n as f64;
                let s = (1.0 - c * c).sqrt();
                let d_out = frame.to_world(Vec3A::new(s as f32, 0.0, c as f32));
                let f = f64::from(phase.eval(d_in, d_out)) * 2.0 * std::f64::consts::PI * 2.0
                    / n as f64;
                total += f;
                mean += f * c;
            }
            let g = match phase {
                Phase::Isotropic => 0.0,
                Phase::HenyeyGreenstein { g } => f64::from(g),
            };
            assert!((total - 1.0).abs() < 2e-4, "{phase:?}: ∫ = {total}");
            assert!(
                (mean - g).abs() < 2e-4,
                "{phase:?}: mean cos = {mean}, g = {g}"
            );
        }
    }

    /// χ² of the sampled cos θ against the phase function's own
    /// distribution in 64 bins, and φ uniform; the pdf returned is the
    /// value at the direction.
    #[test]
    fn sampling_follows_the_phase_function() {
        let d_in = Vec3A::new(-0.2, 0.9, 0.1).normalize();
        let frame = Frame::from_normal(d_in);
        let n = 400_000;
        let bins = 64;
        for phase in phases() {
            let mut rng = Rng::new(7, 3);
            let mut count = vec![0u32; bins];
            let mut phi_count = vec![0u32; 8];
            for _ in 0..n {
                let (d, pdf) = phase.sample(d_in, Vec2::new(rng.next_f32(), rng.next_f32()));
                assert!((d.length() - 1.0).abs() < 1e-5);
                let want = phase.eval(d_in, d);
                assert!(
                    (pdf - want).abs() <= 1e-5 * want,
                    "{phase:?}: {pdf} vs {want}"
                );
                let c = d.dot(d_in).clamp(-1.0, 1.0);
                count[(((c + 1.0) * 0.5 * bins as f32) as usize).min(bins - 1)] += 1;
                let l = frame.to_local(d);
                let phi = l.y.atan2(l.x) + PI;
                phi_count[((phi / (2.0 * PI) * 8.0) as usize).min(7)] += 1;
            }
            // Expected counts from the phase function integrated over each bin.
            let mut chi2 = 0.0f64;
            let mut dof = 0;
            for (b, &c) in count.iter().enumerate() {
                let sub = 200;
                let mut p = 0.0f64;
                for k in 0..sub {
                    let cos = -1.0 + 2.0 * (b as f64 + (k as f64 + 0.5) / sub as f64) / bins as f64;
                    let s = (1.0 - cos * cos).sqrt();
                    let d = frame.to_world(Vec3A::new(s as f32, 0.0, cos as f32));
                    p += f64::from(phase.eval(d_in, d))
                        * 2.0
                        * std::f64::consts::PI
                        * (2.0 / bins as f64)
                        / sub as f64;
                }
                let e = p * n as f64;
                if e < 5.0 {
                    assert!(f64::from(c) < 30.0, "{phase:?}: bin {b} {c} vs {e}");
                    continue;
                }
                chi2 += (f64::from(c) - e).powi(2) / e;
                dof += 1;
            }
            // χ² with ≤ 63 degrees of freedom: 1e-4 significance is below 120.
            assert!(chi2 < 120.0, "{phase:?}: χ² = {chi2} over {dof} bins");
            for &c in &phi_count {
                let e = n as f64 / 8.0;
                assert!(
                    (f64::from(c) - e).abs() < 5.0 * e.sqrt(),
                    "{phase:?}: φ bins {phi_count:?}"
                );
            }
        }
    }
}
