//! Denoising: Intel Open Image Denoise (OIDN) on a render's radiance, guided
//! by its `albedo` and `normal` AOVs, then blended back towards the noisy
//! image wherever that is already as good (weighed by each pixel's
//! `variance` AOV).
//!
//! [`Denoiser`] is the step every part of raylab uses (`raylab render
//! --denoise`, `raylab merge --denoise`, the viewer, and a crate user):
//!
//! ```no_run
//! use raylab::denoise::{DenoiseOptions, Denoiser};
//! use raylab::load::cornell;
//! # fn main() -> Result<(), Box<dyn std::error::Error>> {
//! let scene = cornell::scene();
//! let camera = raylab::Camera::lab(cornell::CAMERA_POSITION, 0.0, 0.0, 256, 256);
//! let settings = raylab::render::RenderSettings {
//!     integrator: raylab::Integrator::path(),
//!     spp: 16,
//!     seed: 0,
//! };
//! // Open Image Denoise is loaded here (an error says how to install it).
//! let mut denoiser = Denoiser::new(&DenoiseOptions::default())?;
//! let guides = raylab::denoise::GUIDES;
//! let rendered = raylab::render::render_with_aovs(&scene, &camera, &settings, guides, &|_| {});
//! let clean = denoiser.denoise(&rendered.film, rendered.aovs.as_ref().unwrap())?;
//! raylab::film::write_image(&clean, std::path::Path::new("box.exr"))?;
//! # Ok(())
//! # }
//! ```
//!
//! # The library
//!
//! OIDN is loaded at run time ([`oidn`]: `RAYLAB_OIDN`, the system's library
//! path, then PyPI's `pyoidn` wheel), so that raylab builds and runs without
//! it; a missing or too old library is an [`OidnError`] that says how to
//! install it.
//!
//! # What is run
//!
//! OIDN's `RT` filter on the HDR radiance (float32, OIDN's automatic input
//! scale), with the albedo and normal guides. The guides are noise-free
//! ([`crate::aov::guides`]: no random numbers, antialiased over the same
//! samples as the colour), so the filter is told so (`cleanAux`). Below
//! [`PREFILTER_BELOW_SPP`] samples they are denoised first all the same
//! (OIDN's recipe for noisy guides, [`Prefilter::Auto`]): one or two samples
//! alias a texture or an edge much as noise would, and prefiltering them
//! lowered both errors on all three scenes of `tools/compare_cycles.py` at 1
//! and 2 spp and changed nothing measurable from 4 on (docs/denoising.md).
//!
//! # Determinism
//!
//! OIDN's CPU device gives the same bits on any number of threads (measured
//! with OIDN 2.5.1: 1, 2 and 4 threads, bit for bit; the test
//! `tests/denoise.rs` checks it), and raylab's inputs are the same bits on
//! any number of threads, so a denoised image is the same for any
//! `--threads`, with the same OIDN library on the same kind of CPU (OIDN's
//! kernels differ between instruction sets: AVX-512 and AVX2 machines may
//! differ in the last bits).

pub mod blend;
pub mod heuristic;
pub mod oidn;

use std::sync::Arc;
use std::time::{Duration, Instant};

use thiserror::Error;

use crate::aov::{Aov, AovImage, AovSet};
use crate::film::Film;

pub use blend::guard;
pub use oidn::{OidnError, Quality};

/// The AOVs the denoiser needs: the guides, and the half of the samples its
/// guard measures the error by.
pub const GUIDES: AovSet = AovSet::of(&[Aov::Albedo, Aov::Normal, Aov::Variance, Aov::Half]);

/// Samples per pixel below which [`Prefilter::Auto`] prefilters the guides.
pub const PREFILTER_BELOW_SPP: u32 = 4;

/// Whether the guides are denoised before they guide (OIDN's prefiltering).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Prefilter {
    /// Below [`PREFILTER_BELOW_SPP`] samples per pixel.
    #[default]
    Auto,
    /// Always (for guides with real noise, e.g. from depth of field).
    On,
    /// Never.
    Off,
}

/// How to denoise.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DenoiseOptions {
    /// Threads OIDN runs (0: one per core). The result does not depend on it.
    pub threads: usize,
    /// OIDN's quality mode ([`Quality::High`] for final images).
    pub quality: Quality,
    /// Whether the guides are denoised first (they are then clean);
    /// otherwise they are taken as clean as they are (raylab's are).
    pub prefilter: Prefilter,
    /// Keep the noisy image where the render's own estimate says it is
    /// better than the denoised one ([`guard()`]: a second denoiser run, on
    /// one half of the samples, cross-validated against the other).
    pub blend: bool,
}

impl Default for DenoiseOptions {
    fn default() -> Self {
        Self {
            threads: 0,
            quality: Quality::High,
            prefilter: Prefilter::Auto,
            blend: true,
        }
    }
}

