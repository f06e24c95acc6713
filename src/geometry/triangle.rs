//! Triangles and the watertight ray–triangle test.
//!
//! We use the watertight test of Woop, Benthin and Wald (JCGT 2013) rather than
//! Möller–Trumbore: it costs about the same (no division until a hit is accepted),
//! but its edge functions are evaluated identically for the two triangles sharing an
//! edge, so a ray through a shared edge or vertex always hits at least one of them
//! (no cracks), and a ray parallel to a triangle or a zero-area triangle gives
//! `det == 0`, which is rejected before any division (no NaN). Möller–Trumbore
//! computes each triangle's barycentrics from its own edge vectors, so rounding can
//! let a ray slip between two neighbours.

#[cfg(target_arch = "x86_64")]
use std::arch::x86_64::{_mm256_andnot_ps, _mm256_set1_ps};
use std::ops::{Add, Div, Mul};

use glam::{Mat3A, Vec3A, Vec4};

use crate::geometry::ray::{Ray, gamma};
#[cfg(target_arch = "x86_64")]
use crate::simd::F8;

/// A triangle given by its three vertices, in the winding the scene defines.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Triangle {
    /// The vertices `v0, v1, v2`.
    pub v: [Vec3A; 3],
}

impl Triangle {
    /// A triangle from three vertices.
    pub fn new(v0: Vec3A, v1: Vec3A, v2: Vec3A) -> Self {
        Self { v: [v0, v1, v2] }
    }

    /// The lab's face normal `normalize(cross(v2 − v0, v1 − v0))`; zero for a
    /// degenerate triangle.
    pub fn lab_normal(&self) -> Vec3A {
        (self.v[2] - self.v[0])
            .cross(self.v[1] - self.v[0])
            .normalize_or_zero()
    }

    /// Whether rays can hit the triangle: its vertices are finite and its area
    /// (computed in f32) is not zero, so that it has a normal. The BVH leaves
    /// out the others, and [`crate::geometry::bvh::brute_force`] skips them too.
    pub fn can_be_hit(&self) -> bool {
        self.is_finite() && self.area() > 0.0
    }

    /// The triangle's area.
    pub fn area(&self) -> f32 {
        0.5 * (self.v[1] - self.v[0])
            .cross(self.v[2] - self.v[0])
            .length()
    }

    /// Componentwise minimum of the vertices.
    pub fn min(&self) -> Vec3A {
        self.v[0].min(self.v[1]).min(self.v[2])
    }

    /// Componentwise maximum of the vertices.
    pub fn max(&self) -> Vec3A {
        self.v[0].max(self.v[1]).max(self.v[2])
    }

    /// Whether all coordinates are finite.
    pub fn is_finite(&self) -> bool {
        self.v.iter().all(|v| v.is_finite())
    }
}

/// Per-ray constants of the watertight test: the ray's origin and the shear that
/// maps its direction onto +z after permuting axes so that the largest direction
/// component becomes z. The permutation and shear form one matrix, so that
/// transforming a vertex is a single SIMD matrix–vector product.
#[derive(Clone, Copy, Debug)]
pub struct RayShear {
    origin: Vec3A,
    /// Rows (as the columns of the transpose): `e_kx − sx·e_kz`, `e_ky − sy·e_kz`, `sz·e_kz`.
    shear: Mat3A,
}

impl RayShear {
    /// Precomputes the shear for `ray`.
    #[inline]
    pub fn new(ray: &Ray) -> Self {
        let [kx, ky, kz] = axis_order(ray.dir);
        let dz = ray.dir[kz];
        let sz = 1.0 / dz;
        let (sx, sy) = (ray.dir[kx] * sz, ray.dir[ky] * sz);
        let mut rows = [Vec3A::ZERO; 3];
        rows[0][kx] = 1.0;
        rows[0][kz] = -sx;
        rows[1][ky] = 1.0;
        rows[1][kz] = -sy;
        rows[2][kz] = sz;
        Self {
            origin: ray.origin,
            shear: Mat3A::from_cols(rows[0], rows[1], rows[2]).transpose(),
        }
    }
}

