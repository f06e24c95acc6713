//! Eight coherent rays traced together in the lanes of AVX2 registers: the
//! eight-wide counterpart of `ray4` for CPUs with AVX2 (a 4×2 pixel block and its
//! shadow rays). Per node each hit child's box is tested for all eight rays at
//! once, per leaf each triangle, so a coherent packet pays for its nodes and
//! triangles once instead of eight times.
//!
//! The per-lane arithmetic is the scalar watertight test's, operation for
//! operation (no FMA), so hits agree bit for bit with [`Bvh::intersect`]; only
//! which of two triangles at exactly the same `t` is reported may differ.
//!
//! The lane type is [`F8`] (`crate::simd`), used only inside the
//! `#[target_feature(enable = "avx2")]` entry points below.

#![cfg(target_arch = "x86_64")]

use std::arch::x86_64::*;

use super::node::{ChildRef, EMPTY, Isa, LEAF, WIDTH};
use super::packet::{Packet, PacketRay};
use super::tree::Bvh;
use super::walk::Stack;
use crate::geometry::packet::{Closest8, Rays8};
use crate::geometry::ray::{Hit, Ray, gamma};
use crate::geometry::triangle::{self, Lanes, RayShear, TriangleHit, axis_order_of, t_error_bound};
use crate::simd::F8;

/// Per-packet constants: origins and safe inverse directions by axis, and the
/// triangle test's shared axis order with per-lane origins and shears.
struct Query8 {
    rays: Rays8,
    inv_dir: [F8; 3],
    k: [usize; 3],
    origin_k: [F8; 3],
    shear: [F8; 3],
}

impl Query8 {
    /// [`Query8::from_lanes`] of the rays as the lanes of one transpose
    /// ([`transpose`]).
    #[inline(always)]
    fn new(rays: &[Ray; 8]) -> Option<Self> {
        let (origin, dir) = transpose(rays);
        Self::from_lanes(Rays8 { origin, dir })
    }

    /// The packet's constants, or `None` when the rays cannot be traced
    /// together: one is not finite, or they do not share the triangle test's
    /// axis order ([`axis_order`], decided here in the lanes: ray by ray it was
    /// 13 % of a `direct` frame's instructions). Called inside the AVX2
    /// functions only.
    #[inline(always)]
    fn from_lanes(rays: Rays8) -> Option<Self> {
        let Rays8 { origin, dir } = rays;
        // `safe_inverse` lane by lane: zeros made the smallest normal number
        // of their sign, then the division.
        let inv_dir = [
            safe_inverse8(dir[0]),
            safe_inverse8(dir[1]),
            safe_inverse8(dir[2]),
        ];
        // A non-finite coordinate times zero is NaN, which stays NaN.
        let zero = F8::zero();
        let mut sum = zero;
        for a in 0..3 {
            sum = sum + origin[a] * zero + dir[a] * zero;
        }
        // `axis_order` lane by lane: the largest axis (ties to the first) and
        // the sign along it, which must be the same in every lane.
        let [ax, ay, az] = [Lanes::abs(dir[0]), Lanes::abs(dir[1]), Lanes::abs(dir[2])];
        let x_largest = ay.cmple(ax) & az.cmple(ax);
        let y_largest = !x_largest & az.cmple(ay);
        let along = F8::select(x_largest, dir[0], F8::select(y_largest, dir[1], dir[2]));
        let negative = along.cmplt(zero).bitmask();
        let (x_largest, y_largest) = (x_largest.bitmask(), y_largest.bitmask());
        let uniform = |bits: u32| bits == 0 || bits == 0xff;
        if sum.cmpeq(zero).bitmask() != 0xff
            || !uniform(x_largest)
            || !uniform(y_largest)
            || !uniform(negative)
        {
            return None;
        }
        let kz = if x_largest != 0 {
            0
        } else if y_largest != 0 {
            1
        } else {
            2
        };
        let k = axis_order_of(kz, negative != 0);
        let inv_z = F8::splat(1.0) / dir[k[2]];
        Some(Self {
            rays,
            inv_dir,
            k,
            origin_k: [origin[k[0]], origin[k[1]], origin[k[2]]],
            shear: [dir[k[0]] * inv_z, dir[k[1]] * inv_z, inv_z],
        })
    }

    /// Whether every ray starts at the first one's origin.
    #[inline(always)]
    fn one_origin(&self) -> bool {
        let origin = &self.rays.origin;
        let same = origin[0].cmpeq(origin[0].broadcast_first())
            & origin[1].cmpeq(origin[1].broadcast_first())
            & origin[2].cmpeq(origin[2].broadcast_first());
        same.bitmask() == 0xff
    }

    /// Whether the rays' directions share their signs on every axis (one
    /// octant): only then does the interval test of a packet from one point
    /// bound anything on an axis. Across a sign change its inverse
    /// directions span both infinities, the axis culls nothing, and a packet
    /// straddling two axes visits nearly every node it can see (measured: a
    /// row of three tessellated spheres seen side on, 71 % of a render in
    /// that test at 0.3 Mrays/s).
    #[inline(always)]
    fn one_octant(&self) -> bool {
        (0..3).all(|a| {
            let inv = &self.inv_dir[a];
            inv.min_element().is_sign_negative() == inv.max_element().is_sign_negative()
        })
    }

