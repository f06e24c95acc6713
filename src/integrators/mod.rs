//! Integrators: what colour a camera ray brings back.

pub(crate) mod direct;
pub mod path;

use std::fmt;
use std::str::FromStr;

use glam::Vec3A;

use crate::geometry::ray::{Hit, Ray};
use crate::sampling::sampler::Rng;
use crate::scene::Scene;
use path::PathOptions;

/// The light transport algorithm used for each camera ray.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Integrator {
    /// The reflectance ρ of the closest triangle; black on a miss (lab task 1).
    Flat,
    /// The lab's model (lab task 3): `ρ ∘ (D + N)` with the point light's
    /// `D = P·max(r̂·n̂, 0) / (4πr²)`, zero in shadow, and the ambient term `N`.
    #[default]
    Direct,
    /// Global illumination in physical units: an unbiased path tracer with
    /// next-event estimation and multiple importance sampling (see [`path`]).
    Path(PathOptions),
}

impl Integrator {
    /// All integrators with default options, in the viewer's key order.
    pub const ALL: [Integrator; 3] = [
        Integrator::Flat,
        Integrator::Direct,
        Integrator::Path(PathOptions {
            max_depth: u32::MAX,
            sampler: path::SamplerKind::DEFAULT,
        }),
    ];

    /// The `path` integrator with default options.
    pub fn path() -> Self {
        Integrator::Path(PathOptions::default())
    }

    /// The name used on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Integrator::Flat => "flat",
            Integrator::Direct => "direct",
            Integrator::Path(_) => "path",
        }
    }

    /// Whether the integrator computes radiance in physical units (`path`), as
    /// opposed to the lab's units (`flat`, `direct`).
    pub fn is_physical(self) -> bool {
        matches!(self, Integrator::Path(_))
    }

    /// The value carried back by `ray`; adds the number of rays cast to `rays`.
    /// `path` draws its random numbers from a fixed stream here; renders seed it
    /// per pixel sample instead (see [`crate::render`]).
    #[inline]
    pub fn radiance(self, scene: &Scene, ray: &Ray, rays: &mut u64) -> Vec3A {
        if let Integrator::Path(options) = self {
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
        if let Integrator::Path(options) = self {
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
        if let Integrator::Path(_) = self {
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

/// `path`'s radiance with the fixed stream of [`Integrator::radiance`]. Out of
/// line: inlined, the path tracer would make the lab integrators' functions too
/// large for the render loop to inline them.
#[inline(never)]
fn path_from(
    scene: &Scene,
    ray: &Ray,
    hit: Option<Hit>,
    options: &PathOptions,
    rays: &mut u64,
) -> Vec3A {
    path::radiance_from(scene, ray, hit, options, &mut Rng::new(0, 0), rays)
}

impl fmt::Display for Integrator {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Integrator {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Integrator::ALL
            .into_iter()
            .find(|i| i.name() == s)
            .ok_or_else(|| format!("unknown integrator '{s}' (expected flat, direct or path)"))
    }
}

/// Forty random triangles and a wall in a two-sided scene (the form of
/// meshes), to hit from both sides: the lanes' tests' scene. `stream` picks
/// the triangles, `ambient` is the lab's `N`.
#[cfg(all(test, target_arch = "x86_64"))]
pub(crate) fn random_two_sided_scene(stream: u64, ambient: Vec3A) -> Scene {
    use crate::geometry::triangle::Triangle;
    use crate::sampling::sampler::Rng;
    use crate::scene::PointLight;
    use crate::scene::SceneParts;
    let mut rng = Rng::new(5, stream);
    let mut r = move || rng.next_f32() * 2.0 - 1.0;
    let mut triangles: Vec<Triangle> = (0..40)
        .map(|_| {
            let c = Vec3A::new(r(), r(), r() * 0.5 + 0.5);
            let e = |r: &mut dyn FnMut() -> f32| Vec3A::new(r(), r(), r()) * 0.4;
            Triangle::new(c, c + e(&mut r), c + e(&mut r))
        })
        .collect();
    triangles.push(Triangle::new(
        Vec3A::new(-3.0, -3.0, 2.0),
        Vec3A::new(3.0, -3.0, 2.0),
        Vec3A::new(0.0, 4.0, 2.0),
    ));
    let rho = (0..triangles.len())
        .map(|i| Vec3A::new(0.2 + 0.1 * (i % 5) as f32, 0.5, 0.9 - 0.1 * (i % 3) as f32))
        .collect();
    let light = PointLight {
        position: Vec3A::new(0.3, -0.2, 0.4),
        power: Vec3A::new(3.0, 5.0, 7.0),
    };
    let mut parts = SceneParts::lab(triangles, rho, light, ambient).expect("valid");
    parts.two_sided = true;
    Scene::from_parts(parts).expect("valid")
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

    #[test]
    fn names_round_trip() {
        for i in Integrator::ALL {
            assert_eq!(i.name().parse::<Integrator>(), Ok(i));
        }
        assert_eq!("path".parse::<Integrator>(), Ok(Integrator::path()));
        assert!("bogus".parse::<Integrator>().is_err());
    }
}
