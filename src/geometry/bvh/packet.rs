//! Four triangles in structure-of-arrays layout and the watertight test of one ray
//! against all four at once (glam's `Vec4`: SSE2 on x86-64, scalar elsewhere).

use glam::{BVec4A, Vec3A, Vec4};

use crate::geometry::ray::Ray;
use crate::geometry::triangle::{self, RayShear, Triangle, TriangleHit, axis_order, t_error_bound};

/// Four triangles, lane by lane: `v[vertex][axis]`. Unused lanes repeat the last
/// triangle, so they never change a result.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(16))]
pub struct Packet {
    pub(super) v: [[Vec4; 3]; 3],
    pub(super) prim: [u32; 4],
}

impl Packet {
    /// Packs up to four triangles with their scene indices.
    pub fn new(tris: &[(Triangle, u32)]) -> Self {
        assert!((1..=4).contains(&tris.len()));
        let lane = |i: usize| tris[i.min(tris.len() - 1)];
        let coord = |vertex: usize, axis: usize| {
            Vec4::from_array(std::array::from_fn(|i| lane(i).0.v[vertex][axis]))
        };
        Self {
            v: std::array::from_fn(|vertex| std::array::from_fn(|axis| coord(vertex, axis))),
            prim: std::array::from_fn(|i| lane(i).1),
        }
    }

    /// The triangle in lane `i`.
    pub(super) fn triangle(&self, i: usize) -> [Vec3A; 3] {
        std::array::from_fn(|vertex| {
            Vec3A::new(
                self.v[vertex][0][i],
                self.v[vertex][1][i],
                self.v[vertex][2][i],
            )
        })
    }

    /// Scene index of the triangle in lane `i`.
    pub fn prim(&self, i: usize) -> u32 {
        self.prim[i]
    }

    /// The triangle in lane `i` broadcast to all four lanes, for testing four rays.
    #[inline(always)]
    pub(super) fn broadcast(&self, i: usize) -> [[Vec4; 3]; 3] {
        // Written out: `array::map` here was sometimes left as a call with copies
        // (seen as a 40 % slower box after an unrelated change elsewhere).
        let s = |vertex: usize, axis: usize| Vec4::splat(self.v[vertex][axis][i]);
        [
            [s(0, 0), s(0, 1), s(0, 2)],
            [s(1, 0), s(1, 1), s(1, 2)],
            [s(2, 0), s(2, 1), s(2, 2)],
        ]
    }

    /// How many lanes hold distinct triangles (the rest repeat the last one).
    #[inline(always)]
    pub(super) fn len(&self) -> usize {
        1 + (1..4)
            .take_while(|&i| self.prim[i] != self.prim[i - 1])
            .count()
    }
}

/// Per-ray constants of the four-wide test.
#[derive(Clone, Copy, Debug)]
pub struct PacketRay {
    pub(super) k: [usize; 3],
    pub(super) origin: [Vec4; 3],
    pub(super) shear: [Vec4; 3],
    ray: Ray,
}

impl PacketRay {
    /// Precomputes the axis permutation and shear (see [`RayShear`]).
    #[inline(always)]
    pub fn new(origin: Vec3A, dir: Vec3A) -> Self {
        let (d, o) = (dir.to_array(), origin.to_array());
        let [kx, ky, kz] = axis_order(dir);
        let inv_z = 1.0 / d[kz];
        Self {
            k: [kx, ky, kz],
            origin: [Vec4::splat(o[kx]), Vec4::splat(o[ky]), Vec4::splat(o[kz])],
            shear: [
                Vec4::splat(d[kx] * inv_z),
                Vec4::splat(d[ky] * inv_z),
                Vec4::splat(inv_z),
            ],
            ray: Ray::new(origin, dir),
        }
    }

