//! Pixel reconstruction filters by importance sampling ([`PixelFilter`]):
//! each sample's image point is drawn from the filter around the pixel's
//! centre and counts with weight 1, so a pixel's value is still a plain
//! mean of its own samples (raylab's exact per-pixel sums) and converges to
//! the filter-weighted image that Mitsuba's splatting computes: the
//! normalised filter times the radiance, integrated.
//!
//! The filters are Mitsuba 3's (`src/rfilters/`), separable in x and y:
//! `box` (the pixel's own square), `tent` of radius r (`1 − |x|/r`) and
//! `gaussian` of standard deviation σ, cut off at 4σ and lowered to reach
//! zero there (`exp(−x²/2σ²) − exp(−8)`).
//!
//! A render may instead *splat* ([`Reconstruction::Splat`], Mitsuba's way):
//! each sample's point is uniform in its pixel and the sample is added to
//! every pixel within the filter's radius, weighted by the filter normalised
//! over the image ([`super::splat::SplatWeights`]). Same expected image; each pixel then
//! averages its neighbours' samples too, which lowers its own noise
//! (neighbouring pixels' noise correlated).

use glam::Vec2;

/// How a render reconstructs pixels from samples under a filter other than
/// the box (with the box both are the same).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Reconstruction {
    /// Each sample's image point is drawn from the filter and counts in its
    /// own pixel only (filter importance sampling).
    #[default]
    Sample,
    /// Each sample's point is uniform in its pixel and the sample is added,
    /// weighted, to every pixel within the filter's radius (Mitsuba's
    /// `hdrfilm`); for filters whose border ([`PixelFilter::splat_border`])
    /// is at most [`MAX_SPLAT_BORDER`] rows, and renders that do not gather
    /// per-pixel statistics (adaptive sampling, `--aov variance`), which
    /// sample instead.
    Splat,
}

impl Reconstruction {
    /// The name on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Reconstruction::Sample => "sample",
            Reconstruction::Splat => "splat",
        }
    }
}

/// The widest border (in pixels, beyond a sample's own) that a splatting
/// filter may reach; wider filters are sampled.
pub const MAX_SPLAT_BORDER: usize = 4;

/// How a pixel weighs the image around it. The widths are stored as `f32`
/// bits so that options holding a filter stay `Eq` and `Hash`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum PixelFilter {
    /// The pixel's own square (`[−½, ½]²` around its centre).
    #[default]
    Box,
    /// `max(0, 1 − |x|/r)` in x and in y.
    Tent {
        /// The radius r, as `f32` bits.
        radius_bits: u32,
    },
    /// `max(0, exp(−x²/2σ²) − exp(−8))` in x and y, out to 4σ.
    Gaussian {
        /// σ, as `f32` bits.
        stddev_bits: u32,
    },
}

impl PixelFilter {
    /// A tent of radius `radius` (> 0).
    pub fn tent(radius: f32) -> Self {
        PixelFilter::Tent {
            radius_bits: radius.to_bits(),
        }
    }

    /// A Gaussian of standard deviation `stddev` (> 0).
    pub fn gaussian(stddev: f32) -> Self {
        PixelFilter::Gaussian {
            stddev_bits: stddev.to_bits(),
        }
    }

    /// The image point's offset from the pixel's corner for the uniform pair
    /// `u`: `u` itself for the box (so box renders are unchanged bit for
    /// bit), else `½ + ` a point drawn from the filter.
    #[inline]
    pub fn offset(self, u: Vec2) -> Vec2 {
        match self {
            PixelFilter::Box => u,
            _ => Vec2::new(0.5 + self.sample_1d(u.x), 0.5 + self.sample_1d(u.y)),
        }
    }

    /// A point of the 1-D filter for uniform `u` in `[0, 1)` (its inverse
    /// cumulative distribution).
    fn sample_1d(self, u: f32) -> f32 {
        match self {
            PixelFilter::Box => u - 0.5,
            PixelFilter::Tent { radius_bits } => {
                let r = f32::from_bits(radius_bits);
                if u < 0.5 {
                    r * ((2.0 * u).sqrt() - 1.0)
                } else {
                    r * (1.0 - (2.0 * (1.0 - u)).sqrt())
                }
            }
            PixelFilter::Gaussian { stddev_bits } => {
                f32::from_bits(stddev_bits) * standard_gaussian_quantile(u)
            }
        }
    }

