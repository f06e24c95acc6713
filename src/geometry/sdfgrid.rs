//! Signed distance grids ([`SdfGrid`]): Mitsuba 3's `sdfgrid` shape, a
//! grid of distance samples whose surface is the zero set of their
//! trilinear interpolation. The samples sit on the corners of the cells:
//! sample `(i, j, k)` of a grid of `nx × ny × nz` lies at
//! `(i/(nx−1), j/(ny−1), k/(nz−1))` in object space, so the grid spans the
//! unit cube `[0, 1]³` and cell `(i, j, k)` is the box between samples
//! `(i, j, k)` and `(i+1, j+1, k+1)`. Within a cell the function is the
//! trilinear interpolation of its eight corner values ([`trilinear`]); a
//! ray meets it where the cubic this makes along the ray first crosses zero
//! in the cell ([`first_crossing`], solved in double precision: the exact
//! root of the cubic, not a march).
//!
//! Normals, as Mitsuba's two modes define them: `analytic` is the gradient
//! of the cell's interpolant ([`trilinear_gradient`]); `smooth`
//! ([`SdfGrid::smooth_normal`]) blends the normalised gradients of the
//! eight cells around the sample nearest the point by the point's position
//! between their centres (Hansson-Söderlund, Evans and Akenine-Möller, "Ray
//! Tracing of Signed Distance Function Grids", JCGT 11(3), 2022), each
//! cell's gradient being the differences of the whole grid's interpolant
//! across the cell at the point's other two coordinates (Mitsuba 3.7.1's
//! `smooth_sh` and `voxel_grad`, sample indices clamped to the grid).
//!
//! Corner values are indexed `x + 2y + 4z` from the cell's lower corner.
//! The placed cells the scene's hierarchy holds are in `sdf_voxel.rs`.

use glam::DVec3;

/// A grid of signed distance samples (Mitsuba's `sdfgrid` data: the
/// single channel of a `.vol` file), `x` varying fastest.
#[derive(Clone, PartialEq)]
pub struct SdfGrid {
    /// Samples along x, y and z (each at least 2).
    res: [u32; 3],
    /// `res[0] · res[1] · res[2]` finite values, x fastest, then y, then z.
    values: Vec<f32>,
}

impl std::fmt::Debug for SdfGrid {
    /// The size and a hash of the values (the scene's fingerprint reads
    /// this; printing every sample would be long).
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        use std::hash::{Hash, Hasher};
        let mut h = std::collections::hash_map::DefaultHasher::new();
        for v in &self.values {
            v.to_bits().hash(&mut h);
        }
        write!(
            f,
            "SdfGrid {}x{}x{} #{:016x}",
            self.res[0],
            self.res[1],
            self.res[2],
            h.finish()
        )
    }
}

impl SdfGrid {
    /// The grid of `res` samples with `values` (x fastest); an error line
    /// when a side has fewer than 2 samples, the count does not match, or a
    /// value is not finite.
    pub fn new(res: [u32; 3], values: Vec<f32>) -> Result<Self, String> {
        if res.iter().any(|&n| n < 2) {
            return Err(format!(
                "an SDF grid needs at least 2 samples along each axis (it has {}x{}x{})",
                res[0], res[1], res[2]
            ));
        }
        let count = res
            .iter()
            .try_fold(1usize, |acc, &n| acc.checked_mul(n as usize));
        if count != Some(values.len()) {
            return Err(format!(
                "an SDF grid of {}x{}x{} samples needs that many values, not {}",
                res[0],
                res[1],
                res[2],
                values.len()
            ));
        }
        if let Some(i) = values.iter().position(|v| !v.is_finite()) {
            return Err(format!("SDF grid value {i} is {} (not finite)", values[i]));
        }
        Ok(Self { res, values })
    }

    /// Bytes the samples take.
    pub fn memory_bytes(&self) -> usize {
        std::mem::size_of_val(self.values.as_slice())
    }

    /// Samples along x, y and z.
    #[inline]
    pub fn resolution(&self) -> [u32; 3] {
        self.res
    }

    /// Cells along each axis (`resolution − 1`), as `f64`: the scale from
    /// object to cell units.
    #[inline]
    pub fn cells(&self) -> DVec3 {
        DVec3::new(
            f64::from(self.res[0] - 1),
            f64::from(self.res[1] - 1),
            f64::from(self.res[2] - 1),
        )
    }

