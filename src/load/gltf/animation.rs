//! glTF animations sampled at one moment: which animation (by index or
//! name), its channels read and checked, and the pose they give at a time —
//! the nodes' translations, rotations and scales and the morph-target
//! weights that replace those of the file.
//!
//! Interpolation follows the glTF 2.0 specification and its Appendix C:
//! `STEP` holds a keyframe's value until the next one; `LINEAR` interpolates
//! component-wise, and rotations by spherical linear interpolation along the
//! shorter arc; `CUBICSPLINE` is the cubic Hermite spline through the
//! keyframes with their in- and out-tangents scaled by the keyframe interval
//! (rotations normalized after). A time before the first keyframe takes the
//! first value, one after the last keyframe the last value.
//!
//! Keyframe times must be finite, at least 0 and strictly increasing (as the
//! specification says): a file whose chosen animation breaks this is refused
//! with one line naming the animation and the sampler.

use std::collections::HashMap;

use glam::{Quat, Vec3};
use gltf::json;

use super::accessor::{read_floats, type_components};
use super::buffers::Buffers;
use super::error::{GltfError, valid};

/// Longest time `--at` (or a scene file's `at`) takes, in seconds (a day).
pub const MAX_AT: f32 = 86_400.0;

/// Most frames per second `--fps` (or a scene file's `fps`) takes.
pub const MAX_FPS: f64 = 10_000.0;

/// What `--at` (and a scene file's `at`) takes.
pub const AT_EXPECTED: &str = "expected a time in seconds from 0 to 86400";

/// Whether `v` seconds is a moment `--at` takes (0 to [`MAX_AT`]).
pub fn at_in_range(v: f64) -> bool {
    (0.0..=f64::from(MAX_AT)).contains(&v)
}

/// Whether `v` is a frame rate `--fps` takes (above 0, at most [`MAX_FPS`]).
pub fn fps_in_range(v: f64) -> bool {
    v > 0.0 && v <= MAX_FPS
}

/// Which of a file's animations to play.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum AnimationChoice {
    /// The animation at this index of the file's `animations` (from 0).
    Index(usize),
    /// The animation of this name.
    Name(String),
}

impl std::str::FromStr for AnimationChoice {
    type Err = String;

    /// A whole number is an index, anything else a name.
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        if s.is_empty() {
            return Err("expected an animation's index (from 0) or name".into());
        }
        Ok(match s.parse::<usize>() {
            Ok(i) => Self::Index(i),
            Err(_) => Self::Name(s.to_string()),
        })
    }
}

impl std::fmt::Display for AnimationChoice {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::Index(i) => write!(f, "{i}"),
            Self::Name(n) => write!(f, "'{}'", crate::guard::one_line(n)),
        }
    }
}

/// When and what to pose a glTF file at. The default poses nothing: the
/// nodes as the file writes them.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct AnimationOptions {
    /// The animation (default: the first, when `time` is given).
    pub animation: Option<AnimationChoice>,
    /// The moment in seconds (default: 0 when `animation` is given; with
    /// neither, the file's own pose).
    pub time: Option<f32>,
    /// Whether a file without animations is left as written rather than
    /// refused (a scene file's moment poses the models that have
    /// animations).
    pub if_animated: bool,
}

impl AnimationOptions {
    /// Whether anything is asked of the file's animations.
    pub fn is_given(&self) -> bool {
        self.animation.is_some() || self.time.is_some()
    }
}

/// What an animation channel changes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Property {
    /// A node's translation (3 values).
    Translation,
    /// A node's rotation (a quaternion x, y, z, w).
    Rotation,
    /// A node's scale (3 values).
    Scale,
    /// A node's morph-target weights (one value per target).
    Weights,
}

/// How values between keyframes are found.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Interpolation {
    /// The previous keyframe's value.
    Step,
    /// Straight lines (rotations: slerp on the shorter arc).
    Linear,
    /// Cubic Hermite splines with the keyframes' tangents.
    CubicSpline,
}

