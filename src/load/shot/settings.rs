//! The `[render]` section checked into [`ShotSettings`]: what the command
//! line leaves out is taken from here, and [`read_settings`] reads it without
//! loading the models.

use std::path::Path;

use super::error::{ShotError, check, invalid};
use super::schema::{RenderSection, parse};
use crate::film::ToneMap;
use crate::integrators::Integrator;

/// Render settings from a scene file, checked: what the command line does not
/// give is taken from here.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ShotSettings {
    /// Image width.
    pub width: Option<u32>,
    /// Image height.
    pub height: Option<u32>,
    /// Samples per pixel.
    pub spp: Option<u32>,
    /// Seconds to render for.
    pub time: Option<f64>,
    /// Adaptive sampling's noise threshold.
    pub noise_threshold: Option<f32>,
    /// Seed.
    pub seed: Option<u64>,
    /// Integrator (with `max_depth` applied).
    pub integrator: Option<Integrator>,
    /// Longest path.
    pub max_depth: Option<u32>,
    /// Pixel filter (Mitsuba scenes' `rfilter`).
    pub filter: Option<crate::sampling::filter::PixelFilter>,
    /// Tone mapping.
    pub tonemap: Option<ToneMap>,
    /// Exposure in stops.
    pub exposure: Option<f32>,
    /// Denoise the image.
    pub denoise: Option<bool>,
    /// The animations' moment in seconds.
    pub at: Option<f32>,
    /// Frames per second of `--frames`.
    pub fps: Option<f64>,
    /// A `[[medium]] type = "fog"` (checked): extinction per scene unit,
    /// albedo and phase function ([`crate::Scene::add_fog_with`]).
    pub fog: Option<(glam::Vec3A, glam::Vec3A, crate::media::Phase)>,
}

/// Reads only a scene file's `[render]` settings (checked), without loading
/// its models: what a program needs to know before it loads the scene.
pub fn read_settings(path: &Path) -> Result<ShotSettings, ShotError> {
    let text = std::fs::read_to_string(path).map_err(|cause| ShotError::Io {
        path: path.to_owned(),
        cause,
    })?;
    settings(path, &parse(&text, path)?.render)
}

/// The `[render]` section checked.
pub(super) fn settings(path: &Path, r: &RenderSection) -> Result<ShotSettings, ShotError> {
    let bad = |m: String| invalid(path, format!("[render] {m}"));
    use crate::limits::{MAX_PIXELS, MAX_SIDE, MAX_SPP, MAX_TIME};
    for (key, v) in [("width", r.width), ("height", r.height)] {
        if let Some(v) = v
            && !(1..=MAX_SIDE).contains(&v)
        {
            return Err(bad(format!("{key} = {v}: expected 1 to {MAX_SIDE} pixels")));
        }
    }
    if let (Some(w), Some(h)) = (r.width, r.height)
        && u64::from(w) * u64::from(h) > MAX_PIXELS
    {
        return Err(bad(format!(
            "width × height = {w} × {h}: expected at most {MAX_PIXELS} pixels"
        )));
    }
    if let Some(spp) = r.spp
        && !(1..=MAX_SPP).contains(&spp)
    {
        return Err(bad(format!("spp = {spp}: expected 1 to {MAX_SPP}")));
    }
    if let Some(t) = r.time
        && !(t > 0.0 && t <= MAX_TIME)
    {
        return Err(bad(format!(
            "time = {t:?}: expected seconds > 0 and at most {MAX_TIME}"
        )));
    }
    if let Some(t) = r.noise_threshold
        && !(t > 0.0 && t <= 1.0)
    {
        return Err(bad(format!(
            "noise_threshold = {t:?}: expected a threshold above 0 and at most 1 (e.g. 0.01)"
        )));
    }
    if r.max_depth == Some(0) {
        return Err(bad("max_depth = 0: expected at least 1".into()));
    }
    if let Some(e) = r.exposure {
        check(path, "[render] exposure", &[e], false)?;
    }
    use crate::load::gltf::{AT_EXPECTED, MAX_FPS, at_in_range, fps_in_range};
    if let Some(at) = r.at
        && !at_in_range(at)
    {
        return Err(bad(format!("at = {at:?}: {AT_EXPECTED}")));
    }
    if let Some(fps) = r.fps
        && !fps_in_range(fps)
    {
        return Err(bad(format!(
            "fps = {fps:?}: expected frames per second above 0 and at most {}",
            MAX_FPS
        )));
    }
    let integrator = r
        .integrator
        .as_deref()
        .map(|s| {
            s.parse::<Integrator>()
                .map_err(|e| bad(format!("integrator: {e}")))
        })
        .transpose()?;
    let integrator = integrator.map(|i| match (i.path_options(), r.max_depth) {
        (Some(mut o), Some(d)) => {
            o.max_depth = d;
            i.with_path_options(o)
        }
        _ => i,
    });
    let tonemap = r
        .tonemap
        .as_deref()
        .map(|s| {
            s.parse::<ToneMap>()
                .map_err(|e| bad(format!("tonemap: {e}")))
        })
        .transpose()?;
    Ok(ShotSettings {
        width: r.width,
        height: r.height,
        spp: r.spp,
        time: r.time,
        noise_threshold: r.noise_threshold,
        seed: r.seed,
        integrator,
        max_depth: r.max_depth,
        filter: None,
        fog: None,
        tonemap,
        exposure: r.exposure,
        denoise: r.denoise,
        at: r.at.map(|t| t as f32),
        fps: r.fps,
    })
}
