//! A bounding volume hierarchy over triangles: binned-SAH build, 32-byte nodes in
//! depth-first order, ordered front-to-back traversal, early exit for any-hit.

use glam::{BVec3A, Vec3A};

use crate::ray::{Hit, Ray, gamma};
use crate::triangle::{self, RayShear, Triangle};

/// Node of the flattened tree. Interior nodes keep their first child right after
/// themselves and the second at `offset`; leaves hold `count > 0` triangles from
/// `offset` on.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(32))]
struct Node {
    min: [f32; 3],
    offset: u32,
    max: [f32; 3],
    count: u16,
    axis: u16,
}

const BINS: usize = 12;
const MAX_LEAF: usize = 8;
/// Cost of a box test relative to a triangle test in the surface area heuristic.
const TRAVERSAL_COST: f32 = 1.0;
const MAX_SAH_DEPTH: usize = 64;
/// Traversal stack size: SAH depth plus median splits of up to 2^32 triangles.
const STACK_SIZE: usize = MAX_SAH_DEPTH + 32;

/// The hierarchy, owning a copy of the triangles in leaf order.
#[derive(Clone, Debug, Default)]
pub struct Bvh {
    nodes: Vec<Node>,
    tris: Vec<[Vec3A; 3]>,
    prim_ids: Vec<u32>,
}

#[derive(Clone, Copy)]
struct Aabb {
    min: Vec3A,
    max: Vec3A,
}

impl Aabb {
    const EMPTY: Aabb = Aabb {
        min: Vec3A::splat(f32::INFINITY),
        max: Vec3A::splat(f32::NEG_INFINITY),
    };
    fn grow(&mut self, o: &Aabb) {
        self.min = self.min.min(o.min);
        self.max = self.max.max(o.max);
    }
    fn grow_point(&mut self, p: Vec3A) {
        self.min = self.min.min(p);
        self.max = self.max.max(p);
    }
    fn half_area(&self) -> f32 {
        let d = (self.max - self.min).max(Vec3A::ZERO);
        d.x * d.y + d.y * d.z + d.z * d.x
    }
}

struct BuildPrim {
    bounds: Aabb,
    centroid: Vec3A,
    id: u32,
}

impl Bvh {
    /// Builds the tree. Triangles with zero area or non-finite vertices can never be
    /// hit and are left out; hits report indices into `triangles`.
    pub fn build(triangles: &[Triangle]) -> Self {
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
        let mut bvh = Bvh::default();
        if prims.is_empty() {
            return bvh;
        }
        bvh.nodes.reserve(2 * prims.len());
        bvh.build_range(&mut prims, 0, 0);
        bvh.prim_ids = prims.iter().map(|p| p.id).collect();
        bvh.tris = bvh
            .prim_ids
            .iter()
            .map(|&i| triangles[i as usize].v)
            .collect();
        bvh
    }

    /// Builds the subtree of `prims`, which start at index `first` of the full array.
    fn build_range(&mut self, prims: &mut [BuildPrim], first: usize, depth: usize) -> usize {
        let mut bounds = Aabb::EMPTY;
        let mut cbounds = Aabb::EMPTY;
        for p in prims.iter() {
            bounds.grow(&p.bounds);
            cbounds.grow_point(p.centroid);
        }
        let index = self.nodes.len();
        self.nodes.push(Node {
            min: bounds.min.into(),
            offset: first as u32,
            max: bounds.max.into(),
            count: prims.len() as u16,
            axis: 0,
        });
        if prims.len() == 1 {
            return index;
        }
        // Past MAX_SAH_DEPTH only median splits, which bound the depth by log2(n).
        let split = if depth < MAX_SAH_DEPTH {
            best_split(prims, &cbounds, &bounds)
        } else {
            None
        };
        let mid = match split {
            Some((axis, bin)) => {
                let (lo, extent) = (cbounds.min[axis], cbounds.max[axis] - cbounds.min[axis]);
                let mid = partition(prims, |p| bin_of(p.centroid[axis], lo, extent) <= bin);
                self.nodes[index].axis = axis as u16;
                mid
            }
            None if prims.len() <= MAX_LEAF => return index,
            None => {
                // SAH prefers a leaf (or centroids coincide) but the leaf would be too
                // big: split in the middle of the longest axis by object count.
                let axis = (bounds.max - bounds.min).max_position();
                prims.sort_by(|a, b| a.centroid[axis].total_cmp(&b.centroid[axis]));
                self.nodes[index].axis = axis as u16;
                prims.len() / 2
            }
        };
        let (left, right) = prims.split_at_mut(mid);
        self.nodes[index].count = 0;
        self.build_range(left, first, depth + 1);
        let right_index = self.build_range(right, first + mid, depth + 1);
        self.nodes[index].offset = right_index as u32;
        index
    }

