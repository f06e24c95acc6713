//! Scenes from meshes: a camera that frames the mesh from the +z side (OBJ and glTF
//! are y-up) and a point light near it, so that any mesh gives a picture at once.

use glam::{Mat3A, Vec3A};

use crate::camera::Y_UP_TOWARDS_MINUS_Z;
use crate::scene::PointLight;

/// Where the camera and light go for a mesh, and how far a key press moves them.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Framing {
    /// Camera position.
    pub camera_pos: Vec3A,
    /// Camera frame at yaw = pitch = 0.
    pub base: Mat3A,
    /// The light: near the camera, up and to the right, bright enough that the
    /// direct light at the mesh's centre is [`MESH_IRRADIANCE`].
    pub light: PointLight,
    /// Viewer travel per key press: 5 % of the mesh's diagonal.
    pub step: f32,
}

/// Direct light `D` at a framed mesh's centre: with reflectance 0.75 and the
/// default ambient term it keeps lit surfaces well inside the PNG's range.
pub const MESH_IRRADIANCE: f32 = 0.5;

/// The lab camera's half vertical field of view: atan(0.5).
const HALF_FOV_TAN: f32 = 0.5;

/// Frames the box `lo`–`hi` from the +z side, looking along −z with +y up, so that
/// every corner of the box lies within 90 % of the lab camera's half field of
/// view (vertically, and horizontally for images at least as wide as high).
pub fn frame(lo: Vec3A, hi: Vec3A) -> Framing {
    let centre = (lo + hi) * 0.5;
    let radius = ((hi - lo).length() * 0.5).max(1e-6);
    // The nearest corners (depth d − half.z) are the widest seen: their offset
    // over depth must stay within tan(half field of view) / 1.1.
    let half = (hi - lo) * 0.5;
    let distance = half.z + 1.1 * half.x.max(half.y).max(1e-6) / HALF_FOV_TAN;
    let camera_pos = centre + Vec3A::new(0.0, 0.0, distance);
    let light_pos = camera_pos + Vec3A::new(0.5, 0.7, 0.0) * radius;
    let r2 = (light_pos - centre).length_squared();
    Framing {
        camera_pos,
        base: Y_UP_TOWARDS_MINUS_Z,
        light: PointLight {
            position: light_pos,
            power: Vec3A::splat(MESH_IRRADIANCE * 4.0 * std::f32::consts::PI * r2),
        },
        step: 0.05 * 2.0 * radius,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::Camera;

    #[test]
    fn the_framed_box_is_in_view_and_lit() {
        let (lo, hi) = (Vec3A::new(-3.0, 10.0, 2.0), Vec3A::new(5.0, 14.0, 4.0));
        let f = frame(lo, hi);
        let cam = Camera::oriented(f.camera_pos, f.base, 0.0, 0.0, 100, 100);
        // Every corner of the box projects inside the image.
        for i in 0..8 {
            let corner = Vec3A::new(
                if i & 1 == 0 { lo.x } else { hi.x },
                if i & 2 == 0 { lo.y } else { hi.y },
                if i & 4 == 0 { lo.z } else { hi.z },
            );
            let d = cam.rotation.transpose() * (corner - cam.position);
            assert!(d.z > 0.0, "corner behind the camera");
            let (px, py) = (
                d.x / d.z * cam.focal_px + 50.0,
                d.y / d.z * cam.focal_px + 50.0,
            );
            assert!(
                (0.0..100.0).contains(&px) && (0.0..100.0).contains(&py),
                "{px} {py}"
            );
        }
        // The light is on the camera's side, and D at the centre is as promised.
        let c = (lo + hi) * 0.5;
        let r2 = (f.light.position - c).length_squared();
        let d = f.light.power.x / (4.0 * std::f32::consts::PI * r2);
        assert!((d - MESH_IRRADIANCE).abs() < 1e-5);
        assert!(f.light.position.z > hi.z && f.light.position.y > c.y);
    }
}
