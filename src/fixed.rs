//! Exact sums of samples: fixed point with 64 fraction bits in an `i128`.
//!
//! A render's per-pixel sums are kept this way (see
//! [`crate::render::Accumulator`]) because integer addition is associative:
//! samples summed in any order or in any split (passes, a render stopped and
//! resumed, sample ranges rendered on different machines and merged) give the
//! same sums bit for bit, which f64 sums do not. Each sample is rounded
//! towards zero to a multiple of 2⁻⁶⁴ (5.4e-20) and clamped to ±2⁴²
//! (4.4e12), so that [`crate::limits::MAX_SPP`] = 2²⁰ samples cannot overflow
//! the sum (2⁴²·2²⁰·2⁶⁴ = 2¹²⁶ < 2¹²⁷). Near 1 that is 40 bits finer than an
//! f32, and finer than a sum of 2²⁰ samples in f64.

/// Fraction bits of a fixed-point sum.
pub const FRACTION_BITS: u32 = 64;

/// Largest magnitude of one sample; larger ones are clamped to it.
pub const MAX_SAMPLE: f32 = (1u64 << 42) as f32;

/// `v` in fixed point: rounded towards zero to a multiple of 2⁻⁶⁴, clamped to
/// ±[`MAX_SAMPLE`]; NaN counts as 0 (callers drop NaN samples before).
#[inline]
pub fn fixed(v: f32) -> i128 {
    // From the bits, with selects rather than branches (this runs three
    // times per sample): |v| = m·2^(e − 150) for a normal number with biased
    // exponent e, which is m·2^(e − 86) units of 2⁻⁶⁴: m shifted left by
    // e − 86 (at most 82, below the clamp) or right by 86 − e (all gone from
    // 24 on, which also sends zeros and subnormals to 0).
    let bits = v.to_bits();
    let e = (bits >> 23) & 0xff;
    let m = u64::from((bits & 0x7f_ffff) | 0x80_0000);
    let up = e.saturating_sub(86).min(82);
    let down = 86u32.saturating_sub(e).min(63);
    let mut magnitude = u128::from(m >> down) << up;
    // |v| ≥ 2⁴² and ±∞ clamp; NaN is 0.
    let clamp = (MAX_SAMPLE as u128) << FRACTION_BITS;
    magnitude = if e >= 127 + 42 { clamp } else { magnitude };
    magnitude = if v.is_nan() { 0 } else { magnitude };
    let sign = -i128::from(bits >> 31 == 1);
    (magnitude as i128 ^ sign) - sign
}

/// [`fixed`] written out with branches, case by case: the reference in tests.
#[cfg(test)]
fn fixed_by_bits(v: f32) -> i128 {
    let bits = v.to_bits();
    let biased = ((bits >> 23) & 0xff) as i32;
    // The value is m · 2^(biased − 150) for normal numbers; in fixed point
    // that is m shifted by biased − 150 + 64.
    let magnitude: i128 = if biased == 0xff {
        if bits & 0x7f_ffff == 0 {
            (MAX_SAMPLE as i128) << FRACTION_BITS
        } else {
            return 0;
        }
    } else if biased >= 127 + 42 {
        (MAX_SAMPLE as i128) << FRACTION_BITS
    } else if biased == 0 {
        0
    } else {
        let m = ((bits & 0x7f_ffff) | 0x80_0000) as i128;
        let shift = biased - 150 + FRACTION_BITS as i32;
        if shift >= 0 {
            m << shift
        } else if shift > -24 {
            m >> -shift
        } else {
            0
        }
    };
    if bits >> 31 == 1 {
        -magnitude
    } else {
        magnitude
    }
}

/// The fixed-point sum `s` as an f64: its whole part plus its fraction,
/// each converted exactly or to nearest and added with one more rounding.
/// Deterministic, and cheaper than a correctly rounded `i128` conversion,
/// which is a library call.
#[inline]
pub fn to_f64(s: i128) -> f64 {
    const TWO_MINUS_64: f64 = 1.0 / 18_446_744_073_709_551_616.0;
    // The arithmetic shift floors, so the fraction is the non-negative rest.
    let whole = (s >> 64) as i64 as f64;
    let fraction = (s as u64) as f64 * TWO_MINUS_64;
    whole + fraction
}

/// Fixed-point RGB sums of one pixel.
pub type Fixed3 = [i128; 3];

