//! Binned-SAH splits of runs of triangles ([`Cluster`]), from which the builder
//! takes a node's children.
//!
//! One pass over a run's triangles bins their centroids on all three axes at
//! once (in parallel for large runs); the split then moves the triangles of each
//! side together.

use glam::Vec4;
use rayon::prelude::*;

use super::node::Isa;
use crate::geometry::triangle::Triangle;

/// Bins per axis for runs of at least [`MANY_BINS_MIN`] triangles, and below.
/// Few bins make the many small runs cheaper to bin; many serve large runs and
/// the few big triangles of scenes like the lab box (8 bins for its 30 triangles
/// made it render 30 % slower).
const MANY_BINS: usize = 12;
const FEW_BINS: usize = 8;
const MANY_BINS_MIN: usize = 24;
/// Triangles per leaf packet.
const PACKET: usize = 4;
/// Runs of at most this many triangles are split by exact SAH, not binned (as
/// many as a leaf holds: binned runs are never small enough to be a leaf).
const EXACT_MAX: usize = MAX_LEAF;
/// Largest leaf, in triangles: two four-wide packets.
pub(super) const MAX_LEAF: usize = 8;
/// Cost of visiting a node relative to testing one packet of four triangles.
const TRAVERSAL_COST: f32 = 0.3;
/// Past this depth only median splits, which bound the depth by log2(n).
pub(super) const MAX_SAH_DEPTH: usize = 64;
/// How far ahead, in triangles, a pass over a run asks for memory (the top of a
/// big tree streams from far caches).
const PREFETCH_AHEAD: usize = 32;
/// Triangles per block of a parallel partition.
const PARTITION_BLOCK: usize = 16_384;
/// Runs at least this big (1 MB) are read with prefetching.
const PREFETCH_MIN: usize = 32_768;
/// Runs at least this big are bounded, binned and partitioned in parallel (the
/// partition's blocks, below [`PREFETCH_MIN`], are read without prefetching).
const PARALLEL_RUN_MIN: usize = 65_536;

/// An axis-aligned box in the first three lanes of two `Vec4`s (the fourth lane is
/// carried along unused: it holds a triangle's index in a [`BuildPrim`]).
#[derive(Clone, Copy, Debug)]
#[repr(C)]
pub(super) struct Aabb {
    pub(super) min: Vec4,
    pub(super) max: Vec4,
}

impl Aabb {
    pub(super) const EMPTY: Aabb = Aabb {
        min: Vec4::splat(f32::INFINITY),
        max: Vec4::splat(f32::NEG_INFINITY),
    };

    #[inline(always)]
    fn grow(&mut self, o: &Aabb) {
        self.min = self.min.min(o.min);
        self.max = self.max.max(o.max);
    }

    #[inline(always)]
    fn union(mut self, o: &Aabb) -> Aabb {
        self.grow(o);
        self
    }

    #[inline(always)]
    fn grow_point(&mut self, p: Vec4) {
        self.min = self.min.min(p);
        self.max = self.max.max(p);
    }

    pub(super) fn half_area(&self) -> f32 {
        let d = (self.max - self.min).max(Vec4::ZERO);
        d.x * d.y + d.y * d.z + d.z * d.x
    }
}

/// A triangle's box, 32 bytes: its scene index rides in the fourth lane of `min`
/// (as bits; indices below 2^27 are tiny positive floats, never NaN, so the
/// min/max of bin boxes leave them harmless).
#[derive(Clone, Copy)]
#[repr(C)]
pub(super) struct BuildPrim {
    bounds: Aabb,
}

impl BuildPrim {
    pub(super) fn new(t: &Triangle, id: u32) -> Self {
        let (lo, hi) = (t.min(), t.max());
        BuildPrim {
            bounds: Aabb {
                min: lo.extend(f32::from_bits(id)),
                max: hi.extend(0.0),
            },
        }
    }

    /// The triangle's index in the scene.
    pub(super) fn id(&self) -> u32 {
        self.bounds.min.w.to_bits()
    }

    /// Twice the centroid (the halving is folded into the bin scale).
    #[inline(always)]
    fn centroid2(&self) -> Vec4 {
        self.bounds.min + self.bounds.max
    }
}