/// One channel with its keyframes: what it animates and its values.
#[derive(Clone, Debug)]
pub(crate) struct Track {
    /// The node animated.
    pub node: usize,
    /// What of it.
    pub property: Property,
    /// How values between keyframes are found.
    pub interpolation: Interpolation,
    /// Keyframe times in seconds: finite, ≥ 0, strictly increasing, at
    /// least one.
    pub times: Vec<f32>,
    /// Values per keyframe (`width` of them; with `CubicSpline` three groups
    /// of `width`: in-tangent, value, out-tangent).
    pub values: Vec<f32>,
    /// Values per element: 3, 4 (a rotation) or the number of morph targets.
    pub width: usize,
}

impl Track {
    /// The element of keyframe `k` (for `CubicSpline`, group `part` of it:
    /// 0 the in-tangent, 1 the value, 2 the out-tangent).
    fn element(&self, k: usize, part: usize) -> &[f32] {
        let groups = if self.interpolation == Interpolation::CubicSpline {
            3
        } else {
            1
        };
        let part = if groups == 3 { part } else { 0 };
        let start = (k * groups + part) * self.width;
        &self.values[start..start + self.width]
    }

    /// The value at time `t` (clamped to the keyframes' span): `width`
    /// numbers, a rotation's normalized.
    pub fn sample(&self, t: f32) -> Vec<f32> {
        let last = self.times.len() - 1;
        // Before the first or at or after the last keyframe: its value.
        if t.is_nan() || t <= self.times[0] {
            return self.finish(self.element(0, 1).to_vec());
        }
        if t >= self.times[last] {
            return self.finish(self.element(last, 1).to_vec());
        }
        // times[k] <= t < times[k + 1].
        let k = self.times.partition_point(|&x| x <= t) - 1;
        let interval = self.times[k + 1] - self.times[k];
        let s = (t - self.times[k]) / interval;
        let value = match self.interpolation {
            Interpolation::Step => self.element(k, 1).to_vec(),
            Interpolation::Linear if self.property == Property::Rotation => {
                let q = slerp(quat(self.element(k, 1)), quat(self.element(k + 1, 1)), s);
                q.to_array().to_vec()
            }
            Interpolation::Linear => {
                let (a, b) = (self.element(k, 1), self.element(k + 1, 1));
                a.iter().zip(b).map(|(&a, &b)| a + (b - a) * s).collect()
            }
            Interpolation::CubicSpline => {
                let (v0, out0) = (self.element(k, 1), self.element(k, 2));
                let (in1, v1) = (self.element(k + 1, 0), self.element(k + 1, 1));
                (0..self.width)
                    .map(|c| hermite(v0[c], interval * out0[c], v1[c], interval * in1[c], s))
                    .collect()
            }
        };
        self.finish(value)
    }

    /// A rotation normalized (a zero quaternion: the identity); other values
    /// as they are.
    fn finish(&self, mut value: Vec<f32>) -> Vec<f32> {
        if self.property == Property::Rotation {
            let q = quat(&value);
            let q = if q.length_squared() > 0.0 && q.is_finite() {
                q.normalize()
            } else {
                Quat::IDENTITY
            };
            value = q.to_array().to_vec();
        }
        value
    }
}

/// The quaternion of four values x, y, z, w.
fn quat(v: &[f32]) -> Quat {
    Quat::from_xyzw(v[0], v[1], v[2], v[3])
}

/// The cubic Hermite spline from `p0` (tangent `m0`) to `p1` (tangent `m1`)
/// at `s` in [0, 1], the tangents already scaled by the keyframe interval
/// (glTF 2.0, Appendix C).
pub(crate) fn hermite(p0: f32, m0: f32, p1: f32, m1: f32, s: f32) -> f32 {
    let (s2, s3) = (s * s, s * s * s);
    (2.0 * s3 - 3.0 * s2 + 1.0) * p0
        + (s3 - 2.0 * s2 + s) * m0
        + (-2.0 * s3 + 3.0 * s2) * p1
        + (s3 - s2) * m1
}