/// Adds the samples of `v` to `sum`. The three conversions run in AVX2
/// lanes where the CPU has it (the same sums, bit for bit): one at a time they
/// were 130 of a `direct` sample's 920 instructions.
#[inline]
pub fn add3(sum: &mut Fixed3, v: glam::Vec3A) {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: the CPU has AVX2.
        unsafe { add3_avx2(sum, v) };
        return;
    }
    add3_scalar(sum, v);
}

/// [`add3`] one channel at a time.
#[inline]
fn add3_scalar(sum: &mut Fixed3, v: glam::Vec3A) {
    sum[0] += fixed(v.x);
    sum[1] += fixed(v.y);
    sum[2] += fixed(v.z);
}

/// [`fixed`] of x, y and z in three 64-bit lanes, each as two halves (the
/// high and low 64 bits of the `i128`), then added to the sums with carries.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn add3_avx2(sum: &mut Fixed3, v: glam::Vec3A) {
    let (lo, hi) = fixed_halves(v);
    add_halves(sum, lo, hi);
}

/// Adds eight samples to the sums of their pixels: `sums[index[k]] += v[k]`
/// (the eight of a 4×2 block of the lab's integrators). The same sums as
/// eight [`add3`] calls, for fewer instructions (one call and one feature
/// test, the constants loaded once).
#[inline]
pub fn add8(sums: &mut [Fixed3], index: [usize; 8], v: [glam::Vec3A; 8]) {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: the CPU has AVX2.
        unsafe { add8_avx2(sums, index, v) };
        return;
    }
    for (i, v) in index.into_iter().zip(v) {
        add3_scalar(&mut sums[i], v);
    }
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn add8_avx2(sums: &mut [Fixed3], index: [usize; 8], v: [glam::Vec3A; 8]) {
    use std::arch::x86_64::*;
    // The eight samples channel by channel (a 4×4 transpose in each half):
    // 24 conversions in six registers of four, where the samples one by one
    // took eight with a lane wasted each.
    // (Macros, not closures: a closure is compiled without AVX2, and its
    // intrinsics may be left as calls.)
    macro_rules! row {
        ($a:expr, $b:expr) => {
            _mm256_set_m128(v[$b].into(), v[$a].into())
        };
    }
    let (r0, r1, r2, r3) = (row!(0, 4), row!(1, 5), row!(2, 6), row!(3, 7));
    let (t0, t1) = (_mm256_unpacklo_ps(r0, r1), _mm256_unpackhi_ps(r0, r1));
    let (t2, t3) = (_mm256_unpacklo_ps(r2, r3), _mm256_unpackhi_ps(r2, r3));
    let channels = [
        _mm256_shuffle_ps::<0x44>(t0, t2),
        _mm256_shuffle_ps::<0xee>(t0, t2),
        _mm256_shuffle_ps::<0x44>(t1, t3),
    ];
    add_channels(sums, index, channels);
}

/// Adds eight samples given channel by channel (`v[c][k]` is channel `c` of
/// sample `k`) to the sums of their pixels, as [`add8`] does.
#[inline]
pub fn add8_channels(sums: &mut [Fixed3], index: [usize; 8], v: &[[f32; 8]; 3]) {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: the CPU has AVX2.
        unsafe { add8_channels_avx2(sums, index, v) };
        return;
    }
    for (k, i) in index.into_iter().enumerate() {
        add3_scalar(&mut sums[i], glam::Vec3A::new(v[0][k], v[1][k], v[2][k]));
    }
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn add8_channels_avx2(sums: &mut [Fixed3], index: [usize; 8], v: &[[f32; 8]; 3]) {
    use std::arch::x86_64::*;
    // SAFETY: each row is eight f32.
    let channels = unsafe {
        [
            _mm256_loadu_ps(v[0].as_ptr()),
            _mm256_loadu_ps(v[1].as_ptr()),
            _mm256_loadu_ps(v[2].as_ptr()),
        ]
    };
    add_channels(sums, index, channels);
}

