//! Arbitrary output variables (AOVs): per-pixel data gathered with the image,
//! written next to it as extra EXR channels: the guides a denoiser takes
//! (`albedo`, `normal`; [`crate::denoise`] uses them with Open Image
//! Denoise), what compositors use for depth effects and masks (`depth`,
//! `position`), and the pixels' noise (`variance`).
//!
//! Every AOV is gathered from the camera rays of the beauty pass itself (the
//! same sample positions, hence the same antialiased edges), from the hit the
//! render already found. `path` also hands over the hit's shading (surface
//! and BSDF), so its textures are not looked up twice; for `flat` and
//! `direct` the AOVs shade the hit themselves. Per pixel sample:
//!
//! * `albedo` and `normal`: the denoiser's guides ([`guides`]): the albedo
//!   and the world-space shading normal (interpolated, normal-mapped, turned
//!   to the side the ray sees) of the first surface that is not specular,
//!   found by following mirrors, glass and smooth metals from the camera
//!   ray's hit (the only AOVs that cast rays of their own, and only there),
//!   with emitters and the environment seen along the way squashed into the
//!   albedo. The albedo is a surface's directional albedo as seen by the ray,
//!   [`Material::albedo`](crate::materials::Material::albedo) (diffuse: the
//!   reflectance; glTF: an estimate from the lobe weights; conductors: their
//!   tint), in `[0, 1]`; on a miss it is the environment's squashed radiance
//!   and the normal zero. They do not depend on the integrator: `flat` and
//!   `direct` get the guides of the BSDFs that `path` uses.
//! * `depth`: camera-space depth of the camera ray's hit, the distance of the
//!   hit point from the camera along its viewing axis (not along the ray),
//!   for perspective and orthographic cameras alike.
//! * `position`: the world-space hit point of the camera ray.
//! * `variance`: the estimated variance of the pixel's value, of its
//!   luminance (Rec. 709): the samples' variance over their number,
//!   `(Σ L² − (Σ L)²/n) / (n (n − 1))`, from the same exact sums as the image
//!   (each sample's `L` clamped to 2²⁰ in `Σ L²`); `+∞` below two samples.
//!   It is what a pixel's noise is, and what [`crate::denoise`] weighs the
//!   noisy image against the denoised one by.
//!
//! A pixel's value is the mean over its samples, so that noise-free geometry
//! gives noise-free AOVs and edges are antialiased as in the image: `albedo`
//! and `normal` over the pixel's first [`GUIDE_SAMPLES`] samples (a miss
//! counts, so an edge pixel blends towards the background and its normal is
//! shorter than 1, as OIDN expects);
//! `depth` and `position` over the samples that hit (a mean with a miss's
//! infinity would be infinite, one with zero meaningless), and `+∞` (every
//! component) where no sample hits. Sums are kept per pixel in sample order, so
//! AOVs are bit-identical for any number of threads, like the image.

use std::fmt;
use std::str::FromStr;

use glam::Vec3A;
use rayon::prelude::*;

use crate::camera::Camera;
use crate::film::Channel;
use crate::geometry::ray::{Hit, Ray};
use crate::materials::Material;
use crate::scene::{Scene, SurfaceHit};

pub mod guides;

pub use guides::Guides;

/// The samples of a pixel (its first ones, by index) that the `albedo` and
/// `normal` guides are the mean of. A camera ray's guides have no noise, only
/// its position in the pixel varies, and the first eight of a pixel's
/// Owen-scrambled Sobol' points already cover it evenly: more would refine
/// the antialiasing of edges that the denoiser does not see, at the full
/// price of the guides' chains through mirrors and glass (on the helmet under
/// the HDRI, guides for every sample of 16 made `--denoise`'s path tracing
/// about 30 % slower; see docs/denoising.md).
pub const GUIDE_SAMPLES: u32 = 8;

/// Whether sample `sample` (its index in the pixel) adds to the guides.
#[inline]
pub(crate) fn adds_guides(sample: u32) -> bool {
    sample < GUIDE_SAMPLES
}

/// Each sample's luminance is clamped to this in the sums of squares of
/// [`Aov::Variance`], so that 2²⁰ samples (the most a render takes) cannot
/// overflow them: `2⁴⁰ · 2²⁰ < 2⁶³`, the fixed-point range.
pub const VARIANCE_CLAMP: f32 = (1u32 << 20) as f32;

/// Rec. 709 luminance of a linear RGB value.
#[inline]
pub fn luminance(c: Vec3A) -> f32 {
    c.dot(Vec3A::new(0.2126, 0.7152, 0.0722))
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
}

impl Aov {
    /// Every AOV, in the order the README lists them.
    pub const ALL: [Aov; 5] = [
        Aov::Albedo,
        Aov::Normal,
        Aov::Depth,
        Aov::Position,
        Aov::Variance,
    ];

