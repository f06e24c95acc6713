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
    /// Whether surfaces are lit from both sides. The lab box is one-sided, as in
    /// the lab (its normal is `cross(v2 − v0, v1 − v0)`); meshes are two-sided,
    /// since their windings vary (and OBJ's is the opposite of the lab's).
    pub two_sided: bool,
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
            two_sided: false,
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

    /// The hit point of a ray along `dir` with its error bound, for spawning rays
    /// off the surface. Its normal is the face normal, turned towards the ray's
    /// origin in a two-sided scene.
    #[inline]
    pub fn surface_point(&self, hit: &Hit, dir: Vec3A) -> SurfacePoint {
        let prim = hit.prim as usize;
        let mut n = self.normals[prim];
        if self.two_sided && n.dot(dir) > 0.0 {
            n = -n;
        }
        SurfacePoint::on_triangle(&self.triangles[prim].v, hit.b1, hit.b2, n)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn light() -> PointLight {
        PointLight {
            position: Vec3A::ZERO,
            power: Vec3A::ONE,
        }
    }

    #[test]
    fn bad_input_is_refused_with_the_triangle_named() {
        let ok = Triangle::new(Vec3A::ZERO, Vec3A::X, Vec3A::Y);
        let nan = Triangle::new(Vec3A::ZERO, Vec3A::new(f32::NAN, 0.0, 0.0), Vec3A::Y);
        let inf = Triangle::new(Vec3A::splat(f32::INFINITY), Vec3A::X, Vec3A::Y);
        let grey = Vec3A::splat(0.5);
        let err = |tris: Vec<Triangle>, rho: Vec<Vec3A>| {
            Scene::new(tris, rho, light(), Vec3A::ZERO).unwrap_err()
        };
        assert_eq!(
            err(vec![ok, nan], vec![grey; 2]),
            SceneError::NonFiniteVertex { index: 1 }
        );
        assert_eq!(
            err(vec![inf], vec![grey]),
            SceneError::NonFiniteVertex { index: 0 }
        );
        assert!(matches!(
            err(vec![ok], vec![Vec3A::new(0.5, 1.5, 0.5)]),
            SceneError::BadReflectance { index: 0, .. }
        ));
        assert!(matches!(
            err(vec![ok], vec![Vec3A::splat(f32::NAN)]),
            SceneError::BadReflectance { index: 0, .. }
        ));
        assert_eq!(
            err(vec![ok, ok], vec![grey]),
            SceneError::LengthMismatch {
                triangles: 2,
                reflectances: 1
            }
        );
        assert_eq!(
            SceneError::NonFiniteVertex { index: 3 }.to_string(),
            "triangle 3 has a non-finite vertex"
        );
    }

    #[test]
    fn empty_and_degenerate_scenes_render_black() {
        let p = Vec3A::new(0.0, 0.0, 1.0);
        for tris in [vec![], vec![Triangle::new(p, p, p); 3]] {
            let n = tris.len();
            let scene = Scene::new(tris, vec![Vec3A::ONE; n], light(), Vec3A::ONE).unwrap();
            let cam = crate::Camera::lab(Vec3A::new(0.0, 0.0, -3.0), 0.0, 0.0, 16, 16);
            let settings = crate::render::RenderSettings::default();
            let out = crate::render::render(&scene, &cam, &settings, &|_| {});
            assert!(out.film.pixels.iter().all(|p| *p == Vec3A::ZERO));
        }
    }
}