/// `sums[index[k]] += fixed(channels[c][k])` for the three channels.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
fn add_channels(sums: &mut [Fixed3], index: [usize; 8], channels: [std::arch::x86_64::__m256; 3]) {
    let (lx, hx) = fixed_halves8(channels[0]);
    let (ly, hy) = fixed_halves8(channels[1]);
    let (lz, hz) = fixed_halves8(channels[2]);
    // SAFETY: six pairs of four 64-bit lanes are three rows of eight u64.
    let (lo, hi): ([[u64; 8]; 3], [[u64; 8]; 3]) = unsafe {
        (
            std::mem::transmute::<[[Wide; 2]; 3], [[u64; 8]; 3]>([lx, ly, lz]),
            std::mem::transmute::<[[Wide; 2]; 3], [[u64; 8]; 3]>([hx, hy, hz]),
        )
    };
    for (k, &i) in index.iter().enumerate() {
        let sum = &mut sums[i];
        for c in 0..3 {
            let x = (u128::from(hi[c][k]) << 64 | u128::from(lo[c][k])) as i128;
            sum[c] = sum[c].wrapping_add(x);
        }
    }
}

/// [`fixed`] of eight values: the low and high 64 bits of each `i128`, lanes
/// 0–3 in the first register of each pair and 4–7 in the second.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
fn fixed_halves8(v: std::arch::x86_64::__m256) -> ([Wide; 2], [Wide; 2]) {
    let parts = fixed_parts(v);
    let (l0, h0) = fixed_wide(&parts, false);
    let (l1, h1) = fixed_wide(&parts, true);
    ([l0, l1], [h0, h1])
}

/// [`fixed`] of x, y and z (and w, unused) as the low and high 64 bits of
/// each `i128`, in four 64-bit lanes.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
fn fixed_halves(v: glam::Vec3A) -> (Wide, Wide) {
    use std::arch::x86_64::*;
    // The 32-bit work costs the same on eight lanes as on four.
    fixed_wide(&fixed_parts(_mm256_castps128_ps256(v.into())), false)
}

/// Four 64-bit lanes.
#[cfg(target_arch = "x86_64")]
type Wide = std::arch::x86_64::__m256i;

/// The 32-bit part of [`fixed`] on eight lanes: mantissa, the left and right
/// shifts, and the clamp, NaN and sign masks.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
fn fixed_parts(v: std::arch::x86_64::__m256) -> [Wide; 6] {
    use std::arch::x86_64::*;
    let bits = _mm256_castps_si256(v);
    let e = _mm256_and_si256(_mm256_srli_epi32::<23>(bits), _mm256_set1_epi32(0xff));
    let zero = _mm256_setzero_si256();
    let up = _mm256_min_epi32(
        _mm256_max_epi32(_mm256_sub_epi32(e, _mm256_set1_epi32(86)), zero),
        _mm256_set1_epi32(82),
    );
    let down = _mm256_min_epi32(
        _mm256_max_epi32(_mm256_sub_epi32(_mm256_set1_epi32(86), e), zero),
        _mm256_set1_epi32(63),
    );
    let m = _mm256_or_si256(
        _mm256_and_si256(bits, _mm256_set1_epi32(0x7f_ffff)),
        _mm256_set1_epi32(0x80_0000),
    );
    // |v| ≥ 2⁴² and ±∞ clamp; NaN is 0.
    let clamp = _mm256_cmpgt_epi32(e, _mm256_set1_epi32(127 + 42 - 1));
    let nan = _mm256_castps_si256(_mm256_cmp_ps::<_CMP_UNORD_Q>(v, v));
    let sign = _mm256_srai_epi32::<31>(bits);
    [m, up, down, clamp, nan, sign]
}

