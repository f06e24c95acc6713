//! `raylab view`: a window that renders on all cores and refines while still.

use std::num::NonZeroU32;
use std::rc::Rc;
use std::time::{Duration, Instant};

use anyhow::{Context, anyhow};
use raylab::controls::Action;
use raylab::interactive::{Applied, Preview};
use raylab::job::{Hooks, SceneOptions, Session};
use rayon::prelude::*;
use winit::application::ApplicationHandler;
use winit::dpi::PhysicalSize;
use winit::event::{ElementState, MouseButton, StartCause, WindowEvent};
use winit::event_loop::{ActiveEventLoop, ControlFlow, EventLoop};
use winit::keyboard::PhysicalKey;
use winit::window::{Window, WindowId};

use crate::keys::action_for_key;

/// How often the title's timing figures are refreshed.
const TITLE_INTERVAL: Duration = Duration::from_millis(250);

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
/// Hooks that print the job's lines on standard error.
pub fn hooks() -> Hooks<'static> {
    Hooks {
        on_event: &|event| {
            if let raylab::job::Event::Line(line) = event {
                eprintln!("{line}")
            }
        },
        stop: None,
    }
}

pub fn run(args: &SceneOptions) -> anyhow::Result<()> {
    let session = raylab::job::load_session(args, false, 0, &hooks())?;
    run_on(open_display()?, session, args)
}

/// Runs the viewer on an event loop already connected to a display.
pub fn run_on(
    event_loop: EventLoop<()>,
    session: Session,
    args: &SceneOptions,
) -> anyhow::Result<()> {
    let proxy = event_loop.create_proxy();
    let wake: std::sync::Arc<dyn Fn() + Send + Sync> = std::sync::Arc::new(move || {
        let _ = proxy.send_event(());
    });
    // --denoise: OIDN is loaded before the window opens (a missing library is
    // one line and exit 1, as for `raylab render`).
    let mut app = Viewer {
        preview: Preview::new(session, args, wake)?,
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
    /// The scene, its view and its samples.
    preview: Preview,
    gfx: Option<Graphics>,
    /// Whether the left button is down (dragging looks around).
    dragging: bool,
    /// Last known cursor position; unknown until the cursor first moves.
    cursor: Option<(f64, f64)>,
    timing: Timing,
    error: Option<anyhow::Error>,
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

    fn redraw(&self) {
        if let Some(g) = &self.gfx {
            g.window.request_redraw();
        }
    }

    fn set_title(&self) {
        if let Some(g) = &self.gfx {
            let title = self
                .preview
                .title(self.timing.last_frame_ms, self.timing.fps);
            g.window.set_title(&title);
        }
    }

    fn handle(&mut self, action: Action, event_loop: &ActiveEventLoop) -> anyhow::Result<()> {
        match self.preview.apply(action)? {
            Applied::Quit => event_loop.exit(),
            Applied::Nothing => {}
            Applied::Changed => self.redraw(),
            Applied::Said(line) => {
                eprintln!("{line}");
                self.redraw();
            }
        }
        Ok(())
    }

    /// Adds one sample per pixel and shows the result.
    fn draw(&mut self) -> anyhow::Result<()> {
        if self.gfx.is_none() {
            return Ok(());
        }
        let start = Instant::now();
        let (new_frame, said) = self.preview.refine();
        for line in said {
            eprintln!("{line}");
        }
        // The thread wakes the loop when its frame is done.
        let waiting = self.preview.denoising();
        self.present()?;
        let refining = self.preview.refining();
        // Refresh the title a few times a second, and at once after a change (the
        // integrator may be new) or when refinement ends.
        let due = self.timing.frame(start.elapsed().as_secs_f64() * 1e3);
        if due || self.preview.samples() == 1 || !refining || new_frame {
            self.set_title();
        }
        if refining && !waiting {
            self.redraw();
        }
        Ok(())
    }

    /// Shows the preview's pixels, sRGB-encoded.
    fn present(&mut self) -> anyhow::Result<()> {
        let (pixels, display) = self.preview.pixels();
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
        self.preview.resize(w.get(), h.get());
        self.redraw();
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
            .with_inner_size(PhysicalSize::new(
                self.preview.size().0,
                self.preview.size().1,
            ));
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
                    && self.preview.drag((now.0 - x0) as f32, (now.1 - y0) as f32)
                        == Applied::Changed
                {
                    self.redraw();
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
        let flow = match self.preview.denoise_due_at() {
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