/// Why an image was not denoised.
#[derive(Debug, Error, Clone, PartialEq, Eq)]
pub enum DenoiseError {
    /// The render lacks an AOV the denoiser needs.
    #[error(
        "the image has no {0} AOV, which the denoiser needs (render with {guides})",
        guides = "--denoise or --aov albedo,normal,variance,half"
    )]
    MissingAov(Aov),
    /// The image and its AOVs differ in size.
    #[error("the image is {0}×{1} pixels but its AOVs {2}×{3}")]
    Size(u32, u32, u32, u32),
    /// OIDN failed.
    #[error(transparent)]
    Oidn(#[from] OidnError),
}

/// Open Image Denoise, loaded, with a CPU device and filters kept for reuse
/// (making a filter is the expensive part of a small image's denoising).
pub struct Denoiser {
    // Filters before the device: they are released first.
    color: Option<oidn::Filter>,
    half: Option<oidn::Filter>,
    guide: Option<oidn::Filter>,
    device: oidn::Device,
    options: DenoiseOptions,
    last: Duration,
}

impl std::fmt::Debug for Denoiser {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Denoiser")
            .field("device", &self.device)
            .field("options", &self.options)
            .finish()
    }
}

impl Denoiser {
    /// Loads OIDN (see [`oidn::search_order`]) and makes its CPU device.
    pub fn new(options: &DenoiseOptions) -> Result<Denoiser, OidnError> {
        let library = Arc::new(oidn::Library::find()?);
        Denoiser::with_library(library, options)
    }

    /// A denoiser on an already loaded `library`.
    pub fn with_library(
        library: Arc<oidn::Library>,
        options: &DenoiseOptions,
    ) -> Result<Denoiser, OidnError> {
        let device = oidn::Device::cpu(library, options.threads)?;
        Ok(Denoiser {
            color: None,
            half: None,
            guide: None,
            device,
            options: *options,
            last: Duration::ZERO,
        })
    }

    /// The options.
    pub fn options(&self) -> &DenoiseOptions {
        &self.options
    }

    /// What runs, for a summary line: `OIDN 2.5.1 on the CPU (2 threads)`.
    pub fn describe(&self) -> String {
        let threads = match self.device.threads() {
            0 => "all cores".to_string(),
            1 => "1 thread".to_string(),
            n => format!("{n} threads"),
        };
        format!(
            "OIDN {} on the CPU ({threads})",
            self.device.version_string()
        )
    }

    /// The library file in use.
    pub fn library_path(&self) -> &std::path::Path {
        self.device.library().path()
    }

    /// How long the last [`Denoiser::denoise`] took.
    pub fn last_time(&self) -> Duration {
        self.last
    }

    /// `image` denoised with the guides of `aovs` and guarded by its half
    /// of the samples (which must hold [`GUIDES`]; the half only with
    /// [`DenoiseOptions::blend`]).
    pub fn denoise(&mut self, image: &Film, aovs: &AovImage) -> Result<Film, DenoiseError> {
        self.denoise_guarded(image, aovs).map(|g| g.image)
    }

