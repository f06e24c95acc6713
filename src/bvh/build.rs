//! Binned-SAH construction of a binary tree, the first step of the BVH build.
//!
//! One pass over a node's triangles bins their centroids on all three axes at
//! once; large nodes bin in parallel, and the two halves of every split larger
//! than [`PARALLEL_MIN`] are built in parallel (rayon's `join`).

use glam::Vec3A;
use rayon::prelude::*;

use crate::triangle::Triangle;

const BINS: usize = 12;
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

/// An axis-aligned box.
#[derive(Clone, Copy, Debug)]
pub(super) struct Aabb {
    pub(super) min: Vec3A,
    pub(super) max: Vec3A,
}

impl Aabb {
    pub(super) const EMPTY: Aabb = Aabb {
        min: Vec3A::splat(f32::INFINITY),
        max: Vec3A::splat(f32::NEG_INFINITY),
    };

    #[inline]
    fn grow(&mut self, o: &Aabb) {
        self.min = self.min.min(o.min);
        self.max = self.max.max(o.max);
    }

    #[inline]
    fn union(mut self, o: &Aabb) -> Aabb {
        self.grow(o);
        self
    }

    #[inline]
    fn grow_point(&mut self, p: Vec3A) {
        self.min = self.min.min(p);
        self.max = self.max.max(p);
    }

    pub(super) fn half_area(&self) -> f32 {
        let d = (self.max - self.min).max(Vec3A::ZERO);
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
        children: Box<[BinNode; 2]>,
    },
}

impl BinNode {
    pub(super) fn bounds(&self) -> &Aabb {
        match self {
            BinNode::Leaf { bounds, .. } | BinNode::Inner { bounds, .. } => bounds,
        }
    }
}

/// A triangle's box and its index in the scene.
#[derive(Clone, Copy)]
pub(super) struct BuildPrim {
    bounds: Aabb,
    pub(super) id: u32,
}

impl BuildPrim {
    #[inline]
    fn centroid(&self) -> Vec3A {
        (self.bounds.min + self.bounds.max) * 0.5
    }
}

/// A binary tree over the triangles that can be hit (finite, non-zero area), and
/// those triangles in leaf order; `None` when there are none.
pub(super) fn build_binary(triangles: &[Triangle]) -> Option<(BinNode, Vec<BuildPrim>)> {
    let mut prims: Vec<BuildPrim> = triangles
        .par_iter()
        .enumerate()
        .filter(|(_, t)| t.is_finite() && t.area() > 0.0)
        .map(|(i, t)| BuildPrim {
            bounds: Aabb {
                min: t.min(),
                max: t.max(),
            },
            id: i as u32,
        })
        .collect();
    if prims.is_empty() {
        return None;
    }
    let (bounds, cbounds) = bounds_of(&prims);
    let root = build_range(&mut prims, 0, 0, bounds, cbounds);
    Some((root, prims))
}

