//! glTF cameras (perspective and orthographic) as the scene's cameras, in the
//! order the node tree is walked.

use glam::{Mat3A, Mat4, Vec3, Vec3A};

use super::error::GltfError;
use super::loader::Loader;
use crate::camera::{Lens, SceneCamera};

impl Loader<'_> {
    /// Camera `index` at a node whose global transform is `world`: it looks
    /// down its local −z with +y up.
    pub(super) fn camera(&mut self, index: usize, world: &Mat4) -> Result<(), GltfError> {
        let cam = self
            .root
            .cameras
            .get(index)
            .ok_or_else(|| GltfError::invalid(format!("camera {index} does not exist")))?;
        let position = Vec3A::from(world.transform_point3(Vec3::ZERO));
        let forward = Vec3A::from(world.transform_vector3(Vec3::NEG_Z)).normalize_or_zero();
        let right = Vec3A::from(world.transform_vector3(Vec3::X));
        let right = (right - forward * forward.dot(right)).normalize_or_zero();
        if forward == Vec3A::ZERO || right == Vec3A::ZERO || !position.is_finite() {
            return Err(GltfError::invalid(format!(
                "camera {index}'s node transform is degenerate"
            )));
        }
        let down = forward.cross(right);
        let (lens, aspect_ratio) = match (&cam.perspective, &cam.orthographic) {
            (Some(p), _) => {
                if !(p.yfov > 0.0 && p.yfov < std::f32::consts::PI) {
                    return Err(GltfError::invalid(format!(
                        "camera {index}: yfov {} is not between 0 and π",
                        p.yfov
                    )));
                }
                (
                    Lens::from_yfov(p.yfov),
                    p.aspect_ratio.filter(|a| a.is_finite() && *a > 0.0),
                )
            }
            (None, Some(o)) => {
                if !(o.ymag.is_finite() && o.ymag != 0.0) {
                    return Err(GltfError::invalid(format!(
                        "camera {index}: ymag {} must be non-zero",
                        o.ymag
                    )));
                }
                let aspect = (o.xmag / o.ymag).abs();
                (
                    Lens::Orthographic {
                        half_height: o.ymag.abs(),
                    },
                    (aspect.is_finite() && aspect > 0.0).then_some(aspect),
                )
            }
            (None, None) => {
                return Err(GltfError::invalid(format!(
                    "camera {index} is neither perspective nor orthographic"
                )));
            }
        };
        self.parts.cameras.push(SceneCamera {
            name: cam.name.clone().unwrap_or_default(),
            position,
            rotation: Mat3A::from_cols(right, down, forward),
            lens,
            aspect_ratio,
            depth_of_field: crate::camera::DepthOfField::default(),
            window: None,
        });
        Ok(())
    }
}
