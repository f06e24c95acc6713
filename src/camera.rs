//! Cameras: the lab's pinhole camera (a position, a rotation `R = Ry(yaw)·Rx(pitch)`
//! and a focal length in pixels), any perspective field of view, orthographic
//! views, and the cameras a scene file brings.
//!
//! Camera space has x to the right, y down and z forward, like the lab's image:
//! the ray through image point `(px, py)` (pixel units, `(0, 0)` the top-left
//! corner) has direction `R·(px − W/2, py − H/2, f)`; an orthographic camera's
//! rays all go along `R·z` from `R·((px − W/2)·s, (py − H/2)·s, 0)`.

use glam::{Mat3A, Vec3A, Vec4};

use crate::geometry::ray::Ray;
#[cfg(target_arch = "x86_64")]
use crate::{geometry::packet::Rays8, simd::F8};

/// How a camera projects: perspective with a focal length relative to the image
/// height, or orthographic with a fixed view height.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Lens {
    /// A pinhole: the focal length is `focal_scale` × the image height in pixels
    /// (the lab's camera has exactly 1, a vertical field of view of `2·atan(0.5)`).
    Perspective {
        /// Focal length over image height: `0.5 / tan(yfov / 2)`.
        focal_scale: f32,
    },
    /// Parallel rays; the image spans `2 · half_height` scene units vertically.
    Orthographic {
        /// Half the view's height in scene units (glTF's `ymag`).
        half_height: f32,
    },
}

impl Lens {
    /// The lab's camera: focal length equal to the image height.
    pub const LAB: Lens = Lens::Perspective { focal_scale: 1.0 };

    /// A perspective lens with vertical field of view `yfov` (radians).
    pub fn from_yfov(yfov: f32) -> Lens {
        Lens::Perspective {
            focal_scale: 0.5 / (0.5 * yfov).tan(),
        }
    }
}

/// A camera as a scene file describes it, before an image size is chosen.
#[derive(Clone, Debug, PartialEq)]
pub struct SceneCamera {
    /// Its name in the file (may be empty).
    pub name: String,
    /// Centre of projection.
    pub position: Vec3A,
    /// Camera-to-world rotation; columns: right, down (image rows), forward.
    pub rotation: Mat3A,
    /// Projection.
    pub lens: Lens,
    /// Width over height the file asks for, if any.
    pub aspect_ratio: Option<f32>,
}

/// A camera producing rays for an image of `width × height` pixels.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    /// Centre of projection.
    pub position: Vec3A,
    /// Camera-to-world rotation; its columns are the right, down and forward axes.
    pub rotation: Mat3A,
    /// Focal length in pixels (perspective cameras).
    pub focal_px: f32,
    /// Scene units per pixel for an orthographic camera; `None` for perspective.
    pub ortho_px: Option<f32>,
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
}

impl Camera {
    /// The lab's camera: yaw and pitch in degrees, focal length equal to the image
    /// height (vertical field of view `2·atan(0.5)` ≈ 53.13°).
    ///
    /// Positive yaw turns towards +x; positive pitch looks up (towards −y).
    pub fn lab(position: Vec3A, yaw_deg: f32, pitch_deg: f32, width: u32, height: u32) -> Self {
        Self::oriented(position, Mat3A::IDENTITY, yaw_deg, pitch_deg, width, height)
    }

    /// The lab's camera in another frame: `base` is the camera-to-world rotation at
    /// yaw = pitch = 0 (for example [`Y_UP_TOWARDS_MINUS_Z`]), and yaw and pitch
    /// turn the view within it as in the lab.
    pub fn oriented(
        position: Vec3A,
        base: Mat3A,
        yaw_deg: f32,
        pitch_deg: f32,
        width: u32,
        height: u32,
    ) -> Self {
        Self::with_lens(
            position,
            base * lab_rotation(yaw_deg, pitch_deg),
            Lens::LAB,
            width,
            height,
        )
    }

    /// A camera with any lens; `rotation`'s columns are right, down and forward.
    pub fn with_lens(
        position: Vec3A,
        rotation: Mat3A,
        lens: Lens,
        width: u32,
        height: u32,
    ) -> Self {
        let (focal_px, ortho_px) = match lens {
            // The lab's exact f = H for focal_scale 1.
            Lens::Perspective { focal_scale } => (focal_scale * height as f32, None),
            Lens::Orthographic { half_height } => {
                (height as f32, Some(2.0 * half_height / height as f32))
            }
        };
        Self {
            position,
            rotation,
            focal_px,
            ortho_px,
            width,
            height,
        }
    }

