//! Writing a render's image: denoised or not, with its AOV layers and its
//! metadata, atomically.

use std::path::Path;
use std::time::Duration;

use anyhow::Context;

use crate::aov::{AovImage, AovSet};
use crate::denoise::Denoiser;
use crate::film::{Channel, Display, Film, Format, MetaValue, write_image_meta};
use crate::render::Accumulator;

/// A render's result as its file holds it: the image (denoised when a
/// denoiser was given), the noisy image beside a denoised one, and the AOVs
/// written as layers.
#[derive(Clone, Debug)]
pub struct Finished {
    /// The image (what a PNG shows and an EXR's RGB holds).
    pub image: Film,
    /// The image before denoising, when it was denoised (an EXR's `noisy`
    /// layer).
    pub noisy: Option<Film>,
    /// The AOVs asked for as layers (the denoiser's guides only when asked
    /// for).
    pub aovs: Option<AovImage>,
    /// How long denoising took, when the image was denoised.
    pub denoise_time: Option<Duration>,
}

/// The result of `acc` (a whole render, or the merge of its parts):
/// denoised by `denoiser` if given, with the AOVs of `layers`.
pub fn finish(
    acc: &Accumulator,
    layers: AovSet,
    denoiser: Option<&mut Denoiser>,
) -> anyhow::Result<Finished> {
    let mut rendered = acc.rendered();
    let aovs = rendered.aovs.take();
    let mut noisy = None;
    let mut took = None;
    let image = match denoiser {
        Some(d) => {
            let guides = aovs
                .as_ref()
                .ok_or(crate::denoise::DenoiseError::MissingAov(
                    crate::aov::Aov::Albedo,
                ))?;
            let clean = d
                .denoise(&rendered.film, guides)
                .context("cannot denoise")?;
            took = Some(d.last_time());
            noisy = Some(rendered.film);
            clean
        }
        None => rendered.film,
    };
    let aovs = aovs.map(|a| AovImage {
        layers: a
            .layers
            .into_iter()
            .filter(|l| layers.contains(l.aov))
            .collect(),
        ..a
    });
    Ok(Finished {
        image,
        noisy,
        aovs,
        denoise_time: took,
    })
}

/// Writes the image of `acc` (a whole render, or the merge of its parts) to
/// `output`: denoised by `denoiser` if given (the noisy image then goes into
/// an EXR as the layer `noisy`), with the AOVs of `layers` as layers and the
/// `metadata` of what it is (given whether the image is denoised). Returns
/// how long denoising took.
pub fn write_result(
    acc: &Accumulator,
    output: &Path,
    display: Display,
    layers: AovSet,
    denoiser: Option<&mut Denoiser>,
    metadata: impl FnOnce(bool) -> [(String, MetaValue); 2],
) -> anyhow::Result<Option<Duration>> {
    let exr = Format::from_path(output)? == Format::Exr;
    let finished = finish(acc, layers, denoiser)?;
    let mut channels = Vec::new();
    if exr && let Some(noisy) = &finished.noisy {
        channels.extend(noisy_channels(noisy));
    }
    // The AOVs asked for as EXR planes; they and the image are written,
    // then freed.
    if let Some(a) = finished.aovs {
        channels.extend(a.into_channels());
    }
    // The samples taken as a number any EXR tool shows, and the rest as
    // text (see `write_image_meta` for why two attributes).
    let took = finished.denoise_time;
    let metadata = metadata(took.is_some());
    write_image_meta(&finished.image, channels, output, display, &metadata)?;
    Ok(took)
}

/// The summary line's `; denoised in 152.3 ms by OIDN ...`.
pub fn denoised_clause(took: Duration, denoiser: &Denoiser) -> String {
    format!(
        "; denoised in {:.1} ms by {}",
        took.as_secs_f64() * 1e3,
        denoiser.describe()
    )
}

/// The noisy image as the EXR layer `noisy` (`noisy.R`, `noisy.G`, `noisy.B`).
fn noisy_channels(film: &Film) -> [Channel; 3] {
    let plane = |c: usize| film.pixels.iter().map(|p| p[c]).collect();
    ["R", "G", "B"]
        .into_iter()
        .enumerate()
        .map(|(c, name)| Channel {
            name: format!("noisy.{name}"),
            values: plane(c),
        })
        .collect::<Vec<_>>()
        .try_into()
        .expect("three channels")
}