/// Spherical linear interpolation from `a` to `b` at `s` along the shorter
/// arc (`b` negated when the two are more than half a turn apart), the result
/// normalized. Nearly equal rotations are interpolated linearly, where the
/// slerp's division by sin θ would lose precision.
pub(crate) fn slerp(a: Quat, b: Quat, s: f32) -> Quat {
    let (a, b) = (a.normalize(), b.normalize());
    let mut dot = a.dot(b);
    let b = if dot < 0.0 {
        dot = -dot;
        -b
    } else {
        b
    };
    if dot > 0.9995 {
        return (a + (b - a) * s).normalize();
    }
    let theta = dot.min(1.0).acos();
    let sin = theta.sin();
    let q = a * (((1.0 - s) * theta).sin() / sin) + b * ((s * theta).sin() / sin);
    q.normalize()
}

/// The nodes' transforms and weights an animation gives at one moment; what
/// it leaves out is the file's.
#[derive(Clone, Debug, Default)]
pub(crate) struct Pose {
    /// Translations by node.
    pub translation: HashMap<usize, Vec3>,
    /// Rotations by node (normalized).
    pub rotation: HashMap<usize, Quat>,
    /// Scales by node.
    pub scale: HashMap<usize, Vec3>,
    /// Morph-target weights by node.
    pub weights: HashMap<usize, Vec<f32>>,
}

/// One animation's name and span, for listing a file's animations.
#[derive(Clone, Debug, PartialEq)]
pub struct AnimationSummary {
    /// Its name in the file (empty if none).
    pub name: String,
    /// Its last keyframe's time in seconds.
    pub duration: f32,
}

/// A name for animation `i` in messages: `0 'Walk'` or `0`.
pub(crate) fn label(root: &json::Root, i: usize) -> String {
    match root.animations[i].name.as_deref() {
        Some(n) if !n.is_empty() => format!("{i} '{}'", crate::guard::one_line(n)),
        _ => i.to_string(),
    }
}

/// The index of the animation `options` choose in `root`, if any is asked.
/// An unknown index or name is an error listing the file's animations and
/// their durations; asking anything of a file without animations is one too.
pub(crate) fn chosen(
    root: &json::Root,
    buffers: &Buffers,
    options: &AnimationOptions,
) -> Result<Option<usize>, GltfError> {
    if !options.is_given() {
        return Ok(None);
    }
    if root.animations.is_empty() {
        if options.if_animated {
            return Ok(None);
        }
        let what = match (&options.animation, options.time) {
            (Some(a), _) => format!("--animation {a}"),
            (None, Some(t)) => format!("--at {t}"),
            (None, None) => unreachable!("is_given"),
        };
        return Err(GltfError::invalid(format!(
            "{what}: the file has no animations"
        )));
    }
    let found = match &options.animation {
        None => Some(0),
        Some(AnimationChoice::Index(i)) => (*i < root.animations.len()).then_some(*i),
        Some(AnimationChoice::Name(n)) => root
            .animations
            .iter()
            .position(|a| a.name.as_deref() == Some(n.as_str())),
    };
    if let Some(i) = found {
        return Ok(Some(i));
    }
    let mut listed = Vec::new();
    for (i, summary) in summaries(root, buffers)?.iter().enumerate() {
        listed.push(format!("{} ({} s)", label(root, i), summary.duration));
    }
    let asked = options.animation.as_ref().expect("found without a choice");
    Err(GltfError::invalid(format!(
        "--animation {asked}: no such animation; the file has {}",
        listed.join(", ")
    )))
}

