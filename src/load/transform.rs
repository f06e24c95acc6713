//! Placing a mesh in a scene: a short list of operations applied in order, e.g.
//! `"fit 0.8; rotate x 180; translate 0.3 1 -0.3"` stands the y-up bunny 0.8 tall
//! on the floor of the y-down lab box.

use std::str::FromStr;

use glam::{Affine3A, Mat3, Vec3, Vec3A};

use crate::geometry::triangle::Triangle;

/// One step of a [`Transform`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Op {
    /// Multiply coordinates componentwise.
    Scale(Vec3A),
    /// Turn about the x, y or z axis (0, 1, 2) by degrees, right-handed.
    Rotate(usize, f32),
    /// Add an offset.
    Translate(Vec3A),
    /// Centre the mesh on the y axis with its lowest point at y = 0, then scale it
    /// uniformly to this height.
    Fit(f32),
}

/// Operations applied to a mesh's vertices in order.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Transform(pub Vec<Op>);

impl FromStr for Transform {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let mut ops = Vec::new();
        for part in s.split(';').map(str::trim).filter(|p| !p.is_empty()) {
            let words: Vec<&str> = part.split_whitespace().collect();
            let nums = |from: usize| -> Result<Vec<f32>, String> {
                words[from..]
                    .iter()
                    .map(|w| match w.parse::<f32>() {
                        Ok(v) if v.is_finite() => Ok(v),
                        _ => Err(format!("'{w}' in '{part}' is not a finite number")),
                    })
                    .collect()
            };
            let op = match (words[0], words.len()) {
                ("scale", 2) => Op::Scale(Vec3A::splat(nums(1)?[0])),
                ("scale", 4) => Op::Scale(Vec3A::from_slice(&nums(1)?)),
                ("translate", 4) => Op::Translate(Vec3A::from_slice(&nums(1)?)),
                ("rotate", 3) => {
                    let axis = match words[1] {
                        "x" => 0,
                        "y" => 1,
                        "z" => 2,
                        other => return Err(format!("'{other}' is not an axis (x, y or z)")),
                    };
                    Op::Rotate(axis, nums(2)?[0])
                }
                ("fit", 2) => match nums(1)?[0] {
                    h if h > 0.0 => Op::Fit(h),
                    _ => return Err("fit needs a height > 0".into()),
                },
                _ => {
                    return Err(format!(
                        "'{part}' is not one of: scale S | scale X Y Z | rotate x|y|z DEG | \
                         translate X Y Z | fit HEIGHT"
                    ));
                }
            };
            if let Op::Scale(s) = op
                && s.cmpeq(Vec3A::ZERO).any()
            {
                return Err("scale by 0 flattens the mesh".into());
            }
            ops.push(op);
        }
        Ok(Transform(ops))
    }
}

impl Transform {
    /// Applies the operations to every vertex, in order.
    pub fn apply(&self, triangles: &mut [Triangle]) {
        for op in &self.0 {
            // Every operation is affine; `fit` depends on the mesh as it is by then.
            let map = match *op {
                Op::Scale(s) => Affine3A::from_scale(s.into()),
                Op::Translate(t) => Affine3A::from_translation(t.into()),
                Op::Rotate(axis, deg) => {
                    let r = deg.to_radians();
                    Affine3A::from_mat3(match axis {
                        0 => Mat3::from_rotation_x(r),
                        1 => Mat3::from_rotation_y(r),
                        _ => Mat3::from_rotation_z(r),
                    })
                }
                Op::Fit(height) => {
                    let (lo, hi) = crate::geometry::triangle::bounds(triangles);
                    let s = height / (hi.y - lo.y).max(f32::MIN_POSITIVE);
                    let base = Vec3A::new((lo.x + hi.x) / 2.0, lo.y, (lo.z + hi.z) / 2.0);
                    Affine3A::from_scale(Vec3::splat(s))
                        * Affine3A::from_translation((-base).into())
                }
            };
            // A mirroring map would turn faces inside out: keep the winding.
            let mirror = map.matrix3.determinant() < 0.0;
            for t in triangles.iter_mut() {
                let v = t.v.map(|p| map.transform_point3a(p));
                t.v = if mirror { [v[0], v[2], v[1]] } else { v };
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_and_applies_in_order() {
        let t: Transform = "fit 2; rotate x 180 ;translate 0 1 0".parse().unwrap();
        assert_eq!(t.0.len(), 3);
        let mut tris = vec![Triangle::new(
            Vec3A::new(1.0, 10.0, 0.0),
            Vec3A::new(3.0, 10.0, 0.0),
            Vec3A::new(2.0, 14.0, 1.0),
        )];
        let normal = tris[0].lab_normal();
        t.apply(&mut tris);
        // Fit: base at y = 0, 2 tall, centred; rotate: y -> -y, z -> -z; translate.
        let v = tris[0].v;
        assert!(
            (v[0] - Vec3A::new(-0.5, 1.0, 0.25)).length() < 1e-5,
            "{v:?}"
        );
        assert!(
            (v[2] - Vec3A::new(0.0, -1.0, -0.25)).length() < 1e-5,
            "{v:?}"
        );
        // A rotation keeps the winding: the normal turns with the mesh.
        let turned = glam::Mat3A::from_rotation_x(std::f32::consts::PI) * normal;
        assert!((tris[0].lab_normal() - turned).length() < 1e-5);
    }

    #[test]
    fn mirroring_keeps_faces_outward_and_bad_specs_are_refused() {
        let t: Transform = "scale 1 -1 1".parse().unwrap();
        let mut tris = vec![Triangle::new(Vec3A::ZERO, Vec3A::X, Vec3A::Z)];
        let before = tris[0].lab_normal();
        t.apply(&mut tris);
        assert!((tris[0].lab_normal() - before * Vec3A::new(1.0, -1.0, 1.0)).length() < 1e-6);
        for bad in [
            "spin 3",
            "scale",
            "scale 0",
            "rotate w 10",
            "translate 1 2",
            "fit -1",
            "scale nan",
        ] {
            assert!(bad.parse::<Transform>().is_err(), "{bad}");
        }
    }
}
