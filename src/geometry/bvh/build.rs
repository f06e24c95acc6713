//! The eight-wide tree, built top down: a node takes the planned split of its
//! triangles, then keeps splitting its widest child that has a planned split
//! until it has [`WIDTH`] children (the tree a binary build collapsed this way
//! would give, without building the binary tree).
//!
//! Children with many triangles are built in parallel, each into its own run of
//! nodes (a [`Piece`]); the runs are then copied into one array, references
//! fixed up, and then the leaves' triangles are gathered into packets in the
//! order of the build array.

use std::sync::atomic::{AtomicBool, AtomicU32, Ordering};

use rayon::prelude::*;

use super::node::{ChildRef, EMPTY, Isa, LEAF, Node, NodeBoxes, WIDTH, leaf_parts, leaf_ref};
use super::packet::Packet;
use super::sah::{Aabb, BuildPrim, Cluster};
use crate::geometry::triangle::Triangle;

/// Children at least this big are built in parallel with their siblings.
const PARALLEL_MIN: usize = 4096;

/// The built tree: nodes, leaf packets and the root.
pub(super) struct Built {
    pub(super) nodes: Vec<NodeBoxes>,
    pub(super) children: Vec<[ChildRef; WIDTH]>,
    pub(super) packets: Vec<Packet>,
    pub(super) root: ChildRef,
    pub(super) triangles: usize,
}

/// Builds the tree over the triangles that can be hit (finite, non-zero area);
/// `None` when there are none.
pub(super) fn build(triangles: &[Triangle], isa: Isa) -> Option<Built> {
    assert!(
        triangles.len() < 1 << 27,
        "too many triangles for the BVH (at most 2^27)"
    );
    // Mapped in parallel into place; the few that cannot be hit (if any) are
    // dropped afterwards (a parallel filter would gather pieces and copy them).
    let valid = Triangle::can_be_hit;
    let any_invalid = AtomicBool::new(false);
    let mut prims: Vec<BuildPrim> = Vec::new();
    triangles
        .par_iter()
        .enumerate()
        .map(|(i, t)| {
            if !valid(t) {
                any_invalid.store(true, Ordering::Relaxed);
            }
            BuildPrim::new(t, i as u32)
        })
        .collect_into_vec(&mut prims);
    if any_invalid.into_inner() {
        prims.retain(|p| valid(&triangles[p.id() as usize]));
    }
    if prims.is_empty() {
        return None;
    }
    let builder = Builder {
        leaf_sizes: (0..prims.len()).map(|_| AtomicU32::new(0)).collect(),
    };
    let root_cluster = Cluster::root(&mut prims, isa);
    let mut top = Piece::new(prims.len());
    let root = builder.subtree(&mut prims, 0, &root_cluster, &mut top);
    let (chunks, leaf_packets) = builder.packet_layout();
    let fix_leaf = |r: ChildRef| {
        let (first, len) = leaf_parts(r);
        leaf_ref(leaf_packets[first] as usize, len.div_ceil(4))
    };
    let root = if root & LEAF != 0 {
        fix_leaf(root)
    } else {
        root
    };
    let (nodes, children) = top.flatten(&fix_leaf);
    let packets = gather_packets(triangles, &prims, &chunks);
    Some(Built {
        nodes,
        children,
        packets,
        root,
        triangles: prims.len(),
    })
}

struct Builder {
    /// At the position of each leaf's first triangle in the build array, the
    /// leaf's triangle count (zero elsewhere).
    leaf_sizes: Vec<AtomicU32>,
}

impl Builder {
    /// Builds the subtree of `cluster`, whose triangles are all of `prims` (which
    /// begins at `first` in the build array), into `piece`.
    fn subtree(
        &self,
        prims: &mut [BuildPrim],
        first: usize,
        cluster: &Cluster,
        piece: &mut Piece,
    ) -> ChildRef {
        if cluster.is_leaf() {
            return self.leaf(first, cluster.len);
        }
        let mut kids: [Option<Cluster>; WIDTH] = [const { None }; WIDTH];
        let n = take_children(prims, cluster, &mut kids);
        let kid = |lane: usize| kids[lane].as_ref().expect("lanes below n are taken");
        let slot = piece.nodes.len();
        piece.nodes.push(Node::EMPTY);
        for lane in 0..n {
            set_bounds(&mut piece.nodes[slot], lane, &kid(lane).bounds);
        }
        // The children's runs as disjoint slices, by lane.
        let mut slices: [Option<&mut [BuildPrim]>; WIDTH] = Default::default();
        let mut order: [usize; WIDTH] = std::array::from_fn(|lane| lane);
        order[..n].sort_unstable_by_key(|&lane| kid(lane).start);
        let mut rest = prims;
        for &lane in &order[..n] {
            let (mine, others) = std::mem::take(&mut rest).split_at_mut(kid(lane).len);
            slices[lane] = Some(mine);
            rest = others;
        }
        let mut refs = [EMPTY; WIDTH];
        let mut subpieces: [Option<Piece>; WIDTH] = Default::default();
        let big = |lane: usize| kid(lane).len >= PARALLEL_MIN;
        let mut build_small = |slices: &mut [Option<&mut [BuildPrim]>; WIDTH]| {
            for lane in (0..n).filter(|&lane| !big(lane)) {
                let slice = slices[lane].take().expect("each run is taken once");
                let offset = first + kid(lane).start;
                refs[lane] = self.subtree(slice, offset, kid(lane), piece);
            }
        };
        if (0..n).any(big) {
            rayon::scope(|scope| {
                for (lane, out) in subpieces.iter_mut().enumerate().take(n) {
                    if !big(lane) {
                        continue;
                    }
                    let slice = slices[lane].take().expect("each run is taken once");
                    let kid = kid(lane);
                    scope.spawn(move |_| {
                        let mut sub = Piece::new(kid.len);
                        let root = self.subtree(slice, first + kid.start, kid, &mut sub);
                        debug_assert_eq!(root, 0, "a big child is a node, made first");
                        *out = Some(sub);
                    });
                }
                build_small(&mut slices);
            });
        } else {
            build_small(&mut slices);
        }
        piece.nodes[slot].children = refs;
        for (lane, sub) in subpieces.into_iter().enumerate() {
            if let Some(sub) = sub {
                piece.links.push((slot as u32, lane, sub));
            }
        }
        slot as ChildRef
    }

