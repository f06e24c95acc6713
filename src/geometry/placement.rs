//! The affine placement of an analytic shape's object space in the world
//! ([`Placement`], Mitsuba's `to_world` without projection): world points
//! from object points in double precision with an error bound, rays taken
//! into object space in double precision, and normals by the inverse
//! transpose. Disks and cylinders keep any affine map (a scaled or sheared
//! disk is an ellipse), so their ray tests are exact in object space.

use glam::{Affine3A, DMat3, DVec3, Mat3A, Vec3A};

use super::ray::{Ray, gamma};

/// `to_world` of an analytic shape: `p_world = linear · p_object + origin`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Placement {
    /// The linear part (columns: the images of the object's x, y and z axes).
    pub linear: Mat3A,
    /// Where the object's origin goes.
    pub origin: Vec3A,
    /// The inverse of `linear`, in double precision.
    to_object: DMat3,
    /// The inverse transpose of `linear` (normals to the world).
    normal_matrix: Mat3A,
}

impl Placement {
    /// The placement `linear · p + origin`, or `None` when `linear` is
    /// singular or not finite.
    pub fn new(linear: Mat3A, origin: Vec3A) -> Option<Self> {
        let m = DMat3::from_cols(
            linear.x_axis.as_dvec3(),
            linear.y_axis.as_dvec3(),
            linear.z_axis.as_dvec3(),
        );
        let det = m.determinant();
        let scale = linear.x_axis.length() * linear.y_axis.length() * linear.z_axis.length();
        if !(det.is_finite() && origin.is_finite() && det.abs() > 1e-12 * f64::from(scale)) {
            return None;
        }
        let to_object = m.inverse();
        let normal_matrix = Mat3A::from_cols(
            to_object.row(0).as_vec3a(),
            to_object.row(1).as_vec3a(),
            to_object.row(2).as_vec3a(),
        );
        Some(Self {
            linear,
            origin,
            to_object,
            normal_matrix,
        })
    }

    /// The placement from an affine transform.
    pub fn from_affine(to_world: Affine3A) -> Option<Self> {
        Self::new(to_world.matrix3, to_world.translation)
    }

    /// This placement followed by `to_world`.
    pub fn then(&self, to_world: Affine3A) -> Option<Self> {
        Self::new(
            to_world.matrix3 * self.linear,
            to_world.transform_point3a(self.origin),
        )
    }

    /// `ray` in object space, in double precision: its origin and direction
    /// (not normalised, so that `t` is the same in both spaces).
    #[inline]
    pub fn ray_to_object(&self, ray: &Ray) -> (DVec3, DVec3) {
        let o = ray.origin.as_dvec3() - self.origin.as_dvec3();
        (self.to_object * o, self.to_object * ray.dir.as_dvec3())
    }

    /// The object-space point at `t` along `ray`, in double precision.
    #[inline]
    pub fn local_at(&self, ray: &Ray, t: f32) -> DVec3 {
        let (o, d) = self.ray_to_object(ray);
        o + d * f64::from(t)
    }

    /// Half the extent, per world axis, of the image of the object's unit
    /// circle about the origin in its xy plane (exact for the ellipse: the
    /// length of each coordinate's row of the two axes).
    pub fn circle_extent(&self) -> Vec3A {
        let l = &self.linear;
        (l.x_axis * l.x_axis + l.y_axis * l.y_axis).powf(0.5)
    }

    /// World point `p` in object space, in double precision.
    #[inline]
    pub fn point_to_object(&self, p: Vec3A) -> DVec3 {
        self.to_object * (p.as_dvec3() - self.origin.as_dvec3())
    }

    /// The world point of object point `local` (computed in double
    /// precision, then rounded) and a bound on its error: the rounding,
    /// plus `slack` times the size of the map's columns (which callers use
    /// for the rounding of the coordinates `local` came from).
    #[inline]
    pub fn point(&self, local: DVec3, slack: f32) -> (Vec3A, Vec3A) {
        let l = &self.linear;
        let w = self.origin.as_dvec3()
            + l.x_axis.as_dvec3() * local.x
            + l.y_axis.as_dvec3() * local.y
            + l.z_axis.as_dvec3() * local.z;
        let p = w.as_vec3a();
        let size = l.x_axis.abs() + l.y_axis.abs() + l.z_axis.abs();
        (p, gamma(2) * p.abs() + slack * size)
    }

    /// An object-space vector in the world.
    #[inline]
    pub fn vector(&self, v: Vec3A) -> Vec3A {
        self.linear * v
    }

    /// The unit world normal of an object-space normal (by the inverse
    /// transpose, so it stays perpendicular to the surface under any scale
    /// or shear).
    #[inline]
    pub fn normal(&self, n: Vec3A) -> Vec3A {
        (self.normal_matrix * n).normalize()
    }
}

/// Two unit vectors completing unit `n` to a right-handed orthonormal frame
/// `(s, t, n)`: Mitsuba's `coordinate_system` (Duff et al. 2017), which its
/// `Frame3f` and `to_frame` use (so a cylinder's `p0`/`p1` frame and its
/// texture coordinates are Mitsuba's).
pub fn coordinate_system(n: DVec3) -> (DVec3, DVec3) {
    let sign = 1f64.copysign(n.z);
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    (
        DVec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x),
        DVec3::new(b, sign + n.y * n.y * a, -n.y),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn points_and_rays_go_both_ways() {
        let linear = Mat3A::from_cols(
            Vec3A::new(2.0, 0.3, 0.0),
            Vec3A::new(0.5, 0.7, -0.2),
            Vec3A::new(0.1, 0.0, 3.0),
        );
        let pl = Placement::new(linear, Vec3A::new(10.0, -4.0, 2.0)).unwrap();
        let local = DVec3::new(0.3, -0.6, 0.25);
        let (p, err) = pl.point(local, 0.0);
        let back = pl.point_to_object(p);
        assert!((back - local).length() < 1e-6, "{back}");
        assert!(err.max_element() < 1e-5);
        let ray = Ray::new(Vec3A::new(1.0, 2.0, 3.0), Vec3A::new(0.2, -0.5, 0.9));
        let (o, d) = pl.ray_to_object(&ray);
        let at = pl.point(o + d * 1.5, 0.0).0;
        assert!((at - ray.at(1.5)).length() < 1e-5);
        // Normals stay perpendicular to object tangents.
        let n = pl.normal(Vec3A::Z);
        assert!(n.dot(pl.vector(Vec3A::X)).abs() < 1e-6);
        assert!(n.dot(pl.vector(Vec3A::Y)).abs() < 1e-6);
        assert!(
            Placement::new(
                Mat3A::from_diagonal(glam::Vec3::new(1.0, 0.0, 1.0)),
                Vec3A::ZERO
            )
            .is_none()
        );
    }

    #[test]
    fn the_coordinate_system_is_right_handed_and_orthonormal() {
        for n in [
            DVec3::Z,
            -DVec3::Z,
            DVec3::new(0.3, -0.4, 0.2).normalize(),
            DVec3::X,
        ] {
            let (s, t) = coordinate_system(n);
            assert!((s.cross(t) - n).length() < 1e-12, "{n}");
            assert!(s.dot(n).abs() < 1e-12 && t.dot(n).abs() < 1e-12);
        }
    }
}
