//! `raylab render`: one image to a file, with a progress bar and a summary line.

use std::io::{IsTerminal, Read};
use std::path::{Path, PathBuf};
use std::sync::OnceLock;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use anyhow::Context;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use raylab::aov::{AovImage, AovSet};
use raylab::checkpoint::{self, Key};
use raylab::denoise::{DenoiseOptions, Denoiser};
use raylab::farm;
use raylab::film::{Channel, Display, Format, MetaValue, write_image_meta};
use raylab::fingerprint::Fingerprint;
use raylab::nan_check::first_bad_sample;
use raylab::render::{Accumulator, Ended, Passes, RenderSettings, Split, render_passes};

use crate::args::{MAX_SPP, RenderArgs};
use crate::signals;

/// A render shorter than this shows no progress bar.
const PROGRESS_DELAY: Duration = Duration::from_millis(300);

pub fn run(args: &RenderArgs) -> anyhow::Result<()> {
    let args = &args.with_scene_file()?;
    let denoise = args.scene.denoise.unwrap_or(false);
    // Open Image Denoise is loaded first: without it, one line that says how
    // to install it, before any time is spent. A part is denoised only once
    // merged, so its render needs no library.
    let mut denoiser = if denoise && !args.is_part() {
        let options = DenoiseOptions {
            threads: args.threads.unwrap_or(0),
            ..DenoiseOptions::default()
        };
        Some(Denoiser::new(&options).context("--denoise")?)
    } else {
        None
    };
    let output = args.output.clone().unwrap_or_else(|| {
        // SCENE.png in the current folder, also for a mesh given by its path;
        // SCENE.exr with AOVs, which only EXR holds.
        let stem = std::path::Path::new(&args.scene.scene)
            .file_stem()
            .map_or_else(|| "image".into(), |s| s.to_string_lossy().into_owned());
        let ext = if args.aov.is_some() { "exr" } else { "png" };
        PathBuf::from(format!("{stem}.{ext}"))
    });
    // The AOVs gathered: those asked for, and the denoiser's.
    let layers = args.aov.unwrap_or_default();
    let aovs = if denoise {
        layers.with(raylab::denoise::GUIDES)
    } else {
        layers
    };
    // Refuse an unsupported format or a missing folder before spending time on
    // the render (of the first frame's file: the pattern is checked by
    // `RenderArgs::validate`).
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
    let aov_channels = aovs.iter().map(|a| a.channels().len()).sum();
    let session = crate::load_for(&args.scene, args.quiet, aov_channels)?;
    let (scene, view) = (&session.scene, &session.view);
    let camera = view.camera(session.size.0, session.size.1);
    let integrator = view.integrator;
    if integrator.is_physical() && !scene.has_lights() && !args.quiet {
        eprintln!(
            "warning: the scene has no light (point light power 0, nothing emits): the path-traced image is black"
        );
    }
    let path_only = args.scene.max_depth.is_some() || !args.scene.material.is_empty();
    if !integrator.is_physical() && path_only && !args.quiet {
        eprintln!(
            "warning: --max-depth and --material only change `path` images; {integrator} ignores them"
        );
    }
    if integrator == raylab::Integrator::Direct && scene.point_power() == 0.0 && !args.quiet {
        eprintln!(
            "warning: the point light is off: `direct` shows only the ambient term (emitting triangles light the scene under --integrator path)"
        );
    }

    let seed = args.seed.unwrap_or(0);
    let budget = args.time.map(Duration::from_secs_f64);
    // Without --time, exactly --spp samples; with it, at most --spp.
    let settings = RenderSettings {
        integrator,
        spp: match budget {
            Some(_) => args.spp.unwrap_or(MAX_SPP),
            None => args.spp.unwrap_or(1),
        },
        seed,
    };

    let bar = ProgressBar::hidden();
    // Ctrl-C and SIGTERM from here on: the first stops the render between
    // passes, the second aborts (removing the temporary files of writes in
    // progress).
    let said = bar.clone();
    signals::install(move |sig| {
        let again = match sig {
            libc::SIGINT => "press Ctrl-C again to abort",
            _ => "a second signal aborts",
        };
        said.suspend(|| {
            eprintln!(
                "{}: stopping after the samples in flight; {again}",
                signals::name(sig)
            )
        });
    })
    .context("cannot handle SIGINT and SIGTERM")?;
    let mut job = Job {
        args,
        session: &session,
        settings: &settings,
        aovs,
        layers,
        denoiser: denoiser.as_mut(),
        bar: &bar,
    };
    let Some((first, end)) = args.frames else {
        job.render_image(&camera, &output, None)?;
        return Ok(());
    };
    // An animation: each frame a render of its own, of the scene loaded once.
    let (low, high) = scene.bounds();
    let centre = 0.5 * (low + high);
    for frame in first..end {
        let path = farm::frame_path(&output, frame).context("-o has no frame number field")?;
        let degrees = args
            .orbit
            .map_or(0.0, |d| (f64::from(d) * f64::from(frame)) % 360.0);
        let camera = camera.orbited(centre, degrees as f32);
        let ended = job.render_image(&camera, &path, Some(frame))?;
        if ended == Ended::Stopped {
            if !args.quiet && frame + 1 < end {
                eprintln!(
                    "stopped at frame {frame}: frames {}..{end} not rendered",
                    frame + 1
                );
            }
            break;
        }
    }
    Ok(())
}

