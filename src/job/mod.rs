//! The render job: what `raylab render` does, as a library call.
//!
//! A [`Job`] takes [`JobOptions`] (every option of the command line, with
//! its defaults) and owns every rule the command line follows: a scene
//! file's `[render]` settings fill in what the options leave out; the
//! integrator, image size and tone mapping follow the kind of scene; one
//! side of the image keeps the aspect ratio; PNG values are scaled for
//! display by scene kind and exposure ([`display`]); a render resumes from
//! its checkpoint and saves one when stopped; parts (`tile`, `samples`) are
//! written for `raylab merge`; frames are rendered one by one; the image is
//! denoised when asked; and the files are written atomically, exactly as
//! `raylab render` writes them. `raylab render`, `raylab view`, `raylab
//! merge` ([`merge`]), the fuzz targets and the tests all go through here.
//!
//! ```no_run
//! use raylab::job::{Job, JobOptions};
//!
//! let mut options = JobOptions::new("assets/models/DamagedHelmet/DamagedHelmet.gltf");
//! options.output = Some("helmet.png".into());
//! Job::new(options)?.run()?;
//! # Ok::<(), anyhow::Error>(())
//! ```
//!
//! What the command line prints (load summaries, warnings, the summary line
//! of each image) comes out as [`Event::Line`]s, and progress as
//! [`Event::Started`]/[`Event::Progress`], through the [`Hooks`] given to
//! [`Job::run_with`], which also carry the flag that stops a render between
//! passes (`raylab render` sets it on Ctrl-C).

pub mod animate;
mod hooks;
mod image;
mod merge;
pub mod options;
mod report;
mod session;
mod write;

use std::path::{Path, PathBuf};

use anyhow::Context;

use crate::aov::AovSet;
use crate::denoise::{DenoiseOptions, Denoiser};
use crate::farm;
use crate::film::Format;
use crate::render::Ended;

pub use hooks::{Event, Hooks, ProgressUnit};
pub use merge::{MergeOptions, MergeReport, merge};
pub use options::{JobOptions, SceneOptions};
pub use report::{ImageReport, NanFound, Rendered, Report};
pub use session::{Session, display, load_session};
pub use write::{Finished, denoised_clause, finish, write_result};

/// A render job: options checked and merged with the scene file, ready to
/// run.
pub struct Job {
    options: JobOptions,
    denoiser: Option<Denoiser>,
    session: Option<Session>,
}

impl Job {
    /// A job of `options`: checks them as the command line does, merges the
    /// scene file's `[render]` settings into what they leave out, and loads
    /// Open Image Denoise when the image is to be denoised (an error that
    /// says how to install it, before any time is spent). The scene is loaded
    /// by [`Job::run`].
    pub fn new(options: JobOptions) -> anyhow::Result<Job> {
        let clean = |e: String| anyhow::anyhow!(e.trim_start_matches("error: ").to_string());
        options.scene.validate().map_err(clean)?;
        options.validate().map_err(clean)?;
        let options = options.with_scene_file()?;
        // A part is denoised only once merged: its render needs no library.
        let denoiser = if options.denoise() && !options.is_part() {
            let denoise = DenoiseOptions {
                threads: options.threads.unwrap_or(0),
                ..DenoiseOptions::default()
            };
            Some(Denoiser::new(&denoise).context("--denoise")?)
        } else {
            None
        };
        Ok(Job {
            options,
            denoiser,
            session: None,
        })
    }

    /// A job of `options` on a scene already loaded (by [`load_session`]):
    /// when `options` load the same scene ([`Session::loads`]: the same
    /// scene, `add`, `env`, lights, materials, ...) it is rendered as
    /// `options` show it (size, camera, integrator, tone mapping) without
    /// loading it again; otherwise the scene of `options` is loaded. A
    /// session's clone is cheap: one load serves many jobs.
    pub fn with_session(session: Session, options: JobOptions) -> anyhow::Result<Job> {
        let mut job = Job::new(options)?;
        job.session = Some(session);
        Ok(job)
    }

    /// The options, merged with the scene file's settings.
    pub fn options(&self) -> &JobOptions {
        &self.options
    }

    /// The file the image goes to: `output`, else `SCENE.png` in the current
    /// folder (`SCENE.exr` with AOVs, which only EXR holds); with frames, the
    /// pattern.
    pub fn output(&self) -> PathBuf {
        self.options.output.clone().unwrap_or_else(|| {
            let stem = Path::new(&self.options.scene.scene)
                .file_stem()
                .map_or_else(|| "image".into(), |s| s.to_string_lossy().into_owned());
            let ext = if self.options.aov.is_some() {
                "exr"
            } else {
                "png"
            };
            PathBuf::from(format!("{stem}.{ext}"))
        })
    }

    /// Runs the job with no one listening and no way to stop it.
    pub fn run(&mut self) -> anyhow::Result<Report> {
        self.run_with(&Hooks::default())
    }

