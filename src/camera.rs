//! Cameras: the lab's pinhole camera (a position, a rotation `R = Ry(yaw)·Rx(pitch)`
//! and a focal length in pixels), any perspective field of view, orthographic
//! views, and the cameras a scene file brings.
//!
//! Camera space has x to the right, y down and z forward, like the lab's image:
//! the ray through image point `(px, py)` (pixel units, `(0, 0)` the top-left
//! corner) has direction `R·(px − W/2, py − H/2, f)`; an orthographic camera's
//! rays all go along `R·z` from `R·((px − W/2)·s, (py − H/2)·s, 0)`. An image
//! that is a window of a larger film ([`Camera::window`], Mitsuba's crop
//! window) keeps the film's projection: `(W/2, H/2)` is then the film's centre
//! in the window's pixel coordinates, `(cx, cy)`.
//!
//! A thin lens ([`ThinLens`]) in the plane `z = 0` of camera space, centred on
//! the position, focuses at distance `F` along the view axis: the ray through
//! image point `(px, py)` and lens point `l` starts at `l` and goes through
//! the point that the pinhole ray through `(px, py)` reaches at depth `F`
//! (for an orthographic camera, the lens is centred on the ray's own origin).
//! A point at depth `z` then spreads over a disk of diameter
//! `2R · f · |z − F| / (z · F)` pixels (`R` the lens radius, `f` the focal
//! length in pixels), the thin-lens circle of confusion of an image plane at
//! distance `f`, as pbrt's and Cycles' thin lenses give.

use glam::{Mat3A, Vec2, Vec3A, Vec4};

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

/// How far a thin lens opens.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Aperture {
    /// The lens's radius in scene units (pbrt's `lensradius`); 0 is a pinhole.
    Radius(f32),
    /// The f-number `N`: the lens's diameter is the focal length over `N`,
    /// with the focal length of a 36 mm sensor across the image's longer side
    /// (Blender's default sensor, fitted as its `Auto` fit does) and scene
    /// units taken as metres, so that `f/2.8` blurs as it does in Blender.
    FNumber(f32),
}

/// Width of the sensor that [`Aperture::FNumber`] takes the focal length
/// from, in millimetres, across the image's longer side.
pub const SENSOR_MM: f32 = 36.0;

/// Largest lens radius and focus distance accepted, in scene units: beyond
/// it the focus point of a wide view's corner pixel could overflow f32.
pub const MAX_LENS_LENGTH: f32 = 1e20;

/// Whether `x` is a lens radius (`>= 0`) or, when `positive`, a focus
/// distance or f-number (`> 0`), finite and at most [`MAX_LENS_LENGTH`].
pub fn lens_length_is_valid(x: f32, positive: bool) -> bool {
    x.is_finite() && x <= MAX_LENS_LENGTH && if positive { x > 0.0 } else { x >= 0.0 }
}

/// Most blades a polygonal aperture may have (more look round anyway).
pub const MAX_BLADES: u32 = 64;

/// Whether `n` blades make an aperture: 0 (round) or 3 to [`MAX_BLADES`].
pub fn blades_are_valid(n: u32) -> bool {
    n == 0 || (3..=MAX_BLADES).contains(&n)
}

/// Where a thin lens focuses.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Focus {
    /// At this distance from the lens along the view axis, in scene units.
    Distance(f32),
    /// At the first hit of the pinhole ray through the centre of this pixel
    /// (column, row from the top-left), its distance along the view axis.
    Pixel([u32; 2]),
}

/// A thin lens as a scene file or the options describe it, each part
/// optional; [`DepthOfField::or`] fills what one source leaves out from
/// another.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct DepthOfField {
    /// The opening; `None` (or a radius of 0) keeps the pinhole.
    pub aperture: Option<Aperture>,
    /// The focus; `None` focuses on the first hit at the image's centre.
    pub focus: Option<Focus>,
    /// Blades of a polygonal aperture (3 or more); `None` or 0: round.
    pub blades: Option<u32>,
}

impl DepthOfField {
    /// Each part of `self`, else of `other`.
    pub fn or(self, other: DepthOfField) -> DepthOfField {
        DepthOfField {
            aperture: self.aperture.or(other.aperture),
            focus: self.focus.or(other.focus),
            blades: self.blades.or(other.blades),
        }
    }

