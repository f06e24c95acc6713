//! The hierarchy itself ([`Bvh`]): its arrays of eight-wide nodes, their
//! children and the leaves' triangle packets; how it is built (or read back
//! from the disk cache, see [`crate::cache`]) and checked; and the accessors
//! every traversal uses (the single-ray one in `single`, the packets' in
//! `ray4` and `ray8`, the streams' in `stream`).

use super::build;
use super::node::{ChildRef, EMPTY, Isa, LEAF, NodeBoxes, WIDTH, leaf_parts};
use super::packet::Packet;
use crate::geometry::triangle::Triangle;
use crate::memory::prefetch;

/// The hierarchy, owning a copy of the triangles in leaf order.
#[derive(Clone, Debug)]
pub struct Bvh {
    pub(super) nodes: Vec<NodeBoxes>,
    pub(super) children: Vec<[ChildRef; WIDTH]>,
    pub(super) packets: Vec<Packet>,
    pub(super) root: Option<ChildRef>,
    pub(super) triangles: usize,
    pub(super) isa: Isa,
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
    pub(super) fn to_cache_bytes(&self) -> Vec<u8> {
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
    pub(super) fn from_cache_bytes(bytes: &[u8], input: usize) -> Option<Self> {
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
    pub(super) fn build_here(triangles: &[Triangle]) -> Self {
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

    /// Asks for the memory of a child that will be visited later, so that its
    /// cache misses overlap with the work on its siblings: a node's three lines of
    /// boxes and its children, or a leaf's first packet and a half.
    #[inline(always)]
    pub(super) fn prefetch_child(&self, r: ChildRef) {
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

    /// The packets of leaf `r`, a reference found in this tree.
    #[inline]
    pub(super) fn leaf(&self, r: ChildRef) -> &[Packet] {
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
    pub(super) fn node(&self, r: ChildRef) -> (&NodeBoxes, &[ChildRef; WIDTH]) {
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

/// Whether every reference of a tree is in range, as traversal assumes: a
/// leaf's packets lie in `0..n_packets`, an inner node is an index into
/// `children` (one entry a node) and comes after its parent, so that the tree
/// has no cycle. `Bvh::from_cache_bytes` checks it on every tree it reads; the
/// builder's trees are checked by the tests.
pub(super) fn references_sound(
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
