//! Eight f32 lanes of an AVX2 register, [`F8`], for the code that runs eight
//! rays or samples at once: the BVH's eight-ray packets and the lab's 4×2 pixel
//! blocks.
//!
//! Its methods are `#[inline(always)]` and only ever run inside functions
//! compiled with `#[target_feature(enable = "avx2")]` (called only when the CPU
//! has AVX2), into which they inline as single instructions. Closures are not
//! compiled with their caller's target features: intrinsics in them are left
//! as calls, so code on `F8` is written as functions and macros.

#![cfg(target_arch = "x86_64")]

use std::arch::x86_64::*;
use std::ops::{Add, BitAnd, BitOr, Div, Mul, Not, Sub};

/// Eight f32 lanes (also used as a mask: all bits set = true).
#[derive(Clone, Copy, Debug)]
#[repr(transparent)]
pub(crate) struct F8(pub(crate) __m256);

// SAFETY (for every `unsafe` block on `F8` below): the intrinsics need AVX (and
// AVX2 for none of them beyond AVX); `F8` values are only made and used inside
// functions compiled with AVX2 enabled, which are only called when
// `Isa::detect` found AVX2.
impl F8 {
    #[inline(always)]
    pub(crate) fn splat(x: f32) -> F8 {
        F8(unsafe { _mm256_set1_ps(x) })
    }
    #[inline(always)]
    pub(crate) fn zero() -> F8 {
        F8(unsafe { _mm256_setzero_ps() })
    }
    /// `lo` in lanes 0–3 and `hi` in lanes 4–7.
    #[inline(always)]
    pub(crate) fn halves(lo: glam::Vec4, hi: glam::Vec4) -> F8 {
        F8(unsafe { _mm256_set_m128(hi.into(), lo.into()) })
    }
    #[inline(always)]
    pub(crate) fn from_array(a: [f32; 8]) -> F8 {
        F8(unsafe { _mm256_loadu_ps(a.as_ptr()) })
    }
    #[inline(always)]
    pub(crate) fn to_array(self) -> [f32; 8] {
        let mut a = [0.0; 8];
        unsafe { _mm256_storeu_ps(a.as_mut_ptr(), self.0) };
        a
    }
    #[inline(always)]
    pub(crate) fn min(self, o: F8) -> F8 {
        F8(unsafe { _mm256_min_ps(self.0, o.0) })
    }
    #[inline(always)]
    pub(crate) fn max_(self, o: F8) -> F8 {
        F8(unsafe { _mm256_max_ps(self.0, o.0) })
    }
    #[inline(always)]
    pub(crate) fn cmple(self, o: F8) -> F8 {
        F8(unsafe { _mm256_cmp_ps::<_CMP_LE_OQ>(self.0, o.0) })
    }
    #[inline(always)]
    pub(crate) fn cmplt(self, o: F8) -> F8 {
        F8(unsafe { _mm256_cmp_ps::<_CMP_LT_OQ>(self.0, o.0) })
    }
    #[inline(always)]
    pub(crate) fn cmpgt(self, o: F8) -> F8 {
        F8(unsafe { _mm256_cmp_ps::<_CMP_GT_OQ>(self.0, o.0) })
    }
    #[inline(always)]
    pub(crate) fn cmpeq(self, o: F8) -> F8 {
        F8(unsafe { _mm256_cmp_ps::<_CMP_EQ_OQ>(self.0, o.0) })
    }
    #[inline(always)]
    pub(crate) fn cmpne(self, o: F8) -> F8 {
        F8(unsafe { _mm256_cmp_ps::<_CMP_NEQ_UQ>(self.0, o.0) })
    }
    /// Lanes of `a` where `mask` is set, else of `b`.
    #[inline(always)]
    pub(crate) fn select(mask: F8, a: F8, b: F8) -> F8 {
        F8(unsafe { _mm256_blendv_ps(b.0, a.0, mask.0) })
    }
    #[inline(always)]
    pub(crate) fn bitmask(self) -> u32 {
        unsafe { _mm256_movemask_ps(self.0) as u32 }
    }
    #[inline(always)]
    pub(crate) fn any(self) -> bool {
        self.bitmask() != 0
    }
    /// ±1 with the sign of each lane (as `Vec4::signum` for non-NaN lanes).
    #[inline(always)]
    pub(crate) fn signum(self) -> F8 {
        unsafe {
            let sign = _mm256_and_ps(self.0, _mm256_set1_ps(-0.0));
            F8(_mm256_or_ps(sign, _mm256_set1_ps(1.0)))
        }
    }
    #[inline(always)]
    pub(crate) fn lane(self, i: usize) -> f32 {
        self.to_array()[i]
    }
    /// Correctly rounded square roots (`vsqrtps`, as `f32::sqrt` lane by lane).
    #[inline(always)]
    pub(crate) fn sqrt(self) -> F8 {
        F8(unsafe { _mm256_sqrt_ps(self.0) })
    }
    /// The lanes with their signs flipped (as `-x`).
    #[inline(always)]
    pub(crate) fn neg(self) -> F8 {
        F8(unsafe { _mm256_xor_ps(self.0, _mm256_set1_ps(-0.0)) })
    }
    /// Lane `i` in every lane.
    #[inline(always)]
    pub(crate) fn broadcast_lane(self, i: usize) -> F8 {
        F8(unsafe { _mm256_permutevar8x32_ps(self.0, _mm256_set1_epi32(i as i32)) })
    }
    /// `crate::geometry::step_towards4` on eight lanes: each lane moved one
    /// representable value in the direction of the sign of the same lane of
    /// `towards` (`next_up`, `next_down`, or unchanged at zero and NaN), bit
    /// for bit.
    #[inline(always)]
    pub(crate) fn step_towards(self, towards: F8) -> F8 {
        unsafe {
            let (x, o) = (self.0, towards.0);
            let zero = _mm256_setzero_ps();
            let up = _mm256_cmp_ps::<_CMP_GT_OQ>(o, zero);
            let down = _mm256_cmp_ps::<_CMP_LT_OQ>(o, zero);
            let positive = _mm256_cmp_ps::<_CMP_GT_OQ>(x, zero);
            let negative = _mm256_cmp_ps::<_CMP_LT_OQ>(x, zero);
            // An infinity moved outwards stays what it is.
            let magnitude = _mm256_andnot_ps(_mm256_set1_ps(-0.0), x);
            let infinite = _mm256_cmp_ps::<_CMP_EQ_OQ>(magnitude, _mm256_set1_ps(f32::INFINITY));
            // Away from zero the bit pattern grows by one, towards zero it
            // shrinks (a mask lane is -1 as an integer).
            let grow = _mm256_andnot_ps(
                infinite,
                _mm256_or_ps(_mm256_and_ps(positive, up), _mm256_and_ps(negative, down)),
            );
            let shrink = _mm256_or_ps(_mm256_and_ps(positive, down), _mm256_and_ps(negative, up));
            let bits = _mm256_sub_epi32(_mm256_castps_si256(x), _mm256_castps_si256(grow));
            let bits = _mm256_castsi256_ps(_mm256_add_epi32(bits, _mm256_castps_si256(shrink)));
            // Either zero steps to the smallest subnormal of the direction's sign.
            let is_zero = _mm256_cmp_ps::<_CMP_EQ_OQ>(x, zero);
            let tiny = _mm256_or_ps(
                _mm256_castsi256_ps(_mm256_set1_epi32(1)),
                _mm256_and_ps(down, _mm256_set1_ps(-0.0)),
            );
            let to_tiny = _mm256_and_ps(is_zero, _mm256_or_ps(up, down));
            F8(_mm256_blendv_ps(bits, tiny, to_tiny))
        }
    }
    /// Lane 0.
    #[inline(always)]
    pub(crate) fn first(self) -> f32 {
        unsafe { _mm256_cvtss_f32(self.0) }
    }
    /// Lane 0 in every lane.
    #[inline(always)]
    pub(crate) fn broadcast_first(self) -> F8 {
        F8(unsafe { _mm256_permutevar8x32_ps(self.0, _mm256_setzero_si256()) })
    }
    /// The smallest lane.
    #[inline(always)]
    pub(crate) fn min_element(self) -> f32 {
        unsafe {
            let m = _mm_min_ps(
                _mm256_castps256_ps128(self.0),
                _mm256_extractf128_ps::<1>(self.0),
            );
            let m = _mm_min_ps(m, _mm_movehl_ps(m, m));
            let m = _mm_min_ss(m, _mm_shuffle_ps::<1>(m, m));
            _mm_cvtss_f32(m)
        }
    }
    /// The largest lane.
    #[inline(always)]
    pub(crate) fn max_element(self) -> f32 {
        unsafe {
            let m = _mm_max_ps(
                _mm256_castps256_ps128(self.0),
                _mm256_extractf128_ps::<1>(self.0),
            );
            let m = _mm_max_ps(m, _mm_movehl_ps(m, m));
            let m = _mm_max_ss(m, _mm_shuffle_ps::<1>(m, m));
            _mm_cvtss_f32(m)
        }
    }
    /// The smallest of lanes 0–3.
    #[inline(always)]
    pub(crate) fn min_lower(self) -> f32 {
        unsafe {
            let m = _mm256_castps256_ps128(self.0);
            let m = _mm_min_ps(m, _mm_movehl_ps(m, m));
            let m = _mm_min_ss(m, _mm_shuffle_ps::<1>(m, m));
            _mm_cvtss_f32(m)
        }
    }
    /// All lanes set where `bits` has a bit.
    #[inline(always)]
    pub(crate) fn mask_from_bits(bits: u32) -> F8 {
        unsafe {
            let lanes = _mm256_setr_epi32(1, 2, 4, 8, 16, 32, 64, 128);
            let b = _mm256_set1_epi32(bits as i32);
            F8(_mm256_castsi256_ps(_mm256_cmpeq_epi32(
                _mm256_and_si256(b, lanes),
                lanes,
            )))
        }
    }
}