/// Triangles that are to become one subtree: a run of the build array (from
/// `start`, relative to the slice it was split from), their boxes, and the split
/// the SAH chose for them (planned when the cluster is made, so that each run is
/// binned once however the wide tree takes its splits apart).
#[derive(Clone, Copy)]
pub(super) struct Cluster {
    pub(super) start: usize,
    pub(super) len: usize,
    pub(super) bounds: Aabb,
    /// Depth in the binary recursion, which bounds the SAH's depth.
    depth: usize,
    split: Split,
    /// The instructions the binning may use.
    isa: Isa,
    /// How leaves and boxes are priced.
    pricing: Pricing,
}

/// How the SAH prices a tree's leaves ([`leaf_cost`]) and boxes ([`Pricing::area`]).
#[derive(Clone, Copy, Debug)]
pub(super) struct Pricing {
    /// Two packets of a leaf tested in one pass (see [`PAIR_MIN`]).
    pairs: bool,
    /// Weight of a box's volume beside its half area (see [`ROOM_MAX`]).
    volume: f32,
}

impl Pricing {
    /// The price of visiting a box: its half area (the chance that a random
    /// line crosses it), plus, in small trees, its volume over a length (the
    /// chance that a ray starts or ends inside it).
    #[inline(always)]
    fn area(&self, b: &Aabb) -> f32 {
        let d = (b.max - b.min).max(Vec4::ZERO);
        d.x * d.y + d.y * d.z + d.z * d.x + self.volume * (d.x * d.y * d.z)
    }
}

#[derive(Clone, Copy)]
enum Split {
    /// One leaf.
    Leaf,
    /// Binned SAH: centroids in bins `..=bin` along `axis` go left; the triangle
    /// boxes of both sides (from the bins).
    Binned {
        axis: usize,
        bin: usize,
        sides: [Aabb; 2],
        grid: BinGrid,
    },
    /// No binned split (past [`MAX_SAH_DEPTH`], or all centroids in one bin) for
    /// more triangles than a leaf holds: half of them by centroid along the
    /// longest axis.
    Median,
    /// A packet's worth, already sorted: the first `mid` go left.
    Sorted(usize),
}

impl Cluster {
    /// The cluster of all of `prims` (its own slice), starting at `start`.
    pub(super) fn new(
        prims: &mut [BuildPrim],
        start: usize,
        bounds: Aabb,
        cbounds: Aabb,
        depth: usize,
        isa: Isa,
        pricing: Pricing,
    ) -> Self {
        let len = prims.len();
        // A few triangles are not worth binning: every split is tried exactly
        // (even one packet's worth: large triangles, as the lab box's walls, still
        // gain from being split apart).
        let split = if len <= EXACT_MAX && (len <= PACKET || depth < MAX_SAH_DEPTH) {
            exact_split(prims, &bounds, pricing).map_or(Split::Leaf, Split::Sorted)
        } else {
            let binned = if depth < MAX_SAH_DEPTH {
                best_split(prims, &cbounds, &bounds, isa, pricing)
            } else {
                None
            };
            match binned {
                Some((axis, bin, sides, grid)) => Split::Binned {
                    axis,
                    bin,
                    sides,
                    grid,
                },
                None if len <= MAX_LEAF => Split::Leaf,
                None => Split::Median,
            }
        };
        Cluster {
            start,
            len,
            bounds,
            depth,
            split,
            isa,
            pricing,
        }
    }

    /// The cluster of all the triangles.
    pub(super) fn root(prims: &mut [BuildPrim], isa: Isa) -> Self {
        let (bounds, cbounds) = bounds_of(prims);
        // Leaves of two packets are priced as one pass only in trees of many
        // triangles (see [`PAIR_MIN`]).
        let pairs = prims.len() >= PAIR_MIN;
        let extent = (bounds.max - bounds.min).truncate().max_element();
        let volume = if prims.len() <= ROOM_MAX && extent > 0.0 {
            ROOM_VOLUME / extent
        } else {
            0.0
        };
        Cluster::new(prims, 0, bounds, cbounds, 0, isa, Pricing { pairs, volume })
    }