    /// The filter's radius: its weight is zero from there on.
    pub fn radius(self) -> f32 {
        match self {
            PixelFilter::Box => 0.5,
            PixelFilter::Tent { radius_bits } => f32::from_bits(radius_bits),
            PixelFilter::Gaussian { stddev_bits } => 4.0 * f32::from_bits(stddev_bits),
        }
    }

    /// How many pixels beyond its own, in each direction, a sample splatted
    /// with this filter can reach: the largest k with k − ½ below the radius.
    pub fn splat_border(self) -> usize {
        ((f64::from(self.radius()) + 0.5).ceil() as usize).saturating_sub(1)
    }

    /// Whether `reconstruction` splats with this filter (see
    /// [`Reconstruction::Splat`]; the box never needs to).
    pub fn splats(self, reconstruction: Reconstruction) -> bool {
        reconstruction == Reconstruction::Splat
            && self != PixelFilter::Box
            && self.splat_border() <= MAX_SPLAT_BORDER
    }

    /// The filter's 1-D weight at `x` (unnormalised).
    pub fn eval_1d(self, x: f32) -> f32 {
        match self {
            PixelFilter::Box => f32::from(u8::from(x.abs() <= 0.5)),
            PixelFilter::Tent { radius_bits } => {
                let r = f32::from_bits(radius_bits);
                (1.0 - x.abs() / r).max(0.0)
            }
            PixelFilter::Gaussian { stddev_bits } => {
                let s = f64::from(f32::from_bits(stddev_bits));
                let x = f64::from(x);
                let bias = (-8.0f64).exp();
                (((-x * x / (2.0 * s * s)).exp() - bias).max(0.0)) as f32
            }
        }
    }
}

/// The error function, from the Chebyshev fit of `erfc` in Press et al.,
/// Numerical Recipes (2nd ed., §6.2), fractional error below 1.2e-7.
fn erf(x: f64) -> f64 {
    let z = x.abs();
    let t = 1.0 / (1.0 + 0.5 * z);
    let poly = -z * z - 1.265_512_23
        + t * (1.000_023_68
            + t * (0.374_091_96
                + t * (0.096_784_18
                    + t * (-0.186_288_06
                        + t * (0.278_868_07
                            + t * (-1.135_203_98
                                + t * (1.488_515_87 + t * (-0.822_152_23 + t * 0.170_872_77))))))));
    let erfc = t * poly.exp();
    if x >= 0.0 { 1.0 - erfc } else { erfc - 1.0 }
}

/// The standard normal quantile Φ⁻¹(p) for p in (0, 1): P. J. Acklam's
/// rational approximation (relative error below 1.2e-9).
fn probit(p: f64) -> f64 {
    const A: [f64; 6] = [
        -3.969_683_028_665_376e1,
        2.209_460_984_245_205e2,
        -2.759_285_104_469_687e2,
        1.383_577_518_672_69e2,
        -3.066_479_806_614_716e1,
        2.506_628_277_459_239,
    ];
    const B: [f64; 5] = [
        -5.447_609_879_822_406e1,
        1.615_858_368_580_409e2,
        -1.556_989_798_598_866e2,
        6.680_131_188_771_972e1,
        -1.328_068_155_288_572e1,
    ];
    const C: [f64; 6] = [
        -7.784_894_002_430_293e-3,
        -3.223_964_580_411_365e-1,
        -2.400_758_277_161_838,
        -2.549_732_539_343_734,
        4.374_664_141_464_968,
        2.938_163_982_698_783,
    ];
    const D: [f64; 4] = [
        7.784_695_709_041_462e-3,
        3.224_671_290_700_398e-1,
        2.445_134_137_142_996,
        3.754_408_661_907_416,
    ];
    let p = p.clamp(1e-300, 1.0 - 1e-16);
    let tail = |q: f64| {
        (((((C[0] * q + C[1]) * q + C[2]) * q + C[3]) * q + C[4]) * q + C[5])
            / ((((D[0] * q + D[1]) * q + D[2]) * q + D[3]) * q + 1.0)
    };
    if p < 0.024_25 {
        tail((-2.0 * p.ln()).sqrt())
    } else if p > 1.0 - 0.024_25 {
        -tail((-2.0 * (1.0 - p).ln()).sqrt())
    } else {
        let q = p - 0.5;
        let r = q * q;
        (((((A[0] * r + A[1]) * r + A[2]) * r + A[3]) * r + A[4]) * r + A[5]) * q
            / (((((B[0] * r + B[1]) * r + B[2]) * r + B[3]) * r + B[4]) * r + 1.0)
    }
}

