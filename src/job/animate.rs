//! A glTF file's animation in a job: the options that pick an animation and
//! a moment (`--at`, `--animation`, `--fps`) and the time of each frame of an
//! animated file (`frame / fps` seconds; `session.rs` loads the file posed at
//! it).

use clap::Args;

use crate::load::gltf::{AnimationChoice, AnimationOptions};

/// Frames per second of `--frames` on an animated file without `--fps`.
pub const DEFAULT_FPS: f64 = 24.0;

pub use crate::load::gltf::{AT_EXPECTED, MAX_AT, MAX_FPS, at_in_range, fps_in_range};

/// The options that pose a glTF file's animation (part of
/// [`SceneOptions`](crate::job::SceneOptions)).
#[derive(Debug, Clone, Default, Args)]
pub struct AnimationArgs {
    /// glTF: render the animation (see --animation) at this moment, in
    /// seconds; times outside its keyframes take the first or last pose
    /// [default: the file's nodes as written, unanimated; with --frames,
    /// frame / --fps].
    #[arg(long, value_name = "SECONDS", allow_hyphen_values = true, value_parser = parse_at)]
    pub at: Option<f32>,
    /// glTF: which animation --at and --frames play, by index (from 0) or
    /// name [default: the first].
    #[arg(long, value_name = "N|NAME")]
    pub animation: Option<AnimationChoice>,
}

impl AnimationArgs {
    /// The loader's animation options.
    pub fn load_options(&self) -> AnimationOptions {
        AnimationOptions {
            animation: self.animation.clone(),
            time: self.at,
            if_animated: false,
        }
    }
}

fn parse_at(s: &str) -> Result<f32, String> {
    match s.trim().parse::<f32>() {
        Ok(v) if at_in_range(f64::from(v)) => Ok(v),
        _ => Err(AT_EXPECTED.to_string()),
    }
}

/// `--fps`: a frame rate above 0 and at most [`MAX_FPS`].
pub(super) fn parse_fps(s: &str) -> Result<f64, String> {
    match s.trim().parse::<f64>() {
        Ok(v) if fps_in_range(v) => Ok(v),
        _ => Err(format!(
            "expected frames per second above 0 and at most {MAX_FPS}"
        )),
    }
}

/// The time of `frame` at `fps` frames per second, in seconds.
pub fn frame_time(frame: u32, fps: f64) -> f32 {
    (f64::from(frame) / fps) as f32
}