/// What every image of a `raylab render` shares.
struct Job<'a> {
    args: &'a RenderArgs,
    session: &'a crate::Session,
    settings: &'a RenderSettings,
    /// The AOVs gathered (those asked for and the denoiser's).
    aovs: AovSet,
    /// The AOVs written as layers (those asked for).
    layers: AovSet,
    denoiser: Option<&'a mut Denoiser>,
    bar: &'a ProgressBar,
}

impl Job<'_> {
    /// Renders one image (the whole render, a part of it, or a frame) of
    /// `session` seen by `camera` to `output`, resuming from and saving to its
    /// checkpoint, and says what it did; returns how the render ended.
    fn render_image(
        &mut self,
        camera: &raylab::camera::Camera,
        output: &Path,
        frame: Option<u32>,
    ) -> anyhow::Result<Ended> {
        let (args, session, settings, bar) = (self.args, self.session, self.settings, self.bar);
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
        let explicit = args.checkpoint.is_some();
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
        if ckpt_path.exists() {
            match resume(&ckpt_path, key(), settings, budget.is_none()) {
                Ok((a, s)) => {
                    let a = a.into_part(split, first_sample);
                    if !args.quiet {
                        let of = match budget {
                            None => format!(" of {}", settings.spp),
                            Some(_) => String::new(),
                        };
                        eprintln!("resuming from {}: {}{of} spp", ckpt_path.display(), a.spp());
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
                        eprintln!(
                            "warning: not resuming from {}: {why}; rendering from the start",
                            ckpt_path.display()
                        );
                    }
                }
            }
        }
        let resumed_spp = acc.spp();
        let tally_before = acc.tally();

        bar.reset();
        bar.set_draw_target(ProgressDrawTarget::hidden());
        let template = match args.time {
            // Time-limited: the bar fills with the time spent.
            Some(_) => "{elapsed_precise} [{wide_bar}] {pos}/{len} ms",
            None => "{elapsed_precise} [{wide_bar}] {percent}% eta {eta}",
        };
        bar.set_style(ProgressStyle::with_template(template).expect("valid template"));
        let show_bar = !args.quiet && std::io::stderr().is_terminal();
        let shown = AtomicBool::new(false);
        let start = Instant::now();
        let reveal = || {
            if show_bar && start.elapsed() > PROGRESS_DELAY && !shown.swap(true, Ordering::Relaxed)
            {
                bar.set_draw_target(ProgressDrawTarget::stderr());
            }
        };
        match budget {
            Some(b) => {
                bar.set_length(b.as_millis() as u64);
                bar.set_position(spent.as_millis() as u64);
            }
            None => {
                let rows = (0..camera.height)
                    .filter(|y| split.has_tile(y / raylab::render::TILE_ROWS as u32))
                    .count() as u64;
                bar.set_length(rows * settings.spp as u64);
                bar.set_position(rows * acc.spp() as u64);
            }
        }
        let progress = |row_samples: u64| {
            match budget {
                Some(_) => bar.set_position((spent + start.elapsed()).as_millis() as u64),
                None => bar.inc(row_samples),
            }
            reveal();
        };

        signals::remove_on_abort(&[
            &raylab::film::temp_path(&output),
            &raylab::film::temp_path(&ckpt_path),
        ]);

        let every = Duration::from_secs_f64(args.checkpoint_every);
        let mut last_save = Instant::now();
        let mut save_cost = Duration::ZERO;
        let mut save_error: Option<String> = None;
        let passes = Passes {
            budget,
            spent,
            stop: Some(&signals::STOP),
        };
        let mut after_pass = |acc: &Accumulator, spent: Duration| {
            // Periodic saves only when asked for (--checkpoint), never after the
            // last pass (the image is about to be written), and at most every
            // twentieth of the time on saving.
            let done = acc.spp() >= settings.spp
                || budget.is_some_and(|b| spent >= b)
                || signals::STOP.load(Ordering::Relaxed);
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
                        bar.suspend(|| eprintln!("warning: {}", raylab::guard::one_line(&text)));
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
        bar.finish_and_clear();
        let stopped = ended == Ended::Stopped;

        if acc.spp() == 0 {
            // Stopped before the first sample: nothing to write or to keep.
            if !args.quiet {
                eprintln!(
                    "interrupted before the first sample: {} not written",
                    output.display()
                );
            }
            return Ok(ended);
        }
        // A stopped render keeps its samples (unless the checkpoint on disk
        // already holds them all).
        let mut saved_now = false;
        if stopped && on_disk != Some(acc.spp()) {
            match checkpoint::write(&ckpt_path, &key(), &acc, spent) {
                Ok(()) => {
                    on_disk = Some(acc.spp());
                    saved_now = true;
                }
                Err(e) => eprintln!(
                    "warning: {:#}; the samples cannot be resumed",
                    anyhow::Error::from(e)
                ),
            }
        }

        let display = crate::display(
            session.kind,
            integrator,
            args.scene.exposure.unwrap_or(0.0),
            session.tonemap,
        );
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
            eprintln!(
                "wrote {}{part}{with_aovs}: {}x{}, {}, {spp}{resumed}, {:.1} ms, {} rays, {:.1} Mrays/s{dropped}{denoised}",
                output.display(),
                camera.width,
                camera.height,
                integrator,
                secs * 1e3,
                rays,
                rays as f64 / secs / 1e6,
            );
            if stopped && on_disk.is_some() {
                let how = if saved_now { "saved in" } else { "kept in" };
                eprintln!(
                    "the samples are {how} {}: the same command resumes from them",
                    ckpt_path.display()
                );
            }
        }
        if args.nan_check {
            let dropped = acc.tally().dropped;
            if dropped == 0 {
                eprintln!("nan-check: no NaN/Inf samples in {} spp", acc.spp());
                return Ok(ended);
            }
            let samples = acc.first_sample()..acc.first_sample() + acc.spp();
            let scan = || first_bad_sample(scene, &camera, integrator, seed, samples.clone());
            let bad = match args.threads {
                Some(n) => rayon::ThreadPoolBuilder::new()
                    .num_threads(n)
                    .build()
                    .context("cannot start worker threads")?
                    .install(scan),
                None => scan(),
            };
            match bad {
                Some(b) => eprintln!("nan-check: {dropped} NaN/Inf samples; {b}"),
                None => eprintln!(
                    "nan-check: {dropped} NaN/Inf samples, but none when evaluated one by one (the render traces rays in packets, which may break exact ties differently)"
                ),
            }
            return Err(NanFound.into());
        }
        Ok(ended)
    }
}

