//! Analytic cylinders ([`Cylinder`]): Mitsuba's `cylinder`, in object
//! space the open tube of radius 1 about the z axis from `z = 0` to `z = 1`
//! (no caps), placed by an affine map (Mitsuba's `p0`, `p1` and `radius`
//! make one). The ray test solves the quadratic in object space in double
//! precision (cancellation-free, as the sphere's), so grazing rays and rays
//! from inside keep their accuracy. Texture coordinates are Mitsuba's:
//! `(u, v) = (φ/2π, z)`, `∂p/∂u = 2π(−y, x, 0)`, `∂p/∂v = (0, 0, 1)` in
//! the world. As a light it is sampled uniformly in `(u, v)`, which is
//! uniform by area when the placement scales x and y alike without shear
//! (Mitsuba's assumption, which it warns about otherwise).

use glam::{DVec3, Vec2, Vec3A};
use std::f64::consts::TAU;

use super::placement::Placement;
use super::ray::{Ray, SurfacePoint};
use super::sphere::first_root;

/// The rounding of a point's `(u, v)` (f32) in object units, which the
/// error bound of a point rebuilt from them covers.
const UV_SLACK: f32 = 1e-6;

/// A cylinder placed in the world.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cylinder {
    /// Object to world.
    pub placement: Placement,
    /// World radius (the length of the object's x axis, as Mitsuba's).
    radius: f32,
    /// World length (the length of the object's z axis).
    length: f32,
}

impl Cylinder {
    /// The unit cylinder placed by `placement`.
    pub fn new(placement: Placement) -> Self {
        Self {
            radius: placement.linear.x_axis.length(),
            length: placement.linear.z_axis.length(),
            placement,
        }
    }

    /// The ray parameter of the ray's first crossing of the tube in
    /// `(0, t_max]` between its ends; rays along the axis never meet it.
    #[inline]
    pub fn intersect(&self, ray: &Ray, t_max: f32) -> Option<f32> {
        let (o, d) = self.placement.ray_to_object(ray);
        let a = d.x * d.x + d.y * d.y;
        if a <= 0.0 {
            return None;
        }
        let b = o.x * d.x + o.y * d.y;
        // The squared distance of the line's projection from the axis,
        // from the perpendicular (no cancellation when the ray is far).
        let (px, py) = (o.x - d.x * (b / a), o.y - d.y * (b / a));
        let disc = a * (1.0 - (px * px + py * py));
        if disc < 0.0 {
            return None;
        }
        let c = o.x * o.x + o.y * o.y - 1.0;
        first_root(a, b, c, disc, t_max, |t| {
            (0.0..=1.0).contains(&(o.z + t * d.z))
        })
    }

    /// The point at `uv` with its error bound and its outward normal.
    #[inline]
    pub fn point_at(&self, uv: Vec2) -> SurfacePoint {
        let (sin, cos) = (TAU * f64::from(uv.x)).sin_cos();
        let (p, error) = self
            .placement
            .point(DVec3::new(cos, sin, f64::from(uv.y)), UV_SLACK);
        let n = self
            .placement
            .normal(Vec3A::new(cos as f32, sin as f32, 0.0));
        SurfacePoint { p, error, n }
    }

    /// `∂p/∂u` and `∂p/∂v` at `uv` (Mitsuba's, in the world).
    #[inline]
    pub fn derivatives(&self, uv: Vec2) -> (Vec3A, Vec3A) {
        let (sin, cos) = (std::f32::consts::TAU * uv.x).sin_cos();
        let du = Vec3A::new(-sin, cos, 0.0) * std::f32::consts::TAU;
        (self.placement.vector(du), self.placement.vector(Vec3A::Z))
    }

    /// World area, `2π r ℓ` (Mitsuba's).
    #[inline]
    pub fn area(&self) -> f32 {
        std::f32::consts::TAU * self.radius * self.length
    }

    /// Axis-aligned bounds: the boxes of the two end circles together.
    pub fn bounds(&self) -> (Vec3A, Vec3A) {
        let e = self.placement.circle_extent();
        let p0 = self.placement.origin;
        let p1 = p0 + self.placement.linear.z_axis;
        ((p0 - e).min(p1 - e), (p0 + e).max(p1 + e))
    }