    /// Entry and exit distances of the slab of axis `a` of child `c`.
    #[inline(always)]
    fn slab(&self, bounds: &[[f32; WIDTH]; 6], c: usize, a: usize) -> (F8, F8) {
        let t0 = (F8::splat(bounds[a][c]) - self.rays.origin[a]) * self.inv_dir[a];
        let t1 = (F8::splat(bounds[a + 3][c]) - self.rays.origin[a]) * self.inv_dir[a];
        (t0.min(t1), t0.max_(t1))
    }

    /// Slab test of child `c` for the eight rays: entry distances and the lanes
    /// that hit within `[0, t_max]` (as `ray4`'s test, lane by lane).
    #[inline(always)]
    fn hit_box(&self, bounds: &[[f32; WIDTH]; 6], c: usize, t_max: F8) -> (F8, F8) {
        let (nx, fx) = self.slab(bounds, c, 0);
        let (ny, fy) = self.slab(bounds, c, 1);
        let (nz, fz) = self.slab(bounds, c, 2);
        let near = nx.max_(ny).max_(nz).max_(F8::zero());
        let far = fx.min(fy).min(fz) * F8::splat(1.0 + 2.0 * gamma(3));
        (near, near.cmple(far.min(t_max)))
    }
}

/// `safe_inverse` lane by lane: zeros made the smallest normal number of their
/// sign, then the division. (A function, not a closure: closures do not
/// inherit the caller's AVX2, and their intrinsics were left as calls.)
#[inline(always)]
fn safe_inverse8(d: F8) -> F8 {
    let tiny = F8::splat(f32::MIN_POSITIVE);
    let small = Lanes::abs(d).cmplt(tiny);
    let signed_tiny = (F8::splat(-0.0) & d) | tiny;
    F8::splat(1.0) / F8::select(small, signed_tiny, d)
}

/// The eight rays' origins and directions, lane by lane: an 8×8 transpose
/// of the rays as loaded (origin and direction in one register each), where
/// storing the 48 coordinates one by one and loading them back took a fifth
/// of a packet query on the lab box.
#[inline(always)]
fn transpose(rays: &[Ray; 8]) -> ([F8; 3], [F8; 3]) {
    // SAFETY: only called inside functions compiled with AVX2 (see `F8`).
    unsafe {
        // (Macros, not closures: see `safe_inverse8`.)
        macro_rules! row {
            ($i:expr) => {
                _mm256_set_m128(rays[$i].dir.into(), rays[$i].origin.into())
            };
        }
        let (r0, r1, r2, r3) = (row!(0), row!(1), row!(2), row!(3));
        let (r4, r5, r6, r7) = (row!(4), row!(5), row!(6), row!(7));
        // [x_i x_j y_i y_j | ...] and [z_i z_j w_i w_j | ...] of ray pairs.
        let (t0, t1) = (_mm256_unpacklo_ps(r0, r1), _mm256_unpackhi_ps(r0, r1));
        let (t2, t3) = (_mm256_unpacklo_ps(r2, r3), _mm256_unpackhi_ps(r2, r3));
        let (t4, t5) = (_mm256_unpacklo_ps(r4, r5), _mm256_unpackhi_ps(r4, r5));
        let (t6, t7) = (_mm256_unpacklo_ps(r6, r7), _mm256_unpackhi_ps(r6, r7));
        // One axis of four rays: origins in the low half, directions in the high.
        let x03 = _mm256_shuffle_ps::<0x44>(t0, t2);
        let y03 = _mm256_shuffle_ps::<0xee>(t0, t2);
        let z03 = _mm256_shuffle_ps::<0x44>(t1, t3);
        let x47 = _mm256_shuffle_ps::<0x44>(t4, t6);
        let y47 = _mm256_shuffle_ps::<0xee>(t4, t6);
        let z47 = _mm256_shuffle_ps::<0x44>(t5, t7);
        (
            [
                F8(_mm256_permute2f128_ps::<0x20>(x03, x47)),
                F8(_mm256_permute2f128_ps::<0x20>(y03, y47)),
                F8(_mm256_permute2f128_ps::<0x20>(z03, z47)),
            ],
            [
                F8(_mm256_permute2f128_ps::<0x31>(x03, x47)),
                F8(_mm256_permute2f128_ps::<0x31>(y03, y47)),
                F8(_mm256_permute2f128_ps::<0x31>(z03, z47)),
            ],
        )
    }
}

/// Hits of the eight rays on one triangle (or of one ray on eight): lanes, `t`
/// and barycentrics, and the undivided `t` and `|det|` that the test compared
/// against `t_max`.
struct Hits8 {
    valid: F8,
    t: F8,
    b1: F8,
    b2: F8,
    t_scaled: F8,
    abs_det: F8,
}

