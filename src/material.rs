//! TEMPORARY stand-in for helper-2's materials (branch `material`): only the
//! diffuse lobe, with the agreed interface. Replaced by theirs on merge.

use glam::{Vec2, Vec3A};
use std::f32::consts::{FRAC_1_PI, PI};

/// An orthonormal frame whose z axis is a given normal.
#[derive(Clone, Copy, Debug)]
pub struct Frame {
    /// Tangent.
    pub s: Vec3A,
    /// Bitangent.
    pub t: Vec3A,
    /// Normal.
    pub n: Vec3A,
}

impl Frame {
    /// A frame around the unit normal `n` (Duff et al. 2017).
    pub fn from_normal(n: Vec3A) -> Self {
        let sign = 1f32.copysign(n.z);
        let a = -1.0 / (sign + n.z);
        let b = n.x * n.y * a;
        Self {
            s: Vec3A::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x),
            t: Vec3A::new(b, sign + n.y * n.y * a, -n.y),
            n,
        }
    }
    /// World to local.
    pub fn to_local(&self, v: Vec3A) -> Vec3A {
        Vec3A::new(v.dot(self.s), v.dot(self.t), v.dot(self.n))
    }
    /// Local to world.
    pub fn to_world(&self, v: Vec3A) -> Vec3A {
        self.s * v.x + self.t * v.y + self.n * v.z
    }
}

/// A sampled direction.
#[derive(Clone, Copy, Debug)]
pub struct BsdfSample {
    /// Incident direction (local).
    pub wi: Vec3A,
    /// f·|cos|/pdf.
    pub weight: Vec3A,
    /// Solid-angle pdf.
    pub pdf: f32,
    /// Delta lobe.
    pub specular: bool,
}

/// A surface material.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Material {
    /// Lambertian.
    Diffuse {
        /// Albedo.
        reflectance: Vec3A,
    },
}

impl Material {
    /// f·|cos wi|.
    pub fn eval(&self, wo: Vec3A, wi: Vec3A) -> Vec3A {
        let Material::Diffuse { reflectance } = self;
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return Vec3A::ZERO;
        }
        *reflectance * (FRAC_1_PI * wi.z)
    }
    /// Solid-angle pdf of `sample`.
    pub fn pdf(&self, wo: Vec3A, wi: Vec3A) -> f32 {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return 0.0;
        }
        wi.z * FRAC_1_PI
    }
    /// Samples wi.
    pub fn sample(&self, wo: Vec3A, _u_lobe: f32, u: Vec2) -> Option<BsdfSample> {
        let Material::Diffuse { reflectance } = self;
        if wo.z <= 0.0 {
            return None;
        }
        let r = u.x.sqrt();
        let phi = 2.0 * PI * u.y;
        let z = (1.0 - u.x).max(0.0).sqrt();
        let wi = Vec3A::new(r * phi.cos(), r * phi.sin(), z);
        if z <= 0.0 {
            return None;
        }
        Some(BsdfSample {
            wi,
            weight: *reflectance,
            pdf: z * FRAC_1_PI,
            specular: false,
        })
    }
    /// Whether every lobe is a delta.
    pub fn is_specular(&self) -> bool {
        false
    }
}
