//! An eight-wide bounding volume hierarchy over triangles.
//!
//! Built top down with binned SAH (modules `sah` and `build`): every node holds
//! up to eight children whose boxes are tested together (`node`: AVX2 where the
//! CPU has it), with leaves of one or two packets of four triangles in
//! structure-of-arrays layout (`packet`; a leaf of two is tested in one AVX2
//! pass, `ray8::pair_closest`). Closest-hit traversal visits children
//! nearest first and skips any whose box starts beyond the closest hit so far;
//! any-hit traversal stops at the first hit.

mod build;
mod node;
mod packet;
mod ray4;
mod ray8;
mod sah;
mod single8;
mod stream;

use std::mem::MaybeUninit;

use glam::Vec3A;

use crate::geometry::ray::{Hit, Ray};
use crate::geometry::triangle::{Triangle, TriangleHit};
use crate::memory::prefetch;
use node::{BoxQuery, ChildRef, EMPTY, Isa, LEAF, NodeBoxes, WIDTH, leaf_parts};
use packet::{Packet, PacketRay};
#[cfg(target_arch = "x86_64")]
pub(crate) use single8::Singles8;
pub use stream::IN_FLIGHT;

/// Traversal stack size: at most `WIDTH - 1` entries per level of the tree, whose
/// depth is at most that of the binary splits it is made of: [`sah::MAX_SAH_DEPTH`]
/// SAH levels, then median splits of fewer than 2^27 triangles down to eight (24
/// levels) and exact splits of four triangles or fewer (2), within the 32 spare.
const STACK_SIZE: usize = (WIDTH - 1) * (sah::MAX_SAH_DEPTH + 32);

/// The hierarchy, owning a copy of the triangles in leaf order.
#[derive(Clone, Debug)]
pub struct Bvh {
    nodes: Vec<NodeBoxes>,
    children: Vec<[ChildRef; WIDTH]>,
    packets: Vec<Packet>,
    root: Option<ChildRef>,
    triangles: usize,
    isa: Isa,
}

impl Bvh {
    /// Builds the tree. Triangles with zero area or non-finite vertices can never be
    /// hit and are left out; hits report indices into `triangles`.
    pub fn build(triangles: &[Triangle]) -> Self {
        // From the cache (see [`crate::cache`]) when there is one: the tree
        // depends only on the triangles.
        if crate::cache::dir().is_none() {
            return Self::build_here(triangles);
        }
        use crate::cache::{self, Kind};
        let key = cache::key(Kind::Bvh, |f| {
            f.floats(
                triangles
                    .iter()
                    .flat_map(|t| t.v)
                    .flat_map(|v| v.to_array()),
            )
        });
        // At most 8 nodes, 8 packets and their children per triangle.
        let max_len = 64 + triangles.len() as u64 * 8 * (192 + 32 + 160);
        if let Some(bvh) = cache::get(Kind::Bvh, key, max_len)
            .and_then(|p| Self::from_cache_bytes(&p, triangles.len()))
        {
            return bvh;
        }
        let bvh = Self::build_here(triangles);
        cache::put(Kind::Bvh, key, &bvh.to_cache_bytes());
        bvh
    }

    /// The tree as [`Bvh::from_cache_bytes`] reads it back (little-endian).
    fn to_cache_bytes(&self) -> Vec<u8> {
        let mut out =
            Vec::with_capacity(40 + self.nodes.len() * (192 + 32) + self.packets.len() * 160);
        for n in [
            self.nodes.len(),
            self.children.len(),
            self.packets.len(),
            self.triangles,
        ] {
            out.extend_from_slice(&(n as u64).to_le_bytes());
        }
        out.extend_from_slice(&self.root.unwrap_or(EMPTY).to_le_bytes());
        out.extend_from_slice(&u32::from(self.root.is_some()).to_le_bytes());
        for n in &self.nodes {
            for x in n.bounds.as_flattened() {
                out.extend_from_slice(&x.to_le_bytes());
            }
        }
        for c in self.children.as_flattened() {
            out.extend_from_slice(&c.to_le_bytes());
        }
        for p in &self.packets {
            for v in p.v.as_flattened() {
                for x in v.to_array() {
                    out.extend_from_slice(&x.to_le_bytes());
                }
            }
            for i in p.prim {
                out.extend_from_slice(&i.to_le_bytes());
            }
        }
        out
    }

