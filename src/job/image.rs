//! One image of a job (the whole render, a part of it, or a frame): resumed
//! from and saved to its checkpoint, rendered in passes, written.

use std::io::Read;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::{Duration, Instant};

use anyhow::Context;

use super::hooks::{Event, Hooks, ProgressUnit};
use super::options::{JobOptions, MAX_SPP};
use super::report::{ImageReport, NanFound};
use super::session::Session;
use super::write::{denoised_clause, write_result};
use crate::aov::AovSet;
use crate::checkpoint::{self, Key};
use crate::denoise::Denoiser;
use crate::farm;
use crate::fingerprint::Fingerprint;
use crate::nan_check::first_bad_sample;
use crate::render::{Accumulator, Adaptive, Ended, Passes, RenderSettings, Split, render_passes};

/// The render settings of `args`: without `time`, exactly `spp` samples (1
/// if not given); with it, at most `spp`.
pub(super) fn settings(
    args: &JobOptions,
    integrator: crate::integrators::Integrator,
) -> RenderSettings {
    RenderSettings {
        integrator,
        spp: match args.time {
            Some(_) => args.spp.unwrap_or(MAX_SPP),
            None => args.spp.unwrap_or(1),
        },
        seed: args.seed.unwrap_or(0),
    }
}

/// What every image of a job shares.
pub(super) struct Images<'a> {
    pub args: &'a JobOptions,
    pub session: &'a Session,
    pub settings: RenderSettings,
    /// The AOVs gathered (those asked for and the denoiser's).
    pub aovs: AovSet,
    /// The AOVs written as layers (those asked for).
    pub layers: AovSet,
    pub denoiser: Option<&'a mut Denoiser>,
    pub hooks: &'a Hooks<'a>,
    /// `Some` to render in memory (no checkpoint, no file): the result goes
    /// here.
    pub kept: Option<Option<super::write::Finished>>,
}

