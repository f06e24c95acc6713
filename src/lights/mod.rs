//! Lights: the closed set of punctual light kinds a scene holds, in radiometric
//! units (`docs/scene-conventions.md`). Area lights are emitting
//! triangles; the scene samples them (see [`crate::scene::Scene::sample_light`]).

pub mod environment;
pub mod rgbe;

use std::f32::consts::PI;

use glam::{Mat3A, Vec2, Vec3A, Vec4, Vec4Swizzles};

use crate::textures::{Pattern, TextureStore};

/// A punctual light.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Light {
    /// Light leaving a point equally in every direction.
    Point {
        /// Where it is.
        position: Vec3A,
        /// Radiant intensity per colour channel, W/sr: irradiance `I·cosθ/r²`.
        intensity: Vec3A,
    },
    /// A point light restricted to a cone (glTF `KHR_lights_punctual` spot).
    Spot {
        /// Where it is.
        position: Vec3A,
        /// Unit direction the cone's axis points to.
        direction: Vec3A,
        /// Radiant intensity on the axis, W/sr.
        intensity: Vec3A,
        /// Cosine of the inner cone angle: full intensity inside it.
        cos_inner: f32,
        /// Cosine of the outer cone angle: nothing outside it.
        cos_outer: f32,
    },
    /// A spot light with Mitsuba 3's falloff and projected texture (its
    /// `spot` emitter); see [`Beam`].
    Beam(Beam),
    /// Parallel light from infinitely far away (a sun).
    Directional {
        /// Unit direction the light travels in.
        direction: Vec3A,
        /// Irradiance on a surface facing the light, W/m².
        irradiance: Vec3A,
    },
}

/// A point light shining through a frame of its own, as Mitsuba 3's
/// `spot` and `projector` emitters define them ([`BeamShape`]), times a
/// texture projected through it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Beam {
    /// Where it is.
    pub position: Vec3A,
    /// World to the light's frame (the inverse of its `to_world`'s linear
    /// part): its axis is the frame's `+z`, the texture's `u` along `+x`.
    pub to_local: Mat3A,
    /// The axis in the world (unit), for choosing lights.
    pub axis: Vec3A,
    /// Radiant intensity on the axis, W/sr (a projector's irradiance at
    /// unit distance on the axis).
    pub intensity: Vec3A,
    /// How the light spreads.
    pub shape: BeamShape,
    /// The texture multiplying the intensity, if any.
    pub texture: Option<Pattern>,
}

/// How a [`Beam`] spreads.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum BeamShape {
    /// Mitsuba's `spot`: full intensity within `beam_width` of the axis,
    /// falling linearly in angle to zero at `cutoff`; the texture spans the
    /// cutoff's square: `uv = ½ + ½ (x, y)/(z tan cutoff)` in the light's
    /// frame.
    Spot {
        /// `cutoff_angle` in radians.
        cutoff: f32,
        /// `beam_width` in radians (below `cutoff`).
        beam_width: f32,
    },
    /// Mitsuba's `projector`: a pinhole projecting its image (the texture)
    /// onto the scene, giving irradiance `π · scale · texel` on a surface
    /// facing it at unit depth (`z = 1` in its frame), the image spanning
    /// `uv = (½ − ½ x/(z t), ½ − ½ a y/(z t))` with `t = tan(x-fov/2)` and
    /// `a` the image's aspect ratio; nothing outside it.
    Projector {
        /// `tan` of half the horizontal field of view.
        tan_half_fov: f32,
        /// The image's width over its height.
        aspect: f32,
        /// The light's `+z` in the world (not normalised: Mitsuba's `n`).
        normal: Vec3A,
    },
}

impl Beam {
    /// A spot's falloff towards the light-frame direction `local`
    /// (unnormalised): Mitsuba's `falloff_curve`.
    #[inline]
    fn falloff(cutoff: f32, beam_width: f32, local: Vec3A) -> f32 {
        let cos = local.normalize_or_zero().z;
        if cos <= cutoff.cos() {
            return 0.0;
        }
        if cos >= beam_width.cos() {
            return 1.0;
        }
        (cutoff - cos.clamp(-1.0, 1.0).acos()) / (cutoff - beam_width)
    }

    /// The intensity sent towards `p` (falloff and texture applied).
    #[inline]
    pub fn intensity_towards(&self, p: Vec3A, textures: &TextureStore) -> Vec3A {
        let d = p - self.position;
        let local = self.to_local * d;
        let (scale, uv) = match self.shape {
            BeamShape::Spot { cutoff, beam_width } => {
                let k = 0.5 / (local.z * cutoff.tan());
                (
                    Self::falloff(cutoff, beam_width, local),
                    Vec2::new(0.5 + local.x * k, 0.5 + local.y * k),
                )
            }
            BeamShape::Projector {
                tan_half_fov,
                aspect,
                normal,
            } => {
                let k = 0.5 / (local.z * tan_half_fov);
                let uv = Vec2::new(0.5 - local.x * k, 0.5 - aspect * local.y * k);
                let inside =
                    local.z > 0.0 && (0.0..=1.0).contains(&uv.x) && (0.0..=1.0).contains(&uv.y);
                // Irradiance π·scale·texel at depth 1 facing it: intensity
                // π·scale·texel·r²/(z²·cos), with cos against Mitsuba's `n`.
                let r2 = d.length_squared();
                let cos = normal.dot(d) / r2.sqrt();
                let s = std::f32::consts::PI * r2 / (local.z * local.z * cos);
                (
                    if inside && s.is_finite() && s > 0.0 {
                        s
                    } else {
                        0.0
                    },
                    uv,
                )
            }
        };
        if scale <= 0.0 {
            return Vec3A::ZERO;
        }
        let mut i = self.intensity * scale;
        if let Some(t) = &self.texture {
            i *= Vec3A::from(t.eval(uv, Vec4::ONE, textures).xyz());
        }
        i
    }

