//! `raylab view`: a window that renders on all cores and refines while still.

use std::num::NonZeroU32;
use std::path::{Path, PathBuf};
use std::rc::Rc;
use std::time::{Duration, Instant};

use anyhow::{Context, anyhow};
use raylab::controls::{Action, ViewState};
use raylab::film::{Display, Film, ToneMap, write_image_with};
use raylab::load::SceneKind;
use raylab::render::{Accumulator, accumulate};
use raylab::{Integrator, Scene};
use rayon::prelude::*;
use winit::application::ApplicationHandler;
use winit::dpi::PhysicalSize;
use winit::event::{ElementState, MouseButton, StartCause, WindowEvent};
use winit::event_loop::{ActiveEventLoop, ControlFlow, EventLoop};
use winit::keyboard::PhysicalKey;
use winit::window::{Window, WindowId};

use crate::Session;
use crate::args::SceneArgs;
use crate::denoise_worker::Worker;
use crate::keys::action_for_key;

/// Samples per pixel after which a still view stops refining and the viewer idles
/// (`flat` and `direct`, whose images are exact but for antialiasing).
const MAX_SAMPLES: u32 = 64;
/// The same for `path`, whose noise keeps falling.
const MAX_PATH_SAMPLES: u32 = 1 << 16;
/// How often the title's timing figures are refreshed.
const TITLE_INTERVAL: Duration = Duration::from_millis(250);
/// How long the view rests before its first denoised frame is made: long
/// enough that a held key or a drag does not denoise every step, short
/// enough to feel immediate.
const DENOISE_AFTER: Duration = Duration::from_millis(200);
/// The first denoised frame needs two samples (the variance that weighs it
/// needs two); later ones come when the samples have doubled.
const DENOISE_FIRST_SPP: u32 = 2;

/// Connects to the X display: the viewer's event loop, or why there is none.
pub fn open_display() -> anyhow::Result<EventLoop<()>> {
    let Some(display) = std::env::var_os("DISPLAY").filter(|d| !d.is_empty()) else {
        return Err(anyhow!(
            "cannot open a window: no X display (DISPLAY is not set); use `raylab render` instead"
        ));
    };
    EventLoop::new().map_err(|_| {
        anyhow!(
            "cannot open a window: no X server answers on DISPLAY={}",
            display.to_string_lossy()
        )
    })
}

/// Opens the viewer on the scene of `args`.
pub fn run(args: &SceneArgs) -> anyhow::Result<()> {
    let session = crate::load(args, false)?;
    run_on(open_display()?, session, args)
}

/// Runs the viewer on an event loop already connected to a display.
pub fn run_on(event_loop: EventLoop<()>, session: Session, args: &SceneArgs) -> anyhow::Result<()> {
    let (w, h) = session.size;
    let proxy = event_loop.create_proxy();
    let wake: std::sync::Arc<dyn Fn() + Send + Sync> = std::sync::Arc::new(move || {
        let _ = proxy.send_event(());
    });
    // --denoise: OIDN is loaded before the window opens (a missing library is
    // one line and exit 1, as for `raylab render`).
    let worker = match args.denoise {
        Some(true) => {
            let wake = wake.clone();
            Some(Worker::start(move || wake())?)
        }
        _ => None,
    };
    let mut app = Viewer {
        wake,
        denoise: worker.map(|worker| Denoising::new(worker, w, h)),
        path: args.integrator_for_path(),
        exposure: args.exposure.unwrap_or(0.0),
        kind: session.kind,
        tonemap: session.tonemap,
        scene: session.scene,
        initial: session.view,
        state: session.view,
        size: (w, h),
        sums: Film::new(w, h),
        samples: 0,
        gfx: None,
        dragging: false,
        cursor: None,
        timing: Timing::new(),
        error: None,
    };
    event_loop
        .run_app(&mut app)
        .map_err(|e| anyhow!("viewer: {e}"))?;
    match app.error {
        Some(e) => Err(e),
        None => Ok(()),
    }
}

/// The window and its pixel surface, created once the event loop is running.
struct Graphics {
    window: Rc<Window>,
    surface: softbuffer::Surface<Rc<Window>, Rc<Window>>,
}

