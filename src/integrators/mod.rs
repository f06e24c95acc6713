//! Integrators: what colour a camera ray brings back.

pub(crate) mod lab8;
pub mod path;
pub(crate) mod path8;

use std::f32::consts::PI;
use std::fmt;
use std::str::FromStr;

use glam::{Vec3A, Vec4};

use crate::geometry::ray::{Hit, Ray, SHADOW_EPSILON};
use crate::geometry::{sqrt4, step_towards4};
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
            _ => rho * (direct_light(scene, &hit, ray.dir, rays) + scene.ambient),
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

    /// The lab's integrators on `N` coherent rays with known hits: one shadow
    /// ray per lit hit, all towards the light and traced together by `occluded`
    /// (a packet query: rays, their `t_max`, which lanes count).
    #[inline(always)]
    fn radiance_n_from<const N: usize>(
        self,
        scene: &Scene,
        rays: &[Ray; N],
        hits: [Option<Hit>; N],
        count: &mut u64,
        occluded: impl FnOnce(&[Ray; N], [f32; N], [bool; N]) -> [bool; N],
    ) -> [Vec3A; N] {
        if let Integrator::Path(options) = self {
            return std::array::from_fn(|i| path_from(scene, &rays[i], hits[i], &options, count));
        }
        // A plain loop: `hits.map` was left as a call (3 % of a `direct` frame).
        let mut rho = [Vec3A::ZERO; N];
        for (r, hit) in rho.iter_mut().zip(&hits) {
            if let Some(h) = hit {
                *r = scene.base_color(h);
            }
        }
        if self == Integrator::Flat {
            return rho;
        }
        let mut shadow = *rays;
        let mut t_max = [0.0; N];
        let mut lit = [false; N];
        let mut irradiance = [Vec3A::ZERO; N];
        for (lane, light) in unshadowed_lights(scene, rays, &hits)
            .into_iter()
            .enumerate()
        {
            if let Some((ray, t, d)) = light {
                (shadow[lane], t_max[lane], irradiance[lane]) = (ray, t, d);
                lit[lane] = true;
                *count += 1;
            }
        }
        // Unlit lanes borrow a lit lane's ray so that the packet can still share
        // the triangle test's axis order; their answers are not used.
        let Some(first) = lit.iter().position(|&l| l) else {
            return rho.map(|r| r * scene.ambient);
        };
        for lane in 0..N {
            if !lit[lane] {
                shadow[lane] = shadow[first];
            }
        }
        let blocked = occluded(&shadow, t_max, lit);
        std::array::from_fn(|lane| {
            let d = if lit[lane] && !blocked[lane] {
                irradiance[lane]
            } else {
                Vec3A::ZERO
            };
            rho[lane] * (d + scene.ambient)
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

/// The lab's `D`: irradiance from the point light at a hit, zero when the light is
/// behind the face (the lab's normals are one-sided) or something blocks it.
#[inline]
fn direct_light(scene: &Scene, hit: &Hit, dir: Vec3A, rays: &mut u64) -> Vec3A {
    let Some((shadow, t_max, d)) = unshadowed_light(scene, hit, dir) else {
        return Vec3A::ZERO;
    };
    *rays += 1;
    if scene.occluded(&shadow, t_max) {
        return Vec3A::ZERO;
    }
    d
}

/// For a hit facing the light: the shadow ray towards it, the ray's `t_max`, and
/// the irradiance `P·cos/(4πr²)` it brings if nothing blocks it.
#[inline]
fn unshadowed_light(scene: &Scene, hit: &Hit, dir: Vec3A) -> Option<(Ray, f32, Vec3A)> {
    let light = &scene.light;
    let sp = scene.surface_point(hit, dir);
    let to_light = light.position - sp.p;
    let r2 = to_light.length_squared();
    let cos = to_light.dot(sp.n) / r2.sqrt();
    if !(cos > 0.0 && r2 > 0.0) {
        return None;
    }
    let (shadow, t_max) = sp.ray_to(light.position);
    Some((shadow, t_max, light.power * (cos / (4.0 * PI * r2))))
}

/// [`unshadowed_light`] for the hits of `N` rays (a multiple of four), bit for
/// bit, four lanes at a time: the surface points are found lane by lane, then
/// the distances, cosines, offsets and shadow-ray directions are computed in
/// the lanes of SSE registers, with the scalar code's operations in its order,
/// so that the lanes' square roots and divisions overlap (lane by lane, waiting
/// for them took about a sixth of the lab's `direct` frame).
#[inline(always)]
fn unshadowed_lights<const N: usize>(
    scene: &Scene,
    rays: &[Ray; N],
    hits: &[Option<Hit>; N],
) -> [Option<(Ray, f32, Vec3A)>; N] {
    const { assert!(N.is_multiple_of(4)) };
    let light = &scene.light;
    let target = light.position;
    let mut out = [None; N];
    for quad in 0..N / 4 {
        let base = 4 * quad;
        // Lanes without a hit compute on a point of the first hit, unused.
        let Some(any) = hits[base..base + 4].iter().flatten().next() else {
            continue;
        };
        // (Written out: `array::from_fn` and `map` here were left as calls.)
        let hit = |i: usize| hits[base + i].as_ref().unwrap_or(any);
        let dir = |i: usize| rays[base + i].dir;
        let [p, n, error] = scene.surface_points4(
            [hit(0), hit(1), hit(2), hit(3)],
            [dir(0), dir(1), dir(2), dir(3)],
        );
        let l = [
            Vec4::splat(target.x),
            Vec4::splat(target.y),
            Vec4::splat(target.z),
        ];
        // `to_light`, `r2`, `cos` of `unshadowed_light`.
        let to_light = [l[0] - p[0], l[1] - p[1], l[2] - p[2]];
        let r2 = dot4(&to_light, &to_light);
        let facing = dot4(&to_light, &n);
        let cos = facing / sqrt4(r2);
        // `SurfacePoint::offset_origin(target - p)`: the offset along the
        // normal, to the side of the light, then rounded away from `p`.
        let d = dot4(&[n[0].abs(), n[1].abs(), n[2].abs()], &error);
        let away = facing.cmplt(Vec4::ZERO);
        let side = |o: Vec4| Vec4::select(away, -o, o);
        let offset = [side(d * n[0]), side(d * n[1]), side(d * n[2])];
        let step = |a: usize| step_towards4(p[a] + offset[a], offset[a]);
        let origin = [step(0), step(1), step(2)];
        // `SurfacePoint::ray_to(target)`.
        let to = [l[0] - origin[0], l[1] - origin[1], l[2] - origin[2]];
        let dist = sqrt4(dot4(&to, &to));
        let dir = [to[0] / dist, to[1] / dist, to[2] / dist];
        let skip = dist * Vec4::splat(SHADOW_EPSILON);
        let start = [
            origin[0] + dir[0] * skip,
            origin[1] + dir[1] * skip,
            origin[2] + dir[2] * skip,
        ];
        let t_max = dist - Vec4::splat(2.0) * skip;
        let scale = cos / (Vec4::splat(4.0 * PI) * r2);
        for i in 0..4 {
            let lane = base + i;
            if hits[lane].is_none() || !(cos[i] > 0.0 && r2[i] > 0.0) {
                continue;
            }
            let at = |v: &[Vec4; 3]| Vec3A::new(v[0][i], v[1][i], v[2][i]);
            out[lane] = Some((
                Ray::new(at(&start), at(&dir)),
                t_max[i],
                light.power * scale[i],
            ));
        }
    }
    out
}

/// `Vec3A::dot` lane by lane: `(x·x' + y·y') + z·z'`, in glam's order.
#[inline(always)]
fn dot4(a: &[Vec4; 3], b: &[Vec4; 3]) -> Vec4 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
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

    /// The lab's shadow rays set up four lanes at a time are the ones set up
    /// one by one, bit for bit: rays, `t_max` and irradiance, and which lanes
    /// are lit (misses, points facing away from the light, the box's blocks).
    #[test]
    fn shadow_rays_in_lanes_equal_shadow_rays_one_by_one() {
        let scene = crate::load::cornell::scene();
        let camera =
            crate::camera::Camera::lab(crate::load::cornell::CAMERA_POSITION, 0.0, 0.0, 64, 64);
        let mut rng = Rng::new(8, 8);
        let (mut lit, mut unlit) = (0, 0);
        for _ in 0..2000 {
            let rays: [Ray; 8] = std::array::from_fn(|_| {
                let (x, y) = (rng.next_f32() * 80.0 - 8.0, rng.next_f32() * 80.0 - 8.0);
                camera.ray(x, y)
            });
            let hits = rays.map(|r| scene.intersect(&r, f32::INFINITY));
            let lanes = unshadowed_lights(&scene, &rays, &hits);
            for ((ray, hit), got) in rays.iter().zip(hits).zip(lanes) {
                let want = hit.and_then(|h| unshadowed_light(&scene, &h, ray.dir));
                let bits = |l: Option<(Ray, f32, Vec3A)>| {
                    l.map(|(r, t, d)| {
                        [r.origin, r.dir, d]
                            .map(|v| v.to_array().map(f32::to_bits))
                            .concat()
                            .into_iter()
                            .chain([t.to_bits()])
                            .collect::<Vec<u32>>()
                    })
                };
                assert_eq!(bits(got), bits(want), "{ray:?} {hit:?}");
                if want.is_some() {
                    lit += 1;
                } else {
                    unlit += 1;
                }
            }
        }
        assert!(lit > 8000 && unlit > 1000, "{lit} lit, {unlit} not");
    }
}
