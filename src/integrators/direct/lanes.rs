//! The lab's integrators (`flat`, `direct`) on a 4×2 pixel block in the lanes
//! of AVX2 registers, from the camera rays to the eight values: the hits,
//! their base colours and surface points, the shadow rays towards the light
//! and their packet, and `ρ ∘ (D + N)`, all eight at once.
//!
//! The scalar code ([`super::scalar`]) is the reference: each lane does its
//! operations in its order (no FMA), and the values must equal those of
//! [`crate::integrators::Integrator::radiance8_from`] bit for bit, which the
//! unit test
//! `integrators::direct::lanes::tests::blocks_in_lanes_match_the_blocks_of_rays`
//! checks. A change to the scalar code is made here too. Kept in lanes from start to end, the block no
//! longer turns its rays, hits and shadow rays into `[Ray; 8]` and
//! `[Option<Hit>; 8]` and back between the steps, which had taken about half
//! of the shading's instructions.

#![cfg(target_arch = "x86_64")]

use std::f32::consts::PI;

use crate::camera::Camera;
use crate::geometry::packet::{Closest8, Rays8};
use crate::geometry::ray::SHADOW_EPSILON;
use crate::geometry::triangle::Lanes;
use crate::scene::Scene;
use crate::simd::F8;

/// `(x·x' + y·y') + z·z'` lane by lane, in glam's order.
#[inline(always)]
fn dot(a: &[F8; 3], b: &[F8; 3]) -> F8 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// The values of `flat` (`direct` false) or `direct` for the camera rays
/// through eight image points (`px`, `py`: [`Camera::ray`]'s), channel by
/// channel (`[r, g, b]`, lane `i` point `i`), and the number of shadow rays
/// traced; `None` when the rays cannot be traced as one packet, before
/// anything is counted (trace them as `[Ray; 8]`). Only for scenes where
/// [`Scene::lab_lanes_apply`].
#[target_feature(enable = "avx2")]
pub(crate) fn radiance8(
    scene: &Scene,
    camera: &Camera,
    px: &[f32; 8],
    py: &[f32; 8],
    direct: bool,
) -> Option<([[f32; 8]; 3], u32)> {
    let rays = &camera.rays8(px, py)?;
    let hits = scene.intersect8_lanes(rays)?;
    let rho = scene.base_colors8(&hits);
    let ambient = scene.ambient;
    let ambient = [
        F8::splat(ambient.x),
        F8::splat(ambient.y),
        F8::splat(ambient.z),
    ];
    if !direct {
        return Some(([rho[0].to_array(), rho[1].to_array(), rho[2].to_array()], 0));
    }
    let Some(lights) = shadow_rays8(scene, &hits, &rays.dir) else {
        // `ρ ∘ N` where no lane is lit, as the scalar code.
        let unlit = [
            (rho[0] * ambient[0]).to_array(),
            (rho[1] * ambient[1]).to_array(),
            (rho[2] * ambient[2]).to_array(),
        ];
        return Some((unlit, 0));
    };
    let Shadows8 {
        rays: shadow,
        t_max,
        scale,
        lit,
    } = lights;
    // Unlit lanes borrow the first lit lane's ray so that the packet can still
    // share the triangle test's axis order; their answers are not used.
    let lit_lanes = F8::mask_from_bits(lit);
    let first = lit.trailing_zeros() as usize;
    // (Macros, not closures: a closure is compiled without AVX2.)
    macro_rules! borrow {
        ($v:expr) => {{
            let v = $v;
            F8::select(lit_lanes, v, v.broadcast_lane(first))
        }};
    }
    let shadow = Rays8 {
        origin: [
            borrow!(shadow.origin[0]),
            borrow!(shadow.origin[1]),
            borrow!(shadow.origin[2]),
        ],
        dir: [
            borrow!(shadow.dir[0]),
            borrow!(shadow.dir[1]),
            borrow!(shadow.dir[2]),
        ],
    };
    let blocked = scene.occluded8_lanes(&shadow, lit_lanes & t_max, lit);
    let open = F8::mask_from_bits(lit & !blocked);
    // `ρ ∘ (D + N)`, with `D = P·cos/(4πr²)` where the light is seen.
    let power = scene.light.power;
    macro_rules! value {
        ($c:expr, $power:expr) => {{
            let irradiance = open & (F8::splat($power) * scale);
            (rho[$c] * (irradiance + ambient[$c])).to_array()
        }};
    }
    Some((
        [value!(0, power.x), value!(1, power.y), value!(2, power.z)],
        lit.count_ones(),
    ))
}

