//! A coarse grid of upper bounds of a field ([`Majorants`]), so that delta
//! and ratio tracking take steps sized by the extinction near them rather
//! than by the medium's largest anywhere: a sparse cloud's empty space is
//! crossed in one step. Cells cover the field's unit cube; each holds the
//! largest value the field's trilinear lookups can take inside it (every
//! sample whose reach overlaps the cell). [`Segments`] walks a ray through
//! the cells (Amanatides and Woo's traversal).

use glam::Vec3A;

use super::sparse::SparseGrid;

/// Most cells along an axis.
pub const MAX_CELLS: u32 = 64;

/// Upper bounds of a field over a grid of cells of its unit cube.
#[derive(Clone, Debug, PartialEq)]
pub struct Majorants {
    res: [u32; 3],
    /// x fastest.
    values: Vec<f32>,
}

impl Majorants {
    fn empty(res: [u32; 3]) -> Majorants {
        let n = res.iter().map(|&r| r as usize).product();
        Majorants {
            res,
            values: vec![0.0; n],
        }
    }

    /// Raises the cells that overlap the box `lo..hi` of the unit cube to
    /// at least `v` (a sliver beyond the box is included, against rounding).
    fn raise(&mut self, lo: Vec3A, hi: Vec3A, v: f32) {
        let r = Vec3A::new(self.res[0] as f32, self.res[1] as f32, self.res[2] as f32);
        let a = ((lo - 1e-4) * r).floor().max(Vec3A::ZERO);
        let b = ((hi + 1e-4) * r).floor().min(r - 1.0);
        if a.cmpgt(b).any() {
            return;
        }
        for z in a.z as u32..=b.z as u32 {
            for y in a.y as u32..=b.y as u32 {
                for x in a.x as u32..=b.x as u32 {
                    let i = ((z * self.res[1] + y) * self.res[0] + x) as usize;
                    self.values[i] = self.values[i].max(v);
                }
            }
        }
    }

    /// Bounds of a dense grid of `n` samples, `sample(x, y, z)` the largest
    /// channel of each (cell-centred samples: sample `i` of `n` reaches from
    /// `(i − ½)/n` to `(i + 1½)/n`).
    pub fn of_grid(n: [u32; 3], sample: impl Fn(u32, u32, u32) -> f32) -> Majorants {
        let res = n.map(|k| k.div_ceil(4).clamp(1, MAX_CELLS));
        let mut m = Majorants::empty(res);
        let nf = Vec3A::new(n[0] as f32, n[1] as f32, n[2] as f32);
        for z in 0..n[2] {
            for y in 0..n[1] {
                for x in 0..n[0] {
                    let v = sample(x, y, z);
                    if v > 0.0 {
                        let i = Vec3A::new(x as f32, y as f32, z as f32);
                        m.raise((i - 0.5) / nf, (i + 1.5) / nf, v);
                    }
                }
            }
        }
        m
    }

    /// Bounds of a sparse grid whose unit cube is the index box `lo..hi`:
    /// each leaf's and tile's largest value over its voxels' reach (one voxel
    /// each way).
    pub fn of_sparse(grid: &SparseGrid, lo: Vec3A, hi: Vec3A) -> Majorants {
        let size = hi - lo;
        let res = [0, 1, 2].map(|k| ((size[k] / 16.0).ceil() as u32).clamp(1, MAX_CELLS));
        let mut m = Majorants::empty(res);
        grid.for_each_block(|origin, dim, max| {
            let o = Vec3A::new(origin[0] as f32, origin[1] as f32, origin[2] as f32);
            let reach_lo = o - 1.0;
            let reach_hi = o + dim as f32;
            m.raise((reach_lo - lo) / size, (reach_hi - lo) / size, max);
        });
        m
    }

    /// The largest bound of all.
    pub fn max(&self) -> f32 {
        self.values.iter().copied().fold(0.0, f32::max)
    }

