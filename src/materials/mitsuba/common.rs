//! What the Mitsuba BSDFs share: the turn of an anisotropic BSDF's axes
//! into raylab's shading frame ([`Tangent`]) and a NaN-safe sign test.

use super::super::frame::Frame;
use glam::{Vec2, Vec3A};

/// Where an anisotropic BSDF's first axis (Mitsuba's `u`, along which the
/// width is `alpha_u`) lies in raylab's shading frame: `(cos φ, sin φ)` of
/// its angle from the frame's `x`. Mitsuba's shading frame has `dp/du` as
/// its `x`; raylab's ([`Frame::from_normal`]) has whatever the normal gives,
/// so an anisotropic BSDF turns its directions by `φ` first.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Tangent(pub Vec2);

impl Tangent {
    /// The frame's own `x` axis (no turn).
    pub const X: Tangent = Tangent(Vec2::X);

    /// The tangent along the world direction `t` projected onto the
    /// shading plane of `frame`; the frame's `x` if `t` has no such part.
    pub fn orient(frame: &Frame, t: Vec3A) -> Tangent {
        let l = frame.to_local(t);
        let d = Vec2::new(l.x, l.y).normalize_or_zero();
        if d != Vec2::ZERO && d.is_finite() {
            Tangent(d)
        } else {
            Tangent::X
        }
    }

    /// Shading-frame `v` in the BSDF's frame (`x` along the tangent).
    #[inline]
    pub fn to_local(self, v: Vec3A) -> Vec3A {
        if self == Tangent::X {
            return v;
        }
        let Vec2 { x: c, y: s } = self.0;
        Vec3A::new(c * v.x + s * v.y, c * v.y - s * v.x, v.z)
    }

    /// The BSDF frame's `v` in the shading frame.
    #[inline]
    pub fn to_shading(self, v: Vec3A) -> Vec3A {
        if self == Tangent::X {
            return v;
        }
        let Vec2 { x: c, y: s } = self.0;
        Vec3A::new(c * v.x - s * v.y, s * v.x + c * v.y, v.z)
    }
}

/// Whether `x > 0` (false for NaN).
#[inline]
pub(super) fn positive(x: f32) -> bool {
    x > 0.0
}
