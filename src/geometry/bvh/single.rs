//! One ray's queries: the closest hit ([`Bvh::intersect`]) and whether
//! anything is hit ([`Bvh::occluded`]), each traversal compiled once for AVX2
//! and once portably, the leaves' tests (two packets in one AVX2 pass, see
//! `ray8::pair_closest`), and [`brute_force`], the reference they are tested
//! against.

use super::node::{BoxQuery, ChildRef, Isa, LEAF, WIDTH};
use super::packet::{self, Packet, PacketRay};
#[cfg(target_arch = "x86_64")]
use super::ray8;
use super::tree::Bvh;
use super::walk::{Stack, is_finite_ray};
use crate::geometry::ray::{Hit, Ray};
use crate::geometry::triangle::{Triangle, TriangleHit};

impl Bvh {
    /// The closest hit with `t` in `(0, t_max]`. (Inlined, with each
    /// traversal out of line: as one call holding the portable traversal too,
    /// it cost the lab box's `path` 2 % in calls.)
    #[inline(always)]
    pub fn intersect(&self, ray: &Ray, t_max: f32) -> Option<Hit> {
        match self.isa {
            // SAFETY: `Isa::Avx2` is only chosen when the CPU has AVX2.
            #[cfg(target_arch = "x86_64")]
            Isa::Avx2 => unsafe { self.intersect_avx2(ray, t_max) },
            Isa::Portable => self.intersect_portable(ray, t_max),
        }
    }

    /// Whether anything is hit with `t` in `(0, t_max]`; stops at the first hit found.
    #[inline(always)]
    pub fn occluded(&self, ray: &Ray, t_max: f32) -> bool {
        match self.isa {
            // SAFETY: as above.
            #[cfg(target_arch = "x86_64")]
            Isa::Avx2 => unsafe { self.occluded_avx2(ray, t_max) },
            Isa::Portable => self.occluded_portable(ray, t_max),
        }
    }

    #[inline(never)]
    fn intersect_portable(&self, ray: &Ray, t_max: f32) -> Option<Hit> {
        self.intersect_with(Isa::Portable, ray, t_max)
    }

    #[inline(never)]
    fn occluded_portable(&self, ray: &Ray, t_max: f32) -> bool {
        self.occluded_with(Isa::Portable, ray, t_max)
    }

    /// The whole traversal compiled for AVX2, so that the box and triangle tests
    /// inline with VEX encodings.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    fn intersect_avx2(&self, ray: &Ray, t_max: f32) -> Option<Hit> {
        self.intersect_with(Isa::Avx2, ray, t_max)
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    fn occluded_avx2(&self, ray: &Ray, t_max: f32) -> bool {
        self.occluded_with(Isa::Avx2, ray, t_max)
    }

    #[inline(always)]
    fn intersect_with(&self, isa: Isa, ray: &Ray, t_max: f32) -> Option<Hit> {
        let root = self.root?;
        if !is_finite_ray(ray) {
            return None;
        }
        let boxes = BoxQuery::new(ray.origin, ray.dir);
        // Made at once: kept in an `Option` until the first leaf, it was copied
        // there and back (most rays reach a leaf).
        let tri_ray = PacketRay::new(ray.origin, ray.dir);
        self.closest_from(isa, root, &boxes, &tri_ray, t_max)
    }

    /// The closest-hit traversal from `root` of the ray of `boxes` and `tri_ray`.
    #[inline(always)]
    pub(super) fn closest_from(
        &self,
        isa: Isa,
        root: ChildRef,
        boxes: &BoxQuery,
        tri_ray: &PacketRay,
        t_max: f32,
    ) -> Option<Hit> {
        let mut best: Option<Hit> = None;
        let mut t_max = t_max;
        let mut stack = Stack::<(ChildRef, f32)>::new();
        let mut t_near = [0.0f32; WIDTH];
        let mut cur = root;
        loop {
            if cur & LEAF != 0 {
                if let Some(h) = self.leaf_closest(isa, tri_ray, cur, t_max) {
                    t_max = h.t;
                    best = Some(h);
                }
            } else {
                let (node, kids) = self.node(cur);
                let mut mask = boxes.hit(isa, node, t_max, &mut t_near);
                if mask != 0 {
                    let first = mask.trailing_zeros() as usize;
                    mask &= mask - 1;
                    if mask == 0 {
                        cur = kids[first];
                        continue;
                    }
                    let second = mask.trailing_zeros() as usize;
                    mask &= mask - 1;
                    if mask == 0 {
                        // Two boxes hit, the most common case: no sort.
                        let (near, far) = if t_near[second] < t_near[first] {
                            (second, first)
                        } else {
                            (first, second)
                        };
                        self.prefetch_child(kids[far]);
                        stack.push((kids[far], t_near[far]));
                        cur = kids[near];
                        continue;
                    }
                    // Several boxes hit: push them all, order them far to near and
                    // continue with the nearest (the pops skip any that start
                    // beyond the closest hit by then).
                    let base = stack.len;
                    stack.push((kids[first], t_near[first]));
                    stack.push((kids[second], t_near[second]));
                    self.prefetch_child(kids[first]);
                    self.prefetch_child(kids[second]);
                    while mask != 0 {
                        let lane = mask.trailing_zeros() as usize;
                        mask &= mask - 1;
                        self.prefetch_child(kids[lane]);
                        stack.push((kids[lane], t_near[lane]));
                    }
                    stack.sort_far_to_near(base);
                    cur = stack.pop().expect("three or more were just pushed").0;
                    continue;
                }
            }
            // Pop the next subtree that may still hold a closer hit.
            loop {
                let Some((r, t)) = stack.pop() else {
                    return best;
                };
                if t <= t_max {
                    cur = r;
                    break;
                }
            }
        }
    }