    /// The closest hit with `t` in `(0, t_max]`.
    pub fn intersect(&self, ray: &Ray, t_max: f32) -> Option<Hit> {
        if self.nodes.is_empty() || !is_finite_ray(ray) {
            return None;
        }
        let q = Query::new(ray);
        let mut best: Option<Hit> = None;
        let mut t_max = t_max;
        let mut stack = [0u32; STACK_SIZE];
        let mut sp = 0;
        let mut node = 0usize;
        loop {
            let n = &self.nodes[node];
            if q.hits_box(n, t_max) {
                if n.count > 0 {
                    let start = n.offset as usize;
                    for i in start..start + n.count as usize {
                        if let Some(h) = triangle::intersect(&q.shear, &self.tris[i], t_max) {
                            t_max = h.t;
                            best = Some(Hit {
                                t: h.t,
                                prim: self.prim_ids[i],
                                b1: h.b1,
                                b2: h.b2,
                            });
                        }
                    }
                } else {
                    // Visit the child on the near side of the split first.
                    let (near, far) = if q.dir_neg.test(n.axis as usize) {
                        (n.offset as usize, node + 1)
                    } else {
                        (node + 1, n.offset as usize)
                    };
                    stack[sp] = far as u32;
                    sp += 1;
                    node = near;
                    continue;
                }
            }
            if sp == 0 {
                return best;
            }
            sp -= 1;
            node = stack[sp] as usize;
        }
    }

    /// Whether anything is hit with `t` in `(0, t_max]`; stops at the first hit found.
    pub fn occluded(&self, ray: &Ray, t_max: f32) -> bool {
        if self.nodes.is_empty() || !is_finite_ray(ray) {
            return false;
        }
        let q = Query::new(ray);
        let mut stack = [0u32; STACK_SIZE];
        let mut sp = 0;
        let mut node = 0usize;
        loop {
            let n = &self.nodes[node];
            if q.hits_box(n, t_max) {
                if n.count > 0 {
                    let start = n.offset as usize;
                    let tris = &self.tris[start..start + n.count as usize];
                    if tris
                        .iter()
                        .any(|v| triangle::intersect(&q.shear, v, t_max).is_some())
                    {
                        return true;
                    }
                } else {
                    stack[sp] = n.offset;
                    sp += 1;
                    node += 1;
                    continue;
                }
            }
            if sp == 0 {
                return false;
            }
            sp -= 1;
            node = stack[sp] as usize;
        }
    }

    /// Number of nodes in the tree.
    pub fn node_count(&self) -> usize {
        self.nodes.len()
    }

    /// Bytes used by nodes, triangles and index map.
    pub fn memory_bytes(&self) -> usize {
        self.nodes.len() * std::mem::size_of::<Node>()
            + self.tris.len() * std::mem::size_of::<[Vec3A; 3]>()
            + self.prim_ids.len() * 4
    }
}

/// Per-ray constants of traversal.
struct Query {
    origin: Vec3A,
    inv_dir: Vec3A,
    dir_neg: BVec3A,
    shear: RayShear,
}

impl Query {
    fn new(ray: &Ray) -> Self {
        // A zero component becomes a tiny one of the same sign, so the inverse is
        // finite and a slab test never computes 0 · inf = NaN; the sign comes from
        // the inverse so that -0.0 counts as negative.
        let tiny = Vec3A::splat(1e-30);
        let safe = Vec3A::select(ray.dir.abs().cmplt(tiny), tiny.copysign(ray.dir), ray.dir);
        let inv_dir = safe.recip();
        Self {
            origin: ray.origin,
            inv_dir,
            dir_neg: inv_dir.cmplt(Vec3A::ZERO),
            shear: RayShear::new(ray),
        }
    }

