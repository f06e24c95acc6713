//! The `raylab` command: `render`, `view`, and a sensible default without arguments.

mod args;
mod bench;
mod denoise_worker;
mod keys;
mod render_cmd;
mod signals;
mod viewer;

use std::process::ExitCode;

use anyhow::Context;
use clap::Parser;
use clap::error::ErrorKind;

use args::{Cli, Command, SceneArgs};
use raylab::film::{Display, ToneMap};
use raylab::load::SceneKind;

fn main() -> ExitCode {
    // A panic the library catches in a third-party decoder becomes an
    // ordinary one-line error: no panic report for it.
    let report = std::panic::take_hook();
    std::panic::set_hook(Box::new(move |info| {
        if !raylab::guard::quiet() {
            report(info)
        }
    }));
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) => match e.kind() {
            ErrorKind::DisplayHelp
            | ErrorKind::DisplayVersion
            | ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand => e.exit(),
            _ => {
                // clap's message spans several lines: its first paragraph, on one line.
                let text = e.render().to_string();
                let first: Vec<&str> = text
                    .lines()
                    .skip_while(|l| l.trim().is_empty())
                    .take_while(|l| !l.trim().is_empty())
                    .map(str::trim)
                    .collect();
                eprintln!("{}", raylab::guard::one_line(&first.join(" ")));
                return ExitCode::from(2);
            }
        },
    };
    let scene_args = match &cli.command {
        Some(Command::Render(a)) => Some(&a.scene),
        Some(Command::View(a)) => Some(&a.scene),
        Some(Command::Bench(_)) | Some(Command::Merge(_)) | None => None,
    };
    if let Some(Err(message)) = scene_args.map(SceneArgs::validate) {
        eprintln!("{}", raylab::guard::one_line(&message));
        return ExitCode::from(2);
    }
    if let Some(Command::Render(a)) = &cli.command
        && let Err(message) = a.validate()
    {
        eprintln!("{}", raylab::guard::one_line(&message));
        return ExitCode::from(2);
    }
    match run(cli) {
        Ok(()) => {
            // A render stopped by SIGINT or SIGTERM wrote what it had; it ends
            // by the signal, as the caller asked.
            signals::exit_if_received();
            ExitCode::SUCCESS
        }
        // A reader that stopped early (`raylab bench ... | head -1`) is not a failure.
        Err(e) if is_broken_pipe(&e) => ExitCode::SUCCESS,
        // The image is written and the bad sample reported.
        Err(e) if e.is::<render_cmd::NanFound>() => {
            signals::exit_if_received();
            ExitCode::from(3)
        }
        Err(e) => {
            eprintln!("error: {}", raylab::guard::one_line(&format!("{e:#}")));
            ExitCode::from(1)
        }
    }
}

fn is_broken_pipe(e: &anyhow::Error) -> bool {
    e.chain()
        .filter_map(|c| c.downcast_ref::<std::io::Error>())
        .any(|io| io.kind() == std::io::ErrorKind::BrokenPipe)
}

fn run(cli: Cli) -> anyhow::Result<()> {
    match cli.command {
        Some(Command::Render(args)) => render_cmd::run(&args),
        Some(Command::View(args)) => view_command(&args.scene),
        Some(Command::Bench(args)) => bench::run(&args),
        Some(Command::Merge(args)) => merge_command(&args),
        None => run_default(),
    }
}