    /// The same cluster, with `start` relative to its own run.
    pub(super) fn on_its_own(self) -> Self {
        Cluster { start: 0, ..self }
    }

    pub(super) fn is_leaf(&self) -> bool {
        matches!(self.split, Split::Leaf)
    }

    /// Splits the cluster as planned; `prims` is the slice `start` is relative to.
    pub(super) fn split(&self, prims: &mut [BuildPrim]) -> [Cluster; 2] {
        let mine = &mut prims[self.start..self.start + self.len];
        let (mid, [(lb, lc), (rb, rc)]) = match self.split {
            Split::Leaf => unreachable!("a leaf is not split"),
            Split::Binned {
                axis,
                bin,
                sides,
                grid,
            } => {
                let (mid, [lc, rc]) = partition(mine, |p| grid.at_most(p, axis, bin));
                (mid, [(sides[0], lc), (sides[1], rc)])
            }
            Split::Median => {
                let axis = (self.bounds.max - self.bounds.min)
                    .truncate()
                    .max_position();
                let mid = mine.len() / 2;
                mine.select_nth_unstable_by(mid, |a, b| {
                    a.centroid2()[axis].total_cmp(&b.centroid2()[axis])
                });
                let (l, r) = mine.split_at(mid);
                (mid, [bounds_of(l), bounds_of(r)])
            }
            Split::Sorted(mid) => {
                let (l, r) = mine.split_at(mid);
                (mid, [bounds_of(l), bounds_of(r)])
            }
        };
        let (l, r) = mine.split_at_mut(mid);
        let depth = self.depth + 1;
        [
            Cluster::new(l, self.start, lb, lc, depth, self.isa, self.pricing),
            Cluster::new(r, self.start + mid, rb, rc, depth, self.isa, self.pricing),
        ]
    }
}

/// Box of the triangles and box of their (doubled) centroids.
fn bounds_of(prims: &[BuildPrim]) -> (Aabb, Aabb) {
    let one = |prims: &[BuildPrim]| {
        let (mut b, mut c) = (Aabb::EMPTY, Aabb::EMPTY);
        let ahead = prims.len() >= PREFETCH_MIN;
        for (k, p) in prims.iter().enumerate() {
            if ahead {
                crate::memory::prefetch(prims.as_ptr().wrapping_add(k + PREFETCH_AHEAD));
            }
            b.grow(&p.bounds);
            c.grow_point(p.centroid2());
        }
        (b, c)
    };
    if prims.len() < PARALLEL_RUN_MIN {
        return one(prims);
    }
    prims.par_chunks(8192).map(one).reduce(
        || (Aabb::EMPTY, Aabb::EMPTY),
        |a, b| (a.0.union(&b.0), a.1.union(&b.1)),
    )
}

