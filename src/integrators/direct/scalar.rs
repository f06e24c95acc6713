//! The lab's integrators, `flat` and `direct`, one ray at a time and on
//! packets of four or eight coherent rays (a pixel quad, a 4×2 block) whose
//! shadow rays are set up four lanes at a time in SSE registers and traced
//! together: the reference that [`super::lanes`] equals bit for bit.

use std::f32::consts::PI;

use glam::{Vec3A, Vec4};

use crate::geometry::ray::{Hit, Ray, SHADOW_EPSILON};
use crate::geometry::{sqrt4, step_towards4};
use crate::integrators::integrator::{Integrator, path_from};
use crate::scene::Scene;

impl Integrator {
    /// The lab's integrators on `N` coherent rays with known hits: one shadow
    /// ray per lit hit, all towards the light and traced together by `occluded`
    /// (a packet query: rays, their `t_max`, which lanes count).
    #[inline(always)]
    pub(crate) fn radiance_n_from<const N: usize>(
        self,
        scene: &Scene,
        rays: &[Ray; N],
        hits: [Option<Hit>; N],
        count: &mut u64,
        occluded: impl FnOnce(&[Ray; N], [f32; N], [bool; N]) -> [bool; N],
    ) -> [Vec3A; N] {
        if let Some(options) = self.path_options() {
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
            return unlit_surfaces(scene, &hits, &rho, rho.map(|r| r * scene.ambient));
        };
        for lane in 0..N {
            if !lit[lane] {
                shadow[lane] = shadow[first];
            }
        }
        let blocked = occluded(&shadow, t_max, lit);
        let out = std::array::from_fn(|lane| {
            let d = if lit[lane] && !blocked[lane] {
                irradiance[lane]
            } else {
                Vec3A::ZERO
            };
            rho[lane] * (d + scene.ambient)
        });
        unlit_surfaces(scene, &hits, &rho, out)
    }
}

/// `direct`'s value of a `KHR_materials_unlit` surface: `π` times its base
/// colour, the value that `direct`'s display (which divides by `π` in glTF
/// scenes, see `crate::job::display`) shows as that colour, and equal to what
/// `path` shows there in any kind of scene.
#[inline]
pub(crate) fn unlit_value(rho: Vec3A) -> Vec3A {
    rho * PI
}

/// `out` with the lanes whose hit is on a `KHR_materials_unlit` surface (not
/// to be confused with the lanes the light does not reach) replaced by
/// [`unlit_value`] of their base colour `rho` (a no-op, one test, in scenes
/// without unlit materials). Their shadow rays were traced for nothing, which
/// keeps the lit lanes' packet as it is.
#[inline(always)]
fn unlit_surfaces<const N: usize>(
    scene: &Scene,
    hits: &[Option<Hit>; N],
    rho: &[Vec3A; N],
    mut out: [Vec3A; N],
) -> [Vec3A; N] {
    if scene.has_unlit() {
        for ((o, hit), r) in out.iter_mut().zip(hits).zip(rho) {
            if let Some(h) = hit
                && scene.material(h.prim).is_unlit()
            {
                *o = unlit_value(*r);
            }
        }
    }
    out
}

/// The lab's `D`: irradiance from the point light at a hit, zero when the light is
/// behind the face (the lab's normals are one-sided) or something blocks it.
#[inline]
pub(crate) fn direct_light(scene: &Scene, hit: &Hit, dir: Vec3A, rays: &mut u64) -> Vec3A {
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
pub(crate) fn unshadowed_light(scene: &Scene, hit: &Hit, dir: Vec3A) -> Option<(Ray, f32, Vec3A)> {
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
pub(crate) fn unshadowed_lights<const N: usize>(
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::sampler::Rng;

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
