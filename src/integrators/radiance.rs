//! What colour a ray brings back: [`Integrator::radiance`] for one ray and
//! its forms for rays whose closest hits are known and for packets of four
//! or eight coherent rays, which hand `path` to its tracer and the lab's
//! integrators to [`direct`].

use glam::Vec3A;

use super::direct;
use super::integrator::{Integrator, path_from};
use super::path;
use crate::geometry::ray::{Hit, Ray};
use crate::sampling::sampler::Rng;
use crate::scene::Scene;

impl Integrator {
    /// The value carried back by `ray`; adds the number of rays cast to `rays`.
    /// `path` draws its random numbers from a fixed stream here; renders seed it
    /// per pixel sample instead (see [`crate::render`]).
    #[inline]
    pub fn radiance(self, scene: &Scene, ray: &Ray, rays: &mut u64) -> Vec3A {
        if let Some(options) = self.path_options() {
            return path::radiance(scene, ray, &options, &mut Rng::new(0, 0), rays);
        }
        *rays += 1;
        let hit = scene.intersect(ray, f32::INFINITY);
        self.radiance_from(scene, ray, hit, rays)
    }

    /// [`Integrator::radiance`] for a ray whose closest hit `hit` is already
    /// known (the render gathers AOVs from it); does not count that ray.
    #[inline]
    pub fn radiance_from(
        self,
        scene: &Scene,
        ray: &Ray,
        hit: Option<Hit>,
        rays: &mut u64,
    ) -> Vec3A {
        if let Some(options) = self.path_options() {
            return path_from(scene, ray, hit, &options, rays);
        }
        let Some(hit) = hit else {
            return Vec3A::ZERO;
        };
        let rho = scene.base_color(&hit);
        match self {
            Integrator::Flat => rho,
            _ if scene.has_unlit() && scene.material(hit.prim).is_unlit() => {
                direct::scalar::unlit_value(rho)
            }
            _ => rho * (direct::scalar::direct_light(scene, &hit, ray.dir, rays) + scene.ambient),
        }
    }

    /// [`Integrator::radiance`] for four coherent rays (a pixel quad), traced
    /// together. Gives the same values as four single calls, except at exact ties.
    #[inline]
    pub fn radiance4(self, scene: &Scene, rays: &[Ray; 4], count: &mut u64) -> [Vec3A; 4] {
        if self.is_physical() {
            return rays.map(|r| self.radiance(scene, &r, count));
        }
        *count += 4;
        let hits = scene.intersect4(rays, f32::INFINITY);
        self.radiance4_from(scene, rays, hits, count)
    }

    /// [`Integrator::radiance4`] for rays whose closest hits `hits` are already
    /// known; does not count them. Always inlined, as [`Integrator::radiance4`]
    /// was before it was split in two: the lab's loop depends on it.
    #[inline(always)]
    pub fn radiance4_from(
        self,
        scene: &Scene,
        rays: &[Ray; 4],
        hits: [Option<Hit>; 4],
        count: &mut u64,
    ) -> [Vec3A; 4] {
        self.radiance_n_from(scene, rays, hits, count, |shadow, t_max, lit| {
            scene.occluded4(shadow, t_max, lit)
        })
    }

    /// [`Integrator::radiance4_from`] for eight coherent rays (a 4×2 pixel
    /// block), whose shadow rays are traced together too.
    #[inline(always)]
    pub fn radiance8_from(
        self,
        scene: &Scene,
        rays: &[Ray; 8],
        hits: [Option<Hit>; 8],
        count: &mut u64,
    ) -> [Vec3A; 8] {
        self.radiance_n_from(scene, rays, hits, count, |shadow, t_max, lit| {
            scene.occluded8(shadow, t_max, lit)
        })
    }
}

#[cfg(test)]
mod tests {
    use std::f32::consts::PI;

    use super::*;
    use crate::geometry::triangle::Triangle;
    use crate::scene::PointLight;