    /// The cosines of the inner (full strength) and outer cone, for
    /// choosing lights.
    pub fn cones(&self) -> (f32, f32) {
        match self.shape {
            BeamShape::Spot { cutoff, beam_width } => (beam_width.cos(), cutoff.cos()),
            BeamShape::Projector {
                tan_half_fov,
                aspect,
                ..
            } => {
                // The image's corner.
                let t = tan_half_fov * (1.0 + 1.0 / (aspect * aspect)).sqrt();
                let c = 1.0 / (1.0 + t * t).sqrt();
                (c, c)
            }
        }
    }
}

/// The glTF reference falloff of a spot light at cosine `cos` from its axis:
/// 1 inside the inner cone, 0 outside the outer one, and between them `t²` with
/// `t = (cos − cos_outer)/(cos_inner − cos_outer)`.
#[inline]
pub fn spot_falloff(cos: f32, cos_inner: f32, cos_outer: f32) -> f32 {
    if cos_inner <= cos_outer {
        // No falloff band (inner ≥ outer): a hard edge at the outer cone.
        return if cos > cos_outer { 1.0 } else { 0.0 };
    }
    let t = ((cos - cos_outer) / (cos_inner - cos_outer)).clamp(0.0, 1.0);
    t * t
}

/// What a light sends towards a point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Incident {
    /// From a point at `position`: the irradiance on a surface facing it is
    /// `intensity / r²`.
    FromPoint {
        /// Where the light is.
        position: Vec3A,
        /// Intensity towards the point, W/sr (a spot's falloff applied).
        intensity: Vec3A,
    },
    /// From infinitely far along `to_light` (unit): irradiance `irradiance` on a
    /// surface facing it.
    FromDirection {
        /// Unit direction towards the light.
        to_light: Vec3A,
        /// Irradiance on a surface facing the light.
        irradiance: Vec3A,
    },
}

impl Light {
    /// What the light sends towards `p`; `None` when nothing (outside a
    /// spot's cone). `textures` holds the images a light's texture reads.
    #[inline]
    pub fn incident(&self, p: Vec3A, textures: &TextureStore) -> Option<Incident> {
        match *self {
            Light::Point {
                position,
                intensity,
            } => Some(Incident::FromPoint {
                position,
                intensity,
            }),
            Light::Spot {
                position,
                direction,
                intensity,
                cos_inner,
                cos_outer,
            } => {
                let cos = (p - position).normalize_or_zero().dot(direction);
                let f = spot_falloff(cos, cos_inner, cos_outer);
                (f > 0.0).then_some(Incident::FromPoint {
                    position,
                    intensity: intensity * f,
                })
            }
            Light::Beam(ref b) => {
                let intensity = b.intensity_towards(p, textures);
                (intensity != Vec3A::ZERO).then_some(Incident::FromPoint {
                    position: b.position,
                    intensity,
                })
            }
            Light::Directional {
                direction,
                irradiance,
            } => Some(Incident::FromDirection {
                to_light: -direction,
                irradiance,
            }),
        }
    }

    /// Emitted power averaged over the colour channels, for choosing lights in
    /// proportion to it: `4πI` for a point light, the cone's solid angle times `I`
    /// for a spot, and the irradiance over the scene's cross-section (a disk of
    /// `scene_radius`) for a directional light.
    pub fn power(&self, scene_radius: f32) -> f32 {
        let mean = |v: Vec3A| (v.as_dvec3().element_sum() / 3.0) as f32;
        let p = match *self {
            Light::Point { intensity, .. } => 4.0 * PI * mean(intensity),
            Light::Spot {
                intensity,
                cos_outer,
                ..
            } => 2.0 * PI * (1.0 - cos_outer.clamp(-1.0, 1.0)) * mean(intensity),
            Light::Beam(ref b) => 2.0 * PI * (1.0 - b.cones().1) * mean(b.intensity),
            Light::Directional { irradiance, .. } => {
                PI * scene_radius * scene_radius * mean(irradiance)
            }
        };
        if p.is_finite() && p > 0.0 { p } else { 0.0 }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spot_falloff_follows_the_gltf_reference() {
        let (inner, outer) = (20f32.to_radians().cos(), 30f32.to_radians().cos());
        assert_eq!(spot_falloff(1.0, inner, outer), 1.0);
        assert_eq!(spot_falloff(inner, inner, outer), 1.0);
        assert_eq!(spot_falloff(outer, inner, outer), 0.0);
        assert_eq!(spot_falloff(40f32.to_radians().cos(), inner, outer), 0.0);
        let mid = 0.5 * (inner + outer);
        assert!((spot_falloff(mid, inner, outer) - 0.25).abs() < 1e-6);
    }
}