/// Box of the triangles and box of their centroids.
fn bounds_of(prims: &[BuildPrim]) -> (Aabb, Aabb) {
    let one = |prims: &[BuildPrim]| {
        let (mut b, mut c) = (Aabb::EMPTY, Aabb::EMPTY);
        for p in prims {
            b.grow(&p.bounds);
            c.grow_point(p.centroid());
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
    let leaf = || BinNode::Leaf {
        bounds,
        first,
        count: prims.len(),
    };
    if prims.len() == 1 {
        return leaf();
    }
    let split = if depth < MAX_SAH_DEPTH {
        best_split(prims, &cbounds, &bounds)
    } else {
        None
    };
    let (mid, boxes) = match split {
        Some((axis, bin)) => {
            let (lo, scale) = bin_scale(&cbounds, axis);
            partition(prims, |p| bin_of(p.centroid()[axis], lo, scale) <= bin)
        }
        None if prims.len() <= MAX_LEAF => return leaf(),
        None => {
            // SAH prefers a leaf (or centroids coincide) but the leaf would be too
            // big: split in the middle of the longest axis by object count.
            let axis = (bounds.max - bounds.min).max_position();
            let mid = prims.len() / 2;
            prims.select_nth_unstable_by(mid, |a, b| {
                a.centroid()[axis].total_cmp(&b.centroid()[axis])
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
        children: Box::new(children),
    }
}

/// SAH cost of a leaf of `n` triangles: one test per packet of four.
fn leaf_cost(n: u32) -> f32 {
    n.div_ceil(4) as f32
}

/// Where the centroid bins of `axis` start and how many bins a unit spans.
fn bin_scale(cbounds: &Aabb, axis: usize) -> (f32, f32) {
    let lo = cbounds.min[axis];
    let extent = cbounds.max[axis] - lo;
    (lo, BINS as f32 / extent)
}

#[inline]
fn bin_of(c: f32, lo: f32, scale: f32) -> usize {
    (((c - lo) * scale) as usize).min(BINS - 1)
}

/// Triangle boxes and counts per bin, for the three axes.
#[derive(Clone, Copy)]
struct Bins([[(Aabb, u32); BINS]; 3]);

impl Bins {
    fn empty() -> Self {
        Bins([[(Aabb::EMPTY, 0); BINS]; 3])
    }

    fn merge(mut self, o: &Bins) -> Self {
        for (a, b) in self.0.iter_mut().zip(&o.0) {
            for (x, y) in a.iter_mut().zip(b) {
                x.0.grow(&y.0);
                x.1 += y.1;
            }
        }
        self
    }
}

/// The SAH-best split as `(axis, last bin of the left side)`, or `None` when a leaf is
/// cheaper (and small enough) or all centroids coincide.
fn best_split(prims: &[BuildPrim], cbounds: &Aabb, bounds: &Aabb) -> Option<(usize, usize)> {
    // Bin indices on all three axes at once (a flat axis gets scale inf or NaN and
    // is skipped below; its indices are clamped into range all the same).
    let lo = cbounds.min;
    let scale = Vec3A::splat(BINS as f32) / (cbounds.max - cbounds.min);
    let last = Vec3A::splat((BINS - 1) as f32);
    let fill = |prims: &[BuildPrim]| {
        let mut bins = Bins::empty();
        for p in prims {
            let index = ((p.centroid() - lo) * scale)
                .min(last)
                .max(Vec3A::ZERO)
                .to_array();
            for (axis, &i) in index.iter().enumerate() {
                let b = &mut bins.0[axis][i as usize];
                b.0.grow(&p.bounds);
                b.1 += 1;
            }
        }
        bins
    };
    let bins = if prims.len() < PARALLEL_BINNING_MIN {
        fill(prims)
    } else {
        prims
            .par_chunks(8192)
            .map(fill)
            .reduce(Bins::empty, |a, b| a.merge(&b))
    };
    let mut best: Option<(usize, usize)> = None;
    let mut best_cost = if prims.len() <= MAX_LEAF {
        leaf_cost(prims.len() as u32)
    } else {
        f32::INFINITY
    };
    let parent_area = bounds.half_area();
    for (axis, bins) in bins.0.iter().enumerate() {
        if cbounds.max[axis] - cbounds.min[axis] <= 0.0 {
            continue;
        }
        // Sweep from the right for every right side's cost, then from the left.
        let mut right_cost = [0.0f32; BINS];
        let (mut acc, mut count) = (Aabb::EMPTY, 0);
        for i in (1..BINS).rev() {
            acc.grow(&bins[i].0);
            count += bins[i].1;
            right_cost[i] = acc.half_area() * leaf_cost(count);
        }
        let (mut acc, mut count) = (Aabb::EMPTY, 0);
        for i in 0..BINS - 1 {
            acc.grow(&bins[i].0);
            count += bins[i].1;
            if count == 0 || count as usize == prims.len() {
                continue;
            }
            let cost = TRAVERSAL_COST
                + (acc.half_area() * leaf_cost(count) + right_cost[i + 1]) / parent_area;
            if cost < best_cost {
                best_cost = cost;
                best = Some((axis, i));
            }
        }
    }
    best
}

/// Moves the triangles for which `left` holds to the front; returns how many
/// there are, and the triangle and centroid boxes of both sides.
fn partition(
    prims: &mut [BuildPrim],
    left: impl Fn(&BuildPrim) -> bool,
) -> (usize, [(Aabb, Aabb); 2]) {
    let mut boxes = [(Aabb::EMPTY, Aabb::EMPTY); 2];
    let mut mid = 0;
    for i in 0..prims.len() {
        let p = prims[i];
        let side = if left(&p) {
            prims.swap(i, mid);
            mid += 1;
            0
        } else {
            1
        };
        boxes[side].0.grow(&p.bounds);
        boxes[side].1.grow_point(p.centroid());
    }
    (mid, boxes)
}
