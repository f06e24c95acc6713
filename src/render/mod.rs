//! Rendering an image: tiles of rows on rayon, samples keyed by (seed, pixel,
//! sample) so the result is bit-identical for any number of threads.
//!
//! Here the API and the passes; the exact sums ([`Accumulator`]), the parts
//! of an image ([`Split`]), what a render gives back ([`Rendered`], [`Tally`])
//! and the tiles' loops are in files of their own.

mod accumulator;
pub mod adaptive;
mod light_image;
mod output;
mod sinks;
mod split;
mod tile;

use std::ops::Range;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use glam::Vec3A;

use crate::aov::AovSet;
use crate::camera::Camera;
use crate::film::Film;
use crate::integrators::Integrator;
use crate::integrators::path;
use crate::materials::Material;
use crate::scene::{Scene, SurfaceHit};
pub use accumulator::{Accumulator, PartsError};
pub use adaptive::Adaptive;
pub use output::{Rendered, Tally};
pub use split::{Split, TILE_ROWS};
use tile::{AnySampler, PathStart, Target, accumulate_into, pixel_ray};

/// How to render.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct RenderSettings {
    /// Light transport algorithm.
    pub integrator: Integrator,
    /// Samples per pixel (at least 1).
    pub spp: u32,
    /// Seed of the sample positions.
    pub seed: u64,
}

impl Default for RenderSettings {
    fn default() -> Self {
        Self {
            integrator: Integrator::Direct,
            spp: 1,
            seed: 0,
        }
    }
}

/// Renders `settings.spp` samples per pixel and averages them. `progress` is
/// called after each tile with the rows it finished times the samples it took
/// of them (the render is done at `height × spp`), from any thread.
pub fn render(
    scene: &Scene,
    camera: &Camera,
    settings: &RenderSettings,
    progress: &(dyn Fn(u64) + Sync),
) -> Rendered {
    render_with_aovs(scene, camera, settings, AovSet::NONE, progress)
}

/// [`render`] that also gathers `aovs` from the camera rays' first hits (see
/// [`crate::aov`]); the image is the same as without them, bit for bit.
pub fn render_with_aovs(
    scene: &Scene,
    camera: &Camera,
    settings: &RenderSettings,
    aovs: AovSet,
    progress: &(dyn Fn(u64) + Sync),
) -> Rendered {
    let mut acc = Accumulator::new(camera.width, camera.height, aovs);
    render_passes(
        scene,
        camera,
        settings,
        &mut acc,
        &Passes::default(),
        &mut |_, _| {},
        progress,
    );
    acc.rendered()
}

/// A render that took as many samples per pixel as fitted a time budget.
#[derive(Clone, Debug)]
pub struct Progressive {
    /// The image, its rays and dropped samples.
    pub rendered: Rendered,
    /// Samples per pixel taken.
    pub spp: u32,
}

/// Longest pass of a time-limited render: short enough to stop close to the
/// budget and to report progress.
const MAX_PASS: Duration = Duration::from_millis(250);

/// Longest pass of a render of a given number of samples: short enough that a
/// stop request (Ctrl-C) is answered within about half a second, long enough
/// that the pass's end (the last tiles on one core) costs under 1 %.
const MAX_SPP_PASS: Duration = Duration::from_millis(500);

/// Renders in passes of whole samples per pixel (sample `k` is the same as in a
/// render with `--spp` above `k`) until `budget` is spent or `max_spp` reached,
/// always at least one sample. A pass is only started when about half its
/// expected time still fits in the budget. `progress` is called with the time
/// spent so far after every tile.
pub fn render_for(
    scene: &Scene,
    camera: &Camera,
    integrator: Integrator,
    seed: u64,
    budget: Duration,
    max_spp: u32,
    progress: &(dyn Fn(Duration) + Sync),
) -> Progressive {
    let settings = RenderSettings {
        integrator,
        spp: max_spp,
        seed,
    };
    render_for_with_aovs(scene, camera, &settings, AovSet::NONE, budget, progress)
}

