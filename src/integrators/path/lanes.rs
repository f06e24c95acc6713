//! The `path` integrator on eight paths at once, their shading in the lanes
//! of AVX2 registers, for scenes of fixed materials (diffuse, mirror, glass,
//! emitting triangles) without textures or shading normals: the lab box,
//! `cornell-area`, meshes in them (see [`Scene::path_lanes_apply`]).
//!
//! Each lane holds one path. The rays are traced one by one (a packet of
//! bounce rays enters every leaf its rays do, and cost as much as the rays
//! alone: docs/performance.md), their per-ray constants made in the lanes
//! ([`Singles8`]); most of the work between two traces, the
//! hit's surface point, frame, the key light's sample, the shadow ray, the
//! diffuse BSDF's sample and the ray that leaves, is done for the eight paths
//! together; what only some lanes need (emission, an area light's sample,
//! mirror and glass) is done lane by lane with the scalar code. When a path
//! ends its lane takes the next sample, so the lanes stay full until the
//! samples run out.
//!
//! The scalar path tracer ([`super::scalar`]) is the reference: each lane does
//! its operations in its order (no FMA), and every sample's value must equal
//! that of [`super::radiance_from`] bit for bit, which the unit test
//! `integrators::path::lanes::tests::paths_in_lanes_match_paths_one_by_one`
//! checks; only the order in which samples finish changes, which the exact
//! sums do not see. A change to the scalar code is made here too.

#![cfg(target_arch = "x86_64")]

use std::f32::consts::{FRAC_1_PI, FRAC_PI_4};

use glam::{Vec2, Vec3A};

use super::options::{RR_DEPTH, RR_SCALE};
use super::samples::{PathSampler, SobolSampler};
use super::vertex::{light_terms, power_heuristic};
use crate::geometry::bvh::Singles8;
use crate::geometry::packet::Closest8;
use crate::geometry::ray::{Hit, Ray};
use crate::geometry::triangle::Lanes;
use crate::integrators::direct::lanes::shadow_segments8;
use crate::materials::Material;
use crate::materials::surface::HitAttributes;
use crate::scene::{Facing, LightSample, Scene};
use crate::simd::F8;

/// `(x·x' + y·y') + z·z'` lane by lane, in glam's order.
#[inline(always)]
fn dot(a: &[F8; 3], b: &[F8; 3]) -> F8 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// One path's start, made by the caller.
#[derive(Clone)]
pub(crate) struct Start {
    /// The caller's tag, given back with the value (e.g. the pixel it adds to).
    pub(crate) tag: usize,
    /// The path's sampler, after the camera's pair.
    pub(crate) sampler: SobolSampler,
    /// The camera ray.
    pub(crate) ray: Ray,
    /// Its closest hit (traced by the caller, which counts the ray).
    pub(crate) hit: Option<Hit>,
}

/// The eight lanes' paths, lane `i` of every array path `i`.
struct Paths {
    /// The lanes holding a path, one bit each.
    active: u32,
    tag: [usize; 8],
    sampler: [Option<SobolSampler>; 8],
    depth: [u32; 8],
    /// The direction of the ray that found the current hit.
    dir: [[f32; 8]; 3],
    /// The current hit.
    t: [f32; 8],
    prim: [u32; 8],
    b1: [f32; 8],
    b2: [f32; 8],
    /// Throughput and radiance so far.
    beta: [[f32; 8]; 3],
    l: [[f32; 8]; 3],
    /// The lanes whose last bounce was a delta lobe (or the camera ray), one
    /// bit each, and each lane's last BSDF sample's pdf: MIS for emission.
    specular: u32,
    bsdf_pdf: [f32; 8],
    /// Each lane's last vertex and the normal of the side it was lit from
    /// (`Facing::Side`), where that MIS weighs the light's choice.
    from: [[f32; 8]; 3],
    from_n: [[f32; 8]; 3],
}

impl Paths {
    #[inline(always)]
    fn vec(v: &[[f32; 8]; 3], i: usize) -> Vec3A {
        Vec3A::new(v[0][i], v[1][i], v[2][i])
    }

