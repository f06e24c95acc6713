//! raylab in Python: the native module `raylab._raylab` behind the `raylab`
//! package (`python/raylab/__init__.py` wraps it for users).
//!
//! Every keyword argument of `raylab.render` is an option of `raylab render`:
//! the keywords become the command line's arguments (`max_depth=8` is
//! `--max-depth=8`), parsed by the same clap definition
//! ([`raylab::job::JobOptions`]), so that names, defaults, checks and messages
//! are the command line's. A render runs on a thread of its own while the
//! calling thread waits without the GIL, waking every 50 ms to print the
//! job's lines, report progress and check for Ctrl-C, which sets the job's
//! stop flag: the render stops after the samples in flight and the image so
//! far comes back, marked as interrupted.

use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, Condvar, Mutex, mpsc};
use std::time::{Duration, Instant};

mod args;

use args::{arguments, parse, scene_name, spec};
use glam::Vec3A;
use pyo3::exceptions::{PyException, PyKeyboardInterrupt, PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyDict, PyList};
use raylab::controls::{Action, ViewState};
use raylab::film::{Channel, Display, Film, MetaValue, ToneMap};
use raylab::job::{Event, Hooks, Job, JobOptions, Rendered, Session, load_session};

pyo3::create_exception!(
    _raylab,
    LoadError,
    PyException,
    "A scene, mesh, environment map or scene file cannot be loaded; the message (the command line's) names the file."
);
pyo3::create_exception!(
    _raylab,
    RenderError,
    PyException,
    "A render failed (or raylab itself failed: a panic inside raylab comes out as this error, never as an abort)."
);

/// A camera given as `camera=` becomes `camera_pos`, `yaw` and `pitch`
/// (which it must not be given with); a number stays the glTF camera's.
fn expand_camera<'py>(function: &str, kwargs: &Bound<'py, PyDict>) -> PyResult<Bound<'py, PyDict>> {
    let out = kwargs.copy()?;
    let Some(value) = kwargs.get_item("camera")? else {
        return Ok(out);
    };
    let Ok(camera) = value.cast::<Camera>() else {
        return Ok(out);
    };
    for key in ["camera_pos", "yaw", "pitch"] {
        if kwargs.get_item(key)?.is_some_and(|v| !v.is_none()) {
            return Err(PyValueError::new_err(format!(
                "{function}(): camera= (a raylab.Camera) and {key}= both place the camera: give one"
            )));
        }
    }
    let v = camera.get().view;
    out.del_item("camera")?;
    let p = v.camera_pos;
    out.set_item("camera_pos", format!("{},{},{}", p.x, p.y, p.z))?;
    out.set_item("yaw", format!("{}", v.yaw_deg))?;
    out.set_item("pitch", format!("{}", v.pitch_deg))?;
    Ok(out)
}

/// What a job's thread tells the waiting Python thread.
struct Mailbox<T> {
    /// Lines to print, and the work's result once it is done.
    state: Mutex<(Vec<String>, Option<std::thread::Result<T>>)>,
    wake: Condvar,
    /// Progress: done, total.
    done: AtomicU64,
    total: AtomicU64,
    /// Set to stop the render (Ctrl-C, or an exception in the callback).
    stop: AtomicBool,
}

impl<T> Mailbox<T> {
    fn say(&self, line: &str) {
        self.state.lock().unwrap().0.push(line.to_string());
        self.wake.notify_one();
    }

    fn finish(&self, result: std::thread::Result<T>) {
        self.state.lock().unwrap().1 = Some(result);
        self.wake.notify_one();
    }

    /// Waits up to `timeout` for the work to end or a line; returns the lines
    /// and the result if the work is done.
    fn wait(&self, timeout: Duration) -> (Vec<String>, Option<std::thread::Result<T>>) {
        let state = self.state.lock().unwrap();
        let mut state = if state.0.is_empty() && state.1.is_none() {
            self.wake.wait_timeout(state, timeout).unwrap().0
        } else {
            state
        };
        (std::mem::take(&mut state.0), state.1.take())
    }
}

/// The message of a panic's payload.
fn panic_message(payload: &(dyn std::any::Any + Send)) -> String {
    if let Some(s) = payload.downcast_ref::<&str>() {
        s.to_string()
    } else if let Some(s) = payload.downcast_ref::<String>() {
        s.clone()
    } else {
        "unknown panic".to_string()
    }
}

