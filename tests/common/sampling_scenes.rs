//! The scenes that light-sampling strategies are compared on, shared by the
//! tests (equal samples: `tests/many_lights.rs`, `tests/environment.rs`) and
//! the benchmark that times them (equal time: `cargo bench --bench sampling`).
//! Both include this file with `#[path]` beside `common`.
// Each includer uses a subset of these scenes.
#![allow(dead_code)]

use glam::Vec3A;
use raylab::camera::{Lens, look_at};
use raylab::lights::environment::{EnvMap, Environment};
use raylab::lights::rgbe::RgbImage;
use raylab::materials::surface::SurfaceMaterial;
use raylab::{Camera, Scene, Triangle};

use crate::common;

/// An environment map of `w × h` texels, texel `(i, j)` from the top-left.
pub fn map_of(w: usize, h: usize, texel: impl Fn(usize, usize) -> [f32; 3]) -> EnvMap {
    let pixels = (0..h)
        .flat_map(|j| (0..w).map(move |i| (i, j)))
        .map(|(i, j)| texel(i, j))
        .collect();
    EnvMap::from_image(RgbImage {
        width: w,
        height: h,
        pixels,
    })
}

/// A grey floor under 100 × 100 small emitters facing down; one in a hundred
/// is a thousand times brighter than the rest (about 90 % of the power in
/// 1 % of the lights). 64 × 48 pixels.
pub fn city_at_night() -> (Scene, Camera) {
    let s = 6.0;
    let mut tris = vec![
        Triangle::new(
            Vec3A::new(-s, 0.0, -s),
            Vec3A::new(s, 0.0, s),
            Vec3A::new(s, 0.0, -s),
        ),
        Triangle::new(
            Vec3A::new(-s, 0.0, -s),
            Vec3A::new(-s, 0.0, s),
            Vec3A::new(s, 0.0, s),
        ),
    ];
    let mut material_of = vec![0, 0];
    let size = 0.05;
    for k in 0..10_000u32 {
        let (x, z) = (-5.0 + 0.1 * (k % 100) as f32, -5.0 + 0.1 * (k / 100) as f32);
        let a = Vec3A::new(x, 1.0, z);
        // Counter-clockwise seen from below: the front faces the floor.
        tris.push(Triangle::new(a, a + Vec3A::X * size, a + Vec3A::Z * size));
        // A scattered one in a hundred is bright.
        let bright = (k.wrapping_mul(2_654_435_761) >> 16) % 100 == 0;
        material_of.push(if bright { 2 } else { 1 });
    }
    let emitter = |le: f32| SurfaceMaterial {
        emission: Vec3A::splat(le),
        ..SurfaceMaterial::diffuse(Vec3A::ZERO)
    };
    let materials = vec![
        SurfaceMaterial::diffuse(Vec3A::splat(0.5)),
        emitter(2.0),
        emitter(2000.0),
    ];
    let scene = common::two_sided_scene(tris, material_of, materials);
    // From above: the emitters show their dark backs, the floor their light.
    let position = Vec3A::new(0.0, 4.0, 4.0);
    let rotation = look_at(position, Vec3A::ZERO, Vec3A::Y).unwrap();
    let camera = Camera::with_lens(position, rotation, Lens::from_yfov(1.0), 64, 48);
    (scene, camera)
}

/// A sphere on a floor under a blue sky with a small, very bright sun (3 × 2
/// texels of a 256 × 128 map, 80,000 times the sky). 48 × 48 pixels.
pub fn sun_patch() -> (Scene, Camera) {
    let mut tris = common::sphere_triangles(Vec3A::new(0.0, 1.0, 0.0), 1.0, 48, 24);
    let spheres = tris.len();
    let s = 20.0;
    let (a, b, c, d) = (
        Vec3A::new(-s, 0.0, -s),
        Vec3A::new(s, 0.0, -s),
        Vec3A::new(s, 0.0, s),
        Vec3A::new(-s, 0.0, s),
    );
    tris.push(Triangle::new(a, c, b));
    tris.push(Triangle::new(a, d, c));
    let mut material_of = vec![0; spheres];
    material_of.extend([1, 1]);
    let materials = vec![
        SurfaceMaterial::diffuse(Vec3A::new(0.8, 0.6, 0.4)),
        SurfaceMaterial::diffuse(Vec3A::splat(0.5)),
    ];
    let mut scene = common::two_sided_scene(tris, material_of, materials);
    let map = map_of(256, 128, |i, j| {
        if (150..153).contains(&i) && (40..42).contains(&j) {
            [40_000.0, 36_000.0, 30_000.0]
        } else if j < 64 {
            [0.2, 0.3, 0.5]
        } else {
            [0.05; 3]
        }
    });
    scene.set_environment(Environment::map(map));
    let cam = common::look_camera(
        Vec3A::new(0.0, 4.0, 7.0),
        Vec3A::new(0.0, 0.5, 0.0),
        40.0,
        48,
        48,
    );
    (scene, cam)
}
