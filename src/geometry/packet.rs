//! Eight rays and their closest hits in the lanes of AVX2 registers ([`F8`]):
//! the form in which the lab's 4×2 pixel blocks make their camera and shadow
//! rays ([`crate::camera`]), the BVH's eight-ray traversal takes them and
//! answers, and the lanes integrators shade the answers.

#![cfg(target_arch = "x86_64")]

use crate::geometry::ray::{Hit, Ray};
use crate::simd::F8;

/// Eight rays in the lanes of AVX2 registers: origins and directions by axis
/// (lane `i` is ray `i`). The lab's 4×2 pixel blocks make their camera and
/// shadow rays in this form and trace them without going through `[Ray; 8]`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Rays8 {
    /// Origins' x, y and z.
    pub(crate) origin: [F8; 3],
    /// Directions' x, y and z.
    pub(crate) dir: [F8; 3],
}

impl Rays8 {
    /// Ray `lane` (for the rare lanes that take the scalar test).
    #[inline(always)]
    pub(crate) fn ray(&self, lane: usize) -> Ray {
        let at = |v: &[F8; 3]| glam::Vec3A::new(v[0].lane(lane), v[1].lane(lane), v[2].lane(lane));
        Ray::new(at(&self.origin), at(&self.dir))
    }
}

/// The closest hits of eight rays, in lanes: which lanes hit (`found`, bit
/// `i` for lane `i`) and, in those lanes, `t`, the barycentrics and the
/// triangle's index (as a bit pattern).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Closest8 {
    /// The lanes that hit, one bit each.
    pub(crate) found: u32,
    /// Ray parameters.
    pub(crate) t: F8,
    /// Weights of `v1`.
    pub(crate) b1: F8,
    /// Weights of `v2`.
    pub(crate) b2: F8,
    /// Triangle indices, as the bit patterns of the lanes.
    pub(crate) prim: F8,
}

impl Closest8 {
    /// The packet's answers as eight [`Hit`]s (only inside AVX2 code: compiled
    /// without it, its lane reads were left as calls).
    #[target_feature(enable = "avx2")]
    #[inline]
    pub(crate) fn hits(self) -> [Option<Hit>; 8] {
        let (t, b1, b2) = (self.t.to_array(), self.b1.to_array(), self.b2.to_array());
        let prim = self.prim.to_array();
        let mut hits = [None; 8];
        for (lane, hit) in hits.iter_mut().enumerate() {
            if self.found >> lane & 1 != 0 {
                *hit = Some(Hit {
                    t: t[lane],
                    prim: prim[lane].to_bits(),
                    b1: b1[lane],
                    b2: b2[lane],
                });
            }
        }
        hits
    }
}
