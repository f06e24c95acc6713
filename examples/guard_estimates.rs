//! The denoiser's guard, looked at: its estimated errors beside the true ones.
//!
//! `cargo run --release --example guard_estimates -- REFERENCE.exr OUT.png -- RENDER ARGS...`
//! renders a scene as `raylab render RENDER ARGS...` does (with the
//! denoiser's AOVs), denoises it, and writes a picture of five panels, each
//! pixel the mean over the guard's window around it, relative to the pixel's
//! value as the guard measures it (`raylab::denoise::blend`), on one log
//! scale (black 10⁻⁴ or below, negative estimates too; white 1), after the
//! guarded image itself:
//!
//! 1. the noisy half's error as the guard estimates it, from the two halves
//!    of the samples alone;
//! 2. the same, true (against REFERENCE, a render of the same scene, size
//!    and camera with many samples);
//! 3. the denoised half's error as the guard estimates it;
//! 4. the same, true;
//! 5. the guard's weight of the denoised image (white: denoised, black:
//!    noisy).
//!
//! Needs Open Image Denoise (as `--denoise`). For example, the picture in
//! docs/denoising.md:
//!
//! ```text
//! raylab render scenes/glass-lamps/glass-lamps.gltf --width 320 --height 240 --spp 4096 \
//!     --default-light off -o ref.exr
//! cargo run --release --example guard_estimates -- ref.exr docs/guard-estimates.png -- \
//!     scenes/glass-lamps/glass-lamps.gltf --width 320 --height 240 --spp 64 --default-light off
//! ```

use anyhow::{Context, bail};
use clap::Parser;
use raylab::denoise::{DenoiseOptions, Denoiser, blend};
use raylab::job::{Hooks, Job, JobOptions};

#[derive(Parser)]
struct Render {
    #[command(flatten)]
    options: JobOptions,
}

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().collect();
    let split = args.iter().position(|a| a == "--");
    let (Some(split), [_, reference, out, ..]) = (split, args.as_slice()) else {
        bail!("usage: guard_estimates REFERENCE.exr OUT.png -- RENDER ARGS...");
    };
    let render_args =
        std::iter::once("render".to_string()).chain(args[split + 1..].iter().cloned());
    let mut options = Render::try_parse_from(render_args)?.options;
    options.aov = Some(raylab::denoise::GUIDES);
    options.scene.denoise = Some(false);
    options.quiet = true;
    let rendered = Job::new(options)?.render_with(&Hooks::default())?;
    let (noisy, aovs) = (&rendered.finished.image, rendered.finished.aovs.as_ref());
    let aovs = aovs.context("the render has no AOVs")?;
    let truth = raylab::film::read_exr(std::path::Path::new(reference))
        .with_context(|| format!("cannot read {reference}"))?;
    if (truth.width, truth.height) != (noisy.width, noisy.height) {
        bail!(
            "{reference} is {}×{}, the render {}×{}",
            truth.width,
            truth.height,
            noisy.width,
            noisy.height
        );
    }
    let mut denoiser = Denoiser::new(&DenoiseOptions::default())?;
    let guarded = denoiser.denoise_guarded(noisy, aovs)?;
    let check = guarded
        .check
        .context("one sample per pixel: the guard has no halves")?;
    let (est_noisy, est_denoised) =
        blend::estimates(&guarded.denoised, &check.halves, &check.denoised_half);
    let half_a = raylab::film::Film {
        width: noisy.width,
        height: noisy.height,
        pixels: check
            .halves
            .iter()
            .zip(&noisy.pixels)
            .map(|(h, x)| h.map_or(*x, |h| h.0))
            .collect(),
    };
    let true_noisy = blend::true_error(&half_a, &truth, &guarded.denoised, &check.halves);
    let true_denoised = blend::true_error(
        &check.denoised_half,
        &truth,
        &guarded.denoised,
        &check.halves,
    );
    let weights: Vec<f64> = guarded
        .weights
        .unwrap_or_default()
        .iter()
        .map(|&w| f64::from(w))
        .collect();
    let (w, h) = (noisy.width as usize, noisy.height as usize);
    let gap = 4;
    let panels: [(&[f64], bool); 5] = [
        (&est_noisy, true),
        (&true_noisy, true),
        (&est_denoised, true),
        (&true_denoised, true),
        (&weights, false),
    ];
    let width = (panels.len() + 1) * w + panels.len() * gap;
    let mut picture =
        image::RgbImage::from_pixel(width as u32, h as u32, image::Rgb([255, 255, 255]));
    // The guarded image, tone mapped as glTF scenes are shown.
    let display = raylab::film::Display {
        scale: 1.0,
        tonemap: raylab::film::ToneMap::KhronosPbrNeutral,
    };
    let shown = guarded.image.to_srgb8(display);
    for (i, rgb) in shown.chunks_exact(3).enumerate() {
        picture.put_pixel(
            (i % w) as u32,
            (i / w) as u32,
            image::Rgb([rgb[0], rgb[1], rgb[2]]),
        );
    }
    for (k, (values, log)) in panels.iter().enumerate() {
        let k = k + 1;
        for (i, &v) in values.iter().enumerate() {
            let t = if *log {
                ((v.max(1e-12).log10() + 4.0) / 4.0).clamp(0.0, 1.0)
            } else {
                v.clamp(0.0, 1.0)
            };
            let g = (t * 255.0).round() as u8;
            let (x, y) = (i % w, i / w);
            picture.put_pixel((k * (w + gap) + x) as u32, y as u32, image::Rgb([g, g, g]));
        }
    }
    picture
        .save(out)
        .with_context(|| format!("cannot write {out}"))?;
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len().max(1) as f64;
    println!(
        "mean relative error, noisy half: estimated {:.3e}, true {:.3e}; denoised half: estimated {:.3e}, true {:.3e}; mean weight {:.2}",
        mean(&est_noisy),
        mean(&true_noisy),
        mean(&est_denoised),
        mean(&true_denoised),
        mean(&weights)
    );
    println!("wrote {out}");
    Ok(())
}