    /// A leaf's provisional reference: its first triangle in the build array and
    /// its triangle count, until the packets are laid out.
    fn leaf(&self, first: usize, len: usize) -> ChildRef {
        self.leaf_sizes[first].store(len as u32, Ordering::Relaxed);
        leaf_ref(first, len)
    }

    /// The leaves' packets in build-array order: each packet's run of the build
    /// array, and for each leaf (at its first triangle's position) its first packet.
    fn packet_layout(self) -> (Vec<(u32, u32)>, Vec<u32>) {
        let mut first_packet: Vec<u32> = self
            .leaf_sizes
            .into_iter()
            .map(|a| a.into_inner())
            .collect();
        let mut chunks = Vec::with_capacity(first_packet.len() / 3 + 1);
        for (first, entry) in first_packet.iter_mut().enumerate() {
            let len = *entry;
            if len == 0 {
                continue;
            }
            *entry = chunks.len() as u32;
            for offset in (0..len).step_by(4) {
                chunks.push((first as u32 + offset, (len - offset).min(4)));
            }
        }
        assert!(chunks.len() < 1 << 27, "too many packets for the BVH");
        (chunks, first_packet)
    }
}

/// The node's children, into `kids`: the cluster's split, then the widest child
/// that has a planned split gives up its place to its two halves, until there are
/// `WIDTH`; returns how many. `prims` are the cluster's triangles.
fn take_children(
    prims: &mut [BuildPrim],
    cluster: &Cluster,
    kids: &mut [Option<Cluster>; WIDTH],
) -> usize {
    kids[0] = Some(cluster.on_its_own());
    let mut n = 1;
    while n < WIDTH {
        let kid = |i: usize| kids[i].as_ref().expect("lanes below n are taken");
        let widest = (0..n).filter(|&i| !kid(i).is_leaf()).max_by(|&a, &b| {
            let area = |i: usize| kid(i).bounds.half_area();
            area(a).total_cmp(&area(b))
        });
        let Some(i) = widest else { break };
        let [left, right] = kid(i).split(prims);
        kids[i] = Some(left);
        kids[n] = Some(right);
        n += 1;
    }
    n
}

/// Stored boxes are the exact bounds moved outward by [`pad`]. A ray parallel
/// to an axis (direction component ±0, made ±`f32::MIN_POSITIVE` for the slab
/// test) whose origin lies exactly on the far face of an exact box would get
/// an exit distance of 0 there and skip the box, though the triangles on that
/// face can be hit on their edges (found by fuzzing against brute force). With
/// the padding such a ray's origin is strictly inside, and the gap times the
/// inverse (at most 2^126) is at least 10^7 scene units, beyond any hit.
fn set_bounds(node: &mut Node, lane: usize, b: &Aabb) {
    for axis in 0..3 {
        node.bounds[axis][lane] = b.min[axis] - pad(b.min[axis]);
        node.bounds[axis + 3][lane] = b.max[axis] + pad(b.max[axis]);
    }
}

/// How far a box face at coordinate `x` is moved outward: a few units in the
/// last place of `x`, at least 10^-30 (so that 0 moves by more than a
/// denormal), nothing for an infinite face (empty lanes).
#[inline]
fn pad(x: f32) -> f32 {
    if x.is_finite() {
        (x.abs() * (4.0 * f32::EPSILON)).max(1e-30)
    } else {
        0.0
    }
}

/// A subtree's nodes, built by one task, with node references local to it; the
/// children built by other tasks hang off `links` as (node, lane, piece).
struct Piece {
    nodes: Vec<Node>,
    links: Vec<(u32, usize, Piece)>,
}