/// Work for a driver thread.
type Task = Box<dyn FnOnce() + Send>;

/// Idle driver threads, each waiting for a task on its channel.
static IDLE: Mutex<Vec<mpsc::Sender<Task>>> = Mutex::new(Vec::new());

/// Runs `task` on an idle driver thread, or on a new one if none is idle.
/// Drivers live on between calls and a render's parallel loops run on
/// rayon's global pool, so that a call starts no thread: threads started
/// for each call (a driver and a pool of its own) cost 1-3 ms on a busy
/// two-core machine, and the small renders of
/// `test_a_python_call_adds_under_5_ms` took 4 ms instead of 0.7 ms. Nor is
/// the driver one of the pool's workers: a worker waiting for its render's
/// loops would run another call's driver on top of its own, and two
/// renders in two Python threads would end one after the other.
fn drive(task: Task) -> PyResult<()> {
    let idle = IDLE.lock().unwrap().pop();
    let task = match idle {
        Some(driver) => match driver.send(task) {
            Ok(()) => return Ok(()),
            Err(mpsc::SendError(task)) => task,
        },
        None => task,
    };
    let (to_driver, tasks) = mpsc::channel::<Task>();
    std::thread::Builder::new()
        .name("raylab".into())
        .spawn(move || {
            let mut next = Some(task);
            while let Some(task) = next {
                task();
                IDLE.lock().unwrap().push(to_driver.clone());
                next = tasks.recv().ok();
            }
        })
        .map(|_| ())
        .map_err(|e| RenderError::new_err(format!("cannot start a thread: {e}")))
}

/// Runs `work` on a driver thread ([`drive`]), with hooks that collect its
/// lines and progress and carry a stop flag, while this thread waits without
/// the GIL, waking every 50 ms to print the lines on `sys.stderr`, call
/// `progress` with `(done, total)` when it moved, and check for signals. A
/// signal's exception (Ctrl-C's `KeyboardInterrupt`) stops the work, which is
/// waited for; it is returned beside the work's result. A panic in `work` is
/// a [`RenderError`].
fn run_blocking<T: Send + 'static>(
    py: Python<'_>,
    progress: Option<&Bound<'_, PyAny>>,
    work: impl FnOnce(&Hooks<'_>) -> T + Send + 'static,
) -> PyResult<(T, Option<PyErr>)> {
    let mailbox = Arc::new(Mailbox {
        state: Mutex::new((Vec::new(), None)),
        wake: Condvar::new(),
        done: AtomicU64::new(0),
        total: AtomicU64::new(0),
        stop: AtomicBool::new(false),
    });
    let stderr = py.import("sys")?.getattr("stderr")?;
    let worker = mailbox.clone();
    drive(Box::new(move || {
        let mailbox = &worker;
        let on_event = |e: Event<'_>| match e {
            Event::Line(l) => mailbox.say(l),
            Event::Started { total, done, .. } => {
                mailbox.total.store(total, Ordering::Relaxed);
                mailbox.done.store(done, Ordering::Relaxed);
            }
            Event::Progress(done) => {
                mailbox.done.fetch_max(done, Ordering::Relaxed);
            }
            Event::Samples(_) | Event::Finished | Event::Writing(_) => {}
        };
        let hooks = Hooks {
            on_event: &on_event,
            stop: Some(&mailbox.stop),
        };
        let result = catch_unwind(AssertUnwindSafe(|| work(&hooks)));
        mailbox.finish(result);
    }))?;
    let mut raised: Option<PyErr> = None;
    let mut shown = (u64::MAX, u64::MAX);
    let result = loop {
        let (lines, result) = py.detach(|| mailbox.wait(Duration::from_millis(50)));
        for line in lines {
            // A closed or broken stderr (an `Exception`) loses the line, not
            // the render; but a signal's exception raised while Python ran
            // the write (Ctrl-C's `KeyboardInterrupt`, which is no
            // `Exception`) stops it, as `check_signals` would have.
            if let Err(e) = stderr.call_method1("write", (format!("{line}\n"),))
                && !e.is_instance_of::<PyException>(py)
                && raised.is_none()
            {
                mailbox.stop.store(true, Ordering::Relaxed);
                raised = Some(e);
            }
        }
        if let Some(callback) = progress {
            let now = (
                mailbox.done.load(Ordering::Relaxed),
                mailbox.total.load(Ordering::Relaxed),
            );
            if now != shown && now.1 > 0 {
                shown = now;
                if let Err(e) = callback.call1((now.0.min(now.1), now.1))
                    && raised.is_none()
                {
                    mailbox.stop.store(true, Ordering::Relaxed);
                    raised = Some(e);
                }
            }
        }
        if raised.is_none()
            && let Err(e) = py.check_signals()
        {
            mailbox.stop.store(true, Ordering::Relaxed);
            raised = Some(e);
        }
        if let Some(result) = result {
            break result;
        }
    };
    let _ = stderr.call_method0("flush");
    match result {
        Ok(value) => Ok((value, raised)),
        Err(payload) => Err(RenderError::new_err(format!(
            "raylab panicked: {}",
            panic_message(payload.as_ref())
        ))),
    }
}