    /// A tree that [`Bvh::to_cache_bytes`] wrote for `input` triangles, if the
    /// bytes make a sound one: sizes that match, and every reference (child,
    /// leaf, triangle index) in range, so that no query can go astray.
    fn from_cache_bytes(bytes: &[u8], input: usize) -> Option<Self> {
        let mut r = crate::cache::Reader(bytes);
        let mut count = || usize::try_from(r.u64()?).ok();
        let (n_nodes, n_children, n_packets, triangles) = (count()?, count()?, count()?, count()?);
        let root = r.u32()?;
        let has_root = r.u32()? == 1;
        let want = n_nodes
            .checked_mul(192)?
            .checked_add(n_children.checked_mul(32)?)?
            .checked_add(n_packets.checked_mul(160)?)?;
        if r.0.len() != want || n_children != n_nodes || triangles > input {
            return None;
        }
        let mut nodes = Vec::with_capacity(n_nodes);
        crate::memory::advise_huge_pages(&mut nodes);
        for _ in 0..n_nodes {
            let mut bounds = [[0f32; WIDTH]; 6];
            for x in bounds.as_flattened_mut() {
                *x = r.f32()?;
            }
            nodes.push(NodeBoxes { bounds });
        }
        let mut children = Vec::with_capacity(n_children);
        crate::memory::advise_huge_pages(&mut children);
        for _ in 0..n_children {
            let mut c = [EMPTY; WIDTH];
            for x in &mut c {
                *x = r.u32()?;
            }
            children.push(c);
        }
        let mut packets = Vec::with_capacity(n_packets);
        crate::memory::advise_huge_pages(&mut packets);
        for _ in 0..n_packets {
            let mut v = [[glam::Vec4::ZERO; 3]; 3];
            for x in v.as_flattened_mut() {
                *x = glam::Vec4::new(r.f32()?, r.f32()?, r.f32()?, r.f32()?);
            }
            let mut prim = [0u32; 4];
            for i in &mut prim {
                *i = r.u32()?;
                if *i as usize >= input {
                    return None;
                }
            }
            packets.push(Packet { v, prim });
        }
        if !references_sound(has_root.then_some(root), &children, n_packets) {
            return None;
        }
        Some(Bvh {
            nodes,
            children,
            packets,
            root: has_root.then_some(root),
            triangles,
            isa: Isa::detect(),
        })
    }

