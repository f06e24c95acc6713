//! The `raylab` command: `render`, `view`, and a sensible default without arguments.

mod args;
mod bench;
mod keys;
mod render_cmd;
mod signals;
mod viewer;

use std::process::ExitCode;

use clap::Parser;
use clap::error::ErrorKind;

use args::{Cli, Command};
use raylab::job::SceneOptions;
use raylab::job::options::is_scene_file;

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
    if let Some(Err(message)) = scene_args.map(SceneOptions::validate) {
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
        Err(e) if e.is::<raylab::job::NanFound>() => {
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
    let options = raylab::job::MergeOptions {
        max_memory: args.max_memory,
        denoise: args.denoise,
    };
    let report = raylab::job::merge(&args.parts, &args.output, &options)?;
    if !args.quiet {
        eprintln!("{}", report.summary);
    }
    Ok(())
}

/// `raylab view`: the viewer, with a scene file's settings where the
/// arguments leave them out.
fn view_command(args: &SceneOptions) -> anyhow::Result<()> {
    if is_scene_file(&args.scene) {
        let settings = raylab::job::options::read_file_settings(&args.scene, &args.define)?;
        return viewer::run(&args.with_file_settings(&settings));
    }
    viewer::run(args)
}

/// No subcommand: the viewer where there is a display, else a render of the box.
fn run_default() -> anyhow::Result<()> {
    // The defaults of `raylab render`, exactly as clap gives them.
    let args = raylab::job::JobOptions::default();
    if let Ok(event_loop) = viewer::open_display() {
        let session = raylab::job::load_session(&args.scene, false, 0, &viewer::hooks())?;
        return viewer::run_on(event_loop, session, &args.scene);
    }
    render_cmd::run(&args)?;
    eprintln!(
        "no display found, so raylab rendered an image instead of opening the viewer; \
         run `raylab view` where an X display is available"
    );
    Ok(())
}
