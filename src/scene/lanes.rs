//! The scene's answers for eight rays and their hits in the lanes of AVX2
//! registers, for the lab's 4×2 pixel blocks (`crate::integrators::direct::lanes`):
//! the rays traced, the hits' surface points and base colours, bit for bit
//! what the scalar functions give lane by lane. Everything here runs only
//! inside functions compiled with AVX2.

#![cfg(target_arch = "x86_64")]

use std::arch::x86_64::*;
use std::mem::{offset_of, size_of};

use super::model::Scene;
use crate::geometry::bvh::Singles8;
use crate::geometry::packet::{Closest8, Rays8};
use crate::geometry::ray::{Hit, Ray, gamma};
use crate::geometry::triangle::{Lanes, Triangle};
use crate::materials::surface::{MaterialKind, SurfaceMaterial};
use crate::simd::F8;

/// Eight surface points by axis: the points, their front normals (turned
/// towards the rays in two-sided scenes) and the points' error bounds, as
/// `SurfacePoint::on_triangle` and `Scene::surface_point` make them.
pub(crate) struct Points8 {
    /// The points.
    pub(crate) p: [F8; 3],
    /// Unit normals on the side the light is reflected from.
    pub(crate) n: [F8; 3],
    /// Absolute error bounds of the points' coordinates.
    pub(crate) error: [F8; 3],
}

impl Scene {
    /// Whether the lab's blocks can be shaded in lanes: no alpha masks (the
    /// packets would pass through them), no analytic shapes (the packets
    /// hold triangles), every material's base colour its
    /// fixed reflectance (no textures), and the gathers' byte offsets within
    /// `i32`.
    pub(crate) fn lab_lanes_apply(&self) -> bool {
        let fits = |bytes: usize| i32::try_from(bytes).is_ok();
        !self.has_alpha
            && self.shapes.is_empty()
            && self
                .materials
                .iter()
                .all(|m| matches!(m.kind, MaterialKind::Fixed(_)))
            && fits(self.triangles.len() * size_of::<Triangle>())
            && fits(self.normals.len() * size_of::<glam::Vec3A>())
            && fits(self.materials.len() * size_of::<SurfaceMaterial>())
    }

    /// Whether `path` can shade eight paths in lanes
    /// (`crate::integrators::path::lanes`): the conditions of
    /// [`Scene::lab_lanes_apply`]; every material a fixed Lambertian reflector
    /// (whose BSDF reflectance is its base colour), mirror or glass, without an
    /// emission texture; flat shading (no mesh has vertex normals); a black
    /// environment; no punctual light but the key light (the others are
    /// chosen by where they shine, which the lanes do not weigh); and no
    /// participating medium.
    pub(crate) fn path_lanes_apply(&self) -> bool {
        use crate::materials::Material;
        let bits = |v: glam::Vec3A| v.to_array().map(f32::to_bits);
        self.lab_lanes_apply()
            && self.materials.iter().all(|m| {
                m.emission_texture.is_none()
                    && match m.kind {
                        MaterialKind::Fixed(Material::Diffuse { reflectance }) => {
                            bits(reflectance) == bits(m.reflectance)
                        }
                        MaterialKind::Fixed(
                            Material::Mirror { .. } | Material::Dielectric { .. },
                        ) => true,
                        _ => false,
                    }
            })
            && self.meshes.iter().all(|m| m.normals.is_empty())
            && self.environment.is_black()
            && self.lights.is_empty()
            && self.media.is_empty()
    }

    /// [`Scene::intersect8`] of rays in lanes, answered in lanes; `None` when
    /// they cannot be traced as one packet (trace them as `[Ray; 8]`). Only
    /// for scenes where [`Scene::lab_lanes_apply`].
    #[target_feature(enable = "avx2")]
    #[inline]
    pub(crate) fn intersect8_lanes(&self, rays: &Rays8) -> Option<Closest8> {
        debug_assert!(!self.has_alpha);
        self.bvh.intersect8_lanes(rays, f32::INFINITY)
    }

