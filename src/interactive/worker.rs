//! The interactive denoiser: Open Image Denoise on a thread of its own, so
//! that a window goes on refining (and answering keys) while a frame is
//! denoised.

use std::sync::mpsc;
use std::thread::JoinHandle;
use std::time::Duration;

use crate::aov::AovImage;
use crate::denoise::{DenoiseOptions, Denoiser, Prefilter, Quality};
use crate::film::Film;
use anyhow::Context;

/// A frame to denoise: which view it belongs to and at how many samples.
struct Request {
    generation: u64,
    spp: u32,
    film: Film,
    aovs: AovImage,
}

/// A denoised frame.
pub struct Done {
    /// The view it belongs to (the viewer drops results of views it left).
    pub generation: u64,
    /// Samples per pixel of its input.
    pub spp: u32,
    /// The frame, or why OIDN failed.
    pub film: Result<Film, String>,
    /// How long denoising took.
    pub took: Duration,
}

/// The worker thread and its queues; one frame at a time.
pub struct Worker {
    requests: Option<mpsc::Sender<Request>>,
    results: mpsc::Receiver<Done>,
    thread: Option<JoinHandle<()>>,
    busy: bool,
    describe: String,
}

impl Worker {
    /// Loads OIDN (an error says how to install it) and starts the thread;
    /// `wake` is called from it when a frame is done.
    pub fn start(wake: impl Fn() + Send + 'static) -> anyhow::Result<Worker> {
        let options = DenoiseOptions {
            // All cores: the window's own refinement shares them.
            threads: 0,
            // OIDN's mode for interactive rendering: about half the time of
            // `High` at a small loss (measured in docs/denoising.md).
            quality: Quality::Balanced,
            // Never prefiltered (OIDN's advice for interactive use): at the
            // first frame's 2 spp it would triple the time (0.62 s against
            // 0.21 s for the helmet at 640×480).
            prefilter: Prefilter::Off,
            ..DenoiseOptions::default()
        };
        let mut denoiser = Denoiser::new(&options).context("--denoise")?;
        let describe = denoiser.describe();
        let (requests, inbox) = mpsc::channel::<Request>();
        let (outbox, results) = mpsc::channel();
        let thread = std::thread::Builder::new()
            .name("raylab-denoise".into())
            .spawn(move || {
                for r in inbox {
                    let film = denoiser
                        .denoise(&r.film, &r.aovs)
                        .map_err(|e| format!("{e}"));
                    let done = Done {
                        generation: r.generation,
                        spp: r.spp,
                        film,
                        took: denoiser.last_time(),
                    };
                    if outbox.send(done).is_err() {
                        return;
                    }
                    wake();
                }
            })
            .context("cannot start the denoising thread")?;
        Ok(Worker {
            requests: Some(requests),
            results,
            thread: Some(thread),
            busy: false,
            describe,
        })
    }

    /// What runs (`OIDN 2.5.1 on the CPU (all cores)`).
    pub fn describe(&self) -> &str {
        &self.describe
    }

    /// Whether a frame is being denoised.
    pub fn busy(&self) -> bool {
        self.busy
    }

    /// Hands a frame to the thread (the caller checks [`Worker::busy`]).
    pub fn submit(&mut self, generation: u64, spp: u32, film: Film, aovs: AovImage) {
        let request = Request {
            generation,
            spp,
            film,
            aovs,
        };
        if let Some(tx) = &self.requests
            && tx.send(request).is_ok()
        {
            self.busy = true;
        }
    }

    /// The frame the thread finished, if there is one.
    pub fn poll(&mut self) -> Option<Done> {
        let done = self.results.try_recv().ok()?;
        self.busy = false;
        Some(done)
    }
}

impl Drop for Worker {
    fn drop(&mut self) {
        // Closing the queue ends the thread after the frame in hand.
        self.requests = None;
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}