/// Writes the image of `acc` (a whole render, or the merge of its parts) to
/// `output`: denoised by `denoiser` if given (the noisy image then goes into
/// an EXR as the layer `noisy`), with the AOVs of `layers` as layers and the
/// `metadata` of what it is (given whether the image is denoised). Returns
/// how long denoising took.
pub fn write_result(
    acc: &Accumulator,
    output: &Path,
    display: Display,
    layers: AovSet,
    denoiser: Option<&mut Denoiser>,
    metadata: impl FnOnce(bool) -> [(String, MetaValue); 2],
) -> anyhow::Result<Option<Duration>> {
    let mut rendered = acc.rendered();
    let aovs = rendered.aovs.take();
    let exr = Format::from_path(output)? == Format::Exr;
    let mut channels = Vec::new();
    let mut took = None;
    let image = match denoiser {
        Some(d) => {
            let guides = aovs
                .as_ref()
                .ok_or(raylab::denoise::DenoiseError::MissingAov(
                    raylab::aov::Aov::Albedo,
                ))?;
            let clean = d
                .denoise(&rendered.film, guides)
                .context("cannot denoise")?;
            took = Some(d.last_time());
            if exr {
                channels.extend(noisy_channels(&rendered.film));
            }
            clean
        }
        None => rendered.film,
    };
    // The AOVs asked for as EXR planes; they and the image are written,
    // then freed.
    if let Some(a) = aovs {
        let shown = AovImage {
            layers: a
                .layers
                .into_iter()
                .filter(|l| layers.contains(l.aov))
                .collect(),
            ..a
        };
        channels.extend(shown.into_channels());
    }
    // The samples taken as a number any EXR tool shows, and the rest as
    // text (see `write_image_meta` for why two attributes).
    let metadata = metadata(took.is_some());
    write_image_meta(&image, channels, output, display, &metadata)?;
    Ok(took)
}

/// The summary line's `; denoised in 152.3 ms by OIDN ...`.
pub fn denoised_clause(took: Duration, denoiser: &Denoiser) -> String {
    format!(
        "; denoised in {:.1} ms by {}",
        took.as_secs_f64() * 1e3,
        denoiser.describe()
    )
}

/// The noisy image as the EXR layer `noisy` (`noisy.R`, `noisy.G`, `noisy.B`).
fn noisy_channels(film: &raylab::film::Film) -> [Channel; 3] {
    let plane = |c: usize| film.pixels.iter().map(|p| p[c]).collect();
    ["R", "G", "B"]
        .into_iter()
        .enumerate()
        .map(|(c, name)| Channel {
            name: format!("noisy.{name}"),
            values: plane(c),
        })
        .collect::<Vec<_>>()
        .try_into()
        .expect("three channels")
}

/// `--nan-check` found a NaN or infinite sample (already reported): exit code 3.
#[derive(Debug)]
pub struct NanFound;

impl std::fmt::Display for NanFound {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("NaN/Inf samples found")
    }
}

impl std::error::Error for NanFound {}

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
    args: &RenderArgs,
    scene: &raylab::Scene,
    camera: &raylab::camera::Camera,
    settings: &RenderSettings,
    aovs: raylab::aov::AovSet,
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
        "{camera:?}|{:?}|{}|{aovs}",
        settings.integrator, settings.seed
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
