//! Gathering the AOVs of each camera ray into a pixel's record ([`Layout`],
//! [`FirstHit`]) and the per-pixel sums of a render ([`AovSums`]), whose
//! means make an [`AovImage`].

use glam::Vec3A;
use rayon::prelude::*;

use super::guides::{self, GUIDE_SAMPLES, Guides, adds_guides};
use super::image::{AovImage, AovLayer};
use super::set::{Aov, AovSet, luminance};
use crate::camera::Camera;
use crate::geometry::ray::{Hit, Ray};
use crate::materials::Material;
use crate::scene::{Scene, SurfaceHit};

/// Each sample's luminance is clamped to this in the sums of squares of
/// [`Aov::Variance`], so that 2²⁰ samples (the most a render takes) cannot
/// overflow them: `2⁴⁰ · 2²⁰ < 2⁶³`, the fixed-point range.
pub const VARIANCE_CLAMP: f32 = (1u32 << 20) as f32;

/// Where each AOV's sums lie in a pixel's record of [`AovSums`]: the AOVs'
/// channels in the set's order, then the number of samples that hit.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Layout {
    /// Offset of each AOV (indexed as [`Aov::ALL`]) if gathered.
    offset: [Option<usize>; 7],
    /// Values per pixel.
    pub(crate) stride: usize,
}

impl Layout {
    pub(crate) fn new(set: AovSet) -> Self {
        let mut offset = [None; 7];
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
    /// drops, adds nothing to the variance or the half's colour, but counts
    /// as a sample). `half` says whether the sample is in [`Aov::Half`]'s
    /// half ([`super::in_half`]). `shaded` is what
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
        half: bool,
        out: &mut [i128],
    ) {
        let [
            mut albedo,
            mut normal,
            depth,
            position,
            variance,
            in_half,
            samples,
        ] = self.offset;
        if !adds_guides(sample) {
            (albedo, normal) = (None, None);
        }
        if let Some(at) = variance
            && value.is_finite()
        {
            let l = luminance(value).clamp(0.0, VARIANCE_CLAMP);
            out[at] += crate::fixed::fixed(l * l);
        }
        let one = 1 << crate::fixed::FRACTION_BITS;
        if let Some(at) = in_half
            && half
        {
            if value.is_finite() {
                crate::fixed::add3((&mut out[at..at + 3]).try_into().unwrap(), value);
            }
            out[at + 3] += one;
        }
        if let Some(at) = samples {
            out[at] += one;
        }
        let Some(hit) = hit else {
            if let Some(at) = albedo {
                let sky = guides::escaped(scene, ray);
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
        out[self.stride - 1] += one;
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
                                // (see `AovSums::sums`), or a count.
                                Aov::Variance | Aov::Samples => 1.0,
                                // The mean over the half's own samples.
                                Aov::Half => f64::from(record[at + 3]),
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
                            if aov == Aov::Half {
                                // Its count as it is (zero where the half is
                                // empty, whose colour is then +∞).
                                pixel[3] = record[at + 3];
                            }
                        }
                    });
                AovLayer { aov, values }
            })
            .collect();
        // Per pixel over its own samples where they are counted (adaptive
        // sampling stops pixels at different counts).
        let counted = layout.offset(Aov::Samples);
        let coverage = self
            .sums
            .par_chunks(stride)
            .map(|record| {
                let n = counted.map_or(n, |at| f64::from(record[at]).max(1.0));
                (f64::from(record[stride - 1]) / n).min(1.0) as f32
            })
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

#[cfg(test)]
mod tests {
    use super::*;

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