    /// The constants of a ray whose axis order `k`, origin coordinates in that
    /// order and shear are made elsewhere, as [`PacketRay::new`] makes them
    /// (`bvh::single8`, eight rays at a time).
    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    pub(super) fn from_parts(k: [usize; 3], origin: [Vec4; 3], shear: [Vec4; 3], ray: Ray) -> Self {
        Self {
            k,
            origin,
            shear,
            ray,
        }
    }
}

/// Which lanes hit within `(0, t_max]`, with their `t`, edge functions and `det`.
pub(super) struct Candidates {
    pub(super) valid: BVec4A,
    pub(super) t: Vec4,
    pub(super) v: Vec4,
    pub(super) w: Vec4,
    pub(super) det: Vec4,
}

/// The watertight test of [`crate::geometry::triangle::intersect`] on four lanes: either one
/// ray against four triangles or four rays against one triangle (broadcast). Each
/// lane computes exactly the scalar test's operations, so the answers agree bit for
/// bit. `Err` means an edge function was exactly zero somewhere: the caller
/// must ask the scalar test, which has the f64 fallback for that case.
#[inline(always)]
pub(super) fn candidates(
    vertices: &[[Vec4; 3]; 3],
    k: [usize; 3],
    origin: &[Vec4; 3],
    shear: &[Vec4; 3],
    t_max: Vec4,
) -> Result<Candidates, ()> {
    let [kx, ky, kz] = k;
    let [sx, sy, sz] = *shear;
    let xform = |vertex: &[Vec4; 3]| {
        let dx = vertex[kx] - origin[0];
        let dy = vertex[ky] - origin[1];
        let dz = vertex[kz] - origin[2];
        (dx - sx * dz, dy - sy * dz, sz * dz)
    };
    let p = vertices;
    let (ax, ay, az) = xform(&p[0]);
    let (bx, by, bz) = xform(&p[1]);
    let (cx, cy, cz) = xform(&p[2]);
    let u = cx * by - cy * bx;
    let v = ax * cy - ay * cx;
    let w = bx * ay - by * ax;
    let zero = Vec4::ZERO;
    // Exact zeros need the f64 edge functions: let the scalar test decide.
    if (u.cmpeq(zero) | v.cmpeq(zero) | w.cmpeq(zero)).any() {
        return Err(());
    }
    let any_neg = u.cmplt(zero) | v.cmplt(zero) | w.cmplt(zero);
    let any_pos = u.cmpgt(zero) | v.cmpgt(zero) | w.cmpgt(zero);
    let det = u + v + w;
    let t_scaled = (u * az + v * bz + w * cz) * det.signum();
    let abs_det = det.abs();
    let mut valid = !(any_neg & any_pos)
        & det.cmpne(zero)
        & t_scaled.cmpgt(zero)
        & t_scaled.cmple(t_max * abs_det);
    if !valid.any() {
        return Ok(Candidates {
            valid,
            t: zero,
            v,
            w,
            det,
        });
    }
    let t = t_scaled / abs_det;
    // The conservative positive-t test of the scalar version, lane by lane.
    let delta_t = t_error_bound([ax, ay, az], [bx, by, bz], [cx, cy, cz], [u, v, w], abs_det);
    // And within `t_max` after the division, as the scalar test.
    valid &= t.cmpgt(delta_t) & t.cmple(Vec4::splat(f32::MAX)) & t.cmple(t_max);
    Ok(Candidates {
        valid,
        t,
        v,
        w,
        det,
    })
}

/// The closest hit among the four triangles: `(lane, hit)`.
#[inline(always)]
pub fn intersect(r: &PacketRay, p: &Packet, t_max: f32) -> Option<(usize, TriangleHit)> {
    let Ok(c) = candidates(&p.v, r.k, &r.origin, &r.shear, Vec4::splat(t_max)) else {
        return scalar_closest(r, p, t_max);
    };
    let mask = c.valid.bitmask();
    if mask == 0 {
        return None;
    }
    let t = Vec4::select(c.valid, c.t, Vec4::INFINITY);
    let t_min = t.min_element();
    let lane = (t.cmpeq(Vec4::splat(t_min)).bitmask() & mask).trailing_zeros() as usize;
    let inv = 1.0 / c.det[lane];
    Some((
        lane,
        TriangleHit {
            t: c.t[lane],
            b1: c.v[lane] * inv,
            b2: c.w[lane] * inv,
        },
    ))
}

