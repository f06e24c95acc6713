//! Geometry: rays, the watertight ray–triangle test and the eight-wide BVH that
//! answers the scene's ray queries, and the analytic shapes (spheres, disks
//! and cylinders, the last two placed by an affine map, and the cells of
//! signed distance grids).

pub mod bvh;
pub mod cylinder;
pub mod disk;
pub(crate) mod packet;
pub mod placement;
pub mod ray;
pub mod sdf_voxel;
pub mod sdfgrid;
#[cfg(test)]
mod shape_checks;
pub mod sphere;
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

/// Each lane of `x` moved one representable value in the direction of the sign
/// of the same lane of `towards`: [`f32::next_up`] where it is positive,
/// [`f32::next_down`] where it is negative, unchanged where it is zero or NaN.
/// Bit for bit the scalar functions' answers (zeros, subnormals, infinities and
/// NaN included), in a dozen SSE2 instructions instead of a branchy call per lane.
#[inline(always)]
pub fn step_towards4(x: glam::Vec4, towards: glam::Vec4) -> glam::Vec4 {
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::x86_64::*;
        // SAFETY: SSE2 is part of x86-64.
        unsafe {
            let (x, o): (__m128, __m128) = (x.into(), towards.into());
            let zero = _mm_setzero_ps();
            let up = _mm_cmpgt_ps(o, zero);
            let down = _mm_cmplt_ps(o, zero);
            let positive = _mm_cmpgt_ps(x, zero);
            let negative = _mm_cmplt_ps(x, zero);
            // An infinity moved outwards stays what it is.
            let magnitude = _mm_andnot_ps(_mm_set1_ps(-0.0), x);
            let infinite = _mm_cmpeq_ps(magnitude, _mm_set1_ps(f32::INFINITY));
            // Away from zero the bit pattern grows by one, towards zero it shrinks
            // (a mask lane is -1 as an integer).
            let grow = _mm_andnot_ps(
                infinite,
                _mm_or_ps(_mm_and_ps(positive, up), _mm_and_ps(negative, down)),
            );
            let shrink = _mm_or_ps(_mm_and_ps(positive, down), _mm_and_ps(negative, up));
            let bits = _mm_sub_epi32(_mm_castps_si128(x), _mm_castps_si128(grow));
            let bits = _mm_castsi128_ps(_mm_add_epi32(bits, _mm_castps_si128(shrink)));
            // Either zero steps to the smallest subnormal of the direction's sign.
            let is_zero = _mm_cmpeq_ps(x, zero);
            let tiny = _mm_or_ps(
                _mm_castsi128_ps(_mm_set1_epi32(1)),
                _mm_and_ps(down, _mm_set1_ps(-0.0)),
            );
            let to_tiny = _mm_and_ps(is_zero, _mm_or_ps(up, down));
            glam::Vec4::from(_mm_or_ps(
                _mm_and_ps(to_tiny, tiny),
                _mm_andnot_ps(to_tiny, bits),
            ))
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        let (x, o) = (x.to_array(), towards.to_array());
        glam::Vec4::from_array(std::array::from_fn(|i| step_towards(x[i], o[i])))
    }
}

/// One lane of [`step_towards4`]: `next_up`, `next_down` or `x` by the sign of
/// `towards`.
pub fn step_towards(x: f32, towards: f32) -> f32 {
    if towards > 0.0 {
        x.next_up()
    } else if towards < 0.0 {
        x.next_down()
    } else {
        x
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec4;

    /// [`step_towards4`] against `next_up`/`next_down` lane by lane: special
    /// values in every combination, then random bit patterns.
    #[test]
    fn lanes_step_exactly_as_next_up_and_next_down() {
        let tiny = f32::from_bits(1);
        let special = [
            0.0,
            -0.0,
            tiny,
            -tiny,
            f32::MIN_POSITIVE,
            -f32::MIN_POSITIVE,
            1.0,
            -1.0,
            f32::MAX,
            f32::MIN,
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::NAN,
            -f32::NAN,
        ];
        let mut cases: Vec<(f32, f32)> = special
            .iter()
            .flat_map(|&x| special.iter().map(move |&o| (x, o)))
            .collect();
        let mut rng = crate::sampling::sampler::Rng::new(3, 4);
        cases.extend((0..200_000).map(|_| {
            (
                f32::from_bits(rng.next_u32()),
                f32::from_bits(rng.next_u32()),
            )
        }));
        for chunk in cases.chunks(4) {
            let lane = |i: usize| chunk[i.min(chunk.len() - 1)];
            let x = Vec4::new(lane(0).0, lane(1).0, lane(2).0, lane(3).0);
            let o = Vec4::new(lane(0).1, lane(1).1, lane(2).1, lane(3).1);
            let got = step_towards4(x, o).to_array();
            for (i, g) in got.iter().enumerate() {
                let (x, o) = lane(i);
                let want = step_towards(x, o);
                assert_eq!(
                    g.to_bits(),
                    want.to_bits(),
                    "x {x:e} ({:#x}) towards {o:e}",
                    x.to_bits()
                );
            }
        }
    }
}
