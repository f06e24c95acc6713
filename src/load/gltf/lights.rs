//! `KHR_lights_punctual`: point, spot and directional lights placed by their
//! nodes.

use glam::{Mat4, Vec3, Vec3A};
use gltf::json;

use super::error::{GltfError, valid};
use super::loader::Loader;
use crate::lights::Light;

impl Loader<'_> {
    /// `KHR_lights_punctual` light `index` at a node whose global transform
    /// is `world`: point lights are gathered for [`Loader::finish`], which
    /// picks the key light; spot and directional lights join the scene's.
    pub(super) fn light(&mut self, index: usize, world: &Mat4) -> Result<(), GltfError> {
        use json::extensions::scene::khr_lights_punctual::Type;
        let light = self
            .root
            .extensions
            .as_ref()
            .and_then(|e| e.khr_lights_punctual.as_ref())
            .and_then(|l| l.lights.get(index))
            .ok_or_else(|| GltfError::invalid(format!("light {index} does not exist")))?;
        let color = Vec3A::from(light.color);
        let value = color * light.intensity;
        if !(value.is_finite() && value.min_element() >= 0.0) {
            return Err(GltfError::invalid(format!(
                "light {index}: colour × intensity {value} must be finite and >= 0"
            )));
        }
        let position = Vec3A::from(world.transform_point3(Vec3::ZERO));
        let direction = Vec3A::from(world.transform_vector3(Vec3::NEG_Z)).normalize_or_zero();
        let kind = valid(&light.type_)
            .ok_or_else(|| GltfError::invalid(format!("light {index}: unknown type")))?;
        if light.range.is_some() {
            self.warn_once(
                "range",
                "glTF light `range` is ignored (inverse-square falloff everywhere)".into(),
            );
        }
        match kind {
            Type::Point => self.point_lights.push((position, value)),
            Type::Directional => {
                if direction == Vec3A::ZERO {
                    return Err(GltfError::invalid(format!(
                        "light {index}: degenerate direction"
                    )));
                }
                self.parts.lights.push(Light::Directional {
                    direction,
                    irradiance: value,
                })
            }
            Type::Spot => {
                let spot = light.spot.as_ref();
                let inner = spot.map_or(0.0, |s| s.inner_cone_angle);
                let outer = spot.map_or(std::f32::consts::FRAC_PI_4, |s| s.outer_cone_angle);
                if direction == Vec3A::ZERO || !(inner.is_finite() && outer.is_finite()) {
                    return Err(GltfError::invalid(format!(
                        "light {index}: degenerate spot light"
                    )));
                }
                self.parts.lights.push(Light::Spot {
                    position,
                    direction,
                    intensity: value,
                    cos_inner: inner.cos(),
                    cos_outer: outer.cos(),
                })
            }
        }
        Ok(())
    }
}
