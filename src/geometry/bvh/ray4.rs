//! Four coherent rays traced together, one per SIMD lane: each node's boxes and each
//! triangle are loaded once for the four rays, and the four tests run side by side
//! instead of one long dependency chain per ray. Camera rays of a 2×2 pixel quad and
//! their shadow rays towards a point light take this path.
//!
//! The per-lane arithmetic of the triangle test is the scalar test's, so hits agree
//! bit for bit with [`Bvh::intersect`]; only which of two triangles at exactly the
//! same `t` (a shared edge) is reported may differ, as traversal order differs.

use glam::{BVec4A, Vec4};

use super::node::{ChildRef, EMPTY, LEAF, WIDTH, safe_inverse};
use super::packet::{Packet, candidates};
use super::tree::Bvh;
use super::walk::Stack;
use crate::geometry::ray::{Hit, Ray, gamma};
use crate::geometry::triangle::{self, RayShear, shared_axis_order};

/// Per-packet constants: origins and safe inverse directions by axis, and the
/// triangle test's shared axis order with per-lane origins and shears.
struct Query4<'a> {
    rays: &'a [Ray; 4],
    origin: [Vec4; 3],
    inv_dir: [Vec4; 3],
    k: [usize; 3],
    origin_k: [Vec4; 3],
    shear: [Vec4; 3],
}

impl<'a> Query4<'a> {
    /// `None` when the rays cannot share the triangle test's axis order (or one is
    /// not finite): the caller traces them one by one.
    #[inline(always)]
    fn new(rays: &'a [Ray; 4]) -> Option<Self> {
        let k = shared_axis_order(rays)?;
        let [a, b, c, d] = rays;
        let origin = [
            Vec4::new(a.origin.x, b.origin.x, c.origin.x, d.origin.x),
            Vec4::new(a.origin.y, b.origin.y, c.origin.y, d.origin.y),
            Vec4::new(a.origin.z, b.origin.z, c.origin.z, d.origin.z),
        ];
        let dir = [
            Vec4::new(a.dir.x, b.dir.x, c.dir.x, d.dir.x),
            Vec4::new(a.dir.y, b.dir.y, c.dir.y, d.dir.y),
            Vec4::new(a.dir.z, b.dir.z, c.dir.z, d.dir.z),
        ];
        let inv = rays.each_ref().map(|r| safe_inverse(r.dir));
        let lanes = |a: usize| Vec4::new(inv[0][a], inv[1][a], inv[2][a], inv[3][a]);
        let inv_z = Vec4::ONE / dir[k[2]];
        Some(Self {
            rays,
            origin,
            inv_dir: [lanes(0), lanes(1), lanes(2)],
            k,
            origin_k: [origin[k[0]], origin[k[1]], origin[k[2]]],
            shear: [dir[k[0]] * inv_z, dir[k[1]] * inv_z, inv_z],
        })
    }

    /// Slab test of child `c` of `node` for the four rays: entry distances and the
    /// lanes that hit within `[0, t_max]`.
    #[inline(always)]
    fn hit_box(&self, bounds: &[[f32; WIDTH]; 6], c: usize, t_max: Vec4) -> (Vec4, BVec4A) {
        let slab = |a: usize| {
            let t0 = (Vec4::splat(bounds[a][c]) - self.origin[a]) * self.inv_dir[a];
            let t1 = (Vec4::splat(bounds[a + 3][c]) - self.origin[a]) * self.inv_dir[a];
            (t0.min(t1), t0.max(t1))
        };
        let (nx, fx) = slab(0);
        let (ny, fy) = slab(1);
        let (nz, fz) = slab(2);
        let near = nx.max(ny).max(nz).max(Vec4::ZERO);
        let far = fx.min(fy).min(fz) * (1.0 + 2.0 * gamma(3));
        (near, near.cmple(far.min(t_max)))
    }
}

