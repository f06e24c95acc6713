//! The operations of a `<transform>` (Mitsuba's `parse_transform_node` and
//! `Transform` constructors in `include/mitsuba/core/transform.h`), in
//! `f64` as Mitsuba's parser computes them. Each one left-multiplies the
//! matrix so far: `<translate/><rotate/>` is `R · T` (translate first).
//!
//! - `translate`: `x`, `y`, `z` (missing ones 0), or `value="x, y, z"` (one
//!   value for all three).
//! - `rotate`: `angle` in degrees, counter-clockwise about the axis `x`, `y`,
//!   `z` (missing ones 0; or `value=`), which is normalized and must not be
//!   zero (Rodrigues' formula).
//! - `scale`: `x`, `y`, `z` (missing ones 1), or `value=` (one value: a
//!   uniform scale).
//! - `matrix`: `value=` of 16 numbers (a 4×4 matrix) or 9 (the upper-left
//!   3×3 of an identity), row by row.
//! - `lookat`: `origin`, `target`, optional `up` (three numbers each). The
//!   columns are `left = normalize(up × dir)`, `up' = dir × left`, `dir =
//!   normalize(target − origin)`, `origin`: the camera looks along its +z
//!   with +x to the *left* (Mitsuba's handedness). A missing or zero `up`
//!   is the first vector of Mitsuba's `coordinate_system(dir)`; an `up`
//!   parallel to `dir` (a NaN matrix) is an error.

use glam::{DMat4, DVec3, DVec4};

use super::attrs::Attrs;
use super::values::{expand_xyz, number, triple};
use crate::guard::quote;

/// Applies the transform operation `op` (an element inside `<transform>`)
/// with its attributes to `m`.
pub(super) fn apply(op: &str, attrs: &mut Attrs, m: &mut DMat4) -> Result<(), String> {
    let t = match op {
        "translate" => {
            expand_value(attrs)?;
            attrs.check(&["x", "y", "z"])?;
            DMat4::from_translation(xyz(attrs, 0.0)?)
        }
        "rotate" => {
            expand_value(attrs)?;
            attrs.check(&["!angle", "x", "y", "z"])?;
            let axis = xyz(attrs, 0.0)?;
            if axis == DVec3::ZERO {
                return Err("rotation axis cannot be zero".into());
            }
            let text = attrs.get("angle").unwrap_or_default();
            let angle = number(text)
                .map_err(|_| format!("could not parse angle value \"{}\"", quote(text)))?;
            rotation(axis, angle)
        }
        "scale" => {
            expand_value(attrs)?;
            attrs.check(&["x", "y", "z"])?;
            DMat4::from_scale(xyz(attrs, 1.0)?)
        }
        "matrix" => {
            attrs.check(&["!value"])?;
            matrix(attrs.get("value").unwrap_or_default())?
        }
        "lookat" => {
            attrs.check(&["!origin", "!target", "up"])?;
            let origin = DVec3::from(triple(attrs.get("origin").unwrap_or_default())?);
            let target = DVec3::from(triple(attrs.get("target").unwrap_or_default())?);
            let up = match attrs.get("up") {
                Some(u) if !u.is_empty() => DVec3::from(triple(u)?),
                _ => DVec3::ZERO,
            };
            let composed = look_at(origin, target, up) * *m;
            if composed.to_cols_array().iter().any(|v| v.is_nan()) {
                return Err("invalid lookat transformation (origin equals target, or up is parallel to the view direction)".into());
            }
            *m = composed;
            return Ok(());
        }
        _ => {
            return Err(format!(
                "unexpected <{}> element inside <transform> (expected translate, rotate, scale, matrix or lookat)",
                quote(op)
            ));
        }
    };
    *m = t * *m;
    Ok(())
}

/// Mitsuba's `expand_value_to_xyz`: `value="v"` or `value="x, y, z"` becomes
/// the `x`, `y`, `z` attributes; mixing the two forms is an error.
fn expand_value(attrs: &mut Attrs) -> Result<(), String> {
    let Some(value) = attrs.get("value") else {
        return Ok(());
    };
    if ["x", "y", "z"].iter().any(|k| attrs.get(k).is_some()) {
        return Err("cannot mix \"value\" and \"x\"/\"y\"/\"z\" attributes".into());
    }
    let [x, y, z] = expand_xyz(value)?.map(str::to_string);
    attrs.remove("value");
    attrs.push("x", x);
    attrs.push("y", y);
    attrs.push("z", z);
    Ok(())
}

/// The `x`, `y`, `z` attributes, `default` for missing ones.
fn xyz(attrs: &Attrs, default: f64) -> Result<DVec3, String> {
    let mut v = [default; 3];
    for (out, k) in v.iter_mut().zip(["x", "y", "z"]) {
        if let Some(t) = attrs.get(k) {
            *out = number(t)?;
        }
    }
    Ok(DVec3::from(v))
}

/// A counter-clockwise rotation by `degrees` about `axis` (normalized here;
/// not zero).
pub(super) fn rotation(axis: DVec3, degrees: f64) -> DMat4 {
    DMat4::from_axis_angle(axis.normalize(), degrees.to_radians())
}

/// A `matrix` of 16 (4×4) or 9 (3×3) numbers, row by row.
fn matrix(text: &str) -> Result<DMat4, String> {
    let list: Vec<&str> = super::values::tokens(text).take(17).collect();
    let n = match list.len() {
        16 => 4,
        9 => 3,
        _ => {
            return Err(format!(
                "matrix must have 9 or 16 values, got {}",
                super::values::tokens(text).count()
            ));
        }
    };
    let mut m = DMat4::IDENTITY;
    for row in 0..n {
        for col in 0..n {
            let t = list[row * n + col];
            let v =
                number(t).map_err(|_| format!("could not parse matrix value \"{}\"", quote(t)))?;
            m.col_mut(col)[row] = v;
        }
    }
    Ok(m)
}

/// Mitsuba's `look_at`: columns left, up, dir, origin.
pub(super) fn look_at(origin: DVec3, target: DVec3, up: DVec3) -> DMat4 {
    // (A zero vector normalizes to NaN, which the caller's check refuses.)
    let dir = (target - origin).normalize();
    let up = match up == DVec3::ZERO {
        true => coordinate_system(dir).0,
        false => up,
    };
    let left = up.cross(dir).normalize();
    let new_up = dir.cross(left);
    DMat4::from_cols(
        left.extend(0.0),
        new_up.extend(0.0),
        dir.extend(0.0),
        DVec4::new(origin.x, origin.y, origin.z, 1.0),
    )
}

/// Mitsuba's `coordinate_system(n)` (Duff et al. 2017, "Building an
/// Orthonormal Basis, Revisited"): two vectors completing the unit `n` to
/// an orthonormal basis. The sign is the sign bit's, as Dr.Jit's.
pub(super) fn coordinate_system(n: DVec3) -> (DVec3, DVec3) {
    let sign = 1.0f64.copysign(n.z);
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    (
        DVec3::new(n.x * n.x * a * sign + 1.0, b * sign, -n.x * sign),
        DVec3::new(b, n.y.mul_add(n.y * a, sign), -n.y),
    )
}