/// Segments of the tabulated standard quantile (of σ = 1).
const QUANTILE_SEGMENTS: usize = 4096;

/// The quantile of the truncated, lowered Gaussian of σ = 1 (every σ's is
/// σ times it: the filter is a function of x/σ alone) for `u` in `[0, 1)`:
/// a cubic Hermite interpolation of the exact quantile between
/// `QUANTILE_SEGMENTS` equal steps of `u`, from its values and its exact
/// slopes (the normaliser over the filter at the node), which stays within
/// 1e-5 σ of the Newton solve wherever |x| ≤ 3σ (the test bounds it; 99.7 %
/// of the mass). The two end segments, where the filter reaches zero and the
/// slope grows without bound, take the Newton solve itself. The solve costs
/// about as much as a path through a small scene; this costs two loads and
/// a few multiply-adds.
#[inline]
fn standard_gaussian_quantile(u: f32) -> f32 {
    static TABLE: std::sync::OnceLock<Box<[[f32; 2]]>> = std::sync::OnceLock::new();
    let table = TABLE.get_or_init(|| {
        let bias = (-8.0f64).exp();
        let total = std::f64::consts::FRAC_PI_2.sqrt() * 2.0 * erf(2.0 * std::f64::consts::SQRT_2)
            - bias * 8.0;
        (0..=QUANTILE_SEGMENTS)
            .map(|i| {
                let x = gaussian_inverse_cdf(1.0, i as f64 / QUANTILE_SEGMENTS as f64);
                let pdf = (-x * x / 2.0).exp() - bias;
                // dx/du over one segment (unused at the ends, where pdf = 0).
                let slope = if pdf > 0.0 {
                    total / pdf / QUANTILE_SEGMENTS as f64
                } else {
                    0.0
                };
                [x as f32, slope as f32]
            })
            .collect()
    });
    let s = u.clamp(0.0, 1.0) * QUANTILE_SEGMENTS as f32;
    let i = (s as usize).min(QUANTILE_SEGMENTS - 1);
    if i == 0 || i == QUANTILE_SEGMENTS - 1 {
        return gaussian_inverse_cdf(1.0, f64::from(u)) as f32;
    }
    let t = s - i as f32;
    let ([x0, d0], [x1, d1]) = (table[i], table[i + 1]);
    let (t2, t3) = (t * t, t * t * t);
    (2.0 * t3 - 3.0 * t2 + 1.0) * x0
        + (t3 - 2.0 * t2 + t) * d0
        + (3.0 * t2 - 2.0 * t3) * x1
        + (t3 - t2) * d1
}

/// The point x in `[−4σ, 4σ]` below which a fraction `u` of the truncated,
/// lowered Gaussian lies. Its cumulative integral has the closed form
/// `σ√(π/2)·(erf(x/σ√2) + erf(2√2)) − e⁻⁸(x + 4σ)`, whose derivative is the
/// filter itself: Newton's method from the untruncated Gaussian's quantile
/// (which the truncation barely moves), kept inside the bracket it
/// narrows, to a change below 1e-7 σ.
fn gaussian_inverse_cdf(stddev: f64, u: f64) -> f64 {
    use std::f64::consts::{PI, SQRT_2};
    let r = 4.0 * stddev;
    let bias = (-8.0f64).exp();
    let k = stddev * (PI / 2.0).sqrt();
    let erf_r = erf(r / (stddev * SQRT_2));
    let cdf = |x: f64| k * (erf(x / (stddev * SQRT_2)) + erf_r) - bias * (x + r);
    let pdf = |x: f64| (-x * x / (2.0 * stddev * stddev)).exp() - bias;
    let target = u.clamp(0.0, 1.0) * cdf(r);
    let (mut lo, mut hi) = (-r, r);
    let mut x = (stddev * probit(u.clamp(1e-12, 1.0 - 1e-12))).clamp(-r, r);
    for _ in 0..40 {
        let f = cdf(x) - target;
        if f < 0.0 {
            lo = x;
        } else {
            hi = x;
        }
        let d = pdf(x);
        let mut next = if d > 0.0 { x - f / d } else { 0.5 * (lo + hi) };
        if !(next > lo && next < hi) {
            next = 0.5 * (lo + hi);
        }
        let done = (next - x).abs() < 1e-7 * stddev;
        x = next;
        if done {
            break;
        }
    }
    x
}