    /// [`Scene::intersect`] of ray `i` of `rays` (whose per-ray constants were
    /// made in lanes): the same answer. Only for scenes without alpha masks
    /// (where [`Scene::lab_lanes_apply`]).
    #[target_feature(enable = "avx2")]
    #[inline]
    pub(crate) fn intersect_single8(&self, rays: &Singles8, i: usize) -> Option<Hit> {
        debug_assert!(!self.has_alpha);
        self.bvh.intersect_single8(rays, i, f32::INFINITY)
    }

    /// [`Scene::occluded`] of ray `i` of `rays` within `t_max`: the same
    /// answer. Only for scenes without alpha masks.
    #[target_feature(enable = "avx2")]
    #[inline]
    pub(crate) fn occluded_single8(&self, rays: &Singles8, i: usize, t_max: f32) -> bool {
        debug_assert!(!self.has_alpha);
        self.bvh.occluded_single8(rays, i, t_max)
    }

    /// [`Scene::occluded8`] of rays in lanes: bit `i` set when lane `i` is
    /// `active` and blocked within its `t_max`. Only for scenes where
    /// [`Scene::lab_lanes_apply`].
    #[target_feature(enable = "avx2")]
    #[inline]
    pub(crate) fn occluded8_lanes(&self, rays: &Rays8, t_max: F8, active: u32) -> u32 {
        debug_assert!(!self.has_alpha);
        if let Some(blocked) = self.bvh.occluded8_lanes(rays, t_max, active) {
            return blocked;
        }
        // Rays that cannot share a packet (rare): as `[Ray; 8]`.
        let (origin, dir) = (rays.origin.map(F8::to_array), rays.dir.map(F8::to_array));
        let at = |v: &[[f32; 8]; 3], i: usize| glam::Vec3A::new(v[0][i], v[1][i], v[2][i]);
        let rays = std::array::from_fn(|i| Ray::new(at(&origin, i), at(&dir, i)));
        let active = std::array::from_fn(|i| active >> i & 1 != 0);
        self.occluded8(&rays, t_max.to_array(), active)
            .iter()
            .enumerate()
            .fold(0, |bits, (i, &b)| bits | (b as u32) << i)
    }

    /// The surface points of the hits in `hits` (lanes without a hit get
    /// triangle 0's, unused), for rays along `dir`; as
    /// [`Scene::surface_points4`], bit for bit. Needs a hit in some lane.
    #[target_feature(enable = "avx2")]
    #[inline]
    pub(crate) fn surface_points8(&self, hits: &Closest8, dir: &[F8; 3]) -> Points8 {
        let mut point = self.surface_points8_front(hits);
        if self.two_sided {
            let n = point.n;
            // `n.dot(dir) > 0`, in glam's order of the sums.
            let away = (n[0] * dir[0] + n[1] * dir[1] + n[2] * dir[2]).cmpgt(F8::zero());
            point.n = [
                F8::select(away, n[0].neg(), n[0]),
                F8::select(away, n[1].neg(), n[1]),
                F8::select(away, n[2].neg(), n[2]),
            ];
        }
        point
    }

