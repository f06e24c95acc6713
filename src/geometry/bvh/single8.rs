//! Eight single-ray queries whose per-ray constants are made together in AVX2
//! lanes: for rays that are already in lanes (the path tracer's bounce and
//! shadow rays, `integrators::path::lanes`) but too incoherent to share a packet.
//!
//! A single ray's set-up (the finiteness check, the slab test's inverse
//! direction and plane rows, the triangle test's axis order and shear) was
//! about a fifth of a bounce ray's instructions in the lab box, done in
//! scalar and SSE code one ray at a time. Here it is done for eight rays at
//! once with the same operations, so each lane's constants are those of
//! [`BoxQuery::new`] and [`PacketRay::new`] bit for bit, and each ray is then
//! traced by the same traversal as [`Bvh::intersect`] and [`Bvh::occluded`]:
//! the answers are the same.

#![cfg(target_arch = "x86_64")]

use std::arch::x86_64::*;

use glam::{Vec3A, Vec4};

use super::node::{BoxQuery, EXIT_SCALE, Isa};
use super::packet::PacketRay;
use super::tree::Bvh;
use crate::geometry::ray::{Hit, Ray};
use crate::geometry::triangle::{Lanes, axis_order_of};
use crate::simd::F8;

/// The per-ray constants of eight rays, lane `i` ray `i`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Singles8 {
    /// The lanes whose ray has only finite coordinates, one bit each.
    finite: u32,
    origin: [[f32; 8]; 3],
    dir: [[f32; 8]; 3],
    /// [`BoxQuery`]'s inverse directions.
    inv_near: [[f32; 8]; 3],
    inv_far: [[f32; 8]; 3],
    /// The inverse direction's sign bits (bit `a`: negative along axis `a`).
    negative: [u32; 8],
    /// The axis order's key, `2·kz + (dir[kz] < 0)`.
    key: [u32; 8],
    /// [`PacketRay`]'s shear: `dir[kx]/dir[kz]`, `dir[ky]/dir[kz]`, `1/dir[kz]`.
    shear: [[f32; 8]; 3],
}

impl Singles8 {
    /// The constants of the rays from `origin` along `dir`, lane by lane.
    #[target_feature(enable = "avx2")]
    #[inline]
    pub(crate) fn new(origin: &[F8; 3], dir: &[F8; 3]) -> Self {
        // (No closures: they are compiled without AVX2; see `crate::simd`.)
        let zero = F8::zero();
        let one = F8::splat(1.0);
        let [dx, dy, dz] = *dir;
        // `is_finite_ray`: `x · 0` is 0 for finite `x`, NaN otherwise.
        let finite = (origin[0] * zero + dx * zero).cmpeq(zero)
            & (origin[1] * zero + dy * zero).cmpeq(zero)
            & (origin[2] * zero + dz * zero).cmpeq(zero);
        // `node::safe_inverse`: components below the smallest normal number
        // become it, with their sign; then `1 / d`.
        let tiny = F8::splat(f32::MIN_POSITIVE);
        let sign_bit = F8::splat(-0.0);
        macro_rules! safe_inverse {
            ($d:expr) => {
                one / F8::select($d.abs().cmplt(tiny), tiny | ($d & sign_bit), $d)
            };
        }
        let inv = [safe_inverse!(dx), safe_inverse!(dy), safe_inverse!(dz)];
        let exit = F8::splat(EXIT_SCALE);
        // The inverses' sign bits (−0 counts as negative), as a number.
        let negative = or3(
            bits_of(inv[0].cmplt(zero), 1),
            bits_of(inv[1].cmplt(zero), 2),
            bits_of(inv[2].cmplt(zero), 4),
        );
        // `triangle::axis_key`: `kz` is the first axis whose magnitude is at
        // least the others'; the key adds the sign of `dir[kz]`.
        let (ax, ay, az) = (dx.abs(), dy.abs(), dz.abs());
        let kz0 = ay.cmple(ax) & az.cmple(ax);
        let kz1 = !kz0 & az.cmple(ay);
        let kz2 = !(kz0 | kz1);
        let n = (kz0 & dx.cmplt(zero)) | (kz1 & dy.cmplt(zero)) | (kz2 & dz.cmplt(zero));
        let key = or3(bits_of(kz1, 2), bits_of(kz2, 4), bits_of(n, 1));
        // `PacketRay::new`'s shear, with each key's `kx` and `ky`
        // (`triangle::ORDER_OF_KEY`).
        macro_rules! by_kz {
            ($if0:expr, $if1:expr, $if2:expr) => {
                F8::select(kz0, $if0, F8::select(kz1, $if1, $if2))
            };
        }
        let d_z = by_kz!(dx, dy, dz);
        let d_x = by_kz!(
            F8::select(n, dz, dy),
            F8::select(n, dx, dz),
            F8::select(n, dy, dx)
        );
        let d_y = by_kz!(
            F8::select(n, dy, dz),
            F8::select(n, dz, dx),
            F8::select(n, dx, dy)
        );
        let inv_z = one / d_z;
        Self {
            finite: finite.bitmask(),
            origin: [
                origin[0].to_array(),
                origin[1].to_array(),
                origin[2].to_array(),
            ],
            dir: [dx.to_array(), dy.to_array(), dz.to_array()],
            inv_near: [inv[0].to_array(), inv[1].to_array(), inv[2].to_array()],
            inv_far: [
                (inv[0] * exit).to_array(),
                (inv[1] * exit).to_array(),
                (inv[2] * exit).to_array(),
            ],
            negative: ints(negative),
            key: ints(key),
            shear: [
                (d_x * inv_z).to_array(),
                (d_y * inv_z).to_array(),
                inv_z.to_array(),
            ],
        }
    }