impl Bvh {
    /// The closest hits of four rays with `t` in `(0, t_max]`, traced together.
    pub fn intersect4(&self, rays: &[Ray; 4], t_max: f32) -> [Option<Hit>; 4] {
        let Some(root) = self.root else {
            return [None; 4];
        };
        let Some(q) = Query4::new(rays) else {
            return rays.map(|r| self.intersect(&r, t_max));
        };
        let mut best_t = Vec4::splat(t_max);
        let (mut b1, mut b2) = (Vec4::ZERO, Vec4::ZERO);
        let mut prim = [u32::MAX; 4];
        let mut found = 0u32;
        let mut stack = Stack::<(ChildRef, Vec4)>::new();
        stack.push((root, Vec4::ZERO));
        while let Some((cur, near)) = stack.pop() {
            if !near.cmple(best_t).any() {
                continue;
            }
            if cur & LEAF != 0 {
                for p in self.leaf(cur) {
                    for i in 0..p.len() {
                        let hit = test_triangle(&q, p, i, best_t);
                        let mask = hit.valid.bitmask();
                        if mask != 0 {
                            best_t = Vec4::select(hit.valid, hit.t, best_t);
                            b1 = Vec4::select(hit.valid, hit.b1, b1);
                            b2 = Vec4::select(hit.valid, hit.b2, b2);
                            for (lane, id) in prim.iter_mut().enumerate() {
                                if mask >> lane & 1 != 0 {
                                    *id = p.prim(i);
                                }
                            }
                            found |= mask;
                        }
                    }
                }
                continue;
            }
            let (node, kids) = self.node(cur);
            // Visit the child whose box the packet enters first next.
            let mut next: Option<(ChildRef, Vec4, f32)> = None;
            for (c, &child) in kids.iter().enumerate() {
                if child == EMPTY {
                    continue;
                }
                let (near, hit) = q.hit_box(&node.bounds, c, best_t);
                if !hit.any() {
                    continue;
                }
                // Lanes that miss get NaN, which no `t` compares below, so the pop
                // skips the entry for them even while their best `t` is infinite.
                let key = Vec4::select(hit, near, Vec4::INFINITY).min_element();
                let near = Vec4::select(hit, near, Vec4::NAN);
                match next {
                    Some((n, nv, nk)) if nk <= key => {
                        stack.push((child, near));
                        next = Some((n, nv, nk));
                    }
                    Some((n, nv, _)) => {
                        stack.push((n, nv));
                        next = Some((child, near, key));
                    }
                    None => next = Some((child, near, key)),
                }
            }
            if let Some((n, nv, _)) = next {
                stack.push((n, nv));
            }
        }
        std::array::from_fn(|lane| {
            (found >> lane & 1 != 0).then(|| Hit {
                t: best_t[lane],
                prim: prim[lane],
                b1: b1[lane],
                b2: b2[lane],
            })
        })
    }

    /// The closest hits of eight rays with `t` in `(0, t_max]`: traced together
    /// in AVX2 lanes where the CPU has AVX2 and the rays share the triangle
    /// test's axis order (as a 4×2 block of camera rays does), otherwise as two
    /// groups of four. The same answers as [`Bvh::intersect`] ray by ray, except
    /// which triangle is reported at an exact tie.
    pub fn intersect8(&self, rays: &[Ray; 8], t_max: f32) -> [Option<Hit>; 8] {
        #[cfg(target_arch = "x86_64")]
        if let Some(hits) = self.intersect8_wide(rays, t_max) {
            return hits;
        }
        let (a, b) = rays.split_at(4);
        let a = self.intersect4(a.try_into().expect("four rays"), t_max);
        let b = self.intersect4(b.try_into().expect("four rays"), t_max);
        std::array::from_fn(|i| if i < 4 { a[i] } else { b[i - 4] })
    }

    /// For eight rays with their own `t_max`, whether anything is hit in
    /// `(0, t_max]`; lanes not in `active` are left out and answer `false`.
    pub fn occluded8(&self, rays: &[Ray; 8], t_max: [f32; 8], active: [bool; 8]) -> [bool; 8] {
        #[cfg(target_arch = "x86_64")]
        if let Some(blocked) = self.occluded8_wide(rays, t_max, active) {
            return blocked;
        }
        let half = |h: usize| {
            let r: &[Ray; 4] = rays[4 * h..4 * h + 4].try_into().expect("four rays");
            self.occluded4(
                r,
                std::array::from_fn(|i| t_max[4 * h + i]),
                std::array::from_fn(|i| active[4 * h + i]),
            )
        };
        let (a, b) = (half(0), half(1));
        std::array::from_fn(|i| if i < 4 { a[i] } else { b[i - 4] })
    }

    /// For four rays with their own `t_max`, whether anything is hit in
    /// `(0, t_max]`; lanes not in `active` are left out and answer `false`.
    pub fn occluded4(&self, rays: &[Ray; 4], t_max: [f32; 4], active: [bool; 4]) -> [bool; 4] {
        let Some(root) = self.root else {
            return [false; 4];
        };
        let Some(q) = Query4::new(rays) else {
            return std::array::from_fn(|i| active[i] && self.occluded(&rays[i], t_max[i]));
        };
        let t_max = Vec4::from_array(t_max);
        let mut open = BVec4A::from_array(active);
        let mut blocked = BVec4A::from_array([false; 4]);
        let mut stack = Stack::<ChildRef>::new();
        stack.push(root);
        while let Some(cur) = stack.pop() {
            if cur & LEAF != 0 {
                for p in self.leaf(cur) {
                    for i in 0..p.len() {
                        let hit = test_triangle(&q, p, i, t_max).valid & open;
                        blocked |= hit;
                        open &= !hit;
                    }
                }
                if !open.any() {
                    break;
                }
                continue;
            }
            let (node, kids) = self.node(cur);
            for (c, &child) in kids.iter().enumerate() {
                if child != EMPTY && (q.hit_box(&node.bounds, c, t_max).1 & open).any() {
                    stack.push(child);
                }
            }
        }
        blocked.into()
    }
}