/// The watertight test's axis order for direction `dir`: `kz` is the axis of the
/// largest component, and `kx`, `ky` follow it, swapped when `dir[kz] < 0` to keep
/// the projected winding.
///
/// Branch-free (three comparisons and a table): with branches, and `dir[kz]`
/// a `match` in glam, it was a tenth of the box's `path`'s mispredicted
/// branches.
#[inline(always)]
pub fn axis_order(dir: Vec3A) -> [usize; 3] {
    ORDER_OF_KEY[axis_key(dir) as usize]
}

/// The axis order of every ray of a packet, if they all share one and all are
/// finite (`None` otherwise: such a packet is traced ray by ray). Each ray's
/// order comes from three comparisons and a 64-entry table, branch-free: with
/// branches this check was 13 % of a `direct` frame's instructions.
#[inline(always)]
pub fn shared_axis_order(rays: &[Ray]) -> Option<[usize; 3]> {
    let first = rays.first()?;
    let key = axis_key(first.dir);
    let mut same = true;
    // A non-finite coordinate times zero is NaN, which stays NaN in the sum.
    let mut sum = Vec3A::ZERO;
    for r in rays {
        same &= axis_key(r.dir) == key;
        sum += r.origin * 0.0 + r.dir * 0.0;
    }
    (same && sum == Vec3A::ZERO).then(|| ORDER_OF_KEY[key as usize])
}

/// [`axis_order`] as a number in `0..6`, `2·kz + (dir[kz] < 0)`: of the
/// comparisons `|x| ≥ |y|`, `|x| ≥ |z|`, `|y| ≥ |z|` and the three signs, looked
/// up in [`KEY_OF_BITS`].
#[inline(always)]
fn axis_key(dir: Vec3A) -> u8 {
    let a = dir.abs();
    let bits = u32::from(a.x >= a.y)
        | u32::from(a.x >= a.z) << 1
        | u32::from(a.y >= a.z) << 2
        | dir.cmplt(Vec3A::ZERO).bitmask() << 3;
    KEY_OF_BITS[bits as usize]
}

/// [`axis_key`] of the comparison and sign bits: `kz` is the first axis whose
/// magnitude is at least the others', and the sign is that of `dir[kz]`.
const KEY_OF_BITS: [u8; 64] = {
    let mut table = [0u8; 64];
    let mut bits = 0;
    while bits < 64 {
        let (x_ge_y, x_ge_z, y_ge_z) = (bits & 1 != 0, bits & 2 != 0, bits & 4 != 0);
        let kz = if x_ge_y && x_ge_z {
            0
        } else if y_ge_z {
            1
        } else {
            2
        };
        let negative = (bits >> (3 + kz)) & 1;
        table[bits] = (2 * kz + negative) as u8;
        bits += 1;
    }
    table
};

/// [`axis_order`] for the largest axis `kz` and the sign of `dir[kz]`.
#[inline(always)]
pub fn axis_order_of(kz: usize, negative: bool) -> [usize; 3] {
    ORDER_OF_KEY[2 * kz + usize::from(negative)]
}

/// The axis order of each [`axis_key`].
const ORDER_OF_KEY: [[usize; 3]; 6] = [
    [1, 2, 0],
    [2, 1, 0],
    [2, 0, 1],
    [0, 2, 1],
    [0, 1, 2],
    [1, 0, 2],
];

/// Componentwise minimum and maximum of all vertices.
pub fn bounds(triangles: &[Triangle]) -> (Vec3A, Vec3A) {
    triangles.iter().fold(
        (Vec3A::splat(f32::INFINITY), Vec3A::splat(f32::NEG_INFINITY)),
        |(lo, hi), t| (lo.min(t.min()), hi.max(t.max())),
    )
}