/// An error of the work, raised as `kind`, unless the wait was interrupted
/// (then that exception).
fn fail(error: anyhow::Error, raised: Option<PyErr>, load: bool) -> PyErr {
    if let Some(e) = raised {
        return e;
    }
    let message = format!("{error:#}");
    if load {
        LoadError::new_err(message)
    } else {
        RenderError::new_err(message)
    }
}

/// A loaded scene: render it as often as you like without loading it again.
///
/// `raylab.load(path, **options)` makes one; the options given there are
/// its renders' defaults. Options that change what is loaded (lights,
/// environment, materials, added meshes, the glTF camera) load it again
/// when a render changes them; the others (size, camera place, integrator,
/// samples, ...) do not.
#[pyclass(frozen, module = "raylab")]
struct Scene {
    session: Session,
    /// The keyword arguments it was loaded with.
    options: Py<PyDict>,
}

#[pymethods]
impl Scene {
    /// The scene's name or path, as given.
    #[getter]
    fn name(&self) -> &str {
        &self.session.loaded_with.scene
    }

    /// What it was made from: "lab" (the built-in box), "mesh" (OBJ), "gltf",
    /// "scene file" or "mitsuba" (a Mitsuba 3 XML scene).
    #[getter]
    fn kind(&self) -> &'static str {
        use raylab::load::SceneKind;
        match self.session.kind {
            SceneKind::Lab => "lab",
            SceneKind::Mesh => "mesh",
            SceneKind::Gltf => "gltf",
            SceneKind::Shot => "scene file",
            SceneKind::Mitsuba => "mitsuba",
        }
    }

    /// The camera it is seen from (its file's, or the options').
    #[getter]
    fn camera(&self) -> Camera {
        Camera {
            view: self.session.view,
        }
    }

    /// The image size (width, height) a render takes by default.
    #[getter]
    fn size(&self) -> (u32, u32) {
        self.session.size
    }

    /// The keyword arguments it was loaded with (its renders' defaults).
    #[getter]
    fn options<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        self.options.bind(py).copy()
    }

    /// The lower and upper corners of the scene's bounding box.
    #[getter]
    fn bounds(&self) -> ((f32, f32, f32), (f32, f32, f32)) {
        let (lo, hi) = self.session.scene.bounds();
        ((lo.x, lo.y, lo.z), (hi.x, hi.y, hi.z))
    }

    fn __repr__(&self) -> String {
        let (w, h) = self.session.size;
        format!(
            "<raylab.Scene {:?}: {}, {w}x{h}, {}>",
            self.session.loaded_with.scene,
            self.kind(),
            self.session.view.integrator
        )
    }
}

/// A camera as the lab's viewer moves it: a position, a yaw and a pitch in
/// the scene's frame. `scene.camera` is the scene's; `camera.moved(...)` a
/// moved copy; `raylab.render(scene, camera=cam)` renders from it (the same
/// as the command line's `--camera-pos X,Y,Z --yaw Y --pitch P`).
#[pyclass(frozen, module = "raylab")]
#[derive(Clone)]
struct Camera {
    view: ViewState,
}

#[pymethods]
impl Camera {
    /// The camera's position (x, y, z).
    #[getter]
    fn position(&self) -> (f32, f32, f32) {
        let p = self.view.camera_pos;
        (p.x, p.y, p.z)
    }

    /// Degrees turned right (positive) or left from the scene's camera.
    #[getter]
    fn yaw(&self) -> f32 {
        self.view.yaw_deg
    }

    /// Degrees looked up (positive) or down, within ±89.
    #[getter]
    fn pitch(&self) -> f32 {
        self.view.pitch_deg
    }

