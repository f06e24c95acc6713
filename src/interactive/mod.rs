//! Interactive rendering: a view that refines one sample per pixel at a
//! time while it rests, starts over when moved, and (with `denoise`) shows a
//! denoised frame made on a thread of its own. `raylab view` puts a
//! [`Preview`] in a window; anything that shows pixels (a notebook widget, a
//! test) can drive it the same way: [`Preview::apply`] the user's actions,
//! [`Preview::refine`] while [`Preview::refining`], and show
//! [`Preview::pixels`].

mod worker;

use std::borrow::Cow;
use std::path::PathBuf;
use std::sync::Arc;
use std::time::{Duration, Instant};

use glam::Vec3A;

use crate::controls::{Action, ViewState};
use crate::film::{Display, Film, ToneMap, write_image_with};
use crate::integrators::Integrator;
use crate::job::{SceneOptions, Session};
use crate::load::SceneKind;
use crate::render::{Accumulator, accumulate};
use crate::scene::Scene;

pub use worker::{Done, Worker};

/// Samples per pixel after which a still view stops refining (`flat` and
/// `direct`, whose images are exact but for antialiasing).
pub const MAX_SAMPLES: u32 = 64;
/// The same for `path`, whose noise keeps falling.
pub const MAX_PATH_SAMPLES: u32 = 1 << 16;
/// How long the view rests before its first denoised frame is made: long
/// enough that a held key or a drag does not denoise every step, short
/// enough to feel immediate.
pub const DENOISE_AFTER: Duration = Duration::from_millis(200);
/// The first denoised frame needs two samples (the variance that weighs it
/// needs two); later ones come when the samples have doubled.
pub const DENOISE_FIRST_SPP: u32 = 2;

/// What [`Preview::apply`] did.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Applied {
    /// Nothing changed.
    Nothing,
    /// The view changed: refinement starts over.
    Changed,
    /// The caller should close the view.
    Quit,
    /// A line to tell the user (a screenshot saved, the denoiser started, or
    /// why not).
    Said(String),
}

/// A scene seen interactively.
pub struct Preview {
    /// Wakes the caller's event loop from the denoising thread.
    wake: Arc<dyn Fn() + Send + Sync>,
    /// The denoiser, while denoised frames are shown.
    denoise: Option<Denoising>,
    /// The `path` integrator with the options' settings (key 3).
    path: Integrator,
    /// Exposure in stops, as for PNG output.
    exposure: f32,
    /// What the scene was made from (how values are shown).
    kind: SceneKind,
    /// Tone mapping on screen and in screenshots.
    tonemap: ToneMap,
    scene: Scene,
    /// The fog the fog keys scale.
    fog: Fog,
    initial: ViewState,
    /// The camera, light and integrator now.
    pub state: ViewState,
    size: (u32, u32),
    /// Sums of `samples` samples per pixel.
    sums: Film,
    samples: u32,
}

/// The fog the viewer's fog keys thicken and thin
/// ([`crate::controls::ViewState::fog`]): the scene's own at factor 1, or,
/// for a scene without, a white isotropic fog of one mean free path per
/// scene radius, added on the first press.
struct Fog {
    /// Extinction and scattering at factor 1.
    sigma_t: Vec3A,
    sigma_s: Vec3A,
    /// The factor the scene's fog has now.
    applied: f32,
}

impl Fog {
    /// The fog of `scene`, whose factor is `factor` (1 if it has fog, 0
    /// if not).
    fn of(scene: &Scene, factor: f32) -> Fog {
        match scene.fog() {
            Some(h) => Fog {
                sigma_t: h.sigma_t,
                sigma_s: h.sigma_s,
                applied: factor,
            },
            None => {
                let sigma = Vec3A::splat(1.0 / scene.radius().max(1e-6));
                Fog {
                    sigma_t: sigma,
                    sigma_s: sigma,
                    applied: 0.0,
                }
            }
        }
    }

    /// Gives the scene's fog the coefficients of `factor` (adding the fog
    /// if the scene has none yet and `factor` is not 0).
    fn apply(&mut self, scene: &mut Scene, factor: f32) {
        if factor == self.applied {
            return;
        }
        if scene.fog().is_none() {
            // (A fog of zero density: the coefficients follow.)
            let white = Vec3A::ONE;
            if scene
                .add_fog_with(Vec3A::ZERO, white, crate::media::Phase::Isotropic)
                .is_err()
            {
                return;
            }
        }
        if let Some(h) = scene.fog_mut() {
            h.sigma_t = self.sigma_t * factor;
            h.sigma_s = self.sigma_s * factor;
        }
        self.applied = factor;
    }
}