/// Numbers the error bound is computed on: `f32` for one ray, [`Vec4`] for four
/// lanes at once, with the same operations in the same order.
pub trait Lanes: Copy + Add<Output = Self> + Mul<Output = Self> + Div<Output = Self> {
    /// The value `x` in every lane.
    fn splat(x: f32) -> Self;
    /// Absolute value per lane.
    fn abs(self) -> Self;
    /// Maximum per lane.
    fn max(self, other: Self) -> Self;
}

impl Lanes for f32 {
    fn splat(x: f32) -> Self {
        x
    }
    fn abs(self) -> Self {
        f32::abs(self)
    }
    fn max(self, other: Self) -> Self {
        f32::max(self, other)
    }
}

impl Lanes for Vec4 {
    fn splat(x: f32) -> Self {
        Vec4::splat(x)
    }
    fn abs(self) -> Self {
        Vec4::abs(self)
    }
    fn max(self, other: Self) -> Self {
        Vec4::max(self, other)
    }
}

// SAFETY (of the `unsafe` block): as for every operation on `F8` (see
// `crate::simd`), which is only made and used inside AVX2 code.
#[cfg(target_arch = "x86_64")]
impl Lanes for F8 {
    #[inline(always)]
    fn splat(x: f32) -> Self {
        F8::splat(x)
    }
    #[inline(always)]
    fn abs(self) -> Self {
        F8(unsafe { _mm256_andnot_ps(_mm256_set1_ps(-0.0), self.0) })
    }
    /// As `Vec4::max` (SSE `maxps`): the second operand where either is NaN.
    #[inline(always)]
    fn max(self, other: Self) -> Self {
        self.max_(other)
    }
}

/// Bound on the rounding error of the watertight test's `t` (pbrt-v4 §6.8.4), from
/// the sheared vertices `a`, `b`, `c`, the edge functions `e` and `|det|`.
#[inline(always)]
pub fn t_error_bound<T: Lanes>(a: [T; 3], b: [T; 3], c: [T; 3], e: [T; 3], abs_det: T) -> T {
    let max3 = |i: usize| a[i].abs().max(b[i].abs()).max(c[i].abs());
    let (max_x, max_y, max_z) = (max3(0), max3(1), max3(2));
    let max_e = e[0].abs().max(e[1].abs()).max(e[2].abs());
    let g = |n| T::splat(gamma(n));
    let delta_z = g(3) * max_z;
    let delta_x = g(5) * (max_x + max_z);
    let delta_y = g(5) * (max_y + max_z);
    let delta_e = T::splat(2.0) * (g(2) * max_x * max_y + delta_y * max_x + delta_x * max_y);
    T::splat(3.0) * (g(3) * max_e * max_z + delta_e * max_z + delta_z * max_e) / abs_det
}

/// Where a ray meets a triangle: `t` and the barycentric weights of `v1`, `v2`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TriangleHit {
    /// Ray parameter.
    pub t: f32,
    /// Weight of `v1`.
    pub b1: f32,
    /// Weight of `v2`.
    pub b2: f32,
}