    /// The ray through image point `(px, py)` in pixel units, with a unit direction.
    #[inline]
    pub fn ray(&self, px: f32, py: f32) -> Ray {
        let (x, y) = (px - 0.5 * self.width as f32, py - 0.5 * self.height as f32);
        if let Some(s) = self.ortho_px {
            let origin = self.position + self.rotation * Vec3A::new(x * s, y * s, 0.0);
            return Ray::new(origin, self.rotation.z_axis);
        }
        let d = Vec3A::new(x, y, self.focal_px);
        Ray::new(self.position, (self.rotation * d).normalize())
    }

    /// [`Camera::ray`] for four image points at once, bit for bit: the four
    /// directions are rotated and normalised in the lanes of SSE registers, so
    /// that their square roots and divisions overlap instead of each waiting
    /// for the last (they were an eighth of the lab's `direct` frame).
    #[inline]
    pub fn rays4(&self, px: [f32; 4], py: [f32; 4]) -> [Ray; 4] {
        if self.ortho_px.is_some() {
            return std::array::from_fn(|i| self.ray(px[i], py[i]));
        }
        let x = Vec4::from_array(px) - Vec4::splat(0.5 * self.width as f32);
        let y = Vec4::from_array(py) - Vec4::splat(0.5 * self.height as f32);
        let z = Vec4::splat(self.focal_px);
        // `Mat3A * Vec3A` (x·c0 + y·c1) + z·c2, and `normalize` (v / √((x² + y²) + z²)),
        // lane by lane with the same operations in the same order.
        let [c0, c1, c2] = [
            self.rotation.x_axis,
            self.rotation.y_axis,
            self.rotation.z_axis,
        ];
        let row =
            |a: usize| Vec4::splat(c0[a]) * x + Vec4::splat(c1[a]) * y + Vec4::splat(c2[a]) * z;
        let (dx, dy, dz) = (row(0), row(1), row(2));
        let length = crate::geometry::sqrt4(dx * dx + dy * dy + dz * dz);
        let (dx, dy, dz) = (dx / length, dy / length, dz / length);
        std::array::from_fn(|i| Ray::new(self.position, Vec3A::new(dx[i], dy[i], dz[i])))
    }

    /// [`Camera::rays4`] for eight image points, as eight rays in the lanes of
    /// AVX2 registers (only inside AVX2 code), bit for bit; `None` for an
    /// orthographic camera.
    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    pub(crate) fn rays8(&self, px: &[f32; 8], py: &[f32; 8]) -> Option<Rays8> {
        if self.ortho_px.is_some() {
            return None;
        }
        let x = F8::from_array(*px) - F8::splat(0.5 * self.width as f32);
        let y = F8::from_array(*py) - F8::splat(0.5 * self.height as f32);
        let z = F8::splat(self.focal_px);
        let [c0, c1, c2] = [
            self.rotation.x_axis,
            self.rotation.y_axis,
            self.rotation.z_axis,
        ];
        // (Written out: a closure here would be compiled without AVX2.)
        let dx = F8::splat(c0.x) * x + F8::splat(c1.x) * y + F8::splat(c2.x) * z;
        let dy = F8::splat(c0.y) * x + F8::splat(c1.y) * y + F8::splat(c2.y) * z;
        let dz = F8::splat(c0.z) * x + F8::splat(c1.z) * y + F8::splat(c2.z) * z;
        let length = (dx * dx + dy * dy + dz * dz).sqrt();
        let p = self.position;
        Some(Rays8 {
            origin: [F8::splat(p.x), F8::splat(p.y), F8::splat(p.z)],
            dir: [dx / length, dy / length, dz / length],
        })
    }

    /// This camera moved `degrees` around the vertical axis (the world's y
    /// axis, which is vertical in the lab's and glTF's scenes) through
    /// `centre`, counter-clockwise seen from above (from the side the image's
    /// up points to): a turntable's view. 0° gives the camera unchanged.
    pub fn orbited(&self, centre: Vec3A, degrees: f32) -> Camera {
        if degrees == 0.0 {
            return *self;
        }
        // Up is −y where image rows run along +y (the lab), +y otherwise.
        let up = if self.down().y > 0.0 {
            -Vec3A::Y
        } else {
            Vec3A::Y
        };
        let turn = Mat3A::from_axis_angle(up.into(), degrees.to_radians());
        Camera {
            position: centre + turn * (self.position - centre),
            rotation: turn * self.rotation,
            ..*self
        }
    }