    fn one_triangle(light: Vec3A, blocker: bool) -> Scene {
        // A large floor triangle in the plane y = 1 whose lab normal points up (-y).
        let mut tris = vec![Triangle::new(
            Vec3A::new(-10.0, 1.0, -10.0),
            Vec3A::new(0.0, 1.0, 10.0),
            Vec3A::new(10.0, 1.0, -10.0),
        )];
        let mut rho = vec![Vec3A::new(0.5, 0.25, 1.0)];
        if blocker {
            tris.push(Triangle::new(
                Vec3A::new(-1.0, 0.0, -1.0),
                Vec3A::new(1.0, 0.0, -1.0),
                Vec3A::new(0.0, 0.0, 1.0),
            ));
            rho.push(Vec3A::ONE);
        }
        let light = PointLight {
            position: light,
            power: Vec3A::new(10.0, 20.0, 30.0),
        };
        Scene::new(tris, rho, light, Vec3A::splat(0.1)).unwrap()
    }

    #[test]
    fn lab_normal_of_the_test_floor_points_up() {
        let s = one_triangle(Vec3A::ZERO, false);
        assert!((s.normal(0) - Vec3A::NEG_Y).length() < 1e-6);
    }

    #[test]
    fn direct_matches_the_hand_computed_value() {
        // Light 2 above and 1 to the side of the point (0, 1, 0).
        let s = one_triangle(Vec3A::new(1.0, -1.0, 0.0), false);
        let ray = Ray::new(
            Vec3A::new(0.0, -1.0, -2.0),
            Vec3A::new(0.0, 2.0, 2.0).normalize(),
        );
        let mut rays = 0;
        let c = Integrator::Direct.radiance(&s, &ray, &mut rays);
        // r² = 1 + 4 = 5, cos = 2/√5, D = P·cos/(4π r²).
        let d = Vec3A::new(10.0, 20.0, 30.0) * (2.0 / 5f32.sqrt()) / (4.0 * PI * 5.0);
        let want = Vec3A::new(0.5, 0.25, 1.0) * (d + 0.1);
        assert!(
            (c - want).abs().max_element() < 1e-5 * want.max_element(),
            "{c} {want}"
        );
        assert_eq!(rays, 2);
        let flat = Integrator::Flat.radiance(&s, &ray, &mut rays);
        assert_eq!(flat, Vec3A::new(0.5, 0.25, 1.0));
        // Pointing away from the triangle: black.
        let miss = Ray::new(ray.origin, -ray.dir);
        assert_eq!(
            Integrator::Direct.radiance(&s, &miss, &mut rays),
            Vec3A::ZERO
        );
    }

    #[test]
    fn shadowed_points_get_only_ambient() {
        // The blocker at y = 0 lies between the light at y = -1 and the point (0, 1, 0).
        let s = one_triangle(Vec3A::new(0.0, -1.0, 0.0), true);
        let ray = Ray::new(
            Vec3A::new(0.0, -1.0, -4.0),
            Vec3A::new(0.0, 2.0, 4.0).normalize(),
        );
        let mut rays = 0;
        let c = Integrator::Direct.radiance(&s, &ray, &mut rays);
        assert!(
            (c - Vec3A::new(0.5, 0.25, 1.0) * 0.1).abs().max_element() < 1e-7,
            "{c}"
        );
        // A point beside the blocker's shadow is lit.
        let lit = Ray::new(
            Vec3A::new(3.0, -1.0, -4.0),
            Vec3A::new(0.0, 2.0, 4.0).normalize(),
        );
        let c = Integrator::Direct.radiance(&s, &lit, &mut rays);
        // Hit point (3, 1, 0): r² = 9 + 4, cos = 2/√13.
        let d = 10.0 * (2.0 / 13f32.sqrt()) / (4.0 * PI * 13.0);
        assert!((c.x - 0.5 * (d + 0.1)).abs() < 1e-6, "{c}");
    }

    #[test]
    fn light_behind_the_face_gives_ambient_only() {
        let s = one_triangle(Vec3A::new(0.0, 3.0, 0.0), false);
        let ray = Ray::new(
            Vec3A::new(0.0, -1.0, -2.0),
            Vec3A::new(0.0, 2.0, 2.0).normalize(),
        );
        let mut rays = 0;
        let c = Integrator::Direct.radiance(&s, &ray, &mut rays);
        assert!((c - Vec3A::new(0.5, 0.25, 1.0) * 0.1).abs().max_element() < 1e-7);
        assert_eq!(rays, 1, "no shadow ray for a light behind the face");
    }
}
