//! Analytic disks ([`Disk`]): Mitsuba's `disk`, the unit disk at `z = 0`
//! facing `+z` in object space, placed by any affine map (so an ellipse in
//! the world, scaled or sheared). The ray test is exact in object space in
//! double precision; texture coordinates are Mitsuba's `(u, v) = (r, φ/2π)`
//! with its `∂p/∂u = (cos φ, sin φ, 0)` and `∂p/∂v = 2πr(−sin φ, cos φ, 0)`
//! mapped to the world. As a light it is sampled uniformly by area.

use glam::{DVec3, Vec2, Vec3A};
use std::f64::consts::TAU;

use super::placement::Placement;
use super::ray::{Ray, SurfacePoint};

/// The rounding of a point's `(u, v)` (f32) in object units, which the
/// error bound of a point rebuilt from them covers.
const UV_SLACK: f32 = 1e-6;

/// A disk placed in the world.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Disk {
    /// Object to world.
    pub placement: Placement,
    /// Unit world normal (the inverse transpose of `+z`).
    normal: Vec3A,
    /// World area, `π |∂x × ∂y|`.
    area: f32,
}

impl Disk {
    /// The unit disk placed by `placement`.
    pub fn new(placement: Placement) -> Self {
        let l = &placement.linear;
        let area = std::f64::consts::PI * l.x_axis.as_dvec3().cross(l.y_axis.as_dvec3()).length();
        Self {
            normal: placement.normal(Vec3A::Z),
            area: area as f32,
            placement,
        }
    }

    /// The ray parameter of the ray's crossing of the disk in `(0, t_max]`
    /// (the rim included), solved in object space in double precision; rays
    /// in the disk's plane never meet it.
    #[inline]
    pub fn intersect(&self, ray: &Ray, t_max: f32) -> Option<f32> {
        let (o, d) = self.placement.ray_to_object(ray);
        if d.z == 0.0 {
            return None;
        }
        let t = -o.z / d.z;
        if !(t > 0.0 && t <= f64::from(t_max)) {
            return None;
        }
        let (x, y) = (o.x + t * d.x, o.y + t * d.y);
        if x * x + y * y > 1.0 {
            return None;
        }
        let t32 = t as f32;
        (t32 > 0.0).then_some(t32)
    }

    /// The point at `uv` with its error bound and the disk's normal.
    #[inline]
    pub fn point_at(&self, uv: Vec2) -> SurfacePoint {
        let (sin, cos) = (TAU * f64::from(uv.y)).sin_cos();
        let r = f64::from(uv.x);
        let (p, error) = self
            .placement
            .point(DVec3::new(r * cos, r * sin, 0.0), UV_SLACK);
        SurfacePoint {
            p,
            error,
            n: self.normal,
        }
    }

    /// The unit world normal (`+z`'s side).
    #[inline]
    pub fn normal(&self) -> Vec3A {
        self.normal
    }

    /// `∂p/∂u` and `∂p/∂v` at `uv` (Mitsuba's, in the world).
    #[inline]
    pub fn derivatives(&self, uv: Vec2) -> (Vec3A, Vec3A) {
        let (sin, cos) = (std::f32::consts::TAU * uv.y).sin_cos();
        let du = Vec3A::new(cos, sin, 0.0);
        let dv = Vec3A::new(-sin, cos, 0.0) * (std::f32::consts::TAU * uv.x);
        (self.placement.vector(du), self.placement.vector(dv))
    }

    /// World area.
    #[inline]
    pub fn area(&self) -> f32 {
        self.area
    }

    /// Axis-aligned bounds (exact for the ellipse).
    pub fn bounds(&self) -> (Vec3A, Vec3A) {
        let (c, e) = (self.placement.origin, self.placement.circle_extent());
        (c - e, c + e)
    }

    /// `(u, v)` of a point uniform by area from `u` in `[0, 1)²` (an affine
    /// map keeps uniformity): `r = √u₀`, `φ = 2πu₁`.
    #[inline]
    pub fn sample_uv(&self, u: Vec2) -> Vec2 {
        Vec2::new(u.x.sqrt(), u.y)
    }
}

