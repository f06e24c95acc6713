//! How a job went: the [`Report`] of its images, each one's
//! [`ImageReport`], an image rendered in memory ([`Rendered`]) and the error
//! `--nan-check` ends a job with ([`NanFound`]).

use std::path::PathBuf;
use std::time::Duration;

use super::write::Finished;
use crate::render::Ended;

/// How a job went: one entry per image written (frames: one each).
#[derive(Clone, Debug, Default)]
pub struct Report {
    /// The images, in the order rendered.
    pub images: Vec<ImageReport>,
}

/// One image of a [`Report`].
#[derive(Clone, Debug)]
pub struct ImageReport {
    /// The file written (nothing is written when stopped before the first
    /// sample).
    pub output: PathBuf,
    /// Samples per pixel in the image (resumed ones included).
    pub spp: u32,
    /// Samples per pixel resumed from a checkpoint.
    pub resumed_spp: u32,
    /// How the render ended.
    pub ended: Ended,
    /// Rays traced by this run.
    pub rays: u64,
    /// NaN or infinite samples dropped.
    pub dropped: u64,
    /// Time spent rendering by this run.
    pub elapsed: Duration,
    /// Time spent denoising, when the image was denoised.
    pub denoise_time: Option<Duration>,
}

/// An image rendered in memory ([`Job::render_with`](crate::job::Job::render_with)).
#[derive(Clone, Debug)]
pub struct Rendered {
    /// The image, its noisy twin when denoised, and its AOVs.
    pub finished: Finished,
    /// How it went.
    pub report: ImageReport,
}

/// `--nan-check` found a NaN or infinite sample (already reported as an
/// [`Event::Line`](crate::job::Event::Line)): `raylab render` exits with code 3.
#[derive(Debug)]
pub struct NanFound;

impl std::fmt::Display for NanFound {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("NaN/Inf samples found")
    }
}

impl std::error::Error for NanFound {}