    #[inline(always)]
    fn set(v: &mut [[f32; 8]; 3], i: usize, x: Vec3A) {
        v[0][i] = x.x;
        v[1][i] = x.y;
        v[2][i] = x.z;
    }

    #[inline(always)]
    fn load(v: &[[f32; 8]; 3]) -> [F8; 3] {
        [
            F8::from_array(v[0]),
            F8::from_array(v[1]),
            F8::from_array(v[2]),
        ]
    }

    #[inline(always)]
    fn store(v: &mut [[f32; 8]; 3], x: &[F8; 3]) {
        v[0] = x[0].to_array();
        v[1] = x[1].to_array();
        v[2] = x[2].to_array();
    }
}

/// Traces every path that `next` starts (until it returns `None`) with
/// `max_depth` as [`super::PathOptions::max_depth`], and gives each
/// path's tag and value to `emit`; returns the rays cast after the camera
/// rays. Only for scenes where [`Scene::path_lanes_apply`].
#[target_feature(enable = "avx2")]
pub(crate) fn trace(
    scene: &Scene,
    max_depth: u32,
    next: &mut impl FnMut() -> Option<Start>,
    emit: &mut impl FnMut(usize, Vec3A),
) -> u64 {
    debug_assert!(scene.path_lanes_apply());
    // What each material is, looked up by the lanes (one byte, not the BSDF).
    let kinds: Vec<u8> = scene
        .materials()
        .iter()
        .map(|m| {
            let bsdf = m.bsdf(&HitAttributes::default(), scene.textures());
            let flag = |b: bool, bit: u8| if b { bit } else { 0 };
            flag(matches!(bsdf, Material::Diffuse { .. }), DIFFUSE)
                | flag(matches!(bsdf, Material::Dielectric { .. }), TWO_SIDED)
                | flag(m.is_emissive(), EMISSIVE)
                | flag(bsdf.chooses_lobe(), CHOOSES_LOBE)
        })
        .collect();
    // With the key light the only light, every point gets the same sample
    // (`Scene::sample_light` draws nothing): the lanes then compute it
    // themselves.
    let key = (!scene.light_needs_samples()).then(|| {
        match scene.sample_light(Vec3A::ZERO, Facing::Any, Vec2::ZERO, Vec2::ZERO) {
            Some(LightSample::Point {
                position,
                intensity,
                ..
            }) => Some((position, intensity)),
            _ => None,
        }
    });
    // The lab's scenes (every surface diffuse, none emitting, the key light
    // alone) take a step compiled without the rest.
    let lab = kinds.iter().all(|&k| k == DIFFUSE) && key.is_some();
    let vertex = Vertex {
        scene,
        kinds: &kinds,
        key,
        max_depth,
        by_point: scene.light_choice_depends_on_point(),
    };
    let mut rays = 0u64;
    let mut lanes = Paths {
        active: 0,
        tag: [0; 8],
        sampler: [const { None }; 8],
        depth: [0; 8],
        dir: [[0.0; 8]; 3],
        t: [0.0; 8],
        prim: [0; 8],
        b1: [0.0; 8],
        b2: [0.0; 8],
        beta: [[0.0; 8]; 3],
        l: [[0.0; 8]; 3],
        specular: 0,
        bsdf_pdf: [0.0; 8],
        from: [[0.0; 8]; 3],
        from_n: [[0.0; 8]; 3],
    };
    let mut exhausted = false;
    loop {
        // Fill the empty lanes with new paths whose camera ray hits.
        if !exhausted {
            for i in 0..8 {
                if lanes.active >> i & 1 != 0 {
                    continue;
                }
                loop {
                    let Some(Start {
                        tag,
                        sampler,
                        ray,
                        hit,
                    }) = next()
                    else {
                        exhausted = true;
                        break;
                    };
                    let Some(hit) = hit else {
                        // Escaped into a black environment.
                        emit(tag, Vec3A::ZERO);
                        continue;
                    };
                    lanes.active |= 1 << i;
                    lanes.tag[i] = tag;
                    lanes.sampler[i] = Some(sampler);
                    lanes.depth[i] = 0;
                    Paths::set(&mut lanes.dir, i, ray.dir);
                    lanes.t[i] = hit.t;
                    lanes.prim[i] = hit.prim;
                    lanes.b1[i] = hit.b1;
                    lanes.b2[i] = hit.b2;
                    Paths::set(&mut lanes.beta, i, Vec3A::ONE);
                    Paths::set(&mut lanes.l, i, Vec3A::ZERO);
                    lanes.specular |= 1 << i;
                    lanes.bsdf_pdf[i] = 0.0;
                    break;
                }
                if exhausted {
                    break;
                }
            }
        }
        if lanes.active == 0 {
            return rays;
        }
        rays += if lab {
            vertex.step::<true>(&mut lanes, emit)
        } else {
            vertex.step::<false>(&mut lanes, emit)
        };
    }
}