impl Piece {
    /// An empty piece for `len` triangles (room for the usual number of nodes).
    fn new(len: usize) -> Self {
        Piece {
            nodes: Vec::with_capacity(len / 8 + 1),
            links: Vec::new(),
        }
    }

    /// All the nodes in one array, pieces in depth-first order, references made
    /// global; `fix_leaf` turns a provisional leaf reference into its packets'.
    fn flatten(
        &self,
        fix_leaf: &(impl Fn(ChildRef) -> ChildRef + Sync),
    ) -> (Vec<NodeBoxes>, Vec<[ChildRef; WIDTH]>) {
        let mut placed = Vec::new();
        let total = self.place(0, &mut placed) as usize;
        let mut boxes = Vec::with_capacity(total);
        let mut children = Vec::with_capacity(total);
        crate::memory::advise_huge_pages(&mut boxes);
        crate::memory::advise_huge_pages(&mut children);
        // Carve the destinations into each piece's run, in offset order.
        let mut rest_boxes = &mut boxes.spare_capacity_mut()[..total];
        let mut rest_children = &mut children.spare_capacity_mut()[..total];
        let mut jobs = Vec::with_capacity(placed.len());
        for placed in placed {
            let len = placed.piece.nodes.len();
            let (my_boxes, others) = std::mem::take(&mut rest_boxes).split_at_mut(len);
            rest_boxes = others;
            let (my_children, others) = std::mem::take(&mut rest_children).split_at_mut(len);
            rest_children = others;
            jobs.push((placed, my_boxes, my_children));
        }
        jobs.into_par_iter()
            .for_each(|(placed, out_boxes, out_children)| {
                let mut links = placed.links.iter().peekable();
                for (slot, ((dst_box, dst_kids), src)) in out_boxes
                    .iter_mut()
                    .zip(out_children.iter_mut())
                    .zip(&placed.piece.nodes)
                    .enumerate()
                {
                    let mut kids = src.children;
                    for r in &mut kids {
                        *r = match *r {
                            EMPTY => EMPTY,
                            r if r & LEAF != 0 => fix_leaf(r),
                            r => r + placed.offset,
                        };
                    }
                    while let Some(&(_, lane, target)) = links.next_if(|l| l.0 == slot as u32) {
                        kids[lane] = target;
                    }
                    dst_box.write(NodeBoxes { bounds: src.bounds });
                    dst_kids.write(kids);
                }
            });
        // SAFETY: the runs cover `0..total` and each was written in full above.
        unsafe {
            boxes.set_len(total);
            children.set_len(total);
        }
        (boxes, children)
    }

    /// Appends this piece and those below it (depth first) to `placed`, starting
    /// at `offset`; returns the offset after them.
    fn place<'p>(&'p self, offset: u32, placed: &mut Vec<Placed<'p>>) -> u32 {
        let me = placed.len();
        placed.push(Placed {
            piece: self,
            offset,
            links: Vec::with_capacity(self.links.len()),
        });
        let mut next = offset + self.nodes.len() as u32;
        for (slot, lane, sub) in &self.links {
            placed[me].links.push((*slot, *lane, next));
            next = sub.place(next, placed);
        }
        placed[me].links.sort_unstable();
        next
    }
}

/// A piece's place in the whole array: its first node's index, and the index of
/// each child built in another piece, as (node, lane, index) sorted by node.
struct Placed<'p> {
    piece: &'p Piece,
    offset: u32,
    links: Vec<(u32, usize, u32)>,
}

/// The packets, in the order of `chunks`, gathered in parallel (the triangles are
/// read by scattered index: the slow part of a big build).
fn gather_packets(
    triangles: &[Triangle],
    prims: &[BuildPrim],
    chunks: &[(u32, u32)],
) -> Vec<Packet> {
    let mut packets = Vec::with_capacity(chunks.len());
    crate::memory::advise_huge_pages(&mut packets);
    chunks
        .par_iter()
        .enumerate()
        .map(|(k, &(first, len))| {
            // The triangles a few packets ahead are fetched while this one is made.
            if let Some(&(ahead, len)) = chunks.get(k + PREFETCH_PACKETS) {
                for p in &prims[ahead as usize..(ahead + len) as usize] {
                    // A triangle (48 bytes) may straddle two cache lines.
                    let t: *const Triangle = &triangles[p.id() as usize];
                    crate::memory::prefetch(t);
                    crate::memory::prefetch(t.cast::<u8>().wrapping_add(size_of::<Triangle>() - 1));
                }
            }
            let chunk = &prims[first as usize..(first + len) as usize];
            let lane = |i: usize| {
                let id = chunk[i.min(chunk.len() - 1)].id();
                (triangles[id as usize], id)
            };
            let four: [(Triangle, u32); 4] = std::array::from_fn(lane);
            Packet::new(&four[..chunk.len()])
        })
        .collect_into_vec(&mut packets);
    packets
}

/// How many packets ahead the gather prefetches.
const PREFETCH_PACKETS: usize = 8;