    /// Whether the lens is more than a pinhole.
    pub fn is_open(&self) -> bool {
        match self.aperture {
            Some(Aperture::Radius(r)) => r > 0.0,
            Some(Aperture::FNumber(_)) => true,
            None => false,
        }
    }
}

/// A thin lens focused at a distance, before an image size is chosen (an
/// f-number's radius depends on the focal length in pixels and the image's
/// longer side).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FocusedLens {
    /// The opening.
    pub aperture: Aperture,
    /// Distance of the focus plane along the view axis, in scene units.
    pub focus_distance: f32,
    /// Blades of a polygonal aperture; below 3: round.
    pub blades: u32,
}

/// A camera's thin lens, in scene units.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ThinLens {
    /// The lens's radius (to a polygon's corners), above 0.
    pub radius: f32,
    /// Distance of the focus plane along the view axis, above 0.
    pub focus_distance: f32,
    /// Blades of a polygonal aperture; below 3: round.
    pub blades: u32,
}

impl ThinLens {
    /// The point of the lens for `u ∈ [0, 1)²`, in the lens plane (x right,
    /// y down), uniform over its area: the concentric map onto the disk, or
    /// for `n` blades a fan of `n` triangles from the centre to the polygon's
    /// corners (the first corner straight up), `u.x` choosing the triangle.
    #[inline]
    pub fn point(&self, u: Vec2) -> Vec2 {
        if self.blades < 3 {
            return self.radius * crate::materials::concentric_disk(u);
        }
        let n = self.blades as f32;
        let scaled = u.x * n;
        let side = scaled.floor().min(n - 1.0);
        let along = scaled - side;
        let corner = |k: f32| {
            let (sin, cos) = (std::f32::consts::TAU * k / n).sin_cos();
            Vec2::new(sin, -cos)
        };
        let (a, b) = (corner(side), corner(side + 1.0));
        // A uniform point of the triangle (centre, a, b): the square root
        // spreads it evenly from the centre out.
        self.radius * u.y.sqrt() * (a + along * (b - a))
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
    /// A thin lens the file asks for (glTF cameras are pinholes).
    pub depth_of_field: DepthOfField,
    /// The window of the film the file renders (Mitsuba's crop window);
    /// `None`: the whole film.
    pub window: Option<FilmWindow>,
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
    /// The thin lens, `None` for a pinhole (or an orthographic camera's
    /// parallel rays).
    pub thin_lens: Option<ThinLens>,
    /// Where the view axis meets the image, in its pixel coordinates: the
    /// image's centre `(W/2, H/2)`, or for a window of a larger film
    /// ([`Camera::window`]) the film's centre.
    pub centre: Vec2,
}

/// A window of a camera's film: only its pixels are rendered, with the
/// whole film's projection (Mitsuba's `hdrfilm` crop window).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FilmWindow {
    /// The film's size in pixels the window is given in.
    pub film: [u32; 2],
    /// The window's top-left pixel (column, row).
    pub offset: [u32; 2],
    /// The window's size in pixels, at least 1 each and within the film.
    pub size: [u32; 2],
}