    /// How far one `forward` step goes (the viewer's key press: 0.1 in the
    /// box, scaled with a scene's size).
    #[getter]
    fn step(&self) -> f32 {
        self.view.step
    }

    /// The camera moved as the viewer moves it: turned `yaw` degrees right
    /// (negative: left) and `pitch` degrees up (as dragging the mouse does;
    /// pitch stays within ±89), then `forward` presses of the up arrow along
    /// the new view direction (negative: the down arrow, back).
    #[pyo3(signature = (*, forward = 0, yaw = 0.0, pitch = 0.0))]
    fn moved(&self, forward: i64, yaw: f32, pitch: f32) -> PyResult<Camera> {
        if !(yaw.is_finite() && pitch.is_finite()) {
            return Err(PyValueError::new_err("yaw and pitch must be finite"));
        }
        if forward.unsigned_abs() > 1_000_000 {
            return Err(PyValueError::new_err(
                "forward: at most 1000000 steps either way",
            ));
        }
        let mut view = self.view;
        view.turn(yaw, pitch);
        let initial = view;
        let action = if forward > 0 {
            Action::CameraForward
        } else {
            Action::CameraBack
        };
        for _ in 0..forward.unsigned_abs() {
            view.apply(action, &initial);
        }
        Ok(Camera { view })
    }

    fn __eq__(&self, other: &Bound<'_, PyAny>) -> bool {
        other
            .cast::<Camera>()
            .is_ok_and(|o| o.get().view == self.view)
    }

    fn __repr__(&self) -> String {
        let (x, y, z) = self.position();
        format!(
            "raylab.Camera(position=({x}, {y}, {z}), yaw={}, pitch={})",
            self.view.yaw_deg, self.view.pitch_deg
        )
    }
}

/// A `bytearray` of `len` bytes filled by `fill`: the one copy of an image
/// into memory that numpy then views (`numpy.frombuffer`).
fn bytearray<'py>(
    py: Python<'py>,
    len: usize,
    fill: impl FnOnce(&mut [u8]),
) -> PyResult<Bound<'py, PyAny>> {
    // SAFETY: a new bytearray of `len` bytes, not yet seen by any other code,
    // is filled before it is returned (no zeroing pass first).
    unsafe {
        let ptr = pyo3::ffi::PyByteArray_FromStringAndSize(std::ptr::null(), len as isize);
        let array = Bound::from_owned_ptr_or_err(py, ptr)?;
        let data = pyo3::ffi::PyByteArray_AsString(array.as_ptr()) as *mut u8;
        fill(std::slice::from_raw_parts_mut(data, len));
        Ok(array)
    }
}

/// A film's pixels as RGB float32s, row-major (a strided copy: pixels are
/// 16 bytes in raylab).
fn film_bytes<'py>(py: Python<'py>, film: &Film) -> PyResult<Bound<'py, PyAny>> {
    bytearray(py, film.pixels.len() * 12, |out| {
        for (o, p) in out.chunks_exact_mut(12).zip(&film.pixels) {
            o[0..4].copy_from_slice(&p.x.to_ne_bytes());
            o[4..8].copy_from_slice(&p.y.to_ne_bytes());
            o[8..12].copy_from_slice(&p.z.to_ne_bytes());
        }
    })
}

/// Float32 values as bytes, copied once.
fn floats_bytes<'py>(py: Python<'py>, values: &[f32]) -> PyResult<Bound<'py, PyAny>> {
    bytearray(py, std::mem::size_of_val(values), |out| {
        for (o, v) in out.chunks_exact_mut(4).zip(values) {
            o.copy_from_slice(&v.to_ne_bytes());
        }
    })
}

/// Native-endian float32 bytes as floats.
fn floats(data: &[u8]) -> PyResult<Vec<f32>> {
    if !data.len().is_multiple_of(4) {
        return Err(PyValueError::new_err("not float32 data"));
    }
    Ok(data
        .chunks_exact(4)
        .map(|b| f32::from_ne_bytes([b[0], b[1], b[2], b[3]]))
        .collect())
}

/// An RGB float32 image as a film.
fn film(data: &[u8], width: u32, height: u32) -> PyResult<Film> {
    let values = floats(data)?;
    if values.len() != width as usize * height as usize * 3 || width == 0 || height == 0 {
        return Err(PyValueError::new_err(format!(
            "{} values are no {width}x{height} RGB image",
            values.len()
        )));
    }
    Ok(Film {
        width,
        height,
        pixels: values
            .chunks_exact(3)
            .map(|c| Vec3A::new(c[0], c[1], c[2]))
            .collect(),
    })
}

