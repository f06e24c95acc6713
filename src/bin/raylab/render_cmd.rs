//! `raylab render`: one image to a file, with a progress bar and a summary line.

use std::io::IsTerminal;
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use anyhow::Context;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use raylab::film::{Format, write_image};
use raylab::render::{RenderSettings, render};

use crate::args::RenderArgs;

/// A render shorter than this shows no progress bar.
const PROGRESS_DELAY: Duration = Duration::from_millis(300);

pub fn run(args: &RenderArgs) -> anyhow::Result<()> {
    let output = args.output.clone().unwrap_or_else(|| {
        // SCENE.png in the current folder, also for a mesh given by its path.
        let stem = std::path::Path::new(&args.scene.scene)
            .file_stem()
            .map_or_else(|| "image".into(), |s| s.to_string_lossy().into_owned());
        PathBuf::from(format!("{stem}.png"))
    });
    // Refuse an unsupported format before spending time on the render.
    Format::from_path(&output)?;
    let (scene, view) = crate::load(&args.scene)?;
    let camera = view.camera(args.scene.width, args.scene.height);
    let settings = RenderSettings {
        integrator: view.integrator,
        spp: args.spp,
        seed: args.seed,
    };

    let bar = ProgressBar::hidden();
    bar.set_length(camera.height as u64);
    bar.set_style(
        ProgressStyle::with_template("{elapsed_precise} [{wide_bar}] {percent}% eta {eta}")
            .expect("valid template"),
    );
    let show_bar = !args.quiet && std::io::stderr().is_terminal();
    let shown = AtomicBool::new(false);
    let start = Instant::now();
    let progress = |rows: u64| {
        bar.inc(rows);
        if show_bar && start.elapsed() > PROGRESS_DELAY && !shown.swap(true, Ordering::Relaxed) {
            bar.set_draw_target(ProgressDrawTarget::stderr());
        }
    };
    let rendered = match args.threads {
        Some(n) => rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build()
            .context("cannot start worker threads")?
            .install(|| render(&scene, &camera, &settings, &progress)),
        None => render(&scene, &camera, &settings, &progress),
    };
    let elapsed = start.elapsed();
    bar.finish_and_clear();

    write_image(&rendered.film, &output)?;
    if !args.quiet {
        let secs = elapsed.as_secs_f64();
        eprintln!(
            "wrote {}: {}x{}, {}, {} spp, {:.1} ms, {} rays, {:.1} Mrays/s",
            output.display(),
            camera.width,
            camera.height,
            settings.integrator,
            settings.spp,
            secs * 1e3,
            rendered.rays,
            rendered.rays as f64 / secs / 1e6,
        );
    }
    Ok(())
}
