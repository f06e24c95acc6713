//! Files older than format 2.0 (Mitsuba 0.5/0.6 scenes) upgraded as Mitsuba
//! 3 does (`upgrade_from_v1` in `parser.cpp`), object by object, for the
//! objects written in such a file:
//!
//! 1. Every property name (and child name) in camelCase becomes snake_case
//!    (`maxDepth` → `max_depth`, `intIOR` → `int_ior`: an underscore before
//!    an upper-case letter that follows a lower-case one, then that run of
//!    upper-case letters lowered), unless the new name is taken.
//! 2. A `diffuse` plugin's `diffuse_reflectance` becomes `reflectance`.
//! 3. `uoffset`, `voffset`, `uscale`, `vscale` (numbers) become one
//!    `to_uv` transform: scale(uscale, vscale, 1) · translate(uoffset,
//!    voffset, 0), missing ones 0 and 1.
//!
//! And, from Mitsuba 3's older `xml.cpp` (the new parser refuses it), a
//! `<lookAt>` in such a file is read as `<lookat>` (`xml.rs` does this).

use glam::{DMat4, DVec3};

use super::table::Node;
use super::tree::{Property, Value};

/// Mitsuba's `camel_to_underscore_case`.
pub(super) fn snake_case(name: &str) -> String {
    let chars: Vec<char> = name.chars().collect();
    let mut out = String::with_capacity(name.len() + 4);
    let mut i = 0;
    while i < chars.len() {
        let c = chars[i];
        if i > 0 && chars[i - 1].is_ascii_lowercase() && c.is_ascii_uppercase() {
            out.push('_');
            out.push(c.to_ascii_lowercase());
            while i + 1 < chars.len() && chars[i + 1].is_ascii_uppercase() {
                i += 1;
                out.push(chars[i].to_ascii_lowercase());
            }
        } else {
            out.push(c);
        }
        i += 1;
    }
    out
}

/// Upgrades one object of a pre-2.0 file (the rules of the module's doc).
pub(super) fn upgrade_v1(node: &mut Node) -> Result<(), String> {
    // 1. Names, in order; a rename to a name already there is skipped (as
    // Mitsuba's `rename_property`).
    let count = node.props.len() + node.edges.len();
    for i in 0..count {
        let old = match name_at(node, i) {
            Some(n) => n.to_string(),
            None => continue,
        };
        let new = snake_case(&old);
        if new != old && !node.has(&new) {
            set_name_at(node, i, new);
        }
    }
    if let Some(n) = &node.name {
        node.name = Some(snake_case(n));
    }
    // 2. diffuse_reflectance.
    if node.plugin == "diffuse" && !node.has("reflectance") {
        for i in 0..count {
            if name_at(node, i) == Some("diffuse_reflectance") {
                set_name_at(node, i, "reflectance".into());
            }
        }
    }
    // 3. Texture offsets and scales.
    let mut offset = DVec3::ZERO;
    let mut scale = DVec3::ONE;
    let mut location = None;
    for (key, slot) in [
        ("uoffset", &mut offset.x),
        ("voffset", &mut offset.y),
        ("uscale", &mut scale.x),
        ("vscale", &mut scale.y),
    ] {
        if !node.has(key) {
            continue;
        }
        let Some(i) = node.props.iter().position(|p| p.name == key) else {
            return Err(format!(
                "'{key}' (a 0.x texture offset or scale) must be a number"
            ));
        };
        let p = node.props.remove(i);
        *slot = match p.value {
            Value::Float(v) => f64::from(v),
            Value::Integer(v) => v as f64,
            _ => {
                return Err(format!(
                    "'{key}' (a 0.x texture offset or scale) must be a number, not {}",
                    p.value.kind()
                ));
            }
        };
        location.get_or_insert(p.location);
    }
    if let Some(location) = location {
        if node.has("to_uv") {
            return Err(
                "'to_uv' is given and also made of uoffset/voffset/uscale/vscale (0.x upgrade)"
                    .into(),
            );
        }
        let m = DMat4::from_scale(scale) * DMat4::from_translation(offset);
        node.props.push(Property {
            name: "to_uv".into(),
            value: Value::Transform(m.as_mat4()),
            location,
        });
    }
    Ok(())
}

/// The name of the `i`-th property, then of the children.
fn name_at(node: &Node, i: usize) -> Option<&str> {
    match i < node.props.len() {
        true => Some(&node.props[i].name),
        false => node.edges[i - node.props.len()].name.as_deref(),
    }
}

fn set_name_at(node: &mut Node, i: usize, name: String) {
    match i < node.props.len() {
        true => node.props[i].name = name,
        false => {
            let k = i - node.props.len();
            node.edges[k].name = Some(name);
        }
    }
}