    /// [`Bvh::build`] without the cache.
    fn build_here(triangles: &[Triangle]) -> Self {
        let isa = Isa::detect();
        match build::build(triangles, isa) {
            Some(built) => {
                // Traversal relies on it (unchecked indexing; see `Bvh::node`).
                debug_assert!(
                    built.nodes.len() == built.children.len()
                        && references_sound(Some(built.root), &built.children, built.packets.len())
                );
                Bvh {
                    nodes: built.nodes,
                    children: built.children,
                    packets: built.packets,
                    root: Some(built.root),
                    triangles: built.triangles,
                    isa,
                }
            }
            None => Bvh {
                nodes: Vec::new(),
                children: Vec::new(),
                packets: Vec::new(),
                root: None,
                triangles: 0,
                isa,
            },
        }
    }

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
    fn closest_from(
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
    fn occluded_from(
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

    /// Asks for the memory of a child that will be visited later, so that its
    /// cache misses overlap with the work on its siblings: a node's three lines of
    /// boxes and its children, or a leaf's first packet and a half.
    #[inline(always)]
    fn prefetch_child(&self, r: ChildRef) {
        if r & LEAF != 0 {
            let p: *const u8 = self.packets.as_ptr().wrapping_add(leaf_parts(r).0).cast();
            for line in 0..3 {
                prefetch(p.wrapping_add(64 * line));
            }
        } else {
            let p: *const u8 = self.nodes.as_ptr().wrapping_add(r as usize).cast();
            for line in 0..3 {
                prefetch(p.wrapping_add(64 * line));
            }
            prefetch(self.children.as_ptr().wrapping_add(r as usize));
        }
    }

    /// The closest hit within `(0, t_max]` among the triangles of `leaf`. Two
    /// packets (eight triangles) at a time are one AVX2 pass where the CPU has
    /// it, with the answers of the packets tested in turn (see
    /// [`ray8::pair_closest`]).
    #[inline(always)]
    fn leaf_closest(&self, isa: Isa, r: &PacketRay, leaf: ChildRef, t_max: f32) -> Option<Hit> {
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
    fn leaf_occluded(&self, isa: Isa, r: &PacketRay, leaf: ChildRef, t_max: f32) -> bool {
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

    /// The packets of leaf `r`, a reference found in this tree.
    #[inline]
    fn leaf(&self, r: ChildRef) -> &[Packet] {
        let (start, count) = leaf_parts(r);
        debug_assert!(start + count <= self.packets.len());
        // SAFETY: every reference in a tree is in range: `build::build` makes
        // them so (the tests check every tree they build, debug builds every
        // tree) and `from_cache_bytes` checks each one before it returns a tree
        // (`references_sound`). Unchecked, as the node loop is short: two
        // comparisons a node were about 4 % of a ray's instructions.
        unsafe { self.packets.get_unchecked(start..start + count) }
    }

    /// The boxes and children of inner node `r`, a reference found in this tree.
    #[inline(always)]
    fn node(&self, r: ChildRef) -> (&NodeBoxes, &[ChildRef; WIDTH]) {
        let i = r as usize;
        debug_assert!(i < self.nodes.len() && i < self.children.len());
        // SAFETY: as in `leaf`; `nodes` and `children` have one entry a node.
        unsafe { (self.nodes.get_unchecked(i), self.children.get_unchecked(i)) }
    }

    /// Number of eight-wide nodes.
    pub fn node_count(&self) -> usize {
        self.nodes.len()
    }

    /// Number of triangles in the tree (those that can be hit).
    pub fn triangle_count(&self) -> usize {
        self.triangles
    }

    /// Bytes used by nodes and triangle packets.
    pub fn memory_bytes(&self) -> usize {
        self.nodes.len()
            * (std::mem::size_of::<NodeBoxes>() + std::mem::size_of::<[ChildRef; WIDTH]>())
            + self.packets.len() * std::mem::size_of::<Packet>()
    }
}

/// A fixed-size traversal stack that is not zeroed on creation: traversal runs once
/// per ray, and clearing a few kilobytes each time cost more than the box tests.
struct Stack<T: Copy> {
    items: [MaybeUninit<T>; STACK_SIZE],
    len: usize,
}

impl<T: Copy> Stack<T> {
    #[inline(always)]
    fn new() -> Self {
        Self {
            items: [const { MaybeUninit::uninit() }; STACK_SIZE],
            len: 0,
        }
    }

    #[inline(always)]
    fn push(&mut self, item: T) {
        // Indexing checks the bound: a too-deep tree panics rather than corrupts.
        self.items[self.len] = MaybeUninit::new(item);
        self.len += 1;
    }

    #[inline(always)]
    fn pop(&mut self) -> Option<T> {
        if self.len == 0 {
            return None;
        }
        self.len -= 1;
        // SAFETY: every slot below `len` was written by `push`.
        Some(unsafe { self.items[self.len].assume_init() })
    }
}

impl Stack<(ChildRef, f32)> {
    /// Sorts the entries from `base` up by entry distance, farthest at the bottom,
    /// so that the nearest pops first (insertion sort: at most eight entries).
    #[inline(always)]
    fn sort_far_to_near(&mut self, base: usize) {
        for i in base + 1..self.len {
            // SAFETY: every slot below `len` was written by `push`.
            let item = unsafe { self.items[i].assume_init() };
            let mut j = i;
            while j > base && unsafe { self.items[j - 1].assume_init().1 } < item.1 {
                self.items[j] = self.items[j - 1];
                j -= 1;
            }
            self.items[j] = MaybeUninit::new(item);
        }
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

/// Whether every reference of a tree is in range, as traversal assumes: a
/// leaf's packets lie in `0..n_packets`, an inner node is an index into
/// `children` (one entry a node) and comes after its parent, so that the tree
/// has no cycle. `Bvh::from_cache_bytes` checks it on every tree it reads; the
/// builder's trees are checked by the tests.
fn references_sound(
    root: Option<ChildRef>,
    children: &[[ChildRef; WIDTH]],
    n_packets: usize,
) -> bool {
    let n_nodes = children.len();
    let sound = |c: ChildRef, parent: Option<usize>| {
        if c & LEAF != 0 {
            let (start, n) = leaf_parts(c);
            n > 0 && start + n <= n_packets
        } else {
            (c as usize) < n_nodes && parent.is_none_or(|p| c as usize > p)
        }
    };
    root.is_none_or(|r| sound(r, None))
        && children
            .iter()
            .enumerate()
            .all(|(parent, slots)| slots.iter().all(|&c| c == EMPTY || sound(c, Some(parent))))
}

/// Whether every coordinate of the ray is finite: `x · 0` is 0 for finite `x`
/// and NaN for an infinity or a NaN (one comparison of the sum, where
/// `is_finite` on both vectors cost a dozen instructions more a ray).
#[inline(always)]
fn is_finite_ray(ray: &Ray) -> bool {
    (ray.origin * 0.0 + ray.dir * 0.0).cmpeq(Vec3A::ZERO).all()
}

#[cfg(test)]
mod tests {
    use super::node::leaf_ref;
    use super::*;
    use crate::sampling::sampler::Rng;
    use glam::Vec3A;

    fn random_triangles(rng: &mut Rng, n: usize) -> Vec<Triangle> {
        let mut p = || Vec3A::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 2.0 - 1.0;
        (0..n)
            .map(|_| {
                let c = p();
                Triangle::new(c, c + 0.2 * p(), c + 0.2 * p())
            })
            .collect()
    }

    /// `rays` random rays through the soup's cube: closest hits agree with brute
    /// force (same hit or miss, `t` within 1e-5, the same triangle or a tie), and
    /// any-hit agrees with closest-hit with and without a `t_max` cut.
    fn check_against_brute_force(bvh: &Bvh, tris: &[Triangle], rng: &mut Rng, rays: usize) {
        // Traversal indexes without bounds checks: the built tree must be sound.
        assert!(references_sound(bvh.root, &bvh.children, bvh.packets.len()));
        assert_eq!(bvh.nodes.len(), bvh.children.len());
        for _ in 0..rays {
            let o = Vec3A::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 3.0 - 1.5;
            let d = (Vec3A::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) - 0.5).normalize();
            let ray = Ray::new(o, d);
            let a = bvh.intersect(&ray, f32::INFINITY);
            let b = brute_force(tris, &ray, f32::INFINITY);
            assert_eq!(a.is_some(), b.is_some(), "n={} {ray:?}", tris.len());
            if let (Some(a), Some(b)) = (a, b) {
                assert!((a.t - b.t).abs() <= 1e-5 * b.t, "{a:?} {b:?}");
                assert!(a.prim == b.prim || a.t == b.t, "{a:?} {b:?}");
            }
            assert_eq!(bvh.occluded(&ray, f32::INFINITY), b.is_some());
            let cut = 0.5;
            assert_eq!(
                bvh.occluded(&ray, cut),
                brute_force(tris, &ray, cut).is_some()
            );
        }
    }

    /// The stream API gives exactly the single-ray answers (the same traversal,
    /// interleaved), with one `t_max` for all and one per ray, on both
    /// instruction sets, including rays that start inside the soup, non-finite
    /// rays and batches smaller than the rays in flight.
    #[test]
    fn stream_answers_equal_single_ray_answers() {
        let mut rng = Rng::new(9, 4);
        let tris = random_triangles(&mut rng, 5000);
        let mut bvh = Bvh::build(&tris);
        let mut rays: Vec<Ray> = (0..3001)
            .map(|_| {
                let o = Vec3A::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 3.0 - 1.5;
                let d = Vec3A::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) - 0.5;
                Ray::new(o, d)
            })
            .collect();
        rays[17] = Ray::new(Vec3A::splat(f32::NAN), Vec3A::Z);
        rays[18] = Ray::new(Vec3A::ZERO, Vec3A::new(0.0, f32::INFINITY, 1.0));
        let t_max: Vec<f32> = (0..rays.len())
            .map(|i| 0.2 + (i % 7) as f32 * 0.3)
            .collect();
        let isas = if Isa::detect() == Isa::Portable {
            vec![Isa::Portable]
        } else {
            vec![Isa::detect(), Isa::Portable]
        };
        for isa in isas {
            bvh.isa = isa;
            for n in [0, 1, 3, 5, rays.len()] {
                let rays = &rays[..n];
                let mut hits = vec![None; n];
                let mut blocked = vec![false; n];
                bvh.intersect_stream(rays, &t_max[..n], &mut hits);
                bvh.occluded_stream(rays, &t_max[..n], &mut blocked);
                for (i, r) in rays.iter().enumerate() {
                    assert_eq!(hits[i], bvh.intersect(r, t_max[i]), "ray {i}");
                    assert_eq!(blocked[i], bvh.occluded(r, t_max[i]), "ray {i}");
                }
                bvh.intersect_stream(rays, &[f32::INFINITY], &mut hits);
                let found = hits.iter().filter(|h| h.is_some()).count();
                for (i, r) in rays.iter().enumerate() {
                    assert_eq!(hits[i], bvh.intersect(r, f32::INFINITY), "ray {i}");
                }
                if n > 1000 {
                    assert!(found > n / 4, "{found} of {n} hit");
                }
            }
        }
        let empty = Bvh::build(&[]);
        let mut hits = vec![
            Some(Hit {
                t: 1.0,
                prim: 0,
                b1: 0.0,
                b2: 0.0
            });
            2
        ];
        empty.intersect_stream(&rays[..2], &[1.0], &mut hits);
        assert_eq!(hits, vec![None, None]);
    }

    /// Found by fuzzing: rays parallel to an axis (a ±0 direction component)
    /// whose origin lies on a face of a triangle's exact box, hitting that
    /// triangle on its edge; the slab test gave them an exit distance of 0
    /// there and the BVH missed the hit, until boxes were padded.
    #[test]
    fn rays_along_a_box_face_find_the_edges_in_it() {
        // An octahedron, a degenerate triangle and a sliver (the fuzz target's
        // fixture), and rays the fuzzer found.
        let p = [
            Vec3A::X,
            Vec3A::NEG_X,
            Vec3A::Y,
            Vec3A::NEG_Y,
            Vec3A::Z,
            Vec3A::NEG_Z,
        ];
        let mut tris = Vec::new();
        for &(a, b) in &[(0, 2), (2, 1), (1, 3), (3, 0)] {
            tris.push(Triangle::new(p[a], p[b], p[4]));
            tris.push(Triangle::new(p[b], p[a], p[5]));
        }
        tris.push(Triangle::new(p[0], p[0], p[1]));
        tris.push(Triangle::new(p[0], p[1], p[1] + Vec3A::splat(1e-7)));
        let bvh = Bvh::build(&tris);
        let rays = [
            // In the plane y = 0 (the sliver's lower face) with dir.y = -0.
            Ray::new(
                Vec3A::new(0.0, 0.0, 0.0625),
                Vec3A::new(0.0, -0.0, -1.3046875),
            ),
            Ray::new(
                Vec3A::new(0.3, 0.0, -1.5258789e-5),
                Vec3A::new(-0.1, -0.0, 2.7872636),
            ),
            // On x = 1 (faces' upper bound in x) with dir.x = +0.
            Ray::new(Vec3A::new(1.0, 3.0, 0.3), Vec3A::new(0.0, -1.0, -0.1)),
        ];
        for r in &rays {
            let want = brute_force(&tris, r, f32::INFINITY);
            assert!(want.is_some(), "{r:?} should hit an edge");
            assert_eq!(
                bvh.intersect(r, f32::INFINITY).map(|h| h.t),
                want.map(|h| h.t),
                "{r:?}"
            );
            assert!(bvh.occluded(r, f32::INFINITY), "{r:?}");
        }
    }

    #[test]
    fn agrees_with_brute_force_on_random_soup() {
        let mut rng = Rng::new(3, 1);
        for &n in &[1usize, 2, 7, 100, 3000] {
            let tris = random_triangles(&mut rng, n);
            let bvh = Bvh::build(&tris);
            check_against_brute_force(&bvh, &tris, &mut rng, 2000);
        }
    }

    /// The soundness check that guards unchecked traversal refuses each kind
    /// of bad reference.
    #[test]
    fn unsound_references_are_refused() {
        let mut rng = Rng::new(9, 4);
        let bvh = Bvh::build(&random_triangles(&mut rng, 500));
        let sound = |root, children: &[[ChildRef; WIDTH]]| {
            references_sound(root, children, bvh.packets.len())
        };
        assert!(sound(bvh.root, &bvh.children));
        assert!(bvh.children.len() > 2);
        let bad_refs = [
            bvh.children.len() as ChildRef,     // past the nodes
            0,                                  // its own parent: a cycle
            leaf_ref(bvh.packets.len(), 1),     // past the packets
            leaf_ref(bvh.packets.len() - 1, 2), // running past them
            leaf_ref(0, 0),                     // empty leaf
        ];
        for bad in bad_refs {
            let mut children = bvh.children.clone();
            children[0][0] = bad;
            assert!(!sound(bvh.root, &children), "{bad:#x}");
        }
        assert!(!sound(Some(bvh.children.len() as ChildRef), &bvh.children));
    }

    /// A large soup takes the parallel paths of the build (children built as
    /// separate pieces, binning and partition in parallel blocks).
    #[test]
    fn agrees_with_brute_force_on_a_large_soup() {
        let mut rng = Rng::new(5, 2);
        let tris = random_triangles(&mut rng, 100_000);
        let bvh = Bvh::build(&tris);
        assert_eq!(bvh.triangle_count(), tris.len());
        check_against_brute_force(&bvh, &tris, &mut rng, 300);
    }

    /// Every node's boxes and children, and every packet's triangles and indices,
    /// hashed bit for bit.
    fn fingerprint(built: &build::Built) -> u64 {
        use std::hash::{Hash, Hasher};
        let mut h = std::collections::hash_map::DefaultHasher::new();
        built.root.hash(&mut h);
        for (node, kids) in built.nodes.iter().zip(&built.children) {
            node.bounds
                .iter()
                .flatten()
                .for_each(|x| x.to_bits().hash(&mut h));
            kids.hash(&mut h);
        }
        for p in &built.packets {
            for lane in 0..4 {
                p.prim(lane).hash(&mut h);
                let t = p.triangle(lane);
                t.iter()
                    .flat_map(|v| v.to_array())
                    .for_each(|x| x.to_bits().hash(&mut h));
            }
        }
        h.finish()
    }

    /// Two triangles hit one ulp apart (found by the `bvh` fuzz target): the
    /// test without division let the farther one pass a `t_max` of the nearer
    /// one's `t`, so brute force and packets took the farther triangle and
    /// single rays the nearer one. Every query kind must take the nearer.
    #[test]
    fn a_hit_one_ulp_behind_the_closest_is_not_taken() {
        let v = |x: f32, y: f32, z: f32| Vec3A::new(x, y, z);
        let a = 0.011_488_97;
        let tris = [
            Triangle::new(v(a, a, 0.011_488_972), v(a, 0.011_489_447, a), v(a, a, a)),
            Triangle::new(
                v(a, 0.011_488_972, 47.058_84),
                v(a, a, a),
                v(a, 0.011_521_045, a),
            ),
        ];
        let ray = Ray::new(v(0.011_488_969, 0.011_488_972, a), v(a, a, a));
        let bvh = Bvh::build_here(&tris);
        let want = brute_force(&tris, &ray, f32::INFINITY).expect("a hit");
        assert_eq!(want.prim, 0, "the nearer triangle");
        for got in [
            bvh.intersect(&ray, f32::INFINITY),
            bvh.intersect4(&[ray; 4], f32::INFINITY)[0],
            bvh.intersect8(&[ray; 8], f32::INFINITY)[0],
        ] {
            let got = got.expect("a hit");
            assert_eq!((got.prim, got.t.to_bits()), (want.prim, want.t.to_bits()));
        }
    }

    /// A tree written for the cache reads back whole, answers as the built one,
    /// and is refused when cut, cyclic or naming triangles it was not given.
    #[test]
    fn cache_bytes_round_trip_and_refuse_damage() {
        let mut rng = Rng::new(3, 7);
        let tris = random_triangles(&mut rng, 3000);
        let bvh = Bvh::build_here(&tris);
        let bytes = bvh.to_cache_bytes();
        let back = Bvh::from_cache_bytes(&bytes, tris.len()).expect("sound");
        assert_eq!(back.to_cache_bytes(), bytes);
        // The same answers as the built tree.
        for _ in 0..2000 {
            let o = Vec3A::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 4.0 - 2.0;
            let d = (Vec3A::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) - 0.5).normalize();
            let ray = Ray::new(o, d);
            assert_eq!(back.intersect(&ray, 1e9), bvh.intersect(&ray, 1e9));
        }
        // Cut, or for fewer triangles than its indices name: refused.
        assert!(Bvh::from_cache_bytes(&bytes[..bytes.len() - 4], tris.len()).is_none());
        assert!(Bvh::from_cache_bytes(&bytes, 10).is_none());
        // A child made to point back at the root: refused (no cycles).
        let mut cyclic = bvh.clone();
        cyclic.children[1][0] = 0;
        assert!(Bvh::from_cache_bytes(&cyclic.to_cache_bytes(), tris.len()).is_none());
        // The empty tree.
        let empty = Bvh::build_here(&[]);
        assert!(Bvh::from_cache_bytes(&empty.to_cache_bytes(), 0).is_some());
    }

    /// The same tree, bit for bit, on any number of threads and with either
    /// instruction set for the binning.
    #[test]
    fn build_is_the_same_on_any_thread_count_and_isa() {
        let mut rng = Rng::new(7, 3);
        let tris = random_triangles(&mut rng, 100_000);
        let on = |threads: usize, isa: Isa| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .expect("thread pool");
            let built = pool.install(|| build::build(&tris, isa)).expect("a tree");
            (built.nodes.len(), fingerprint(&built))
        };
        let isa = Isa::detect();
        let one = on(1, isa);
        assert!(one.0 > 1000, "a big tree: {} nodes", one.0);
        assert_eq!(on(2, isa), one);
        assert_eq!(on(3, isa), one);
        assert_eq!(on(2, Isa::Portable), one);
    }

    #[test]
    fn empty_and_degenerate_inputs() {
        let ray = Ray::new(Vec3A::ZERO, Vec3A::Z);
        let empty = Bvh::build(&[]);
        assert!(empty.intersect(&ray, f32::INFINITY).is_none());
        assert!(!empty.occluded(&ray, f32::INFINITY));
        let p = Vec3A::new(0.0, 0.0, 1.0);
        let degenerate = vec![Triangle::new(p, p, p); 5];
        let bvh = Bvh::build(&degenerate);
        assert_eq!(bvh.triangle_count(), 0);
        assert!(bvh.intersect(&ray, f32::INFINITY).is_none());
        // Non-finite vertices are dropped, the rest keep their indices.
        let good = Triangle::new(
            Vec3A::new(-1.0, -1.0, 2.0),
            Vec3A::new(1.0, -1.0, 2.0),
            Vec3A::new(0.0, 1.0, 2.0),
        );
        let bad = Triangle::new(Vec3A::splat(f32::NAN), p, p);
        let bvh = Bvh::build(&[bad, good]);
        assert_eq!(bvh.intersect(&ray, f32::INFINITY).unwrap().prim, 1);
        // NaN and infinite rays hit nothing and do not panic.
        for r in [
            Ray::new(Vec3A::splat(f32::NAN), Vec3A::Z),
            Ray::new(Vec3A::ZERO, Vec3A::new(f32::NAN, 0.0, 1.0)),
            Ray::new(Vec3A::ZERO, Vec3A::ZERO),
            Ray::new(Vec3A::splat(f32::INFINITY), Vec3A::Z),
            Ray::new(Vec3A::ZERO, Vec3A::new(0.0, 0.0, f32::INFINITY)),
        ] {
            assert!(bvh.intersect(&r, f32::INFINITY).is_none(), "{r:?}");
            assert!(!bvh.occluded(&r, f32::INFINITY), "{r:?}");
        }
    }

    #[test]
    fn axis_aligned_rays_on_box_planes_still_hit() {
        // Boxes flat in z whose min x plane contains the ray, which has zero x and y
        // direction components: the slab test sees 0 * inf = NaN on x.
        let a = Triangle::new(
            Vec3A::new(0.0, -1.0, 2.0),
            Vec3A::new(2.0, -1.0, 2.0),
            Vec3A::new(0.0, 1.0, 2.0),
        );
        let b = Triangle::new(
            Vec3A::new(0.0, -1.0, 4.0),
            Vec3A::new(0.0, 1.0, 4.0),
            Vec3A::new(-2.0, 1.0, 4.0),
        );
        let bvh = Bvh::build(&[a, b]);
        for (dir, want) in [(Vec3A::Z, (0, 2.0)), (-Vec3A::Z, (1, 4.0))] {
            let origin = if dir.z > 0.0 {
                Vec3A::ZERO
            } else {
                Vec3A::new(0.0, 0.0, 8.0)
            };
            let hit = bvh
                .intersect(&Ray::new(origin, dir), f32::INFINITY)
                .expect("hit");
            assert_eq!((hit.prim, hit.t), want);
            assert!(bvh.occluded(&Ray::new(origin, dir), f32::INFINITY));
        }
    }

    /// In a small room (the lab box), rays that start on a surface and end on
    /// the next enter few leaves: each wall has leaves of its own, apart from
    /// the blocks' (the SAH's volume term for small trees). Priced by area
    /// alone, a side wall and the floor shared leaves with faces of the blocks,
    /// boxes that many of these rays entered: 2.09 leaves a ray before the hit
    /// against 1.84 (and 7 % more instructions for `path`, 11 % for `direct`).
    #[test]
    fn rays_in_a_small_room_enter_few_leaves() {
        let (tris, _) = crate::load::cornell::triangles();
        let bvh = Bvh::build(&tris);
        let room = crate::load::cornell::parts::ROOM;
        let mut leaf_boxes = Vec::new();
        for (n, kids) in bvh.children.iter().enumerate() {
            for (c, &kid) in kids.iter().enumerate() {
                if kid == EMPTY || kid & LEAF == 0 {
                    continue;
                }
                let prims: Vec<u32> = bvh
                    .leaf(kid)
                    .iter()
                    .flat_map(|p| (0..p.len()).map(|i| p.prim(i)))
                    .collect();
                let walls = prims
                    .iter()
                    .filter(|&&p| room.contains(&(p as usize)))
                    .count();
                assert!(
                    walls == 0 || walls == prims.len(),
                    "a leaf of walls and blocks: {prims:?}"
                );
                let b = &bvh.nodes[n].bounds;
                let lo = Vec3A::new(b[0][c], b[1][c], b[2][c]);
                let hi = Vec3A::new(b[3][c], b[4][c], b[5][c]);
                leaf_boxes.push((lo, hi));
            }
        }
        let mut rng = Rng::new(5, 5);
        let (mut entered, mut rays) = (0usize, 0usize);
        for _ in 0..20_000 {
            let tri = &tris[(rng.next_f32() * tris.len() as f32) as usize % tris.len()];
            let (u, v) = (rng.next_f32(), rng.next_f32());
            let (u, v) = if u + v > 1.0 {
                (1.0 - u, 1.0 - v)
            } else {
                (u, v)
            };
            let p = tri.v[0] + u * (tri.v[1] - tri.v[0]) + v * (tri.v[2] - tri.v[0]);
            let d = (Vec3A::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) - 0.5).normalize();
            let ray = Ray::new(p + 1e-4 * d, d);
            let Some(hit) = bvh.intersect(&ray, f32::INFINITY) else {
                continue;
            };
            rays += 1;
            for &(lo, hi) in &leaf_boxes {
                let inv = d.recip();
                let (t0, t1) = ((lo - ray.origin) * inv, (hi - ray.origin) * inv);
                let near = t0.min(t1).max_element().max(0.0);
                let far = t0.max(t1).min_element().min(hit.t);
                entered += (near <= far) as usize;
            }
        }
        let per_ray = entered as f64 / rays as f64;
        assert!(
            rays > 10_000 && per_ray < 1.95,
            "{per_ray} leaves a ray over {rays} rays"
        );
    }
}