impl FilmWindow {
    /// The window on a film of `width × height` pixels: the same pixels when
    /// that is the film's size, else the window scaled with the film (each
    /// edge rounded to the nearest pixel, at least one pixel wide).
    pub fn at(&self, width: u32, height: u32) -> FilmWindow {
        let scale = |v: u32, to: u32, from: u32| -> u32 {
            // round(v · to / from) in integers: exact at to == from.
            ((2 * u64::from(v) * u64::from(to) + u64::from(from)) / (2 * u64::from(from))) as u32
        };
        let axis = |k: usize, to: u32| {
            let from = self.film[k];
            let start = scale(self.offset[k], to, from).min(to - 1);
            let end = scale(self.offset[k] + self.size[k], to, from).clamp(start + 1, to);
            (start, end - start)
        };
        let (x, w) = axis(0, width);
        let (y, h) = axis(1, height);
        FilmWindow {
            film: [width, height],
            offset: [x, y],
            size: [w, h],
        }
    }
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
            thin_lens: None,
            centre: Vec2::new(0.5 * width as f32, 0.5 * height as f32),
        }
    }

    /// This camera's image cut to `window` of its film (the window's offset
    /// and size; [`FilmWindow::at`] fits a window to the film): the same
    /// rays through the same film points, only those of the window's pixels,
    /// and the image the window's size.
    pub fn window(self, window: FilmWindow) -> Camera {
        let [x, y] = window.offset;
        Camera {
            width: window.size[0],
            height: window.size[1],
            centre: self.centre - Vec2::new(x as f32, y as f32),
            ..self
        }
    }

    /// This camera with `lens` in front: an f-number takes the focal length
    /// of [`SENSOR_MM`] across the image's longer side (perspective cameras
    /// only; an orthographic one has no focal length and keeps its parallel
    /// rays); a radius of 0 leaves the pinhole as it is.
    pub fn focused(self, lens: FocusedLens) -> Camera {
        let radius = match (lens.aperture, self.ortho_px) {
            (Aperture::Radius(r), _) => r,
            (Aperture::FNumber(n), None) => {
                let focal_mm = SENSOR_MM * self.focal_px / self.width.max(self.height) as f32;
                // Millimetres to metres, the diameter to the radius.
                0.5 * focal_mm / n * 1e-3
            }
            (Aperture::FNumber(_), Some(_)) => 0.0,
        };
        let thin_lens = (radius > 0.0).then_some(ThinLens {
            radius,
            focus_distance: lens.focus_distance,
            blades: lens.blades,
        });
        Camera { thin_lens, ..self }
    }

    /// The ray through image point `(px, py)` in pixel units, with a unit
    /// direction, from the centre of projection: a pinhole's, or the ray
    /// through a thin lens's centre (renders take [`Camera::lens_ray`]).
    #[inline]
    pub fn ray(&self, px: f32, py: f32) -> Ray {
        let (x, y) = (px - self.centre.x, py - self.centre.y);
        if let Some(s) = self.ortho_px {
            let origin = self.position + self.rotation * Vec3A::new(x * s, y * s, 0.0);
            return Ray::new(origin, self.rotation.z_axis);
        }
        let d = Vec3A::new(x, y, self.focal_px);
        Ray::new(self.position, (self.rotation * d).normalize())
    }

    /// The ray through image point `(px, py)` and the point of the thin lens
    /// that `lens` (in `[0, 1)²`) picks ([`ThinLens::point`]), with a unit
    /// direction: it starts on the lens and goes through the point that
    /// [`Camera::ray`] reaches at the focus distance along the view axis.
    /// Without a lens, [`Camera::ray`] itself, bit for bit.
    #[inline]
    pub fn lens_ray(&self, px: f32, py: f32, lens: Vec2) -> Ray {
        let Some(thin) = self.thin_lens else {
            return self.ray(px, py);
        };
        let (x, y) = (px - self.centre.x, py - self.centre.y);
        let on_lens = thin.point(lens);
        let f = thin.focus_distance;
        // In camera space: where the pinhole ray meets the focus plane, and
        // where this ray starts.
        let (focus, start) = match self.ortho_px {
            Some(s) => {
                let centre = Vec3A::new(x * s, y * s, 0.0);
                (
                    centre + Vec3A::new(0.0, 0.0, f),
                    centre + Vec3A::from(on_lens.extend(0.0)),
                )
            }
            None => (
                Vec3A::new(x, y, self.focal_px) * (f / self.focal_px),
                Vec3A::from(on_lens.extend(0.0)),
            ),
        };
        Ray::new(
            self.position + self.rotation * start,
            (self.rotation * (focus - start)).normalize(),
        )
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
        let x = Vec4::from_array(px) - Vec4::splat(self.centre.x);
        let y = Vec4::from_array(py) - Vec4::splat(self.centre.y);
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
    /// orthographic camera or one with a thin lens (whose rays need the
    /// lens's samples: [`Camera::lens_ray`]).
    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    pub(crate) fn rays8(&self, px: &[f32; 8], py: &[f32; 8]) -> Option<Rays8> {
        if self.ortho_px.is_some() || self.thin_lens.is_some() {
            return None;
        }
        let x = F8::from_array(*px) - F8::splat(self.centre.x);
        let y = F8::from_array(*py) - F8::splat(self.centre.y);
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

    /// Where a perspective camera (a pinhole or a thin lens) sees the world
    /// point `p` through the point of its lens that `lens` picks
    /// ([`ThinLens::point`]; ignored by a pinhole): the lens point (world),
    /// the image point (in pixels, within the image) whose rays through
    /// that lens point pass `p` (the ray from the lens point through `p`
    /// meets the focus plane where the pixel's pinhole ray does), and the
    /// unit direction from the lens point to `p`. `None` behind the lens,
    /// outside the image, or for an orthographic camera.
    pub fn seen_at(&self, p: Vec3A, lens: Vec2) -> Option<(Vec3A, Vec2, Vec3A)> {
        if self.ortho_px.is_some() {
            return None;
        }
        let (start, local) = match self.thin_lens {
            None => (Vec3A::ZERO, self.rotation.transpose() * (p - self.position)),
            Some(thin) => {
                let start = Vec3A::from(thin.point(lens).extend(0.0));
                let to_p = self.rotation.transpose() * (p - self.position) - start;
                if !to_p.z.gt(&0.0) {
                    return None;
                }
                // Where the ray from the lens point through `p` crosses the
                // focus plane, in camera space.
                let f = thin.focus_distance;
                (start, start + to_p * (f / to_p.z))
            }
        };
        if !local.z.gt(&0.0) {
            return None;
        }
        let x = self.centre.x + local.x / local.z * self.focal_px;
        let y = self.centre.y + local.y / local.z * self.focal_px;
        let inside = x >= 0.0 && y >= 0.0 && x < self.width as f32 && y < self.height as f32;
        let origin = self.position + self.rotation * start;
        inside.then(|| (origin, Vec2::new(x, y), (p - origin).normalize()))
    }

    /// Whether the camera is orthographic.
    pub fn is_orthographic(&self) -> bool {
        self.ortho_px.is_some()
    }

    /// The solid-angle density with which a perspective camera's rays from
    /// one point of its lens (the centre of projection of a pinhole), over
    /// the whole image (a pixel chosen uniformly, then a point in it), take
    /// the unit direction `dir`: `f² / (W H cos³θ)` with `f` the focal
    /// length in pixels and `θ` the angle to the view axis (one pixel spans
    /// `cos³θ / f²` sr; through a thin lens the pixels map onto the focus
    /// plane as through its centre, so the same holds from every lens
    /// point). It is also the camera's importance times `cos θ`,
    /// which light paths splatted onto the image are weighted by. Zero
    /// outside the image's cone of directions is the caller's to check
    /// ([`Camera::seen_at`]).
    pub fn direction_density(&self, dir: Vec3A) -> f32 {
        let cos = dir.dot(self.rotation.z_axis);
        if !cos.gt(&0.0) {
            return 0.0;
        }
        let f2 = self.focal_px * self.focal_px;
        f2 / (self.width as f32 * self.height as f32 * cos * cos * cos)
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

    /// A camera of 320×200 pixels (f = 250 px, so a 36 mm sensor across its
    /// 320 px gives a 28.125 mm lens) turned and moved off the axes, with a
    /// thin lens of radius `radius` focused at `focus`.
    fn lens_camera(radius: f32, focus: f32, blades: u32) -> Camera {
        let rotation = lab_rotation(23.0, -11.0);
        Camera::with_lens(
            Vec3A::new(0.3, -0.2, 1.5),
            rotation,
            Lens::Perspective { focal_scale: 1.25 },
            320,
            200,
        )
        .focused(FocusedLens {
            aperture: Aperture::Radius(radius),
            focus_distance: focus,
            blades,
        })
    }

    /// Lens samples over the whole square, its edges (the lens's rim)
    /// included.
    fn lens_samples() -> Vec<Vec2> {
        let steps = [0.0, 0.1, 0.25, 0.4, 0.5, 0.6, 0.75, 0.9, 1.0 - 1e-7];
        steps
            .iter()
            .flat_map(|&x| steps.iter().map(move |&y| Vec2::new(x, y)))
            .collect()
    }

    /// The image point (pixel units) whose ray through lens point `u` passes
    /// through world point `p`, found with the camera's rays alone: where a
    /// ray meets the plane at `p`'s depth is affine in the image point, so
    /// three rays give it exactly (to rounding).
    fn image_of(camera: &Camera, p: Vec3A, u: Vec2) -> Vec2 {
        let forward = camera.forward();
        let depth = (p - camera.position).dot(forward);
        let meet = |px: f32, py: f32| {
            let ray = camera.lens_ray(px, py, u);
            let t = (depth - (ray.origin - camera.position).dot(forward)) / ray.dir.dot(forward);
            let q = ray.origin + t * ray.dir - camera.position;
            glam::DVec2::new(q.dot(camera.right()) as f64, q.dot(camera.down()) as f64)
        };
        let (x0, y0) = (160.0f32, 100.0f32);
        let o = meet(x0, y0);
        let (ex, ey) = (meet(x0 + 50.0, y0) - o, meet(x0, y0 + 50.0) - o);
        let offset = p - camera.position;
        let target = glam::DVec2::new(
            offset.dot(camera.right()) as f64,
            offset.dot(camera.down()) as f64,
        );
        // Solve o + a·ex + b·ey = target (a, b in steps of 50 px).
        let ab = glam::DMat2::from_cols(ex, ey).inverse() * (target - o);
        Vec2::new(x0 + (50.0 * ab.x) as f32, y0 + (50.0 * ab.y) as f32)
    }

    /// `seen_at` inverts `lens_ray`: a point on the ray through image point
    /// `(px, py)` and lens point `u` is seen through that lens point at that
    /// image point, from the ray's origin, along its direction (a pinhole
    /// and a thin lens, round and with blades, in and out of focus).
    #[test]
    fn seen_at_inverts_lens_rays() {
        let pinhole = Camera::with_lens(
            Vec3A::new(0.3, -0.2, 1.5),
            lab_rotation(23.0, -11.0),
            Lens::Perspective { focal_scale: 1.25 },
            320,
            200,
        );
        for camera in [pinhole, lens_camera(0.2, 3.0, 0), lens_camera(0.2, 3.0, 6)] {
            for (px, py) in [(0.5, 0.5), (160.0, 100.0), (319.25, 17.75), (5.5, 199.0)] {
                for u in lens_samples() {
                    let ray = camera.lens_ray(px, py, u);
                    for t in [0.5f32, 3.0, 11.0] {
                        let p = ray.origin + ray.dir * t;
                        let (origin, at, dir) = camera.seen_at(p, u).expect("seen");
                        assert!(
                            (origin - ray.origin).length() < 1e-5,
                            "{origin} {}",
                            ray.origin
                        );
                        assert!(
                            (at - Vec2::new(px, py)).length() < 2e-3,
                            "({px}, {py}) through {u} at {t}: {at}"
                        );
                        assert!((dir - ray.dir).length() < 1e-5);
                    }
                }
            }
        }
    }

    /// A point at depth z spreads over the thin lens's circle of confusion,
    /// of diameter 2R·f·|z − F| / (z·F) pixels, whatever the lens sample;
    /// a point on the focus plane images to one point for every lens sample.
    #[test]
    fn out_of_focus_points_spread_over_the_circle_of_confusion() {
        let (radius, focus) = (0.05, 4.0);
        let camera = lens_camera(radius, focus, 0);
        let f = camera.focal_px;
        assert_eq!(f, 250.0);
        let off_axis = |z: f32| {
            // A point at depth z, seen 40 px right of and 25 px above the
            // image's centre by the pinhole.
            let d = camera.rotation * Vec3A::new(40.0, -25.0, f);
            camera.position + d * (z / f)
        };
        for z in [1.0f32, 2.5, 3.9, 4.0, 4.2, 7.0, 40.0] {
            let p = off_axis(z);
            let images: Vec<Vec2> = lens_samples()
                .into_iter()
                .map(|u| image_of(&camera, p, u))
                .collect();
            let centre = image_of(&camera, p, Vec2::splat(0.5));
            // The lens's centre sees the point where the pinhole does.
            assert!(
                (centre - Vec2::new(200.0, 75.0)).length() < 1e-3,
                "{z}: {centre}"
            );
            let want = 2.0 * radius * f * (z - focus).abs() / (z * focus);
            let spread = images
                .iter()
                .flat_map(|a| images.iter().map(move |b| (*a - *b).length()))
                .fold(0.0f32, f32::max);
            let tolerance = 2e-3 + 1e-3 * want;
            assert!(
                (spread - want).abs() <= tolerance,
                "z = {z}: the image spreads over {spread} px, the thin-lens formula says {want}"
            );
            for image in &images {
                assert!(
                    (*image - centre).length() <= 0.5 * want + tolerance,
                    "{z}: {image}"
                );
            }
        }
    }

    /// Every ray starts on the lens (in the plane through the position across
    /// the view axis, within the radius) and passes through the point the
    /// pinhole ray through the same image point reaches at the focus distance.
    #[test]
    fn lens_rays_start_on_the_lens_and_meet_the_pinhole_ray_at_the_focus() {
        for blades in [0, 5] {
            let camera = lens_camera(0.2, 3.0, blades);
            for (px, py) in [(0.0, 0.0), (160.0, 100.0), (319.5, 17.25), (5.5, 199.0)] {
                let pinhole = camera.ray(px, py);
                let focus_point =
                    pinhole.origin + pinhole.dir * (3.0 / pinhole.dir.dot(camera.forward()));
                for u in lens_samples() {
                    let ray = camera.lens_ray(px, py, u);
                    let offset = ray.origin - camera.position;
                    assert!(offset.dot(camera.forward()).abs() < 1e-6);
                    assert!(offset.length() <= 0.2 * (1.0 + 1e-5), "{offset}");
                    let t = (focus_point - ray.origin).dot(ray.dir);
                    let miss = (ray.origin + t * ray.dir - focus_point).length();
                    assert!(miss < 2e-5, "{px} {py} {u}: {miss}");
                    assert!((ray.dir.length() - 1.0).abs() < 1e-6);
                }
            }
        }
    }

    /// With a radius of 0 the camera stays a pinhole: `lens_ray` is `ray`,
    /// bit for bit, for any lens sample.
    #[test]
    fn a_closed_lens_is_the_pinhole_bit_for_bit() {
        let closed = lens_camera(0.0, 2.0, 6);
        assert_eq!(closed.thin_lens, None);
        let pinhole = Camera::with_lens(
            closed.position,
            closed.rotation,
            Lens::Perspective { focal_scale: 1.25 },
            320,
            200,
        );
        assert_eq!(closed, pinhole);
        let bits = |r: Ray| [r.origin, r.dir].map(|v| v.to_array().map(f32::to_bits));
        for u in lens_samples() {
            for (px, py) in [(0.5, 0.5), (100.25, 33.75), (319.0, 199.0)] {
                assert_eq!(bits(closed.lens_ray(px, py, u)), bits(pinhole.ray(px, py)));
            }
        }
    }

    /// An f-number's radius is half the focal length of a 36 mm sensor across
    /// the image's longer side over N, in metres; an orthographic camera
    /// keeps its parallel rays.
    #[test]
    fn an_f_number_opens_the_lens_as_a_36_mm_camera_does() {
        let camera = lens_camera(0.0, 2.0, 0).focused(FocusedLens {
            aperture: Aperture::FNumber(2.8125),
            focus_distance: 2.0,
            blades: 0,
        });
        // f = 250 px across 320 px: 28.125 mm, so f/2.8125 is 10 mm wide.
        let lens = camera.thin_lens.expect("open");
        assert!((lens.radius - 0.005).abs() < 1e-8, "{}", lens.radius);
        let ortho = Camera::with_lens(
            Vec3A::ZERO,
            Mat3A::IDENTITY,
            Lens::Orthographic { half_height: 1.0 },
            40,
            20,
        );
        let focused = |aperture| {
            ortho.focused(FocusedLens {
                aperture,
                focus_distance: 2.0,
                blades: 0,
            })
        };
        assert_eq!(focused(Aperture::FNumber(2.0)).thin_lens, None);
        // An orthographic camera with a radius: rays from the lens around
        // the pixel's own origin, through the point 2 units along the axis.
        let camera = focused(Aperture::Radius(0.1));
        let ray = camera.lens_ray(0.0, 0.0, Vec2::new(0.0, 0.5));
        let centre = ortho.ray(0.0, 0.0);
        assert!((ray.origin - (centre.origin + Vec3A::new(-0.1, 0.0, 0.0))).length() < 1e-6);
        let t = 2.0 / ray.dir.z;
        assert!((ray.origin + t * ray.dir - (centre.origin + Vec3A::Z * 2.0)).length() < 1e-5);
    }

    /// Lens points are uniform over the disk or the polygon: each of four
    /// quadrants gets its share of a grid of samples, and a polygon's points
    /// stay inside it (within its inscribed circle's reach past the sides).
    #[test]
    fn lens_points_cover_the_aperture_uniformly() {
        for blades in [0, 3, 6] {
            let lens = ThinLens {
                radius: 2.0,
                focus_distance: 1.0,
                blades,
            };
            let n = 200;
            let mut quadrants = [0u32; 4];
            let mut inside_half = 0;
            for i in 0..n {
                for j in 0..n {
                    let u = Vec2::new((i as f32 + 0.5) / n as f32, (j as f32 + 0.5) / n as f32);
                    let p = lens.point(u);
                    assert!(p.length() <= 2.0 * (1.0 + 1e-6), "{blades}: {p}");
                    if blades >= 3 {
                        // Inside every side: the side's normal at angle
                        // (k + ½)·2π/n from straight up, at distance r·cos(π/n).
                        let apothem = 2.0 * (std::f32::consts::PI / blades as f32).cos();
                        for k in 0..blades {
                            let a = std::f32::consts::TAU * (k as f32 + 0.5) / blades as f32;
                            let normal = Vec2::new(a.sin(), -a.cos());
                            assert!(p.dot(normal) <= apothem * (1.0 + 1e-5), "{blades}: {p}");
                        }
                    }
                    quadrants[(p.x >= 0.0) as usize + 2 * (p.y >= 0.0) as usize] += 1;
                    inside_half += (p.length() < 1.0) as u32;
                }
            }
            let total = (n * n) as f32;
            if blades != 3 {
                for q in quadrants {
                    assert!(
                        (q as f32 / total - 0.25).abs() < 0.01,
                        "{blades}: {quadrants:?}"
                    );
                }
            }
            // A disk of half the radius holds a quarter of the area (of a
            // polygon's, with its corners cut: 1/4 × π/(n/2·sin(2π/n))).
            let area = match blades {
                0 => std::f32::consts::PI,
                n => 0.5 * n as f32 * (std::f32::consts::TAU / n as f32).sin(),
            };
            let want = 0.25 * std::f32::consts::PI / area;
            assert!(
                (inside_half as f32 / total - want).abs() < 0.01,
                "{blades}: {} against {want}",
                inside_half as f32 / total
            );
        }
    }

    /// A window of the film keeps the film's rays: its pixel `(x, y)` is the
    /// film's `(x + ox, y + oy)`, for pinholes, thin lenses and parallel
    /// rays; its four-ray path matches its one-ray path bit for bit.
    #[test]
    fn a_window_keeps_the_films_rays() {
        let window = FilmWindow {
            film: [320, 200],
            offset: [211, 13],
            size: [64, 48],
        };
        let ortho = Camera::with_lens(
            Vec3A::new(1.0, 2.0, 3.0),
            lab_rotation(-30.0, 12.0),
            Lens::Orthographic { half_height: 2.5 },
            320,
            200,
        );
        for film in [lens_camera(0.0, 2.0, 0), lens_camera(0.1, 3.0, 0), ortho] {
            let cut = film.window(window);
            assert_eq!((cut.width, cut.height), (64, 48));
            for (px, py) in [(0.0, 0.0), (31.5, 20.25), (63.9, 47.9)] {
                for u in [Vec2::splat(0.5), Vec2::new(0.1, 0.8)] {
                    let a = cut.lens_ray(px, py, u);
                    let b = film.lens_ray(px + 211.0, py + 13.0, u);
                    assert!((a.origin - b.origin).length() < 1e-5, "{px} {py}");
                    assert!((a.dir - b.dir).length() < 1e-6, "{px} {py}");
                }
            }
            let (px, py) = ([0.5, 10.25, 40.0, 63.75], [47.5, 3.0, 20.5, 0.25]);
            let four = cut.rays4(px, py);
            for i in 0..4 {
                let one = cut.ray(px[i], py[i]);
                assert_eq!(
                    [four[i].origin, four[i].dir].map(|v| v.to_array().map(f32::to_bits)),
                    [one.origin, one.dir].map(|v| v.to_array().map(f32::to_bits)),
                );
            }
        }
        // The whole film as a window is the camera itself.
        let camera = lens_camera(0.1, 3.0, 0);
        let whole = FilmWindow {
            film: [320, 200],
            offset: [0, 0],
            size: [320, 200],
        };
        assert_eq!(camera.window(whole), camera);
        // Fitted to a film of another size: the same part of it, each edge
        // rounded, at least a pixel.
        assert_eq!(window.at(320, 200), window);
        let half = window.at(160, 100);
        assert_eq!((half.offset, half.size), ([106, 7], [32, 24]));
        let tiny = window.at(2, 1);
        assert_eq!((tiny.offset, tiny.size), ([1, 0], [1, 1]));
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