    /// The sample at `(x, y, z)`, each index clamped to the grid.
    #[inline]
    pub fn sample(&self, x: i64, y: i64, z: i64) -> f32 {
        let c = |i: i64, n: u32| i.clamp(0, i64::from(n) - 1) as usize;
        let (x, y, z) = (c(x, self.res[0]), c(y, self.res[1]), c(z, self.res[2]));
        self.values[(z * self.res[1] as usize + y) * self.res[0] as usize + x]
    }

    /// The eight corner values of cell `cell` (indexed `x + 2y + 4z`).
    pub fn corners(&self, cell: [u32; 3]) -> [f32; 8] {
        let [x, y, z] = cell.map(i64::from);
        std::array::from_fn(|i| {
            self.sample(
                x + (i & 1) as i64,
                y + ((i >> 1) & 1) as i64,
                z + (i >> 2) as i64,
            )
        })
    }

    /// The cells the surface may pass through, in x-fastest order: those
    /// whose corners are neither all positive nor all negative (Mitsuba's
    /// occupied voxels; a corner at zero counts).
    pub fn surface_cells(&self) -> impl Iterator<Item = [u32; 3]> + '_ {
        let [nx, ny, nz] = self.res.map(|n| n - 1);
        (0..nz)
            .flat_map(move |z| (0..ny).flat_map(move |y| (0..nx).map(move |x| [x, y, z])))
            .filter(|&cell| {
                let c = self.corners(cell);
                !(c.iter().all(|&v| v > 0.0) || c.iter().all(|&v| v < 0.0))
            })
    }

    /// The grid's interpolant on the sample plane `index` of `axis` (its
    /// index clamped to the grid), bilinear in the other two axes at the
    /// object point `p`'s coordinates (their sample indices clamped, as
    /// Mitsuba's texture lookups clamp).
    fn plane(&self, axis: usize, index: i64, p: DVec3) -> f64 {
        let (b, c) = ((axis + 1) % 3, (axis + 2) % 3);
        let cells = self.cells();
        let (sb, sc) = (p[b] * cells[b], p[c] * cells[c]);
        let (fb, fc) = (sb.floor(), sc.floor());
        let (wb, wc) = (sb - fb, sc - fc);
        let (ib, ic) = (fb as i64, fc as i64);
        let at = |db: i64, dc: i64| {
            let mut idx = [0i64; 3];
            idx[axis] = index;
            idx[b] = ib + db;
            idx[c] = ic + dc;
            f64::from(self.sample(idx[0], idx[1], idx[2]))
        };
        let lo = at(0, 0) + wb * (at(1, 0) - at(0, 0));
        let hi = at(0, 1) + wb * (at(1, 1) - at(0, 1));
        lo + wc * (hi - lo)
    }

    /// Mitsuba's `smooth` shading normal at the object point `p`, in object
    /// space (not normalised; the caller maps it by the inverse transpose
    /// and normalises). The eight cells around the sample nearest `p`
    /// (lower corner `round(p·cells) − 1`) each give their gradient, the
    /// differences of the grid's interpolant between the cell's two sample
    /// planes along each axis at `p`'s other coordinates, normalised; these
    /// are blended trilinearly by `p`'s position between the cells'
    /// centres. Cells before the grid's start give nothing and the weight
    /// along their axis goes wholly to the cells after.
    pub fn smooth_normal(&self, p: DVec3) -> DVec3 {
        let cells = self.cells();
        let s = p * cells;
        let lower = [0, 1, 2].map(|a| s[a].round_ties_even() as i64 - 1);
        let mut w = DVec3::new(
            s.x - lower[0] as f64 - 0.5,
            s.y - lower[1] as f64 - 0.5,
            s.z - lower[2] as f64 - 0.5,
        );
        for a in 0..3 {
            if lower[a] < 0 {
                w[a] = 1.0;
            }
        }
        let mut sum = DVec3::ZERO;
        for i in 0..8usize {
            let v = [
                lower[0] + (i & 1) as i64,
                lower[1] + ((i >> 1) & 1) as i64,
                lower[2] + (i >> 2) as i64,
            ];
            if v.iter().any(|&k| k < 0) {
                continue;
            }
            let g = DVec3::new(
                (self.plane(0, v[0] + 1, p) - self.plane(0, v[0], p)) * cells.x,
                (self.plane(1, v[1] + 1, p) - self.plane(1, v[1], p)) * cells.y,
                (self.plane(2, v[2] + 1, p) - self.plane(2, v[2], p)) * cells.z,
            );
            let weight = (if i & 1 != 0 { w.x } else { 1.0 - w.x })
                * (if i & 2 != 0 { w.y } else { 1.0 - w.y })
                * (if i & 4 != 0 { w.z } else { 1.0 - w.z });
            sum += weight * g.normalize_or_zero();
        }
        sum
    }
}

