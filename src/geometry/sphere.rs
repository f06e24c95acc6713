//! Analytic spheres ([`Sphere`]): the exact ray test, the point of a hit
//! from its spherical coordinates with an error bound, and sampling a
//! sphere as a light by the solid angle it subtends (Mitsuba 3 and pbrt-v4
//! do the same: a uniform direction inside the cone from the shading point
//! that touches the sphere, uniform area from inside it).

use glam::{Mat3A, Vec2, Vec3A};
use std::f32::consts::PI;

use super::ray::{Ray, SurfacePoint, gamma};

/// A sphere placed in the world: centre, radius and the rotation of its
/// object frame (which fixes its texture coordinates: `u = φ/2π` about the
/// object's z axis from its x axis, `v = θ/π` from its +z pole, as Mitsuba's
/// `sphere`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sphere {
    /// Centre.
    pub center: Vec3A,
    /// Radius (> 0).
    pub radius: f32,
    /// Object to world rotation (orthonormal columns: the object's x, y, z).
    pub frame: Mat3A,
}

impl Sphere {
    /// The ray parameter of the closest crossing of the sphere in
    /// `(t_min, t_max]`, solved in double precision with the cancellation-free
    /// form of the quadratic (the discriminant from the perpendicular
    /// distance, Haines et al., Ray Tracing Gems ch. 7), so grazing and
    /// distant rays keep their accuracy.
    #[inline]
    pub fn intersect(&self, ray: &Ray, t_max: f32) -> Option<f32> {
        let o = ray.origin.as_dvec3() - self.center.as_dvec3();
        let d = ray.dir.as_dvec3();
        let a = d.length_squared();
        if a <= 0.0 {
            return None;
        }
        let r = f64::from(self.radius);
        let b = o.dot(d);
        // |o − (o·d̂)d̂|², the squared distance of the line from the centre.
        let perp = o - d * (b / a);
        let disc = a * (r * r - perp.length_squared());
        if disc < 0.0 {
            return None;
        }
        let c = o.length_squared() - r * r;
        first_root(a, b, c, disc, t_max, |_| true)
    }

    /// The object-frame unit direction of world point `p`'s projection, as
    /// spherical coordinates `(u, v) = (φ/2π, θ/π)`.
    #[inline]
    pub fn uv_of(&self, p: Vec3A) -> Vec2 {
        let local = self.frame.transpose() * (p - self.center);
        let len = local.length();
        if len.is_nan() || len <= 0.0 {
            return Vec2::ZERO;
        }
        let local = local / len;
        let mut phi = local.y.atan2(local.x);
        if phi < 0.0 {
            phi += 2.0 * PI;
        }
        // (atan2, not acos: as well conditioned at the poles as elsewhere.)
        let theta = local.x.hypot(local.y).atan2(local.z);
        Vec2::new(phi * (0.5 / PI), theta * (1.0 / PI))
    }

    /// The world unit normal (outwards) at spherical coordinates `uv`.
    #[inline]
    pub fn normal_at(&self, uv: Vec2) -> Vec3A {
        let (sin_p, cos_p) = (2.0 * PI * uv.x).sin_cos();
        let (sin_t, cos_t) = (PI * uv.y).sin_cos();
        (self.frame * Vec3A::new(sin_t * cos_p, sin_t * sin_p, cos_t)).normalize()
    }

    /// The point at spherical coordinates `uv` with its error bound, and its
    /// outward normal as the point's normal. The point is rebuilt from the
    /// angles, so its bound covers their rounding as well as pbrt-v4's
    /// reprojection bound (`γ₅|p|`): `2e-6 r` more in each coordinate.
    #[inline]
    pub fn point_at(&self, uv: Vec2) -> SurfacePoint {
        let n = self.normal_at(uv);
        let p = self.center + self.radius * n;
        let error = gamma(5) * p.abs() + Vec3A::splat(2e-6 * self.radius);
        SurfacePoint { p, error, n }
    }

