//! `raylab render`: the library's render job, with a progress bar, the
//! job's lines on standard error, and Ctrl-C/SIGTERM.

use std::io::IsTerminal;
use std::sync::Once;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use anyhow::Context;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use raylab::job::{Event, Hooks, Job, JobOptions, ProgressUnit};

use crate::signals;

/// A render shorter than this shows no progress bar.
const PROGRESS_DELAY: Duration = Duration::from_millis(300);

pub fn run(options: &JobOptions) -> anyhow::Result<()> {
    let mut job = Job::new(options.clone())?;
    let show_bar = !options.quiet && std::io::stderr().is_terminal();
    let bar = ProgressBar::hidden();
    let shown = AtomicBool::new(false);
    let started = std::sync::Mutex::new(Instant::now());
    let signals_installed = Once::new();
    let install_error = std::sync::Mutex::new(None);
    let on_event = |event: Event<'_>| match event {
        Event::Line(line) => bar.suspend(|| eprintln!("{line}")),
        Event::Started {
            total, done, unit, ..
        } => {
            // Ctrl-C and SIGTERM from the first render on: the first stops it
            // between passes, the second aborts (removing the temporary files
            // of writes in progress).
            signals_installed.call_once(|| {
                let said = bar.clone();
                let installed = signals::install(move |sig| {
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
                });
                if let Err(e) = installed {
                    *install_error.lock().unwrap() = Some(e);
                }
            });
            bar.reset();
            bar.set_draw_target(ProgressDrawTarget::hidden());
            let template = match unit {
                // Time-limited: the bar fills with the time spent.
                ProgressUnit::Milliseconds => "{elapsed_precise} [{wide_bar}] {pos}/{len} ms{msg}",
                ProgressUnit::RowSamples => {
                    "{elapsed_precise} [{wide_bar}] {percent}% eta {eta}{msg}"
                }
            };
            bar.set_message("");
            bar.set_style(ProgressStyle::with_template(template).expect("valid template"));
            bar.set_length(total);
            bar.set_position(done);
            shown.store(false, Ordering::Relaxed);
            *started.lock().unwrap() = Instant::now();
        }
        Event::Progress(done) => {
            bar.set_position(done);
            let start = *started.lock().unwrap();
            if show_bar && start.elapsed() > PROGRESS_DELAY && !shown.swap(true, Ordering::Relaxed)
            {
                bar.set_draw_target(ProgressDrawTarget::stderr());
            }
        }
        // Adaptive sampling: the bar counts every pixel's samples up to
        // --spp, and says how many the pixels took so far.
        Event::Samples(mean) => bar.set_message(format!(", {mean:.1} spp on average")),
        Event::Finished => bar.finish_and_clear(),
        Event::Writing(paths) => {
            let paths: Vec<&std::path::Path> = paths.iter().map(|p| p.as_path()).collect();
            signals::remove_on_abort(&paths);
        }
    };
    let hooks = Hooks {
        on_event: &on_event,
        stop: Some(&signals::STOP),
    };
    let result = job.run_with(&hooks);
    if let Some(e) = install_error.lock().unwrap().take() {
        return Err(e).context("cannot handle SIGINT and SIGTERM");
    }
    result.map(|_| ())
}