/// Every animation's name and duration (reading each sampler's times).
pub(crate) fn summaries(
    root: &json::Root,
    buffers: &Buffers,
) -> Result<Vec<AnimationSummary>, GltfError> {
    let mut out = Vec::with_capacity(root.animations.len().min(1024));
    for (a, animation) in root.animations.iter().enumerate() {
        let mut duration = 0.0f32;
        for s in 0..animation.samplers.len() {
            let times = times(root, buffers, a, s)?;
            duration = duration.max(*times.last().expect("times are never empty"));
        }
        out.push(AnimationSummary {
            name: animation.name.clone().unwrap_or_default(),
            duration,
        });
    }
    Ok(out)
}

/// The checked keyframe times of sampler `s` of animation `a`.
pub(crate) fn times(
    root: &json::Root,
    buffers: &Buffers,
    a: usize,
    s: usize,
) -> Result<Vec<f32>, GltfError> {
    let what = format!("animation {} sampler {s}", label(root, a));
    let sampler = &root.animations[a].samplers[s];
    let input = sampler.input.value();
    if components(root, input) != Some(1) {
        return Err(GltfError::invalid(format!(
            "{what}: input accessor {input} must hold scalar times"
        )));
    }
    let times: Vec<f32> = read_floats::<1>(buffers, input, &format!("{what} input"))?
        .into_iter()
        .map(|[t]| t)
        .collect();
    if times.is_empty() {
        return Err(GltfError::invalid(format!("{what} has no keyframes")));
    }
    for (k, &t) in times.iter().enumerate() {
        if !t.is_finite() || t < 0.0 {
            return Err(GltfError::invalid(format!(
                "{what}: keyframe time {k} is {t} (times must be finite and >= 0)"
            )));
        }
        if k > 0 && t <= times[k - 1] {
            return Err(GltfError::invalid(format!(
                "{what}: keyframe time {k} ({t}) is not after time {} ({}): times must increase",
                k - 1,
                times[k - 1]
            )));
        }
    }
    Ok(times)
}

/// Components per element of accessor `index`, if it exists and is valid.
pub(crate) fn components(root: &json::Root, index: usize) -> Option<usize> {
    let acc = root.accessors.get(index)?;
    valid(&acc.type_).map(|t| type_components(*t))
}

/// The number of morph targets node `node`'s mesh has (its first
/// primitive's), if it has a mesh.
pub(crate) fn morph_targets(root: &json::Root, node: usize) -> Option<usize> {
    let mesh = root.nodes.get(node)?.mesh?.value();
    let prim = root.meshes.get(mesh)?.primitives.first()?;
    Some(prim.targets.as_ref().map_or(0, |t| t.len()))
}