/// The watertight test of the eight rays against triangle `i` of `p`, as
/// `packet::candidates` does it lane by lane.
#[inline(always)]
fn test_triangle(q: &Query8, p: &Packet, i: usize, t_max: F8) -> Hits8 {
    let a = sheared(q, p, 0, i);
    let b = sheared(q, p, 1, i);
    let c = sheared(q, p, 2, i);
    match watertight8(a, b, c, t_max) {
        Ok(hits) => hits,
        Err(()) => scalar_lanes(q, p, i, t_max),
    }
}

/// The watertight test's arithmetic (that of `packet::candidates`, operation for
/// operation) on eight lanes, from each lane's triangle already in its ray's
/// sheared frame: eight rays against one triangle or one ray against eight.
/// `Err` when an edge function is exactly zero in some lane: that lane needs
/// the scalar test's f64 fallback.
#[inline(always)]
fn watertight8(
    (ax, ay, az): (F8, F8, F8),
    (bx, by, bz): (F8, F8, F8),
    (cx, cy, cz): (F8, F8, F8),
    t_max: F8,
) -> Result<Hits8, ()> {
    let u = cx * by - cy * bx;
    let v = ax * cy - ay * cx;
    let w = bx * ay - by * ax;
    let zero = F8::zero();
    if (u.cmpeq(zero) | v.cmpeq(zero) | w.cmpeq(zero)).any() {
        return Err(());
    }
    let any_neg = u.cmplt(zero) | v.cmplt(zero) | w.cmplt(zero);
    let any_pos = u.cmpgt(zero) | v.cmpgt(zero) | w.cmpgt(zero);
    let det = u + v + w;
    let t_scaled = (u * az + v * bz + w * cz) * det.signum();
    let abs_det = det.abs();
    let mut valid = !(any_neg & any_pos)
        & det.cmpne(zero)
        & t_scaled.cmpgt(zero)
        & t_scaled.cmple(t_max * abs_det);
    if !valid.any() {
        return Ok(Hits8 {
            valid,
            t: zero,
            b1: zero,
            b2: zero,
            t_scaled,
            abs_det,
        });
    }
    let t = t_scaled / abs_det;
    let delta_t = t_error_bound([ax, ay, az], [bx, by, bz], [cx, cy, cz], [u, v, w], abs_det);
    // And within `t_max` after the division, as the scalar test.
    valid = valid & t.cmpgt(delta_t) & t.cmple(F8::splat(f32::MAX)) & t.cmple(t_max);
    let inv = F8::splat(1.0) / det;
    Ok(Hits8 {
        valid,
        t,
        b1: v * inv,
        b2: w * inv,
        t_scaled,
        abs_det,
    })
}

/// Vertex `vertex` of the eight triangles of two packets (lanes 0–3 the first
/// packet's, 4–7 the second's) in the single ray's sheared frame, as
/// `packet::candidates` computes it per packet.
#[inline(always)]
fn pair_sheared(r: &PacketRay, pair: &[Packet], vertex: usize) -> (F8, F8, F8) {
    let [kx, ky, kz] = r.k;
    let row = |axis: usize| F8::halves(pair[0].v[vertex][axis], pair[1].v[vertex][axis]);
    let [sx, sy, sz] = r.shear.map(|s| F8::splat(s.x));
    let [ox, oy, oz] = r.origin.map(|o| F8::splat(o.x));
    let dx = row(kx) - ox;
    let dy = row(ky) - oy;
    let dz = row(kz) - oz;
    (dx - sx * dz, dy - sy * dz, sz * dz)
}

/// [`watertight8`] of one ray against the eight triangles of two packets.
#[inline(always)]
fn pair_hits(r: &PacketRay, pair: &[Packet], t_max: f32) -> Result<Hits8, ()> {
    watertight8(
        pair_sheared(r, pair, 0),
        pair_sheared(r, pair, 1),
        pair_sheared(r, pair, 2),
        F8::splat(t_max),
    )
}

/// One ray against the eight triangles of two packets in one AVX2 pass (only
/// inside AVX2 code), with the answer of the four-wide test run on the first
/// packet and then on the second with `t_max` cut to the first one's hit, bit
/// for bit (the same triangle at an exact tie too). Each lane computes what the
/// four-wide test computes for it; the cut is applied afterwards, to the second
/// packet's lanes. The closest hit within `(0, t_max]` as `(packet, lane,
/// hit)`. `Err` when an edge function is exactly zero somewhere: the caller
/// then tests the packets in turn, which have the f64 fallback.
#[inline(always)]
pub(super) fn pair_closest(
    r: &PacketRay,
    pair: &[Packet],
    t_max: f32,
) -> Result<Option<(usize, usize, TriangleHit)>, ()> {
    let hits = pair_hits(r, pair, t_max)?;
    let valid = hits.valid.bitmask();
    if valid == 0 {
        return Ok(None);
    }
    let t = F8::select(hits.valid, hits.t, F8::splat(f32::INFINITY));
    let first = valid & 0x0f;
    // The second packet's lanes that pass the four-wide test's two comparisons
    // with `t_max` cut to the first packet's closest hit.
    let cut = F8::splat(if first != 0 { t.min_lower() } else { t_max });
    let second =
        (hits.t_scaled.cmple(cut * hits.abs_det) & hits.t.cmple(cut)).bitmask() & valid & 0xf0;
    let lanes = if second != 0 { second } else { first };
    let t = F8::select(F8::mask_from_bits(lanes), t, F8::splat(f32::INFINITY));
    let lane = (t.cmpeq(F8::splat(t.min_element())).bitmask() & lanes).trailing_zeros() as usize;
    Ok(Some((
        lane / 4,
        lane % 4,
        TriangleHit {
            t: hits.t.lane(lane),
            b1: hits.b1.lane(lane),
            b2: hits.b2.lane(lane),
        },
    )))
}

