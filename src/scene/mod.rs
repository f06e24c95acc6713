//! The scene: triangles with their reflectance, materials and emission, a point
//! light and the ambient term, behind one query seam ([`Scene::intersect`],
//! [`Scene::occluded`]).

pub mod cornell;
pub mod framing;
pub mod obj;
pub mod transform;

use std::f32::consts::PI;

use glam::{Vec2, Vec3A};
use thiserror::Error;

use crate::geometry::bvh::Bvh;
use crate::geometry::ray::{Hit, Ray, SurfacePoint};
use crate::geometry::triangle::Triangle;
use crate::materials::Material;

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
    /// An emitted radiance is negative or not finite.
    #[error("triangle {index} has emitted radiance {value:?} (must be finite and >= 0)")]
    BadEmission {
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
    materials: Vec<Material>,
    emission: Vec<Vec3A>,
    area_lights: AreaLights,
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
        let materials = reflectance
            .iter()
            .map(|&reflectance| Material::Diffuse { reflectance })
            .collect();
        let emission = vec![Vec3A::ZERO; triangles.len()];
        Ok(Self {
            triangles,
            normals,
            reflectance,
            materials,
            emission,
            area_lights: AreaLights::default(),
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

    /// Material of triangle `prim` (used by the `path` integrator; `flat` and
    /// `direct` keep using the reflectance). A diffuse one with the triangle's
    /// reflectance unless [`Scene::set_material`] changed it.
    #[inline]
    pub fn material(&self, prim: u32) -> &Material {
        &self.materials[prim as usize]
    }

    /// Gives triangle `prim` another material (for the `path` integrator).
    pub fn set_material(&mut self, prim: usize, material: Material) {
        self.materials[prim] = material;
    }

    /// Radiance `Le` emitted by triangle `prim` from its front side (the side its
    /// lab normal points to); zero for a triangle that is not a light.
    #[inline]
    pub fn emission(&self, prim: u32) -> Vec3A {
        self.emission[prim as usize]
    }

    /// Makes triangle `prim` an area light emitting radiance `le` from its front
    /// side (zero turns it off), and updates the light list.
    pub fn set_emission(&mut self, prim: usize, le: Vec3A) -> Result<(), SceneError> {
        if !(le.is_finite() && le.min_element() >= 0.0) {
            return Err(SceneError::BadEmission {
                index: prim,
                value: le.into(),
            });
        }
        self.emission[prim] = le;
        self.area_lights = AreaLights::build(&self.triangles, &self.emission);
        Ok(())
    }

    /// Total emitted power of the point light, averaged over the colour
    /// channels (`P`, since its intensity is `P/(4π)` in every direction).
    #[inline]
    pub fn point_power(&self) -> f32 {
        // In f64: three channels near f32::MAX must not overflow their sum.
        let p = (self.light.power.as_dvec3().element_sum() / 3.0) as f32;
        if p.is_finite() && p > 0.0 { p } else { 0.0 }
    }

    /// Whether anything emits light: the point light has power or a triangle
    /// emits.
    pub fn has_lights(&self) -> bool {
        self.point_power() > 0.0 || self.area_lights.total > 0.0
    }

    /// Picks a light in proportion to its power (area lights: `π·A·Le`, one
    /// triangle at a time, a point uniformly by area on it) with `u_light`, and a
    /// point on it with `u`. `None` when the scene has no light.
    #[inline]
    pub fn sample_light(&self, u_light: f32, u: Vec2) -> Option<LightSample> {
        let point = self.point_power();
        let total = point + self.area_lights.total;
        if total <= 0.0 {
            return None;
        }
        let x = u_light * total;
        if x < point || self.area_lights.prims.is_empty() {
            let pmf = point / total;
            return Some(LightSample::Point {
                position: self.light.position,
                intensity: self.light.power * (1.0 / (4.0 * PI * pmf)),
            });
        }
        let lights = &self.area_lights;
        let i = lights
            .cdf
            .partition_point(|&c| c <= x - point)
            .min(lights.prims.len() - 1);
        let prim = lights.prims[i];
        let v = &self.triangles[prim as usize].v;
        let su = u.x.sqrt();
        let (b1, b2) = (1.0 - su, u.y * su);
        let position = (1.0 - b1 - b2) * v[0] + b1 * v[1] + b2 * v[2];
        Some(LightSample::Area {
            position,
            normal: self.normals[prim as usize],
            radiance: self.emission[prim as usize],
            pdf_area: self.light_pdf_area(prim),
        })
    }

    /// The density per unit area with which [`Scene::sample_light`] picks a point
    /// on emitting triangle `prim`: its selection probability over its area.
    #[inline]
    pub fn light_pdf_area(&self, prim: u32) -> f32 {
        let total = self.point_power() + self.area_lights.total;
        let Some(&(power, area)) = self.area_lights.per_prim.get(prim as usize) else {
            return 0.0;
        };
        if total <= 0.0 || area <= 0.0 {
            return 0.0;
        }
        power / (total * area)
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

/// A light chosen by [`Scene::sample_light`], with its selection probability
/// already divided out.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LightSample {
    /// The point light.
    Point {
        /// Where it is.
        position: Vec3A,
        /// Its intensity `P/(4π)` (W/sr) divided by the probability of choosing it.
        intensity: Vec3A,
    },
    /// A point on an emitting triangle.
    Area {
        /// The point.
        position: Vec3A,
        /// The triangle's front-side normal (light leaves along it).
        normal: Vec3A,
        /// Its emitted radiance `Le`.
        radiance: Vec3A,
        /// Probability density of this point per unit area (selection included).
        pdf_area: f32,
    },
}

/// The emitting triangles and their power, for power-proportional selection.
#[derive(Clone, Debug, Default)]
struct AreaLights {
    /// Emitting triangles.
    prims: Vec<u32>,
    /// Running sums of their powers.
    cdf: Vec<f32>,
    /// Sum of their powers.
    total: f32,
    /// Power and area of every triangle (zero power for non-emitters); empty
    /// when none emits.
    per_prim: Vec<(f32, f32)>,
}

impl AreaLights {
    fn build(triangles: &[Triangle], emission: &[Vec3A]) -> Self {
        let mut lights = Self {
            per_prim: vec![(0.0, 0.0); triangles.len()],
            ..Self::default()
        };
        for (i, (t, le)) in triangles.iter().zip(emission).enumerate() {
            let area = t.area();
            let power = PI * area * le.element_sum() / 3.0;
            if power > 0.0 {
                lights.total += power;
                lights.prims.push(i as u32);
                lights.cdf.push(lights.total);
                lights.per_prim[i] = (power, area);
            }
        }
        if lights.prims.is_empty() {
            lights.per_prim.clear();
        }
        lights
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