/// `raylab merge`: the parts of a render into its image, written as
/// `raylab render` writes it.
fn merge_command(args: &args::MergeArgs) -> anyhow::Result<()> {
    let start = std::time::Instant::now();
    raylab::film::Format::from_path(&args.output)?;
    // As `raylab render --denoise`: the library first, before the work
    // (when the parts ask for it, once they are read).
    let load = || {
        let options = raylab::denoise::DenoiseOptions::default();
        raylab::denoise::Denoiser::new(&options).context("--denoise")
    };
    let mut denoiser = match args.denoise {
        Some(true) => Some(load()?),
        _ => None,
    };
    let budget = args
        .max_memory
        .unwrap_or_else(raylab::memory::MemoryBudget::machine_default);
    let merged = raylab::farm::merge_within(&args.parts, &budget)?;
    let r = &merged.render;
    let denoise = args.denoise.unwrap_or(r.denoise);
    if denoise && !merged.acc.aov_set().includes(raylab::denoise::GUIDES) {
        anyhow::bail!(
            "--denoise: the parts carry no denoising guides (they gathered {}): render them with --denoise",
            match merged.acc.aov_set() {
                s if s.is_empty() => "no AOVs".to_string(),
                s => format!("the AOVs {s}"),
            }
        );
    }
    if denoise && denoiser.is_none() {
        denoiser = Some(load()?);
    }
    let metadata = |denoised| {
        raylab::farm::image_metadata(r.spp, Some(r.spp), r.seed, &r.integrator, false, denoised)
    };
    let denoised = render_cmd::write_result(
        &merged.acc,
        &args.output,
        r.display,
        r.layers,
        denoiser.as_mut(),
        metadata,
    )?;
    if !args.quiet {
        let denoised = match (denoised, &denoiser) {
            (Some(t), Some(d)) => render_cmd::denoised_clause(t, d),
            _ => String::new(),
        };
        eprintln!(
            "merged {} parts into {}: {}x{}, {} spp, {} rays, {} NaN/Inf samples dropped, {:.1} ms{denoised}",
            args.parts.len(),
            args.output.display(),
            merged.acc.width(),
            merged.acc.height(),
            r.spp,
            merged.acc.tally().rays,
            merged.acc.tally().dropped,
            start.elapsed().as_secs_f64() * 1e3
        );
    }
    Ok(())
}

/// `raylab view`: the viewer, with a scene file's settings where the
/// arguments leave them out.
fn view_command(args: &SceneArgs) -> anyhow::Result<()> {
    if args::is_scene_file(&args.scene) {
        let settings = raylab::load::shot::read_settings(std::path::Path::new(&args.scene))?;
        return viewer::run(&args.with_file_settings(&settings));
    }
    viewer::run(args)
}

/// No subcommand: the viewer where there is a display, else a render of the box.
fn run_default() -> anyhow::Result<()> {
    // The defaults of `raylab render`, exactly as clap gives them.
    let Ok(Cli {
        command: Some(Command::Render(args)),
    }) = Cli::try_parse_from(["raylab", "render"])
    else {
        anyhow::bail!("internal error: the default render arguments do not parse");
    };
    if let Ok(event_loop) = viewer::open_display() {
        let session = load(&args.scene, false)?;
        return viewer::run_on(event_loop, session, &args.scene);
    }
    render_cmd::run(&args)?;
    eprintln!(
        "no display found, so raylab rendered an image instead of opening the viewer; \
         run `raylab view` where an X display is available"
    );
    Ok(())
}

/// A loaded scene with everything the commands need to show it.
pub struct Session {
    /// The scene.
    pub scene: raylab::Scene,
    /// What it was made from.
    pub kind: SceneKind,
    /// The starting view (camera, light, integrator).
    pub view: raylab::controls::ViewState,
    /// Image size.
    pub size: (u32, u32),
    /// Tone mapping for PNG output and the screen.
    pub tonemap: ToneMap,
}

/// How pixel values are shown (PNG, screen) for `exposure` stops. The lab's
/// scenes and OBJ meshes: `2^E`, and `π` more for `path`, so that a diffuse
/// surface lit by the point light alone shows the lab's `ρ·D` (radiance is
/// `ρ·E/π`, the lab's `D` is the irradiance `E`). glTF scenes show radiance:
/// `path` as it is, `direct`'s `ρ·(D + N)` divided by `π` (the radiance of a
/// diffuse surface under that irradiance), `flat`'s base colour as it is.
pub fn display(
    kind: SceneKind,
    integrator: raylab::Integrator,
    exposure: f32,
    tonemap: ToneMap,
) -> Display {
    let factor = match (kind, integrator) {
        (k, raylab::Integrator::Direct) if k.is_physical() => 1.0 / std::f32::consts::PI,
        (k, _) if k.is_physical() => 1.0,
        (_, i) if i.is_physical() => std::f32::consts::PI,
        _ => 1.0,
    };
    Display {
        scale: factor * exposure.exp2(),
        tonemap,
    }
}