    /// The unit viewing direction (camera +z in world space).
    pub fn forward(&self) -> Vec3A {
        self.rotation.z_axis
    }

    /// The unit right direction (camera +x in world space).
    pub fn right(&self) -> Vec3A {
        self.rotation.x_axis
    }

    /// The unit down direction of the image (camera +y in world space).
    pub fn down(&self) -> Vec3A {
        self.rotation.y_axis
    }
}

/// The camera-to-world rotation (columns right, down, forward) of a camera at
/// `position` looking at `target` with `up` pointing up in the image; `None`
/// when the view direction is zero or parallel to `up`.
pub fn look_at(position: Vec3A, target: Vec3A, up: Vec3A) -> Option<Mat3A> {
    let forward = (target - position).normalize_or_zero();
    let right = forward.cross(up).normalize_or_zero();
    if forward == Vec3A::ZERO || right == Vec3A::ZERO || !right.is_finite() {
        return None;
    }
    Some(Mat3A::from_cols(right, forward.cross(right), forward))
}

/// Camera frame for y-up scenes (OBJ, glTF) seen from the +z side: image right is
/// +x, image down is −y, the view goes along −z.
pub const Y_UP_TOWARDS_MINUS_Z: Mat3A = Mat3A::from_cols(Vec3A::X, Vec3A::NEG_Y, Vec3A::NEG_Z);

