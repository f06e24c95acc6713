//! Deterministic random numbers keyed by (seed, pixel, sample).
//!
//! Every sample draws its numbers from a generator seeded by its own key, so an
//! image never depends on which thread rendered which tile, or in which order.

#[cfg(target_arch = "x86_64")]
use crate::simd::F8;

/// A small PCG32 generator (O'Neill 2014).
#[derive(Clone, Debug)]
pub struct Rng {
    state: u64,
    inc: u64,
}

/// SplitMix64 finaliser: a bijective 64-bit mix with good avalanche.
fn mix64(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// Two uniform numbers in `[0, 1)` (24 bits each) for sample `sample` of pixel
/// `pixel` in a render seeded `seed`: one SplitMix64 hash of the three, where
/// seeding a generator for two numbers cost three (46 instructions of a
/// `direct` sample's 840). The key is distinct for every pixel below 2⁴⁴ and
/// sample below 2²⁰ ([`crate::limits::MAX_PIXELS`], [`crate::limits::MAX_SPP`]).
#[inline]
pub fn pixel_jitter(seed: u64, pixel: u64, sample: u32) -> (f32, f32) {
    let h = mix64(((pixel << 20) | u64::from(sample)) ^ mix64(seed));
    let unit = 1.0 / (1u32 << 24) as f32;
    (
        (h >> 40) as f32 * unit,
        ((h >> 16) & 0xff_ffff) as f32 * unit,
    )
}

/// Two uniform numbers in `[0, 1)` for the thin lens of sample `sample` of
/// pixel `pixel` (the lab's integrators; `path` takes its own): the numbers
/// [`pixel_jitter`] gives for a seed of their own, so that the lens point is
/// independent of the point in the pixel.
#[inline]
pub fn lens_jitter(seed: u64, pixel: u64, sample: u32) -> (f32, f32) {
    // "lens" in ASCII, mixed: another seed for any seed.
    pixel_jitter(mix64(seed ^ 0x6c65_6e73), pixel, sample)
}

/// [`pixel_jitter`] of eight pixels, `first[0]..first[0] + 4` and
/// `first[1]..first[1] + 4` (a 4×2 block's two rows), in the lanes of AVX2
/// registers (only inside AVX2 code): the eight x and the eight y offsets, bit
/// for bit (AVX2 has no 64-bit multiply: each is three 32-bit ones).
#[cfg(target_arch = "x86_64")]
#[inline(always)]
pub(crate) fn pixel_jitter8(seed: u64, first: [u64; 2], sample: u32) -> (F8, F8) {
    use std::arch::x86_64::*;
    // SAFETY: only inside AVX2 code (see `crate::simd`).
    unsafe {
        // `a × b` modulo 2⁶⁴ in each 64-bit lane.
        macro_rules! mul {
            ($a:expr, $b:expr) => {{
                let (a, b) = ($a, _mm256_set1_epi64x($b as i64));
                let low = _mm256_mul_epu32(a, b);
                let cross = _mm256_add_epi64(
                    _mm256_mul_epu32(_mm256_srli_epi64::<32>(a), b),
                    _mm256_mul_epu32(a, _mm256_srli_epi64::<32>(b)),
                );
                _mm256_add_epi64(low, _mm256_slli_epi64::<32>(cross))
            }};
        }
        macro_rules! mix64 {
            ($z:expr) => {{
                let z = $z;
                let z = mul!(
                    _mm256_xor_si256(z, _mm256_srli_epi64::<30>(z)),
                    0xbf58_476d_1ce4_e5b9u64
                );
                let z = mul!(
                    _mm256_xor_si256(z, _mm256_srli_epi64::<27>(z)),
                    0x94d0_49bb_1331_11ebu64
                );
                _mm256_xor_si256(z, _mm256_srli_epi64::<31>(z))
            }};
        }
        let salt = _mm256_set1_epi64x(mix64(seed) as i64);
        let steps = _mm256_setr_epi64x(0, 1, 2, 3);
        macro_rules! row {
            ($first:expr) => {{
                let pixel = _mm256_add_epi64(_mm256_set1_epi64x($first as i64), steps);
                let key = _mm256_or_si256(
                    _mm256_slli_epi64::<20>(pixel),
                    _mm256_set1_epi64x(i64::from(sample)),
                );
                mix64!(_mm256_xor_si256(key, salt))
            }};
        }
        let (top, below) = (row!(first[0]), row!(first[1]));
        // The eight 32-bit words of bits `shift..shift + 24` of the hashes.
        let gather = _mm256_setr_epi32(0, 2, 4, 6, 1, 3, 5, 7);
        macro_rules! words {
            ($shift:literal) => {{
                let a = _mm256_permutevar8x32_epi32(_mm256_srli_epi64::<$shift>(top), gather);
                let b = _mm256_permutevar8x32_epi32(_mm256_srli_epi64::<$shift>(below), gather);
                let w = _mm256_permute2x128_si256::<0x20>(a, b);
                _mm256_and_si256(w, _mm256_set1_epi32(0xff_ffff))
            }};
        }
        let unit = _mm256_set1_ps(1.0 / (1u32 << 24) as f32);
        (
            F8(_mm256_mul_ps(_mm256_cvtepi32_ps(words!(40)), unit)),
            F8(_mm256_mul_ps(_mm256_cvtepi32_ps(words!(16)), unit)),
        )
    }
}

impl Rng {
    /// A generator for stream `key` of a render seeded with `seed`.
    pub fn new(seed: u64, key: u64) -> Self {
        let mut rng = Self {
            state: 0,
            inc: (mix64(key ^ 0x9e37_79b9_7f4a_7c15) << 1) | 1,
        };
        rng.next_u32();
        rng.state = rng.state.wrapping_add(mix64(seed));
        rng.next_u32();
        rng
    }

    /// The generator of sample `sample` of pixel `pixel`.
    pub fn for_sample(seed: u64, pixel: u64, sample: u32) -> Self {
        Self::new(seed, mix64(pixel).wrapping_add(sample as u64))
    }

    /// The next 32 random bits.
    #[inline]
    pub fn next_u32(&mut self) -> u32 {
        let old = self.state;
        self.state = old
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(self.inc);
        let xorshifted = (((old >> 18) ^ old) >> 27) as u32;
        let rot = (old >> 59) as u32;
        xorshifted.rotate_right(rot)
    }

    /// A uniform float in `[0, 1)`.
    #[inline]
    pub fn next_f32(&mut self) -> f32 {
        (self.next_u32() >> 8) as f32 * (1.0 / (1u32 << 24) as f32)
    }
}

#[cfg(test)]
mod tests {
    /// The jitter of a 4×2 block in lanes is the pixels' own, bit for bit.
    #[test]
    fn jitter_of_eight_pixels_matches_one_by_one() {
        #[target_feature(enable = "avx2")]
        fn lanes(seed: u64, first: [u64; 2], sample: u32) -> ([f32; 8], [f32; 8]) {
            let (x, y) = pixel_jitter8(seed, first, sample);
            (x.to_array(), y.to_array())
        }
        if !std::arch::is_x86_feature_detected!("avx2") {
            return;
        }
        let mut rng = Rng::new(77, 0);
        for round in 0..20_000u64 {
            let wide = |r: &mut Rng| u64::from(r.next_u32()) << 12 | u64::from(r.next_u32() >> 20);
            let seed = u64::from(rng.next_u32()) << 32 | u64::from(rng.next_u32());
            let first = [wide(&mut rng), wide(&mut rng)];
            let sample = if round % 2 == 0 {
                rng.next_u32() >> 12
            } else {
                round as u32 % 7
            };
            // SAFETY: the CPU has AVX2.
            let (x, y) = unsafe { lanes(seed, first, sample) };
            for i in 0..8 {
                let pixel = first[i / 4] + (i % 4) as u64;
                let (wx, wy) = pixel_jitter(seed, pixel, sample);
                assert_eq!(
                    (x[i].to_bits(), y[i].to_bits()),
                    (wx.to_bits(), wy.to_bits())
                );
            }
        }
    }

    use super::*;

    #[test]
    fn same_key_same_stream_other_key_other_stream() {
        let stream = |seed, pixel, sample| {
            let mut rng = Rng::for_sample(seed, pixel, sample);
            (0..8).map(|_| rng.next_u32()).collect::<Vec<u32>>()
        };
        let (a, b) = (stream(1, 42, 3), stream(1, 42, 3));
        let (c, d) = (stream(1, 42, 4), stream(2, 42, 3));
        assert_eq!(a, b);
        assert_ne!(a, c);
        assert_ne!(a, d);
    }

    #[test]
    fn floats_are_uniform_in_unit_interval() {
        let mut rng = Rng::new(0, 0);
        let n = 100_000;
        let mut buckets = [0u32; 10];
        let mut sum = 0.0f64;
        for _ in 0..n {
            let x = rng.next_f32();
            assert!((0.0..1.0).contains(&x));
            buckets[(x * 10.0) as usize] += 1;
            sum += x as f64;
        }
        assert!((sum / n as f64 - 0.5).abs() < 0.005);
        // Each decile within 5 standard deviations of n/10.
        for b in buckets {
            assert!((b as f64 - 10_000.0).abs() < 5.0 * 95.0, "{buckets:?}");
        }
    }
}