/// What a render in memory gives Python: the image and its AOVs as bytes
/// (numpy views them), how to show it, and how it went.
fn rendered_to_python<'py>(
    py: Python<'py>,
    out: &Done,
    interrupted: bool,
) -> PyResult<Bound<'py, PyDict>> {
    let Done {
        rendered: Rendered { finished, report },
        factor,
        exposure,
        tonemap,
        seed,
        requested,
        integrator,
    } = out;
    let d = PyDict::new(py);
    let image = &finished.image;
    d.set_item("width", image.width)?;
    d.set_item("height", image.height)?;
    d.set_item("image", film_bytes(py, image)?)?;
    d.set_item(
        "noisy",
        match &finished.noisy {
            Some(n) => Some(film_bytes(py, n)?),
            None => None,
        },
    )?;
    let aovs = PyList::empty(py);
    if let Some(a) = &finished.aovs {
        for layer in &a.layers {
            aovs.append((
                layer.aov.name(),
                floats_bytes(py, &layer.values)?,
                layer.aov.channels().len(),
            ))?;
        }
    }
    d.set_item("aovs", aovs)?;
    d.set_item("display", (*factor, *exposure, tonemap.name()))?;
    let info = PyDict::new(py);
    info.set_item("spp", report.spp)?;
    info.set_item("spp_requested", *requested)?;
    info.set_item("seed", *seed)?;
    info.set_item("integrator", integrator)?;
    info.set_item(
        "ended",
        match report.ended {
            raylab::render::Ended::Complete => "complete",
            raylab::render::Ended::Budget => "time",
            raylab::render::Ended::Stopped => "stopped",
        },
    )?;
    info.set_item("seconds", report.elapsed.as_secs_f64())?;
    info.set_item("rays", report.rays)?;
    info.set_item("dropped", report.dropped)?;
    info.set_item(
        "denoise_seconds",
        report.denoise_time.map(|t| t.as_secs_f64()),
    )?;
    d.set_item("info", info)?;
    d.set_item("interrupted", interrupted)?;
    Ok(d)
}

/// A render in memory and how to show it.
struct Done {
    rendered: Rendered,
    /// The display factor of the scene's kind and integrator (exposure 0).
    factor: f32,
    exposure: f32,
    tonemap: ToneMap,
    seed: u64,
    /// The spp asked for (none for a time-limited render without --spp).
    requested: Option<u32>,
    integrator: String,
}

/// Why a job failed: loading (a `LoadError`) or the render.
enum Failure {
    Load(anyhow::Error),
    Render(anyhow::Error),
}

/// The session of `options`: `given` when it loads the same scene, else
/// one loaded now.
fn session_for(
    options: &JobOptions,
    given: Option<Session>,
    hooks: &Hooks<'_>,
) -> Result<Session, Failure> {
    let merged = options.with_scene_file().map_err(Failure::Load)?;
    match given {
        Some(s) if s.loads(&merged.scene) => Ok(s),
        _ => load_session(&merged.scene, options.quiet, 0, hooks).map_err(Failure::Load),
    }
}

/// Renders `options` on `session` (loading it if needed) in memory.
fn render_in_memory(
    options: JobOptions,
    session: Option<Session>,
    hooks: &Hooks<'_>,
) -> Result<Done, Failure> {
    let session = session_for(&options, session, hooks)?;
    let mut job = Job::with_session(session, options).map_err(Failure::Render)?;
    let rendered = job.render_with(hooks).map_err(Failure::Render)?;
    let args = job.options();
    let session = job.session().expect("the job's scene, once rendered");
    let display = raylab::job::display(session.kind, session.view.integrator, 0.0, session.tonemap);
    Ok(Done {
        rendered,
        factor: display.scale,
        exposure: args.scene.exposure.unwrap_or(0.0),
        tonemap: session.tonemap,
        seed: args.seed.unwrap_or(0),
        requested: match (args.time, args.spp) {
            (Some(_), None) => None,
            (_, spp) => Some(spp.unwrap_or(1)),
        },
        integrator: session.view.integrator.to_string(),
    })
}

