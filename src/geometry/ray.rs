//! Rays, hit records and robust spawning of rays that leave a surface.

use glam::Vec3A;

/// A ray `origin + t * dir` for `t` in `(0, t_max]` (`t_max` is given per query).
///
/// `dir` need not be normalised; `t` is measured in units of `dir`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ray {
    /// Where the ray starts.
    pub origin: Vec3A,
    /// Which way it goes.
    pub dir: Vec3A,
}

impl Ray {
    /// A ray from `origin` along `dir`.
    pub fn new(origin: Vec3A, dir: Vec3A) -> Self {
        Self { origin, dir }
    }

    /// The point at parameter `t`.
    pub fn at(&self, t: f32) -> Vec3A {
        self.origin + t * self.dir
    }
}

/// The closest intersection found by a scene query.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    /// Ray parameter of the hit.
    pub t: f32,
    /// Index of the triangle in the scene's triangle order.
    pub prim: u32,
    /// Barycentric weight of the triangle's second vertex.
    pub b1: f32,
    /// Barycentric weight of the triangle's third vertex.
    pub b2: f32,
}

/// `gamma(n)` of floating-point error analysis (Higham): a bound on the relative
/// error of `n` chained f32 operations.
pub const fn gamma(n: u32) -> f32 {
    let eps = f32::EPSILON * 0.5;
    (n as f32 * eps) / (1.0 - n as f32 * eps)
}

/// A point on a surface with a conservative bound on its floating-point error.
///
/// The point is reconstructed from barycentric coordinates, which keeps its error
/// small and known (pbrt-v4 §6.8): rays spawned from it are pushed just past this
/// error bound along the normal so that they never hit the surface they start on.
#[derive(Clone, Copy, Debug)]
pub struct SurfacePoint {
    /// The reconstructed hit point.
    pub p: Vec3A,
    /// Per-component absolute error bound of `p`.
    pub error: Vec3A,
    /// Unit geometric normal of the surface at `p` (either side).
    pub n: Vec3A,
}

impl SurfacePoint {
    /// An exact point on no surface (a camera's or a point light's), its
    /// normal zero.
    #[inline]
    pub fn bare(p: Vec3A) -> Self {
        Self {
            p,
            error: Vec3A::ZERO,
            n: Vec3A::ZERO,
        }
    }

    /// Builds the point `b0*v0 + b1*v1 + b2*v2` of a triangle and its error bound.
    pub fn on_triangle(v: &[Vec3A; 3], b1: f32, b2: f32, n: Vec3A) -> Self {
        let b0 = 1.0 - b1 - b2;
        let (a, b, c) = (b0 * v[0], b1 * v[1], b2 * v[2]);
        let p = a + b + c;
        let error = gamma(7) * (a.abs() + b.abs() + c.abs());
        Self { p, error, n }
    }

    /// An origin for a ray leaving the surface in direction `w` that is
    /// guaranteed to lie on `w`'s side of the surface.
    pub fn offset_origin(&self, w: Vec3A) -> Vec3A {
        let d = self.n.abs().dot(self.error);
        let mut offset = d * self.n;
        if w.dot(self.n) < 0.0 {
            offset = -offset;
        }
        let po = self.p + offset;
        // Round away from p so that the offset survives the addition's rounding.
        // (`extend` costs one insert; `from_vec4` nothing.)
        Vec3A::from_vec4(super::step_towards4(po.extend(0.0), offset.extend(0.0)))
    }

    /// A ray towards `target` for a shadow test, with the `t_max` that stops just
    /// short of it. Both ends are trimmed by [`SHADOW_EPSILON`] of the distance: at
    /// the far end a light lying on a surface is not shadowed by that surface; at
    /// the near end, in a concave corner (a floor meeting a wall), a point computed
    /// on one face may lie a rounding error behind the other face, which the offset
    /// along its own normal cannot clear.
    pub fn ray_to(&self, target: Vec3A) -> (Ray, f32) {
        let origin = self.offset_origin(target - self.p);
        let to = target - origin;
        let dist = to.length();
        let dir = to / dist;
        let skip = dist * SHADOW_EPSILON;
        (Ray::new(origin + dir * skip, dir), dist - 2.0 * skip)
    }
}

/// Relative trim of both ends of shadow rays (see [`SurfacePoint::ray_to`]).
pub const SHADOW_EPSILON: f32 = 1e-4;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn offset_origin_lies_on_the_side_of_the_direction() {
        let v = [
            Vec3A::new(-1e3, 5.0, -1e3),
            Vec3A::new(1e3, 5.0, -1e3),
            Vec3A::new(0.0, 5.0, 1e3),
        ];
        let n = Vec3A::Y;
        let sp = SurfacePoint::on_triangle(&v, 0.3, 0.3, n);
        assert!(sp.offset_origin(Vec3A::Y).y > 5.0);
        assert!(sp.offset_origin(-Vec3A::Y).y < 5.0);
        // The offset is tiny: a few ulps of the coordinates involved.
        assert!((sp.offset_origin(Vec3A::Y).y - 5.0) < 1e-3);
    }

    /// Rays spawned off random triangles at any angle, on either side, never hit
    /// the triangle they leave (the lab report's acne, in general form).
    #[test]
    fn spawned_rays_never_hit_their_own_triangle() {
        use crate::geometry::triangle::{RayShear, Triangle, intersect};
        let mut rng = crate::sampling::sampler::Rng::new(9, 9);
        let mut r = move || rng.next_f32();
        for i in 0..200_000 {
            let scale = [0.01, 1.0, 100.0][i % 3];
            let mut p = || (Vec3A::new(r(), r(), r()) * 2.0 - 1.0) * scale;
            let tri = Triangle::new(p(), p(), p());
            let n = tri.lab_normal();
            if n == Vec3A::ZERO {
                continue;
            }
            let (b1, b2) = (r() * 0.5, r() * 0.5);
            let sp = SurfacePoint::on_triangle(&tri.v, b1, b2, n);
            // Directions down to grazing angles, on both sides.
            let dir = (Vec3A::new(r(), r(), r()) - 0.5).normalize();
            let ray = Ray::new(sp.offset_origin(dir), dir);
            assert!(
                intersect(&RayShear::new(&ray), &tri.v, f32::INFINITY).is_none(),
                "{tri:?} {ray:?}"
            );
        }
    }
}
