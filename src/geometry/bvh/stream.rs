//! Batches of rays traced with several rays in flight at once.
//!
//! One ray's traversal is a chain of dependent steps: load a node, test its
//! boxes, choose a child, load that child. On meshes larger than the L2 cache
//! most of a step is waiting for memory, and nothing else can run meanwhile. A
//! stream keeps [`IN_FLIGHT`] independent traversals and advances them in turn,
//! one node or leaf each, so that their cache misses and arithmetic overlap in
//! the out-of-order core (the CPU counterpart of a GPU running many rays per
//! core). Each such ray is traversed exactly as [`Bvh::intersect`] and
//! [`Bvh::occluded`] do it, so the answers are the same as theirs. Runs of
//! eight coherent rays (one origin, nearly one direction) go through the
//! eight-ray packets instead: the same `t`, bit for bit, but which of two
//! triangles at exactly the same `t` is reported may differ.

use std::mem::MaybeUninit;

use super::node::{BoxQuery, ChildRef, Isa, LEAF, WIDTH};
use super::packet::PacketRay;
use super::tree::Bvh;
use super::walk::{Stack, is_finite_ray};
use crate::geometry::ray::{Hit, Ray};

/// Rays traversed together. Four measured best on the shared meshes: two
/// overlap too little, eight spill the lanes' state out of the L1 cache.
pub const IN_FLIGHT: usize = 4;

/// One closest-hit traversal in progress.
struct Closest {
    index: usize,
    boxes: BoxQuery,
    tri_ray: PacketRay,
    t_max: f32,
    best: Option<Hit>,
    cur: ChildRef,
    stack: Stack<(ChildRef, f32)>,
}

/// One any-hit traversal in progress.
struct Any {
    index: usize,
    boxes: BoxQuery,
    tri_ray: PacketRay,
    t_max: f32,
    cur: ChildRef,
    stack: Stack<ChildRef>,
}

impl Bvh {
    /// Closest hits of a batch of rays, each within `(0, t_max[i]]` (`t_max` is
    /// either one value for all or one per ray), into `out`. The same answers as
    /// [`Bvh::intersect`] ray by ray (except which triangle is reported at an
    /// exact tie, for runs traced as packets), usually in less time for large
    /// batches.
    ///
    /// # Panics
    /// When `out` and `rays` differ in length, or `t_max` has neither one nor
    /// `rays.len()` values.
    pub fn intersect_stream(&self, rays: &[Ray], t_max: &[f32], out: &mut [Option<Hit>]) {
        check_lengths(rays.len(), t_max.len(), out.len());
        // Runs of eight rays from one point in nearly one direction (camera rays
        // of neighbouring pixels) are traced as packets; the rest interleaved.
        if self.isa != Isa::Portable && t_max.len() == 1 && rays.len() >= PACKET {
            let mut start = 0;
            let mut i = 0;
            while i + PACKET <= rays.len() {
                let group: &[Ray; PACKET] = rays[i..i + PACKET].try_into().expect("eight rays");
                if !is_coherent(group) {
                    i += PACKET;
                    continue;
                }
                if start < i {
                    self.intersect_interleaved(&rays[start..i], t_max, &mut out[start..i]);
                }
                out[i..i + PACKET].copy_from_slice(&self.intersect8(group, t_max[0]));
                i += PACKET;
                start = i;
            }
            if start < rays.len() {
                self.intersect_interleaved(&rays[start..], t_max, &mut out[start..]);
            }
            return;
        }
        self.intersect_interleaved(rays, t_max, out);
    }

    /// [`Bvh::intersect_stream`] with every ray in the interleaved traversal.
    fn intersect_interleaved(&self, rays: &[Ray], t_max: &[f32], out: &mut [Option<Hit>]) {
        match self.isa {
            // SAFETY: `Isa::Avx2` is only chosen when the CPU has AVX2.
            #[cfg(target_arch = "x86_64")]
            Isa::Avx2 => unsafe { self.intersect_stream_avx2(rays, t_max, out) },
            Isa::Portable => self.intersect_stream_with(Isa::Portable, rays, t_max, out),
        }
    }