/// Hits of the four rays on triangle `i` of packet `p`: lanes, `t` and barycentrics.
struct Hits4 {
    valid: BVec4A,
    t: Vec4,
    b1: Vec4,
    b2: Vec4,
}

#[inline(always)]
fn test_triangle(q: &Query4<'_>, p: &Packet, i: usize, t_max: Vec4) -> Hits4 {
    match candidates(&p.broadcast(i), q.k, &q.origin_k, &q.shear, t_max) {
        Ok(c) => {
            let inv = Vec4::ONE / c.det;
            Hits4 {
                valid: c.valid,
                t: c.t,
                b1: c.v * inv,
                b2: c.w * inv,
            }
        }
        Err(()) => scalar_lanes(q, p, i, t_max),
    }
}

/// The scalar test lane by lane, for the rare exact-zero edge functions.
#[cold]
fn scalar_lanes(q: &Query4<'_>, p: &Packet, i: usize, t_max: Vec4) -> Hits4 {
    let tri = p.triangle(i);
    let hits: [Option<triangle::TriangleHit>; 4] = std::array::from_fn(|lane| {
        triangle::intersect(&RayShear::new(&q.rays[lane]), &tri, t_max[lane])
    });
    let get = |f: &dyn Fn(&triangle::TriangleHit) -> f32| {
        Vec4::from_array(hits.map(|h| h.as_ref().map_or(0.0, f)))
    };
    Hits4 {
        valid: BVec4A::from_array(hits.map(|h| h.is_some())),
        t: get(&|h| h.t),
        b1: get(&|h| h.b1),
        b2: get(&|h| h.b2),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::triangle::Triangle;
    use crate::sampling::sampler::Rng;
    use glam::Vec3A;

    /// A closed icosphere-like blob of triangles with shared edges.
    fn mesh(rng: &mut Rng) -> Vec<Triangle> {
        let (n_lat, n_lon) = (12, 24);
        let p = |i: usize, j: usize| {
            let (th, ph) = (
                std::f32::consts::PI * i as f32 / n_lat as f32,
                std::f32::consts::TAU * j as f32 / n_lon as f32,
            );
            let r = 1.0 + 0.1 * ((3.0 * ph).sin() * (2.0 * th).cos());
            Vec3A::new(
                r * th.sin() * ph.cos(),
                r * th.cos(),
                r * th.sin() * ph.sin(),
            )
        };
        let mut tris = Vec::new();
        for i in 0..n_lat {
            for j in 0..n_lon {
                let (a, b, c, d) = (p(i, j), p(i + 1, j), p(i + 1, j + 1), p(i, j + 1));
                tris.push(Triangle::new(a, b, c));
                tris.push(Triangle::new(a, c, d));
            }
        }
        // Plus a few loose triangles inside and outside.
        for _ in 0..40 {
            let c = Vec3A::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 3.0 - 1.5;
            let e = Vec3A::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 0.3;
            tris.push(Triangle::new(c, c + e, c + Vec3A::new(e.z, e.x, e.y)));
        }
        tris
    }

    #[test]
    fn four_rays_together_agree_with_one_at_a_time() {
        let mut rng = Rng::new(21, 0);
        let tris = mesh(&mut rng);
        let bvh = Bvh::build(&tris);
        let (mut hits, mut packets) = (0, 0);
        for round in 0..3000 {
            // Coherent bundles (as from a pixel quad or towards a light) and, every
            // fourth round, incoherent ones that fall back to single rays.
            let origin = Vec3A::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 6.0 - 3.0;
            let aim = Vec3A::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 2.0 - 1.0;
            let spread = if round % 4 == 0 { 2.0 } else { 0.05 };
            let rays: [Ray; 4] = std::array::from_fn(|_| {
                let jitter = Vec3A::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) - 0.5;
                Ray::new(origin, (aim + spread * jitter - origin).normalize())
            });
            packets += Query4::new(&rays).is_some() as u32;
            let t_max = if round % 3 == 0 { 3.0 } else { f32::INFINITY };
            let together = bvh.intersect4(&rays, t_max);
            let active = [true, round % 2 == 0, true, true];
            let occluded = bvh.occluded4(&rays, [t_max, 2.0, t_max, 1.0], active);
            for lane in 0..4 {
                let alone = bvh.intersect(&rays[lane], t_max);
                assert_eq!(
                    together[lane].is_some(),
                    alone.is_some(),
                    "round {round} lane {lane}"
                );
                if let (Some(a), Some(b)) = (together[lane], alone) {
                    hits += 1;
                    assert_eq!(a.t.to_bits(), b.t.to_bits(), "round {round}");
                    if a.prim == b.prim {
                        assert_eq!((a.b1, a.b2), (b.b1, b.b2));
                    }
                }
                let limit = [t_max, 2.0, t_max, 1.0][lane];
                let want = active[lane] && bvh.occluded(&rays[lane], limit);
                assert_eq!(occluded[lane], want, "round {round} lane {lane}");
            }
        }
        assert!(
            hits > 3000 && packets > 1500,
            "{hits} hits, {packets} packets"
        );
    }
}