/// The trilinear interpolation of the corner values `c` at `q` (cell
/// units, `[0, 1]³` inside the cell).
#[inline]
pub fn trilinear(c: &[f32; 8], q: DVec3) -> f64 {
    let c = c.map(f64::from);
    let lerp = |a: f64, b: f64, t: f64| a + t * (b - a);
    let face = |o: usize| {
        lerp(
            lerp(c[o], c[o + 1], q.x),
            lerp(c[o + 2], c[o + 3], q.x),
            q.y,
        )
    };
    lerp(face(0), face(4), q.z)
}

/// The gradient of [`trilinear`] at `q`, per cell unit.
#[inline]
pub fn trilinear_gradient(c: &[f32; 8], q: DVec3) -> DVec3 {
    let c = c.map(f64::from);
    let bilerp = |v: [f64; 4], u: f64, w: f64| {
        let lo = v[0] + u * (v[1] - v[0]);
        let hi = v[2] + u * (v[3] - v[2]);
        lo + w * (hi - lo)
    };
    DVec3::new(
        bilerp(
            [c[1] - c[0], c[3] - c[2], c[5] - c[4], c[7] - c[6]],
            q.y,
            q.z,
        ),
        bilerp(
            [c[2] - c[0], c[3] - c[1], c[6] - c[4], c[7] - c[5]],
            q.x,
            q.z,
        ),
        bilerp(
            [c[4] - c[0], c[5] - c[1], c[6] - c[2], c[7] - c[3]],
            q.x,
            q.y,
        ),
    )
}

/// The coefficients `[k0, k1, k2, k3]` of the cubic `k0 + k1 s + k2 s² +
/// k3 s³` that [`trilinear`] is along the line `e + s d` (cell units).
fn cubic_along(c: &[f32; 8], e: DVec3, d: DVec3) -> [f64; 4] {
    let c = c.map(f64::from);
    // A bilinear function a0 + a1 x + a2 y + a3 xy of the four values `v`
    // (indexed x + 2y) along the line: a quadratic in s.
    let along = |v: [f64; 4]| {
        let (a0, a1, a2, a3) = (v[0], v[1] - v[0], v[2] - v[0], v[3] - v[2] - v[1] + v[0]);
        [
            a0 + a1 * e.x + a2 * e.y + a3 * e.x * e.y,
            a1 * d.x + a2 * d.y + a3 * (e.x * d.y + e.y * d.x),
            a3 * d.x * d.y,
        ]
    };
    // f = A + z (B − A), A on the face z = 0 and B on z = 1.
    let a = along([c[0], c[1], c[2], c[3]]);
    let b = along([c[4], c[5], c[6], c[7]]);
    let dz = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
    [
        a[0] + e.z * dz[0],
        a[1] + e.z * dz[1] + d.z * dz[0],
        a[2] + e.z * dz[2] + d.z * dz[1],
        d.z * dz[2],
    ]
}

/// `k0 + k1 s + k2 s² + k3 s³` by Horner's rule.
#[inline]
fn horner(k: &[f64; 4], s: f64) -> f64 {
    ((k[3] * s + k[2]) * s + k[1]) * s + k[0]
}

/// The real roots of `a s² + b s + c` in increasing order (`None` for
/// none; a single root twice when `a` is zero), without cancellation.
fn quadratic_roots(a: f64, b: f64, c: f64) -> Option<(f64, f64)> {
    if a == 0.0 {
        if b == 0.0 {
            return None;
        }
        let r = -c / b;
        return Some((r, r));
    }
    let disc = b * b - 4.0 * a * c;
    if disc < 0.0 {
        return None;
    }
    let q = -0.5 * (b + b.signum() * disc.sqrt());
    let (r0, r1) = if q == 0.0 { (0.0, 0.0) } else { (q / a, c / q) };
    Some(if r0 <= r1 { (r0, r1) } else { (r1, r0) })
}