/// `(u, v) = (r, φ/2π)` of an object-space point (its projection onto the
/// disk's plane), `φ` in `[0, 2π)`.
#[inline]
pub fn uv_of_local(local: DVec3) -> Vec2 {
    let r = local.x.hypot(local.y).min(1.0);
    let mut phi = local.y.atan2(local.x);
    if phi < 0.0 {
        phi += TAU;
    }
    Vec2::new(r as f32, ((phi / TAU) as f32).min(1.0))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::shape_checks::{
        assert_area_sampling_sees_what_rays_see, assert_derivatives,
    };
    use crate::sampling::sampler::Rng;
    use glam::Mat3A;

    fn disk(linear: Mat3A, origin: Vec3A) -> Disk {
        Disk::new(Placement::new(linear, origin).unwrap())
    }

    /// A sheared, unevenly scaled disk.
    fn sheared() -> Disk {
        disk(
            Mat3A::from_cols(
                Vec3A::new(2.0, 0.2, 0.3),
                Vec3A::new(0.6, 0.5, -0.4),
                Vec3A::new(0.0, 0.3, 1.0),
            ),
            Vec3A::new(1.0, -2.0, 0.5),
        )
    }

    #[test]
    fn rays_meet_the_unit_disk_inside_its_rim() {
        let d = disk(Mat3A::IDENTITY, Vec3A::new(0.0, 0.0, 3.0));
        let down = |x: f32, y: f32| Ray::new(Vec3A::new(x, y, 5.0), -Vec3A::Z);
        assert_eq!(d.intersect(&down(0.0, 0.0), f32::INFINITY), Some(2.0));
        assert_eq!(d.intersect(&down(0.0, 0.0), 1.9), None);
        // Either side of the rim, and on it exactly.
        assert!(d.intersect(&down(0.9999, 0.0), f32::INFINITY).is_some());
        assert!(d.intersect(&down(1.0001, 0.0), f32::INFINITY).is_none());
        assert!(d.intersect(&down(-1.0, 0.0), f32::INFINITY).is_some());
        assert!(d.intersect(&down(0.0, -1.0), f32::INFINITY).is_some());
        // From below (the back) too; away from it and in its plane, never.
        let up = Ray::new(Vec3A::new(0.2, 0.1, 0.0), Vec3A::Z);
        assert_eq!(d.intersect(&up, f32::INFINITY), Some(3.0));
        let away = Ray::new(Vec3A::new(0.2, 0.1, 4.0), Vec3A::Z);
        assert!(d.intersect(&away, f32::INFINITY).is_none());
        let grazing = Ray::new(Vec3A::new(-5.0, 0.0, 3.0), Vec3A::X);
        assert!(d.intersect(&grazing, f32::INFINITY).is_none());
        // Nearly grazing: exact, by the plane's geometry.
        let dir = Vec3A::new(1.0, 0.0, -1e-4).normalize();
        let nearly = Ray::new(Vec3A::new(-5.0, 0.0, 3.0 + 5e-4), dir);
        let t = d.intersect(&nearly, f32::INFINITY).unwrap();
        assert!((nearly.at(t).z - 3.0).abs() < 1e-6 && (nearly.at(t).x).abs() < 1e-3);
        // Mitsuba's coordinates: r, then φ/2π from +x towards +y.
        let uv = uv_of_local(d.placement.local_at(&down(0.0, 0.5), 2.0));
        assert!((uv - Vec2::new(0.5, 0.25)).length() < 1e-6, "{uv}");
    }

    #[test]
    fn a_scaled_disk_is_an_ellipse() {
        let d = disk(
            Mat3A::from_diagonal(glam::Vec3::new(2.0, 0.5, 1.0)),
            Vec3A::ZERO,
        );
        let down = |x: f32, y: f32| Ray::new(Vec3A::new(x, y, 1.0), -Vec3A::Z);
        assert!(d.intersect(&down(1.99, 0.0), f32::INFINITY).is_some());
        assert!(d.intersect(&down(0.0, 0.49), f32::INFINITY).is_some());
        assert!(d.intersect(&down(0.0, 0.51), f32::INFINITY).is_none());
        assert!(d.intersect(&down(1.5, 0.4), f32::INFINITY).is_none());
        assert!((d.area() - std::f32::consts::PI).abs() < 1e-6);
        assert_eq!(d.normal(), Vec3A::Z);
    }

    /// The ray test against brute force in the world: the plane through the
    /// centre with the normal, then the crossing's object coordinates from
    /// the two axes (least squares), on random rays at a sheared disk.
    #[test]
    fn the_ray_test_matches_brute_force_on_a_sheared_disk() {
        let d = sheared();
        let l = d.placement.linear;
        let (a, b) = (l.x_axis.as_dvec3(), l.y_axis.as_dvec3());
        let n = a.cross(b).normalize();
        let c = d.placement.origin.as_dvec3();
        let mut rng = Rng::new(4, 4);
        let mut r = || f64::from(rng.next_f32());
        let (mut hits, mut checked) = (0, 0);
        for _ in 0..20_000 {
            let o = c + DVec3::new(r() - 0.5, r() - 0.5, r() - 0.5) * 8.0;
            let target = c + (a * (r() * 2.6 - 1.3) + b * (r() * 2.6 - 1.3));
            let dir = (target - o).normalize();
            let ray = Ray::new(o.as_vec3a(), dir.as_vec3a());
            let (o, dir) = (ray.origin.as_dvec3(), ray.dir.as_dvec3());
            let t = n.dot(c - o) / n.dot(dir);
            let q = o + dir * t - c;
            // Solve q = x a + y b.
            let (aa, ab, bb) = (a.dot(a), a.dot(b), b.dot(b));
            let det = aa * bb - ab * ab;
            let x = (bb * q.dot(a) - ab * q.dot(b)) / det;
            let y = (aa * q.dot(b) - ab * q.dot(a)) / det;
            let rr = (x * x + y * y).sqrt();
            if (rr - 1.0).abs() < 1e-5 {
                continue;
            }
            checked += 1;
            let got = d.intersect(&ray, f32::INFINITY);
            let want = t > 0.0 && rr < 1.0;
            assert_eq!(got.is_some(), want, "r {rr} t {t}");
            if let Some(got) = got {
                hits += 1;
                assert!((f64::from(got) - t).abs() <= 1e-6 * t, "{got} vs {t}");
                let uv = uv_of_local(d.placement.local_at(&ray, got));
                assert!((f64::from(uv.x) - rr).abs() < 1e-5);
            }
        }
        assert!(hits > 2000 && checked > 15_000, "{hits} {checked}");
    }

    #[test]
    fn points_from_coordinates_lie_on_the_disk_within_their_bound() {
        let d = sheared();
        let mut rng = Rng::new(5, 1);
        for _ in 0..10_000 {
            let (r, phi) = (
                f64::from(rng.next_f32()).sqrt(),
                TAU * f64::from(rng.next_f32()),
            );
            let l = d.placement.linear;
            let exact = d.placement.origin.as_dvec3()
                + l.x_axis.as_dvec3() * (r * phi.cos())
                + l.y_axis.as_dvec3() * (r * phi.sin());
            let uv = uv_of_local(d.placement.point_to_object(exact.as_vec3a()));
            let sp = d.point_at(uv);
            crate::geometry::shape_checks::assert_within_bound(&sp, exact);
            // The normal is perpendicular to the surface's tangents.
            let (du, dv) = d.derivatives(uv);
            assert!(sp.n.dot(du).abs() < 1e-5 * du.length());
            assert!(sp.n.dot(dv).abs() < 1e-5 * (1.0 + dv.length()));
        }
    }

    #[test]
    fn derivatives_are_finite_differences() {
        let d = sheared();
        let uv = Vec2::new(0.6, 0.3);
        assert_derivatives(|uv| d.point_at(uv), d.derivatives(uv), uv);
    }

    /// Uniform area sampling against the ray test.
    #[test]
    fn area_sampling_matches_the_solid_angle_the_ray_test_sees() {
        let d = sheared();
        assert_area_sampling_sees_what_rays_see(
            Vec3A::new(0.5, 1.0, 3.0),
            d.area(),
            |u| d.point_at(d.sample_uv(u)),
            |ray| d.intersect(ray, f32::INFINITY),
        );
    }
}