/// Renders `options` to files, as `raylab render` writes them.
fn render_to_files(
    options: JobOptions,
    session: Option<Session>,
    hooks: &Hooks<'_>,
) -> Result<raylab::job::Report, Failure> {
    let session = session_for(&options, session, hooks)?;
    let mut job = Job::with_session(session, options).map_err(Failure::Render)?;
    job.run_with(hooks).map_err(Failure::Render)
}

/// The options of `scene` and `kwargs` (a scene's own options first, then
/// the call's), and the scene's session if it is a `Scene`.
fn options_of(
    function: &str,
    scene: &Bound<'_, PyAny>,
    kwargs: Option<&Bound<'_, PyDict>>,
) -> PyResult<(JobOptions, Option<Session>)> {
    let py = scene.py();
    let call = match kwargs {
        Some(k) => expand_camera(function, k)?,
        None => PyDict::new(py),
    };
    let (name, merged, session) = match scene.cast::<Scene>() {
        Ok(s) => {
            let s = s.get();
            let merged = s.options.bind(py).copy()?;
            merged.update(call.as_mapping())?;
            (
                s.session.loaded_with.scene.clone(),
                merged,
                Some(s.session.clone()),
            )
        }
        Err(_) => (scene_name(scene)?, call, None),
    };
    let options = parse(&arguments(function, &name, &merged)?)?;
    Ok((options, session))
}

/// `raylab.render`'s work: renders `scene` with the options of `kwargs`,
/// in memory (a dict of bytes for numpy) or, given `output`, to files (a
/// list of what was written).
#[pyfunction]
#[pyo3(signature = (scene, kwargs = None, progress = None))]
fn render<'py>(
    py: Python<'py>,
    scene: &Bound<'py, PyAny>,
    kwargs: Option<&Bound<'py, PyDict>>,
    progress: Option<&Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyAny>> {
    let (options, session) = options_of("render", scene, kwargs)?;
    if options.output.is_none() && options.checkpoint.is_some() {
        return Err(PyValueError::new_err(
            "checkpoint: a render in memory keeps no checkpoint; give output= too (the checkpoint is of the file's render)",
        ));
    }
    let progress = progress.filter(|p| !p.is_none());
    if options.output.is_some() {
        let (result, raised) = run_blocking(py, progress, move |hooks| {
            render_to_files(options, session, hooks)
        })?;
        let report = match result {
            Ok(r) => r,
            Err(Failure::Load(e)) => return Err(fail(e, raised, true)),
            Err(Failure::Render(e)) => {
                if e.downcast_ref::<raylab::job::NanFound>().is_some() && raised.is_none() {
                    return Err(RenderError::new_err(
                        "nan_check: NaN/Inf samples found (see the lines above)",
                    ));
                }
                return Err(fail(e, raised, false));
            }
        };
        let list = PyList::empty(py);
        for image in &report.images {
            let d = PyDict::new(py);
            d.set_item("output", &image.output)?;
            d.set_item("spp", image.spp)?;
            d.set_item("resumed_spp", image.resumed_spp)?;
            d.set_item(
                "ended",
                match image.ended {
                    raylab::render::Ended::Complete => "complete",
                    raylab::render::Ended::Budget => "time",
                    raylab::render::Ended::Stopped => "stopped",
                },
            )?;
            d.set_item("seconds", image.elapsed.as_secs_f64())?;
            d.set_item("rays", image.rays)?;
            list.append(d)?;
        }
        let out = PyDict::new(py);
        out.set_item("files", list)?;
        out.set_item("interrupted", raised.is_some())?;
        if let Some(e) = raised
            && !e.is_instance_of::<PyKeyboardInterrupt>(py)
        {
            return Err(e);
        }
        return Ok(out.into_any());
    }
    let (result, raised) = run_blocking(py, progress, move |hooks| {
        render_in_memory(options, session, hooks)
    })?;
    let done = match result {
        Ok(d) => d,
        Err(Failure::Load(e)) => return Err(fail(e, raised, true)),
        Err(Failure::Render(e)) => return Err(fail(e, raised, false)),
    };
    let interrupted = match raised {
        None => false,
        Some(e) if e.is_instance_of::<PyKeyboardInterrupt>(py) => true,
        Some(e) => return Err(e),
    };
    Ok(rendered_to_python(py, &done, interrupted)?.into_any())
}