/// Intersects a ray (via its shear) with a triangle, accepting `t` in `(0, t_max]`.
///
/// Both faces are hit (no culling). Returns `None` for parallel rays, degenerate
/// triangles and NaN input. An infinite ray direction is the caller's to reject
/// (the scene queries do, once per ray). A hit is only reported when `t` is
/// provably positive given the rounding error of its computation (pbrt-v4 §6.8.4),
/// so a ray leaving a surface never hits that surface, or a surface meeting it at a
/// corner, at `t ≈ 0`.
#[inline]
pub fn intersect(s: &RayShear, v: &[Vec3A; 3], t_max: f32) -> Option<TriangleHit> {
    let a = s.shear * (v[0] - s.origin);
    let b = s.shear * (v[1] - s.origin);
    let c = s.shear * (v[2] - s.origin);
    let (ax, ay, az) = (a.x, a.y, a.z);
    let (bx, by, bz) = (b.x, b.y, b.z);
    let (cx, cy, cz) = (c.x, c.y, c.z);

    let mut u = cx * by - cy * bx;
    let mut w_v = ax * cy - ay * cx;
    let mut w = bx * ay - by * ax;
    // On an edge the f32 products can cancel to exactly zero; redo them in f64
    // so that the two triangles sharing that edge agree on its side.
    if u == 0.0 || w_v == 0.0 || w == 0.0 {
        let f = |p: f32, q: f32, r: f32, s: f32| (p as f64 * q as f64 - r as f64 * s as f64) as f32;
        u = f(cx, by, cy, bx);
        w_v = f(ax, cy, ay, cx);
        w = f(bx, ay, by, ax);
    }
    if (u < 0.0 || w_v < 0.0 || w < 0.0) && (u > 0.0 || w_v > 0.0 || w > 0.0) {
        return None;
    }
    let det = u + w_v + w;
    if det == 0.0 {
        return None;
    }
    let t_scaled = u * az + w_v * bz + w * cz;
    // Compare t = t_scaled / det against the interval without dividing; written so
    // that NaN fails the test.
    let (t_scaled, abs_det) = if det < 0.0 {
        (-t_scaled, -det)
    } else {
        (t_scaled, det)
    };
    if !(t_scaled > 0.0 && t_scaled <= t_max * abs_det) {
        return None;
    }
    let t = t_scaled / abs_det;
    // Reject t within its own error bound of zero (pbrt-v4's conservative test).
    let delta_t = t_error_bound(
        [ax, ay, az],
        [bx, by, bz],
        [cx, cy, cz],
        [u, w_v, w],
        abs_det,
    );
    // Written so that NaN fails, and a t that overflowed to infinity (a
    // denormal determinant in a triangle with coordinates near f32::MAX,
    // found by fuzzing) is no hit either; the packet tests do the same.
    // `t <= t_max` again after the division: the test above, made without
    // dividing, can pass a `t` that rounds to one ulp beyond `t_max`, and a
    // closest-hit search would then take a triangle one ulp behind the one
    // it has (found by fuzzing: brute force and the BVH disagreed).
    if !(t > delta_t && t <= f32::MAX && t <= t_max) {
        return None;
    }
    let inv = 1.0 / det;
    Some(TriangleHit {
        t,
        b1: w_v * inv,
        b2: w * inv,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn hit(ray: &Ray, tri: &Triangle) -> Option<TriangleHit> {
        intersect(&RayShear::new(ray), &tri.v, f32::INFINITY)
    }

    /// `axis_order` as it was written with branches.
    fn axis_order_by_branches(dir: Vec3A) -> [usize; 3] {
        let a = dir.abs();
        let kz = if a.x >= a.y && a.x >= a.z {
            0
        } else if a.y >= a.z {
            1
        } else {
            2
        };
        let (kx, ky) = ((kz + 1) % 3, (kz + 2) % 3);
        if dir[kz] < 0.0 {
            [ky, kx, kz]
        } else {
            [kx, ky, kz]
        }
    }

    /// The table's order is the branches' for every direction, ties, zeros of
    /// both signs and infinities included, and a packet shares it exactly when
    /// all its rays have it and are finite.
    #[test]
    fn shared_axis_order_is_axis_order() {
        let values = [
            0.0f32,
            -0.0,
            1.0,
            -1.0,
            0.5,
            -0.5,
            2.0,
            -2.0,
            1e-30,
            f32::INFINITY,
        ];
        let mut dirs = Vec::new();
        for &x in &values {
            for &y in &values {
                for &z in &values {
                    dirs.push(Vec3A::new(x, y, z));
                }
            }
        }
        let mut rng = crate::sampling::sampler::Rng::new(3, 4);
        for _ in 0..20_000 {
            dirs.push(Vec3A::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) - 0.5);
        }
        let o = Vec3A::new(0.25, -1.0, 3.0);
        for (i, &d) in dirs.iter().enumerate() {
            let one = [Ray::new(o, d)];
            assert_eq!(axis_order(d), axis_order_by_branches(d), "{d:?}");
            let want = d.is_finite().then(|| axis_order(d));
            assert_eq!(shared_axis_order(&one), want, "{d:?}");
            // Paired with another direction: shared only if both orders agree.
            let e = dirs[(i * 7 + 3) % dirs.len()];
            let two = [Ray::new(o, d), Ray::new(o, e)];
            let want = (d.is_finite() && e.is_finite() && axis_order(d) == axis_order(e))
                .then(|| axis_order(d));
            assert_eq!(shared_axis_order(&two), want, "{d:?} {e:?}");
        }
        for bad in [f32::NAN, f32::INFINITY, -f32::INFINITY] {
            let rays = [
                Ray::new(o, Vec3A::X),
                Ray::new(Vec3A::new(0.0, bad, 0.0), Vec3A::X),
            ];
            assert_eq!(shared_axis_order(&rays), None);
        }
    }

    fn unit() -> Triangle {
        Triangle::new(
            Vec3A::new(0.0, 0.0, 1.0),
            Vec3A::new(1.0, 0.0, 1.0),
            Vec3A::new(0.0, 1.0, 1.0),
        )
    }

    /// Found by fuzzing: a triangle spanning -1.7e38 with denormal coordinates
    /// and a ray with a denormal direction component gave a "hit" at t = NaN
    /// (∞/∞); the 4- and 8-wide tests already said no.
    #[test]
    fn overflowing_triangles_give_no_hit_rather_than_a_nan_one() {
        let f = |bits: [u32; 3]| Vec3A::from_array(bits.map(f32::from_bits));
        let tri = Triangle::new(
            f([0x0, 0xff00_008b, 0xff]),
            f([0x0, 0x4000, 0xc000_0000]),
            f([0x4000_0000, 0x0, 0x4000]),
        );
        let ray = Ray::new(f([0, 0, 0x4080_0000]), f([0x1, 0x0, 0xbf80_0000]));
        for t_max in [f32::INFINITY, 10.0] {
            if let Some(h) = intersect(&RayShear::new(&ray), &tri.v, t_max) {
                assert!(h.t.is_finite() && h.t > 0.0, "{h:?}");
            }
        }
    }

    #[test]
    fn hits_with_exact_t_and_barycentrics() {
        let ray = Ray::new(Vec3A::new(0.25, 0.5, -1.0), Vec3A::Z);
        let h = hit(&ray, &unit()).expect("hit");
        assert!((h.t - 2.0).abs() < 1e-6);
        assert!((h.b1 - 0.25).abs() < 1e-6);
        assert!((h.b2 - 0.5).abs() < 1e-6);
        // Both faces are hit: the same ray from the other side.
        let back = Ray::new(Vec3A::new(0.25, 0.5, 3.0), -Vec3A::Z);
        assert!((hit(&back, &unit()).unwrap().t - 2.0).abs() < 1e-6);
    }

    #[test]
    fn misses_outside_behind_and_beyond_t_max() {
        let outside = Ray::new(Vec3A::new(0.75, 0.75, 0.0), Vec3A::Z);
        assert!(hit(&outside, &unit()).is_none());
        let behind = Ray::new(Vec3A::new(0.25, 0.25, 2.0), Vec3A::Z);
        assert!(hit(&behind, &unit()).is_none());
        let ray = Ray::new(Vec3A::new(0.25, 0.25, 0.0), Vec3A::Z);
        let s = RayShear::new(&ray);
        assert!(intersect(&s, &unit().v, 0.999).is_none());
        assert!(intersect(&s, &unit().v, 1.0).is_some());
        // A ray starting on the triangle does not hit it.
        let on = Ray::new(Vec3A::new(0.25, 0.25, 1.0), Vec3A::new(0.3, 0.1, 1.0));
        assert!(hit(&on, &unit()).is_none());
    }

    #[test]
    fn parallel_rays_and_degenerate_triangles_never_hit() {
        let parallel = Ray::new(Vec3A::new(-1.0, 0.25, 1.0), Vec3A::X);
        assert!(hit(&parallel, &unit()).is_none());
        let parallel_off = Ray::new(Vec3A::new(-1.0, 0.25, 0.5), Vec3A::X);
        assert!(hit(&parallel_off, &unit()).is_none());
        let p = Vec3A::new(0.2, 0.2, 1.0);
        let point = Triangle::new(p, p, p);
        let line = Triangle::new(
            Vec3A::new(0.0, 0.0, 1.0),
            Vec3A::new(1.0, 1.0, 1.0),
            Vec3A::new(0.5, 0.5, 1.0),
        );
        for tri in [point, line] {
            for dir in [Vec3A::Z, Vec3A::new(0.1, 0.2, 1.0).normalize(), Vec3A::X] {
                let ray = Ray::new(Vec3A::new(0.2, 0.2, 0.0), dir);
                assert!(hit(&ray, &tri).is_none(), "{tri:?} {dir:?}");
            }
        }
    }

    #[test]
    fn non_finite_rays_give_no_hit() {
        for (o, d) in [
            (Vec3A::splat(f32::NAN), Vec3A::Z),
            (Vec3A::new(0.25, 0.25, 0.0), Vec3A::new(f32::NAN, 0.0, 1.0)),
            (Vec3A::new(f32::INFINITY, 0.25, 0.0), Vec3A::Z),
            (Vec3A::new(0.25, 0.25, 0.0), Vec3A::ZERO),
        ] {
            assert!(hit(&Ray::new(o, d), &unit()).is_none(), "{o:?} {d:?}");
        }
    }

    /// Rays aimed exactly at a shared edge or vertex of a fan of triangles must hit
    /// at least one of them, for many irregular fans and directions.
    #[test]
    fn shared_edges_and_vertices_have_no_cracks() {
        let mut rng = crate::sampling::sampler::Rng::new(7, 0);
        let mut tests = 0;
        for _ in 0..2000 {
            // A fan of triangles around a centre vertex, all in a tilted plane.
            let centre = Vec3A::new(rng.next_f32(), rng.next_f32(), 2.0 + rng.next_f32());
            let n = 5 + (rng.next_u32() % 4) as usize;
            let rim: Vec<Vec3A> = (0..n)
                .map(|i| {
                    let a = (i as f32 + 0.5 * rng.next_f32()) / n as f32 * std::f32::consts::TAU;
                    let r = 0.5 + rng.next_f32();
                    centre + Vec3A::new(r * a.cos(), r * a.sin(), 0.3 * r * a.cos())
                })
                .collect();
            let tris: Vec<Triangle> = (0..n)
                .map(|i| Triangle::new(centre, rim[i], rim[(i + 1) % n]))
                .collect();
            let origin = Vec3A::new(rng.next_f32() - 0.5, rng.next_f32() - 0.5, -rng.next_f32());
            // Aim at the centre vertex and at points exactly on each spoke.
            let mut targets = vec![centre];
            for r in &rim {
                let s = rng.next_f32();
                targets.push(centre + s * (*r - centre));
            }
            for target in targets {
                let ray = Ray::new(origin, target - origin);
                tests += 1;
                assert!(
                    tris.iter().any(|t| hit(&ray, t).is_some()),
                    "crack at {target:?} from {origin:?}"
                );
            }
        }
        assert!(tests > 10_000);
    }

    #[test]
    fn lab_normal_follows_the_lab_winding() {
        // cross(v2 - v0, v1 - v0) for the unit triangle is (0,1,0) x (1,0,0) = -z.
        assert_eq!(unit().lab_normal(), -Vec3A::Z);
        let p = Vec3A::ONE;
        assert_eq!(Triangle::new(p, p, p).lab_normal(), Vec3A::ZERO);
    }
}