impl Images<'_> {
    /// Renders one image (the whole render, a part of it, or a frame) of
    /// `session` seen by `camera` to `output`, resuming from and saving to its
    /// checkpoint, and says what it did.
    pub fn render_image(
        &mut self,
        camera: &crate::camera::Camera,
        output: &Path,
        frame: Option<u32>,
    ) -> anyhow::Result<ImageReport> {
        let (args, session, settings, hooks) =
            (self.args, self.session, &self.settings, self.hooks);
        let output = output.to_path_buf();
        let scene = &session.scene;
        let camera = *camera;
        let integrator = settings.integrator;
        let seed = settings.seed;
        let budget = args.time.map(Duration::from_secs_f64);
        let aovs = self.aovs;
        // A part (--tile, --samples): its rows and samples, and the samples it
        // takes; else the whole image and all of --spp.
        let split = match args.tile {
            Some((k, n)) => {
                Split::new(k, n, camera.height).map_err(|e| anyhow::anyhow!("--{e}"))?
            }
            None => Split::WHOLE,
        };
        let first_sample = args.samples.map_or(0, |(a, _)| a);
        let whole = *settings;
        let settings = &RenderSettings {
            spp: args.samples.map_or(settings.spp, |(a, b)| b - a),
            ..*settings
        };

        // The checkpoint: the one named, else the one a stopped render leaves
        // beside its output.
        // In memory: no checkpoint read or written.
        let in_memory = self.kept.is_some();
        let explicit = args.checkpoint.is_some() && !in_memory;
        let ckpt_path = args
            .checkpoint
            .clone()
            .unwrap_or_else(|| default_checkpoint(&output));
        let key_cell = OnceLock::new();
        let render_key =
            || *key_cell.get_or_init(|| render_key(args, &session.scene, &camera, &whole, aovs));
        // A part's checkpoint is of its rows and samples only.
        let key = || {
            let mut k = render_key();
            if args.is_part() {
                let mut h = Fingerprint::new();
                h.update(&k.settings.to_le_bytes());
                use std::fmt::Write;
                let _ = write!(h, "|part {split} from {first_sample}");
                k.settings = h.value();
            }
            k
        };
        let mut acc = Accumulator::part(camera.width, camera.height, aovs, split, first_sample);
        let mut spent = Duration::ZERO;
        // The spp of the checkpoint on disk that is this render's (resumed from or
        // saved by this run), if any.
        let mut on_disk: Option<u32> = None;
        if !in_memory && ckpt_path.exists() {
            match resume(&ckpt_path, key(), settings, budget.is_none()) {
                Ok((a, s)) => {
                    let a = a.into_part(split, first_sample);
                    if !args.quiet {
                        let of = match budget {
                            None => format!(" of {}", settings.spp),
                            Some(_) => String::new(),
                        };
                        hooks.say(&format!(
                            "resuming from {}: {}{of} spp",
                            ckpt_path.display(),
                            a.spp()
                        ));
                    }
                    on_disk = Some(a.spp());
                    (acc, spent) = (a, s);
                }
                Err(why) if explicit => anyhow::bail!(
                    "{} {why}: remove it to start over, or name another --checkpoint file",
                    ckpt_path.display()
                ),
                Err(why) => {
                    if !args.quiet {
                        hooks.say(&format!(
                            "warning: not resuming from {}: {why}; rendering from the start",
                            ckpt_path.display()
                        ));
                    }
                }
            }
        }
        let resumed_spp = acc.spp();
        let tally_before = acc.tally();

        let start = Instant::now();
        let (unit, total, done) = match budget {
            // Time-limited: progress is the time spent.
            Some(b) => (
                ProgressUnit::Milliseconds,
                b.as_millis() as u64,
                spent.as_millis() as u64,
            ),
            None => {
                let rows = (0..camera.height)
                    .filter(|y| split.has_tile(y / crate::render::TILE_ROWS as u32))
                    .count() as u64;
                (
                    ProgressUnit::RowSamples,
                    rows * settings.spp as u64,
                    rows * acc.spp() as u64,
                )
            }
        };
        (hooks.on_event)(Event::Started {
            output: &output,
            total,
            done,
            unit,
        });
        let counted = AtomicU64::new(done);
        let progress = |row_samples: u64| {
            let done = match budget {
                Some(_) => (spent + start.elapsed()).as_millis() as u64,
                None => counted.fetch_add(row_samples, Ordering::Relaxed) + row_samples,
            };
            (hooks.on_event)(Event::Progress(done));
        };

        (hooks.on_event)(Event::Writing(&[
            crate::film::temp_path(&output),
            crate::film::temp_path(&ckpt_path),
        ]));

        let every = Duration::from_secs_f64(args.checkpoint_every);
        let mut last_save = Instant::now();
        let mut save_cost = Duration::ZERO;
        let mut save_error: Option<String> = None;
        let passes = Passes {
            budget,
            spent,
            stop: hooks.stop,
            adaptive: args.noise_threshold.map(Adaptive::new),
        };
        let mut after_pass = |acc: &Accumulator, spent: Duration| {
            if args.noise_threshold.is_some() {
                (hooks.on_event)(Event::Samples(acc.mean_spp()));
            }
            // Periodic saves only when asked for (--checkpoint), never after the
            // last pass (the image is about to be written), and at most every
            // twentieth of the time on saving.
            let done = acc.spp() >= settings.spp
                || budget.is_some_and(|b| spent >= b)
                || hooks.stop.is_some_and(|s| s.load(Ordering::Relaxed));
            if !explicit || done || last_save.elapsed() < every.max(save_cost * 20) {
                return;
            }
            let t = Instant::now();
            match checkpoint::write(&ckpt_path, &key(), acc, spent) {
                Ok(()) => {
                    on_disk = Some(acc.spp());
                    save_error = None;
                }
                Err(e) => {
                    if save_error.is_none() && !args.quiet {
                        let text = format!("{:#}", anyhow::Error::from(e));
                        hooks.say(&format!("warning: {}", crate::guard::one_line(&text)));
                    }
                    save_error = Some(String::new());
                }
            }
            save_cost = t.elapsed();
            last_save = Instant::now();
        };
        let mut work = || {
            render_passes(
                scene,
                &camera,
                settings,
                &mut acc,
                &passes,
                &mut after_pass,
                &progress,
            )
        };
        let ended = match args.threads {
            Some(n) => rayon::ThreadPoolBuilder::new()
                .num_threads(n)
                .build()
                .context("cannot start worker threads")?
                .install(work),
            None => work(),
        };
        let elapsed = start.elapsed();
        let spent = spent + elapsed;
        (hooks.on_event)(Event::Finished);
        let stopped = ended == Ended::Stopped;

        // What this run did, once the image is (or is not) denoised.
        let report = |denoise_time| ImageReport {
            output: output.clone(),
            spp: acc.spp(),
            resumed_spp,
            ended,
            rays: acc.tally().rays - tally_before.rays,
            dropped: acc.tally().dropped,
            elapsed,
            denoise_time,
        };
        if acc.spp() == 0 {
            // Stopped before the first sample: nothing to write or to keep.
            if !args.quiet {
                hooks.say(&format!(
                    "interrupted before the first sample: {} not written",
                    output.display()
                ));
            }
            return Ok(report(None));
        }
        // A stopped render keeps its samples (unless the checkpoint on disk
        // already holds them all).
        let mut saved_now = false;
        if stopped && !in_memory && on_disk != Some(acc.spp()) {
            match checkpoint::write(&ckpt_path, &key(), &acc, spent) {
                Ok(()) => {
                    on_disk = Some(acc.spp());
                    saved_now = true;
                }
                Err(e) => hooks.say(&format!(
                    "warning: {:#}; the samples cannot be resumed",
                    anyhow::Error::from(e)
                )),
            }
        }

        let display = super::session::display(
            session.kind,
            integrator,
            args.scene.exposure.unwrap_or(0.0),
            session.tonemap,
        );
        if let Some(kept) = self.kept.as_mut() {
            let finished = super::write::finish(&acc, self.layers, self.denoiser.as_deref_mut())?;
            let report = report(finished.denoise_time);
            *kept = Some(finished);
            // In memory the finding is said, and the image kept all the same.
            if args.nan_check {
                nan_check(args, scene, &camera, integrator, &acc, hooks)?;
            }
            return Ok(report);
        }
        let existed = output.exists();
        let written = if args.is_part() {
            let part = farm::Part {
                render: farm::Render {
                    key: render_key(),
                    spp: whole.spp,
                    seed,
                    integrator: integrator.to_string(),
                    display,
                    frame,
                    layers: self.layers,
                    denoise: self.args.scene.denoise.unwrap_or(false),
                },
                acc: acc.clone(),
            };
            farm::write_part(&output, &part)
                .map(|()| None)
                .map_err(anyhow::Error::from)
        } else {
            let unbounded = budget.is_some() && args.spp.is_none();
            let requested = (!unbounded).then_some(settings.spp);
            let metadata = |denoised| {
                farm::image_metadata(
                    acc.spp(),
                    requested,
                    settings.seed,
                    &settings.integrator.to_string(),
                    stopped,
                    denoised,
                )
            };
            let denoiser = self.denoiser.as_deref_mut();
            write_result(&acc, &output, display, self.layers, denoiser, metadata)
        };
        let denoised = match written {
            Ok(d) => d,
            Err(e) => {
                // Keep the samples for a later try: a checkpoint of them all (which
                // may fail too, on a full disk), else the one already on disk.
                if on_disk != Some(acc.spp())
                    && checkpoint::write(&ckpt_path, &key(), &acc, spent).is_ok()
                {
                    on_disk = Some(acc.spp());
                }
                let previous = if existed {
                    format!("the previous {} is unchanged", output.display())
                } else {
                    "nothing was written".to_string()
                };
                let kept = match on_disk {
                    Some(n) => format!(
                        "; {} keeps {n} spp: the same command resumes from it",
                        ckpt_path.display()
                    ),
                    None => String::new(),
                };
                anyhow::bail!("{e:#}; {previous}{kept}");
            }
        };
        // The image is out: its checkpoint is spent, unless the render was stopped.
        if !stopped && on_disk.is_some() {
            let _ = std::fs::remove_file(&ckpt_path);
        }
        if !args.quiet {
            let secs = elapsed.as_secs_f64();
            let rays = acc.tally().rays - tally_before.rays;
            let dropped = acc.tally().dropped;
            let dropped = if integrator.is_physical() || dropped > 0 {
                format!(", {dropped} NaN/Inf samples dropped")
            } else {
                String::new()
            };
            let with_aovs = if self.layers.is_empty() {
                String::new()
            } else {
                format!(" (with AOVs {})", self.layers)
            };
            let spp = match (stopped, budget) {
                (false, _) => format!("{} spp", acc.spp()),
                (true, None) => format!("interrupted after {} of {} spp", acc.spp(), settings.spp),
                (true, Some(b)) => format!(
                    "interrupted after {} spp, {:.1} of {} s",
                    acc.spp(),
                    spent.as_secs_f64().min(b.as_secs_f64()),
                    b.as_secs_f64()
                ),
            };
            // Adaptive sampling: the samples the pixels took on average.
            let spp = match args.noise_threshold {
                Some(_) => format!("{spp}, {:.1} spp on average", acc.mean_spp()),
                None => spp,
            };
            let resumed = if resumed_spp > 0 {
                format!(" ({} resumed)", resumed_spp)
            } else {
                String::new()
            };
            // A part says which one, for `raylab merge`.
            let part = if args.is_part() {
                let first = acc.first_sample();
                format!(
                    " (part: tile {split}, samples {first}..{} of {})",
                    first + acc.spp(),
                    whole.spp
                )
            } else {
                String::new()
            };
            let denoised = match (denoised, self.denoiser.as_deref()) {
                (Some(t), Some(d)) => denoised_clause(t, d),
                _ if self.args.is_part() && self.args.scene.denoise == Some(true) => {
                    "; with the guides for `raylab merge --denoise`".to_string()
                }
                _ => String::new(),
            };
            hooks.say(&format!(
                "wrote {}{part}{with_aovs}: {}x{}, {}, {spp}{resumed}, {:.1} ms, {} rays, {:.1} Mrays/s{dropped}{denoised}",
                output.display(),
                camera.width,
                camera.height,
                integrator,
                secs * 1e3,
                rays,
                rays as f64 / secs / 1e6,
            ));
            if stopped && on_disk.is_some() {
                let how = if saved_now { "saved in" } else { "kept in" };
                hooks.say(&format!(
                    "the samples are {how} {}: the same command resumes from them",
                    ckpt_path.display()
                ));
            }
        }
        let report = report(denoised);
        if args.nan_check && nan_check(args, scene, &camera, integrator, &acc, hooks)? {
            return Err(NanFound.into());
        }
        Ok(report)
    }
}