/// Whether one ray hits any of the eight triangles of a two-packet leaf within
/// `(0, t_max]` (only inside AVX2 code); `Err` as for [`pair_closest`].
#[inline(always)]
pub(super) fn pair_occluded(r: &PacketRay, pair: &[Packet], t_max: f32) -> Result<bool, ()> {
    let hits = pair_hits(r, pair, t_max)?;
    Ok(hits.valid.any())
}

/// The closest-hit leaf loop of the eight-ray packets: tests every triangle of
/// leaf `cur` against the packet and keeps, per lane, the closest hit so far
/// (`best_t`, `b1`, `b2`, `prim` (indices as bit patterns, blended like the
/// rest: a loop over the lanes cost 1 % of the lab's frame), and the lanes hit
/// in `found`). A macro, not a function: shared through a helper (a struct of
/// the closest hits, by reference or by value) it cost 5 % more instructions
/// on the lab's frame.
macro_rules! closest_in_leaf {
    ($bvh:expr, $q:expr, $cur:expr, $best_t:ident, $b1:ident, $b2:ident, $prim:ident, $found:ident) => {
        for p in $bvh.leaf($cur) {
            for i in 0..p.len() {
                let hit = test_triangle($q, p, i, $best_t);
                let mask = hit.valid.bitmask();
                if mask != 0 {
                    $best_t = F8::select(hit.valid, hit.t, $best_t);
                    $b1 = F8::select(hit.valid, hit.b1, $b1);
                    $b2 = F8::select(hit.valid, hit.b2, $b2);
                    // The triangle's index as a bit pattern, blended like the rest.
                    $prim = F8::select(hit.valid, F8::splat(f32::from_bits(p.prim(i))), $prim);
                    $found |= mask;
                }
            }
        }
    };
}

/// Vertex `vertex` of triangle `i` of `p` in each ray's sheared frame (a
/// function, not a closure: closures were left as calls, outside the AVX2
/// code). Each coordinate is broadcast straight from the packet (one
/// `vbroadcastss`), not gathered into a vector first and picked out of it.
#[inline(always)]
fn sheared(q: &Query8, p: &Packet, vertex: usize, i: usize) -> (F8, F8, F8) {
    let [kx, ky, kz] = q.k;
    let [sx, sy, sz] = q.shear;
    let row = &p.v[vertex];
    let coordinate = |axis: usize| -> f32 {
        let lanes: &[f32; 4] = row[axis].as_ref();
        lanes[i]
    };
    let dx = F8::splat(coordinate(kx)) - q.origin_k[0];
    let dy = F8::splat(coordinate(ky)) - q.origin_k[1];
    let dz = F8::splat(coordinate(kz)) - q.origin_k[2];
    (dx - sx * dz, dy - sy * dz, sz * dz)
}

/// The scalar test lane by lane, for the rare exact-zero edge functions.
#[cold]
#[inline(never)]
fn scalar_lanes(q: &Query8, p: &Packet, i: usize, t_max: F8) -> Hits8 {
    let tri = p.triangle(i);
    let t_max = t_max.to_array();
    let hits: [Option<triangle::TriangleHit>; 8] = std::array::from_fn(|lane| {
        triangle::intersect(&RayShear::new(&q.rays.ray(lane)), &tri, t_max[lane])
    });
    let get = |f: fn(&triangle::TriangleHit) -> f32| {
        F8::from_array(hits.map(|h| h.as_ref().map_or(0.0, f)))
    };
    let bits = hits
        .iter()
        .enumerate()
        .fold(0, |m, (i, h)| m | (h.is_some() as u32) << i);
    Hits8 {
        valid: F8::mask_from_bits(bits),
        t: get(|h| h.t),
        b1: get(|h| h.b1),
        b2: get(|h| h.b2),
        // Unused by the ray packets that take this path.
        t_scaled: F8::zero(),
        abs_det: F8::zero(),
    }
}

impl Bvh {
    /// [`Bvh::intersect8`] on AVX2 when the rays can share the triangle test's
    /// axis order; `None` otherwise.
    pub(super) fn intersect8_wide(&self, rays: &[Ray; 8], t_max: f32) -> Option<[Option<Hit>; 8]> {
        if self.isa != Isa::Avx2 {
            return None;
        }
        let root = self.root?;
        // SAFETY: `Isa::Avx2` is only chosen when the CPU has AVX2.
        unsafe { self.intersect8_either_avx2(rays, root, t_max) }
    }

