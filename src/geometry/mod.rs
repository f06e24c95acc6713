//! Geometry: rays, the watertight ray–triangle test and the eight-wide BVH that
//! answers the scene's ray queries.

pub mod bvh;
pub mod ray;
pub mod triangle;

/// The square roots of four lanes (`sqrtps`: correctly rounded, as `f32::sqrt`,
/// but one instruction for the four).
#[inline(always)]
pub fn sqrt4(v: glam::Vec4) -> glam::Vec4 {
    #[cfg(target_arch = "x86_64")]
    {
        // SAFETY: SSE is part of x86-64: every x86-64 CPU has `sqrtps`.
        glam::Vec4::from(unsafe { std::arch::x86_64::_mm_sqrt_ps(v.into()) })
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        v.map(f32::sqrt)
    }
}