    /// [`Denoiser::denoise`], with what the guard decided from.
    pub fn denoise_guarded(
        &mut self,
        image: &Film,
        aovs: &AovImage,
    ) -> Result<Guarded, DenoiseError> {
        let start = Instant::now();
        if (image.width, image.height) != (aovs.width, aovs.height) {
            return Err(DenoiseError::Size(
                image.width,
                image.height,
                aovs.width,
                aovs.height,
            ));
        }
        let layer = |aov: Aov| {
            aovs.layer(aov)
                .map(|l| l.values.as_slice())
                .ok_or(DenoiseError::MissingAov(aov))
        };
        let (albedo, normal) = (layer(Aov::Albedo)?, layer(Aov::Normal)?);
        let (half, variance) = if self.options.blend {
            (Some(layer(Aov::Half)?), Some(layer(Aov::Variance)?))
        } else {
            (None, None)
        };
        let counts = aovs.layer(Aov::Samples).map(|l| l.values.as_slice());
        let (w, h) = (image.width as usize, image.height as usize);
        // OIDN takes HDR values in [0, ∞): radiance is never negative, but
        // the film's values are clamped to be sure.
        let color: Vec<f32> = image
            .pixels
            .iter()
            .flat_map(|p| p.max(glam::Vec3A::ZERO).to_array())
            .collect();
        let settings = |hdr, clean_aux| oidn::FilterSettings {
            hdr,
            clean_aux,
            quality: self.options.quality,
        };
        let mut out = vec![0.0f32; color.len()];
        let prefilter = match self.options.prefilter {
            Prefilter::Auto => aovs.samples < PREFILTER_BELOW_SPP,
            Prefilter::On => true,
            Prefilter::Off => false,
        };
        let prefiltered = if prefilter {
            let guide = take_filter(&mut self.guide, &self.device)?;
            let mut clean = [vec![0.0f32; color.len()], vec![0.0f32; color.len()]];
            for ((name, values), clean) in [("albedo", albedo), ("normal", normal)]
                .into_iter()
                .zip(&mut clean)
            {
                guide.run(
                    oidn::Images {
                        width: w,
                        height: h,
                        input: (name, values),
                        guides: Vec::new(),
                        output: clean,
                    },
                    settings(false, false),
                )?;
            }
            Some(clean)
        } else {
            None
        };
        let (albedo, normal) = match &prefiltered {
            Some([a, n]) => (a.as_slice(), n.as_slice()),
            None => (albedo, normal),
        };
        let filter = take_filter(&mut self.color, &self.device)?;
        filter.run(
            oidn::Images {
                width: w,
                height: h,
                input: ("color", &color),
                guides: vec![("albedo", albedo), ("normal", normal)],
                output: &mut out,
            },
            settings(true, true),
        )?;
        let to_film = |out: &[f32]| {
            let mut film = Film::new(image.width, image.height);
            for (p, v) in film.pixels.iter_mut().zip(out.chunks_exact(3)) {
                *p = glam::Vec3A::new(v[0], v[1], v[2]);
            }
            film.clamp_to_finite();
            film
        };
        let denoised = to_film(&out);
        let halves = half.map(|half| blend::halves(image, half, counts, aovs.samples));
        let result = match halves {
            // Some pixel has two halves: the guard.
            Some(halves) if halves.iter().any(Option::is_some) => {
                let a: Vec<f32> = halves
                    .iter()
                    .zip(&image.pixels)
                    .flat_map(|(h, x)| match h {
                        Some((a, _)) => a.to_array(),
                        // No halves: the pixel's value (its estimate is 0).
                        None => x.max(glam::Vec3A::ZERO).to_array(),
                    })
                    .collect();
                let filter = take_filter(&mut self.half, &self.device)?;
                filter.run(
                    oidn::Images {
                        width: w,
                        height: h,
                        input: ("color", &a),
                        guides: vec![("albedo", albedo), ("normal", normal)],
                        output: &mut out,
                    },
                    settings(true, true),
                )?;
                let denoised_a = to_film(&out);
                let mut weights = guard(image, &denoised, &halves, &denoised_a);
                if let Some(v) = variance {
                    let heuristic = heuristic::weights(image, &denoised, v, &aovs.coverage);
                    for (w, h) in weights.iter_mut().zip(heuristic) {
                        *w = w.min(h);
                    }
                }
                Guarded {
                    image: heuristic::apply(image, &denoised, &weights),
                    denoised,
                    weights: Some(weights),
                    check: Some(Check {
                        halves,
                        denoised_half: denoised_a,
                    }),
                }
            }
            // One sample: nothing is known of the noise (see `blend`); the
            // heuristic blend alone.
            _ => match variance {
                Some(v) => {
                    let weights = heuristic::weights(image, &denoised, v, &aovs.coverage);
                    Guarded {
                        image: heuristic::apply(image, &denoised, &weights),
                        denoised,
                        weights: Some(weights),
                        check: None,
                    }
                }
                None => Guarded {
                    image: denoised.clone(),
                    denoised,
                    weights: None,
                    check: None,
                },
            },
        };
        self.last = start.elapsed();
        Ok(result)
    }
}

/// What [`Denoiser::denoise_guarded`] made.
#[derive(Clone, Debug)]
pub struct Guarded {
    /// The result: the noisy image moved towards `denoised` by `weights`.
    pub image: Film,
    /// The denoiser's output for the whole noisy image.
    pub denoised: Film,
    /// Each pixel's weight of `denoised` (`None` without the guard).
    pub weights: Option<Vec<f32>>,
    /// The guard's cross-validation, where it ran (two samples or more).
    pub check: Option<Check>,
}

/// The guard's second denoiser run and what it is compared with.
#[derive(Clone, Debug)]
pub struct Check {
    /// Each pixel's halves `(A, B)` ([`blend::halves`]).
    pub halves: Vec<Option<(glam::Vec3A, glam::Vec3A)>>,
    /// The denoiser's output for `A`.
    pub denoised_half: Film,
}

/// The filter in `slot`, made on `device` the first time.
fn take_filter<'a>(
    slot: &'a mut Option<oidn::Filter>,
    device: &oidn::Device,
) -> Result<&'a mut oidn::Filter, OidnError> {
    if slot.is_none() {
        *slot = Some(device.filter()?);
    }
    Ok(slot.as_mut().expect("made above"))
}
