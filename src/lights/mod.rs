//! Lights: the closed set of punctual light kinds a scene holds, in radiometric
//! units (`docs/scene-conventions.md`). Area lights are emitting
//! triangles; the scene samples them (see [`crate::scene::Scene::sample_light`]).

pub mod environment;
pub mod rgbe;

use std::f32::consts::PI;

use glam::Vec3A;

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
    /// Parallel light from infinitely far away (a sun).
    Directional {
        /// Unit direction the light travels in.
        direction: Vec3A,
        /// Irradiance on a surface facing the light, W/m².
        irradiance: Vec3A,
    },
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
    /// What the light sends towards `p`; `None` when nothing (outside a spot's cone).
    #[inline]
    pub fn incident(&self, p: Vec3A) -> Option<Incident> {
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