/// The root of the cubic `k` between `lo` and `hi`, where it has the values
/// `f_lo` and `f_hi` of opposite signs (or one of them zero) and is
/// monotone: Newton's method kept inside the shrinking bracket (bisection
/// where a step would leave it), to the last bits of `f64`.
fn bracketed_root(k: &[f64; 4], mut lo: f64, mut hi: f64, f_lo: f64, f_hi: f64) -> f64 {
    if f_lo == 0.0 {
        return lo;
    }
    if f_hi == 0.0 {
        return hi;
    }
    let rising = f_hi > 0.0;
    let mut t = lo + (hi - lo) * (f_lo / (f_lo - f_hi));
    if !(t > lo && t < hi) {
        t = 0.5 * (lo + hi);
    }
    for _ in 0..100 {
        let f = horner(k, t);
        if f == 0.0 {
            return t;
        }
        if (f > 0.0) == rising {
            hi = t;
        } else {
            lo = t;
        }
        let slope = (3.0 * k[3] * t + 2.0 * k[2]) * t + k[1];
        let mut next = t - f / slope;
        if !(next > lo && next < hi) {
            next = 0.5 * (lo + hi);
        }
        if next == t || hi - lo <= 4.0 * f64::EPSILON * hi.abs().max(lo.abs()) {
            return next;
        }
        t = next;
    }
    t
}