    /// Packets from one point into one octant take the interval test, the
    /// others the eight slab tests.
    #[target_feature(enable = "avx2")]
    fn intersect8_either_avx2(
        &self,
        rays: &[Ray; 8],
        root: ChildRef,
        t_max: f32,
    ) -> Option<[Option<Hit>; 8]> {
        let q = &Query8::new(rays)?;
        Some(self.intersect8_query(q, root, t_max).hits())
    }

    /// The closest hits of a packet: packets from one point into one octant
    /// take the interval test, the others the eight slab tests.
    #[target_feature(enable = "avx2")]
    #[inline]
    fn intersect8_query(&self, q: &Query8, root: ChildRef, t_max: f32) -> Closest8 {
        if q.one_origin() && q.one_octant() {
            self.intersect8_from_one_point_avx2(q, root, t_max)
        } else {
            self.intersect8_avx2(q, root, t_max)
        }
    }

    /// [`Bvh::intersect8`] of eight rays given in lanes, answered in lanes
    /// (the same hits): `None` when this tree does not use AVX2 or the rays
    /// cannot share a packet (then trace them as `[Ray; 8]`).
    #[inline]
    #[target_feature(enable = "avx2")]
    pub(crate) fn intersect8_lanes(&self, rays: &Rays8, t_max: f32) -> Option<Closest8> {
        if self.isa != Isa::Avx2 {
            return None;
        }
        let q = &Query8::from_lanes(*rays)?;
        Some(match self.root {
            Some(root) => self.intersect8_query(q, root, t_max),
            None => Closest8 {
                found: 0,
                t: F8::splat(t_max),
                b1: F8::zero(),
                b2: F8::zero(),
                prim: F8::zero(),
            },
        })
    }

    /// [`Bvh::occluded8`] of eight rays given in lanes: bit `i` of the answer
    /// set when lane `i` is `active` (bit `i`) and blocked within its `t_max`;
    /// `None` as for [`Bvh::intersect8_lanes`].
    #[inline]
    #[target_feature(enable = "avx2")]
    pub(crate) fn occluded8_lanes(&self, rays: &Rays8, t_max: F8, active: u32) -> Option<u32> {
        if self.isa != Isa::Avx2 {
            return None;
        }
        let q = &Query8::from_lanes(*rays)?;
        Some(match self.root {
            Some(root) => self.occluded8_query(q, root, t_max, F8::mask_from_bits(active)),
            None => 0,
        })
    }

    /// [`Bvh::occluded8`] on AVX2 when the rays can share the axis order.
    pub(super) fn occluded8_wide(
        &self,
        rays: &[Ray; 8],
        t_max: [f32; 8],
        active: [bool; 8],
    ) -> Option<[bool; 8]> {
        if self.isa != Isa::Avx2 {
            return None;
        }
        let root = self.root?;
        // SAFETY: as above.
        unsafe { self.occluded8_avx2(rays, root, t_max, active) }
    }

    #[target_feature(enable = "avx2")]
    fn intersect8_avx2(&self, q: &Query8, root: ChildRef, t_max: f32) -> Closest8 {
        let mut best_t = F8::splat(t_max);
        let (mut b1, mut b2) = (F8::zero(), F8::zero());
        let mut prim = F8::splat(f32::from_bits(u32::MAX));
        let mut found = 0u32;
        let mut stack = Stack::<(ChildRef, F8)>::new();
        stack.push((root, F8::zero()));
        while let Some((cur, near)) = stack.pop() {
            if !near.cmple(best_t).any() {
                continue;
            }
            if cur & LEAF != 0 {
                closest_in_leaf!(self, q, cur, best_t, b1, b2, prim, found);
                continue;
            }
            let (node, kids) = self.node(cur);
            // Visit next the child whose box the packet enters first.
            let mut next: Option<(ChildRef, F8, f32)> = None;
            for (c, &child) in kids.iter().enumerate() {
                if child == EMPTY {
                    continue;
                }
                let (near, hit) = q.hit_box(&node.bounds, c, best_t);
                if !hit.any() {
                    continue;
                }
                // Lanes that miss get NaN, which no `t` compares below.
                let key = F8::select(hit, near, F8::splat(f32::INFINITY)).min_element();
                let near = F8::select(hit, near, F8::splat(f32::NAN));
                match next {
                    Some((n, nv, nk)) if nk <= key => {
                        stack.push((child, near));
                        next = Some((n, nv, nk));
                    }
                    Some((n, nv, _)) => {
                        stack.push((n, nv));
                        next = Some((child, near, key));
                    }
                    None => next = Some((child, near, key)),
                }
            }
            if let Some((n, nv, _)) = next {
                stack.push((n, nv));
            }
        }
        Closest8 {
            found,
            t: best_t,
            b1,
            b2,
            prim,
        }
    }