/// Loads the scene of the arguments through the library, prints its warnings
/// and (unless `quiet`) a summary line for files, and sets up the view.
fn load(args: &SceneArgs, quiet: bool) -> anyhow::Result<Session> {
    load_for(args, quiet, 0)
}

/// [`load`] for a film with `aov_channels` AOV channels: the scene's memory
/// estimate and the film's must fit `--max-memory` together.
pub fn load_for(args: &SceneArgs, quiet: bool, aov_channels: usize) -> anyhow::Result<Session> {
    if let Some(dir) = &args.cache {
        raylab::cache::set_dir(Some(dir.clone()))
            .map_err(|e| anyhow::anyhow!("--cache {}: {e}", dir.display()))?;
    }
    let loaded = raylab::load::load(&args.scene, &args.load_options())?;
    if let Some(dir) = &args.cache
        && !quiet
    {
        let (hits, misses) = raylab::cache::stats();
        eprintln!(
            "cache {}: {hits} of {} entries found (textures and BVHs)",
            dir.display(),
            hits + misses
        );
    }
    let size = args
        .size(loaded.kind, loaded.view.aspect_ratio)
        .map_err(|e| anyhow::anyhow!(e.trim_start_matches("error: ").to_string()))?;
    // The film is allocated when the render starts: check it with the scene
    // (already loaded within the budget) before then.
    let needs = raylab::memory::Needs {
        film: raylab::memory::film_bytes(size.0, size.1, aov_channels),
        ..loaded.summary.needs
    };
    args.memory_budget().check(&args.scene, &needs)?;
    for w in &loaded.warnings {
        eprintln!("warning: {}", raylab::guard::one_line(w));
    }
    let kind = loaded.kind;
    if !quiet && kind != SceneKind::Lab {
        let s = &loaded.summary;
        let mib = |b: usize| b as f64 / (1024.0 * 1024.0);
        let plural = |n: usize, what: &str| format!("{n} {what}{}", if n == 1 { "" } else { "s" });
        let lights = if loaded.default_light {
            "no lights in the file: default key light and grey sky".to_string()
        } else {
            plural(s.punctual_lights, "light")
        };
        eprintln!(
            "loaded {}: {}, {}, {} ({:.1} MiB), {}, {}, geometry {:.1} MiB, {:.0} ms",
            args.scene,
            plural(s.triangles, "triangle"),
            plural(s.materials, "material"),
            plural(s.textures, "texture"),
            mib(s.texture_bytes),
            lights,
            plural(s.emitters, "emitting triangle"),
            mib(s.geometry_bytes),
            s.time.as_secs_f64() * 1e3,
        );
    }
    if !quiet && let Some([w, h]) = loaded.summary.environment_size {
        let s = &loaded.summary;
        eprintln!(
            "environment {w}×{h}: {:.1} MiB with its sampling tables, {:.0} ms",
            s.environment_bytes as f64 / (1024.0 * 1024.0),
            s.environment_time.as_secs_f64() * 1e3
        );
    }
    let v = &loaded.view;
    let view = raylab::controls::ViewState {
        camera_pos: args.camera_pos.unwrap_or(v.position),
        base: v.rotation,
        step: v.step,
        yaw_deg: args.yaw,
        pitch_deg: args.pitch,
        light_pos: loaded.scene.light.position,
        integrator: args.integrator(kind),
        lens: v.lens,
    };
    let tonemap = args.tonemap.unwrap_or(match kind {
        SceneKind::Gltf | SceneKind::Shot => ToneMap::KhronosPbrNeutral,
        _ => ToneMap::Clamp,
    });
    Ok(Session {
        scene: loaded.scene,
        kind,
        view,
        size,
        tonemap,
    })
}