    /// [`Scene::surface_points8`] with the triangles' front normals, as
    /// [`Scene::surface`] gives them (`SurfaceHit::ng`).
    #[target_feature(enable = "avx2")]
    #[inline]
    pub(crate) fn surface_points8_front(&self, hits: &Closest8) -> Points8 {
        assert!(hits.found != 0 && !self.triangles.is_empty());
        let prim = prim_lanes(hits);
        let triangles = self.triangles.as_ptr().cast::<u8>();
        let tri = mul_lanes(prim, size_of::<Triangle>());
        // (Macros, not closures: a closure is compiled without AVX2.)
        macro_rules! vertex {
            ($k:expr) => {{
                let at = offset_of!(Triangle, v) + $k * size_of::<glam::Vec3A>();
                [
                    gather(triangles, tri, at),
                    gather(triangles, tri, at + 4),
                    gather(triangles, tri, at + 8),
                ]
            }};
        }
        let (v0, v1, v2) = (vertex!(0), vertex!(1), vertex!(2));
        let (b1, b2) = (hits.b1, hits.b2);
        // `SurfacePoint::on_triangle`.
        let b0 = F8::splat(1.0) - b1 - b2;
        let a = [b0 * v0[0], b0 * v0[1], b0 * v0[2]];
        let b = [b1 * v1[0], b1 * v1[1], b1 * v1[2]];
        let c = [b2 * v2[0], b2 * v2[1], b2 * v2[2]];
        let p = [a[0] + b[0] + c[0], a[1] + b[1] + c[1], a[2] + b[2] + c[2]];
        let g = F8::splat(gamma(7));
        let error = [
            g * (a[0].abs() + b[0].abs() + c[0].abs()),
            g * (a[1].abs() + b[1].abs() + c[1].abs()),
            g * (a[2].abs() + b[2].abs() + c[2].abs()),
        ];
        let normals = self.normals.as_ptr().cast::<u8>();
        let at = mul_lanes(prim, size_of::<glam::Vec3A>());
        let n = [
            gather(normals, at, 0),
            gather(normals, at, 4),
            gather(normals, at, 8),
        ];
        Points8 { p, n, error }
    }

    /// The hits' base colours ([`Scene::base_color`]: a fixed material's
    /// reflectance), zero in lanes without a hit. Only for scenes where
    /// [`Scene::lab_lanes_apply`].
    #[target_feature(enable = "avx2")]
    #[inline]
    pub(crate) fn base_colors8(&self, hits: &Closest8) -> [F8; 3] {
        if hits.found == 0 {
            return [F8::zero(); 3];
        }
        let prim = prim_lanes(hits);
        // SAFETY: the lanes are triangle indices (or 0 where there is no hit,
        // and there are triangles, since some lane hit one), and every
        // triangle has a material.
        let material =
            unsafe { _mm256_i32gather_epi32::<4>(self.material_of.as_ptr().cast(), prim) };
        let materials = self.materials.as_ptr().cast::<u8>();
        let at = mul_lanes(material, size_of::<SurfaceMaterial>());
        let first = offset_of!(SurfaceMaterial, reflectance);
        let found = F8::mask_from_bits(hits.found);
        [
            found & gather(materials, at, first),
            found & gather(materials, at, first + 4),
            found & gather(materials, at, first + 8),
        ]
    }
}

/// The hits' triangle indices, 0 in lanes without a hit.
#[inline(always)]
fn prim_lanes(hits: &Closest8) -> __m256i {
    // SAFETY: only inside AVX2 code (see `crate::simd`).
    unsafe {
        let found = F8::mask_from_bits(hits.found);
        _mm256_castps_si256(_mm256_and_ps(hits.prim.0, found.0))
    }
}

/// `index × size` in each lane: byte offsets of array elements (the caller
/// checked that the array's length in bytes fits `i32`).
#[inline(always)]
fn mul_lanes(index: __m256i, size: usize) -> __m256i {
    // SAFETY: only inside AVX2 code.
    unsafe { _mm256_mullo_epi32(index, _mm256_set1_epi32(size as i32)) }
}

/// The f32 at byte `offset + at` from `base` in each lane.
#[inline(always)]
fn gather(base: *const u8, offset: __m256i, at: usize) -> F8 {
    // SAFETY: only inside AVX2 code; the callers' offsets point at f32 fields of
    // elements of the arrays `base` starts: triangle indices come from the
    // tree built over `triangles` (0 where there is no hit, and only when some
    // lane hit, so that there are triangles), `Scene::from_parts` checked that
    // `normals` and `material_of` are as long as `triangles` and that every
    // material index is in range.
    F8(unsafe { _mm256_i32gather_ps::<1>(base.add(at).cast(), offset) })
}
