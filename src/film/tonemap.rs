//! Tone mapping: how linear radiance becomes display values in `[0, 1]` before
//! the sRGB encoding of a PNG (EXR files are never tone mapped).

use std::fmt;
use std::str::FromStr;

use glam::{Mat3A, Vec3A};

/// A tone mapping operator.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum ToneMap {
    /// Values clamped to `[0, 1]` (the lab's scenes).
    #[default]
    Clamp,
    /// Stephen Hill's fit of the ACES reference rendering and output transforms
    /// (sRGB), as the Khronos glTF Sample Viewer has it.
    Aces,
    /// The Khronos PBR Neutral operator, exactly as its specification gives it:
    /// colours below 0.76 stay as they are (less a tiny toe offset), highlights
    /// are compressed and desaturated towards white.
    KhronosPbrNeutral,
}

impl ToneMap {
    /// Every operator, for the command line.
    pub const ALL: [ToneMap; 3] = [ToneMap::Clamp, ToneMap::Aces, ToneMap::KhronosPbrNeutral];

    /// The name used on the command line.
    pub fn name(self) -> &'static str {
        match self {
            ToneMap::Clamp => "clamp",
            ToneMap::Aces => "aces",
            ToneMap::KhronosPbrNeutral => "khronos-pbr-neutral",
        }
    }

    /// The display value of linear colour `c` (non-negative), in `[0, 1]`.
    #[inline]
    pub fn apply(self, c: Vec3A) -> Vec3A {
        let c = c.max(Vec3A::ZERO);
        let out = match self {
            ToneMap::Clamp => c,
            ToneMap::Aces => aces_hill(c),
            ToneMap::KhronosPbrNeutral => pbr_neutral(c),
        };
        out.clamp(Vec3A::ZERO, Vec3A::ONE)
    }
}

/// Khronos PBR Neutral (KhronosGroup/ToneMapping, PBR_Neutral/README.md):
/// `F90 = 0.04`, `Ks = 0.8 − F90`, `Kd = 0.15`; `x = min(R, G, B)`,
/// `f = x − x²/(4·F90)` for `x ≤ 2·F90` else `F90`; `p = max(c − f)`;
/// `pn = 1 − (1 − Ks)²/(p + 1 − 2·Ks)`; `g = 1/(Kd·(p − pn) + 1)`; the output
/// is `c − f` for `p ≤ Ks`, else `(c − f)·(pn/p)·g + pn·(1 − g)`.
pub fn pbr_neutral(c: Vec3A) -> Vec3A {
    const F90: f32 = 0.04;
    const KS: f32 = 0.8 - F90;
    const KD: f32 = 0.15;
    let x = c.min_element();
    let f = if x <= 2.0 * F90 {
        x - x * x / (4.0 * F90)
    } else {
        F90
    };
    let p = (c - f).max_element();
    if p <= KS {
        return c - f;
    }
    let pn = 1.0 - (1.0 - KS) * (1.0 - KS) / (p + 1.0 - 2.0 * KS);
    let g = 1.0 / (KD * (p - pn) + 1.0);
    (c - f) * (pn / p * g) + Vec3A::splat(pn * (1.0 - g))
}

/// Hill's ACES fit: input matrix (sRGB to the RRT's space with the exposure
/// bias folded in), the RRT+ODT rational fit, output matrix back to sRGB.
pub fn aces_hill(c: Vec3A) -> Vec3A {
    // Rows as published; glam takes columns, hence the transposes.
    let input = Mat3A::from_cols_array(&[
        0.59719, 0.35458, 0.04823, 0.07600, 0.90834, 0.01566, 0.02840, 0.13383, 0.83777,
    ])
    .transpose();
    let output = Mat3A::from_cols_array(&[
        1.60475, -0.53108, -0.07367, -0.10208, 1.10813, -0.00605, -0.00327, -0.07276, 1.07602,
    ])
    .transpose();
    let v = input * c;
    let a = v * (v + 0.024_578_6) - 0.000_090_537;
    let b = v * (0.983_729 * v + 0.432_951) + 0.238_081;
    output * (a / b)
}

impl fmt::Display for ToneMap {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for ToneMap {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        ToneMap::ALL
            .into_iter()
            .find(|t| t.name() == s)
            .ok_or_else(|| {
                format!("unknown tone mapper '{s}' (expected clamp, aces or khronos-pbr-neutral)")
            })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pbr_neutral_matches_its_specification() {
        // Below the compression start only the toe offset applies.
        let c = Vec3A::new(0.5, 0.3, 0.2);
        assert!((pbr_neutral(c) - (c - 0.04)).abs().max_element() < 1e-7);
        let dark = Vec3A::new(0.05, 0.1, 0.2);
        let f = 0.05 - 0.05 * 0.05 / 0.16;
        assert!((pbr_neutral(dark) - (dark - f)).abs().max_element() < 1e-7);
        // A bright grey: p = 4 − 0.04, pn = 1 − 0.0576/(p − 0.52), g = 1/(0.15(p − pn) + 1);
        // a grey stays grey with value pn.
        let p = 4.0f32 - 0.04;
        let pn = 1.0 - 0.24 * 0.24 / (p + 1.0 - 1.52);
        let out = pbr_neutral(Vec3A::splat(4.0));
        assert!((out - Vec3A::splat(pn)).abs().max_element() < 1e-6, "{out}");
        // A saturated highlight is pulled towards white and stays below 1.
        let red = pbr_neutral(Vec3A::new(10.0, 0.0, 0.0));
        assert!(
            red.x < 1.0 && red.x > 0.95 && red.y > 0.0 && red.y < red.x,
            "{red}"
        );
        // The curve is continuous at the compression start.
        let below = pbr_neutral(Vec3A::splat(0.8 - 1e-4));
        let above = pbr_neutral(Vec3A::splat(0.8 + 1e-4));
        assert!((below - above).abs().max_element() < 1e-3);
    }

    #[test]
    fn aces_is_monotone_and_bounded() {
        let mut last = -1.0;
        for i in 0..100 {
            let v = ToneMap::Aces.apply(Vec3A::splat(i as f32 * 0.2)).x;
            assert!(v >= last && (0.0..=1.0).contains(&v));
            last = v;
        }
        assert_eq!(ToneMap::Aces.apply(Vec3A::ZERO), Vec3A::ZERO);
        // Values of Hill's matrices and rational fit worked out separately (in
        // double precision): mid grey 0.18 → 0.10559, (1, 0.5, 0.25) → (0.63499,
        // 0.38460, 0.20316).
        let g = ToneMap::Aces.apply(Vec3A::splat(0.18));
        assert!(
            (g - Vec3A::splat(0.105_591)).abs().max_element() < 1e-5,
            "{g}"
        );
        let c = ToneMap::Aces.apply(Vec3A::new(1.0, 0.5, 0.25));
        assert!(
            (c - Vec3A::new(0.634_990, 0.384_600, 0.203_160))
                .abs()
                .max_element()
                < 1e-5,
            "{c}"
        );
    }

    #[test]
    fn names_round_trip() {
        for t in ToneMap::ALL {
            assert_eq!(t.name().parse::<ToneMap>(), Ok(t));
        }
        assert!("filmic".parse::<ToneMap>().is_err());
    }
}