/// The shadow rays of eight hits towards the point light, in lanes.
struct Shadows8 {
    /// `SurfacePoint::ray_to`'s rays (in lit lanes).
    rays: Rays8,
    /// Their `t_max`.
    t_max: F8,
    /// `cos/(4πr²)`, the light's power to irradiance where it is seen.
    scale: F8,
    /// The lanes whose hit faces the light, one bit each.
    lit: u32,
}

/// [`super::scalar::unshadowed_light`] of eight hits (rays along `dir`), in lanes;
/// `None` when no lane hit, or no hit faces the light.
#[target_feature(enable = "avx2")]
#[inline]
fn shadow_rays8(scene: &Scene, hits: &Closest8, dir: &[F8; 3]) -> Option<Shadows8> {
    if hits.found == 0 {
        return None;
    }
    // `unshadowed_light`: the distance and cosine to the light.
    let light = &scene.light;
    let target = [
        F8::splat(light.position.x),
        F8::splat(light.position.y),
        F8::splat(light.position.z),
    ];
    let point = scene.surface_points8(hits, dir);
    let (p, n) = (&point.p, &point.n);
    let to_light = [target[0] - p[0], target[1] - p[1], target[2] - p[2]];
    let r2 = dot(&to_light, &to_light);
    let facing = dot(&to_light, n);
    let cos = facing / r2.sqrt();
    let zero = F8::zero();
    let lit = (cos.cmpgt(zero) & r2.cmpgt(zero)).bitmask() & hits.found;
    if lit == 0 {
        return None;
    }
    // `SurfacePoint::offset_origin(target − p)`: along the normal, to the side
    // of the light, then rounded away from `p`.
    let d = dot(&[n[0].abs(), n[1].abs(), n[2].abs()], &point.error);
    let away = facing.cmplt(zero);
    let offset = [
        F8::select(away, (d * n[0]).neg(), d * n[0]),
        F8::select(away, (d * n[1]).neg(), d * n[1]),
        F8::select(away, (d * n[2]).neg(), d * n[2]),
    ];
    let origin = [
        (p[0] + offset[0]).step_towards(offset[0]),
        (p[1] + offset[1]).step_towards(offset[1]),
        (p[2] + offset[2]).step_towards(offset[2]),
    ];
    let (rays, t_max) = shadow_segments8(&origin, &target);
    Some(Shadows8 {
        rays,
        t_max,
        scale: cos / (F8::splat(4.0 * PI) * r2),
        lit,
    })
}

/// `SurfacePoint::ray_to(target)` after its offset origin, in lanes: the rays
/// from `origin` towards `target` with both ends trimmed by
/// [`SHADOW_EPSILON`] of the distance, and their `t_max`.
#[inline(always)]
pub(crate) fn shadow_segments8(origin: &[F8; 3], target: &[F8; 3]) -> (Rays8, F8) {
    let to = [
        target[0] - origin[0],
        target[1] - origin[1],
        target[2] - origin[2],
    ];
    let dist = dot(&to, &to).sqrt();
    let dir = [to[0] / dist, to[1] / dist, to[2] / dist];
    let skip = dist * F8::splat(SHADOW_EPSILON);
    let start = [
        origin[0] + dir[0] * skip,
        origin[1] + dir[1] * skip,
        origin[2] + dir[2] * skip,
    ];
    (Rays8 { origin: start, dir }, dist - F8::splat(2.0) * skip)
}

