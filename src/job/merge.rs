//! `raylab merge`: the parts of a split render into its image, written as
//! the whole render's job writes it.

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use anyhow::Context;

use super::write::{denoised_clause, write_result};
use crate::denoise::{DenoiseOptions, Denoiser};
use crate::film::Format;
use crate::memory::MemoryBudget;

/// How to merge parts.
#[derive(Clone, Debug, Default)]
pub struct MergeOptions {
    /// Most memory the merge may take [default: the machine's, see
    /// [`MemoryBudget::machine_default`]].
    pub max_memory: Option<MemoryBudget>,
    /// Denoise the merged image: `Some(true)` always (the parts must carry
    /// the guides), `Some(false)` never, `None` as the parts were rendered.
    pub denoise: Option<bool>,
}

/// What a merge made.
#[derive(Clone, Debug)]
pub struct MergeReport {
    /// The image's width and height.
    pub size: (u32, u32),
    /// Samples per pixel of the whole render.
    pub spp: u32,
    /// Rays the parts traced.
    pub rays: u64,
    /// NaN or infinite samples the parts dropped.
    pub dropped: u64,
    /// Time spent denoising, if the image was denoised.
    pub denoise_time: Option<Duration>,
    /// The summary line `raylab merge` prints.
    pub summary: String,
}

/// Merges the parts at `parts` (`raylab render --tile/--samples` outputs of
/// one render) into `output`, which is then the file the whole render
/// writes, byte for byte; denoised as `options` say.
pub fn merge(
    parts: &[PathBuf],
    output: &Path,
    options: &MergeOptions,
) -> anyhow::Result<MergeReport> {
    let start = Instant::now();
    Format::from_path(output)?;
    // As a job with `denoise`: the library first, before the work (when the
    // parts ask for it, once they are read).
    let load = || Denoiser::new(&DenoiseOptions::default()).context("--denoise");
    let mut denoiser = match options.denoise {
        Some(true) => Some(load()?),
        _ => None,
    };
    let budget = options
        .max_memory
        .unwrap_or_else(MemoryBudget::machine_default);
    let merged = crate::farm::merge_within(parts, &budget)?;
    let r = &merged.render;
    let denoise = options.denoise.unwrap_or(r.denoise);
    if denoise && !merged.acc.aov_set().includes(crate::denoise::GUIDES) {
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
        crate::farm::image_metadata(r.spp, Some(r.spp), r.seed, &r.integrator, false, denoised)
    };
    let denoise_time = write_result(
        &merged.acc,
        output,
        r.display,
        r.layers,
        denoiser.as_mut(),
        metadata,
    )?;
    let clause = match (denoise_time, &denoiser) {
        (Some(t), Some(d)) => denoised_clause(t, d),
        _ => String::new(),
    };
    let (size, tally) = (
        (merged.acc.width(), merged.acc.height()),
        merged.acc.tally(),
    );
    // Adaptive sampling's parts count each pixel's samples.
    let spp = match merged.acc.sample_counts() {
        Some(_) => format!("{} spp, {:.1} spp on average", r.spp, merged.acc.mean_spp()),
        None => format!("{} spp", r.spp),
    };
    let summary = format!(
        "merged {} parts into {}: {}x{}, {spp}, {} rays, {} NaN/Inf samples dropped, {:.1} ms{clause}",
        parts.len(),
        output.display(),
        size.0,
        size.1,
        tally.rays,
        tally.dropped,
        start.elapsed().as_secs_f64() * 1e3
    );
    Ok(MergeReport {
        size,
        spp: r.spp,
        rays: tally.rays,
        dropped: tally.dropped,
        denoise_time,
        summary,
    })
}