impl Preview {
    /// A preview of `session` (loaded with `options`, whose `path` settings
    /// and exposure it keeps); with `options.denoise`, Open Image Denoise is
    /// loaded first (an error says how to install it). `wake` is called from
    /// the denoising thread when a frame is ready.
    pub fn new(
        session: Session,
        options: &SceneOptions,
        wake: Arc<dyn Fn() + Send + Sync>,
    ) -> anyhow::Result<Preview> {
        let (w, h) = session.size;
        let denoise = match options.denoise {
            Some(true) => {
                let wake = wake.clone();
                Some(Denoising::new(Worker::start(move || wake())?, w, h))
            }
            _ => None,
        };
        Ok(Preview {
            wake,
            denoise,
            path: options.integrator_for_path(),
            exposure: options.exposure.unwrap_or(0.0),
            kind: session.kind,
            tonemap: session.tonemap,
            // The viewer moves the scene's light: its own copy (none when unshared).
            fog: Fog::of(&session.scene, session.view.fog),
            scene: std::sync::Arc::unwrap_or_clone(session.scene),
            initial: session.view,
            state: session.view,
            size: (w, h),
            sums: Film::new(w, h),
            samples: 0,
        })
    }

    /// The image size.
    pub fn size(&self) -> (u32, u32) {
        self.size
    }

    /// Samples per pixel of the view so far.
    pub fn samples(&self) -> u32 {
        self.samples
    }

    /// Whether the view has samples still to take.
    pub fn refining(&self) -> bool {
        self.samples < self.max_samples()
    }

    /// Whether a frame is being denoised (the caller is woken when it is
    /// done).
    pub fn denoising(&self) -> bool {
        self.denoise.as_ref().is_some_and(|d| d.worker.busy())
    }

    /// When the next denoised frame is due, if it waits only for the view to
    /// rest: the caller wakes then even if refinement has ended.
    pub fn denoise_due_at(&self) -> Option<Instant> {
        self.denoise.as_ref().and_then(Denoising::due_at)
    }

    /// Starts over (a changed view).
    pub fn restart(&mut self) {
        self.samples = 0;
        if let Some(d) = &mut self.denoise {
            d.restart(self.size.0, self.size.1);
        }
    }

    /// A new image size; starts over.
    pub fn resize(&mut self, w: u32, h: u32) {
        if self.size != (w, h) || self.sums.pixels.is_empty() {
            self.size = (w, h);
            self.sums = Film::new(w, h);
        }
        self.restart();
    }

    /// A drag of the pointer by `dx`, `dy` pixels (looks around).
    pub fn drag(&mut self, dx: f32, dy: f32) -> Applied {
        if self.state.drag(dx, dy) {
            self.restart();
            return Applied::Changed;
        }
        Applied::Nothing
    }

    /// Applies a user's action (see [`crate::controls`]).
    pub fn apply(&mut self, action: Action) -> anyhow::Result<Applied> {
        // Key 3 selects `path` with the options' settings (`max_depth`).
        let action = match action {
            Action::Use(Integrator::Path(_)) => Action::Use(self.path),
            other => other,
        };
        Ok(match action {
            Action::Quit => Applied::Quit,
            Action::ToggleDenoise => {
                let mut said = Applied::Changed;
                if self.denoise.take().is_none() {
                    // A library that cannot be loaded is said, not fatal.
                    let wake = self.wake.clone();
                    said = match Worker::start(move || wake()) {
                        Ok(worker) => {
                            let line = format!("denoising with {}", worker.describe());
                            self.denoise = Some(Denoising::new(worker, self.size.0, self.size.1));
                            Applied::Said(line)
                        }
                        Err(e) => Applied::Said(format!(
                            "error: {}",
                            crate::guard::one_line(&format!("{e:#}"))
                        )),
                    }
                }
                self.restart();
                said
            }
            Action::Screenshot => {
                // After a change the sums are stale until the next sample.
                if self.samples == 0 {
                    self.refine();
                }
                // A screenshot that cannot be saved is reported, not fatal.
                Applied::Said(match self.save_screenshot() {
                    Ok(path) => format!("saved {}", path.display()),
                    Err(e) => format!("error: screenshot not saved: {e:#}"),
                })
            }
            _ => {
                if self.state.apply(action, &self.initial) {
                    self.restart();
                    Applied::Changed
                } else {
                    Applied::Nothing
                }
            }
        })
    }