    /// [`Bvh::intersect8`] for rays from one point (a pinhole camera's): a
    /// node's eight boxes are tested at once, one per lane, against the whole
    /// packet, with interval arithmetic over the rays' inverse directions; the
    /// leaves test each ray exactly. `(b − o)·inv` is monotonic in `inv`, and
    /// so is its rounding, so the smallest entry and largest exit distance over
    /// the rays are those at the extreme inverses: a box that any ray's own
    /// slab test enters passes the packet's test too, and every hit is found.
    #[target_feature(enable = "avx2")]
    fn intersect8_from_one_point_avx2(&self, q: &Query8, root: ChildRef, t_max: f32) -> Closest8 {
        let o = &q.rays.origin;
        let origin = [o[0].first(), o[1].first(), o[2].first()];
        // (Written out: a closure here is compiled without AVX2 and was left
        // as a call with its intrinsics.)
        let inv = &q.inv_dir;
        let inv_lo = [
            inv[0].min_element(),
            inv[1].min_element(),
            inv[2].min_element(),
        ];
        let inv_hi = [
            inv[0].max_element(),
            inv[1].max_element(),
            inv[2].max_element(),
        ];
        let exit_scale = F8::splat(1.0 + 2.0 * gamma(3));
        let mut best_t = F8::splat(t_max);
        let (mut b1, mut b2) = (F8::zero(), F8::zero());
        let mut prim = F8::splat(f32::from_bits(u32::MAX));
        let mut found = 0u32;
        // The largest `t` any ray may still hit at.
        let mut reach = t_max;
        let mut stack = Stack::<(ChildRef, f32)>::new();
        stack.push((root, 0.0));
        while let Some((cur, near)) = stack.pop() {
            if near > reach {
                continue;
            }
            if cur & LEAF != 0 {
                closest_in_leaf!(self, q, cur, best_t, b1, b2, prim, found);
                reach = best_t.max_element();
                continue;
            }
            let (node, kids) = self.node(cur);
            // Per axis, the packet's entry and exit distances of every child's
            // two planes, at the inverse that makes each smallest or largest.
            let mut enter = F8::zero();
            let mut exit = F8::splat(f32::INFINITY);
            for a in 0..3 {
                let o = F8::splat(origin[a]);
                let (lo, hi) = (F8::splat(inv_lo[a]), F8::splat(inv_hi[a]));
                let d0 = F8::from_array(node.bounds[a]) - o;
                let d1 = F8::from_array(node.bounds[a + 3]) - o;
                let zero = F8::zero();
                let first0 = d0 * F8::select(d0.cmplt(zero), hi, lo);
                let first1 = d1 * F8::select(d1.cmplt(zero), hi, lo);
                let last0 = d0 * F8::select(d0.cmplt(zero), lo, hi);
                let last1 = d1 * F8::select(d1.cmplt(zero), lo, hi);
                enter = enter.max_(first0.min(first1));
                exit = exit.min(last0.max_(last1));
            }
            let exit = exit * exit_scale;
            let mut mask = enter.cmple(exit.min(F8::splat(reach))).bitmask();
            let enter = enter.to_array();
            let base = stack.len;
            while mask != 0 {
                let c = mask.trailing_zeros() as usize;
                mask &= mask - 1;
                if kids[c] != EMPTY {
                    stack.push((kids[c], enter[c]));
                }
            }
            stack.sort_far_to_near(base);
        }
        Closest8 {
            found,
            t: best_t,
            b1,
            b2,
            prim,
        }
    }

    #[target_feature(enable = "avx2")]
    fn occluded8_avx2(
        &self,
        rays: &[Ray; 8],
        root: ChildRef,
        t_max: [f32; 8],
        active: [bool; 8],
    ) -> Option<[bool; 8]> {
        let q = &Query8::new(rays)?;
        let bits = active
            .iter()
            .enumerate()
            .fold(0, |m, (i, &a)| m | (a as u32) << i);
        let blocked =
            self.occluded8_query(q, root, F8::from_array(t_max), F8::mask_from_bits(bits));
        Some(std::array::from_fn(|lane| blocked >> lane & 1 != 0))
    }

