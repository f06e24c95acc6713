//! The scene: triangles with their reflectance, a point light and the ambient
//! term, behind one query seam ([`Scene::intersect`], [`Scene::occluded`]).

use glam::Vec3A;
use thiserror::Error;

use crate::bvh::Bvh;
use crate::ray::{Hit, Ray, SurfacePoint};
use crate::triangle::Triangle;

/// The lab's point light: position and power per colour channel.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PointLight {
    /// Where the light is.
    pub position: Vec3A,
    /// Emitted power `P` per colour channel (the lab's "light colour").
    pub power: Vec3A,
}

/// Why a scene cannot be built.
#[derive(Debug, Error, PartialEq)]
pub enum SceneError {
    /// A vertex has a NaN or infinite coordinate.
    #[error("triangle {index} has a non-finite vertex")]
    NonFiniteVertex {
        /// Index of the triangle.
        index: usize,
    },
    /// A reflectance is outside `[0, 1]` or not finite.
    #[error("triangle {index} has reflectance {value:?} outside [0, 1]")]
    BadReflectance {
        /// Index of the triangle.
        index: usize,
        /// The offending value.
        value: [f32; 3],
    },
    /// Triangle and reflectance lists differ in length.
    #[error("{triangles} triangles but {reflectances} reflectances")]
    LengthMismatch {
        /// Number of triangles.
        triangles: usize,
        /// Number of reflectances.
        reflectances: usize,
    },
}

/// Triangles, their materials and the light, with an acceleration structure.
#[derive(Clone, Debug)]
pub struct Scene {
    triangles: Vec<Triangle>,
    normals: Vec<Vec3A>,
    reflectance: Vec<Vec3A>,
    bvh: Bvh,
    /// The point light.
    pub light: PointLight,
    /// The lab's constant ambient term `N` (indirect light stand-in).
    pub ambient: Vec3A,
}

impl Scene {
    /// Builds a scene. Degenerate (zero-area) triangles are kept, so indices stay
    /// those of the input, but can never be hit.
    pub fn new(
        triangles: Vec<Triangle>,
        reflectance: Vec<Vec3A>,
        light: PointLight,
        ambient: Vec3A,
    ) -> Result<Self, SceneError> {
        if triangles.len() != reflectance.len() {
            return Err(SceneError::LengthMismatch {
                triangles: triangles.len(),
                reflectances: reflectance.len(),
            });
        }
        if let Some(index) = triangles.iter().position(|t| !t.is_finite()) {
            return Err(SceneError::NonFiniteVertex { index });
        }
        let valid = |r: &Vec3A| r.is_finite() && r.min_element() >= 0.0 && r.max_element() <= 1.0;
        if let Some(index) = reflectance.iter().position(|r| !valid(r)) {
            return Err(SceneError::BadReflectance {
                index,
                value: reflectance[index].into(),
            });
        }
        let normals = triangles.iter().map(Triangle::lab_normal).collect();
        let bvh = Bvh::build(&triangles);
        Ok(Self {
            triangles,
            normals,
            reflectance,
            bvh,
            light,
            ambient,
        })
    }

    /// The closest hit along `ray` with `t` in `(0, t_max]`.
    #[inline]
    pub fn intersect(&self, ray: &Ray, t_max: f32) -> Option<Hit> {
        self.bvh.intersect(ray, t_max)
    }

    /// Whether anything blocks `ray` for `t` in `(0, t_max]`.
    #[inline]
    pub fn occluded(&self, ray: &Ray, t_max: f32) -> bool {
        self.bvh.occluded(ray, t_max)
    }

    /// The closest hits of four coherent rays (say, a 2×2 pixel quad), traced
    /// together; the same answers as four calls of [`Scene::intersect`] except
    /// which triangle is reported at an exact tie.
    #[inline]
    pub fn intersect4(&self, rays: &[Ray; 4], t_max: f32) -> [Option<Hit>; 4] {
        self.bvh.intersect4(rays, t_max)
    }

    /// Whether anything blocks each of four rays within its own `t_max`; lanes
    /// not `active` answer `false`.
    #[inline]
    pub fn occluded4(&self, rays: &[Ray; 4], t_max: [f32; 4], active: [bool; 4]) -> [bool; 4] {
        self.bvh.occluded4(rays, t_max, active)
    }

    /// The triangles, in input order.
    pub fn triangles(&self) -> &[Triangle] {
        &self.triangles
    }

    /// Face normal (the lab's convention) of triangle `prim`.
    #[inline]
    pub fn normal(&self, prim: u32) -> Vec3A {
        self.normals[prim as usize]
    }

    /// Diffuse reflectance ρ of triangle `prim`.
    #[inline]
    pub fn reflectance(&self, prim: u32) -> Vec3A {
        self.reflectance[prim as usize]
    }

    /// The hit point with its error bound, for spawning rays off the surface.
    #[inline]
    pub fn surface_point(&self, hit: &Hit) -> SurfacePoint {
        let prim = hit.prim as usize;
        SurfacePoint::on_triangle(&self.triangles[prim].v, hit.b1, hit.b2, self.normals[prim])
    }
}