/// `--nan-check`: says whether the render of `acc` dropped NaN or infinite
/// samples and, if it did, where the first went bad; returns whether it did.
fn nan_check(
    args: &JobOptions,
    scene: &crate::scene::Scene,
    camera: &crate::camera::Camera,
    integrator: crate::integrators::Integrator,
    acc: &Accumulator,
    hooks: &Hooks<'_>,
) -> anyhow::Result<bool> {
    let dropped = acc.tally().dropped;
    if dropped == 0 {
        hooks.say(&format!(
            "nan-check: no NaN/Inf samples in {} spp",
            acc.spp()
        ));
        return Ok(false);
    }
    let seed = args.seed.unwrap_or(0);
    let samples = acc.first_sample()..acc.first_sample() + acc.spp();
    let scan = || first_bad_sample(scene, camera, integrator, seed, samples.clone());
    let bad = match args.threads {
        Some(n) => rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build()
            .context("cannot start worker threads")?
            .install(scan),
        None => scan(),
    };
    match bad {
        Some(b) => hooks.say(&format!("nan-check: {dropped} NaN/Inf samples; {b}")),
        None => hooks.say(&format!(
            "nan-check: {dropped} NaN/Inf samples, but none when evaluated one by one (the render traces rays in packets, which may break exact ties differently)"
        )),
    }
    Ok(true)
}