#[cfg(test)]
mod tests {
    use glam::Vec3A;

    use super::*;
    use crate::geometry::ray::Hit;
    use crate::integrators::Integrator;
    use crate::load::cornell;
    use crate::sampling::sampler::Rng;

    #[target_feature(enable = "avx2")]
    fn lanes(
        scene: &Scene,
        camera: &Camera,
        px: &[f32; 8],
        py: &[f32; 8],
        direct: bool,
    ) -> Option<([[f32; 8]; 3], u32)> {
        radiance8(scene, camera, px, py, direct)
    }

    /// Lane by lane: the camera ray's hit, and for lanes facing the light
    /// the shadow ray's origin, direction, `t_max` and irradiance scale.
    type Lane = (Option<Hit>, Option<([f32; 3], [f32; 3], f32, f32)>);

    #[target_feature(enable = "avx2")]
    fn lanes_shadow_rays(
        scene: &Scene,
        camera: &Camera,
        px: &[f32; 8],
        py: &[f32; 8],
    ) -> Option<[Lane; 8]> {
        let rays = camera.rays8(px, py)?;
        let hits = scene.intersect8_lanes(&rays)?;
        let mut lanes = hits.hits().map(|h| (h, None));
        if hits.found == 0 {
            return Some(lanes);
        }
        if let Some(s) = shadow_rays8(scene, &hits, &rays.dir) {
            let o = s.rays.origin.map(F8::to_array);
            let d = s.rays.dir.map(F8::to_array);
            let (t_max, scale) = (s.t_max.to_array(), s.scale.to_array());
            for (i, lane) in lanes.iter_mut().enumerate() {
                if s.lit >> i & 1 != 0 {
                    let at = |v: &[[f32; 8]; 3]| [v[0][i], v[1][i], v[2][i]];
                    lane.1 = Some((at(&o), at(&d), t_max[i], scale[i]));
                }
            }
        }
        Some(lanes)
    }

    /// What the block loop does without lanes: two `rays4`, `intersect8` and
    /// `radiance8_from`; the values and the number of shadow rays.
    fn rays(
        scene: &Scene,
        camera: &Camera,
        px: &[f32; 8],
        py: &[f32; 8],
        integrator: Integrator,
    ) -> ([Vec3A; 8], u64) {
        let t = camera.rays4([px[0], px[1], px[2], px[3]], [py[0], py[1], py[2], py[3]]);
        let b = camera.rays4([px[4], px[5], px[6], px[7]], [py[4], py[5], py[6], py[7]]);
        let primary = [t[0], t[1], t[2], t[3], b[0], b[1], b[2], b[3]];
        let hits = scene.intersect8(&primary, f32::INFINITY);
        let mut count = 0;
        let values = integrator.radiance8_from(scene, &primary, hits, &mut count);
        (values, count)
    }

    /// Forty random triangles and a wall in a two-sided scene (the form of
    /// meshes), to hit from both sides, and the lab box.
    fn scenes() -> Vec<Scene> {
        let random = crate::integrators::random_two_sided_scene(0, Vec3A::new(0.1, 0.2, 0.3));
        vec![cornell::scene(), random]
    }

