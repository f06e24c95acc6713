//! The viewer's state (camera, light, integrator) and how user input changes it,
//! kept free of any windowing code so that it can be tested on its own.

use glam::{Mat3A, Vec3A};

use crate::camera::{Camera, FilmWindow, FocusedLens, Lens, lab_rotation};
use crate::integrators::Integrator;

/// Camera turn per key press, in degrees.
pub const TURN_STEP_DEG: f32 = 5.0;
/// Degrees of yaw or pitch per pixel of mouse drag.
pub const DRAG_DEG_PER_PIXEL: f32 = 0.25;
/// Pitch stays within ±this, so the view never flips over.
pub const MAX_PITCH_DEG: f32 = 89.0;
/// Factor of the fog's density per press of the fog keys.
pub const FOG_STEP: f32 = 1.5;
/// The thinnest fog before none (as a factor of the scene's fog; [`ViewState::fog`]).
pub const FOG_MIN: f32 = 0.131_687_24; // 1.5^-5
/// The thickest fog (1.5^10).
pub const FOG_MAX: f32 = 57.665_04;

/// Something the user asked for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Action {
    /// Move the camera along its view direction.
    CameraForward,
    /// Move the camera against its view direction.
    CameraBack,
    /// Turn the camera left (yaw down).
    TurnLeft,
    /// Turn the camera right (yaw up).
    TurnRight,
    /// Move the light away from the viewer (camera forward, kept level).
    LightForward,
    /// Move the light towards the viewer.
    LightBack,
    /// Move the light to the viewer's left.
    LightLeft,
    /// Move the light to the viewer's right.
    LightRight,
    /// Move the light up (the image's up direction).
    LightUp,
    /// Move the light down.
    LightDown,
    /// Return camera, light and integrator to where they started.
    Reset,
    /// Switch to an integrator.
    Use(Integrator),
    /// Save the current frame as a PNG.
    Screenshot,
    /// Show the denoised frame once the view rests, or stop showing it.
    ToggleDenoise,
    /// Make the fog thicker (turn it on if there is none).
    FogThicker,
    /// Make the fog thinner (off below [`FOG_MIN`]).
    FogThinner,
    /// Close the viewer.
    Quit,
}

/// What the viewer shows: a lab camera (position, yaw, pitch in a base frame), the
/// light position and the integrator.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ViewState {
    /// Camera position.
    pub camera_pos: Vec3A,
    /// Camera-to-world rotation at yaw = pitch = 0 (identity in the lab box).
    pub base: Mat3A,
    /// Camera and light travel per key press, in scene units.
    pub step: f32,
    /// Camera yaw in degrees.
    pub yaw_deg: f32,
    /// Camera pitch in degrees.
    pub pitch_deg: f32,
    /// Light position.
    pub light_pos: Vec3A,
    /// Integrator in use.
    pub integrator: Integrator,
    /// The camera's projection.
    pub lens: Lens,
    /// A thin lens in front of it, focused; `None`: a pinhole.
    pub thin_lens: Option<FocusedLens>,
    /// The window of the film that is shown (a Mitsuba scene's crop
    /// window), fitted to the image's size ([`FilmWindow::at`]); `None`:
    /// the whole film.
    pub window: Option<FilmWindow>,
    /// The fog's density as a factor of the scene's own fog (or, for a
    /// scene without, of a default fog: one mean free path per scene
    /// radius): 0 is none, else from [`FOG_MIN`] to [`FOG_MAX`] in steps of
    /// [`FOG_STEP`].
    pub fog: f32,
}

impl ViewState {
    /// The camera for a film of `width × height`: its window's pixels when
    /// it has one (the camera's image is then the window's size).
    pub fn camera(&self, width: u32, height: u32) -> Camera {
        let pinhole = Camera::with_lens(
            self.camera_pos,
            self.base * lab_rotation(self.yaw_deg, self.pitch_deg),
            self.lens,
            width,
            height,
        );
        let camera = match self.thin_lens {
            Some(lens) => pinhole.focused(lens),
            None => pinhole,
        };
        match self.window {
            Some(window) => camera.window(window.at(width, height)),
            None => camera,
        }
    }