    /// Adds one sample per pixel (unless refinement has ended, or paused
    /// while a frame is denoised) and hands the denoiser its next frame when
    /// due. Returns whether a new denoised frame came in, and lines to tell
    /// the user (the denoiser's errors).
    pub fn refine(&mut self) -> (bool, Vec<String>) {
        let (w, h) = self.size;
        if self.samples == 0 {
            self.sums.pixels.fill(Vec3A::ZERO);
        }
        // While a frame is being denoised, refinement pauses: OIDN then has
        // every core (on two cores it took 0.74–0.97 s beside the render
        // instead of 0.21 s alone, for the helmet at 640×480), and the
        // samples it would add cannot reach the frame in hand anyway.
        if self.refining() && !self.denoising() {
            self.scene.light.position = self.state.light_pos;
            self.fog.apply(&mut self.scene, self.state.fog);
            let camera = self.state.camera(w, h);
            let k = self.samples;
            match &mut self.denoise {
                // Exact sums with the guides, for the denoiser.
                Some(d) => {
                    d.acc
                        .add(&self.scene, &camera, self.state.integrator, 0, 1, &|_| {});
                }
                None => {
                    accumulate(
                        &self.scene,
                        &camera,
                        self.state.integrator,
                        0,
                        k..k + 1,
                        &mut self.sums,
                        &|_| {},
                    );
                }
            }
            self.samples += 1;
        }
        let mut said = Vec::new();
        let mut new_frame = false;
        if let Some(d) = &mut self.denoise {
            let before = d.shown.as_ref().map(|s| s.1);
            said = d.step();
            new_frame = d.shown.as_ref().map(|s| s.1) != before;
        }
        (new_frame, said)
    }

    /// How pixel values are shown (exposure, π for the lab's `path`, tone
    /// mapping), as in `raylab render`'s PNG.
    pub fn display(&self) -> Display {
        crate::job::display(
            self.kind,
            self.state.integrator,
            self.exposure,
            self.tonemap,
        )
    }

    /// The pixels to show and how: the newest denoised frame of this view,
    /// else the samples so far (as sums, with the display's scale divided by
    /// their count, so that nothing is copied).
    pub fn pixels(&self) -> (Cow<'_, [Vec3A]>, Display) {
        let mut display = self.display();
        let pixels = match &self.denoise {
            Some(Denoising {
                shown: Some((film, _)),
                ..
            }) => Cow::Borrowed(film.pixels.as_slice()),
            Some(d) => Cow::Owned(d.acc.film().pixels),
            None => {
                display.scale /= self.samples.max(1) as f32;
                Cow::Borrowed(self.sums.pixels.as_slice())
            }
        };
        (pixels, display)
    }

    /// The frame on show as an image (the denoised one of this view when
    /// there is one, else the average of the samples so far).
    pub fn frame(&self) -> Film {
        match &self.denoise {
            Some(Denoising {
                shown: Some((film, _)),
                ..
            }) => film.clone(),
            Some(d) => d.acc.film(),
            None => {
                let mut frame = self.sums.clone();
                frame.average(self.samples);
                frame
            }
        }
    }

    /// Saves the frame on show as the first free `raylab-NNNN.png`.
    pub fn save_screenshot(&self) -> anyhow::Result<PathBuf> {
        let path = (1..)
            .map(|i| PathBuf::from(format!("raylab-{i:04}.png")))
            .find(|p| !p.exists())
            .expect("a free name");
        write_image_with(&self.frame(), &path, self.display())?;
        Ok(path)
    }

    /// The window title's text: integrator, size, the last frame's time and
    /// rate, samples, and the denoiser's state.
    pub fn title(&self, frame_ms: f64, fps: f64) -> String {
        let denoised = match &self.denoise {
            Some(Denoising {
                shown: Some((_, spp)),
                took,
                ..
            }) => format!(
                " · denoised at {spp} spp in {:.0} ms",
                took.as_secs_f64() * 1e3
            ),
            Some(_) => " · denoising".to_string(),
            None => String::new(),
        };
        format!(
            "raylab · {} · {}×{} · {frame_ms:.1} ms ({fps:.0} fps) · {} spp{denoised}",
            self.state.integrator, self.size.0, self.size.1, self.samples
        )
    }

    /// Samples per pixel at which refinement stops for the current integrator.
    fn max_samples(&self) -> u32 {
        if self.state.integrator.is_physical() {
            MAX_PATH_SAMPLES
        } else {
            MAX_SAMPLES
        }
    }
}

/// The preview's state while it denoises: exact sums with the denoiser's
/// guides (instead of the f32 film), and the denoised frames of this view.
struct Denoising {
    worker: Worker,
    /// Samples of the current view, with the guides and variance.
    acc: Accumulator,
    /// Which view the sums are of (bumped by every change).
    generation: u64,
    /// When the view last changed.
    since: Instant,
    /// Samples at which the next frame is denoised.
    next_spp: u32,
    /// The newest denoised frame of this view and its samples.
    shown: Option<(Film, u32)>,
    /// How long the last denoising took.
    took: Duration,
}

impl Denoising {
    fn new(worker: Worker, w: u32, h: u32) -> Self {
        Self {
            worker,
            acc: Accumulator::new(w, h, crate::denoise::GUIDES),
            generation: 0,
            since: Instant::now(),
            next_spp: DENOISE_FIRST_SPP,
            shown: None,
            took: Duration::ZERO,
        }
    }