/// `raylab.load`'s work: loads `scene` with the options of `kwargs` (which
/// become its renders' defaults).
#[pyfunction]
#[pyo3(signature = (scene, kwargs = None))]
fn load(
    py: Python<'_>,
    scene: &Bound<'_, PyAny>,
    kwargs: Option<&Bound<'_, PyDict>>,
) -> PyResult<Scene> {
    if scene.cast::<Scene>().is_ok() {
        return Err(PyTypeError::new_err(
            "load() takes a name or a path; this is a loaded raylab.Scene already",
        ));
    }
    let (options, _) = options_of("load", scene, kwargs)?;
    let stored = match kwargs {
        Some(k) => expand_camera("load", k)?,
        None => PyDict::new(py),
    };
    let (result, raised) = run_blocking(py, None, move |hooks| session_for(&options, None, hooks))?;
    if let Some(e) = raised {
        return Err(e);
    }
    match result {
        Ok(session) => Ok(Scene {
            session,
            options: stored.unbind(),
        }),
        Err(Failure::Load(e)) | Err(Failure::Render(e)) => {
            Err(LoadError::new_err(format!("{e:#}")))
        }
    }
}

/// Every keyword argument of `raylab.render` from the command line's
/// definition: (name, value name, default, help) in the command line's
/// order.
#[pyfunction]
fn options() -> Vec<(String, Option<String>, Option<String>, String)> {
    spec()
        .iter()
        .map(|o| {
            (
                o.name.clone(),
                o.value_name.clone(),
                o.default.clone(),
                o.help.clone(),
            )
        })
        .collect()
}

/// The display of `factor`, `exposure` stops and tone mapping `tonemap`,
/// as `raylab::job::display` computes it.
fn display_of(factor: f32, exposure: f32, tonemap: &str) -> PyResult<Display> {
    Ok(Display {
        scale: factor * exposure.exp2(),
        tonemap: tonemap.parse().map_err(PyValueError::new_err)?,
    })
}

/// An RGB float32 image (bytes) as the PNG the command line writes of it.
#[pyfunction]
fn png<'py>(
    py: Python<'py>,
    data: &[u8],
    width: u32,
    height: u32,
    factor: f32,
    exposure: f32,
    tonemap: &str,
) -> PyResult<Bound<'py, PyBytes>> {
    use image::ImageEncoder;
    let film = film(data, width, height)?;
    let display = display_of(factor, exposure, tonemap)?;
    let mut out = Vec::new();
    image::codecs::png::PngEncoder::new(&mut out)
        .write_image(
            &film.to_srgb8(display),
            width,
            height,
            image::ExtendedColorType::Rgb8,
        )
        .map_err(|e| RenderError::new_err(e.to_string()))?;
    Ok(PyBytes::new(py, &out))
}

/// An RGB float32 image (bytes) as the 8-bit sRGB RGB bytes of the command
/// line's PNG (for `Image.to_srgb8`, e.g. for matplotlib).
#[pyfunction]
fn srgb8<'py>(
    py: Python<'py>,
    data: &[u8],
    width: u32,
    height: u32,
    factor: f32,
    exposure: f32,
    tonemap: &str,
) -> PyResult<Bound<'py, PyBytes>> {
    let film = film(data, width, height)?;
    let display = display_of(factor, exposure, tonemap)?;
    Ok(PyBytes::new(py, &film.to_srgb8(display)))
}