/// Reads animation `a`'s channels, checking every reference, count and
/// time. Channels of a path raylab does not know (an extension's) are
/// skipped with a warning in `warnings`.
pub(crate) fn tracks(
    root: &json::Root,
    buffers: &Buffers,
    a: usize,
    warnings: &mut Vec<String>,
) -> Result<Vec<Track>, GltfError> {
    use json::animation::Property as P;
    let animation = &root.animations[a];
    let name = label(root, a);
    let mut out = Vec::with_capacity(animation.channels.len().min(1 << 16));
    for (c, channel) in animation.channels.iter().enumerate() {
        let what = format!("animation {name} channel {c}");
        let s = channel.sampler.value();
        let sampler = animation
            .samplers
            .get(s)
            .ok_or_else(|| GltfError::invalid(format!("{what}: sampler {s} does not exist")))?;
        let node = channel.target.node.value();
        let target = root
            .nodes
            .get(node)
            .ok_or_else(|| GltfError::invalid(format!("{what}: node {node} does not exist")))?;
        let Some(path) = valid(&channel.target.path) else {
            let warning = format!("animation {name}: skipping channels of unknown target paths");
            if !warnings.contains(&warning) {
                warnings.push(warning);
            }
            continue;
        };
        let property = match path {
            P::Translation => Property::Translation,
            P::Rotation => Property::Rotation,
            P::Scale => Property::Scale,
            P::MorphTargetWeights => Property::Weights,
        };
        if property != Property::Weights && target.matrix.is_some() {
            return Err(GltfError::invalid(format!(
                "{what}: node {node} has a matrix, and glTF animates only nodes given by translation, rotation and scale"
            )));
        }
        let interpolation = interpolation_of(sampler, s, &what)?;
        let times = times(root, buffers, a, s)?;
        let output = sampler.output.value();
        let out_what = format!("{what} output");
        let (width, values) = match property {
            Property::Translation | Property::Scale => {
                expect_components(root, output, 3, &out_what)?;
                let v = read_floats::<3>(buffers, output, &out_what)?;
                (3, v.into_iter().flatten().collect::<Vec<f32>>())
            }
            Property::Rotation => {
                expect_components(root, output, 4, &out_what)?;
                let v = read_floats::<4>(buffers, output, &out_what)?;
                (4, v.into_iter().flatten().collect())
            }
            Property::Weights => {
                expect_components(root, output, 1, &out_what)?;
                let Some(targets) = morph_targets(root, node).filter(|&t| t > 0) else {
                    return Err(GltfError::invalid(format!(
                        "{what}: animates the weights of node {node}, whose mesh has no morph targets"
                    )));
                };
                let v = read_floats::<1>(buffers, output, &out_what)?;
                (targets, v.into_iter().flatten().collect())
            }
        };
        check_output(&out_what, &values, times.len(), interpolation, width)?;
        out.push(Track {
            node,
            property,
            interpolation,
            times,
            values,
            width,
        });
    }
    Ok(out)
}

/// The interpolation of sampler `s` (`what` names the channel in errors).
pub(crate) fn interpolation_of(
    sampler: &json::animation::Sampler,
    s: usize,
    what: &str,
) -> Result<Interpolation, GltfError> {
    use json::animation::Interpolation as I;
    match valid(&sampler.interpolation) {
        Some(I::Step) => Ok(Interpolation::Step),
        Some(I::Linear) => Ok(Interpolation::Linear),
        Some(I::CubicSpline) => Ok(Interpolation::CubicSpline),
        None => Err(GltfError::invalid(format!(
            "{what}: sampler {s} has an unknown interpolation"
        ))),
    }
}

/// Refuses a sampler's output `values` (`out_what` names them) unless they
/// are `width` per keyframe of `keyframes` (with `CUBICSPLINE`, each with
/// its two tangents), all finite.
pub(crate) fn check_output(
    out_what: &str,
    values: &[f32],
    keyframes: usize,
    interpolation: Interpolation,
    width: usize,
) -> Result<(), GltfError> {
    let groups = if interpolation == Interpolation::CubicSpline {
        3
    } else {
        1
    };
    let want = keyframes as u64 * groups * width as u64;
    if values.len() as u64 != want {
        return Err(GltfError::invalid(format!(
            "{out_what}: {} values for {keyframes} keyframes of {width} value{}{} (expected {want})",
            values.len(),
            if width == 1 { "" } else { "s" },
            if groups == 3 {
                ", each with two tangents"
            } else {
                ""
            },
        )));
    }
    if let Some(i) = values.iter().position(|v| !v.is_finite()) {
        return Err(GltfError::invalid(format!(
            "{out_what}: value {i} is not finite"
        )));
    }
    Ok(())
}

/// Refuses accessor `index` unless it has `n` components per element.
fn expect_components(
    root: &json::Root,
    index: usize,
    n: usize,
    what: &str,
) -> Result<(), GltfError> {
    match components(root, index) {
        Some(k) if k == n => Ok(()),
        Some(k) => Err(GltfError::invalid(format!(
            "{what}: accessor {index} has {k} components per element, expected {n}"
        ))),
        None => Err(GltfError::invalid(format!(
            "{what}: accessor {index} does not exist or has an unknown type"
        ))),
    }
}