    /// `∂p/∂u` and `∂p/∂v` at `uv` (Mitsuba's: `2π(−y, x, 0)` and
    /// `π(z cos φ, z sin φ, −sin θ)` in the object frame, scaled by the
    /// radius and turned to the world).
    #[inline]
    pub fn derivatives(&self, uv: Vec2) -> (Vec3A, Vec3A) {
        let (sin_p, cos_p) = (2.0 * PI * uv.x).sin_cos();
        let (sin_t, cos_t) = (PI * uv.y).sin_cos();
        let r = self.radius;
        let du = Vec3A::new(-sin_t * sin_p, sin_t * cos_p, 0.0) * (2.0 * PI * r);
        let dv = Vec3A::new(cos_t * cos_p, cos_t * sin_p, -sin_t) * (PI * r);
        (self.frame * du, self.frame * dv)
    }

    /// `(u, v)` of a point uniform by area from `u` in `[0, 1)²`: `φ = 2πu₀`
    /// and `cos θ = 1 − 2u₁` (Archimedes: equal heights, equal areas).
    #[inline]
    pub fn sample_uv(&self, u: Vec2) -> Vec2 {
        let cos = (1.0 - 2.0 * u.y).clamp(-1.0, 1.0);
        Vec2::new(u.x, cos.acos() * (1.0 / PI))
    }

    /// Surface area, `4πr²`.
    #[inline]
    pub fn area(&self) -> f32 {
        4.0 * PI * self.radius * self.radius
    }

    /// Axis-aligned bounds.
    #[inline]
    pub fn bounds(&self) -> (Vec3A, Vec3A) {
        let r = Vec3A::splat(self.radius);
        (self.center - r, self.center + r)
    }

    /// The cosine of the half angle of the cone from `p` that touches the
    /// sphere, or `None` when `p` is inside it (or on it, to rounding).
    #[inline]
    fn cone_from(&self, p: Vec3A) -> Option<f64> {
        let d2 = (self.center.as_dvec3() - p.as_dvec3()).length_squared();
        let r2 = f64::from(self.radius).powi(2);
        if d2 <= r2 * (1.0 + 1e-6) {
            return None;
        }
        Some((1.0 - r2 / d2).max(0.0).sqrt())
    }

    /// A point on the sphere for lighting `p`, from `u` in `[0, 1)²`: from
    /// outside, a uniform direction in the cone that touches the sphere and
    /// that direction's first crossing; from inside, a uniform point by area.
    /// Returns the point's spherical coordinates and the solid-angle density
    /// of the direction from `p` (from inside: the area density turned into
    /// solid angle).
    pub fn sample_from(&self, p: Vec3A, u: Vec2) -> Option<(Vec2, f32)> {
        let Some(cos_max) = self.cone_from(p) else {
            // Uniform over the whole sphere.
            let z = 1.0 - 2.0 * u.x;
            let phi = 2.0 * PI * u.y;
            let s = (1.0 - z * z).max(0.0).sqrt();
            let n = Vec3A::new(s * phi.cos(), s * phi.sin(), z);
            let q = self.center + self.radius * n;
            let to = q - p;
            let cos = n.dot(to).abs() / to.length();
            if cos.is_nan() || cos <= 0.0 {
                return None;
            }
            let pdf = to.length_squared() / (cos * self.area());
            let uv = self.uv_of(q);
            return Some((uv, pdf));
        };
        let c = self.center.as_dvec3();
        let pd = p.as_dvec3();
        let axis = (c - pd).normalize();
        // cos θ uniform in [cos_max, 1].
        let cos_t = 1.0 - f64::from(u.x) * (1.0 - cos_max);
        let sin_t = (1.0 - cos_t * cos_t).max(0.0).sqrt();
        let phi = 2.0 * std::f64::consts::PI * f64::from(u.y);
        let (t, b) = super::placement::coordinate_system(axis);
        let dir = axis * cos_t + (t * phi.cos() + b * phi.sin()) * sin_t;
        // The first crossing along `dir` (the nearest root; rounding near
        // the cone's edge may miss, then the closest point of the line).
        let o = pd - c;
        let bq = o.dot(dir);
        let r = f64::from(self.radius);
        let disc = bq * bq - (o.length_squared() - r * r);
        let t_hit = -bq - disc.max(0.0).sqrt();
        let q = pd + dir * t_hit;
        let pdf = 1.0 / (2.0 * std::f64::consts::PI * (1.0 - cos_max));
        if !pdf.is_finite() {
            return None;
        }
        let uv = self.uv_of(q.as_vec3a());
        Some((uv, pdf as f32))
    }