/// [`render_for`] that also gathers `aovs` (see [`crate::aov`]) over the
/// samples taken; `settings.spp` is the most samples per pixel to take. The
/// image is the one [`render_with_aovs`] gives for the samples taken, bit for
/// bit.
pub fn render_for_with_aovs(
    scene: &Scene,
    camera: &Camera,
    settings: &RenderSettings,
    aovs: AovSet,
    budget: Duration,
    progress: &(dyn Fn(Duration) + Sync),
) -> Progressive {
    let start = Instant::now();
    let mut acc = Accumulator::new(camera.width, camera.height, aovs);
    let passes = Passes {
        budget: Some(budget),
        ..Passes::default()
    };
    render_passes(
        scene,
        camera,
        settings,
        &mut acc,
        &passes,
        &mut |_, _| {},
        &|_| progress(start.elapsed()),
    );
    Progressive {
        rendered: acc.rendered(),
        spp: acc.spp(),
    }
}

/// How [`render_passes`] goes about its passes.
#[derive(Clone, Copy, Debug, Default)]
pub struct Passes<'a> {
    /// Stop when this much time is spent (counting `spent`), rather than
    /// only at `settings.spp`; at least one sample is always taken.
    pub budget: Option<Duration>,
    /// Time already spent on the accumulator (by an earlier, stopped run).
    pub spent: Duration,
    /// Checked between passes: when set, the render stops after the samples in
    /// flight, with whole samples of every pixel.
    pub stop: Option<&'a AtomicBool>,
    /// Adaptive sampling: pixels stop when their error is below its threshold
    /// (`settings.spp` still caps them). The accumulator must gather
    /// [`crate::aov::Aov::Half`] and [`crate::aov::Aov::Samples`].
    pub adaptive: Option<Adaptive>,
}

/// How [`render_passes`] ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Ended {
    /// Every sample asked for was taken (or, with adaptive sampling, every
    /// pixel stopped).
    Complete,
    /// The time budget was spent.
    Budget,
    /// The stop flag was set.
    Stopped,
}

/// Adds samples to `acc` in passes of whole samples per pixel, each pass sized
/// to take about half a second (or a quarter under a budget) by the time
/// per sample so far, until `settings.spp` samples are taken, the budget is
/// spent or `passes.stop` is set (checked before every pass). After each pass
/// `after_pass` is given the sums and the time spent in all (with
/// `passes.spent`), e.g. to save them. `progress` as for [`render`]. The
/// sums, and so the image, do not depend on how the samples fell into passes.
pub fn render_passes(
    scene: &Scene,
    camera: &Camera,
    settings: &RenderSettings,
    acc: &mut Accumulator,
    passes: &Passes<'_>,
    after_pass: &mut dyn FnMut(&Accumulator, Duration),
    progress: &(dyn Fn(u64) + Sync),
) -> Ended {
    let start = Instant::now();
    let max_spp = settings.spp.max(1);
    let longest = if passes.budget.is_some() {
        MAX_PASS
    } else {
        MAX_SPP_PASS
    };
    loop {
        if acc.spp >= max_spp {
            return Ended::Complete;
        }
        if passes.stop.is_some_and(|s| s.load(Ordering::Relaxed)) {
            return Ended::Stopped;
        }
        // Which pixels go on (made again from the sums before every pass, so
        // that a resumed render decides as the one that was stopped).
        let active = passes
            .adaptive
            .as_ref()
            .and_then(|a| adaptive::active_pixels(acc, a));
        if active.as_ref().is_some_and(|a| !a.contains(&true)) {
            // Every pixel stopped: the render is complete (its pixels count
            // their own samples), as one that went on to `spp` would be.
            acc.spp = max_spp;
            return Ended::Complete;
        }
        // Passes end at the checks.
        let until_check = passes
            .adaptive
            .as_ref()
            .map_or(u32::MAX, |a| a.next_check(acc.spp) - acc.spp);
        let spent = passes.spent + start.elapsed();
        let n = if acc.spp == 0 {
            1
        } else {
            let per_sample = spent / acc.spp;
            let mut room = longest;
            if let Some(budget) = passes.budget {
                let remaining = budget.saturating_sub(spent);
                if remaining < per_sample / 2 {
                    return Ended::Budget;
                }
                room = room.min(remaining);
            }
            let fit = room.as_secs_f64() / per_sample.as_secs_f64().max(1e-9);
            (fit.round().min(u32::MAX as f64) as u32).clamp(1, max_spp - acc.spp)
        };
        acc.add_active(
            scene,
            camera,
            settings.integrator,
            settings.seed,
            n.min(until_check),
            active.as_deref(),
            progress,
        );
        after_pass(acc, passes.spent + start.elapsed());
    }
}