/// The lab's `Ry(yaw)·Rx(pitch)`, angles in degrees.
pub fn lab_rotation(yaw_deg: f32, pitch_deg: f32) -> Mat3A {
    let (sy, cy) = yaw_deg.to_radians().sin_cos();
    let (sp, cp) = pitch_deg.to_radians().sin_cos();
    // Written by rows as in the lab report; glam takes columns.
    let ry = Mat3A::from_cols(
        Vec3A::new(cy, 0.0, -sy),
        Vec3A::new(0.0, 1.0, 0.0),
        Vec3A::new(sy, 0.0, cy),
    );
    let rx = Mat3A::from_cols(
        Vec3A::new(1.0, 0.0, 0.0),
        Vec3A::new(0.0, cp, sp),
        Vec3A::new(0.0, -sp, cp),
    );
    ry * rx
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Four rays at once are the four single rays, bit for bit, for
    /// perspective and orthographic lenses, inside and outside the image.
    #[test]
    fn four_rays_at_once_equal_the_rays_one_by_one() {
        let mut rng = crate::sampling::sampler::Rng::new(4, 4);
        let cameras = [
            Camera::lab(Vec3A::new(0.1, 0.2, -3.0), 17.0, -23.0, 640, 480),
            Camera::with_lens(
                Vec3A::new(1.0, 2.0, 3.0),
                Mat3A::from_rotation_y(0.3),
                Lens::Orthographic { half_height: 2.0 },
                300,
                200,
            ),
        ];
        for camera in cameras {
            for _ in 0..10_000 {
                let mut point = || rng.next_f32() * 900.0 - 100.0;
                let px: [f32; 4] = std::array::from_fn(|_| point());
                let py: [f32; 4] = std::array::from_fn(|_| point());
                let four = camera.rays4(px, py);
                for i in 0..4 {
                    let one = camera.ray(px[i], py[i]);
                    assert_eq!(
                        [four[i].origin, four[i].dir].map(|v| v.to_array().map(f32::to_bits)),
                        [one.origin, one.dir].map(|v| v.to_array().map(f32::to_bits)),
                    );
                }
            }
        }
    }

    #[test]
    fn pixel_rays_follow_the_lab_formula() {
        let (w, h) = (500u32, 400u32);
        for (yaw, pitch) in [(0.0f32, 0.0f32), (30.0, 0.0), (0.0, -20.0), (-45.0, 10.0)] {
            let cam = Camera::lab(Vec3A::new(0.1, 0.2, -3.0), yaw, pitch, w, h);
            let (a, b) = (yaw.to_radians(), pitch.to_radians());
            for (x, y) in [(0u32, 0u32), (249, 199), (499, 399), (17, 311)] {
                // R·(x + 0.5 − W/2, y + 0.5 − H/2, f), the formula written out.
                let d = [x as f32 + 0.5 - 250.0, y as f32 + 0.5 - 200.0, h as f32];
                let rx = [
                    d[0],
                    b.cos() * d[1] - b.sin() * d[2],
                    b.sin() * d[1] + b.cos() * d[2],
                ];
                let want = Vec3A::new(
                    a.cos() * rx[0] + a.sin() * rx[2],
                    rx[1],
                    -a.sin() * rx[0] + a.cos() * rx[2],
                )
                .normalize();
                let ray = cam.ray(x as f32 + 0.5, y as f32 + 0.5);
                assert_eq!(ray.origin, cam.position);
                assert!((ray.dir - want).length() < 1e-6, "{yaw} {pitch} {x} {y}");
            }
        }
    }

    #[test]
    fn y_up_frame_looks_down_minus_z_with_up_up() {
        let cam = Camera::oriented(Vec3A::ZERO, Y_UP_TOWARDS_MINUS_Z, 0.0, 0.0, 10, 10);
        assert_eq!(cam.forward(), Vec3A::NEG_Z);
        assert!(cam.ray(5.0, 0.0).dir.y > 0.0, "the top row looks up (+y)");
        assert!(
            cam.ray(10.0, 5.0).dir.x > 0.0,
            "the right column looks right (+x)"
        );
        // Yaw still turns right and pitch still looks up.
        let turned = Camera::oriented(Vec3A::ZERO, Y_UP_TOWARDS_MINUS_Z, 90.0, 0.0, 10, 10);
        assert!((turned.forward() - Vec3A::X).length() < 1e-6);
        let up = Camera::oriented(Vec3A::ZERO, Y_UP_TOWARDS_MINUS_Z, 0.0, 30.0, 10, 10);
        assert!(up.forward().y > 0.4);
    }

    #[test]
    fn lenses_give_the_field_of_view_and_parallel_rays() {
        // A perspective lens of yfov 60°: the top edge's ray is 30° up, the lab
        // lens keeps f = H exactly.
        let cam = Camera::with_lens(
            Vec3A::ZERO,
            Mat3A::IDENTITY,
            Lens::from_yfov(60f32.to_radians()),
            80,
            40,
        );
        let top = cam.ray(40.0, 0.0).dir;
        assert!(
            (top.y.atan2(top.z).to_degrees() + 30.0).abs() < 1e-4,
            "{top}"
        );
        assert_eq!(Camera::lab(Vec3A::ZERO, 0.0, 0.0, 7, 9).focal_px, 9.0);
        // Orthographic with half height 2 on a 40×20 image: 0.2 units a pixel,
        // every ray along the forward axis from its own point.
        let rot = crate::camera::Y_UP_TOWARDS_MINUS_Z;
        let pos = Vec3A::new(1.0, 2.0, 3.0);
        let cam = Camera::with_lens(pos, rot, Lens::Orthographic { half_height: 2.0 }, 40, 20);
        let corner = cam.ray(0.0, 0.0);
        assert_eq!(corner.dir, Vec3A::NEG_Z);
        assert!((corner.origin - (pos + Vec3A::new(-4.0, 2.0, 0.0))).length() < 1e-6);
        let centre = cam.ray(20.0, 10.0);
        assert!((centre.origin - pos).length() < 1e-6);
    }

    #[test]
    fn yaw_turns_right_and_pitch_looks_up() {
        let cam = Camera::lab(Vec3A::ZERO, 90.0, 0.0, 10, 10);
        assert!((cam.forward() - Vec3A::X).length() < 1e-6);
        let cam = Camera::lab(Vec3A::ZERO, 0.0, 90.0, 10, 10);
        assert!((cam.forward() - Vec3A::NEG_Y).length() < 1e-6);
        // Vertical field of view is 2·atan(0.5): the top edge ray is 26.57° up.
        let cam = Camera::lab(Vec3A::ZERO, 0.0, 0.0, 500, 500);
        let top = cam.ray(250.0, 0.0).dir;
        assert!((top.y.atan2(top.z).to_degrees() + 26.565).abs() < 1e-3);
    }
}