    /// Slab test, near and far planes chosen by the direction's sign; the far
    /// distance is enlarged by `1 + 2γ(3)` so that rounding never culls a box the
    /// ray grazes (Ize 2013).
    #[inline]
    fn hits_box(&self, n: &Node, t_max: f32) -> bool {
        let (min, max) = (Vec3A::from(n.min), Vec3A::from(n.max));
        let near = Vec3A::select(self.dir_neg, max, min);
        let far = Vec3A::select(self.dir_neg, min, max);
        let t0 = ((near - self.origin) * self.inv_dir).max_element().max(0.0);
        let t1 = ((far - self.origin) * self.inv_dir).min_element() * (1.0 + 2.0 * gamma(3));
        t0 <= t1.min(t_max)
    }
}

fn is_finite_ray(ray: &Ray) -> bool {
    ray.origin.is_finite() && ray.dir.is_finite()
}

fn bin_of(c: f32, lo: f32, extent: f32) -> usize {
    (((c - lo) / extent * BINS as f32) as usize).min(BINS - 1)
}

/// The SAH-best split as `(axis, last bin of the left side)`, or `None` when a leaf is
/// cheaper (and small enough) or all centroids coincide.
fn best_split(prims: &[BuildPrim], cbounds: &Aabb, bounds: &Aabb) -> Option<(usize, usize)> {
    let mut best: Option<(usize, usize)> = None;
    let mut best_cost = if prims.len() <= MAX_LEAF {
        prims.len() as f32
    } else {
        f32::INFINITY
    };
    let parent_area = bounds.half_area();
    for axis in 0..3 {
        let (lo, extent) = (cbounds.min[axis], cbounds.max[axis] - cbounds.min[axis]);
        if !(extent > 0.0) {
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
            right_cost[i] = acc.half_area() * count as f32;
        }
        let mut acc = Aabb::EMPTY;
        let mut count = 0;
        for i in 0..BINS - 1 {
            acc.grow(&bins[i].0);
            count += bins[i].1;
            if count == 0 || count as usize == prims.len() {
                continue;
            }
            let cost =
                TRAVERSAL_COST + (acc.half_area() * count as f32 + right_cost[i + 1]) / parent_area;
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampler::Rng;

    fn random_triangles(rng: &mut Rng, n: usize) -> Vec<Triangle> {
        let mut p = || Vec3A::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 2.0 - 1.0;
        (0..n)
            .map(|_| {
                let c = p();
                Triangle::new(c, c + 0.2 * p(), c + 0.2 * p())
            })
            .collect()
    }

    fn brute_force(tris: &[Triangle], ray: &Ray, t_max: f32) -> Option<Hit> {
        let s = RayShear::new(ray);
        let mut best: Option<Hit> = None;
        for (i, t) in tris.iter().enumerate() {
            let limit = best.map_or(t_max, |b| b.t);
            if let Some(h) = triangle::intersect(&s, &t.v, limit) {
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

    #[test]
    fn agrees_with_brute_force_on_random_soup() {
        let mut rng = Rng::new(3, 1);
        for &n in &[1usize, 2, 7, 100, 3000] {
            let tris = random_triangles(&mut rng, n);
            let bvh = Bvh::build(&tris);
            for _ in 0..2000 {
                let o = Vec3A::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 3.0 - 1.5;
                let d = (Vec3A::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) - 0.5)
                    .normalize();
                let ray = Ray::new(o, d);
                let a = bvh.intersect(&ray, f32::INFINITY);
                let b = brute_force(&tris, &ray, f32::INFINITY);
                assert_eq!(a.is_some(), b.is_some(), "n={n} {ray:?}");
                if let (Some(a), Some(b)) = (a, b) {
                    assert!((a.t - b.t).abs() <= 1e-5 * b.t, "{a:?} {b:?}");
                    assert!(a.prim == b.prim || a.t == b.t, "{a:?} {b:?}");
                }
                // Any-hit agrees with closest-hit, with and without a t_max cut.
                assert_eq!(bvh.occluded(&ray, f32::INFINITY), b.is_some());
                let cut = 0.5;
                assert_eq!(
                    bvh.occluded(&ray, cut),
                    brute_force(&tris, &ray, cut).is_some()
                );
            }
        }
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
        assert_eq!(bvh.node_count(), 0);
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
            let origin = if dir.z > 0.0 { Vec3A::ZERO } else { Vec3A::new(0.0, 0.0, 8.0) };
            let hit = bvh.intersect(&Ray::new(origin, dir), f32::INFINITY).expect("hit");
            assert_eq!((hit.prim, hit.t), want);
            assert!(bvh.occluded(&Ray::new(origin, dir), f32::INFINITY));
        }
    }
}