struct Viewer {
    /// Wakes the event loop from the denoising thread.
    wake: std::sync::Arc<dyn Fn() + Send + Sync>,
    /// The denoiser, while denoised frames are shown (--denoise, key N).
    denoise: Option<Denoising>,
    /// The `path` integrator with the command line's options (key 3).
    path: Integrator,
    /// PNG exposure in stops, also applied on screen.
    exposure: f32,
    /// What the scene was made from (how values are shown).
    kind: SceneKind,
    /// Tone mapping on screen and in screenshots.
    tonemap: ToneMap,
    scene: Scene,
    initial: ViewState,
    state: ViewState,
    size: (u32, u32),
    /// Sums of `samples` samples per pixel.
    sums: Film,
    samples: u32,
    gfx: Option<Graphics>,
    /// Whether the left button is down (dragging looks around).
    dragging: bool,
    /// Last known cursor position; unknown until the cursor first moves.
    cursor: Option<(f64, f64)>,
    timing: Timing,
    error: Option<anyhow::Error>,
}

/// The viewer's state while it denoises: exact sums with the denoiser's
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
            acc: Accumulator::new(w, h, raylab::denoise::GUIDES),
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
        self.acc = Accumulator::new(w, h, raylab::denoise::GUIDES);
        self.generation += 1;
        self.since = Instant::now();
        self.next_spp = DENOISE_FIRST_SPP;
        self.shown = None;
    }

    /// Takes a finished frame (if it is of this view), and hands the worker
    /// the next one when it is due: the view has rested a moment and the
    /// samples have doubled since the last.
    fn step(&mut self) {
        while let Some(done) = self.worker.poll() {
            if done.generation != self.generation {
                continue; // of a view left behind
            }
            match done.film {
                Ok(film) => {
                    self.shown = Some((film, done.spp));
                    self.took = done.took;
                }
                Err(e) => eprintln!("error: {}", raylab::guard::one_line(&e)),
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
    }
}

/// Frame time and rate for the title bar.
struct Timing {
    last_frame_ms: f64,
    frames: u32,
    since: Instant,
    fps: f64,
}

impl Timing {
    fn new() -> Self {
        Self {
            last_frame_ms: 0.0,
            frames: 0,
            since: Instant::now(),
            fps: 0.0,
        }
    }

    /// Records a frame; returns true when the title is due for a refresh.
    fn frame(&mut self, ms: f64) -> bool {
        self.last_frame_ms = ms;
        self.frames += 1;
        let elapsed = self.since.elapsed();
        if elapsed >= TITLE_INTERVAL {
            self.fps = self.frames as f64 / elapsed.as_secs_f64();
            self.frames = 0;
            self.since = Instant::now();
            return true;
        }
        false
    }
}

impl Viewer {
    fn fail(&mut self, event_loop: &ActiveEventLoop, e: anyhow::Error) {
        self.error = Some(e);
        event_loop.exit();
    }

    fn restart(&mut self) {
        self.samples = 0;
        if let Some(d) = &mut self.denoise {
            d.restart(self.size.0, self.size.1);
        }
        if let Some(g) = &self.gfx {
            g.window.request_redraw();
        }
    }

    fn set_title(&self) {
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
        if let Some(g) = &self.gfx {
            g.window.set_title(&format!(
                "raylab · {} · {}×{} · {:.1} ms ({:.0} fps) · {} spp{denoised}",
                self.state.integrator,
                self.size.0,
                self.size.1,
                self.timing.last_frame_ms,
                self.timing.fps,
                self.samples
            ));
        }
    }

    /// Samples per pixel at which refinement stops for the current integrator.
    fn max_samples(&self) -> u32 {
        if self.state.integrator.is_physical() {
            MAX_PATH_SAMPLES
        } else {
            MAX_SAMPLES
        }
    }

    /// How pixel values are shown (exposure, π for the lab's `path`, tone mapping).
    fn display(&self) -> Display {
        crate::display(
            self.kind,
            self.state.integrator,
            self.exposure,
            self.tonemap,
        )
    }

    fn handle(&mut self, action: Action, event_loop: &ActiveEventLoop) -> anyhow::Result<()> {
        // Key 3 selects `path` with the command line's options (--max-depth).
        let action = match action {
            Action::Use(Integrator::Path(_)) => Action::Use(self.path),
            other => other,
        };
        match action {
            Action::Quit => event_loop.exit(),
            Action::ToggleDenoise => {
                if self.denoise.take().is_none() {
                    // A library that cannot be loaded is said, not fatal.
                    let wake = self.wake_fn();
                    match Worker::start(wake) {
                        Ok(worker) => {
                            eprintln!("denoising with {}", worker.describe());
                            self.denoise = Some(Denoising::new(worker, self.size.0, self.size.1));
                        }
                        Err(e) => {
                            eprintln!("error: {}", raylab::guard::one_line(&format!("{e:#}")))
                        }
                    }
                }
                self.restart();
            }
            Action::Screenshot => {
                // After a change the sums are stale until the next frame: draw it now.
                if self.samples == 0 {
                    self.draw()?;
                }
                // A screenshot that cannot be saved is reported, not fatal.
                match self.save_screenshot() {
                    Ok(path) => eprintln!("saved {}", path.display()),
                    Err(e) => eprintln!("error: screenshot not saved: {e:#}"),
                }
            }
            _ => {
                if self.state.apply(action, &self.initial) {
                    self.restart();
                }
            }
        }
        Ok(())
    }

    /// Saves the frame on screen as the first free `raylab-NNNN.png`.
    fn save_screenshot(&self) -> anyhow::Result<PathBuf> {
        let path = (1..)
            .map(|i| PathBuf::from(format!("raylab-{i:04}.png")))
            .find(|p| !p.exists())
            .expect("a free name");
        write_image_with(&self.frame(), Path::new(&path), self.display())?;
        Ok(path)
    }

    /// The frame to show: the denoised one of this view when there is one,
    /// else the average of the samples so far.
    fn frame(&self) -> Film {
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

    /// A function that wakes the event loop (for the denoising thread).
    fn wake_fn(&self) -> impl Fn() + Send + 'static {
        let wake = self.wake.clone();
        move || wake()
    }

    /// Adds one sample per pixel and shows the average.
    fn draw(&mut self) -> anyhow::Result<()> {
        if self.gfx.is_none() {
            return Ok(());
        }
        let start = Instant::now();
        let (w, h) = self.size;
        if self.samples == 0 {
            self.sums.pixels.fill(glam::Vec3A::ZERO);
        }
        // While a frame is being denoised, refinement pauses: OIDN then has
        // every core (on two cores it took 0.74–0.97 s beside the render
        // instead of 0.21 s alone, for the helmet at 640×480), and the
        // samples it would add cannot reach the frame in hand anyway.
        let paused = self.denoise.as_ref().is_some_and(|d| d.worker.busy());
        if self.samples < self.max_samples() && !paused {
            self.scene.light.position = self.state.light_pos;
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
        let mut new_frame = false;
        let mut waiting = false;
        if let Some(d) = &mut self.denoise {
            let before = d.shown.as_ref().map(|s| s.1);
            d.step();
            new_frame = d.shown.as_ref().map(|s| s.1) != before;
            // The thread wakes the loop when its frame is done.
            waiting = d.worker.busy();
        }
        self.present()?;
        let refining = self.samples < self.max_samples();
        // Refresh the title a few times a second, and at once after a change (the
        // integrator may be new) or when refinement ends.
        let due = self.timing.frame(start.elapsed().as_secs_f64() * 1e3);
        if due || self.samples == 1 || !refining || new_frame {
            self.set_title();
        }
        if let (true, false, Some(gfx)) = (refining, waiting, &self.gfx) {
            gfx.window.request_redraw();
        }
        Ok(())
    }

    /// Shows the average of the samples so far, sRGB-encoded (or, while
    /// denoising, the newest denoised frame of this view).
    fn present(&mut self) -> anyhow::Result<()> {
        let mut display = self.display();
        // (Borrowed field by field: the window is borrowed mutably below.)
        let averaged;
        let pixels = match &self.denoise {
            Some(Denoising {
                shown: Some((film, _)),
                ..
            }) => &film.pixels,
            Some(d) => {
                averaged = d.acc.film();
                &averaged.pixels
            }
            None => {
                display.scale /= self.samples.max(1) as f32;
                &self.sums.pixels
            }
        };
        let Some(gfx) = self.gfx.as_mut() else {
            return Ok(());
        };
        let mut buffer = gfx
            .surface
            .buffer_mut()
            .map_err(|e| anyhow!("cannot draw: {e}"))?;
        buffer
            .par_chunks_mut(4096)
            .zip(pixels.par_chunks(4096))
            .for_each(|(out, sums)| {
                for (o, s) in out.iter_mut().zip(sums) {
                    let [r, g, b] = display.srgb8(*s);
                    *o = (r as u32) << 16 | (g as u32) << 8 | b as u32;
                }
            });
        buffer.present().map_err(|e| anyhow!("cannot draw: {e}"))
    }

    fn resize(&mut self, size: PhysicalSize<u32>) -> anyhow::Result<()> {
        let (Some(w), Some(h)) = (NonZeroU32::new(size.width), NonZeroU32::new(size.height)) else {
            return Ok(()); // minimised
        };
        if let Some(gfx) = self.gfx.as_mut() {
            gfx.surface
                .resize(w, h)
                .map_err(|e| anyhow!("cannot resize: {e}"))?;
        }
        if self.size != (w.get(), h.get()) || self.sums.pixels.is_empty() {
            self.size = (w.get(), h.get());
            self.sums = Film::new(w.get(), h.get());
        }
        self.restart();
        Ok(())
    }
}

impl ApplicationHandler for Viewer {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if self.gfx.is_some() {
            return;
        }
        let attrs = Window::default_attributes()
            .with_title("raylab")
            .with_inner_size(PhysicalSize::new(self.size.0, self.size.1));
        let result = (|| -> anyhow::Result<Graphics> {
            let window = Rc::new(
                event_loop
                    .create_window(attrs)
                    .context("cannot open a window")?,
            );
            let context = softbuffer::Context::new(window.clone())
                .map_err(|e| anyhow!("cannot draw to the window: {e}"))?;
            let surface = softbuffer::Surface::new(&context, window.clone())
                .map_err(|e| anyhow!("cannot draw to the window: {e}"))?;
            Ok(Graphics { window, surface })
        })();
        match result {
            Ok(gfx) => {
                let size = gfx.window.inner_size();
                self.gfx = Some(gfx);
                if let Err(e) = self.resize(size) {
                    self.fail(event_loop, e);
                }
                self.set_title();
            }
            Err(e) => self.fail(event_loop, e),
        }
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _: WindowId, event: WindowEvent) {
        let result = match event {
            WindowEvent::CloseRequested => {
                event_loop.exit();
                Ok(())
            }
            WindowEvent::Resized(size) => self.resize(size),
            WindowEvent::RedrawRequested => self.draw(),
            WindowEvent::KeyboardInput { event, .. } if event.state == ElementState::Pressed => {
                match event.physical_key {
                    PhysicalKey::Code(code) => match action_for_key(code) {
                        // A held key repeats moves, not screenshots or toggles.
                        Some(Action::Screenshot | Action::ToggleDenoise | Action::Quit)
                            if event.repeat =>
                        {
                            Ok(())
                        }
                        Some(action) => self.handle(action, event_loop),
                        None => Ok(()),
                    },
                    PhysicalKey::Unidentified(_) => Ok(()),
                }
            }
            WindowEvent::MouseInput {
                state,
                button: MouseButton::Left,
                ..
            } => {
                self.dragging = state == ElementState::Pressed;
                Ok(())
            }
            WindowEvent::CursorMoved { position, .. } => {
                let now = (position.x, position.y);
                if let (true, Some((x0, y0))) = (self.dragging, self.cursor)
                    && self.state.drag((now.0 - x0) as f32, (now.1 - y0) as f32)
                {
                    self.restart();
                }
                self.cursor = Some(now);
                Ok(())
            }
            _ => Ok(()),
        };
        if let Err(e) = result {
            self.fail(event_loop, e);
        }
    }

    fn about_to_wait(&mut self, event_loop: &ActiveEventLoop) {
        // A denoised frame due once the view has rested: wake up for it even
        // if refinement has ended.
        let flow = match self.denoise.as_ref().and_then(Denoising::due_at) {
            Some(t) => ControlFlow::WaitUntil(t),
            None => ControlFlow::Wait,
        };
        event_loop.set_control_flow(flow);
    }

    fn new_events(&mut self, _: &ActiveEventLoop, cause: StartCause) {
        if let (StartCause::ResumeTimeReached { .. }, Some(g)) = (cause, &self.gfx) {
            g.window.request_redraw();
        }
    }

    fn user_event(&mut self, _: &ActiveEventLoop, (): ()) {
        // The denoising thread finished a frame.
        if let Some(g) = &self.gfx {
            g.window.request_redraw();
        }
    }
}
