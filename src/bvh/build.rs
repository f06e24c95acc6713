//! Binned-SAH construction of a binary tree, the first step of the BVH build.
//!
//! One pass over a node's triangles bins their centroids on all three axes at
//! once; large nodes bin in parallel, and the two halves of every split larger
//! than [`PARALLEL_MIN`] are built in parallel (rayon's `join`).

use glam::Vec4;
use rayon::prelude::*;

use crate::triangle::Triangle;

const BINS: usize = 12;
/// Triangles per leaf packet.
const PACKET: usize = 4;
/// Largest leaf, in triangles: two four-wide packets.
pub(super) const MAX_LEAF: usize = 8;
/// Cost of visiting a node relative to testing one packet of four triangles.
const TRAVERSAL_COST: f32 = 0.3;
/// Past this depth only median splits, which bound the depth by log2(n).
pub(super) const MAX_SAH_DEPTH: usize = 64;
/// Subtrees at least this big are built in parallel with their siblings.
const PARALLEL_MIN: usize = 4096;
/// Nodes at least this big are binned in parallel.
const PARALLEL_BINNING_MIN: usize = 65_536;

/// An axis-aligned box in the first three lanes of two `Vec4`s (the fourth lane is
/// carried along unused: it holds a triangle's index in a [`BuildPrim`]).
#[derive(Clone, Copy, Debug)]
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

/// A node of the binary tree: a leaf with `count` triangles from `first` on (in
/// build order), or an inner node owning its two children.
pub(super) enum BinNode {
    Leaf {
        bounds: Aabb,
        first: usize,
        count: usize,
    },
    Inner {
        bounds: Aabb,
        count: usize,
        children: Box<[BinNode; 2]>,
    },
}

impl BinNode {
    pub(super) fn bounds(&self) -> &Aabb {
        match self {
            BinNode::Leaf { bounds, .. } | BinNode::Inner { bounds, .. } => bounds,
        }
    }

    /// Triangles in the subtree.
    pub(super) fn count(&self) -> usize {
        match self {
            BinNode::Leaf { count, .. } | BinNode::Inner { count, .. } => *count,
        }
    }
}

/// A triangle's box, 32 bytes: its scene index rides in the fourth lane of `min`
/// (as bits; indices below 2^27 are tiny positive floats, never NaN, so the
/// min/max of bin boxes leave them harmless).
#[derive(Clone, Copy)]
pub(super) struct BuildPrim {
    bounds: Aabb,
}