/// The first `t` in `(0, t_max]` where the trilinear interpolant of the
/// corner values `c` is zero along the line `o + t d` (cell units) inside
/// the cell `[0, 1]³`: the first sign change of the cubic along the ray's
/// segment in the cell, found between the roots of its derivative (so each
/// piece is monotone) and solved to `f64` precision. A touch without a sign
/// change (a double root) is not a crossing unless it is exactly zero.
pub fn first_crossing(c: &[f32; 8], o: DVec3, d: DVec3, t_max: f64) -> Option<f64> {
    // The segment of the line inside the cell (and in (0, t_max]).
    let (mut t_in, mut t_out) = (0.0f64, t_max);
    let (mut face_in, mut face_out) = (None, None);
    for a in 0..3 {
        if d[a] == 0.0 {
            if !(0.0..=1.0).contains(&o[a]) {
                return None;
            }
            continue;
        }
        let (t0, t1) = ((0.0 - o[a]) / d[a], (1.0 - o[a]) / d[a]);
        let (near, far, up) = if t0 <= t1 {
            (t0, t1, true)
        } else {
            (t1, t0, false)
        };
        if near > t_in {
            t_in = near;
            face_in = Some((a, up));
        }
        if far < t_out {
            t_out = far;
            face_out = Some((a, up));
        }
    }
    if t_in.is_nan() || t_out.is_nan() || t_in > t_out || d == DVec3::ZERO {
        return None;
    }
    // The ends, clamped into the cell and put exactly on the face they
    // cross (so that two neighbouring cells see the same values there).
    let end = |t: f64, face: Option<(usize, bool)>, entering: bool| {
        let mut p = (o + t * d).clamp(DVec3::ZERO, DVec3::ONE);
        if let Some((a, up)) = face {
            p[a] = if up == entering { 0.0 } else { 1.0 };
        }
        p
    };
    let e = end(t_in, face_in, true);
    let f_in = trilinear(c, e);
    let f_out = trilinear(c, end(t_out, face_out, false));
    let length = t_out - t_in;
    let k = cubic_along(c, e, d);
    // Split at the derivative's roots inside the segment.
    let mut stops = [length; 3];
    let mut n = 0;
    if let Some((r0, r1)) = quadratic_roots(3.0 * k[3], 2.0 * k[2], k[1]) {
        for r in [r0, r1] {
            if r > 0.0 && r < length && (n == 0 || r > stops[n - 1]) {
                stops[n] = r;
                n += 1;
            }
        }
    }
    stops[n] = length;
    let (mut s0, mut f0) = (0.0, f_in);
    for (i, &s1) in stops[..=n].iter().enumerate() {
        let f1 = if i == n { f_out } else { horner(&k, s1) };
        if f0 * f1 <= 0.0 {
            let t = t_in + bracketed_root(&k, s0, s1, f0, f1);
            if t > 0.0 && t <= t_max {
                return Some(t);
            }
        }
        (s0, f0) = (s1, f1);
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::sampler::Rng;

    fn random_corners(rng: &mut Rng) -> [f32; 8] {
        std::array::from_fn(|_| rng.next_f32() * 2.0 - 1.0)
    }

    /// The first zero of the trilinear function along the ray inside the
    /// cell, by dense sampling and bisection of every sign change.
    fn brute_force(c: &[f32; 8], o: DVec3, d: DVec3) -> Option<f64> {
        // The segment inside the cell, by slabs.
        let (mut t0, mut t1) = (0.0f64, f64::INFINITY);
        for a in 0..3 {
            let (u, v) = ((0.0 - o[a]) / d[a], (1.0 - o[a]) / d[a]);
            t0 = t0.max(u.min(v));
            t1 = t1.min(u.max(v));
        }
        if t0 > t1 {
            return None;
        }
        let f = |t: f64| trilinear(c, o + t * d);
        let steps = 20_000;
        let (mut tp, mut fp) = (t0, f(t0));
        if fp == 0.0 {
            return Some(t0);
        }
        for i in 1..=steps {
            let t = t0 + (t1 - t0) * f64::from(i) / f64::from(steps);
            let ft = f(t);
            if fp * ft <= 0.0 {
                let (mut lo, mut hi) = (tp, t);
                for _ in 0..200 {
                    let mid = 0.5 * (lo + hi);
                    if (f(mid) > 0.0) == (fp > 0.0) {
                        lo = mid;
                    } else {
                        hi = mid;
                    }
                }
                return Some(0.5 * (lo + hi));
            }
            (tp, fp) = (t, ft);
        }
        None
    }

    /// The cubic's first crossing agrees with bisection of the trilinear
    /// function sampled along the ray, on random cells and rays from
    /// outside and inside the cell.
    #[test]
    fn the_cubic_root_is_the_first_zero_along_the_ray() {
        let mut rng = Rng::new(17, 3);
        let (mut hits, mut misses) = (0, 0);
        for i in 0..3000 {
            let c = random_corners(&mut rng);
            let mut r = || f64::from(rng.next_f32());
            let o = if i % 2 == 0 {
                DVec3::new(r(), r(), r())
            } else {
                DVec3::new(r() * 3.0 - 1.0, r() * 3.0 - 1.0, r() * 3.0 - 1.0)
            };
            let target = DVec3::new(r(), r(), r());
            let d = (target - o).normalize_or(DVec3::X) * (0.5 + r());
            let got = first_crossing(&c, o, d, f64::INFINITY);
            let want = brute_force(&c, o, d);
            match (got, want) {
                (Some(g), Some(w)) => {
                    // The sampling step bounds where bisection starts: a
                    // crossing pair closer than a step can be missed by
                    // sampling, so compare the zero itself too.
                    assert!(
                        (g - w).abs() < 1e-9 || trilinear(&c, o + g * d).abs() < 1e-12,
                        "cell {c:?} o {o} d {d}: {g} vs {w}"
                    );
                    assert!(g <= w + 1e-9, "not the first: {g} vs {w}");
                    hits += 1;
                }
                (None, None) => misses += 1,
                (g, w) => {
                    // Only a grazing pair of roots closer than the sampling
                    // step may be seen by one and not the other.
                    let g = g.or(w).unwrap();
                    let slope = trilinear_gradient(&c, o + g * d).dot(d).abs();
                    assert!(slope < 1e-3, "cell {c:?} o {o} d {d}: {got:?} vs {want:?}");
                }
            }
        }
        assert!(hits > 500 && misses > 500, "{hits} hits, {misses} misses");
    }

    /// `t_max` cuts the search, and a crossing at `t ≤ 0` is not one.
    #[test]
    fn crossings_are_kept_within_t_max_and_ahead() {
        // f = x − 0.5: the plane x = 0.5.
        let c = [-0.5, 0.5, -0.5, 0.5, -0.5, 0.5, -0.5, 0.5];
        let o = DVec3::new(-1.0, 0.5, 0.5);
        let t = first_crossing(&c, o, DVec3::X, f64::INFINITY).unwrap();
        assert!((t - 1.5).abs() < 1e-15, "{t}");
        assert_eq!(first_crossing(&c, o, DVec3::X, 1.4), None);
        // From the far side inside, looking away: nothing ahead.
        assert_eq!(
            first_crossing(&c, DVec3::new(0.7, 0.5, 0.5), DVec3::X, 10.0),
            None
        );
        // Along a face of the cell (d's other components zero).
        let t = first_crossing(&c, DVec3::new(0.0, 1.0, 0.0), DVec3::X, 10.0).unwrap();
        assert!((t - 0.5).abs() < 1e-15);
    }

    /// The gradient is the central difference of the interpolant.
    #[test]
    fn the_gradient_is_the_interpolants_derivative() {
        let mut rng = Rng::new(5, 8);
        for _ in 0..1000 {
            let c = random_corners(&mut rng);
            let mut r = || f64::from(rng.next_f32());
            let q = DVec3::new(r(), r(), r()) * 0.9 + 0.05;
            let g = trilinear_gradient(&c, q);
            let h = 1e-5;
            for a in 0..3 {
                let mut e = DVec3::ZERO;
                e[a] = h;
                let fd = (trilinear(&c, q + e) - trilinear(&c, q - e)) / (2.0 * h);
                assert!((fd - g[a]).abs() < 1e-8, "{fd} vs {}", g[a]);
            }
        }
    }

    /// The values at the corners are the samples, and [`trilinear`] is the
    /// grid's interpolant ([`SdfGrid::plane`]) on the sample planes.
    #[test]
    fn cells_interpolate_the_grid() {
        let mut rng = Rng::new(2, 2);
        let res = [4, 5, 3];
        let values: Vec<f32> = (0..60).map(|_| rng.next_f32() - 0.5).collect();
        let grid = SdfGrid::new(res, values.clone()).unwrap();
        // Index (z·ny + y)·nx + x.
        assert_eq!(grid.sample(1, 2, 1), values[(5 + 2) * 4 + 1]);
        assert_eq!(grid.sample(-3, 9, 1), values[(5 + 4) * 4]);
        let cell = [2, 1, 1];
        let c = grid.corners(cell);
        assert_eq!(c[7], grid.sample(3, 2, 2));
        let q = DVec3::new(0.25, 0.5, 0.0);
        let p = (DVec3::new(2.0, 1.0, 1.0) + q) / grid.cells();
        assert!((trilinear(&c, q) - grid.plane(2, 1, p)).abs() < 1e-7);
        assert!(
            SdfGrid::new([1, 4, 4], vec![0.0; 16]).is_err()
                && SdfGrid::new([2, 2, 2], vec![0.0; 7]).is_err()
                && SdfGrid::new([2, 2, 2], vec![f32::NAN; 8]).is_err()
        );
    }

    /// Away from the grid's edges, on a grid of a linear function, every
    /// cell's gradient is the same, so the smooth normal is its direction;
    /// on a sphere's distances it is close to the radial direction.
    #[test]
    fn smooth_normals_follow_the_field() {
        let n = 12u32;
        let at = |f: &dyn Fn(DVec3) -> f64| {
            let mut v = Vec::new();
            for z in 0..n {
                for y in 0..n {
                    for x in 0..n {
                        let p =
                            DVec3::new(f64::from(x), f64::from(y), f64::from(z)) / f64::from(n - 1);
                        v.push(f(p) as f32);
                    }
                }
            }
            SdfGrid::new([n; 3], v).unwrap()
        };
        let dir = DVec3::new(0.3, -0.5, 0.8);
        let plane = at(&|p| p.dot(dir) - 0.2);
        let s = plane
            .smooth_normal(DVec3::new(0.41, 0.52, 0.33))
            .normalize();
        assert!((s - dir.normalize()).length() < 1e-6, "{s}");
        let centre = DVec3::splat(0.5);
        let sphere = at(&|p| (p - centre).length() - 0.3);
        let mut rng = Rng::new(4, 4);
        for _ in 0..200 {
            let mut r = || f64::from(rng.next_f32()) * 2.0 - 1.0;
            let w = DVec3::new(r(), r(), r()).normalize_or(DVec3::Z);
            let p = centre + 0.3 * w;
            let s = sphere.smooth_normal(p).normalize();
            assert!(s.dot(w) > 0.995, "{s} vs {w}");
        }
    }
}