/// Writes an RGB float32 image (bytes) to `path` as the command line does:
/// PNG through the display, EXR as it is with `layers` ((name, bytes,
/// channels) each, e.g. ("albedo", ..., 3)) and `noisy` as layers and the
/// command line's metadata when given ((spp, spp asked for, seed,
/// integrator, interrupted, denoised)).
#[pyfunction]
#[pyo3(signature = (path, data, width, height, factor, exposure, tonemap, layers, noisy = None, metadata = None))]
#[allow(clippy::too_many_arguments)]
fn save(
    path: PathBuf,
    data: &[u8],
    width: u32,
    height: u32,
    factor: f32,
    exposure: f32,
    tonemap: &str,
    layers: Vec<(String, Vec<u8>, usize)>,
    noisy: Option<Vec<u8>>,
    metadata: Option<(u32, Option<u32>, u64, String, bool, bool)>,
) -> PyResult<()> {
    let image = film(data, width, height)?;
    let display = display_of(factor, exposure, tonemap)?;
    let mut channels = Vec::new();
    if let Some(n) = noisy {
        let n = film(&n, width, height)?;
        for (c, name) in ["R", "G", "B"].into_iter().enumerate() {
            channels.push(Channel {
                name: format!("noisy.{name}"),
                values: n.pixels.iter().map(|p| p[c]).collect(),
            });
        }
    }
    for (name, data, k) in layers {
        let aov: raylab::aov::Aov = name
            .parse::<raylab::aov::AovSet>()
            .ok()
            .and_then(|s| s.iter().next())
            .ok_or_else(|| PyValueError::new_err(format!("unknown AOV '{name}'")))?;
        let values = floats(&data)?;
        if k != aov.channels().len() || values.len() != image.pixels.len() * k {
            return Err(PyValueError::new_err(format!(
                "the {name} AOV must be {height}x{width}x{}",
                aov.channels().len()
            )));
        }
        for (c, channel) in aov.channel_names().enumerate() {
            channels.push(Channel {
                name: channel,
                values: values.iter().skip(c).step_by(k).copied().collect(),
            });
        }
    }
    let metadata: Vec<(String, MetaValue)> = match metadata {
        Some((spp, requested, seed, integrator, interrupted, denoised)) => {
            raylab::farm::image_metadata(spp, requested, seed, &integrator, interrupted, denoised)
                .to_vec()
        }
        None => Vec::new(),
    };
    raylab::film::write_image_meta(&image, channels, &path, display, &metadata)
        .map_err(|e| RenderError::new_err(e.to_string()))
}

/// An EXR file's channels: (name, float32 bytes) each.
type ExrPlanes<'py> = Vec<(String, Bound<'py, PyAny>)>;

/// Every channel of an OpenEXR file: (width, height, [(name, bytes)]).
#[pyfunction]
fn read_exr<'py>(py: Python<'py>, path: PathBuf) -> PyResult<(u32, u32, ExrPlanes<'py>)> {
    let exr = py
        .detach(|| raylab::film::read_exr_channels(Path::new(&path)))
        .map_err(|e| LoadError::new_err(e.to_string()))?;
    let channels = exr
        .channels
        .iter()
        .map(|c| Ok((c.name.clone(), floats_bytes(py, &c.values)?)))
        .collect::<PyResult<_>>()?;
    Ok((exr.width, exr.height, channels))
}

/// Seconds each of `n` renders of `scene` with `kwargs` take through the
/// library alone (`Job::new(options).render_with`, on this thread without
/// the GIL): what a Python call adds is measured against these.
#[pyfunction]
#[pyo3(signature = (scene, kwargs, n))]
fn _library_seconds(
    py: Python<'_>,
    scene: &Bound<'_, PyAny>,
    kwargs: &Bound<'_, PyDict>,
    n: usize,
) -> PyResult<Vec<f64>> {
    let (options, _) = options_of("render", scene, Some(kwargs))?;
    py.detach(|| {
        (0..n)
            .map(|_| {
                let start = Instant::now();
                let mut job = Job::new(options.clone())?;
                job.render_with(&Hooks::default())?;
                Ok(start.elapsed().as_secs_f64())
            })
            .collect::<anyhow::Result<Vec<f64>>>()
    })
    .map_err(|e| RenderError::new_err(format!("{e:#}")))
}

/// Panics inside a job's thread, as a bug in raylab would: for the test
/// that such a panic is a `RenderError`, not an abort.
#[pyfunction]
fn _panic_in_job(py: Python<'_>, message: String) -> PyResult<()> {
    run_blocking::<()>(py, None, move |_| panic!("{message}"))?;
    Ok(())
}

/// The native half of the `raylab` package.
#[pymodule]
fn _raylab(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add("LoadError", py.get_type::<LoadError>())?;
    m.add("RenderError", py.get_type::<RenderError>())?;
    m.add_class::<Scene>()?;
    m.add_class::<Camera>()?;
    m.add_function(wrap_pyfunction!(render, m)?)?;
    m.add_function(wrap_pyfunction!(load, m)?)?;
    m.add_function(wrap_pyfunction!(options, m)?)?;
    m.add_function(wrap_pyfunction!(png, m)?)?;
    m.add_function(wrap_pyfunction!(srgb8, m)?)?;
    m.add_function(wrap_pyfunction!(save, m)?)?;
    m.add_function(wrap_pyfunction!(read_exr, m)?)?;
    m.add_function(wrap_pyfunction!(_library_seconds, m)?)?;
    m.add_function(wrap_pyfunction!(_panic_in_job, m)?)?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