impl BuildPrim {
    fn new(t: &Triangle, id: u32) -> Self {
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

/// A binary tree over the triangles that can be hit (finite, non-zero area), and
/// those triangles in leaf order; `None` when there are none.
pub(super) fn build_binary(triangles: &[Triangle]) -> Option<(BinNode, Vec<BuildPrim>)> {
    assert!(
        triangles.len() < 1 << 27,
        "too many triangles for the BVH (at most 2^27)"
    );
    // Mapped in parallel into place; the few that cannot be hit (if any) are
    // dropped afterwards (a parallel filter would gather pieces and copy them).
    let valid = |t: &Triangle| t.is_finite() && t.area() > 0.0;
    let mut prims: Vec<BuildPrim> = Vec::new();
    triangles
        .par_iter()
        .enumerate()
        .map(|(i, t)| BuildPrim::new(t, i as u32))
        .collect_into_vec(&mut prims);
    if !triangles.par_iter().all(valid) {
        prims.retain(|p| valid(&triangles[p.id() as usize]));
    }
    if prims.is_empty() {
        return None;
    }
    let (bounds, cbounds) = bounds_of(&prims);
    let root = build_range(&mut prims, 0, 0, bounds, cbounds);
    Some((root, prims))
}

/// Box of the triangles and box of their (doubled) centroids.
fn bounds_of(prims: &[BuildPrim]) -> (Aabb, Aabb) {
    let one = |prims: &[BuildPrim]| {
        let (mut b, mut c) = (Aabb::EMPTY, Aabb::EMPTY);
        for p in prims {
            b.grow(&p.bounds);
            c.grow_point(p.centroid2());
        }
        (b, c)
    };
    if prims.len() < PARALLEL_BINNING_MIN {
        return one(prims);
    }
    prims.par_chunks(8192).map(one).reduce(
        || (Aabb::EMPTY, Aabb::EMPTY),
        |a, b| (a.0.union(&b.0), a.1.union(&b.1)),
    )
}

/// Builds the subtree of `prims`, which start at index `first` of the full array;
/// `bounds` and `cbounds` are the boxes of their triangles and centroids.
fn build_range(
    prims: &mut [BuildPrim],
    first: usize,
    depth: usize,
    bounds: Aabb,
    cbounds: Aabb,
) -> BinNode {
    let count = prims.len();
    let leaf = || BinNode::Leaf {
        bounds,
        first,
        count,
    };
    // Up to four triangles fit one packet: binning is not worth it; try the few
    // possible splits exactly (large triangles, as the lab box's walls, still
    // gain from being split apart).
    if prims.len() <= PACKET {
        return match small_split(prims, &bounds) {
            None => leaf(),
            Some(mid) => {
                let (l, r) = prims.split_at_mut(mid);
                let ((lb, lc), (rb, rc)) = (bounds_of(l), bounds_of(r));
                BinNode::Inner {
                    bounds,
                    count,
                    children: Box::new([
                        build_range(l, first, depth + 1, lb, lc),
                        build_range(r, first + mid, depth + 1, rb, rc),
                    ]),
                }
            }
        };
    }
    let split = if depth < MAX_SAH_DEPTH {
        best_split(prims, &cbounds, &bounds)
    } else {
        None
    };
    let (mid, boxes) = match split {
        Some((axis, bin)) => {
            let grid = BinGrid::new(&cbounds);
            partition(prims, |p| grid.at_most(p, axis, bin))
        }
        None if prims.len() <= MAX_LEAF => return leaf(),
        None => {
            // SAH prefers a leaf (or centroids coincide) but the leaf would be too
            // big: split in the middle of the longest axis by object count.
            let axis = (bounds.max - bounds.min).truncate().max_position();
            let mid = prims.len() / 2;
            prims.select_nth_unstable_by(mid, |a, b| {
                a.centroid2()[axis].total_cmp(&b.centroid2()[axis])
            });
            let (l, r) = prims.split_at(mid);
            (mid, [bounds_of(l), bounds_of(r)])
        }
    };
    let [(lb, lc), (rb, rc)] = boxes;
    let (left, right) = prims.split_at_mut(mid);
    let children = if left.len().min(right.len()) >= PARALLEL_MIN {
        let (l, r) = rayon::join(
            || build_range(left, first, depth + 1, lb, lc),
            || build_range(right, first + mid, depth + 1, rb, rc),
        );
        [l, r]
    } else {
        [
            build_range(left, first, depth + 1, lb, lc),
            build_range(right, first + mid, depth + 1, rb, rc),
        ]
    };
    BinNode::Inner {
        bounds,
        count,
        children: Box::new(children),
    }
}

/// For at most one packet of triangles: the exact SAH-best split (sorting them by
/// centroid along the best axis and returning the left count), or `None` when one
/// leaf is cheaper.
fn small_split(prims: &mut [BuildPrim], bounds: &Aabb) -> Option<usize> {
    let area = bounds.half_area();
    // A leaf costs one packet test; a split at least a traversal step plus one
    // packet test in each child the ray enters.
    let mut best = (area, None);
    for axis in 0..3 {
        prims.sort_unstable_by(|a, b| a.centroid2()[axis].total_cmp(&b.centroid2()[axis]));
        for mid in 1..prims.len() {
            let (l, r) = prims.split_at(mid);
            let cost =
                TRAVERSAL_COST * area + bounds_of(l).0.half_area() + bounds_of(r).0.half_area();
            if cost < best.0 {
                best = (cost, Some((axis, mid)));
            }
        }
    }
    let (axis, mid) = best.1?;
    prims.sort_unstable_by(|a, b| a.centroid2()[axis].total_cmp(&b.centroid2()[axis]));
    Some(mid)
}

/// SAH cost of a leaf of `n` triangles: one test per packet of four.
fn leaf_cost(n: u32) -> f32 {
    n.div_ceil(4) as f32
}

/// The mapping of (doubled) centroids to bins on all three axes at once.
struct BinGrid {
    lo: Vec4,
    scale: Vec4,
}

impl BinGrid {
    fn new(cbounds: &Aabb) -> Self {
        // A flat axis gets scale inf or NaN; its indices are clamped into range all
        // the same, and no split is ever chosen on it.
        BinGrid {
            lo: cbounds.min,
            scale: Vec4::splat(BINS as f32) / (cbounds.max - cbounds.min),
        }
    }

    /// Bin indices on x, y, z (and an unused fourth lane), each in `0..BINS`.
    #[inline(always)]
    fn bins_of(&self, p: &BuildPrim) -> [u32; 4] {
        // `min` and `max` return their second operand for NaN: the result is in range.
        let f = ((p.centroid2() - self.lo) * self.scale)
            .min(Vec4::splat((BINS - 1) as f32))
            .max(Vec4::ZERO);
        truncate(f)
    }

    /// `bins_of(p)[axis] <= bin` for `bin < BINS - 1`, on that axis alone: the bin
    /// index truncates the same float clamped to `[0, BINS - 1]`, so it is at most
    /// `bin` exactly when the float is below `bin + 1` (NaN, clamped to the last
    /// bin, is not).
    #[inline(always)]
    fn at_most(&self, p: &BuildPrim, axis: usize, bin: usize) -> bool {
        (p.centroid2()[axis] - self.lo[axis]) * self.scale[axis] < (bin + 1) as f32
    }
}

/// Lane-wise truncation of floats known to lie in `[0, BINS)`.
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

/// Triangle boxes and counts per bin, for the three axes.
#[derive(Clone, Copy)]
struct Bins {
    boxes: [[Aabb; BIN_SLOTS]; 3],
    counts: [[u32; BIN_SLOTS]; 3],
}

/// Bins allocated per axis: a power of two at least [`BINS`].
const BIN_SLOTS: usize = BINS.next_power_of_two();

impl Bins {
    fn empty() -> Self {
        Bins {
            boxes: [[Aabb::EMPTY; BIN_SLOTS]; 3],
            counts: [[0; BIN_SLOTS]; 3],
        }
    }

    /// Adds `prims` to the bins (in place: a `Bins` is 1.3 KB, and moving it
    /// around cost more than filling it for small nodes).
    fn fill(&mut self, grid: &BinGrid, prims: &[BuildPrim]) {
        for p in prims {
            let index = grid.bins_of(p);
            for (axis, &i) in index[..3].iter().enumerate() {
                // The mask lets the compiler drop the bounds check (indices < BINS).
                let i = i as usize & (BIN_SLOTS - 1);
                self.boxes[axis][i].grow(&p.bounds);
                self.counts[axis][i] += 1;
            }
        }
    }

    fn merge(mut self, o: &Bins) -> Self {
        for axis in 0..3 {
            for i in 0..BINS {
                self.boxes[axis][i].grow(&o.boxes[axis][i]);
                self.counts[axis][i] += o.counts[axis][i];
            }
        }
        self
    }
}

/// The SAH-best split as `(axis, last bin of the left side)`, or `None` when a leaf is
/// cheaper (and small enough) or all centroids coincide.
fn best_split(prims: &[BuildPrim], cbounds: &Aabb, bounds: &Aabb) -> Option<(usize, usize)> {
    let grid = BinGrid::new(cbounds);
    let bins = if prims.len() < PARALLEL_BINNING_MIN {
        let mut bins = Bins::empty();
        bins.fill(&grid, prims);
        bins
    } else {
        prims
            .par_chunks(8192)
            .map(|chunk| {
                let mut bins = Bins::empty();
                bins.fill(&grid, chunk);
                bins
            })
            .reduce(Bins::empty, |a, b| a.merge(&b))
    };
    let mut best: Option<(usize, usize)> = None;
    // Costs are compared multiplied by the parent's area (no division per bin).
    let parent_area = bounds.half_area();
    let mut best_cost = if prims.len() <= MAX_LEAF {
        leaf_cost(prims.len() as u32) * parent_area
    } else {
        f32::INFINITY
    };
    let split_cost = TRAVERSAL_COST * parent_area;
    for axis in 0..3 {
        if cbounds.max[axis] - cbounds.min[axis] <= 0.0 {
            continue;
        }
        let (boxes, counts) = (&bins.boxes[axis][..BINS], &bins.counts[axis][..BINS]);
        // Sweep from the right for every right side's cost, then from the left.
        let mut right_cost = [0.0f32; BINS];
        let (mut acc, mut count) = (Aabb::EMPTY, 0);
        for i in (1..BINS).rev() {
            acc.grow(&boxes[i]);
            count += counts[i];
            right_cost[i] = acc.half_area() * leaf_cost(count);
        }
        let (mut acc, mut count) = (Aabb::EMPTY, 0);
        for i in 0..BINS - 1 {
            acc.grow(&boxes[i]);
            count += counts[i];
            if count == 0 || count as usize == prims.len() {
                continue;
            }
            let cost = split_cost + acc.half_area() * leaf_cost(count) + right_cost[i + 1];
            if cost < best_cost {
                best_cost = cost;
                best = Some((axis, i));
            }
        }
    }
    best
}

/// Moves the triangles for which `left` holds to the front, swapping only the
/// misplaced pairs (Hoare); returns how many there are, and the triangle and
/// centroid boxes of both sides.
fn partition(
    prims: &mut [BuildPrim],
    left: impl Fn(&BuildPrim) -> bool,
) -> (usize, [(Aabb, Aabb); 2]) {
    let mut boxes = [(Aabb::EMPTY, Aabb::EMPTY); 2];
    let add = |side: &mut (Aabb, Aabb), p: &BuildPrim| {
        side.0.grow(&p.bounds);
        side.1.grow_point(p.centroid2());
    };
    let (mut i, mut j) = (0, prims.len());
    loop {
        while i < j && left(&prims[i]) {
            add(&mut boxes[0], &prims[i]);
            i += 1;
        }
        while i < j && !left(&prims[j - 1]) {
            add(&mut boxes[1], &prims[j - 1]);
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