    /// The lanes of `open` that something blocks within their `t_max`, as bits.
    #[target_feature(enable = "avx2")]
    #[inline]
    fn occluded8_query(&self, q: &Query8, root: ChildRef, t_max: F8, mut open: F8) -> u32 {
        let mut blocked = 0u32;
        let mut stack = Stack::<ChildRef>::new();
        stack.push(root);
        while let Some(cur) = stack.pop() {
            if cur & LEAF != 0 {
                for p in self.leaf(cur) {
                    for i in 0..p.len() {
                        let hit = test_triangle(q, p, i, t_max).valid & open;
                        blocked |= hit.bitmask();
                        open = open & !hit;
                    }
                }
                if !open.any() {
                    break;
                }
                continue;
            }
            let (node, kids) = self.node(cur);
            for (c, &child) in kids.iter().enumerate() {
                if child != EMPTY && (q.hit_box(&node.bounds, c, t_max).1 & open).any() {
                    stack.push(child);
                }
            }
        }
        blocked
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::triangle::Triangle;
    use crate::sampling::sampler::Rng;
    use glam::Vec3A;

    /// Two packets tested in one eight-wide pass give what testing them in turn
    /// gives, bit for bit: the same hit or miss, `t`, barycentrics and triangle,
    /// the same one at an exact tie (a triangle duplicated across the packets),
    /// and the exact-zero edge case left to the caller.
    #[test]
    fn two_packets_together_agree_with_the_packets_in_turn() {
        if Isa::detect() != Isa::Avx2 {
            return;
        }
        let mut rng = Rng::new(31, 0);
        let mut r = move || rng.next_f32();
        let (mut hits, mut ties, mut zeros) = (0, 0, 0);
        for round in 0..20_000 {
            let n = 5 + round % 4;
            let mut tris: Vec<(Triangle, u32)> = (0..n)
                .map(|i| {
                    let c = Vec3A::new(r(), r(), r()) * 2.0 - 1.0;
                    let e = |r: &mut dyn FnMut() -> f32| Vec3A::new(r(), r(), r()) - 0.5;
                    (Triangle::new(c, c + e(&mut r), c + e(&mut r)), i as u32)
                })
                .collect();
            if round % 5 == 0 {
                // The same triangle in both packets: an exact tie.
                tris[4 + round % (n - 4)].0 = tris[round % 4].0;
            }
            if round % 7 == 0 {
                // Integer coordinates: rays along the axes meet edges exactly.
                for (t, _) in &mut tris {
                    t.v = t.v.map(|v| (v * 4.0).round());
                }
            }
            let tris: Vec<_> = tris.into_iter().filter(|(t, _)| t.can_be_hit()).collect();
            if tris.len() < 5 {
                continue;
            }
            let pair = [Packet::new(&tris[..4]), Packet::new(&tris[4..])];
            let origin = Vec3A::new(r(), r(), r()) * 6.0 - 3.0;
            let (tri, _) = tris[round % tris.len()];
            let (s1, s2) = (r() * 0.6, r() * 0.6);
            let target = tri.v[0] + s1 * (tri.v[1] - tri.v[0]) + s2 * (tri.v[2] - tri.v[0]);
            let (origin, dir) = if round % 7 == 0 {
                (
                    origin.round(),
                    Vec3A::AXES[round % 3] * if round % 2 == 0 { 1.0 } else { -1.0 },
                )
            } else {
                (origin, (target - origin).normalize())
            };
            let pr = PacketRay::new(origin, dir);
            let t_max = if round % 3 == 0 { 2.0 } else { f32::INFINITY };
            let mut limit = t_max;
            let mut want = None;
            for (k, p) in pair.iter().enumerate() {
                if let Some((lane, h)) = super::super::packet::intersect(&pr, p, limit) {
                    limit = h.t;
                    want = Some((k, lane, h));
                }
            }
            let want_any = pair
                .iter()
                .any(|p| super::super::packet::occluded(&pr, p, t_max));
            // SAFETY: AVX2 was detected above; the test calls the pair tests
            // from a function compiled for AVX2.
            let (got, got_any) = unsafe { both(&pr, &pair, t_max) };
            let (Ok(got), Ok(got_any)) = (got, got_any) else {
                zeros += 1;
                continue;
            };
            assert_eq!(got_any, want_any, "round {round}");
            match (got, want) {
                (None, None) => {}
                (Some((k, lane, h)), Some((wk, wlane, w))) => {
                    hits += 1;
                    ties += (round % 5 == 0 && k == 1) as u32;
                    assert_eq!((k, lane), (wk, wlane), "round {round}");
                    assert_eq!(
                        [h.t, h.b1, h.b2].map(f32::to_bits),
                        [w.t, w.b1, w.b2].map(f32::to_bits),
                        "round {round}"
                    );
                }
                (g, w) => panic!("round {round}: {g:?} against {w:?}"),
            }
        }
        assert!(
            hits > 10_000 && ties > 500 && zeros > 100,
            "{hits} {ties} {zeros}"
        );

        #[target_feature(enable = "avx2")]
        #[allow(clippy::type_complexity)]
        fn both(
            r: &PacketRay,
            pair: &[Packet],
            t_max: f32,
        ) -> (
            Result<Option<(usize, usize, TriangleHit)>, ()>,
            Result<bool, ()>,
        ) {
            (pair_closest(r, pair, t_max), pair_occluded(r, pair, t_max))
        }
    }

    /// Eight rays traced together, from one point or from nearby points, give
    /// the single rays' closest hits (the same `t` bit for bit; barycentrics
    /// where the triangle is the same) and any-hit answers.
    /// The lanes' decision to trace a packet together, and its axis order,
    /// are those of `shared_axis_order` ray by ray: on packets of tied, signed
    /// zero, infinite and NaN components, and on nearly parallel ones.
    #[test]
    fn packets_share_the_axis_order_the_rays_have() {
        #[target_feature(enable = "avx2")]
        fn lanes(rays: &[Ray; 8]) -> Option<([usize; 3], bool)> {
            Query8::new(rays).map(|q| (q.k, q.one_origin()))
        }
        if !std::arch::is_x86_feature_detected!("avx2") {
            return;
        }
        let mut rng = Rng::new(31, 0);
        let values = [0.0f32, -0.0, 1.0, -1.0, 0.5, -2.0, f32::INFINITY, f32::NAN];
        let (mut shared, mut apart) = (0, 0);
        for round in 0..40_000 {
            let base = Vec3A::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) - 0.5;
            let pick = |rng: &mut Rng| values[(rng.next_f32() * 8.0) as usize % 8];
            let tied = Vec3A::new(pick(&mut rng), pick(&mut rng), pick(&mut rng));
            let origin = Vec3A::new(1.0, 2.0, 3.0);
            let odd_lane = (rng.next_f32() * 16.0) as usize;
            let rays: [Ray; 8] = std::array::from_fn(|lane| {
                let d = match round % 3 {
                    // Built of the special values, the same in every lane but
                    // perhaps one.
                    0 if lane == odd_lane => {
                        Vec3A::new(pick(&mut rng), pick(&mut rng), pick(&mut rng))
                    }
                    0 => tied,
                    1 => {
                        base + (Vec3A::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) - 0.5)
                            * 0.1
                    }
                    _ => base,
                };
                let o = if round % 5 == 0 {
                    origin + d * 0.5
                } else {
                    origin
                };
                Ray::new(o, d)
            });
            // SAFETY: the CPU has AVX2.
            let got = unsafe { lanes(&rays) };
            let want = crate::geometry::triangle::shared_axis_order(&rays);
            assert_eq!(got.map(|g| g.0), want, "round {round}: {rays:?}");
            if let Some((_, one)) = got {
                assert_eq!(one, rays.iter().all(|r| r.origin == rays[0].origin));
                shared += 1;
            } else {
                apart += 1;
            }
        }
        assert!(
            shared > 10_000 && apart > 10_000,
            "{shared} shared, {apart} apart"
        );
    }

    #[test]
    fn eight_rays_together_agree_with_one_at_a_time() {
        let mut rng = Rng::new(23, 0);
        let mut tris = Vec::new();
        // A bumpy closed sphere (shared edges) and loose triangles.
        let (n_lat, n_lon) = (16, 32);
        let p = |i: usize, j: usize| {
            let (th, ph) = (
                std::f32::consts::PI * i as f32 / n_lat as f32,
                std::f32::consts::TAU * j as f32 / n_lon as f32,
            );
            let r = 1.0 + 0.1 * ((3.0 * ph).sin() * (2.0 * th).cos());
            Vec3A::new(
                r * th.sin() * ph.cos(),
                r * th.cos(),
                r * th.sin() * ph.sin(),
            )
        };
        for i in 0..n_lat {
            for j in 0..n_lon {
                let (a, b, c, d) = (p(i, j), p(i + 1, j), p(i + 1, j + 1), p(i, j + 1));
                tris.push(Triangle::new(a, b, c));
                tris.push(Triangle::new(a, c, d));
            }
        }
        for _ in 0..60 {
            let c = Vec3A::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 3.0 - 1.5;
            let e = Vec3A::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 0.3;
            tris.push(Triangle::new(c, c + e, c + Vec3A::new(e.z, e.x, e.y)));
        }
        let bvh = Bvh::build(&tris);
        let (mut hits, mut blocked) = (0, 0);
        for round in 0..3000 {
            let origin = Vec3A::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 6.0 - 3.0;
            let aim = Vec3A::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 2.0 - 1.0;
            // From one point (a camera's packets, traced with the packet's
            // interval test) or from nearby points (the per-ray box tests).
            let spread = if round % 4 == 0 { 2.0 } else { 0.05 };
            let apart = if round % 4 == 1 { 0.01 } else { 0.0 };
            let rays: [Ray; 8] = std::array::from_fn(|_| {
                let mut v = || Vec3A::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) - 0.5;
                let (jitter, shift) = (v(), v());
                let from = origin + apart * shift;
                Ray::new(from, (aim + spread * jitter - from).normalize())
            });
            let t_max = if round % 3 == 0 { 3.0 } else { f32::INFINITY };
            let together = bvh.intersect8(&rays, t_max);
            let limits: [f32; 8] = std::array::from_fn(|i| [t_max, 2.0, 1.0, t_max][i % 4]);
            let active: [bool; 8] = std::array::from_fn(|i| i != 1 || round % 2 == 0);
            let occluded = bvh.occluded8(&rays, limits, active);
            for lane in 0..8 {
                let alone = bvh.intersect(&rays[lane], t_max);
                assert_eq!(
                    together[lane].is_some(),
                    alone.is_some(),
                    "round {round} lane {lane}"
                );
                if let (Some(a), Some(b)) = (together[lane], alone) {
                    hits += 1;
                    assert_eq!(a.t.to_bits(), b.t.to_bits(), "round {round}");
                    if a.prim == b.prim {
                        assert_eq!((a.b1, a.b2), (b.b1, b.b2));
                    }
                }
                let want = active[lane] && bvh.occluded(&rays[lane], limits[lane]);
                blocked += want as u32;
                assert_eq!(occluded[lane], want, "round {round} lane {lane}");
            }
        }
        assert!(
            hits > 6000 && blocked > 3000,
            "{hits} hits, {blocked} blocked"
        );
    }
}
