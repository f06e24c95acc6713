//! What a job tells its caller while it runs ([`Event`]s, counted in a
//! [`ProgressUnit`]) and how the caller hears them and stops the job
//! ([`Hooks`]).

use std::path::{Path, PathBuf};
use std::sync::atomic::AtomicBool;

/// What a job tells its caller while it runs.
#[derive(Clone, Copy, Debug)]
pub enum Event<'a> {
    /// A line for the user, as `raylab render` prints it on standard error:
    /// load summaries, notes, `warning: ...` lines and each image's summary
    /// (with `quiet`, only warnings about the scene and `--nan-check`'s
    /// findings). One line, without its newline.
    Line(&'a str),
    /// An image's render starts (its scene is loaded): progress goes from
    /// `done` to `total`, counted in `unit`s.
    Started {
        /// Where the image goes.
        output: &'a Path,
        /// The progress when finished.
        total: u64,
        /// The progress already made (resumed samples, time spent before).
        done: u64,
        /// What progress counts.
        unit: ProgressUnit,
    },
    /// Progress of the render started last, from any worker thread: the work
    /// done so far, out of [`Event::Started`]'s `total`.
    Progress(u64),
    /// Adaptive sampling (`noise_threshold`): after each pass of the render
    /// started last, the samples its pixels took on average so far.
    Samples(f64),
    /// The render started last has taken its last sample.
    Finished,
    /// Files are about to be written through these temporary files: a caller
    /// that can be killed removes them if it is.
    Writing(&'a [PathBuf]),
}

/// What [`Event::Progress`] counts.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ProgressUnit {
    /// Samples of image rows (rows × samples per pixel).
    RowSamples,
    /// Milliseconds of a time-limited render (`--time`).
    Milliseconds,
}

/// What a job's caller hears and how it stops the job.
#[derive(Clone, Copy)]
pub struct Hooks<'a> {
    /// Called with each [`Event`], from the job's thread and (for
    /// [`Event::Progress`]) from the render's workers.
    pub on_event: &'a (dyn Fn(Event<'_>) + Sync),
    /// When set, the render stops after the samples in flight, keeps them in
    /// its checkpoint and writes the image so far.
    pub stop: Option<&'a AtomicBool>,
}

impl Default for Hooks<'_> {
    /// Hears nothing; never stops.
    fn default() -> Self {
        Self {
            on_event: &|_| {},
            stop: None,
        }
    }
}

impl Hooks<'_> {
    /// Tells the caller `line` ([`Event::Line`]).
    pub(super) fn say(&self, line: &str) {
        (self.on_event)(Event::Line(line));
    }
}