/// Ends path `i` with its value.
#[inline(always)]
fn finish(lanes: &mut Paths, i: usize, emit: &mut impl FnMut(usize, Vec3A)) {
    lanes.active &= !(1 << i);
    emit(lanes.tag[i], Paths::vec(&lanes.l, i));
}

/// [`Vertex::kinds`]' bits.
const DIFFUSE: u8 = 1;
const TWO_SIDED: u8 = 2;
const EMISSIVE: u8 = 4;
const CHOOSES_LOBE: u8 = 8;

/// What a vertex of the paths needs besides the paths.
struct Vertex<'a> {
    scene: &'a Scene,
    /// Per material: [`DIFFUSE`] (else mirror or glass), [`TWO_SIDED`] (glass:
    /// the BSDF tells the sides apart), [`EMISSIVE`], [`CHOOSES_LOBE`].
    kinds: &'a [u8],
    /// When the key light is the only light: its position and intensity
    /// (`None`: it has no power).
    key: Option<Option<(Vec3A, Vec3A)>>,
    max_depth: u32,
    /// Whether the lights' choice depends on the point and its side (then
    /// each lane keeps its last vertex for MIS).
    by_point: bool,
}

impl Vertex<'_> {
    /// One vertex of every active path: shades its hit (emission, next-event
    /// estimation, a BSDF sample), and traces the ray that leaves it or ends
    /// the path. Returns the rays cast. `LAB`: the scene is the lab's kind
    /// (every surface diffuse, none emitting, the key light alone).
    #[target_feature(enable = "avx2")]
    #[inline]
    fn step<const LAB: bool>(&self, lanes: &mut Paths, emit: &mut impl FnMut(usize, Vec3A)) -> u64 {
        let (scene, max_depth) = (self.scene, self.max_depth);
        let mut rays = 0;
        let active = lanes.active;
        let zero = F8::zero();
        let one = F8::splat(1.0);
        let hits = Closest8 {
            found: active,
            t: F8::zero(),
            b1: F8::from_array(lanes.b1),
            b2: F8::from_array(lanes.b2),
            prim: F8::from_array(lanes.prim.map(f32::from_bits)),
        };
        let dir = Paths::load(&lanes.dir);
        let point = scene.surface_points8_front(&hits);
        let (p, ng, error) = (&point.p, &point.n, &point.error);
        // `cos_out = -ng·dir`.
        let cos_out = dot(ng, &dir).neg();
        let (p_at, cos_at) = (
            [p[0].to_array(), p[1].to_array(), p[2].to_array()],
            cos_out.to_array(),
        );
        let ng_at = self
            .by_point
            .then(|| [ng[0].to_array(), ng[1].to_array(), ng[2].to_array()]);

        // Lane by lane: emission seen at the hit; the end of paths of
        // `max_depth` segments (Mitsuba's convention); the sample values; the
        // light sample of surfaces that are not specular.
        let textures = scene.textures();
        let needs_choice = scene.light_needs_samples();
        let (mut ub, mut u_lobe) = (([0.0f32; 8], [0.0f32; 8]), [0.0f32; 8]);
        let mut target = [[0.0f32; 8]; 3];
        let mut li = [[0.0f32; 8]; 3];
        let mut light_pdf = [0.0f32; 8];
        let (mut diffuse, mut one_sided, mut lights, mut mis) = (0u32, 0u32, 0u32, 0u32);
        for i in 0..8 {
            if active >> i & 1 == 0 {
                continue;
            }
            let kind = if LAB {
                DIFFUSE
            } else {
                self.kinds[scene.material_index(lanes.prim[i])]
            };
            let cos_out = cos_at[i];
            if kind & EMISSIVE != 0 {
                let material = scene.material(lanes.prim[i]);
                if cos_out > 0.0 || material.emits_both_sides {
                    // (No emission textures here: the attributes are not needed.)
                    let le = material.emission;
                    let weight = if lanes.specular >> i & 1 != 0 {
                        1.0
                    } else {
                        let t = lanes.t[i];
                        let from = Facing::Side(Paths::vec(&lanes.from_n, i));
                        let pdf =
                            scene.light_pdf_area(lanes.prim[i], Paths::vec(&lanes.from, i), from)
                                * t
                                * t
                                / cos_out.abs();
                        power_heuristic(lanes.bsdf_pdf[i], pdf)
                    };
                    let l = Paths::vec(&lanes.l, i) + Paths::vec(&lanes.beta, i) * le * weight;
                    Paths::set(&mut lanes.l, i, l);
                }
            }
            if lanes.depth[i] + 1 >= max_depth {
                finish(lanes, i, emit);
                continue;
            }
            let light_sampled = kind & DIFFUSE != 0;
            diffuse |= u32::from(light_sampled) << i;
            one_sided |= u32::from(kind & TWO_SIDED == 0) << i;
            let sampler = lanes.sampler[i]
                .as_mut()
                .expect("an active lane has a sampler");
            let (u_light, u_bsdf) = (sampler.next_2d(), sampler.next_2d());
            let u_choice = if (light_sampled && needs_choice) || kind & CHOOSES_LOBE != 0 {
                sampler.next_2d_minor()
            } else {
                Vec2::ZERO
            };
            (ub.0[i], ub.1[i], u_lobe[i]) = (u_bsdf.x, u_bsdf.y, u_choice.y);
            if LAB || self.key.is_some() {
                continue;
            }
            let at = Paths::vec(&p_at, i);
            // With the light tree: the side the path leaves by, as the scalar
            // code's `Facing` (these scenes have no shading normals), kept
            // for the next hit's MIS. (Else the choice does not depend on it.)
            let facing = match &ng_at {
                Some(ng_at) => {
                    let ng = Paths::vec(ng_at, i);
                    let side = if cos_out < 0.0 { -ng } else { ng };
                    Paths::set(&mut lanes.from, i, at);
                    Paths::set(&mut lanes.from_n, i, side);
                    Facing::Side(side)
                }
                None => Facing::Any,
            };
            if !light_sampled {
                continue;
            }
            if let Some(light) = scene.sample_light(at, facing, u_choice, u_light) {
                let (to, arriving, pdf) = light_terms(at, light);
                // (No environment here: the value is known.)
                let radiance = arriving.value(scene);
                if radiance != Vec3A::ZERO {
                    lights |= 1 << i;
                    Paths::set(&mut target, i, to);
                    Paths::set(&mut li, i, radiance);
                    if let Some(pdf) = pdf {
                        mis |= 1 << i;
                        light_pdf[i] = pdf;
                    }
                }
            }
        }
        let active = lanes.active;
        if active == 0 {
            return 0;
        }

        // The frame: one-sided BSDFs face the ray in two-sided scenes.
        let n = if scene.two_sided {
            let back = cos_out.cmplt(zero) & F8::mask_from_bits(one_sided);
            [
                F8::select(back, ng[0].neg(), ng[0]),
                F8::select(back, ng[1].neg(), ng[1]),
                F8::select(back, ng[2].neg(), ng[2]),
            ]
        } else {
            *ng
        };
        // `Frame::from_normal` (Duff et al.); `1.copysign(n.z)` first.
        let sign = (n[2] & F8::splat(-0.0)) | one;
        let a = (one.neg()) / (sign + n[2]);
        let b = n[0] * n[1] * a;
        let t = [one + sign * n[0] * n[0] * a, sign * b, sign.neg() * n[0]];
        let bt = [b, sign + n[1] * n[1] * a, n[1].neg()];
        let wo_world = [dir[0].neg(), dir[1].neg(), dir[2].neg()];
        let wo_z = dot(&wo_world, &n);
        let wo_above = wo_z.cmpgt(zero);
        // `SurfacePoint::offset_origin`'s distance along the normal.
        let d = dot(&[ng[0].abs(), ng[1].abs(), ng[2].abs()], error);
        let off = [d * ng[0], d * ng[1], d * ng[2]];
        // (Macros, not closures: a closure is compiled without AVX2.)
        macro_rules! offset_origin {
            ($w:expr) => {{
                let away = dot($w, ng).cmplt(zero);
                let o = [
                    F8::select(away, off[0].neg(), off[0]),
                    F8::select(away, off[1].neg(), off[1]),
                    F8::select(away, off[2].neg(), off[2]),
                ];
                [
                    (p[0] + o[0]).step_towards(o[0]),
                    (p[1] + o[1]).step_towards(o[1]),
                    (p[2] + o[2]).step_towards(o[2]),
                ]
            }};
        }
        let rho = scene.base_colors8(&hits);
        let mut beta = Paths::load(&lanes.beta);

        // Next-event estimation on diffuse surfaces.
        let (target, li, nee) = match self.key {
            // The key light's sample (`light_terms`), in the lanes.
            Some(Some((position, intensity))) => {
                let target = [
                    F8::splat(position.x),
                    F8::splat(position.y),
                    F8::splat(position.z),
                ];
                let v = [target[0] - p[0], target[1] - p[1], target[2] - p[2]];
                let r2 = dot(&v, &v);
                let li = [
                    F8::splat(intensity.x) / r2,
                    F8::splat(intensity.y) / r2,
                    F8::splat(intensity.z) / r2,
                ];
                let seen = li[0].cmpne(zero) | li[1].cmpne(zero) | li[2].cmpne(zero);
                (target, li, seen.bitmask() & diffuse & active)
            }
            Some(None) => ([zero; 3], [zero; 3], 0),
            None => (
                Paths::load(&target),
                Paths::load(&li),
                lights & diffuse & active,
            ),
        };
        if nee != 0 {
            let v = [target[0] - p[0], target[1] - p[1], target[2] - p[2]];
            let len = dot(&v, &v).sqrt();
            let wi_world = [v[0] / len, v[1] / len, v[2] / len];
            let wi_z = dot(&wi_world, &n);
            let scale = F8::splat(FRAC_1_PI) * wi_z;
            let f = [rho[0] * scale, rho[1] * scale, rho[2] * scale];
            let nonzero = f[0].cmpne(zero) | f[1].cmpne(zero) | f[2].cmpne(zero);
            let lit = (wo_above & wi_z.cmpgt(zero) & nonzero).bitmask() & nee;
            if lit != 0 {
                // `SurfacePoint::ray_to(target)`.
                let origin = offset_origin!(&v);
                let (shadow, t_max) = shadow_segments8(&origin, &target);
                // Their constants made in the lanes, the rays traced one by one.
                let shadow = Singles8::new(&shadow.origin, &shadow.dir);
                let t_max = t_max.to_array();
                let wi_z = wi_z.to_array();
                let mut open = 0u32;
                let mut weight = [1.0f32; 8];
                for (i, &t_max) in t_max.iter().enumerate() {
                    if lit >> i & 1 == 0 {
                        continue;
                    }
                    rays += 1;
                    if !scene.occluded_single8(&shadow, i, t_max) {
                        open |= 1 << i;
                        if mis >> i & 1 != 0 {
                            // The diffuse BSDF's pdf (`Material::pdf`) against the light's.
                            weight[i] = power_heuristic(light_pdf[i], FRAC_1_PI * wi_z[i]);
                        }
                    }
                }
                if open != 0 {
                    let open = F8::mask_from_bits(open);
                    let weight = F8::from_array(weight);
                    let mut l = Paths::load(&lanes.l);
                    for c in 0..3 {
                        // `l += β·f·Li·w`.
                        let add = l[c] + beta[c] * f[c] * li[c] * weight;
                        l[c] = F8::select(open, add, l[c]);
                    }
                    Paths::store(&mut lanes.l, &l);
                }
            }
        }

        // The BSDF sample: on diffuse surfaces a cosine-weighted direction
        // (`concentric_disk`, then up to the hemisphere) in the lanes; on the
        // others `Material::sample` lane by lane.
        let (u0, u1) = (F8::from_array(ub.0), F8::from_array(ub.1));
        let two = F8::splat(2.0);
        let ox = two * u0 - one;
        let oy = two * u1 - one;
        let centre = ox.cmpeq(zero) & oy.cmpeq(zero);
        let x_major = ox.abs().cmpgt(oy.abs());
        let r = F8::select(x_major, ox, oy);
        let other = F8::select(x_major, oy, ox);
        let (s, c) = sin_cos_quarter(F8::splat(FRAC_PI_4) * (other / r));
        let mut wi = [
            F8::select(centre, zero, r * F8::select(x_major, c, s)),
            F8::select(centre, zero, r * F8::select(x_major, s, c)),
            zero,
        ];
        wi[2] = (one - (wi[0] * wi[0] + wi[1] * wi[1])).max_(zero).sqrt();
        let mut leaves = (wo_above & wi[2].cmpgt(zero)).bitmask() & diffuse & active;
        let mut weight = rho;
        let mut pdf = F8::splat(FRAC_1_PI) * wi[2];
        let others = active & !diffuse;
        if !LAB && others != 0 {
            let wo = [dot(&wo_world, &t), dot(&wo_world, &bt), wo_z];
            let wo = [wo[0].to_array(), wo[1].to_array(), wo[2].to_array()];
            let (mut wi_at, mut weight_at) = ([[0.0f32; 8]; 3], [[0.0f32; 8]; 3]);
            let mut pdf_at = [0.0f32; 8];
            for i in 0..8 {
                if others >> i & 1 == 0 {
                    continue;
                }
                let bsdf = scene
                    .material(lanes.prim[i])
                    .bsdf(&HitAttributes::default(), textures);
                let u = Vec2::new(ub.0[i], ub.1[i]);
                if let Some(bs) = bsdf.sample(Paths::vec(&wo, i), u_lobe[i], u) {
                    leaves |= 1 << i;
                    Paths::set(&mut wi_at, i, bs.wi);
                    Paths::set(&mut weight_at, i, bs.weight);
                    pdf_at[i] = bs.pdf;
                    if bs.specular {
                        lanes.specular |= 1 << i;
                    } else {
                        lanes.specular &= !(1 << i);
                    }
                }
            }
            let from = F8::mask_from_bits(others);
            let (wi_at, weight_at) = (Paths::load(&wi_at), Paths::load(&weight_at));
            for c in 0..3 {
                wi[c] = F8::select(from, wi_at[c], wi[c]);
                weight[c] = F8::select(from, weight_at[c], weight[c]);
            }
            pdf = F8::select(from, F8::from_array(pdf_at), pdf);
        }
        lanes.specular &= !diffuse;
        lanes.bsdf_pdf = pdf.to_array();
        let wi_world = [
            wi[0] * t[0] + wi[1] * bt[0] + wi[2] * n[0],
            wi[0] * t[1] + wi[1] * bt[1] + wi[2] * n[1],
            wi[0] * t[2] + wi[1] * bt[2] + wi[2] * n[2],
        ];
        let origin = offset_origin!(&wi_world);
        for (c, b) in beta.iter_mut().enumerate() {
            *b = *b * weight[c];
        }
        Paths::store(&mut lanes.beta, &beta);
        Paths::store(&mut lanes.dir, &wi_world);
        let leaving = Singles8::new(&origin, &wi_world);

        // Each path's roulette and next hit, one by one.
        for i in 0..8 {
            if active >> i & 1 == 0 {
                continue;
            }
            if leaves >> i & 1 == 0 {
                finish(lanes, i, emit);
                continue;
            }
            lanes.depth[i] += 1;
            let mut beta = Paths::vec(&lanes.beta, i);
            if beta == Vec3A::ZERO {
                finish(lanes, i, emit);
                continue;
            }
            if lanes.depth[i] >= RR_DEPTH {
                let survive = (beta.max_element() * RR_SCALE).min(0.95);
                let sampler = lanes.sampler[i]
                    .as_mut()
                    .expect("an active lane has a sampler");
                // (A NaN throughput ends the path too.)
                if sampler.next_1d() >= survive || survive.is_nan() {
                    finish(lanes, i, emit);
                    continue;
                }
                beta /= survive;
                Paths::set(&mut lanes.beta, i, beta);
            }
            rays += 1;
            match scene.intersect_single8(&leaving, i) {
                Some(hit) => {
                    lanes.t[i] = hit.t;
                    lanes.prim[i] = hit.prim;
                    lanes.b1[i] = hit.b1;
                    lanes.b2[i] = hit.b2;
                }
                None => finish(lanes, i, emit),
            }
        }
        rays
    }
}