    /// Loads the scene (unless given), renders every image of the job
    /// (one, or a part, or each frame) and writes it, telling `hooks`.
    pub fn run_with(&mut self, hooks: &Hooks<'_>) -> anyhow::Result<Report> {
        let args = &self.options;
        let output = self.output();
        let (aovs, layers) = args.aov_sets();
        // Refuse an unsupported format or a missing folder before spending
        // time on the render (of the first frame's file: the pattern is
        // checked by `JobOptions::validate`).
        let first_output = match args.frames {
            Some((first, _)) => {
                farm::frame_path(&output, first).context("-o has no frame number field")?
            }
            None => output.clone(),
        };
        Format::from_path(&first_output)?;
        if let Some(dir) = first_output.parent().filter(|d| !d.as_os_str().is_empty())
            && !dir.is_dir()
        {
            anyhow::bail!(
                "cannot write {}: the folder {} does not exist",
                first_output.display(),
                dir.display()
            );
        }
        let session = self.take_session(aovs, hooks)?;
        let result = self.render_all(&session, &output, aovs, layers, hooks);
        self.session = Some(session);
        result
    }

    /// Renders the image in memory, as [`Job::run_with`] would write it (the
    /// same values, bit for bit, as the EXR it writes), without reading or
    /// writing any file but the scene's (no checkpoint either; `nan_check`'s
    /// finding is said, and the image kept). Not for frames or parts, which
    /// are files by nature.
    pub fn render_with(&mut self, hooks: &Hooks<'_>) -> anyhow::Result<Rendered> {
        let args = &self.options;
        if args.frames.is_some() || args.is_part() {
            anyhow::bail!(
                "frames and parts (--frames, --tile, --samples) are rendered to files: run the job instead"
            );
        }
        let (aovs, layers) = args.aov_sets();
        let output = self.output();
        let session = self.take_session(aovs, hooks)?;
        let result = self.render_kept(&session, &output, aovs, layers, hooks);
        self.session = Some(session);
        result
    }

    fn render_kept(
        &mut self,
        session: &Session,
        output: &Path,
        aovs: AovSet,
        layers: AovSet,
        hooks: &Hooks<'_>,
    ) -> anyhow::Result<Rendered> {
        let args = &self.options;
        let camera = session.view.camera(session.size.0, session.size.1);
        if let Some(why) = bdpt_refusal(args, session, &camera) {
            anyhow::bail!("{why}");
        }
        if !args.quiet {
            for warning in settings_warnings(args, session) {
                hooks.say(&warning);
            }
        }
        let mut images = image::Images {
            args,
            session,
            settings: image::settings(args, session.view.integrator),
            aovs,
            layers,
            denoiser: self.denoiser.as_mut(),
            hooks,
            kept: Some(None),
        };
        let report = images.render_image(&camera, output, None)?;
        let Some(Some(finished)) = images.kept else {
            anyhow::bail!("stopped before the first sample: no image");
        };
        Ok(Rendered { finished, report })
    }

    /// The loaded scene (loaded now if not given), for a film with `aovs`.
    fn take_session(&mut self, aovs: AovSet, hooks: &Hooks<'_>) -> anyhow::Result<Session> {
        let aov_channels = aovs.iter().map(|a| a.channels().len()).sum();
        match self.session.take() {
            Some(s) if s.loads(&self.options.scene) => s.shown(&self.options.scene, aov_channels),
            _ => load_session(&self.options.scene, self.options.quiet, aov_channels, hooks),
        }
    }

    /// The scene, once loaded (by [`Job::run_with`] or given).
    pub fn session(&self) -> Option<&Session> {
        self.session.as_ref()
    }