/// Whether any of the four triangles is hit within `(0, t_max]`.
#[inline(always)]
pub fn occluded(r: &PacketRay, p: &Packet, t_max: f32) -> bool {
    match candidates(&p.v, r.k, &r.origin, &r.shear, Vec4::splat(t_max)) {
        Ok(c) => c.valid.any(),
        Err(()) => scalar_closest(r, p, t_max).is_some(),
    }
}

#[cold]
fn scalar_closest(r: &PacketRay, p: &Packet, t_max: f32) -> Option<(usize, TriangleHit)> {
    let shear = RayShear::new(&r.ray);
    let mut best: Option<(usize, TriangleHit)> = None;
    for lane in 0..4 {
        let limit = best.map_or(t_max, |(_, h)| h.t);
        if let Some(h) = triangle::intersect(&shear, &p.triangle(lane), limit)
            && best.is_none_or(|(_, b)| h.t < b.t)
        {
            best = Some((lane, h));
        }
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::sampler::Rng;

    #[test]
    fn four_wide_test_agrees_with_the_scalar_test() {
        let mut rng = Rng::new(11, 0);
        let p3 =
            |rng: &mut Rng, s: f32| Vec3A::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * s;
        let mut hits = 0;
        for round in 0..4000 {
            let n = 1 + round % 4;
            let tris: Vec<(Triangle, u32)> = (0..n)
                .map(|i| {
                    let c = p3(&mut rng, 2.0) - 1.0;
                    let (e1, e2) = (p3(&mut rng, 1.0) - 0.5, p3(&mut rng, 1.0) - 0.5);
                    (Triangle::new(c, c + e1, c + e2), i as u32 * 7)
                })
                .collect();
            let packet = Packet::new(&tris);
            let origin = p3(&mut rng, 4.0) - 2.0;
            // Aim at a point of one of the triangles (sometimes just outside it).
            let (tri, _) = tris[round % n];
            let (s1, s2) = (rng.next_f32() * 1.2, rng.next_f32() * 1.2);
            let (s1, s2) = if s1 + s2 > 1.2 {
                (1.2 - s1, 1.2 - s2)
            } else {
                (s1, s2)
            };
            let target = tri.v[0] + s1 * (tri.v[1] - tri.v[0]) + s2 * (tri.v[2] - tri.v[0]);
            let dir = (target - origin).normalize();
            let ray = Ray::new(origin, dir);
            let pr = PacketRay::new(origin, dir);
            let s = RayShear::new(&ray);
            let t_max = if round % 3 == 0 { 1.0 } else { f32::INFINITY };
            let want = tris
                .iter()
                .filter_map(|(t, id)| triangle::intersect(&s, &t.v, t_max).map(|h| (h, *id)))
                .min_by(|a, b| a.0.t.total_cmp(&b.0.t));
            let got = intersect(&pr, &packet, t_max).map(|(lane, h)| (h, packet.prim(lane)));
            assert_eq!(got.is_some(), want.is_some(), "round {round}");
            assert_eq!(occluded(&pr, &packet, t_max), want.is_some());
            if let (Some((g, gid)), Some((w, wid))) = (got, want) {
                hits += 1;
                assert_eq!(gid, wid);
                assert!((g.t - w.t).abs() <= 1e-6 * w.t);
                assert!((g.b1 - w.b1).abs() < 1e-5 && (g.b2 - w.b2).abs() < 1e-5);
            }
        }
        assert!(hits > 1500, "{hits}");
    }
}