/// The 64-bit part of [`fixed`] on the lower or `upper` four lanes of
/// [`fixed_parts`]: the low and high halves of each `i128`. AVX2's variable
/// shifts give 0 for counts of 64 or more, which the shifts rely on (a count
/// "below zero" wraps to a huge one).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
fn fixed_wide(parts: &[Wide; 6], upper: bool) -> (Wide, Wide) {
    use std::arch::x86_64::*;
    // (A macro, not a closure: a closure is compiled without AVX2, and its
    // intrinsics may be left as calls.)
    macro_rules! half {
        ($x:expr) => {
            if upper {
                _mm256_extracti128_si256::<1>($x)
            } else {
                _mm256_castsi256_si128($x)
            }
        };
    }
    let [m, up, down, clamp, nan, sign] = *parts;
    let m = _mm256_cvtepu32_epi64(half!(m));
    let up = _mm256_cvtepu32_epi64(half!(up));
    let down = _mm256_cvtepu32_epi64(half!(down));
    let clamp = _mm256_cvtepi32_epi64(half!(clamp));
    let nan = _mm256_cvtepi32_epi64(half!(nan));
    let sign = _mm256_cvtepi32_epi64(half!(sign));
    // m >> down << up as 128 bits: `up` and `down` are never both non-zero.
    let m = _mm256_srlv_epi64(m, down);
    let sixty_four = _mm256_set1_epi64x(64);
    let lo = _mm256_sllv_epi64(m, up);
    let hi = _mm256_or_si256(
        _mm256_srlv_epi64(m, _mm256_sub_epi64(sixty_four, up)),
        _mm256_sllv_epi64(m, _mm256_sub_epi64(up, sixty_four)),
    );
    let keep = _mm256_andnot_si256(nan, _mm256_andnot_si256(clamp, _mm256_set1_epi64x(-1)));
    let lo = _mm256_and_si256(lo, keep);
    let hi = _mm256_or_si256(
        _mm256_and_si256(hi, keep),
        _mm256_andnot_si256(nan, _mm256_and_si256(clamp, _mm256_set1_epi64x(1 << 42))),
    );
    // Negative values: the 128-bit two's complement, !x + 1, whose carry
    // reaches the high half when the low half is 0.
    let lo_zero = _mm256_cmpeq_epi64(lo, _mm256_setzero_si256());
    let lo = _mm256_sub_epi64(_mm256_xor_si256(lo, sign), sign);
    let hi = _mm256_sub_epi64(_mm256_xor_si256(hi, sign), _mm256_and_si256(sign, lo_zero));
    (lo, hi)
}