    /// Applies a state-changing action; returns whether anything changed.
    /// `initial` is the state that [`Action::Reset`] returns to.
    pub fn apply(&mut self, action: Action, initial: &ViewState) -> bool {
        let before = *self;
        let rot = self.base * lab_rotation(self.yaw_deg, self.pitch_deg);
        // The light moves in the camera's level frame: forward without pitch, so
        // W/S keep the light's height; "up" is the image's up.
        let level = self.base * lab_rotation(self.yaw_deg, 0.0);
        let step = self.step;
        match action {
            Action::CameraForward => self.camera_pos += step * rot.z_axis,
            Action::CameraBack => self.camera_pos -= step * rot.z_axis,
            Action::TurnLeft => self.yaw_deg -= TURN_STEP_DEG,
            Action::TurnRight => self.yaw_deg += TURN_STEP_DEG,
            Action::LightForward => self.light_pos += step * level.z_axis,
            Action::LightBack => self.light_pos -= step * level.z_axis,
            Action::LightLeft => self.light_pos -= step * level.x_axis,
            Action::LightRight => self.light_pos += step * level.x_axis,
            Action::LightUp => self.light_pos -= step * level.y_axis,
            Action::LightDown => self.light_pos += step * level.y_axis,
            Action::Reset => *self = *initial,
            Action::Use(integrator) => self.integrator = integrator,
            Action::FogThicker => {
                self.fog = if self.fog < FOG_MIN {
                    FOG_MIN
                } else {
                    (self.fog * FOG_STEP).min(FOG_MAX)
                }
            }
            Action::FogThinner => {
                let thinner = self.fog / FOG_STEP;
                self.fog = if thinner < FOG_MIN * 0.999 {
                    0.0
                } else {
                    thinner
                }
            }
            Action::Screenshot | Action::Quit | Action::ToggleDenoise => {}
        }
        self.yaw_deg = wrap_degrees(self.yaw_deg);
        *self != before
    }

    /// Mouse-look: dragging right turns right, dragging up looks up.
    pub fn drag(&mut self, dx_px: f32, dy_px: f32) -> bool {
        self.turn(DRAG_DEG_PER_PIXEL * dx_px, -DRAG_DEG_PER_PIXEL * dy_px)
    }

    /// Turns the camera by `yaw_deg` (positive: right) and `pitch_deg`
    /// (positive: up), as a mouse drag does: yaw wraps into `(-180, 180]`,
    /// pitch stays within ±[`MAX_PITCH_DEG`]. Returns whether anything changed.
    pub fn turn(&mut self, yaw_deg: f32, pitch_deg: f32) -> bool {
        let before = *self;
        self.yaw_deg = wrap_degrees(self.yaw_deg + yaw_deg);
        self.pitch_deg = (self.pitch_deg + pitch_deg).clamp(-MAX_PITCH_DEG, MAX_PITCH_DEG);
        *self != before
    }
}

