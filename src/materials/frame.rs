//! The local shading frame every BSDF works in: [`Frame`], an orthonormal
//! basis with the shading normal as `+z`, and the two questions asked of a
//! local direction most often (its mirror image about the normal, whether it
//! is above the horizon).

use glam::Vec3A;

/// An orthonormal basis `(t, b, n)` with `n` as the local `+z` axis.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Frame {
    /// First tangent (local `+x`).
    pub t: Vec3A,
    /// Second tangent (local `+y`), `n × t`.
    pub b: Vec3A,
    /// The normal (local `+z`).
    pub n: Vec3A,
}

impl Frame {
    /// A right-handed frame around the unit normal `n`, without branches (Duff et
    /// al. 2017, "Building an orthonormal basis, revisited"); accurate for every
    /// unit `n`, including those near `±z`.
    #[inline]
    pub fn from_normal(n: Vec3A) -> Frame {
        let sign = 1.0f32.copysign(n.z);
        let a = -1.0 / (sign + n.z);
        let b = n.x * n.y * a;
        let t = Vec3A::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x);
        let bt = Vec3A::new(b, sign + n.y * n.y * a, -n.y);
        Frame { t, b: bt, n }
    }

    /// World direction `v` in this frame's coordinates.
    #[inline]
    pub fn to_local(&self, v: Vec3A) -> Vec3A {
        Vec3A::new(v.dot(self.t), v.dot(self.b), v.dot(self.n))
    }

    /// Local direction `v` in world coordinates.
    #[inline]
    pub fn to_world(&self, v: Vec3A) -> Vec3A {
        v.x * self.t + v.y * self.b + v.z * self.n
    }
}

/// Mirror reflection of `wo` about the local normal `+z`.
#[inline]
pub(super) fn reflect_z(wo: Vec3A) -> Vec3A {
    Vec3A::new(-wo.x, -wo.y, wo.z)
}

/// Whether `w` is strictly above the local horizon (false for NaN).
#[inline]
pub(super) fn above(w: Vec3A) -> bool {
    w.z > 0.0
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::materials::test_util::*;

    #[test]
    fn frame_is_orthonormal_for_random_normals_incl_poles() {
        let mut r = rng(1);
        let mut normals: Vec<Vec3A> = (0..10_000).map(|_| sphere(&mut r)).collect();
        // The troublesome neighbourhoods of ±z, down to f32 resolution.
        for &e in &[0.0f32, 1e-8, 1e-6, 1e-4, 1e-2] {
            for &s in &[1.0f32, -1.0] {
                normals.push(Vec3A::new(e, 0.0, s).normalize());
                normals.push(Vec3A::new(-e, e, s).normalize());
                normals.push(Vec3A::new(0.0, -e, s).normalize());
            }
        }
        // z = −0.0 picks the −z branch of the frame.
        normals.push(Vec3A::new(1.0, 0.0, -0.0));
        let mut worst = 0.0f32;
        for n in normals {
            let f = Frame::from_normal(n);
            let errs = [
                (f.t.length() - 1.0).abs(),
                (f.b.length() - 1.0).abs(),
                f.t.dot(f.b).abs(),
                f.t.dot(f.n).abs(),
                f.b.dot(f.n).abs(),
                (f.t.cross(f.b) - f.n).abs().max_element(),
            ];
            let v = sphere(&mut r);
            let round_trip = (f.to_world(f.to_local(v)) - v).abs().max_element();
            let local_n = (f.to_local(n) - Vec3A::Z).abs().max_element();
            let e = errs.into_iter().fold(round_trip.max(local_n), f32::max);
            assert!(e < 1e-5, "frame of {n:?}: error {e}, {f:?}");
            worst = worst.max(e);
        }
        eprintln!("frame: worst orthonormality error {worst:e}");
    }
}