    /// Ray `i`.
    #[inline(always)]
    fn ray(&self, i: usize) -> Ray {
        let at = |v: &[[f32; 8]; 3]| Vec3A::new(v[0][i], v[1][i], v[2][i]);
        Ray::new(at(&self.origin), at(&self.dir))
    }

    /// Ray `i`'s [`BoxQuery`].
    #[inline(always)]
    fn boxes(&self, i: usize) -> BoxQuery {
        let at = |v: &[[f32; 8]; 3]| [v[0][i], v[1][i], v[2][i]];
        BoxQuery::from_parts(
            at(&self.origin),
            at(&self.inv_near),
            at(&self.inv_far),
            self.negative[i] as usize,
        )
    }

    /// Ray `i`'s [`PacketRay`].
    #[inline(always)]
    fn packet_ray(&self, i: usize) -> PacketRay {
        let key = self.key[i] as usize;
        let k = axis_order_of(key / 2, key & 1 != 0);
        PacketRay::from_parts(
            k,
            [
                Vec4::splat(self.origin[k[0]][i]),
                Vec4::splat(self.origin[k[1]][i]),
                Vec4::splat(self.origin[k[2]][i]),
            ],
            [
                Vec4::splat(self.shear[0][i]),
                Vec4::splat(self.shear[1][i]),
                Vec4::splat(self.shear[2][i]),
            ],
            self.ray(i),
        )
    }
}

/// `bit` in the lanes where `mask` is set, 0 elsewhere, as integers.
#[inline(always)]
fn bits_of(mask: F8, bit: i32) -> __m256i {
    // SAFETY: AVX2, inside the AVX2 functions of this module only.
    unsafe { _mm256_and_si256(_mm256_castps_si256(mask.0), _mm256_set1_epi32(bit)) }
}

/// `a | b | c`, lane by lane.
#[inline(always)]
fn or3(a: __m256i, b: __m256i, c: __m256i) -> __m256i {
    // SAFETY: as `bits_of`.
    unsafe { _mm256_or_si256(_mm256_or_si256(a, b), c) }
}

/// The eight lanes of `v` as integers.
#[inline(always)]
fn ints(v: __m256i) -> [u32; 8] {
    let mut out = [0u32; 8];
    // SAFETY: AVX2 (as above); `out` holds eight u32.
    unsafe { _mm256_storeu_si256(out.as_mut_ptr().cast(), v) };
    out
}

impl Bvh {
    /// [`Bvh::intersect`] of ray `i` of `rays`: the same answer.
    #[target_feature(enable = "avx2")]
    #[inline(never)]
    pub(crate) fn intersect_single8(&self, rays: &Singles8, i: usize, t_max: f32) -> Option<Hit> {
        if self.isa != Isa::Avx2 {
            return self.intersect(&rays.ray(i), t_max);
        }
        let root = self.root?;
        if rays.finite >> i & 1 == 0 {
            return None;
        }
        self.closest_from(Isa::Avx2, root, &rays.boxes(i), &rays.packet_ray(i), t_max)
    }