    fn render_all(
        &mut self,
        session: &Session,
        output: &Path,
        aovs: AovSet,
        layers: AovSet,
        hooks: &Hooks<'_>,
    ) -> anyhow::Result<Report> {
        let args = &self.options;
        let scene = &session.scene;
        let view = &session.view;
        let camera = view.camera(session.size.0, session.size.1);
        let integrator = view.integrator;
        if let Some(why) = bdpt_refusal(args, session, &camera) {
            anyhow::bail!("{why}");
        }
        if !args.quiet {
            for warning in settings_warnings(args, session) {
                hooks.say(&warning);
            }
        }
        let mut images = image::Images {
            args,
            session,
            settings: image::settings(args, integrator),
            aovs,
            layers,
            denoiser: self.denoiser.as_mut(),
            hooks,
            kept: None,
        };
        let mut report = Report::default();
        let Some((first, end)) = args.frames else {
            report
                .images
                .push(images.render_image(&camera, output, None)?);
            return Ok(report);
        };
        // An animation: each frame a render of its own, of the scene loaded
        // once, or (a file with animations) loaded posed at the frame's time.
        let (low, high) = scene.bounds();
        let centre = 0.5 * (low + high);
        let aov_channels = aovs.iter().map(|a| a.channels().len()).sum();
        let fps = args.fps.unwrap_or(animate::DEFAULT_FPS);
        for frame in first..end {
            let path = farm::frame_path(output, frame).context("-o has no frame number field")?;
            let degrees = args
                .orbit
                .map_or(0.0, |d| (f64::from(d) * f64::from(frame)) % 360.0);
            let posed = if session.animations.is_empty() {
                None
            } else {
                let time = animate::frame_time(frame, fps);
                let posed = session::posed_session(&args.scene, session, time, aov_channels, hooks);
                Some(posed?)
            };
            let shown = posed.as_ref().unwrap_or(session);
            let camera = shown
                .view
                .camera(shown.size.0, shown.size.1)
                .orbited(centre, degrees as f32);
            let image = image::Images {
                session: shown,
                denoiser: images.denoiser.as_deref_mut(),
                kept: None,
                ..images
            }
            .render_image(&camera, &path, Some(frame))?;
            let ended = image.ended;
            report.images.push(image);
            if ended == Ended::Stopped {
                if !args.quiet && frame + 1 < end {
                    hooks.say(&format!(
                        "stopped at frame {frame}: frames {}..{end} not rendered",
                        frame + 1
                    ));
                }
                break;
            }
        }
        Ok(report)
    }
}

/// Warnings about options the scene makes useless.
fn settings_warnings(args: &JobOptions, session: &Session) -> Vec<String> {
    let (scene, integrator) = (&session.scene, session.view.integrator);
    let mut said = Vec::new();
    if integrator.is_physical() && !scene.has_lights() {
        said.push(
            "warning: the scene has no light (point light power 0, nothing emits): the path-traced image is black".to_string(),
        );
    }
    let path_only = args.scene.max_depth.is_some()
        || !args.scene.material.is_empty()
        || args.scene.fog.is_some();
    if !integrator.is_physical() && path_only {
        said.push(format!(
            "warning: --max-depth, --material and --fog only change `path` images; {integrator} ignores them"
        ));
    }
    if integrator == crate::integrators::Integrator::Direct && scene.point_power() == 0.0 {
        said.push(
            "warning: the point light is off: `direct` shows only the ambient term (emitting triangles light the scene under --integrator path)".to_string(),
        );
    }
    said
}

impl JobOptions {
    /// Whether the image is denoised (`denoise`, or the scene file's).
    pub fn denoise(&self) -> bool {
        self.scene.denoise.unwrap_or(false)
    }

    /// The AOVs a render gathers (those asked for, the denoiser's guides
    /// and the half of the samples its guard and adaptive sampling measure
    /// the noise by, and the sample counts of adaptive sampling) and those
    /// written as layers (those asked for).
    pub fn aov_sets(&self) -> (AovSet, AovSet) {
        let layers = self.aov.unwrap_or_default();
        let mut gathered = layers;
        if self.denoise() {
            gathered = gathered.with(crate::denoise::GUIDES);
        }
        if self.noise_threshold.is_some() {
            gathered = gathered.with(crate::render::adaptive::AOVS);
        }
        (gathered, layers)
    }
}

/// Why `bdpt` cannot render this job (what it does not support yet:
/// [`crate::integrators::bdpt`]), as the one line to print; `None` when it
/// can, or when the integrator is another.
pub fn bdpt_refusal(
    args: &JobOptions,
    session: &Session,
    camera: &crate::camera::Camera,
) -> Option<String> {
    let integrator = session.view.integrator;
    let (crate::integrators::Integrator::Bdpt(options)
    | crate::integrators::Integrator::Vcm(options)) = integrator
    else {
        return None;
    };
    let scene = &session.scene;
    let why = if scene.has_media() {
        "participating media".to_string()
    } else if let Some(light) = scene.emission_unsupported() {
        light
    } else if camera.is_orthographic() {
        "an orthographic camera".to_string()
    } else if options.filter != crate::sampling::filter::PixelFilter::Box {
        let name = match options.filter {
            crate::sampling::filter::PixelFilter::Tent { .. } => "tent",
            _ => "Gaussian",
        };
        format!("the {name} pixel filter (add --filter box)")
    } else if args.noise_threshold.is_some() {
        "adaptive sampling (--noise-threshold)".to_string()
    } else if args.tile.is_some() {
        "--tile parts (light paths land on every row: split by --samples)".to_string()
    } else if options.hide_emitters != crate::integrators::path::HideEmitters::No {
        "hidden emitters (Mitsuba's hide_emitters)".to_string()
    } else if options.counts_direct() {
        "counted direct samples (Mitsuba's direct integrator)".to_string()
    } else {
        return None;
    };
    Some(format!(
        "{integrator} does not render {why} yet: use --integrator path"
    ))
}