    /// Whether each ray of a batch is blocked within `(0, t_max[i]]`, as
    /// [`Bvh::occluded`] ray by ray.
    ///
    /// # Panics
    /// As [`Bvh::intersect_stream`].
    pub fn occluded_stream(&self, rays: &[Ray], t_max: &[f32], out: &mut [bool]) {
        check_lengths(rays.len(), t_max.len(), out.len());
        match self.isa {
            // SAFETY: as above.
            #[cfg(target_arch = "x86_64")]
            Isa::Avx2 => unsafe { self.occluded_stream_avx2(rays, t_max, out) },
            Isa::Portable => self.occluded_stream_with(Isa::Portable, rays, t_max, out),
        }
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    fn intersect_stream_avx2(&self, rays: &[Ray], t_max: &[f32], out: &mut [Option<Hit>]) {
        self.intersect_stream_with(Isa::Avx2, rays, t_max, out)
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    fn occluded_stream_avx2(&self, rays: &[Ray], t_max: &[f32], out: &mut [bool]) {
        self.occluded_stream_with(Isa::Avx2, rays, t_max, out)
    }

    #[inline(always)]
    fn intersect_stream_with(
        &self,
        isa: Isa,
        rays: &[Ray],
        t_max: &[f32],
        out: &mut [Option<Hit>],
    ) {
        let Some(root) = self.root else {
            out.fill(None);
            return;
        };
        let limit = |i: usize| t_max[if t_max.len() == 1 { 0 } else { i }];
        let mut lanes: [MaybeUninit<Closest>; IN_FLIGHT] =
            [const { MaybeUninit::uninit() }; IN_FLIGHT];
        let mut live = 0u32;
        let mut next = 0;
        // Starts the next ray that needs a traversal in `lane`, answering the
        // ones that do not on the way; false when there are none left.
        let mut start = |lane: &mut MaybeUninit<Closest>, out: &mut [Option<Hit>]| -> bool {
            while next < rays.len() {
                let i = next;
                next += 1;
                let ray = &rays[i];
                if !is_finite_ray(ray) {
                    out[i] = None;
                    continue;
                }
                lane.write(Closest {
                    index: i,
                    boxes: BoxQuery::new(ray.origin, ray.dir),
                    tri_ray: PacketRay::new(ray.origin, ray.dir),
                    t_max: limit(i),
                    best: None,
                    cur: root,
                    stack: Stack::new(),
                });
                return true;
            }
            false
        };
        for (l, lane) in lanes.iter_mut().enumerate() {
            if start(lane, out) {
                live |= 1 << l;
            }
        }
        let mut t_near = [0.0f32; WIDTH];
        while live != 0 {
            for (l, lane) in lanes.iter_mut().enumerate() {
                if live >> l & 1 == 0 {
                    continue;
                }
                // SAFETY: lanes whose bit is set in `live` were written by `start`.
                let ray = unsafe { lane.assume_init_mut() };
                if self.closest_step(isa, ray, &mut t_near) {
                    out[ray.index] = ray.best;
                    if !start(lane, out) {
                        live &= !(1 << l);
                    }
                }
            }
        }
    }

    /// One node or leaf of a closest-hit traversal, then the choice of the next;
    /// true when the traversal is over.
    #[inline(always)]
    fn closest_step(&self, isa: Isa, ray: &mut Closest, t_near: &mut [f32; WIDTH]) -> bool {
        let cur = ray.cur;
        if cur & LEAF != 0 {
            if let Some(h) = self.leaf_closest(isa, &ray.tri_ray, cur, ray.t_max) {
                ray.t_max = h.t;
                ray.best = Some(h);
            }
        } else {
            let (node, kids) = self.node(cur);
            let mut mask = ray.boxes.hit(isa, node, ray.t_max, t_near);
            if mask != 0 {
                let first = mask.trailing_zeros() as usize;
                mask &= mask - 1;
                if mask == 0 {
                    ray.cur = kids[first];
                    self.prefetch_child(ray.cur);
                    return false;
                }
                let second = mask.trailing_zeros() as usize;
                mask &= mask - 1;
                if mask == 0 {
                    let (near, far) = if t_near[second] < t_near[first] {
                        (second, first)
                    } else {
                        (first, second)
                    };
                    ray.stack.push((kids[far], t_near[far]));
                    ray.cur = kids[near];
                    self.prefetch_child(kids[near]);
                    self.prefetch_child(kids[far]);
                    return false;
                }
                let base = ray.stack.len;
                ray.stack.push((kids[first], t_near[first]));
                ray.stack.push((kids[second], t_near[second]));
                self.prefetch_child(kids[first]);
                self.prefetch_child(kids[second]);
                while mask != 0 {
                    let lane = mask.trailing_zeros() as usize;
                    mask &= mask - 1;
                    self.prefetch_child(kids[lane]);
                    ray.stack.push((kids[lane], t_near[lane]));
                }
                ray.stack.sort_far_to_near(base);
                ray.cur = ray.stack.pop().expect("three or more were just pushed").0;
                return false;
            }
        }
        loop {
            let Some((r, t)) = ray.stack.pop() else {
                return true;
            };
            if t <= ray.t_max {
                ray.cur = r;
                self.prefetch_child(r);
                return false;
            }
        }
    }

    #[inline(always)]
    fn occluded_stream_with(&self, isa: Isa, rays: &[Ray], t_max: &[f32], out: &mut [bool]) {
        let Some(root) = self.root else {
            out.fill(false);
            return;
        };
        let limit = |i: usize| t_max[if t_max.len() == 1 { 0 } else { i }];
        let mut lanes: [MaybeUninit<Any>; IN_FLIGHT] = [const { MaybeUninit::uninit() }; IN_FLIGHT];
        let mut live = 0u32;
        let mut next = 0;
        let mut start = |lane: &mut MaybeUninit<Any>, out: &mut [bool]| -> bool {
            while next < rays.len() {
                let i = next;
                next += 1;
                let ray = &rays[i];
                if !is_finite_ray(ray) {
                    out[i] = false;
                    continue;
                }
                lane.write(Any {
                    index: i,
                    boxes: BoxQuery::new(ray.origin, ray.dir),
                    tri_ray: PacketRay::new(ray.origin, ray.dir),
                    t_max: limit(i),
                    cur: root,
                    stack: Stack::new(),
                });
                return true;
            }
            false
        };
        for (l, lane) in lanes.iter_mut().enumerate() {
            if start(lane, out) {
                live |= 1 << l;
            }
        }
        let mut t_near = [0.0f32; WIDTH];
        while live != 0 {
            for (l, lane) in lanes.iter_mut().enumerate() {
                if live >> l & 1 == 0 {
                    continue;
                }
                // SAFETY: lanes whose bit is set in `live` were written by `start`.
                let ray = unsafe { lane.assume_init_mut() };
                if let Some(blocked) = self.any_step(isa, ray, &mut t_near) {
                    out[ray.index] = blocked;
                    if !start(lane, out) {
                        live &= !(1 << l);
                    }
                }
            }
        }
    }

    /// One node or leaf of an any-hit traversal; the answer when it is over.
    #[inline(always)]
    fn any_step(&self, isa: Isa, ray: &mut Any, t_near: &mut [f32; WIDTH]) -> Option<bool> {
        let cur = ray.cur;
        if cur & LEAF != 0 {
            if self.leaf_occluded(isa, &ray.tri_ray, cur, ray.t_max) {
                return Some(true);
            }
        } else {
            let (node, kids) = self.node(cur);
            let mut mask = ray.boxes.hit(isa, node, ray.t_max, t_near);
            while mask != 0 {
                let lane = mask.trailing_zeros() as usize;
                mask &= mask - 1;
                self.prefetch_child(kids[lane]);
                ray.stack.push(kids[lane]);
            }
        }
        match ray.stack.pop() {
            Some(next) => {
                ray.cur = next;
                None
            }
            None => Some(false),
        }
    }
}

/// Rays per packet of the stream's coherent runs.
const PACKET: usize = 8;

/// Whether eight rays share their origin and point within about 18° of the
/// first (cosine 0.95), as the camera rays of a pixel run do: then one packet
/// traversal visits few nodes more than each ray alone would.
fn is_coherent(rays: &[Ray; PACKET]) -> bool {
    let o = rays[0].origin;
    let d = rays[0].dir;
    let d2 = d.length_squared();
    rays[1..].iter().all(|r| {
        let dot = r.dir.dot(d);
        r.origin == o && dot > 0.0 && dot * dot >= 0.9025 * d2 * r.dir.length_squared()
    })
}

fn check_lengths(rays: usize, t_max: usize, out: usize) {
    assert_eq!(rays, out, "one answer per ray");
    assert!(
        t_max == 1 || t_max == rays,
        "t_max: one value, or one per ray ({t_max} for {rays} rays)"
    );
}
