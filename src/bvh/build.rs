//! Binned-SAH construction of a binary tree, the first step of the BVH build.

use glam::Vec3A;

use crate::triangle::Triangle;

pub(super) const BINS: usize = 12;
/// Largest leaf, in triangles: two four-wide packets.
pub(super) const MAX_LEAF: usize = 8;
/// Cost of visiting a node relative to testing one packet of four triangles.
const TRAVERSAL_COST: f32 = 0.3;
/// Past this depth only median splits, which bound the depth by log2(n).
pub(super) const MAX_SAH_DEPTH: usize = 64;

#[derive(Clone, Copy)]
pub(super) struct Aabb {
    pub(super) min: Vec3A,
    pub(super) max: Vec3A,
}

impl Aabb {
    pub(super) const EMPTY: Aabb = Aabb {
        min: Vec3A::splat(f32::INFINITY),
        max: Vec3A::splat(f32::NEG_INFINITY),
    };
    pub(super) fn grow(&mut self, o: &Aabb) {
        self.min = self.min.min(o.min);
        self.max = self.max.max(o.max);
    }
    fn grow_point(&mut self, p: Vec3A) {
        self.min = self.min.min(p);
        self.max = self.max.max(p);
    }
    pub(super) fn half_area(&self) -> f32 {
        let d = (self.max - self.min).max(Vec3A::ZERO);
        d.x * d.y + d.y * d.z + d.z * d.x
    }
}

/// A node of the binary tree: a leaf with `count` triangles from `first` on
/// (in build order), or an inner node with two children.
pub(super) enum BinNode {
    Leaf {
        bounds: Aabb,
        first: usize,
        count: usize,
    },
    Inner {
        bounds: Aabb,
        children: [usize; 2],
    },
}

impl BinNode {
    pub(super) fn bounds(&self) -> &Aabb {
        match self {
            BinNode::Leaf { bounds, .. } | BinNode::Inner { bounds, .. } => bounds,
        }
    }
}

pub(super) struct BuildPrim {
    bounds: Aabb,
    centroid: Vec3A,
    pub(super) id: u32,
}

/// A binary tree over the triangles that can be hit (finite, non-zero area);
/// node 0 is the root. Returns the nodes and the triangles in leaf order.
pub(super) fn build_binary(triangles: &[Triangle]) -> (Vec<BinNode>, Vec<BuildPrim>) {
    let mut prims: Vec<BuildPrim> = triangles
        .iter()
        .enumerate()
        .filter(|(_, t)| t.is_finite() && t.area() > 0.0)
        .map(|(i, t)| BuildPrim {
            bounds: Aabb {
                min: t.min(),
                max: t.max(),
            },
            centroid: (t.min() + t.max()) * 0.5,
            id: i as u32,
        })
        .collect();
    let mut nodes = Vec::new();
    if !prims.is_empty() {
        nodes.reserve(prims.len() / 2 + 1);
        build_range(&mut nodes, &mut prims, 0, 0);
    }
    (nodes, prims)
}

/// Builds the subtree of `prims`, which start at index `first` of the full array.
fn build_range(
    nodes: &mut Vec<BinNode>,
    prims: &mut [BuildPrim],
    first: usize,
    depth: usize,
) -> usize {
    let mut bounds = Aabb::EMPTY;
    let mut cbounds = Aabb::EMPTY;
    for p in prims.iter() {
        bounds.grow(&p.bounds);
        cbounds.grow_point(p.centroid);
    }
    let index = nodes.len();
    let leaf = BinNode::Leaf {
        bounds,
        first,
        count: prims.len(),
    };
    nodes.push(leaf);
    if prims.len() == 1 {
        return index;
    }
    let split = if depth < MAX_SAH_DEPTH {
        best_split(prims, &cbounds, &bounds)
    } else {
        None
    };
    let mid = match split {
        Some((axis, bin)) => {
            let (lo, extent) = (cbounds.min[axis], cbounds.max[axis] - cbounds.min[axis]);
            partition(prims, |p| bin_of(p.centroid[axis], lo, extent) <= bin)
        }
        None if prims.len() <= MAX_LEAF => return index,
        None => {
            // SAH prefers a leaf (or centroids coincide) but the leaf would be too
            // big: split in the middle of the longest axis by object count.
            let axis = (bounds.max - bounds.min).max_position();
            prims.sort_by(|a, b| a.centroid[axis].total_cmp(&b.centroid[axis]));
            prims.len() / 2
        }
    };
    let (left, right) = prims.split_at_mut(mid);
    let l = build_range(nodes, left, first, depth + 1);
    let r = build_range(nodes, right, first + mid, depth + 1);
    nodes[index] = BinNode::Inner {
        bounds,
        children: [l, r],
    };
    index
}

/// SAH cost of a leaf of `n` triangles: one test per packet of four.
fn leaf_cost(n: usize) -> f32 {
    n.div_ceil(4) as f32
}

fn bin_of(c: f32, lo: f32, extent: f32) -> usize {
    (((c - lo) / extent * BINS as f32) as usize).min(BINS - 1)
}

/// The SAH-best split as `(axis, last bin of the left side)`, or `None` when a leaf is
/// cheaper (and small enough) or all centroids coincide.
fn best_split(prims: &[BuildPrim], cbounds: &Aabb, bounds: &Aabb) -> Option<(usize, usize)> {
    let mut best: Option<(usize, usize)> = None;
    let mut best_cost = if prims.len() <= MAX_LEAF {
        leaf_cost(prims.len())
    } else {
        f32::INFINITY
    };
    let parent_area = bounds.half_area();
    for axis in 0..3 {
        let (lo, extent) = (cbounds.min[axis], cbounds.max[axis] - cbounds.min[axis]);
        if extent <= 0.0 {
            continue;
        }
        let mut bins = [(Aabb::EMPTY, 0u32); BINS];
        for p in prims {
            let b = &mut bins[bin_of(p.centroid[axis], lo, extent)];
            b.0.grow(&p.bounds);
            b.1 += 1;
        }
        // Sweep from the right to get the cost of every right side, then from the left.
        let mut right_cost = [0.0f32; BINS];
        let mut acc = Aabb::EMPTY;
        let mut count = 0;
        for i in (1..BINS).rev() {
            acc.grow(&bins[i].0);
            count += bins[i].1;
            right_cost[i] = acc.half_area() * leaf_cost(count as usize);
        }
        let mut acc = Aabb::EMPTY;
        let mut count = 0;
        for i in 0..BINS - 1 {
            acc.grow(&bins[i].0);
            count += bins[i].1;
            if count == 0 || count as usize == prims.len() {
                continue;
            }
            let cost = TRAVERSAL_COST
                + (acc.half_area() * leaf_cost(count as usize) + right_cost[i + 1]) / parent_area;
            if cost < best_cost {
                best_cost = cost;
                best = Some((axis, i));
            }
        }
    }
    best
}

fn partition<T>(items: &mut [T], pred: impl Fn(&T) -> bool) -> usize {
    let mut mid = 0;
    for i in 0..items.len() {
        if pred(&items[i]) {
            items.swap(i, mid);
            mid += 1;
        }
    }
    mid
}
