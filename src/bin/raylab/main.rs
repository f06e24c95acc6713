//! The `raylab` command: `render`, `view`, and a sensible default without arguments.

mod args;
mod bench;
mod keys;
mod render_cmd;
mod viewer;

use std::process::ExitCode;

use clap::Parser;
use clap::error::ErrorKind;

use args::{Cli, Command, RenderArgs, SceneArgs};

fn main() -> ExitCode {
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
                eprintln!("{}", first.join(" "));
                return ExitCode::from(2);
            }
        },
    };
    let scene_args = match &cli.command {
        Some(Command::Render(a)) => Some(&a.scene),
        Some(Command::View(a)) => Some(&a.scene),
        Some(Command::Bench(_)) | None => None,
    };
    if let Some(Err(message)) = scene_args.map(SceneArgs::validate) {
        eprintln!("{message}");
        return ExitCode::from(2);
    }
    match run(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::from(1)
        }
    }
}

fn run(cli: Cli) -> anyhow::Result<()> {
    match cli.command {
        Some(Command::Render(args)) => render_cmd::run(&args),
        Some(Command::View(args)) => viewer::run(&args.scene),
        Some(Command::Bench(args)) => bench::run(&args),
        None => run_default(),
    }
}

/// No subcommand: the viewer where there is a display, else a render of the box.
fn run_default() -> anyhow::Result<()> {
    let scene = SceneArgs {
        scene: "cornell".into(),
        width: 500,
        height: 500,
        integrator: raylab::Integrator::Direct,
        camera_pos: None,
        yaw: 0.0,
        pitch: 0.0,
        light_pos: None,
        light_power: raylab::cornell::LIGHT_POWER,
        ambient: raylab::cornell::AMBIENT,
    };
    if let Ok(event_loop) = viewer::open_display() {
        let (loaded, initial) = load(&scene)?;
        return viewer::run_on(event_loop, loaded, initial, &scene);
    }
    let args = RenderArgs {
        scene,
        output: None,
        spp: 1,
        seed: 0,
        threads: None,
        quiet: false,
    };
    render_cmd::run(&args)?;
    eprintln!(
        "no display found, so raylab rendered an image instead of opening the viewer; \
         run `raylab view` where an X display is available"
    );
    Ok(())
}

/// Builds the scene and the initial view from the shared arguments.
fn load(args: &SceneArgs) -> anyhow::Result<(raylab::Scene, raylab::controls::ViewState)> {
    let mut scene = match args.scene.as_str() {
        "cornell" => raylab::cornell::scene(),
        other => anyhow::bail!("scene '{other}': unknown scene (built in: cornell)"),
    };
    scene.light.position = args.light_pos.unwrap_or(raylab::cornell::LIGHT_POSITION);
    scene.light.power = glam::Vec3A::splat(args.light_power);
    scene.ambient = glam::Vec3A::splat(args.ambient);
    let view = raylab::controls::ViewState {
        camera_pos: args.camera_pos.unwrap_or(raylab::cornell::CAMERA_POSITION),
        yaw_deg: args.yaw,
        pitch_deg: args.pitch,
        light_pos: scene.light.position,
        integrator: args.integrator,
    };
    Ok((scene, view))
}
