//! Integrators: what colour a camera ray brings back.
//!
//! The [`Integrator`] enum and its names are in `integrator`, its radiance
//! for one ray and for packets in `radiance`; the lab's integrators (`flat`,
//! `direct`) are in `direct`, the path tracer in [`path`], bidirectional
//! path tracing in [`bdpt`].

pub mod bdpt;
pub(crate) mod direct;
mod integrator;
pub mod path;
mod radiance;

#[cfg(all(test, target_arch = "x86_64"))]
use glam::Vec3A;

#[cfg(all(test, target_arch = "x86_64"))]
use crate::scene::Scene;
pub use integrator::Integrator;

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
