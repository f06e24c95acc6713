//! Which key does what in the viewer.

use raylab::Integrator;
use raylab::controls::Action;
use winit::keyboard::KeyCode;

/// The action of a key, by its position on the keyboard (layout-independent).
pub fn action_for_key(key: KeyCode) -> Option<Action> {
    Some(match key {
        KeyCode::ArrowUp => Action::CameraForward,
        KeyCode::ArrowDown => Action::CameraBack,
        KeyCode::ArrowLeft => Action::TurnLeft,
        KeyCode::ArrowRight => Action::TurnRight,
        KeyCode::KeyW => Action::LightForward,
        KeyCode::KeyS => Action::LightBack,
        KeyCode::KeyA => Action::LightLeft,
        KeyCode::KeyD => Action::LightRight,
        KeyCode::KeyQ => Action::LightUp,
        KeyCode::KeyE => Action::LightDown,
        KeyCode::KeyR => Action::Reset,
        KeyCode::Digit1 | KeyCode::Numpad1 => Action::Use(Integrator::Flat),
        KeyCode::Digit2 | KeyCode::Numpad2 => Action::Use(Integrator::Direct),
        KeyCode::Digit3 | KeyCode::Numpad3 => Action::Use(Integrator::path()),
        KeyCode::KeyP => Action::Screenshot,
        KeyCode::KeyN => Action::ToggleDenoise,
        KeyCode::BracketRight => Action::FogThicker,
        KeyCode::BracketLeft => Action::FogThinner,
        KeyCode::Escape => Action::Quit,
        _ => return None,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_lab_keys_and_the_extras_are_bound() {
        let expect = [
            (KeyCode::ArrowUp, Action::CameraForward),
            (KeyCode::ArrowDown, Action::CameraBack),
            (KeyCode::ArrowLeft, Action::TurnLeft),
            (KeyCode::ArrowRight, Action::TurnRight),
            (KeyCode::KeyW, Action::LightForward),
            (KeyCode::KeyS, Action::LightBack),
            (KeyCode::KeyA, Action::LightLeft),
            (KeyCode::KeyD, Action::LightRight),
            (KeyCode::KeyQ, Action::LightUp),
            (KeyCode::KeyE, Action::LightDown),
            (KeyCode::KeyR, Action::Reset),
            (KeyCode::Digit1, Action::Use(Integrator::Flat)),
            (KeyCode::Digit2, Action::Use(Integrator::Direct)),
            (KeyCode::Digit3, Action::Use(Integrator::path())),
            (KeyCode::Numpad3, Action::Use(Integrator::path())),
            (KeyCode::KeyP, Action::Screenshot),
            (KeyCode::KeyN, Action::ToggleDenoise),
            (KeyCode::BracketRight, Action::FogThicker),
            (KeyCode::BracketLeft, Action::FogThinner),
            (KeyCode::Escape, Action::Quit),
        ];
        for (key, action) in expect {
            assert_eq!(action_for_key(key), Some(action), "{key:?}");
        }
        assert_eq!(action_for_key(KeyCode::KeyZ), None);
    }
}
