//! Helpers of the glTF animation tests (`tests/animation.rs`,
//! `tests/gltf_animation_pointer.rs`): loading a file posed at a moment,
//! float accessors of keyframes, and writing a built or edited file. Include
//! it with `#[path = "common/gltf_animation.rs"] mod anim;` beside
//! `common/gltf_builder.rs` as `mod builder`.

use std::ops::{Add, Mul};
use std::path::{Path, PathBuf};

use raylab::load::gltf::{AnimationChoice, AnimationOptions};
use raylab::load::{LoadOptions, Loaded};
use serde_json::{Value, json};

use super::builder::{F32, Gltf, base64, write_json};

/// Loads `path` posed by `animation` (by index or name) at `time`, as
/// `--animation` and `--at` do; the error as its message.
pub fn load_at(path: &Path, animation: Option<&str>, time: Option<f32>) -> Result<Loaded, String> {
    let options = LoadOptions {
        animation: AnimationOptions {
            animation: animation.map(|a| a.parse::<AnimationChoice>().unwrap()),
            time,
            if_animated: false,
        },
        ..LoadOptions::default()
    };
    raylab::load::load(path.to_str().unwrap(), &options).map_err(|e| e.to_string())
}

/// [`load_at`] of a file that must load.
pub fn posed(path: &Path, animation: Option<&str>, time: Option<f32>) -> Loaded {
    load_at(path, animation, time).unwrap_or_else(|e| panic!("{e}"))
}

/// A float accessor of `components` per element over `values`.
pub fn floats(g: &mut Gltf, values: &[f32], components: usize) -> usize {
    let bytes: Vec<u8> = values.iter().flat_map(|x| x.to_le_bytes()).collect();
    let view = g.view(&bytes, None);
    let kind = ["SCALAR", "VEC2", "VEC3", "VEC4"][components - 1];
    g.accessor(json!({
        "bufferView": view, "componentType": F32,
        "count": values.len() / components, "type": kind,
    }))
}

/// Writes `g` with `extra` (animations, skins, ...) merged into its JSON.
pub fn write_with(g: &Gltf, dir: &Path, name: &str, extra: Value) -> PathBuf {
    let uri = format!("data:application/octet-stream;base64,{}", base64(&g.buffer));
    let mut root = g.to_json(Some(uri));
    for (k, v) in extra.as_object().unwrap() {
        root[k] = v.clone();
    }
    write_json(dir, name, &root)
}

/// `path`'s JSON changed by `edit` and written as `name` beside it.
pub fn edited(path: &Path, name: &str, edit: impl FnOnce(&mut Value)) -> PathBuf {
    let mut root: Value = serde_json::from_slice(&std::fs::read(path).unwrap()).unwrap();
    edit(&mut root);
    write_json(path.parent().unwrap(), name, &root)
}

/// A hand-written cubic Hermite segment (glTF 2.0, Appendix C): from `v0`
/// with out-tangent `b0` to `v1` with in-tangent `a1`, keyframes `dt` apart,
/// at `s` in [0, 1] (of numbers or vectors).
pub fn hermite<T: Mul<f32, Output = T> + Add<Output = T>>(
    v0: T,
    b0: T,
    v1: T,
    a1: T,
    dt: f32,
    s: f32,
) -> T {
    let (s2, s3) = (s * s, s * s * s);
    v0 * (2.0 * s3 - 3.0 * s2 + 1.0)
        + b0 * ((s3 - 2.0 * s2 + s) * dt)
        + v1 * (-2.0 * s3 + 3.0 * s2)
        + a1 * ((s3 - s2) * dt)
}