impl Add for F8 {
    type Output = F8;
    #[inline(always)]
    fn add(self, o: F8) -> F8 {
        F8(unsafe { _mm256_add_ps(self.0, o.0) })
    }
}
impl Sub for F8 {
    type Output = F8;
    #[inline(always)]
    fn sub(self, o: F8) -> F8 {
        F8(unsafe { _mm256_sub_ps(self.0, o.0) })
    }
}
impl Mul for F8 {
    type Output = F8;
    #[inline(always)]
    fn mul(self, o: F8) -> F8 {
        F8(unsafe { _mm256_mul_ps(self.0, o.0) })
    }
}
impl Div for F8 {
    type Output = F8;
    #[inline(always)]
    fn div(self, o: F8) -> F8 {
        F8(unsafe { _mm256_div_ps(self.0, o.0) })
    }
}
impl BitAnd for F8 {
    type Output = F8;
    #[inline(always)]
    fn bitand(self, o: F8) -> F8 {
        F8(unsafe { _mm256_and_ps(self.0, o.0) })
    }
}
impl BitOr for F8 {
    type Output = F8;
    #[inline(always)]
    fn bitor(self, o: F8) -> F8 {
        F8(unsafe { _mm256_or_ps(self.0, o.0) })
    }
}
impl Not for F8 {
    type Output = F8;
    #[inline(always)]
    fn not(self) -> F8 {
        F8(unsafe { _mm256_xor_ps(self.0, _mm256_castsi256_ps(_mm256_set1_epi32(-1))) })
    }
}