/// Adds samples `samples` of every pixel to `sums`, in sample order, and returns
/// the number of rays cast and of samples dropped. For `flat` and `direct`, sample
/// 0 goes through the pixel centre and the others are uniformly jittered over the
/// pixel; `path` jitters every sample (a box filter, the pixel-area average, as
/// Mitsuba's `box`), its random numbers keyed by (seed, pixel, sample,
/// dimension). A sample that is NaN or infinite is dropped and counted. The viewer
/// refines by calls for `0..1`, `1..2`, ...; one call for `0..n` gives the same
/// sums up to f32 rounding ([`Accumulator`] keeps them exact).
pub fn accumulate(
    scene: &Scene,
    camera: &Camera,
    integrator: Integrator,
    seed: u64,
    samples: Range<u32>,
    sums: &mut Film,
    progress: &(dyn Fn(u64) + Sync),
) -> Tally {
    accumulate_into(
        scene,
        camera,
        integrator,
        seed,
        samples,
        Target::Narrow(sums),
        progress,
    )
}

/// The value of one pixel sample, for tests and tools that probe single pixels.
pub fn sample_pixel(
    scene: &Scene,
    camera: &Camera,
    integrator: Integrator,
    x: u32,
    y: u32,
) -> Vec3A {
    let mut rays = 0;
    let ray = camera.ray(x as f32 + 0.5, y as f32 + 0.5);
    integrator.radiance(scene, &ray, &mut rays)
}

/// Sample `s` of pixel `(x, y)` exactly as a render with `seed` computes it (the
/// same camera ray, random numbers and hit), its path shown to `tracer`
/// (`path` only; `flat` and `direct` have no path). For `--nan-check` and for
/// reproducing one sample of an image.
#[allow(clippy::too_many_arguments)]
pub fn probe_sample(
    scene: &Scene,
    camera: &Camera,
    integrator: Integrator,
    seed: u64,
    x: u32,
    y: u32,
    s: u32,
    tracer: &mut impl path::PathTracer,
) -> Vec3A {
    let mut rays = 0;
    let width = camera.width as usize;
    match integrator {
        Integrator::Path(options) => {
            let start = PathStart::new(camera, &options, seed, (x as usize, y as usize), s);
            let hit = scene.intersect(&start.ray, f32::INFINITY);
            let ray = start.ray;
            let mut observe = |_: &SurfaceHit, _: &Material| {};
            match start.sampler {
                AnySampler::Sobol(mut smp) => path::radiance_traced(
                    scene,
                    &ray,
                    hit,
                    &options,
                    &mut smp,
                    &mut rays,
                    &mut observe,
                    tracer,
                ),
                AnySampler::Independent(mut rng) => path::radiance_traced(
                    scene,
                    &ray,
                    hit,
                    &options,
                    &mut rng,
                    &mut rays,
                    &mut observe,
                    tracer,
                ),
            }
        }
        _ => {
            let ray = pixel_ray(camera, seed, s, x as usize, y as usize, width);
            integrator.radiance(scene, &ray, &mut rays)
        }
    }
}