/// For at most [`EXACT_MAX`] triangles: the exact SAH-best split between their
/// centroids sorted along some axis (ordering them so, and returning the left
/// count), or `None` when one leaf is cheaper.
fn exact_split(prims: &mut [BuildPrim], bounds: &Aabb, pricing: Pricing) -> Option<usize> {
    let n = prims.len();
    assert!(n <= EXACT_MAX);
    let pairs = pricing.pairs;
    let area = pricing.area(bounds);
    let split_cost = TRAVERSAL_COST * area;
    let mut best_cost = leaf_cost(n as u32, pairs) * area;
    // One triangle is a leaf; two have one split (in centroid order along x).
    if n == 1 {
        return None;
    }
    if n == 2 {
        let [a, b] = [&prims[0], &prims[1]].map(|p| pricing.area(&p.bounds));
        if split_cost + a + b >= best_cost {
            return None;
        }
        if prims[0].centroid2().x > prims[1].centroid2().x {
            prims.swap(0, 1);
        }
        return Some(1);
    }
    let mut best: Option<([u8; EXACT_MAX], usize)> = None;
    let centroids: [Vec4; EXACT_MAX] = std::array::from_fn(|k| prims[k.min(n - 1)].centroid2());
    let keys: [[f32; EXACT_MAX]; 3] =
        std::array::from_fn(|axis| std::array::from_fn(|k| centroids[k][axis]));
    for keys in &keys {
        // Insertion sort of indices by centroid (stable: equal keys keep their order).
        let mut order: [u8; EXACT_MAX] = std::array::from_fn(|k| k as u8);
        let key = |k: u8| keys[k as usize];
        for i in 1..n {
            let item = order[i];
            let mut j = i;
            while j > 0 && key(order[j - 1]) > key(item) {
                order[j] = order[j - 1];
                j -= 1;
            }
            order[j] = item;
        }
        // Every right side's cost from the right, then each split's from the left.
        let mut right_cost = [0.0f32; EXACT_MAX];
        let mut acc = Aabb::EMPTY;
        for k in (1..n).rev() {
            acc.grow(&prims[order[k] as usize].bounds);
            right_cost[k] = pricing.area(&acc) * leaf_cost((n - k) as u32, pairs);
        }
        let mut acc = Aabb::EMPTY;
        for k in 1..n {
            acc.grow(&prims[order[k - 1] as usize].bounds);
            let cost = split_cost + pricing.area(&acc) * leaf_cost(k as u32, pairs) + right_cost[k];
            if cost < best_cost {
                best_cost = cost;
                best = Some((order, k));
            }
        }
    }
    let (order, mid) = best?;
    let copy: [BuildPrim; EXACT_MAX] = std::array::from_fn(|k| prims[k.min(n - 1)]);
    for (p, &k) in prims.iter_mut().zip(&order) {
        *p = copy[k as usize];
    }
    Some(mid)
}

/// SAH cost of a leaf of `n` triangles, in tests of one packet of four. With
/// `pairs`, two packets are tested together in one eight-wide pass, which costs
/// about [`PAIR_COST`] packet tests.
fn leaf_cost(n: u32, pairs: bool) -> f32 {
    let packets = n.div_ceil(4);
    if !pairs {
        return packets as f32;
    }
    (packets / 2) as f32 * PAIR_COST + (packets % 2) as f32
}

/// Cost of testing two packets together, relative to one.
const PAIR_COST: f32 = 1.25;
/// Trees of fewer triangles price leaves by packets, as if tested one at a time.
/// The lab box (30 triangles, every ray starting inside it) priced by pairs got
/// larger leaves that most rays enter: its `direct` frame took 10–15 % longer and
/// its `path` 3 % more instructions, while meshes gain 10–30 % (docs/performance.md).
const PAIR_MIN: usize = 256;
/// Trees of at most this many triangles price a box by its volume too
/// ([`Pricing::area`], [`ROOM_VOLUME`]): small scenes are often rooms, whose
/// rays start and end inside the scene's box, and a box that takes in much of
/// the room is entered by every ray that starts or ends in it, however small
/// its area. The lab box priced by area alone put each side wall in a leaf
/// with two faces of a block, boxes that most rays enter.
const ROOM_MAX: usize = PAIR_MIN;
/// The volume's weight, times the scene's largest extent. On the lab box 1, 2 and 4
/// give the same tree (0.5 a worse one): walls in leaves of their own, the blocks
/// apart from them.
const ROOM_VOLUME: f32 = 2.0;

/// The mapping of (doubled) centroids to `bins` bins on all three axes at once.
#[derive(Clone, Copy)]
struct BinGrid {
    lo: Vec4,
    scale: Vec4,
    /// The last bin's index, in every lane.
    last: Vec4,
}

impl BinGrid {
    fn new(cbounds: &Aabb, bins: usize) -> Self {
        // A flat axis gets scale inf or NaN; its indices are clamped into range all
        // the same, and no split is ever chosen on it.
        BinGrid {
            lo: cbounds.min,
            scale: Vec4::splat(bins as f32) / (cbounds.max - cbounds.min),
            last: Vec4::splat((bins - 1) as f32),
        }
    }

    /// Bin indices on x, y, z (and an unused fourth lane), each in `0..bins`.
    #[inline(always)]
    fn bins_of(&self, p: &BuildPrim) -> [u32; 4] {
        // `min` and `max` return their second operand for NaN: the result is in range.
        let f = ((p.centroid2() - self.lo) * self.scale)
            .min(self.last)
            .max(Vec4::ZERO);
        truncate(f)
    }