    #[inline(always)]
    fn occluded_with(&self, isa: Isa, ray: &Ray, t_max: f32) -> bool {
        let Some(root) = self.root else {
            return false;
        };
        if !is_finite_ray(ray) {
            return false;
        }
        let boxes = BoxQuery::new(ray.origin, ray.dir);
        self.occluded_from(isa, root, &boxes, t_max, || {
            PacketRay::new(ray.origin, ray.dir)
        })
    }

    /// The any-hit traversal from `root` of the ray of `boxes`, whose
    /// [`PacketRay`] `make_tri_ray` makes at the first leaf (many shadow rays
    /// never reach one).
    #[inline(always)]
    pub(super) fn occluded_from(
        &self,
        isa: Isa,
        root: ChildRef,
        boxes: &BoxQuery,
        t_max: f32,
        make_tri_ray: impl Fn() -> PacketRay,
    ) -> bool {
        let mut tri_ray: Option<PacketRay> = None;
        let mut stack = Stack::<ChildRef>::new();
        let mut t_near = [0.0f32; WIDTH];
        let mut cur = root;
        loop {
            if cur & LEAF != 0 {
                let tri_ray = tri_ray.get_or_insert_with(&make_tri_ray);
                if self.leaf_occluded(isa, tri_ray, cur, t_max) {
                    return true;
                }
            } else {
                let (node, kids) = self.node(cur);
                let mut mask = boxes.hit(isa, node, t_max, &mut t_near);
                while mask != 0 {
                    let lane = mask.trailing_zeros() as usize;
                    mask &= mask - 1;
                    stack.push(kids[lane]);
                }
            }
            match stack.pop() {
                Some(next) => cur = next,
                None => return false,
            }
        }
    }
    /// The closest hit within `(0, t_max]` among the triangles of `leaf`. Two
    /// packets (eight triangles) at a time are one AVX2 pass where the CPU has
    /// it, with the answers of the packets tested in turn (see
    /// [`ray8::pair_closest`]).
    #[inline(always)]
    pub(super) fn leaf_closest(
        &self,
        isa: Isa,
        r: &PacketRay,
        leaf: ChildRef,
        t_max: f32,
    ) -> Option<Hit> {
        let packets = self.leaf(leaf);
        // A leaf of one packet (a wall of a room, most leaves of small trees):
        // its test alone, without the loop's state (−5 % instructions on the
        // lab box's `path`).
        if let [p] = packets {
            let (lane, h) = packet::intersect(r, p, t_max)?;
            return Some(Hit {
                t: h.t,
                prim: p.prim(lane),
                b1: h.b1,
                b2: h.b2,
            });
        }
        let mut t_max = t_max;
        let mut best: Option<(&Packet, usize, TriangleHit)> = None;
        for pair in packets.chunks(2) {
            #[cfg(target_arch = "x86_64")]
            if isa == Isa::Avx2
                && pair.len() == 2
                && let Ok(found) = ray8::pair_closest(r, pair, t_max)
            {
                if let Some((p, lane, h)) = found {
                    t_max = h.t;
                    best = Some((&pair[p], lane, h));
                }
                continue;
            }
            for p in pair {
                if let Some((lane, h)) = packet::intersect(r, p, t_max) {
                    t_max = h.t;
                    best = Some((p, lane, h));
                }
            }
        }
        let _ = isa;
        best.map(|(p, lane, h)| Hit {
            t: h.t,
            prim: p.prim(lane),
            b1: h.b1,
            b2: h.b2,
        })
    }

    /// Whether any triangle of `leaf` is hit within `(0, t_max]` (two packets
    /// at a time in one AVX2 pass, as [`Bvh::leaf_closest`]).
    #[inline(always)]
    pub(super) fn leaf_occluded(
        &self,
        isa: Isa,
        r: &PacketRay,
        leaf: ChildRef,
        t_max: f32,
    ) -> bool {
        let packets = self.leaf(leaf);
        if let [p] = packets {
            return packet::occluded(r, p, t_max);
        }
        // Plain loops: a closure here (`Iterator::any`) was left as a call outside
        // the AVX2 code, its intrinsics as calls too (15× slower).
        for pair in packets.chunks(2) {
            #[cfg(target_arch = "x86_64")]
            if isa == Isa::Avx2
                && pair.len() == 2
                && let Ok(any) = ray8::pair_occluded(r, pair, t_max)
            {
                if any {
                    return true;
                }
                continue;
            }
            for p in pair {
                if packet::occluded(r, p, t_max) {
                    return true;
                }
            }
        }
        let _ = isa;
        false
    }
}

/// The closest hit by testing every triangle that can be hit
/// ([`Triangle::can_be_hit`]): the reference the BVH is tested against (and a
/// way to check a suspicious hit by hand). Same answers as [`Bvh::intersect`]
/// except which triangle is reported at an exact tie.
pub fn brute_force(triangles: &[Triangle], ray: &Ray, t_max: f32) -> Option<Hit> {
    let s = crate::geometry::triangle::RayShear::new(ray);
    let mut best: Option<Hit> = None;
    for (i, t) in triangles.iter().enumerate() {
        if !t.can_be_hit() {
            continue;
        }
        let limit = best.map_or(t_max, |b| b.t);
        if let Some(h) = crate::geometry::triangle::intersect(&s, &t.v, limit) {
            best = Some(Hit {
                t: h.t,
                prim: i as u32,
                b1: h.b1,
                b2: h.b2,
            });
        }
    }
    best
}