    /// The solid-angle density with which [`Sphere::sample_from`] picks the
    /// direction from `p` that meets the sphere at `q` (whose outward normal
    /// makes cosine `cos_q` with the direction, either sign).
    pub fn pdf_from(&self, p: Vec3A, q: Vec3A, cos_q: f32) -> f32 {
        match self.cone_from(p) {
            Some(cos_max) => (1.0 / (2.0 * std::f64::consts::PI * (1.0 - cos_max))) as f32,
            None => {
                let cos = cos_q.abs();
                if cos > 0.0 {
                    (q - p).length_squared() / (cos * self.area())
                } else {
                    0.0
                }
            }
        }
    }
}

/// The first root in `(0, t_max]` that `keep` accepts of `a t² + 2b t + c`
/// whose discriminant `b² − ac` (≥ 0) is `disc`, by the cancellation-free
/// form (`q = −b ∓ √disc`, roots `q/a` and `c/q`); as `f32`, never 0.
#[inline]
pub(crate) fn first_root(
    a: f64,
    b: f64,
    c: f64,
    disc: f64,
    t_max: f32,
    keep: impl Fn(f64) -> bool,
) -> Option<f32> {
    let root = disc.sqrt();
    let q = if b > 0.0 { -b - root } else { -b + root };
    let (mut t0, mut t1) = (q / a, if q != 0.0 { c / q } else { q / a });
    if t0 > t1 {
        std::mem::swap(&mut t0, &mut t1);
    }
    let t_max = f64::from(t_max);
    [t0, t1]
        .into_iter()
        .filter(|&t| t > 0.0 && t <= t_max && keep(t))
        .map(|t| t as f32)
        .find(|&t| t > 0.0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::sampler::Rng;

    fn sphere(center: Vec3A, radius: f32) -> Sphere {
        Sphere {
            center,
            radius,
            frame: Mat3A::IDENTITY,
        }
    }

    #[test]
    fn rays_meet_the_sphere_where_the_quadratic_says() {
        let s = sphere(Vec3A::new(0.0, 0.0, 5.0), 2.0);
        // Straight on: the near side at 3, from inside the far side.
        let ray = Ray::new(Vec3A::ZERO, Vec3A::Z);
        assert_eq!(s.intersect(&ray, f32::INFINITY), Some(3.0));
        assert_eq!(s.intersect(&ray, 2.9), None);
        let inside = Ray::new(Vec3A::new(0.0, 0.0, 5.0), Vec3A::Z);
        assert_eq!(s.intersect(&inside, f32::INFINITY), Some(2.0));
        // Tangent lines at distance 2 ± ε, and a ray pointing away.
        let graze = |x: f32| Ray::new(Vec3A::new(x, 0.0, 0.0), Vec3A::Z);
        assert!(s.intersect(&graze(1.999), f32::INFINITY).is_some());
        assert!(s.intersect(&graze(2.001), f32::INFINITY).is_none());
        assert!(
            s.intersect(&Ray::new(Vec3A::ZERO, -Vec3A::Z), f32::INFINITY)
                .is_none()
        );
        // Far away and small: t to f32 accuracy, by f64 brute force.
        let far = sphere(Vec3A::new(1e4, 3.0, -2.0), 0.01);
        let dir = (far.center + Vec3A::new(0.0, 0.004, 0.0)).normalize();
        let t = far
            .intersect(&Ray::new(Vec3A::ZERO, dir), f32::INFINITY)
            .unwrap();
        // The exact near root for the f32 ray, in f64 (no cancellation
        // that matters at these sizes: b² ≈ 1e8, the discriminant ≈ 1e-4).
        let (d, c) = (dir.as_dvec3(), far.center.as_dvec3());
        let (a, b) = (d.length_squared(), -d.dot(c));
        let disc = b * b - a * (c.length_squared() - 1e-4);
        let exact = (-b - disc.sqrt()) / a;
        assert!(
            (f64::from(t) - exact).abs() <= 2.0 * f64::from(t) * f64::from(f32::EPSILON),
            "{t} vs {exact}"
        );
    }

    #[test]
    fn points_from_coordinates_lie_on_the_sphere_within_their_bound() {
        let s = Sphere {
            center: Vec3A::new(100.0, -3.0, 7.0),
            radius: 3.5,
            frame: Mat3A::from_rotation_y(0.7) * Mat3A::from_rotation_x(0.3),
        };
        let mut rng = Rng::new(1, 2);
        for _ in 0..10_000 {
            let dir = Vec3A::new(
                rng.next_f32() - 0.5,
                rng.next_f32() - 0.5,
                rng.next_f32() - 0.5,
            )
            .normalize();
            let exact = s.center.as_dvec3() + dir.as_dvec3() * 3.5;
            let uv = s.uv_of(exact.as_vec3a());
            let sp = s.point_at(uv);
            crate::geometry::shape_checks::assert_within_bound(&sp, exact);
            assert!((sp.n - dir).length() < 1e-5);
        }
    }

    #[test]
    fn coordinates_follow_mitsubas_sphere() {
        let s = sphere(Vec3A::ZERO, 1.0);
        let uv = s.uv_of(Vec3A::new(0.0, 1.0, 0.0));
        assert!((uv - Vec2::new(0.25, 0.5)).length() < 1e-6, "{uv}");
        assert!((s.uv_of(Vec3A::Z) - Vec2::ZERO).length() < 1e-6);
        // ∂p/∂u by finite differences.
        let uv = Vec2::new(0.3, 0.4);
        crate::geometry::shape_checks::assert_derivatives(
            |uv| s.point_at(uv),
            s.derivatives(uv),
            uv,
        );
    }

    /// The sampled directions' density is `pdf_from`: the estimate of the
    /// solid angle (∫ 1/pdf over samples) is the cone's `2π(1 − cos θmax)`,
    /// and from inside the estimate of the full sphere of directions is 4π.
    #[test]
    fn solid_angle_sampling_matches_its_density() {
        let s = sphere(Vec3A::new(0.3, 4.0, -1.0), 1.5);
        for (p, want) in [
            (Vec3A::ZERO, {
                let d2 = (s.center).length_squared() as f64;
                2.0 * std::f64::consts::PI * (1.0 - (1.0 - 2.25 / d2).sqrt())
            }),
            (
                s.center + Vec3A::new(0.2, 0.1, 0.0),
                4.0 * std::f64::consts::PI,
            ),
        ] {
            let mut rng = Rng::new(7, 9);
            let n = 200_000;
            let mut sum = 0.0f64;
            for _ in 0..n {
                let (uv, pdf) = s
                    .sample_from(p, Vec2::new(rng.next_f32(), rng.next_f32()))
                    .unwrap();
                let sp = s.point_at(uv);
                let to = sp.p - p;
                let cos = sp.n.dot(to) / to.length();
                let again = s.pdf_from(p, sp.p, cos);
                assert!((again - pdf).abs() <= 1e-3 * pdf, "{again} vs {pdf}");
                // The sampled point is one the ray from p meets first.
                let t = s
                    .intersect(&Ray::new(p, to.normalize()), f32::INFINITY)
                    .unwrap();
                assert!(
                    (t - to.length()).abs() < 1e-3 * (1.0 + t),
                    "{t} {}",
                    to.length()
                );
                sum += 1.0 / f64::from(pdf);
            }
            let est = sum / n as f64;
            assert!((est - want).abs() < 0.01 * want, "{est} vs {want}");
        }
    }
}