/// `.NAME.raylab-checkpoint` beside `output`.
fn default_checkpoint(output: &Path) -> PathBuf {
    let name = output
        .file_name()
        .map_or_else(|| "image".into(), |n| n.to_string_lossy().into_owned());
    output.with_file_name(format!(".{name}.raylab-checkpoint"))
}

/// The sums of the checkpoint at `path` if it is one of the render `key`
/// names with no more samples than asked for (`exact`: without --time),
/// with the time they took; else why not.
fn resume(
    path: &Path,
    key: Key,
    settings: &RenderSettings,
    exact: bool,
) -> Result<(Accumulator, Duration), String> {
    let header = checkpoint::read_header(path).map_err(|e| format!("is unusable: {e}"))?;
    if let Some(why) = header.key.mismatch(&key) {
        return Err(format!("is a checkpoint of {why}"));
    }
    if exact && header.spp > settings.spp {
        return Err(format!(
            "holds {} spp, more than the {} asked for",
            header.spp, settings.spp
        ));
    }
    let c = checkpoint::read(path).map_err(|e| format!("is unusable: {e}"))?;
    Ok((c.accumulator, c.header.spent))
}

/// What the render's samples are samples of (see [`checkpoint::Key`]): this
/// program's bytes; the scene's files and the scene loaded from them; the
/// camera, integrator, seed and AOVs. Not the sample count, time, threads or
/// output: a checkpoint goes on with more samples under any of those.
fn render_key(
    args: &JobOptions,
    scene: &crate::scene::Scene,
    camera: &crate::camera::Camera,
    settings: &RenderSettings,
    aovs: crate::aov::AovSet,
) -> Key {
    let mut build = Fingerprint::new();
    build.update(env!("CARGO_PKG_VERSION").as_bytes());
    if let Ok(exe) = std::env::current_exe() {
        let _ = hash_file(&exe, &mut build);
    }
    let mut files = Fingerprint::new();
    let s = &args.scene;
    let named = std::iter::once(PathBuf::from(&s.scene))
        .chain(s.add.iter().cloned())
        .chain(s.env.iter().cloned());
    for path in named {
        files.update(path.as_os_str().as_encoded_bytes());
        if path.is_file() {
            let _ = hash_file(&path, &mut files);
        }
    }
    // What was loaded, to the last texel: also what the files above refer to
    // (buffers, textures), which they do not hold.
    files.update(&scene.fingerprint().to_le_bytes());
    let mut view = Fingerprint::new();
    use std::fmt::Write;
    let _ = write!(
        view,
        "{camera:?}|{:?}|{}|{aovs}|{:?}",
        settings.integrator, settings.seed, args.noise_threshold
    );
    Key {
        build: build.value(),
        scene: files.value(),
        settings: view.value(),
    }
}

fn hash_file(path: &Path, into: &mut Fingerprint) -> std::io::Result<()> {
    let mut f = std::fs::File::open(path)?;
    let mut buf = vec![0u8; 1 << 16];
    loop {
        let n = f.read(&mut buf)?;
        if n == 0 {
            return Ok(());
        }
        into.update(&buf[..n]);
    }
}