    /// `bins_of(p)[axis] <= bin` for `bin` below the last, on that axis alone: the
    /// bin index truncates the same float clamped to `[0, last]`, so it is at most
    /// `bin` exactly when the float is below `bin + 1` (NaN, clamped to the last
    /// bin, is not).
    #[inline(always)]
    fn at_most(&self, p: &BuildPrim, axis: usize, bin: usize) -> bool {
        // Scalar loads of the one axis (the same sum as `centroid2`'s lane).
        let c = p.bounds.min[axis] + p.bounds.max[axis];
        (c - self.lo[axis]) * self.scale[axis] < (bin + 1) as f32
    }
}

/// Lane-wise truncation of floats known to lie in `[0, 2^31)`.
#[inline(always)]
fn truncate(f: Vec4) -> [u32; 4] {
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::x86_64::{__m128, __m128i, _mm_cvttps_epi32};
        // SAFETY: SSE2 is part of x86-64; both types are 16 bytes of plain integers.
        unsafe {
            let i: __m128i = _mm_cvttps_epi32(__m128::from(f));
            std::mem::transmute::<__m128i, [u32; 4]>(i)
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        f.to_array().map(|x| x as u32)
    }
}

/// A bin's box as its minimum and its negated maximum: growing it is then one
/// eight-wide minimum (with AVX), and an empty box is all +inf.
#[derive(Clone, Copy)]
#[repr(C, align(32))]
struct BinBox {
    lo: Vec4,
    neg_hi: Vec4,
}

impl BinBox {
    const EMPTY: BinBox = BinBox {
        lo: Vec4::INFINITY,
        neg_hi: Vec4::INFINITY,
    };

    #[inline(always)]
    fn grow(&mut self, lo: Vec4, neg_hi: Vec4) {
        self.lo = self.lo.min(lo);
        self.neg_hi = self.neg_hi.min(neg_hi);
    }

    fn aabb(&self) -> Aabb {
        Aabb {
            min: self.lo,
            max: -self.neg_hi,
        }
    }
}

/// Triangle boxes per bin for the three axes, and counts per bin with one lane
/// per axis; `SLOTS` bins per axis, a power of two (at least the bins used).
#[derive(Clone, Copy)]
struct Bins<const SLOTS: usize> {
    boxes: [[BinBox; SLOTS]; 3],
    counts: [[u32; 4]; SLOTS],
}

impl<const SLOTS: usize> Bins<SLOTS> {
    #[inline(always)]
    fn empty() -> Self {
        Bins {
            boxes: [[BinBox::EMPTY; SLOTS]; 3],
            counts: [[0; 4]; SLOTS],
        }
    }

    /// Adds `prims` to the bins (in place: a `Bins` is 1.8 KB, and moving it
    /// around cost more than filling it for small nodes).
    fn fill(&mut self, isa: Isa, grid: &BinGrid, prims: &[BuildPrim]) {
        match isa {
            // SAFETY: `Isa::Avx2` is only chosen when the CPU has AVX2.
            #[cfg(target_arch = "x86_64")]
            Isa::Avx2 => unsafe { self.fill_avx2(grid, prims) },
            Isa::Portable => self.fill_portable(grid, prims),
        }
    }

    fn fill_portable(&mut self, grid: &BinGrid, prims: &[BuildPrim]) {
        if prims.len() >= PREFETCH_MIN {
            self.fill_with::<true>(grid, prims, |b, p| b.grow(p.bounds.min, -p.bounds.max))
        } else {
            self.fill_with::<false>(grid, prims, |b, p| b.grow(p.bounds.min, -p.bounds.max))
        }
    }