#[cfg(test)]
mod tests {
    use super::*;

    /// χ²-like check: histogram of sampled offsets against the filter's
    /// normalised integral over each bin.
    fn check(filter: PixelFilter, radius: f32) {
        const BINS: usize = 40;
        const N: usize = 200_000;
        let mut counts = [0usize; BINS];
        for i in 0..N {
            let u = (i as f32 + 0.5) / N as f32;
            let x = filter.sample_1d(u);
            assert!(x.abs() <= radius + 1e-5, "{x}");
            let b = (((x + radius) / (2.0 * radius)) * BINS as f32) as usize;
            counts[b.min(BINS - 1)] += 1;
        }
        // Expected mass per bin by the midpoint rule on 100 sub-steps.
        let mut mass = [0.0f64; BINS];
        for (b, m) in mass.iter_mut().enumerate() {
            for k in 0..100 {
                let x =
                    -radius + 2.0 * radius * (b as f32 + (k as f32 + 0.5) / 100.0) / BINS as f32;
                *m += f64::from(filter.eval_1d(x));
            }
        }
        let total: f64 = mass.iter().sum();
        for b in 0..BINS {
            let expected = mass[b] / total * N as f64;
            let got = counts[b] as f64;
            assert!(
                (got - expected).abs() <= 3.0 + 0.01 * expected,
                "{filter:?} bin {b}: {got} samples, expected {expected:.1}"
            );
        }
    }

    #[test]
    fn sampled_offsets_follow_the_filters() {
        check(PixelFilter::tent(1.0), 1.0);
        check(PixelFilter::tent(2.5), 2.5);
        check(PixelFilter::gaussian(0.5), 2.0);
        check(PixelFilter::gaussian(0.3), 1.2);
    }

    #[test]
    fn the_tabulated_gaussian_quantile_is_the_exact_one() {
        // Within |x| ≤ 3σ (all but 0.3 % of the mass), against the Newton
        // solve, at points between the table's nodes.
        let mut worst = 0.0f64;
        for k in 0..100_000 {
            let u = (k as f64 + 0.37) / 100_000.0;
            let exact = gaussian_inverse_cdf(1.0, u);
            if exact.abs() <= 3.0 {
                let got = f64::from(standard_gaussian_quantile(u as f32));
                worst = worst.max((got - exact).abs());
            }
        }
        assert!(worst < 1e-5, "worst deviation {worst:e} σ");
        let g = PixelFilter::gaussian(0.5);
        assert!(g.sample_1d(0.5).abs() < 1e-6);
        let ends = (g.sample_1d(0.0), g.sample_1d(0.999_999_9));
        assert!(ends.0 == -2.0 && ends.1 > 1.98 && ends.1 <= 2.0, "{ends:?}");
    }

    #[test]
    fn the_box_leaves_the_uniform_point_as_it_is() {
        let u = Vec2::new(0.123, 0.987);
        assert_eq!(PixelFilter::Box.offset(u), u);
    }

    #[test]
    fn probit_inverts_the_normal_distribution() {
        for (p, x) in [
            (0.5, 0.0),
            (0.975, 1.959_963_985),
            (0.01, -2.326_347_874),
            (1e-6, -4.753_424_309),
        ] {
            assert!((probit(p) - x).abs() < 1e-6, "probit({p}) = {}", probit(p));
        }
    }

    #[test]
    fn erf_matches_known_values() {
        for (x, e) in [
            (0.0, 0.0),
            (0.5, 0.520_499_877_8),
            (1.0, 0.842_700_792_9),
            (2.0, 0.995_322_265_0),
            (-1.0, -0.842_700_792_9),
        ] {
            assert!((erf(x) - e).abs() < 2e-7, "erf({x}) = {}", erf(x));
        }
    }
}