/// `sin_cos_quarter` of `materials/disk.rs` lane by lane.
#[inline(always)]
fn sin_cos_quarter(x: F8) -> (F8, F8) {
    let x2 = x * x;
    let sin = x + x
        * x2
        * (F8::splat(-1.666_665_5e-1)
            + x2 * (F8::splat(8.332_161e-3) + x2 * F8::splat(-1.951_529_6e-4)));
    let cos = F8::splat(1.0) - F8::splat(0.5) * x2
        + x2 * x2
            * (F8::splat(4.166_664_6e-2)
                + x2 * (F8::splat(-1.388_731_6e-3) + x2 * F8::splat(2.443_315_7e-5)));
    (sin, cos)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::integrators::path::{self, PathOptions, SamplerKind};
    use crate::load::cornell;
    use crate::sampling::sampler::Rng;

    /// The lab box (one-sided); forty random triangles with a wall in a
    /// two-sided scene (the form of meshes), to hit from both sides; the
    /// same with mirrors, glass and emitting triangles; `cornell-area` with a
    /// mirror and a glass block, with and without the key light.
    fn scenes() -> Vec<Scene> {
        let random = crate::integrators::random_two_sided_scene(1, Vec3A::ZERO);
        let mut mixed = random.clone();
        for prim in 0..40 {
            match prim % 5 {
                1 => mixed.set_material(
                    prim,
                    Material::Mirror {
                        reflectance: Vec3A::new(0.9, 0.8, 0.7),
                    },
                ),
                2 => mixed.set_material(prim, Material::Dielectric { ior: 1.5 }),
                3 => mixed
                    .set_emission(prim, Vec3A::new(2.0, 3.0, 4.0))
                    .expect("a valid radiance"),
                _ => {}
            }
        }
        let mut area = cornell::area_scene();
        cornell::MaterialChoice::Other(Material::Mirror {
            reflectance: Vec3A::ONE,
        })
        .apply(&mut area, cornell::parts::TALL_BLOCK);
        cornell::MaterialChoice::Other(Material::Dielectric { ior: 1.5 })
            .apply(&mut area, cornell::parts::SHORT_BLOCK);
        let mut both = area.clone();
        both.light = cornell::scene().light;
        vec![cornell::scene(), random, mixed, area, both]
    }

    #[target_feature(enable = "avx2")]
    fn in_lanes(scene: &Scene, max_depth: u32, starts: &[Start]) -> (Vec<(usize, Vec3A)>, u64) {
        let mut queue = starts.iter().cloned();
        let mut values = Vec::new();
        let rays = trace(scene, max_depth, &mut || queue.next(), &mut |tag, v| {
            values.push((tag, v))
        });
        (values, rays)
    }

    /// Every path traced in lanes has the value of the same path traced alone
    /// (`path::radiance_from` with the same sampler), bit for bit, and the
    /// lanes cast as many rays: one- and two-sided scenes, diffuse surfaces,
    /// mirrors, glass and emitting triangles, point lights inside, outside and
    /// on a surface, with area lights and without, a key light of no power,
    /// camera rays that miss, and paths cut at every depth.
    #[test]
    fn paths_in_lanes_match_paths_one_by_one() {
        if !std::arch::is_x86_feature_detected!("avx2") {
            return;
        }
        let mut rng = Rng::new(11, 0);
        let (mut compared, mut lit, mut long) = (0, 0, 0);
        for (k, mut scene) in scenes().into_iter().enumerate() {
            for (round, max_depth) in [u32::MAX, 1, 2, 3, 6, u32::MAX].into_iter().enumerate() {
                let mut r = || rng.next_f32();
                let (lo, hi) = scene.bounds();
                scene.light.position = match round {
                    0 => scene.light.position,
                    // On the ceiling or on the wall: shadow rays must stop
                    // short of the surface the light lies on.
                    3 if k == 0 => Vec3A::new(0.1, lo.y, 0.05),
                    3 => Vec3A::new(0.1, -0.2, hi.z),
                    4 => Vec3A::new(0.0, 0.0, -9.0),
                    _ => Vec3A::new(r(), r(), r()) * 1.6 - 0.8,
                };
                scene.light.power = if round == 5 || (k == 3 && round != 2) {
                    Vec3A::ZERO
                } else {
                    Vec3A::new(3.0, 4.0, 5.0)
                };
                assert!(scene.path_lanes_apply());
                let starts: Vec<Start> = (0..1500)
                    .map(|tag| {
                        let mut sampler = SobolSampler::new(tag as u64, round as u32, 7 + k as u64);
                        let _camera = sampler.next_2d();
                        let origin = lo + (hi - lo) * (Vec3A::new(r(), r(), r()) * 0.9 + 0.05);
                        let dir = (Vec3A::new(r(), r(), r()) * 2.0 - 1.0).normalize();
                        let ray = Ray::new(origin, dir);
                        Start {
                            tag,
                            sampler,
                            ray,
                            hit: scene.intersect(&ray, f32::INFINITY),
                        }
                    })
                    .collect();
                // SAFETY: the CPU has AVX2.
                let (mut got, rays) = unsafe { in_lanes(&scene, max_depth, &starts) };
                got.sort_by_key(|g| g.0);
                assert_eq!(got.len(), starts.len());
                let options = PathOptions {
                    max_depth,
                    sampler: SamplerKind::Sobol,
                    filter: crate::sampling::filter::PixelFilter::Box,
                    ..PathOptions::default()
                };
                let mut want_rays = 0;
                for (start, (got_tag, v)) in starts.iter().zip(&got) {
                    let Start {
                        tag,
                        sampler,
                        ray,
                        hit,
                    } = start;
                    assert_eq!(tag, got_tag);
                    let mut sampler = sampler.clone();
                    let before = want_rays;
                    let want = path::radiance_from(
                        &scene,
                        ray,
                        *hit,
                        &options,
                        &mut sampler,
                        &mut want_rays,
                    );
                    let bits = |v: Vec3A| v.to_array().map(f32::to_bits);
                    assert_eq!(bits(*v), bits(want), "scene {k}, round {round}, path {tag}");
                    compared += 1;
                    lit += usize::from(want != Vec3A::ZERO);
                    long += usize::from(want_rays - before > 6);
                }
                assert_eq!(rays, want_rays, "scene {k}, round {round}");
            }
        }
        assert!(
            compared == 45_000 && lit > 12_000 && long > 3000,
            "{compared} compared, {lit} lit, {long} long"
        );
    }
}