    /// The same as the portable fill, each box grown by one eight-wide minimum.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    fn fill_avx2(&mut self, grid: &BinGrid, prims: &[BuildPrim]) {
        use std::arch::x86_64::{
            __m256, _mm256_load_ps, _mm256_loadu_ps, _mm256_min_ps, _mm256_set_ps, _mm256_store_ps,
            _mm256_xor_ps,
        };
        let grow = |b: &mut BinBox, p: &BuildPrim| {
            // SAFETY: a `BuildPrim` is eight floats (minimum, maximum) and a `BinBox`
            // eight floats aligned to 32 bytes (minimum, negated maximum).
            unsafe {
                let neg_hi = _mm256_set_ps(-0.0, -0.0, -0.0, -0.0, 0.0, 0.0, 0.0, 0.0);
                let prim: __m256 = _mm256_loadu_ps((p as *const BuildPrim).cast());
                let b = (b as *mut BinBox).cast::<f32>();
                _mm256_store_ps(
                    b,
                    _mm256_min_ps(_mm256_load_ps(b), _mm256_xor_ps(prim, neg_hi)),
                );
            }
        };
        if prims.len() >= PREFETCH_MIN {
            self.fill_with::<true>(grid, prims, grow)
        } else {
            self.fill_with::<false>(grid, prims, grow)
        }
    }

    #[inline(always)]
    fn fill_with<const PREFETCH: bool>(
        &mut self,
        grid: &BinGrid,
        prims: &[BuildPrim],
        grow: impl Fn(&mut BinBox, &BuildPrim),
    ) {
        for (k, p) in prims.iter().enumerate() {
            if PREFETCH {
                crate::memory::prefetch(prims.as_ptr().wrapping_add(k + PREFETCH_AHEAD));
            }
            let index = grid.bins_of(p);
            for (axis, &i) in index[..3].iter().enumerate() {
                // The mask lets the compiler drop the bounds check (indices < SLOTS).
                let i = i as usize & (SLOTS - 1);
                grow(&mut self.boxes[axis][i], p);
                self.counts[i][axis] += 1;
            }
        }
    }

    /// Triangles in bin `i` of `axis`.
    fn count(&self, axis: usize, i: usize) -> u32 {
        self.counts[i][axis]
    }

    fn merge(mut self, o: &Self) -> Self {
        for i in 0..SLOTS {
            for axis in 0..3 {
                let other = o.boxes[axis][i];
                self.boxes[axis][i].grow(other.lo, other.neg_hi);
                self.counts[i][axis] += o.counts[i][axis];
            }
        }
        self
    }

    fn bin(&self, axis: usize, i: usize) -> Aabb {
        self.boxes[axis][i].aabb()
    }
}

/// The growing boxes of one sweep over the bins, on the three axes at once.
struct Sweep {
    boxes: [Aabb; 3],
    counts: [u32; 4],
}

impl Sweep {
    fn new() -> Self {
        Sweep {
            boxes: [Aabb::EMPTY; 3],
            counts: [0; 4],
        }
    }

    /// Takes in bin `i` of every axis.
    #[inline(always)]
    fn add<const SLOTS: usize>(&mut self, bins: &Bins<SLOTS>, i: usize) {
        for axis in 0..3 {
            self.boxes[axis].grow(&bins.bin(axis, i));
            self.counts[axis] += bins.count(axis, i);
        }
    }

    /// Half area times leaf cost of the boxes so far, one lane per axis (the same
    /// operations as [`Aabb::half_area`] and [`leaf_cost`], lane by lane).
    #[inline(always)]
    fn cost(&self, pricing: Pricing) -> Vec4 {
        let pairs = pricing.pairs;
        let d = self.boxes.map(|b| (b.max - b.min).max(Vec4::ZERO));
        let x = Vec4::new(d[0].x, d[1].x, d[2].x, 0.0);
        let y = Vec4::new(d[0].y, d[1].y, d[2].y, 0.0);
        let z = Vec4::new(d[0].z, d[1].z, d[2].z, 0.0);
        let c = self.counts;
        let leaf = Vec4::new(
            leaf_cost(c[0], pairs),
            leaf_cost(c[1], pairs),
            leaf_cost(c[2], pairs),
            0.0,
        );
        (x * y + y * z + z * x + Vec4::splat(pricing.volume) * (x * y * z)) * leaf
    }
}