    /// The name on the command line and of the EXR layer.
    pub fn name(self) -> &'static str {
        match self {
            Aov::Albedo => "albedo",
            Aov::Normal => "normal",
            Aov::Depth => "depth",
            Aov::Position => "position",
            Aov::Variance => "variance",
        }
    }

    /// The channels' suffixes, as compositors read them: colours `R, G, B`,
    /// vectors `X, Y, Z`, depth `Z` (Nuke's `depth.Z`), variance `Y` (of
    /// the luminance).
    pub fn channels(self) -> &'static [&'static str] {
        match self {
            Aov::Albedo => &["R", "G", "B"],
            Aov::Normal | Aov::Position => &["X", "Y", "Z"],
            Aov::Depth => &["Z"],
            Aov::Variance => &["Y"],
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
    fn over_hits(self) -> bool {
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
    list: [Aov; 5],
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

/// Where each AOV's sums lie in a pixel's record of [`AovSums`]: the AOVs'
/// channels in the set's order, then the number of samples that hit.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Layout {
    /// Offset of each AOV (indexed as [`Aov::ALL`]) if gathered.
    offset: [Option<usize>; 5],
    /// Values per pixel.
    pub(crate) stride: usize,
}

impl Layout {
    pub(crate) fn new(set: AovSet) -> Self {
        let mut offset = [None; 5];
        let mut next = 0;
        for a in set.iter() {
            offset[a as usize] = Some(next);
            next += a.channels().len();
        }
        Layout {
            offset,
            stride: next + 1,
        }
    }

    /// Where `aov`'s values lie in a record, if it is gathered.
    pub(crate) fn offset(&self, aov: Aov) -> Option<usize> {
        self.offset[aov as usize]
    }

    /// What the AOVs need of sample `sample`'s camera-ray hit, from its
    /// shading: the surface `s` and (if the guides are wanted) its BSDF, which
    /// `bsdf` gives. `path` passes the ones it shades the hit with, so that
    /// the textures are not looked up twice.
    #[inline]
    pub(crate) fn first_hit(
        &self,
        scene: &Scene,
        ray: &Ray,
        s: &SurfaceHit,
        sample: u32,
        bsdf: impl FnOnce() -> Material,
    ) -> FirstHit {
        let [albedo, normal, ..] = self.offset;
        let guides = if (albedo.is_some() || normal.is_some()) && adds_guides(sample) {
            guides::guides(scene, ray, s, &bsdf())
        } else {
            Guides::default()
        };
        FirstHit {
            point: s.point.p,
            guides,
        }
    }

    /// Adds the AOVs of one camera ray `ray` (the pixel's sample `sample`)
    /// with closest hit `hit` and sample value `value` to a pixel's record
    /// `out` (the guides only from the first [`GUIDE_SAMPLES`]; a miss adds the
    /// environment to the albedo and nothing to the normal, and depth and
    /// position only count hits; a value that is not finite, which the image
    /// drops, adds nothing to the variance). `shaded` is what
    /// [`Layout::first_hit`] made of the hit if the integrator shaded it;
    /// otherwise the hit is shaded here, as far as the AOVs need. Out of line:
    /// a call per sample costs nothing measurable, while inlined it changed
    /// what the compiler inlined in the render loop (renders without AOVs
    /// included, 1 % of `flat`).
    #[allow(clippy::too_many_arguments)]
    #[inline(never)]
    pub(crate) fn gather(
        &self,
        scene: &Scene,
        camera: &Camera,
        ray: &Ray,
        hit: Option<Hit>,
        shaded: Option<&FirstHit>,
        value: Vec3A,
        sample: u32,
        out: &mut [i128],
    ) {
        let [mut albedo, mut normal, depth, position, variance] = self.offset;
        if !adds_guides(sample) {
            (albedo, normal) = (None, None);
        }
        if let Some(at) = variance
            && value.is_finite()
        {
            let l = luminance(value).clamp(0.0, VARIANCE_CLAMP);
            out[at] += crate::fixed::fixed(l * l);
        }
        let Some(hit) = hit else {
            if let Some(at) = albedo {
                let sky = guides::sky(scene, ray.dir);
                if sky.is_finite() {
                    for (o, c) in out[at..at + 3].iter_mut().zip(sky.to_array()) {
                        *o += crate::fixed::fixed(c);
                    }
                }
            }
            return;
        };
        let first = match shaded {
            Some(&f) => f,
            // Depth and position need just the point.
            None if albedo.is_none() && normal.is_none() => FirstHit {
                point: scene.surface_point(&hit, ray.dir).p,
                guides: Guides::default(),
            },
            None => {
                let s = scene.surface(&hit);
                self.first_hit(scene, ray, &s, sample, || {
                    let material = &scene.materials()[s.material as usize];
                    material.bsdf(&s.attrs, scene.textures())
                })
            }
        };
        let p = first.point;
        let g = first.guides;
        if !(p.is_finite() && g.normal.is_finite() && g.albedo.is_finite()) {
            return;
        }
        let mut add = |at: Option<usize>, v: Vec3A, n: usize| {
            if let Some(at) = at {
                for (o, c) in out[at..at + n].iter_mut().zip(v.to_array()) {
                    *o += crate::fixed::fixed(c);
                }
            }
        };
        add(albedo, g.albedo, 3);
        add(normal, g.normal, 3);
        // Along the viewing axis: (p − eye)·forward, the same for an orthographic
        // camera, whose rays start on the plane through the eye.
        let d = (p - camera.position).dot(camera.forward());
        add(depth, Vec3A::splat(d), 1);
        add(position, p, 3);
        out[self.stride - 1] += 1 << crate::fixed::FRACTION_BITS;
    }
}

/// A camera ray's hit as the AOVs see it (see [`Layout::first_hit`]).
#[derive(Clone, Copy, Debug)]
pub(crate) struct FirstHit {
    point: Vec3A,
    guides: Guides,
}

/// Per-pixel sums of AOVs over the samples taken so far (a record of
/// `f32`s per pixel; see [`AovSums::average`] for the means).
#[derive(Clone, Debug, PartialEq)]
pub struct AovSums {
    set: AovSet,
    layout: Layout,
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// `width * height` records, row-major: sums over the samples, but for
    /// [`Aov::Variance`], whose estimate needs the image's sums too, the
    /// finished estimate ([`crate::render::Accumulator::rendered`] makes it).
    pub(crate) sums: Vec<f32>,
}

impl AovSums {
    /// Zero sums of `set` for a `width × height` image.
    pub fn new(set: AovSet, width: u32, height: u32) -> Self {
        let layout = Layout::new(set);
        let len = width as usize * height as usize * layout.stride;
        // Zeros written, not `vec![0.0; len]`'s lazily zeroed pages: those are
        // read before they are written, and each then faults twice (the second
        // time with a TLB shootdown), which cost more than the AOVs themselves.
        let mut sums = Vec::with_capacity(len);
        sums.resize(len, 0.0);
        Self {
            set,
            layout,
            width,
            height,
            sums,
        }
    }

    /// The AOVs gathered.
    pub fn set(&self) -> AovSet {
        self.set
    }

    /// The means over `samples` samples per pixel, the first ones of the
    /// render (see the module documentation for what each AOV averages over).
    pub fn average(&self, samples: u32) -> AovImage {
        self.average_of(0, samples)
    }

    /// The means over samples `first..first + samples` of every pixel (a
    /// part of a render, `--samples A..B`): the guides over those of them
    /// below [`GUIDE_SAMPLES`], zero where the part has none (its merged
    /// render has them).
    pub fn average_of(&self, first: u32, samples: u32) -> AovImage {
        let layout = self.layout;
        let stride = layout.stride;
        let n = f64::from(samples.max(1));
        let end = first.saturating_add(samples);
        let guide_samples = end.min(GUIDE_SAMPLES) - first.min(GUIDE_SAMPLES);
        let guide_n = f64::from(guide_samples.max(1));
        // The records hold the AOVs' channels in the set's order.
        let mut next = 0;
        let layers = self
            .set
            .iter()
            .map(|aov| {
                let k = aov.channels().len();
                let at = next;
                next += k;
                let mut values = vec![0.0f32; self.sums.len() / stride * k];
                // A row at a time on rayon (a pixel at a time would be mostly
                // scheduling).
                let row = self.width.max(1) as usize;
                values
                    .par_chunks_mut(k * row)
                    .zip(self.sums.par_chunks(stride * row))
                    .for_each(|(pixels, records)| {
                        for (pixel, record) in
                            pixels.chunks_exact_mut(k).zip(records.chunks_exact(stride))
                        {
                            let hits = f64::from(record[stride - 1]);
                            let count = match aov {
                                // The record holds the finished estimate
                                // (see `AovSums::sums`).
                                Aov::Variance => 1.0,
                                a if a.over_hits() => hits,
                                Aov::Albedo | Aov::Normal => guide_n,
                                _ => n,
                            };
                            for (v, &sum) in pixel.iter_mut().zip(&record[at..at + k]) {
                                *v = if count > 0.0 {
                                    (f64::from(sum) / count) as f32
                                } else {
                                    f32::INFINITY
                                };
                            }
                        }
                    });
                AovLayer { aov, values }
            })
            .collect();
        let coverage = self
            .sums
            .par_chunks(stride)
            .map(|record| (f64::from(record[stride - 1]) / n).min(1.0) as f32)
            .collect();
        AovImage {
            width: self.width,
            height: self.height,
            layers,
            coverage,
            samples,
        }
    }
}

/// One AOV of a whole image.
#[derive(Clone, Debug, PartialEq)]
pub struct AovLayer {
    /// Which AOV.
    pub aov: Aov,
    /// Its values, row-major from the top-left, the channels of a pixel together
    /// (`aov.channels().len()` per pixel, as OIDN takes them).
    pub values: Vec<f32>,
}

/// The averaged AOVs of a render, in the order they were asked for.
#[derive(Clone, Debug, PartialEq)]
pub struct AovImage {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// One layer per AOV.
    pub layers: Vec<AovLayer>,
    /// Per pixel, the share of its samples whose camera ray hit a surface
    /// (the others saw the environment, or nothing).
    pub coverage: Vec<f32>,
    /// Samples per pixel averaged.
    pub samples: u32,
}

impl AovImage {
    /// The layer of `aov`, if it was gathered.
    pub fn layer(&self, aov: Aov) -> Option<&AovLayer> {
        self.layers.iter().find(|l| l.aov == aov)
    }

    /// The channels of `aov` at pixel `(x, y)`, if it was gathered.
    pub fn get(&self, aov: Aov, x: u32, y: u32) -> Option<&[f32]> {
        let k = aov.channels().len();
        let i = (y as usize * self.width as usize + x as usize) * k;
        self.layer(aov)?.values.get(i..i + k)
    }

    /// Every channel as an EXR channel named `layer.channel` (one plane each),
    /// each layer freed as soon as its planes are made (a large image's AOVs
    /// need not be held twice).
    pub fn into_channels(self) -> Vec<Channel> {
        let mut channels = Vec::new();
        for layer in self.layers {
            let k = layer.aov.channels().len();
            for (c, name) in layer.aov.channel_names().enumerate() {
                let values = layer.values.iter().skip(c).step_by(k).copied().collect();
                channels.push(Channel { name, values });
            }
        }
        channels
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
            "unknown AOV 'colour' (expected albedo, normal, depth, position, variance)"
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

    #[test]
    fn means_count_misses_as_zero_or_leave_them_out() {
        // Two pixels, four samples each: the first hit twice, the second never.
        let set: AovSet = "normal,depth".parse().unwrap();
        let mut sums = AovSums::new(set, 2, 1);
        assert_eq!(sums.layout.stride, 3 + 1 + 1);
        sums.sums[..5].copy_from_slice(&[0.0, 2.0, 0.0, 7.0, 2.0]);
        let image = sums.average(4);
        assert_eq!(image.get(Aov::Normal, 0, 0), Some(&[0.0, 0.5, 0.0][..]));
        assert_eq!(image.get(Aov::Depth, 0, 0), Some(&[3.5][..]));
        assert_eq!(image.get(Aov::Normal, 1, 0), Some(&[0.0; 3][..]));
        assert_eq!(image.get(Aov::Depth, 1, 0), Some(&[f32::INFINITY][..]));
        assert_eq!(image.get(Aov::Albedo, 0, 0), None);
        let channels = image.into_channels();
        let names: Vec<&str> = channels.iter().map(|c| c.name.as_str()).collect();
        assert_eq!(names, ["normal.X", "normal.Y", "normal.Z", "depth.Z"]);
        assert_eq!(channels[1].values, [0.5, 0.0]);
    }

    #[test]
    fn guides_are_the_mean_of_the_first_samples_of_the_render() {
        // One pixel whose albedo sums 4 over the guides' samples.
        let set: AovSet = "albedo".parse().unwrap();
        let mut sums = AovSums::new(set, 1, 1);
        sums.sums[..4].copy_from_slice(&[4.0, 4.0, 4.0, 16.0]);
        let albedo = |first, samples| {
            sums.average_of(first, samples)
                .get(Aov::Albedo, 0, 0)
                .unwrap()[0]
        };
        // A whole render: 4 samples, or 16 of which the first 8 add guides.
        assert_eq!(albedo(0, 4), 1.0);
        assert_eq!(albedo(0, 16), 0.5);
        assert_eq!(sums.average(16).get(Aov::Albedo, 0, 0).unwrap()[0], 0.5);
        // Parts: samples 4..12 hold four of the guides' samples, 6..7 one,
        // 8..16 none (its sums, zero in a real part, are kept as they are: its
        // merged render has the guides).
        assert_eq!(albedo(4, 8), 1.0);
        assert_eq!(albedo(6, 1), 4.0);
        assert_eq!(albedo(8, 8), 4.0);
        assert_eq!(GUIDE_SAMPLES, 8);
    }
}