/// `deg` wrapped into `(-180, 180]`.
fn wrap_degrees(deg: f32) -> f32 {
    let w = deg.rem_euclid(360.0);
    if w > 180.0 { w - 360.0 } else { w }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::load::cornell::LAB_STEP;

    fn start() -> ViewState {
        ViewState {
            camera_pos: Vec3A::new(0.0, 0.0, -3.0),
            base: Mat3A::IDENTITY,
            step: LAB_STEP,
            yaw_deg: 0.0,
            pitch_deg: 0.0,
            light_pos: Vec3A::new(0.0, -0.5, -0.7),
            integrator: Integrator::Direct,
            lens: Lens::LAB,
            thin_lens: None,
            window: None,
            fog: 0.0,
        }
    }

    fn close(a: Vec3A, b: Vec3A) -> bool {
        (a - b).length() < 1e-5
    }

    #[test]
    fn camera_moves_along_its_view_direction_and_turns() {
        let init = start();
        let mut s = init;
        assert!(s.apply(Action::CameraForward, &init));
        assert!(close(s.camera_pos, Vec3A::new(0.0, 0.0, -2.9)));
        assert!(s.apply(Action::TurnRight, &init));
        assert_eq!(s.yaw_deg, 5.0);
        // After turning 90° right, forward is +x.
        for _ in 0..17 {
            s.apply(Action::TurnRight, &init);
        }
        assert!((s.yaw_deg - 90.0).abs() < 1e-4);
        s.apply(Action::CameraForward, &init);
        assert!(close(s.camera_pos, Vec3A::new(0.1, 0.0, -2.9)));
        s.apply(Action::CameraBack, &init);
        s.apply(Action::CameraBack, &init);
        assert!(close(s.camera_pos, Vec3A::new(-0.1, 0.0, -2.9)));
        s.apply(Action::TurnLeft, &init);
        assert!((s.yaw_deg - 85.0).abs() < 1e-4);
    }

    #[test]
    fn light_moves_in_the_viewers_frame() {
        let init = start();
        let mut s = init;
        let l = init.light_pos;
        let moved = |a: Action| {
            let mut t = init;
            t.apply(a, &init);
            t.light_pos - l
        };
        assert!(close(
            moved(Action::LightForward),
            Vec3A::new(0.0, 0.0, 0.1)
        ));
        assert!(close(moved(Action::LightBack), Vec3A::new(0.0, 0.0, -0.1)));
        assert!(close(moved(Action::LightLeft), Vec3A::new(-0.1, 0.0, 0.0)));
        assert!(close(moved(Action::LightRight), Vec3A::new(0.1, 0.0, 0.0)));
        // y points down in the lab box: up is -y.
        assert!(close(moved(Action::LightUp), Vec3A::new(0.0, -0.1, 0.0)));
        assert!(close(moved(Action::LightDown), Vec3A::new(0.0, 0.1, 0.0)));
        // Turned 90° right, "left" is -z; pitch does not tilt the light's moves.
        s.yaw_deg = 90.0;
        s.pitch_deg = 30.0;
        s.apply(Action::LightLeft, &init);
        assert!(close(s.light_pos - l, Vec3A::new(0.0, 0.0, 0.1)));
    }

    #[test]
    fn reset_integrator_switch_and_no_ops() {
        let init = start();
        let mut s = init;
        s.apply(Action::LightLeft, &init);
        s.drag(40.0, -20.0);
        assert!(s.apply(Action::Use(Integrator::Flat), &init));
        assert!(!s.apply(Action::Use(Integrator::Flat), &init));
        assert!(s.apply(Action::Reset, &init));
        assert_eq!(s, init);
        assert!(!s.apply(Action::Screenshot, &init));
        assert!(!s.apply(Action::Quit, &init));
        assert!(!s.apply(Action::ToggleDenoise, &init));
    }

    #[test]
    fn y_up_scenes_move_in_their_own_frame() {
        let mut init = start();
        init.base = crate::camera::Y_UP_TOWARDS_MINUS_Z;
        init.step = 2.0;
        let mut s = init;
        s.apply(Action::CameraForward, &init);
        assert!(close(
            s.camera_pos - init.camera_pos,
            Vec3A::new(0.0, 0.0, -2.0)
        ));
        s.apply(Action::LightUp, &init);
        assert!(close(
            s.light_pos - init.light_pos,
            Vec3A::new(0.0, 2.0, 0.0)
        ));
        s.apply(Action::LightRight, &init);
        assert!(close(
            s.light_pos - init.light_pos,
            Vec3A::new(2.0, 2.0, 0.0)
        ));
    }

    /// The fog keys step the density by 1.5 between off, the thinnest and
    /// the thickest; a scene's own fog (1) comes back after a press each
    /// way; reset restores it.
    #[test]
    fn fog_keys_thicken_and_thin_the_fog() {
        let mut init = start();
        init.fog = 1.0;
        let mut s = init;
        assert!(s.apply(Action::FogThicker, &init));
        assert!((s.fog - 1.5).abs() < 1e-6);
        s.apply(Action::FogThinner, &init);
        assert!((s.fog - 1.0).abs() < 1e-6);
        for _ in 0..5 {
            s.apply(Action::FogThinner, &init);
        }
        assert!((s.fog - FOG_MIN).abs() < 1e-6, "{}", s.fog);
        assert!(s.apply(Action::FogThinner, &init));
        assert_eq!(s.fog, 0.0, "off below the thinnest");
        assert!(!s.apply(Action::FogThinner, &init));
        assert!(s.apply(Action::FogThicker, &init));
        assert_eq!(s.fog, FOG_MIN, "on again at the thinnest");
        for _ in 0..30 {
            s.apply(Action::FogThicker, &init);
        }
        assert!((s.fog - FOG_MAX).abs() < 1e-3, "{}", s.fog);
        assert!(!s.apply(Action::FogThicker, &init));
        s.apply(Action::Reset, &init);
        assert_eq!(s.fog, 1.0);
    }

    #[test]
    fn drag_looks_around_and_clamps_pitch() {
        let init = start();
        let mut s = init;
        assert!(s.drag(40.0, 0.0));
        assert_eq!(s.yaw_deg, 10.0);
        s.drag(0.0, -40.0);
        assert_eq!(s.pitch_deg, 10.0, "dragging up looks up");
        assert!(s.camera(10, 10).forward().y < 0.0, "up is -y");
        s.drag(0.0, -10_000.0);
        assert_eq!(s.pitch_deg, MAX_PITCH_DEG);
        s.drag(-1000.0, 0.0);
        assert!(s.yaw_deg > -180.0 && s.yaw_deg <= 180.0);
        let mut t = init;
        assert!(t.turn(190.0, -100.0));
        assert_eq!((t.yaw_deg, t.pitch_deg), (-170.0, -MAX_PITCH_DEG));
        assert!(!t.turn(0.0, 0.0));
    }
}