    /// The cells along the ray `o + t d` (in unit-cube coordinates) from
    /// `t0` to `t1`, both within the cube's span of the ray.
    pub fn segments(&self, o: Vec3A, d: Vec3A, t0: f32, t1: f32) -> Segments<'_> {
        let r = Vec3A::new(self.res[0] as f32, self.res[1] as f32, self.res[2] as f32);
        let p = (o + d * t0) * r;
        let hi = r - 1.0;
        let cell = p.floor().clamp(Vec3A::ZERO, hi);
        let step = Vec3A::select(d.cmplt(Vec3A::ZERO), Vec3A::NEG_ONE, Vec3A::ONE);
        // Cells per unit of t along each axis, and the t of the next face.
        let inv = (d * r).recip();
        let next_face = cell + Vec3A::select(d.cmplt(Vec3A::ZERO), Vec3A::ZERO, Vec3A::ONE);
        let t_next = Vec3A::select(
            d.cmpeq(Vec3A::ZERO),
            Vec3A::INFINITY,
            t0 + (next_face - p) * inv,
        );
        let t_delta = Vec3A::select(d.cmpeq(Vec3A::ZERO), Vec3A::INFINITY, inv.abs());
        Segments {
            m: self,
            cell: [cell.x as i32, cell.y as i32, cell.z as i32],
            step: [step.x as i32, step.y as i32, step.z as i32],
            t_next,
            t_delta,
            t: t0,
            t1,
        }
    }
}

/// The cells a ray crosses: `(t_enter, t_leave, bound)` in order.
pub struct Segments<'a> {
    m: &'a Majorants,
    cell: [i32; 3],
    step: [i32; 3],
    t_next: Vec3A,
    t_delta: Vec3A,
    t: f32,
    t1: f32,
}

impl Iterator for Segments<'_> {
    type Item = (f32, f32, f32);

    #[inline]
    fn next(&mut self) -> Option<(f32, f32, f32)> {
        if self.t >= self.t1 {
            return None;
        }
        let res = self.m.res;
        let inside = (0..3).all(|k| self.cell[k] >= 0 && self.cell[k] < res[k] as i32);
        if !inside {
            // Rounding took the walk out of the cube: the rest of the span
            // is its face's sliver; bound it by the largest value of all.
            let seg = (self.t, self.t1, self.m.max());
            self.t = self.t1;
            return Some(seg);
        }
        let i = ((self.cell[2] as u32 * res[1] + self.cell[1] as u32) * res[0]
            + self.cell[0] as u32) as usize;
        let v = self.m.values[i];
        let axis = if self.t_next.x <= self.t_next.y && self.t_next.x <= self.t_next.z {
            0
        } else if self.t_next.y <= self.t_next.z {
            1
        } else {
            2
        };
        let leave = self.t_next[axis].min(self.t1);
        let seg = (self.t, leave, v);
        self.t = leave;
        self.cell[axis] += self.step[axis];
        self.t_next[axis] += self.t_delta[axis];
        Some(seg)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3A;

    /// Every trilinear lookup along random rays lies under its cell's
    /// bound, and the segments tile the span without gaps.
    #[test]
    fn bounds_hold_along_rays_and_segments_tile_the_span() {
        let grid = super::super::grid::random_grid([13, 7, 9], 5, 0.7, 10.0);
        let mut state = 99u32;
        let mut next = || {
            state = state.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
            (state >> 8) as f32 / (1u32 << 24) as f32
        };
        let m = Majorants::of_grid(grid.resolution(), |x, y, z| grid.sample(x, y, z).x);
        assert!((m.max() - grid.max()).abs() < 1e-6);
        for _ in 0..300 {
            let o = Vec3A::new(next(), next(), next());
            let d = (Vec3A::new(next(), next(), next()) - 0.5).normalize();
            // The span of the ray inside the cube, from o.
            let inv = d.recip();
            let a = (Vec3A::ZERO - o) * inv;
            let b = (Vec3A::ONE - o) * inv;
            let t1 = a.max(b).min_element();
            let mut t = 0.0;
            for (ta, tb, bound) in m.segments(o, d, 0.0, t1) {
                assert!((ta - t).abs() < 1e-6, "a gap at {t}: {ta}");
                assert!(tb >= ta);
                for k in 0..8 {
                    let s = ta + (tb - ta) * (k as f32 + 0.5) / 8.0;
                    let v = grid.eval(o + d * s, false).x;
                    assert!(v <= bound + 1e-5, "{v} over {bound} at t = {s}");
                }
                t = tb;
            }
            assert!((t - t1).abs() < 1e-6);
        }
    }
}