/// The pose of `options` in the file: `None` when nothing is asked (the
/// nodes as written), else every channel of the chosen animation sampled at
/// the time (0 when not given). Channels later in the file win over earlier
/// ones on the same node and property.
pub(crate) fn pose(
    root: &json::Root,
    buffers: &Buffers,
    options: &AnimationOptions,
    warnings: &mut Vec<String>,
) -> Result<Option<Pose>, GltfError> {
    let Some(a) = chosen(root, buffers, options)? else {
        return Ok(None);
    };
    let t = options.time.unwrap_or(0.0);
    if !t.is_finite() {
        return Err(GltfError::invalid(format!("--at {t}: not a finite time")));
    }
    let mut pose = Pose::default();
    for track in tracks(root, buffers, a, warnings)? {
        let v = track.sample(t);
        match track.property {
            Property::Translation => {
                pose.translation.insert(track.node, Vec3::from_slice(&v));
            }
            Property::Rotation => {
                pose.rotation.insert(track.node, quat(&v));
            }
            Property::Scale => {
                pose.scale.insert(track.node, Vec3::from_slice(&v));
            }
            Property::Weights => {
                pose.weights.insert(track.node, v);
            }
        }
    }
    Ok(Some(pose))
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f32::consts::FRAC_PI_2;

    fn track(
        property: Property,
        interpolation: Interpolation,
        times: &[f32],
        values: &[f32],
    ) -> Track {
        let width = match property {
            Property::Rotation => 4,
            Property::Weights => 1,
            _ => 3,
        };
        Track {
            node: 0,
            property,
            interpolation,
            times: times.to_vec(),
            values: values.to_vec(),
            width,
        }
    }

    #[test]
    fn step_holds_each_keyframe_until_the_next() {
        let t = track(
            Property::Translation,
            Interpolation::Step,
            &[1.0, 2.0, 4.0],
            &[0.0, 0.0, 0.0, 1.0, 2.0, 3.0, -5.0, 0.5, 7.0],
        );
        assert_eq!(t.sample(1.0), [0.0, 0.0, 0.0]);
        assert_eq!(t.sample(1.999), [0.0, 0.0, 0.0]);
        assert_eq!(t.sample(2.0), [1.0, 2.0, 3.0]);
        assert_eq!(t.sample(3.9), [1.0, 2.0, 3.0]);
        assert_eq!(t.sample(4.0), [-5.0, 0.5, 7.0]);
        // Clamped outside the keyframes.
        assert_eq!(t.sample(0.0), [0.0, 0.0, 0.0]);
        assert_eq!(t.sample(100.0), [-5.0, 0.5, 7.0]);
    }

    #[test]
    fn linear_interpolates_component_wise_and_clamps() {
        let t = track(
            Property::Scale,
            Interpolation::Linear,
            &[0.5, 1.5],
            &[1.0, 2.0, -4.0, 3.0, 2.0, 0.0],
        );
        assert_eq!(t.sample(0.5), [1.0, 2.0, -4.0]);
        assert_eq!(t.sample(1.0), [2.0, 2.0, -2.0]);
        assert_eq!(t.sample(1.25), [2.5, 2.0, -1.0]);
        assert_eq!(t.sample(-3.0), [1.0, 2.0, -4.0]);
        assert_eq!(t.sample(9.0), [3.0, 2.0, 0.0]);
    }

    #[test]
    fn slerp_at_a_quarter_of_a_right_angle_turns_22_5_degrees() {
        let end = Quat::from_rotation_y(FRAC_PI_2);
        let t = track(
            Property::Rotation,
            Interpolation::Linear,
            &[0.0, 1.0],
            &[0.0, 0.0, 0.0, 1.0, end.x, end.y, end.z, end.w],
        );
        let q = quat(&t.sample(0.25));
        let want = Quat::from_rotation_y(FRAC_PI_2 / 4.0);
        // 22.5° about y: (0, sin 11.25°, 0, cos 11.25°).
        let half = 11.25f32.to_radians();
        assert!((want.y - half.sin()).abs() < 1e-7 && (want.w - half.cos()).abs() < 1e-7);
        assert!((q - want).length() < 1e-6, "{q} vs {want}");
        assert!((q.length() - 1.0).abs() < 1e-6);
    }

    #[test]
    fn slerp_takes_the_shorter_arc() {
        // The end given as −q (the same rotation): 0.5 of a 90° turn is 45°,
        // not the 135° of the long way round.
        let end = -Quat::from_rotation_z(FRAC_PI_2);
        let q = slerp(Quat::IDENTITY, end, 0.5);
        let want = Quat::from_rotation_z(FRAC_PI_2 / 2.0);
        assert!(q.dot(want).abs() > 1.0 - 1e-6, "{q} vs {want}");
    }

    #[test]
    fn cubic_spline_is_the_hermite_curve_with_tangents_times_the_interval() {
        // Keyframes at 1 s and 3 s (interval 2): value 1 → 5, out-tangent of
        // the first 0.5, in-tangent of the second −1.
        let (p0, b0, p1, a1) = (1.0f32, 0.5f32, 5.0f32, -1.0f32);
        let values = [
            9.0, p0, b0, // keyframe 0: in-tangent (unused), value, out-tangent
            a1, p1, 9.0, // keyframe 1: in-tangent, value, out-tangent (unused)
        ];
        let t = track(
            Property::Weights,
            Interpolation::CubicSpline,
            &[1.0, 3.0],
            &values,
        );
        // s = 0.25 at t = 1.5, written out by hand:
        // h00 = 2s³ − 3s² + 1 = 0.84375, h10 = s³ − 2s² + s = 0.140625,
        // h01 = −2s³ + 3s² = 0.15625, h11 = s³ − s² = −0.046875.
        let want = 0.84375 * p0 + 0.140625 * 2.0 * b0 + 0.15625 * p1 + -0.046875 * 2.0 * a1;
        assert!(
            (t.sample(1.5)[0] - want).abs() < 1e-6,
            "{:?} vs {want}",
            t.sample(1.5)
        );
        assert!((want - 1.859375).abs() < 1e-6);
        // At the keyframes the values, outside them clamped to the values (not tangents).
        assert_eq!(t.sample(1.0), [p0]);
        assert_eq!(t.sample(3.0), [p1]);
        assert_eq!(t.sample(0.0), [p0]);
        assert_eq!(t.sample(4.0), [p1]);
    }

    #[test]
    fn cubic_spline_rotations_come_out_normalized() {
        let (a, b) = (Quat::IDENTITY, Quat::from_rotation_x(1.0));
        let mut values = vec![0.0; 4];
        values.extend(a.to_array());
        values.extend([0.0; 8]);
        values.extend(b.to_array());
        values.extend([0.0; 4]);
        let t = track(
            Property::Rotation,
            Interpolation::CubicSpline,
            &[0.0, 1.0],
            &values,
        );
        let q = quat(&t.sample(0.5));
        assert!((q.length() - 1.0).abs() < 1e-6);
        // Zero tangents: the blend of the two is symmetric, halfway between.
        assert!(q.dot(Quat::from_rotation_x(0.5)).abs() > 1.0 - 1e-6, "{q}");
    }

    #[test]
    fn a_single_keyframe_is_constant() {
        let t = track(
            Property::Translation,
            Interpolation::Linear,
            &[2.0],
            &[1.0, 2.0, 3.0],
        );
        for time in [0.0, 2.0, 5.0] {
            assert_eq!(t.sample(time), [1.0, 2.0, 3.0]);
        }
    }

    #[test]
    fn choices_parse_as_indices_or_names() {
        assert_eq!("3".parse(), Ok(AnimationChoice::Index(3)));
        assert_eq!("Walk".parse(), Ok(AnimationChoice::Name("Walk".into())));
        assert!("".parse::<AnimationChoice>().is_err());
    }
}