/// The binned SAH's best split of `prims` as `(axis, last bin of the left side,
/// the sides' boxes, the grid)`, with [`FEW_BINS`] bins for runs under
/// [`MANY_BINS_MIN`] triangles and [`MANY_BINS`] otherwise; or `None` when the
/// centroids fall in one bin on every axis. The run is too big for a leaf.
fn best_split(
    prims: &[BuildPrim],
    cbounds: &Aabb,
    bounds: &Aabb,
    isa: Isa,
    pricing: Pricing,
) -> Option<BinSplit> {
    let run = BinRun {
        prims,
        cbounds,
        bounds,
        isa,
        pricing,
    };
    if prims.len() < MANY_BINS_MIN {
        best_split_in::<FEW_BINS, { FEW_BINS.next_power_of_two() }>(run)
    } else {
        best_split_in::<MANY_BINS, { MANY_BINS.next_power_of_two() }>(run)
    }
}

/// A binned split: the axis, the last bin of the left side, the triangle boxes of
/// both sides and the grid.
type BinSplit = (usize, usize, [Aabb; 2], BinGrid);

/// What [`best_split_in`] splits: the triangles, the boxes of their centroids and
/// of themselves, the instructions the binning may use and how leaves are priced.
struct BinRun<'a> {
    prims: &'a [BuildPrim],
    cbounds: &'a Aabb,
    bounds: &'a Aabb,
    isa: Isa,
    pricing: Pricing,
}

fn best_split_in<const BINS: usize, const SLOTS: usize>(run: BinRun<'_>) -> Option<BinSplit> {
    let BinRun {
        prims,
        cbounds,
        bounds,
        isa,
        pricing,
    } = run;
    const { assert!(BINS <= SLOTS && SLOTS.is_power_of_two()) };
    let grid = BinGrid::new(cbounds, BINS);
    // Filled in place (the serial case is the common one: no copy of 1.8 KB).
    let mut bins = Bins::<SLOTS>::empty();
    if prims.len() < PARALLEL_RUN_MIN {
        bins.fill(isa, &grid, prims);
    } else {
        bins = prims
            .par_chunks(8192)
            .map(|chunk| {
                let mut bins = Bins::empty();
                bins.fill(isa, &grid, chunk);
                bins
            })
            .reduce(Bins::empty, |a, b| a.merge(&b));
    }
    debug_assert!(prims.len() > MAX_LEAF, "smaller runs take the exact split");
    // Costs are compared multiplied by the parent's area (no division per bin).
    let parent_area = pricing.area(bounds);
    let split_cost = Vec4::splat(TRAVERSAL_COST * parent_area);
    // Sweep from the right for every right side's cost, then from the left; the
    // three axes side by side, each lane keeping its first cheapest bin.
    let mut right_cost = [Vec4::ZERO; BINS];
    let mut sweep = Sweep::new();
    for i in (1..BINS).rev() {
        sweep.add(&bins, i);
        right_cost[i] = sweep.cost(pricing);
    }
    let mut best_cost = Vec4::INFINITY;
    let mut best_bin = [usize::MAX; 3];
    let mut sweep = Sweep::new();
    let n = prims.len() as u32;
    for i in 0..BINS - 1 {
        sweep.add(&bins, i);
        let cost = split_cost + sweep.cost(pricing) + right_cost[i + 1];
        let better = cost.cmplt(best_cost).bitmask();
        if better == 0 {
            continue;
        }
        for axis in 0..3 {
            let count = sweep.counts[axis];
            if better & 1 << axis != 0 && count != 0 && count != n {
                best_cost[axis] = cost[axis];
                best_bin[axis] = i;
            }
        }
    }
    // The cheapest axis (the first of equals); a flat axis (all centroids in one
    // bin) never has a bin.
    let mut best: Option<(usize, usize)> = None;
    let mut cheapest = f32::INFINITY;
    for axis in 0..3 {
        let flat = cbounds.max[axis] - cbounds.min[axis] <= 0.0;
        if best_bin[axis] != usize::MAX && !flat && best_cost[axis] < cheapest {
            cheapest = best_cost[axis];
            best = Some((axis, best_bin[axis]));
        }
    }
    let (axis, bin) = best?;
    let side = |range: std::ops::Range<usize>| {
        range.fold(Aabb::EMPTY, |acc, i| acc.union(&bins.bin(axis, i)))
    };
    Some((axis, bin, [side(0..bin + 1), side(bin + 1..BINS)], grid))
}