    /// [`Bvh::occluded`] of ray `i` of `rays`: the same answer.
    #[target_feature(enable = "avx2")]
    #[inline(never)]
    pub(crate) fn occluded_single8(&self, rays: &Singles8, i: usize, t_max: f32) -> bool {
        if self.isa != Isa::Avx2 {
            return self.occluded(&rays.ray(i), t_max);
        }
        let Some(root) = self.root else {
            return false;
        };
        if rays.finite >> i & 1 == 0 {
            return false;
        }
        self.occluded_from(Isa::Avx2, root, &rays.boxes(i), t_max, || {
            rays.packet_ray(i)
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::triangle::Triangle;
    use crate::sampling::sampler::Rng;

    /// Directions that stress the set-up: axis-parallel (with +0 and −0
    /// components), components below the smallest normal number, exact ties
    /// between the largest magnitudes, and NaN or infinite coordinates.
    fn special_direction(rng: &mut Rng, case: usize) -> Vec3A {
        let mut c = || rng.next_f32() - 0.5;
        match case % 12 {
            0 => Vec3A::new(0.0, 0.0, if c() < 0.0 { -1.0 } else { 1.0 }),
            1 => Vec3A::new(-0.0, c(), 0.0),
            2 => Vec3A::new(1e-39, -1e-40, c()),
            3 => {
                let a = c();
                Vec3A::new(a, -a, c() * 0.5)
            }
            4 => {
                let a = c();
                Vec3A::new(a, a, a)
            }
            5 => Vec3A::new(c(), -0.0, -c().abs()),
            6 => Vec3A::new(f32::NAN, c(), c()),
            7 => Vec3A::new(c(), f32::INFINITY, c()),
            _ => Vec3A::new(c(), c(), c()),
        }
    }

    /// Eight rays at a time, from inside and around a soup of triangles (and
    /// from a NaN or infinite origin now and then): each lane's closest hit and
    /// any-hit answer (with several `t_max`) are those of `Bvh::intersect` and
    /// `Bvh::occluded` for the same ray, bit for bit.
    #[test]
    fn lanes_answer_as_single_rays() {
        if Isa::detect() != Isa::Avx2 {
            return;
        }
        let mut rng = Rng::new(8, 1);
        let p =
            |rng: &mut Rng| Vec3A::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 2.0 - 1.0;
        let tris: Vec<Triangle> = (0..3000)
            .map(|_| {
                let c = p(&mut rng);
                Triangle::new(c, c + 0.2 * p(&mut rng), c + 0.2 * p(&mut rng))
            })
            .collect();
        let bvh = Bvh::build(&tris);
        let (mut hits, mut blocked, mut case) = (0, 0, 0);
        for round in 0..4000 {
            let mut origin = [[0.0f32; 8]; 3];
            let mut dir = [[0.0f32; 8]; 3];
            for i in 0..8 {
                let mut o = p(&mut rng) * 1.5;
                if round % 97 == 0 && i == 3 {
                    o.y = if round % 2 == 0 {
                        f32::NAN
                    } else {
                        f32::NEG_INFINITY
                    };
                }
                let d = special_direction(&mut rng, case);
                case += 1;
                for a in 0..3 {
                    origin[a][i] = o[a];
                    dir[a][i] = d[a];
                }
            }
            // SAFETY: AVX2 was detected above.
            let rays = unsafe {
                let lanes = |v: &[[f32; 8]; 3]| {
                    [
                        F8::from_array(v[0]),
                        F8::from_array(v[1]),
                        F8::from_array(v[2]),
                    ]
                };
                Singles8::new(&lanes(&origin), &lanes(&dir))
            };
            for i in 0..8 {
                let ray = rays.ray(i);
                let t_max = [f32::INFINITY, 0.3, 1.7][i % 3];
                let one = bvh.intersect(&ray, t_max);
                // SAFETY: as above.
                let lane = unsafe { bvh.intersect_single8(&rays, i, t_max) };
                let bits = |h: Option<Hit>| {
                    h.map(|h| (h.t.to_bits(), h.prim, h.b1.to_bits(), h.b2.to_bits()))
                };
                assert_eq!(bits(lane), bits(one), "{ray:?}");
                hits += usize::from(one.is_some());
                let any = bvh.occluded(&ray, t_max);
                // SAFETY: as above.
                assert_eq!(
                    unsafe { bvh.occluded_single8(&rays, i, t_max) },
                    any,
                    "{ray:?}"
                );
                blocked += usize::from(any);
            }
        }
        // Both answers occur often.
        assert!(
            hits > 4000 && blocked > 4000 && hits < 28_000,
            "{hits} {blocked}"
        );
    }
}
