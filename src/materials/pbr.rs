//! Temporary stub of the glTF metallic–roughness BSDF (replaced by the real module).
#![allow(missing_docs, dead_code, unused_variables)]

use glam::{Vec2, Vec3A};

use super::BsdfSample;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PbrBsdf {
    pub base_color: Vec3A,
    pub metallic: f32,
    pub alpha: f32,
    pub ior: f32,
    pub specular: f32,
    pub specular_color: Vec3A,
    pub transmission: f32,
    pub thin_walled: bool,
}

impl PbrBsdf {
    pub fn eval(&self, wo: Vec3A, wi: Vec3A) -> Vec3A {
        super::Material::Diffuse {
            reflectance: self.base_color,
        }
        .eval(wo, wi)
    }
    pub fn pdf(&self, wo: Vec3A, wi: Vec3A) -> f32 {
        super::Material::Diffuse {
            reflectance: self.base_color,
        }
        .pdf(wo, wi)
    }
    pub fn sample(&self, wo: Vec3A, u_lobe: f32, u: Vec2) -> Option<BsdfSample> {
        super::Material::Diffuse {
            reflectance: self.base_color,
        }
        .sample(wo, u_lobe, u)
    }
    pub fn is_specular(&self) -> bool {
        false
    }
}
