//! From the binary build tree to eight-wide nodes: every node takes the children of
//! its largest inner children until it has [`WIDTH`] of them, and every leaf
//! becomes a run of four-triangle packets (recorded here as `(first, count)`
//! ranges of the build order; the packets themselves are gathered afterwards).

use super::build::{Aabb, BinNode};
use super::node::{ChildRef, LEAF, Node, WIDTH};

/// Wide nodes and the packet ranges of their leaves, in the order made.
pub(super) struct Wide {
    pub(super) nodes: Vec<Node>,
    pub(super) chunks: Vec<(u32, u32)>,
}

/// Collapses the tree under `root`; returns the wide tree and its root reference.
pub(super) fn collapse(root: &BinNode) -> (Wide, ChildRef) {
    let mut wide = Wide {
        nodes: Vec::with_capacity(root.count() / 8 + 1),
        chunks: Vec::with_capacity(root.count() / 3 + 1),
    };
    let r = collapse_into(root, &mut wide);
    (wide, r)
}

fn collapse_into(node: &BinNode, out: &mut Wide) -> ChildRef {
    let BinNode::Inner { children, .. } = node else {
        return leaf(node, out);
    };
    let (kids, n) = wide_children(children);
    let slot = out.nodes.len();
    out.nodes.push(Node::EMPTY);
    for (lane, kid) in kids[..n].iter().enumerate() {
        let child = collapse_into(kid, out);
        set_lane(&mut out.nodes[slot], lane, kid.bounds(), child);
    }
    slot as u32
}

fn leaf(node: &BinNode, out: &mut Wide) -> ChildRef {
    let BinNode::Leaf { first, count, .. } = *node else {
        unreachable!("leaf() takes leaves")
    };
    let start = out.chunks.len() as u32;
    for offset in (0..count).step_by(4) {
        out.chunks
            .push(((first + offset) as u32, (count - offset).min(4) as u32));
    }
    assert!(start < 1 << 27, "too many triangles for the BVH");
    LEAF | start << 4 | (out.chunks.len() as u32 - start)
}

/// Up to `WIDTH` descendants to be one node's children: the inner child with the
/// largest box gives up its two children until there are enough.
fn wide_children(children: &[BinNode; 2]) -> ([&BinNode; WIDTH], usize) {
    let mut kids: [&BinNode; WIDTH] = [&children[0]; WIDTH];
    kids[1] = &children[1];
    let mut n = 2;
    while n < WIDTH {
        let widest = (0..n)
            .filter(|&i| matches!(kids[i], BinNode::Inner { .. }))
            .max_by(|&a, &b| {
                let area = |i: usize| kids[i].bounds().half_area();
                area(a).total_cmp(&area(b))
            });
        let Some(i) = widest else { break };
        let BinNode::Inner { children, .. } = kids[i] else {
            unreachable!()
        };
        kids[i] = &children[0];
        kids[n] = &children[1];
        n += 1;
    }
    (kids, n)
}

fn set_lane(node: &mut Node, lane: usize, b: &Aabb, child: ChildRef) {
    for axis in 0..3 {
        node.bounds[axis][lane] = b.min[axis];
        node.bounds[axis + 3][lane] = b.max[axis];
    }
    node.children[lane] = child;
}
