//! Equiangular sampling (Kulla & Fajardo 2012, "Importance sampling
//! techniques for path tracing in participating media"): a distance `t` along
//! a ray, in `[t0, t1]`, with density proportional to `1/r²`, `r` the
//! distance from the point at `t` to a point `c` (a light). Seen from `c`,
//! the points are spread evenly in angle, so the light's `1/r²` near the ray
//! is divided out exactly.
//!
//! With `Δ` the ray's distance to the foot of the perpendicular from `c` and
//! `h` the length of that perpendicular, `t = Δ + h tan θ` with `θ` uniform
//! between `θ(t0)` and `θ(t1)`; the density is
//! `h / ((θ1 − θ0) (h² + (t − Δ)²))`.

use glam::Vec3A;

/// The foot and height of the perpendicular from `c` to the line
/// `origin + t·dir` (`dir` of unit length), and the angles of `t0` and `t1`
/// seen from `c`; `None` when `c` is on the line or the angles span nothing.
#[inline]
fn frame(c: Vec3A, origin: Vec3A, dir: Vec3A, t0: f32, t1: f32) -> Option<(f32, f32, f32, f32)> {
    let delta = (c - origin).dot(dir);
    let h = (c - (origin + dir * delta)).length();
    if !(h > 0.0 && h.is_finite() && delta.is_finite()) {
        return None;
    }
    let theta0 = (t0 - delta).atan2(h);
    let theta1 = (t1 - delta).atan2(h);
    (theta1 > theta0).then_some((delta, h, theta0, theta1))
}

/// A distance in `[t0, t1]` along the ray `origin + t·dir` (unit `dir`)
/// drawn with `u` in `[0, 1)` with density proportional to the inverse
/// square distance to `c`, and that density; `None` when `c` lies on the
/// ray's line or the stretch is empty. `t1` may be infinite.
#[inline]
pub fn sample(c: Vec3A, origin: Vec3A, dir: Vec3A, t0: f32, t1: f32, u: f32) -> Option<(f32, f32)> {
    let (delta, h, theta0, theta1) = frame(c, origin, dir, t0, t1)?;
    let theta = theta0 + u * (theta1 - theta0);
    // (Clamped: rounding near ±π/2 must not leave the stretch.)
    let t = (delta + h * theta.tan()).clamp(t0, t1.min(f32::MAX));
    let x = t - delta;
    let pdf = h / ((theta1 - theta0) * (h * h + x * x));
    (pdf > 0.0 && pdf.is_finite()).then_some((t, pdf))
}

/// The density with which [`sample`] draws `t` (zero outside `[t0, t1]` or
/// when it cannot draw at all).
#[inline]
pub fn pdf(c: Vec3A, origin: Vec3A, dir: Vec3A, t0: f32, t1: f32, t: f32) -> f32 {
    if !(t >= t0 && t <= t1) {
        return 0.0;
    }
    let Some((delta, h, theta0, theta1)) = frame(c, origin, dir, t0, t1) else {
        return 0.0;
    };
    let x = t - delta;
    let pdf = h / ((theta1 - theta0) * (h * h + x * x));
    if pdf.is_finite() { pdf } else { 0.0 }
}

/// `∫ dt / r²` over `[t0, t1]` for the point `c`: `(θ1 − θ0) / h`, what a
/// light of unit intensity at `c` sends into the stretch (before the
/// medium's attenuation and phase function). Zero when `c` is on the line.
#[inline]
pub fn inverse_square_integral(c: Vec3A, origin: Vec3A, dir: Vec3A, t0: f32, t1: f32) -> f32 {
    frame(c, origin, dir, t0, t1).map_or(0.0, |(_, h, theta0, theta1)| (theta1 - theta0) / h)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::sampler::Rng;

    /// The density integrates to one and matches a histogram of samples (χ²
    /// over 64 bins of equal probability under the density).
    #[test]
    fn samples_follow_the_density() {
        let c = Vec3A::new(0.3, 0.7, -0.2);
        let (o, d) = (
            Vec3A::new(-1.0, 0.0, 0.0),
            Vec3A::new(1.0, 0.2, 0.1).normalize(),
        );
        for (t0, t1) in [(0.0, 3.0), (0.5, 1.2), (0.0, f32::INFINITY)] {
            // The CDF at `t` in closed form: (θ(t) − θ0)/(θ1 − θ0).
            let (delta, h, th0, th1) = frame(c, o, d, t0, t1).unwrap();
            let cdf = |t: f32| ((t - delta).atan2(h) - th0) / (th1 - th0);
            // Integral of the pdf by the midpoint rule on a finite stretch.
            if t1.is_finite() {
                let n = 20_000;
                let dt = (t1 - t0) / n as f32;
                let total: f64 = (0..n)
                    .map(|k| f64::from(pdf(c, o, d, t0, t1, t0 + (k as f32 + 0.5) * dt) * dt))
                    .sum();
                assert!((total - 1.0).abs() < 1e-3, "∫pdf = {total}");
            }
            let bins = 64;
            let n = 64_000;
            let mut counts = vec![0u32; bins];
            let mut rng = Rng::new(7, 1);
            for _ in 0..n {
                let (t, p) = sample(c, o, d, t0, t1, rng.next_f32()).unwrap();
                assert!((p - pdf(c, o, d, t0, t1, t)).abs() <= 1e-4 * p);
                let k = ((cdf(t) * bins as f32) as usize).min(bins - 1);
                counts[k] += 1;
            }
            let expected = n as f64 / bins as f64;
            let chi2: f64 = counts
                .iter()
                .map(|&k| (f64::from(k) - expected).powi(2) / expected)
                .sum();
            // 63 degrees of freedom: the 0.999 quantile is about 103.
            assert!(chi2 < 103.0, "χ² = {chi2} on [{t0}, {t1}]");
        }
    }

    /// The inverse-square integral against the midpoint rule.
    #[test]
    fn the_inverse_square_integral_is_exact() {
        let c = Vec3A::new(0.0, 0.5, 0.0);
        let (o, d) = (Vec3A::new(-2.0, 0.0, 0.0), Vec3A::X);
        let n = 100_000;
        let dt = 4.0 / n as f64;
        let sum: f64 = (0..n)
            .map(|k| {
                let t = (k as f64 + 0.5) * dt;
                let r2 = (t - 2.0).powi(2) + 0.25;
                dt / r2
            })
            .sum();
        let exact = inverse_square_integral(c, o, d, 0.0, 4.0);
        assert!(
            (f64::from(exact) - sum).abs() < 1e-4 * sum,
            "{exact} vs {sum}"
        );
        // A point on the line: nothing to sample.
        assert_eq!(inverse_square_integral(Vec3A::X, o, d, 0.0, 4.0), 0.0);
        assert!(sample(Vec3A::X, o, d, 0.0, 4.0, 0.5).is_none());
    }
}