    /// `(u, v)` of a point uniform by area from `u` in `[0, 1)²`
    /// (Mitsuba's: `φ = 2πu₁`, `z = u₀`).
    #[inline]
    pub fn sample_uv(&self, u: Vec2) -> Vec2 {
        Vec2::new(u.y, u.x)
    }
}

/// `(u, v) = (φ/2π, z)` of an object-space point (its projection onto the
/// tube), `φ` in `[0, 2π)`.
#[inline]
pub fn uv_of_local(local: DVec3) -> Vec2 {
    let mut phi = local.y.atan2(local.x);
    if phi < 0.0 {
        phi += TAU;
    }
    Vec2::new(
        ((phi / TAU) as f32).min(1.0),
        (local.z as f32).clamp(0.0, 1.0),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::shape_checks::{
        assert_area_sampling_sees_what_rays_see, assert_derivatives,
    };
    use crate::sampling::sampler::Rng;
    use glam::Mat3A;

    /// Radius 0.5 about the line from (1, 2, 0) along +y, length 3.
    fn tube() -> Cylinder {
        let linear = Mat3A::from_cols(
            Vec3A::new(0.0, 0.0, 0.5),
            Vec3A::new(0.5, 0.0, 0.0),
            Vec3A::new(0.0, 3.0, 0.0),
        );
        Cylinder::new(Placement::new(linear, Vec3A::new(1.0, 2.0, 0.0)).unwrap())
    }

    #[test]
    fn rays_meet_the_tube_between_its_ends() {
        let c = Cylinder::new(Placement::new(Mat3A::IDENTITY, Vec3A::ZERO).unwrap());
        let across = |y: f32, z: f32| Ray::new(Vec3A::new(-5.0, y, z), Vec3A::X);
        assert_eq!(c.intersect(&across(0.0, 0.5), f32::INFINITY), Some(4.0));
        assert_eq!(c.intersect(&across(0.0, 0.5), 3.9), None);
        // Grazing either side of the silhouette.
        assert!(c.intersect(&across(0.9999, 0.5), f32::INFINITY).is_some());
        assert!(c.intersect(&across(1.0001, 0.5), f32::INFINITY).is_none());
        // Past its ends: open, no caps.
        assert!(c.intersect(&across(0.0, 1.01), f32::INFINITY).is_none());
        assert!(c.intersect(&across(0.0, -0.01), f32::INFINITY).is_none());
        // Along the axis, inside or out: never.
        let along = Ray::new(Vec3A::new(0.3, 0.0, -1.0), Vec3A::Z);
        assert!(c.intersect(&along, f32::INFINITY).is_none());
        // From inside: the far wall; from inside out through an open end:
        // nothing.
        let inside = Ray::new(Vec3A::new(0.0, 0.0, 0.5), Vec3A::new(0.0, 1.0, 0.0));
        assert_eq!(c.intersect(&inside, f32::INFINITY), Some(1.0));
        let out = Ray::new(Vec3A::new(0.0, 0.0, 0.5), Vec3A::new(0.1, 0.0, 1.0));
        assert!(c.intersect(&out, f32::INFINITY).is_none());
        // In through the open end, onto the inner wall.
        let dir = Vec3A::new(1.0, 0.0, -1.0).normalize();
        let t = c
            .intersect(&Ray::new(Vec3A::new(0.0, 0.0, 1.5), dir), f32::INFINITY)
            .unwrap();
        assert!((t - 2f32.sqrt()).abs() < 1e-6, "{t}");
        // From outside, the near side only.
        let t = c.intersect(&across(0.6, 0.2), f32::INFINITY).unwrap();
        assert!((t - (5.0 - 0.8)).abs() < 1e-6, "{t}");
        // Mitsuba's coordinates: φ/2π from +x towards +y, then z.
        let uv = uv_of_local(c.placement.local_at(&across(0.0, 0.25), 4.0));
        assert!((uv - Vec2::new(0.5, 0.25)).length() < 1e-6, "{uv}");
    }

    /// Random rays against brute force in the world: the closest crossing of
    /// the infinite tube (points at distance r from the axis line, solved
    /// in the plane across it), within the ends.
    #[test]
    fn the_ray_test_matches_brute_force() {
        let c = tube();
        let p0 = DVec3::new(1.0, 2.0, 0.0);
        let axis = DVec3::Y;
        let mut rng = Rng::new(2, 8);
        let mut r = || f64::from(rng.next_f32());
        let (mut hits, mut checked) = (0, 0);
        for i in 0..20_000 {
            // Half from inside the tube, half from around it.
            let o = if i % 2 == 0 {
                p0 + DVec3::new(r() * 0.6 - 0.3, r() * 3.0, r() * 0.6 - 0.3)
            } else {
                p0 + DVec3::new(r() * 6.0 - 3.0, r() * 7.0 - 2.0, r() * 6.0 - 3.0)
            };
            let target = p0 + DVec3::new(r() - 0.5, r() * 4.0 - 0.5, r() - 0.5);
            let ray = Ray::new(o.as_vec3a(), (target - o).normalize().as_vec3a());
            let (o, d) = (ray.origin.as_dvec3(), ray.dir.as_dvec3());
            let (oq, dq) = (o - p0 - axis * (o - p0).dot(axis), d - axis * d.dot(axis));
            let (a, b, cc) = (dq.dot(dq), oq.dot(dq), oq.dot(oq) - 0.25);
            let disc = b * b - a * cc;
            let mut want = None;
            let mut near_edge = false;
            if disc >= 0.0 {
                for t in [(-b - disc.sqrt()) / a, (-b + disc.sqrt()) / a] {
                    let y = (o + d * t - p0).dot(axis);
                    near_edge |= y.abs() < 1e-5 || (y - 3.0).abs() < 1e-5 || t.abs() < 1e-5;
                    if want.is_none() && t > 0.0 && (0.0..=3.0).contains(&y) {
                        want = Some(t);
                    }
                }
            }
            if near_edge || disc.abs() < 1e-6 {
                continue;
            }
            checked += 1;
            let got = c.intersect(&ray, f32::INFINITY);
            assert_eq!(got.is_some(), want.is_some(), "{ray:?} {want:?}");
            if let (Some(got), Some(want)) = (got, want) {
                hits += 1;
                assert!(
                    (f64::from(got) - want).abs() <= 1e-5 * want.max(1.0),
                    "{got} vs {want}"
                );
            }
        }
        assert!(hits > 5000 && checked > 15_000, "{hits} {checked}");
    }

    /// Uniform area sampling against the ray test, from outside the tube and
    /// from inside it.
    #[test]
    fn area_sampling_matches_the_solid_angle_the_ray_test_sees() {
        let c = tube();
        for p in [Vec3A::new(2.5, 3.0, 1.0), Vec3A::new(1.1, 3.0, 0.1)] {
            assert_area_sampling_sees_what_rays_see(
                p,
                c.area(),
                |u| c.point_at(c.sample_uv(u)),
                |ray| c.intersect(ray, f32::INFINITY),
            );
        }
    }

    #[test]
    fn points_from_coordinates_lie_on_the_tube_within_their_bound() {
        let c = tube();
        let mut rng = Rng::new(6, 6);
        for _ in 0..10_000 {
            let (phi, z) = (TAU * f64::from(rng.next_f32()), f64::from(rng.next_f32()));
            let exact =
                DVec3::new(1.0, 2.0, 0.0) + DVec3::new(0.5 * phi.sin(), 3.0 * z, 0.5 * phi.cos());
            let uv = uv_of_local(c.placement.point_to_object(exact.as_vec3a()));
            let sp = c.point_at(uv);
            crate::geometry::shape_checks::assert_within_bound(&sp, exact);
            // Outward, across the axis.
            let radial = (exact - DVec3::new(1.0, exact.y, 0.0)).normalize();
            assert!((sp.n.as_dvec3() - radial).length() < 1e-5);
        }
        // Derivatives by finite differences.
        let uv = Vec2::new(0.3, 0.4);
        assert_derivatives(|uv| c.point_at(uv), c.derivatives(uv), uv);
        assert!((c.area() - std::f32::consts::TAU * 1.5).abs() < 1e-5);
    }
}