    /// The block in lanes gives the values of the block as `[Ray; 8]`, bit for
    /// bit, and counts the same shadow rays: `flat` and `direct`, one- and
    /// two-sided scenes, lights inside and outside the scene, blocks that hit
    /// and miss, are lit, unlit and shadowed in part, and whose shadow rays
    /// cannot share a packet.
    #[test]
    fn blocks_in_lanes_match_the_blocks_of_rays() {
        if !std::arch::is_x86_feature_detected!("avx2") {
            return;
        }
        let mut rng = Rng::new(9, 0);
        let (mut compared, mut lit, mut shadowed, mut missed) = (0, 0, 0, 0);
        for (k, mut scene) in scenes().into_iter().enumerate() {
            assert!(scene.lab_lanes_apply());
            for round in 0..3000 {
                let mut r = || rng.next_f32();
                if round % 50 == 0 {
                    scene.light.position = Vec3A::new(r(), r(), r()) * 2.0 - 1.0;
                }
                let position = if k == 0 {
                    Vec3A::new(r() - 0.5, r() - 0.5, -3.0 + 2.5 * r())
                } else {
                    Vec3A::new(r() - 0.5, r() - 0.5, -2.0 - r())
                };
                let camera = Camera::lab(position, 40.0 * r() - 20.0, 40.0 * r() - 20.0, 64, 48);
                // A 4×2 block, jittered or through the centres, or spread out.
                let (x0, y0) = ((r() * 60.0).floor(), (r() * 46.0).floor());
                let spread = if round % 3 == 0 { 8.0 * r() } else { 1.0 };
                let mut px = [0.0; 8];
                let mut py = [0.0; 8];
                for i in 0..8 {
                    let jitter = round % 2 == 0;
                    px[i] = x0 + spread * (i % 4) as f32 + if jitter { r() } else { 0.5 };
                    py[i] = y0 + spread * (i / 4) as f32 + if jitter { r() } else { 0.5 };
                }
                for integrator in [Integrator::Flat, Integrator::Direct] {
                    let direct = integrator == Integrator::Direct;
                    // SAFETY: the CPU has AVX2.
                    let Some((got, shadows)) =
                        (unsafe { lanes(&scene, &camera, &px, &py, direct) })
                    else {
                        continue;
                    };
                    let (want, count) = rays(&scene, &camera, &px, &py, integrator);
                    for i in 0..8 {
                        let got = [got[0][i], got[1][i], got[2][i]].map(f32::to_bits);
                        assert_eq!(got, want[i].to_array().map(f32::to_bits), "{k} {round} {i}");
                    }
                    assert_eq!(u64::from(shadows), count, "{k} {round}");
                    compared += 1;
                    if !direct {
                        continue;
                    }
                    // What the lanes had to get right: misses, lit lanes,
                    // and lit lanes in shadow.
                    // SAFETY: the CPU has AVX2.
                    let lanes =
                        unsafe { lanes_shadow_rays(&scene, &camera, &px, &py) }.expect("traced");
                    for (i, (hit, got)) in lanes.into_iter().enumerate() {
                        let ray = camera.ray(px[i], py[i]);
                        let Some(hit) = hit else {
                            missed += 1;
                            continue;
                        };
                        let want = crate::integrators::direct::scalar::unshadowed_light(
                            &scene, &hit, ray.dir,
                        );
                        let bits = |v: [f32; 3]| v.map(f32::to_bits);
                        match (got, want) {
                            (None, None) => {}
                            (
                                Some((o, d, t_max, scale)),
                                Some((shadow, want_t_max, irradiance)),
                            ) => {
                                assert_eq!(
                                    bits(o),
                                    bits(shadow.origin.to_array()),
                                    "{k} {round} {i}"
                                );
                                assert_eq!(bits(d), bits(shadow.dir.to_array()), "{k} {round} {i}");
                                assert_eq!(
                                    t_max.to_bits(),
                                    want_t_max.to_bits(),
                                    "{k} {round} {i}"
                                );
                                let power = scene.light.power * scale;
                                assert_eq!(bits(power.to_array()), bits(irradiance.to_array()));
                                lit += 1;
                                shadowed += scene.occluded(&shadow, want_t_max) as u32;
                            }
                            (got, want) => panic!("{k} {round} {i}: {got:?} against {want:?}"),
                        }
                    }
                }
            }
        }
        assert!(
            compared > 10_000 && lit > 2000 && shadowed > 1000 && missed > 1000,
            "{compared} {lit} {shadowed} {missed}"
        );
    }
}