/// Adds the x, y and z lanes of [`fixed_halves`] to `sum`, with carries.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
fn add_halves(sum: &mut Fixed3, lo: Wide, hi: Wide) {
    use std::arch::x86_64::*;
    let mut los = [0u64; 4];
    let mut his = [0u64; 4];
    // SAFETY: both arrays hold four 64-bit lanes.
    unsafe {
        _mm256_storeu_si256(los.as_mut_ptr().cast(), lo);
        _mm256_storeu_si256(his.as_mut_ptr().cast(), hi);
    }
    for c in 0..3 {
        sum[c] = sum[c].wrapping_add((u128::from(his[c]) << 64 | u128::from(los[c])) as i128);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn conversion_is_exact_where_f32_fits_the_grid() {
        // Every f32 from 2⁻⁴¹ up lies on the grid.
        for v in [
            0.0f32, 1.0, -1.0, 0.5, 3.25, 1e-6, -7e5, 1e12, 5e-13, 123.456,
        ] {
            let exact = (v as f64 * 2f64.powi(64)).trunc();
            assert_eq!(fixed(v) as f64, exact, "{v}");
            // Round trip: the f32 comes back exactly.
            assert_eq!(to_f64(fixed(v)) as f32, v, "{v}");
        }
        // Below it: truncated towards zero.
        assert_eq!(
            fixed(1.5e-19),
            (1.5e-19f32 as f64 * 2f64.powi(64)).trunc() as i128
        );
        assert_eq!(fixed(1e-20), 0);
        assert_eq!(fixed(f32::MIN_POSITIVE), 0);
        assert_eq!(fixed(-3e-20), -(3e-20f64 * 2f64.powi(64)).trunc() as i128);
    }

    #[test]
    fn the_conversion_equals_the_reference_by_cases() {
        let mut x = 0x9e37_79b9_7f4a_7c15u64;
        let check = |v: f32| assert_eq!(fixed(v), fixed_by_bits(v), "{v:e} ({:#x})", v.to_bits());
        for _ in 0..2_000_000 {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            check(f32::from_bits(x as u32));
        }
        for v in [
            0.0,
            -0.0,
            1.0,
            -1.0,
            MAX_SAMPLE,
            -MAX_SAMPLE,
            f32::MAX,
            f32::MIN_POSITIVE,
            5.4e-20,
            5.5e-20,
        ] {
            check(v);
            check(v.next_up());
            check(v.next_down());
        }
    }

    /// The lanes' conversion adds exactly what the scalar one does, on random
    /// bit patterns (NaNs, infinities, subnormals, both signs) and on the
    /// edges of each case.
    #[test]
    fn lanes_add_what_one_at_a_time_adds() {
        let mut x = 0x51_7cc1_b727_220au64;
        let mut next = || {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            x
        };
        let mut edges = Vec::new();
        for v in [
            0.0f32,
            1.0,
            MAX_SAMPLE,
            f32::MAX,
            f32::MIN_POSITIVE,
            5.4e-20,
            2f32.powi(-41),
            2f32.powi(22),
            f32::INFINITY,
        ] {
            for w in [v, v.next_up(), v.next_down()] {
                edges.extend([w, -w]);
            }
        }
        edges.push(f32::NAN);
        // Far from zero, so that carries between the halves are exercised.
        let mut lanes: Fixed3 = [1 << 100, -3, -(1 << 100) + 7];
        let mut one = lanes;
        for round in 0..300_000 {
            let v = if round < edges.len() * 3 {
                let i = round % edges.len();
                glam::Vec3A::new(
                    edges[i],
                    edges[(i + 1) % edges.len()],
                    edges[(i + 7) % edges.len()],
                )
            } else {
                let r = next();
                glam::Vec3A::new(
                    f32::from_bits(r as u32),
                    f32::from_bits((r >> 32) as u32),
                    f32::from_bits((r >> 16) as u32),
                )
            };
            add3(&mut lanes, v);
            for c in 0..3 {
                one[c] += fixed(v[c]);
            }
            assert_eq!(lanes, one, "round {round}: {v:?}");
        }
    }

    /// Eight samples at once add what they add one at a time, to the pixels
    /// named (some named twice).
    #[test]
    fn eight_at_once_add_what_one_at_a_time_adds() {
        let mut x = 0x2f1d_9a3b_57c4_e601u64;
        let mut next = move || {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            x
        };
        let mut together = vec![[5i128 << 90, -7, 3]; 16];
        let mut apart = together.clone();
        for round in 0..20_000 {
            let index: [usize; 8] = std::array::from_fn(|_| (next() % 16) as usize);
            let v: [glam::Vec3A; 8] = std::array::from_fn(|_| {
                let r = next();
                let f = |b: u64| {
                    // Mostly ordinary magnitudes, sometimes any bit pattern.
                    if round % 4 == 0 {
                        f32::from_bits(b as u32)
                    } else {
                        (b as u32 >> 8) as f32 / (1u32 << 20) as f32 - 8.0
                    }
                };
                glam::Vec3A::new(f(r), f(r >> 21), f(r >> 42))
            });
            add8(&mut together, index, v);
            for (i, v) in index.into_iter().zip(v) {
                add3_scalar(&mut apart[i], v);
            }
            assert_eq!(together, apart, "round {round}");
        }
    }

    #[test]
    fn huge_values_clamp_and_cannot_overflow_a_full_render() {
        let max = fixed(MAX_SAMPLE);
        assert_eq!(fixed(1e20), max);
        assert_eq!(fixed(f32::INFINITY), max);
        assert_eq!(fixed(f32::NEG_INFINITY), -max);
        assert_eq!(fixed(f32::NAN), 0);
        assert!(max.checked_mul(crate::limits::MAX_SPP as i128).is_some());
    }

    #[test]
    fn sums_do_not_depend_on_order_or_grouping() {
        // Values over 32 orders of magnitude (below the clamp), where f64 sums
        // would round.
        let mut x = 0x2545_f491_4f6c_dd1du64;
        let values: Vec<f32> = (0..10_000)
            .map(|_| {
                x ^= x << 13;
                x ^= x >> 7;
                x ^= x << 17;
                let e = (x % 32) as i32 - 20;
                (x >> 40) as f32 / (1u64 << 24) as f32 * 10f32.powi(e)
            })
            .collect();
        let forward: i128 = values.iter().map(|&v| fixed(v)).sum();
        let backward: i128 = values.iter().rev().map(|&v| fixed(v)).sum();
        let halves: i128 = values[..3_333].iter().map(|&v| fixed(v)).sum::<i128>()
            + values[3_333..].iter().map(|&v| fixed(v)).sum::<i128>();
        assert_eq!(forward, backward);
        assert_eq!(forward, halves);
        // And the sum is the exact one, to the grid: compare in f64 against
        // a sorted (small first) sum, which is accurate to ~1e-16.
        let mut sorted: Vec<f64> = values.iter().map(|&v| v as f64).collect();
        sorted.sort_by(|a, b| a.partial_cmp(b).unwrap());
        let reference: f64 = sorted.iter().sum();
        assert!((to_f64(forward) - reference).abs() <= reference * 1e-15);
    }
}
