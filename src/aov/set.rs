//! The AOVs there are ([`Aov`]: names, channels, what each averages over),
//! a set of them asked for ([`AovSet`]), and the Rec. 709 [`luminance`] that
//! the variance and the guides measure values by.

use std::fmt;
use std::str::FromStr;

use glam::Vec3A;

/// Rec. 709 luminance of a linear RGB value.
#[inline]
pub fn luminance(c: Vec3A) -> f32 {
    c.dot(Vec3A::new(0.2126, 0.7152, 0.0722))
}

/// Whether sample `sample` of pixel number `pixel` (row-major over the whole
/// image) of a render with `seed` belongs to the [`Aov::Half`] half: of each
/// pair of samples `2k, 2k + 1` exactly one does, chosen by a hash of
/// `(seed, pixel, k)`. Not simply the odd samples: the Sobol' sampler puts a
/// pair's two samples in opposite halves of the pixel (and of every other
/// stratified dimension), so the odd samples alone would see the pixel's
/// right half and their difference from the even ones an edge, not noise.
#[inline]
pub fn in_half(seed: u64, pixel: u64, sample: u32) -> bool {
    let mut h = seed ^ 0x9e37_79b9_7f4a_7c15;
    h ^= pixel.wrapping_mul(0xbf58_476d_1ce4_e5b9);
    h ^= u64::from(sample >> 1).wrapping_mul(0x94d0_49bb_1331_11eb);
    // SplitMix64's finaliser.
    h = (h ^ (h >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    h = (h ^ (h >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    h ^= h >> 31;
    (h & 1) as u32 == sample & 1
}

/// One output variable.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Aov {
    /// The denoiser's albedo guide (through specular surfaces), linear RGB
    /// in `[0, 1]`.
    Albedo,
    /// The denoiser's normal guide: the world-space shading normal, facing
    /// the ray, of the same surface.
    Normal,
    /// Camera-space depth of the camera ray's hit (along the viewing axis).
    Depth,
    /// World-space position of the camera ray's hit.
    Position,
    /// Variance of the pixel's luminance estimate.
    Variance,
    /// The mean of one half of the pixel's samples (of each pair of samples
    /// `2k, 2k + 1`, the one a hash of the seed, pixel and pair picks; see
    /// [`in_half`]) and how many samples that half holds: with the image,
    /// two independent estimates whose difference is the pixel's noise
    /// (adaptive sampling and the denoiser's guard measure it so).
    Half,
    /// The number of samples the pixel took (adaptive sampling stops
    /// converged pixels early).
    Samples,
}

impl Aov {
    /// Every AOV, in the order the README lists them.
    pub const ALL: [Aov; 7] = [
        Aov::Albedo,
        Aov::Normal,
        Aov::Depth,
        Aov::Position,
        Aov::Variance,
        Aov::Half,
        Aov::Samples,
    ];

    /// The name on the command line and of the EXR layer.
    pub fn name(self) -> &'static str {
        match self {
            Aov::Albedo => "albedo",
            Aov::Normal => "normal",
            Aov::Depth => "depth",
            Aov::Position => "position",
            Aov::Variance => "variance",
            Aov::Half => "half",
            Aov::Samples => "samples",
        }
    }

    /// The channels' suffixes, as compositors read them: colours `R, G, B`,
    /// vectors `X, Y, Z`, depth `Z` (Nuke's `depth.Z`), variance `Y` (of
    /// the luminance), the half's colour and sample count `R, G, B, N`, the
    /// sample count `N`.
    pub fn channels(self) -> &'static [&'static str] {
        match self {
            Aov::Albedo => &["R", "G", "B"],
            Aov::Normal | Aov::Position => &["X", "Y", "Z"],
            Aov::Depth => &["Z"],
            Aov::Variance => &["Y"],
            Aov::Half => &["R", "G", "B", "N"],
            Aov::Samples => &["N"],
        }
    }

    /// The full EXR channel names, `layer.channel` (e.g. `albedo.R`).
    pub fn channel_names(self) -> impl Iterator<Item = String> {
        self.channels()
            .iter()
            .map(move |c| format!("{}.{c}", self.name()))
    }

    /// Whether pixels average this AOV over the samples that hit (and are `+∞`
    /// where none did) rather than over all samples.
    pub(super) fn over_hits(self) -> bool {
        matches!(self, Aov::Depth | Aov::Position)
    }

    /// The valid names, for error messages.
    fn expected() -> String {
        let names: Vec<&str> = Aov::ALL.iter().map(|a| a.name()).collect();
        names.join(", ")
    }
}

impl fmt::Display for Aov {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Aov {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Aov::ALL
            .into_iter()
            .find(|a| a.name() == s)
            .ok_or_else(|| format!("unknown AOV '{s}' (expected {})", Aov::expected()))
    }
}

/// A set of AOVs in the order given, each at most once (possibly empty).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct AovSet {
    list: [Aov; 7],
    len: u8,
}