/// Moves the triangles for which `left` holds to the front; returns how many
/// there are, and the centroid boxes of both sides. Large runs are partitioned
/// in blocks in parallel, then the misplaced triangles swapped across.
fn partition(
    prims: &mut [BuildPrim],
    left: impl Fn(&BuildPrim) -> bool + Sync,
) -> (usize, [Aabb; 2]) {
    if prims.len() < PARALLEL_RUN_MIN {
        return partition_block(prims, &left);
    }
    // Fixed blocks: the result does not depend on the number of threads.
    let blocks: Vec<(usize, [Aabb; 2])> = prims
        .par_chunks_mut(PARTITION_BLOCK)
        .map(|block| partition_block(block, &left))
        .collect();
    let mid: usize = blocks.iter().map(|b| b.0).sum();
    let mut boxes = [Aabb::EMPTY; 2];
    for (_, [l, r]) in &blocks {
        boxes[0].grow(l);
        boxes[1].grow(r);
    }
    // Each block is [left | right]. The right runs that lie before `mid` trade
    // places with the left runs that lie from `mid` on (as many), in order.
    let n = prims.len();
    let block = |k: usize| k * PARTITION_BLOCK..((k + 1) * PARTITION_BLOCK).min(n);
    let mut holes = blocks.iter().enumerate().filter_map(|(k, &(l, _))| {
        let (from, to) = (block(k).start + l, block(k).end.min(mid));
        (from < to).then_some(from..to)
    });
    let mut strays = blocks.iter().enumerate().filter_map(|(k, &(l, _))| {
        let (from, to) = (block(k).start.max(mid), block(k).start + l);
        (from < to).then_some(from..to)
    });
    let (mut hole, mut stray) = (holes.next(), strays.next());
    while let (Some(h), Some(s)) = (&mut hole, &mut stray) {
        let len = h.len().min(s.len());
        // Holes lie before `mid`, strays from it on.
        let (front, back) = prims.split_at_mut(s.start);
        front[h.start..h.start + len].swap_with_slice(&mut back[..len]);
        h.start += len;
        s.start += len;
        if h.start == h.end {
            hole = holes.next();
        }
        if s.start == s.end {
            stray = strays.next();
        }
    }
    (mid, boxes)
}

/// Hoare partition of one block: swaps only the misplaced pairs.
fn partition_block(
    prims: &mut [BuildPrim],
    left: &impl Fn(&BuildPrim) -> bool,
) -> (usize, [Aabb; 2]) {
    if prims.len() >= PREFETCH_MIN {
        partition_with::<true>(prims, left)
    } else {
        partition_with::<false>(prims, left)
    }
}

#[inline(always)]
fn partition_with<const PREFETCH: bool>(
    prims: &mut [BuildPrim],
    left: impl Fn(&BuildPrim) -> bool,
) -> (usize, [Aabb; 2]) {
    let mut boxes = [Aabb::EMPTY; 2];
    let add = |side: &mut Aabb, p: &BuildPrim| side.grow_point(p.centroid2());
    let (mut i, mut j) = (0, prims.len());
    let base = prims.as_ptr();
    loop {
        while i < j && left(&prims[i]) {
            add(&mut boxes[0], &prims[i]);
            if PREFETCH {
                crate::memory::prefetch(base.wrapping_add(i + PREFETCH_AHEAD));
            }
            i += 1;
        }
        while i < j && !left(&prims[j - 1]) {
            add(&mut boxes[1], &prims[j - 1]);
            if PREFETCH {
                crate::memory::prefetch(base.wrapping_add(j).wrapping_sub(PREFETCH_AHEAD));
            }
            j -= 1;
        }
        if i == j {
            return (i, boxes);
        }
        prims.swap(i, j - 1);
        add(&mut boxes[0], &prims[i]);
        add(&mut boxes[1], &prims[j - 1]);
        i += 1;
        j -= 1;
    }
}