    /// When the next frame is due to be denoised, if it waits only for the
    /// view to rest.
    fn due_at(&self) -> Option<Instant> {
        let ready = !self.worker.busy() && self.acc.spp() >= self.next_spp;
        let at = self.since + DENOISE_AFTER;
        (ready && Instant::now() < at).then_some(at)
    }

    /// Starts over for a changed view.
    fn restart(&mut self, w: u32, h: u32) {
        self.acc = Accumulator::new(w, h, crate::denoise::GUIDES);
        self.generation += 1;
        self.since = Instant::now();
        self.next_spp = DENOISE_FIRST_SPP;
        self.shown = None;
    }

    /// Takes a finished frame (if it is of this view), and hands the worker
    /// the next one when it is due: the view has rested a moment and the
    /// samples have doubled since the last. Returns the errors to tell.
    fn step(&mut self) -> Vec<String> {
        let mut said = Vec::new();
        while let Some(done) = self.worker.poll() {
            if done.generation != self.generation {
                continue; // of a view left behind
            }
            match done.film {
                Ok(film) => {
                    self.shown = Some((film, done.spp));
                    self.took = done.took;
                }
                Err(e) => said.push(format!("error: {}", crate::guard::one_line(&e))),
            }
        }
        let spp = self.acc.spp();
        if !self.worker.busy() && spp >= self.next_spp && self.since.elapsed() >= DENOISE_AFTER {
            let rendered = self.acc.rendered();
            if let Some(aovs) = rendered.aovs {
                self.worker
                    .submit(self.generation, spp, rendered.film, aovs);
                self.next_spp = spp.saturating_mul(2);
            }
        }
        said
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::controls::{FOG_MIN, FOG_STEP};

    /// The fog keys' fog: a scene without one gets a white fog of one
    /// mean free path per radius, scaled by the factor, on the first
    /// non-zero factor; a scene with one has its own scaled; factor 0
    /// clears it; the paths through the box see it (thick white fog lit by
    /// the box's light: 2.6 times the clear box's light, measured).
    #[test]
    fn the_fog_keys_scale_the_scenes_fog() {
        let mut scene = crate::load::cornell::scene();
        let mut fog = Fog::of(&scene, 0.0);
        assert!(scene.fog().is_none());
        fog.apply(&mut scene, 0.0);
        assert!(scene.fog().is_none(), "nothing to do at 0");
        fog.apply(&mut scene, FOG_MIN);
        let sigma = FOG_MIN / scene.radius();
        let h = scene.fog().expect("fog added");
        assert!((h.sigma_t - Vec3A::splat(sigma)).abs().max_element() < 1e-6);
        assert_eq!(h.sigma_s, h.sigma_t);
        let radiance = |scene: &Scene| {
            let camera = crate::camera::Camera::lab(Vec3A::new(0.0, 0.0, -3.0), 0.0, 0.0, 32, 32);
            let opts = crate::integrators::path::PathOptions::default();
            let mut rays = 0;
            let mut sum = 0.0f64;
            for i in 0..4096u64 {
                let mut rng = crate::sampling::sampler::Rng::new(i, 1);
                let ray = camera.ray(16.0 + (i % 7) as f32, 16.0 + (i % 5) as f32);
                let l = crate::integrators::path::radiance(scene, &ray, &opts, &mut rng, &mut rays);
                sum += f64::from(l.x + l.y + l.z);
            }
            sum
        };
        fog.apply(&mut scene, 0.0);
        assert_eq!(scene.fog().unwrap().sigma_t, Vec3A::ZERO, "off is clear");
        let clear = radiance(&scene);
        fog.apply(&mut scene, FOG_MIN * FOG_STEP.powi(12));
        let thick = radiance(&scene);
        // (White fog lit by the box's light: brighter than the walls.)
        assert!(
            (thick - clear).abs() > 0.2 * clear,
            "thick fog {thick} vs clear {clear}"
        );

        // A scene's own fog is the factor's 1.
        let mut foggy = crate::load::cornell::scene();
        foggy
            .add_fog_with(
                Vec3A::new(0.2, 0.3, 0.4),
                Vec3A::splat(0.5),
                crate::media::Phase::Isotropic,
            )
            .unwrap();
        let mut fog = Fog::of(&foggy, 1.0);
        fog.apply(&mut foggy, 1.5);
        let h = foggy.fog().unwrap();
        assert!((h.sigma_t - Vec3A::new(0.3, 0.45, 0.6)).abs().max_element() < 1e-6);
        assert!(
            (h.sigma_s - Vec3A::new(0.15, 0.225, 0.3))
                .abs()
                .max_element()
                < 1e-6
        );
    }
}
