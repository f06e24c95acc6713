//! `raylab render`: one image to a file, with a progress bar and a summary line.

use std::io::IsTerminal;
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use anyhow::Context;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use raylab::film::{Format, write_image_layers};
use raylab::render::{Progressive, RenderSettings, render_for_with_aovs, render_with_aovs};

use crate::args::{MAX_SPP, RenderArgs};

/// A render shorter than this shows no progress bar.
const PROGRESS_DELAY: Duration = Duration::from_millis(300);

pub fn run(args: &RenderArgs) -> anyhow::Result<()> {
    let args = &args.with_scene_file()?;
    let output = args.output.clone().unwrap_or_else(|| {
        // SCENE.png in the current folder, also for a mesh given by its path;
        // SCENE.exr with AOVs, which only EXR holds.
        let stem = std::path::Path::new(&args.scene.scene)
            .file_stem()
            .map_or_else(|| "image".into(), |s| s.to_string_lossy().into_owned());
        let ext = if args.aov.is_some() { "exr" } else { "png" };
        PathBuf::from(format!("{stem}.{ext}"))
    });
    let aovs = args.aov.unwrap_or_default();
    // Refuse an unsupported format or a missing folder before spending time on
    // the render.
    Format::from_path(&output)?;
    if let Some(dir) = output.parent().filter(|d| !d.as_os_str().is_empty())
        && !dir.is_dir()
    {
        anyhow::bail!(
            "cannot write {}: the folder {} does not exist",
            output.display(),
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

    let bar = ProgressBar::hidden();
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
        if show_bar && start.elapsed() > PROGRESS_DELAY && !shown.swap(true, Ordering::Relaxed) {
            bar.set_draw_target(ProgressDrawTarget::stderr());
        }
    };
    let rows_done = |rows: u64| {
        bar.inc(rows);
        reveal();
    };
    let time_spent = |t: Duration| {
        bar.set_position(t.as_millis() as u64);
        reveal();
    };
    let work = || match args.time {
        Some(seconds) => {
            let budget = Duration::from_secs_f64(seconds);
            bar.set_length(budget.as_millis() as u64);
            let settings = RenderSettings {
                integrator,
                spp: args.spp.unwrap_or(MAX_SPP),
                seed: args.seed.unwrap_or(0),
            };
            render_for_with_aovs(scene, &camera, &settings, aovs, budget, &time_spent)
        }
        None => {
            let spp = args.spp.unwrap_or(1);
            bar.set_length(camera.height as u64);
            let settings = RenderSettings {
                integrator,
                spp,
                seed: args.seed.unwrap_or(0),
            };
            Progressive {
                rendered: render_with_aovs(scene, &camera, &settings, aovs, &rows_done),
                spp,
            }
        }
    };
    let mut done = match args.threads {
        Some(n) => rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build()
            .context("cannot start worker threads")?
            .install(work),
        None => work(),
    };
    let elapsed = start.elapsed();
    bar.finish_and_clear();

    let display = crate::display(
        session.kind,
        integrator,
        args.scene.exposure.unwrap_or(0.0),
        session.tonemap,
    );
    // The AOVs as EXR planes; they and the image are written, then freed.
    let channels = done
        .rendered
        .aovs
        .take()
        .map(|a| a.into_channels())
        .unwrap_or_default();
    write_image_layers(&done.rendered.film, channels, &output, display)?;
    if !args.quiet {
        let secs = elapsed.as_secs_f64();
        let rays = done.rendered.rays;
        let dropped = if integrator.is_physical() || done.rendered.dropped > 0 {
            format!(", {} NaN/Inf samples dropped", done.rendered.dropped)
        } else {
            String::new()
        };
        let with_aovs = if aovs.is_empty() {
            String::new()
        } else {
            format!(" (with AOVs {aovs})")
        };
        eprintln!(
            "wrote {}{with_aovs}: {}x{}, {}, {} spp, {:.1} ms, {} rays, {:.1} Mrays/s{dropped}",
            output.display(),
            camera.width,
            camera.height,
            integrator,
            done.spp,
            secs * 1e3,
            rays,
            rays as f64 / secs / 1e6,
        );
    }
    Ok(())
}