impl Default for AovSet {
    fn default() -> Self {
        Self::NONE
    }
}

impl AovSet {
    /// No AOVs: the render gathers nothing.
    pub const NONE: AovSet = AovSet {
        list: Aov::ALL,
        len: 0,
    };

    /// The set of `aovs` in their order, for constants (given twice, or
    /// more than there are, fails to compile).
    pub const fn of(aovs: &[Aov]) -> AovSet {
        let mut set = AovSet::NONE;
        let mut i = 0;
        while i < aovs.len() {
            let mut j = 0;
            while j < i {
                assert!(aovs[j] as u8 != aovs[i] as u8, "an AOV given twice");
                j += 1;
            }
            set.list[i] = aovs[i];
            i += 1;
        }
        set.len = aovs.len() as u8;
        set
    }

    /// The set of `aovs` in their order; an error if one is given twice.
    pub fn new(aovs: &[Aov]) -> Result<Self, String> {
        let mut set = Self::NONE;
        for &a in aovs {
            if set.contains(a) {
                return Err(format!("AOV '{a}' given twice"));
            }
            set.list[set.len as usize] = a;
            set.len += 1;
        }
        Ok(set)
    }

    /// The AOVs in order.
    pub fn iter(&self) -> impl Iterator<Item = Aov> + '_ {
        self.list[..self.len as usize].iter().copied()
    }

    /// Whether the set holds `aov`.
    pub fn contains(&self, aov: Aov) -> bool {
        self.iter().any(|a| a == aov)
    }

    /// This set and then those of `more` it lacks, in their order.
    pub fn with(&self, more: AovSet) -> AovSet {
        let mut set = *self;
        for a in more.iter().filter(|&a| !self.contains(a)) {
            set.list[set.len as usize] = a;
            set.len += 1;
        }
        set
    }

    /// Whether every AOV of `other` is in this set.
    pub fn includes(&self, other: AovSet) -> bool {
        other.iter().all(|a| self.contains(a))
    }

    /// Whether the set is empty.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Number of AOVs.
    pub fn len(&self) -> usize {
        self.len as usize
    }
}

impl FromStr for AovSet {
    type Err = String;
    /// A comma-separated list such as `albedo,normal`.
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let aovs: Vec<Aov> = s
            .split(',')
            .map(|name| match name.trim() {
                "" => Err(format!(
                    "expected a comma-separated list of AOVs ({}), got '{s}'",
                    Aov::expected()
                )),
                name => name.parse(),
            })
            .collect::<Result<_, _>>()?;
        AovSet::new(&aovs)
    }
}

impl fmt::Display for AovSet {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let names: Vec<&str> = self.iter().map(Aov::name).collect();
        f.write_str(&names.join(","))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sets_parse_in_order_and_reject_unknown_names_and_repeats() {
        let set: AovSet = "depth, albedo".parse().unwrap();
        assert_eq!(set.iter().collect::<Vec<_>>(), [Aov::Depth, Aov::Albedo]);
        assert_eq!(set.to_string(), "depth,albedo");
        let all: AovSet = "albedo,normal,depth,position".parse().unwrap();
        assert_eq!(all.len(), 4);
        let err = "albedo,colour".parse::<AovSet>().unwrap_err();
        assert_eq!(
            err,
            "unknown AOV 'colour' (expected albedo, normal, depth, position, variance, half, samples)"
        );
        assert!(
            "normal,normal"
                .parse::<AovSet>()
                .unwrap_err()
                .contains("twice")
        );
        for bad in ["", "albedo,", ","] {
            assert!(bad.parse::<AovSet>().is_err(), "{bad:?}");
        }
        assert!(AovSet::NONE.is_empty());
    }
}
