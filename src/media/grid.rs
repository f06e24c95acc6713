//! Values that vary through space for heterogeneous media: [`Field`], a
//! constant or a [`Grid`] of samples (Mitsuba's `constvolume` and
//! `gridvolume`), placed by a transform whose unit cube is the field's
//! extent.
//!
//! A grid's samples sit at cell centres: sample `(i, j, k)` of an
//! `nx × ny × nz` grid is at `((i + ½)/nx, (j + ½)/ny, (k + ½)/nz)` of the
//! unit cube, and a point between them is interpolated trilinearly, with
//! positions outside the samples clamped to the outermost ones (Mitsuba
//! 3.7.1's `gridvolume` with its default `filter_type` `bilinear` and
//! `wrap_mode` `clamp`; nearest lookups are the other choice).

use std::sync::Arc;

use glam::{Affine3A, Vec3A};

use super::majorant::{Majorants, Segments};
use super::sparse::SparseGrid;

/// A grid of samples with one or three channels (RGB).
#[derive(Clone, PartialEq)]
pub struct Grid {
    res: [u32; 3],
    channels: u32,
    /// Channels fastest, then x, y and z (the `.vol` layout).
    values: Vec<f32>,
    max: f32,
}

impl std::fmt::Debug for Grid {
    /// Its size, channels and a hash of every value (for fingerprints,
    /// without printing millions of numbers).
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let mut h = 0xcbf2_9ce4_8422_2325u64;
        for v in &self.values {
            h = (h ^ u64::from(v.to_bits())).wrapping_mul(0x100_0000_01b3);
        }
        write!(
            f,
            "Grid {{ res: {:?}, channels: {}, values: {h:016x} }}",
            self.res, self.channels
        )
    }
}

impl Grid {
    /// A grid of `res` samples of `channels` (1 or 3) channels each, `values`
    /// channels fastest, then x, y, z; every value finite and ≥ 0.
    pub fn new(res: [u32; 3], channels: u32, values: Vec<f32>) -> Result<Grid, String> {
        if res.contains(&0) || !(channels == 1 || channels == 3) {
            return Err(format!(
                "a medium's grid needs at least one sample along each axis and 1 or 3 channels (it has {}x{}x{} samples of {channels})",
                res[0], res[1], res[2]
            ));
        }
        let n = res
            .iter()
            .try_fold(channels as usize, |a, &r| a.checked_mul(r as usize));
        if n != Some(values.len()) {
            return Err(format!(
                "a grid of {}x{}x{} samples of {channels} channels needs {} values, not {}",
                res[0],
                res[1],
                res[2],
                n.map_or("too many".into(), |n| n.to_string()),
                values.len()
            ));
        }
        if let Some(i) = values.iter().position(|v| !(v.is_finite() && *v >= 0.0)) {
            return Err(format!(
                "grid value {i} is {} (a medium's values must be finite and >= 0)",
                values[i]
            ));
        }
        let max = values.iter().copied().fold(0.0f32, f32::max);
        Ok(Grid {
            res,
            channels,
            values,
            max,
        })
    }

    /// Its channels per sample (1 or 3).
    #[inline]
    pub fn channels(&self) -> u32 {
        self.channels
    }

    /// The largest value of any channel.
    pub fn max(&self) -> f32 {
        self.max
    }

    /// The number of samples along x, y and z.
    pub fn resolution(&self) -> [u32; 3] {
        self.res
    }

    /// Sample `(x, y, z)` (each below the resolution), RGB (a grey grid's
    /// value thrice).
    #[inline]
    pub fn sample(&self, x: u32, y: u32, z: u32) -> Vec3A {
        self.at(x, y, z)
    }

    #[inline(always)]
    fn at(&self, x: u32, y: u32, z: u32) -> Vec3A {
        let i = (((z * self.res[1] + y) * self.res[0] + x) * self.channels) as usize;
        if self.channels == 1 {
            Vec3A::splat(self.values[i])
        } else {
            Vec3A::new(self.values[i], self.values[i + 1], self.values[i + 2])
        }
    }

    /// The value at `p` in the unit cube's coordinates (clamped outside it),
    /// trilinear or `nearest`.
    #[inline]
    pub fn eval(&self, p: Vec3A, nearest: bool) -> Vec3A {
        let res = Vec3A::new(self.res[0] as f32, self.res[1] as f32, self.res[2] as f32);
        let hi = [self.res[0] - 1, self.res[1] - 1, self.res[2] - 1];
        if nearest {
            let q = (p * res).floor();
            let i = |k: usize| (q[k].max(0.0) as u32).min(hi[k]);
            return self.at(i(0), i(1), i(2));
        }
        let q = p * res - 0.5;
        let f = q.floor();
        let w = q - f;
        let lo = |k: usize| -> (u32, u32) {
            let a = f[k];
            let i0 = (a.max(0.0) as u32).min(hi[k]);
            let i1 = ((a + 1.0).max(0.0) as u32).min(hi[k]);
            (i0, i1)
        };
        let (x0, x1) = lo(0);
        let (y0, y1) = lo(1);
        let (z0, z1) = lo(2);
        let lerp = |a: Vec3A, b: Vec3A, t: f32| a * (1.0 - t) + b * t;
        let c00 = lerp(self.at(x0, y0, z0), self.at(x1, y0, z0), w.x);
        let c10 = lerp(self.at(x0, y1, z0), self.at(x1, y1, z0), w.x);
        let c01 = lerp(self.at(x0, y0, z1), self.at(x1, y0, z1), w.x);
        let c11 = lerp(self.at(x0, y1, z1), self.at(x1, y1, z1), w.x);
        // (Rounding may carry `a(1 − t) + b t` an ulp past both ends; the
        // largest value stays a bound, as majorants need.)
        lerp(lerp(c00, c10, w.y), lerp(c01, c11, w.y), w.z).min(Vec3A::splat(self.max))
    }
}

/// What a field holds.
#[derive(Clone, Debug, PartialEq)]
pub enum FieldValues {
    /// The same value everywhere (Mitsuba's `constvolume`).
    Constant(Vec3A),
    /// Samples, interpolated (`nearest`: not).
    Grid {
        /// The samples.
        grid: Arc<Grid>,
        /// Nearest-sample lookups instead of trilinear ones.
        nearest: bool,
    },
    /// A sparse grid (an OpenVDB file's), one channel, whose unit cube is its
    /// voxels' box grown by one voxel each way (where its trilinear values
    /// reach 0).
    Sparse(Arc<SparseGrid>),
}

impl FieldValues {
    /// The box of index space (min, max) that the unit cube stands for:
    /// the unit cube itself, but a sparse grid's voxels.
    fn index_box(&self) -> (Vec3A, Vec3A) {
        match self {
            FieldValues::Sparse(g) => g.index_box(),
            _ => (Vec3A::ZERO, Vec3A::ONE),
        }
    }

    /// The map from index space to the unit cube.
    fn unit_from_index(&self) -> Affine3A {
        let (lo, hi) = self.index_box();
        Affine3A::from_scale(glam::Vec3::from(1.0 / (hi - lo)))
            * Affine3A::from_translation(glam::Vec3::from(-lo))
    }
}

/// A field placed in the scene: its values over the unit cube that
/// `to_local` maps the world to, and the world box around that cube (the
/// extent of a medium whose extinction it is).
#[derive(Clone, Debug, PartialEq)]
pub struct Field {
    /// The values.
    pub values: FieldValues,
    /// World to the unit cube's coordinates.
    pub to_local: Affine3A,
    /// The world bounds of the cube (min, max).
    pub bounds: (Vec3A, Vec3A),
    /// Bounds of its values over cells of the cube, for grids placed
    /// without rotation (whose cube then fills `bounds`).
    pub majorants: Option<Arc<Majorants>>,
}

/// The world bounds `(min, max)` of the box `lo..hi` placed by `to_world`:
/// the box around its eight corners (exact without rotation).
pub(crate) fn world_box(lo: Vec3A, hi: Vec3A, to_world: Affine3A) -> (Vec3A, Vec3A) {
    (0..8).fold(
        (Vec3A::splat(f32::INFINITY), Vec3A::splat(f32::NEG_INFINITY)),
        |(a, b), i: u32| {
            let pick = |bit: u32, l: f32, h: f32| if i >> bit & 1 == 0 { l } else { h };
            let c = Vec3A::new(
                pick(0, lo.x, hi.x),
                pick(1, lo.y, hi.y),
                pick(2, lo.z, hi.z),
            );
            let w = to_world.transform_point3a(c);
            (a.min(w), b.max(w))
        },
    )
}

impl Field {
    /// A sparse grid placed by `index_to_world` (invertible), the map from
    /// its index space to the world.
    pub fn sparse(grid: Arc<SparseGrid>, index_to_world: Affine3A) -> Field {
        let values = FieldValues::Sparse(grid);
        let to_world = index_to_world * values.unit_from_index().inverse();
        Field::new(values, to_world)
    }

    /// `values` over the unit cube placed by `to_world` (invertible).
    pub fn new(values: FieldValues, to_world: Affine3A) -> Field {
        let (lo, hi) = world_box(Vec3A::ZERO, Vec3A::ONE, to_world);
        let m = to_world.matrix3;
        let axis_aligned = m.x_axis.y == 0.0
            && m.x_axis.z == 0.0
            && m.y_axis.x == 0.0
            && m.y_axis.z == 0.0
            && m.z_axis.x == 0.0
            && m.z_axis.y == 0.0;
        let majorants = match &values {
            FieldValues::Grid { grid, .. } if axis_aligned => Some(Arc::new(Majorants::of_grid(
                grid.resolution(),
                |x, y, z| grid.sample(x, y, z).max_element(),
            ))),
            FieldValues::Sparse(grid) if axis_aligned => {
                let (lo, hi) = values.index_box();
                Some(Arc::new(Majorants::of_sparse(grid, lo, hi)))
            }
            _ => None,
        };
        Field {
            values,
            to_local: to_world.inverse(),
            bounds: (lo, hi),
            majorants,
        }
    }

    /// The cells of its majorant grid along `ray` from `t0` to `t1` (a span
    /// within `bounds`), if it has one.
    #[inline]
    pub fn segments(
        &self,
        ray: &crate::geometry::ray::Ray,
        t0: f32,
        t1: f32,
    ) -> Option<Segments<'_>> {
        let m = self.majorants.as_deref()?;
        let o = self.to_local.transform_point3a(ray.origin);
        let d = self.to_local.transform_vector3a(ray.dir);
        Some(m.segments(o, d, t0, t1))
    }

    /// The value at world point `p`.
    #[inline]
    pub fn eval(&self, p: Vec3A) -> Vec3A {
        match &self.values {
            FieldValues::Constant(v) => *v,
            FieldValues::Grid { grid, nearest } => {
                grid.eval(self.to_local.transform_point3a(p), *nearest)
            }
            FieldValues::Sparse(grid) => {
                let unit = self.to_local.transform_point3a(p);
                let (lo, hi) = grid.index_box();
                Vec3A::splat(grid.eval(lo + unit * (hi - lo)))
            }
        }
    }

    /// Whether every channel has the same value everywhere (a grey
    /// field): a constant with equal channels, a one-channel grid.
    pub fn is_grey(&self) -> bool {
        match &self.values {
            FieldValues::Constant(v) => v.x == v.y && v.y == v.z,
            FieldValues::Grid { grid, .. } => grid.channels() == 1,
            FieldValues::Sparse(_) => true,
        }
    }

    /// The largest value of any channel anywhere.
    pub fn max(&self) -> f32 {
        match &self.values {
            FieldValues::Constant(v) => v.max_element(),
            FieldValues::Grid { grid, .. } => grid.max(),
            FieldValues::Sparse(grid) => grid.max(),
        }
    }

    /// Moves the field with the scene it is in, placed by `to_world`.
    pub fn transform(&mut self, to_world: Affine3A) {
        let inv = self.to_local.inverse();
        *self = Field::new(self.values.clone(), to_world * inv);
    }
}

/// A grid of `n` samples for tests: a share `empty` of them 0, the rest
/// uniform in `[empty, 1) · scale`, from a fixed sequence seeded by `seed`.
#[cfg(test)]
pub(crate) fn random_grid(n: [u32; 3], seed: u32, empty: f32, scale: f32) -> Grid {
    let mut state = seed;
    let values = (0..n.iter().product::<u32>())
        .map(|_| {
            state = state.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
            let v = (state >> 8) as f32 / (1u32 << 24) as f32;
            if v < empty { 0.0 } else { v * scale }
        })
        .collect();
    Grid::new(n, 1, values).unwrap()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Samples sit at cell centres; between them values are trilinear;
    /// beyond the outermost ones they are clamped.
    #[test]
    fn lookups_interpolate_between_cell_centres() {
        // 2×1×1, one channel: 1 at x = ¼, 3 at x = ¾.
        let g = Grid::new([2, 1, 1], 1, vec![1.0, 3.0]).unwrap();
        let at = |x: f32| g.eval(Vec3A::new(x, 0.5, 0.5), false).x;
        assert_eq!(at(0.25), 1.0);
        assert_eq!(at(0.75), 3.0);
        assert_eq!(at(0.5), 2.0);
        assert_eq!(at(0.0), 1.0);
        assert_eq!(at(-3.0), 1.0);
        assert_eq!(at(1.5), 3.0);
        assert_eq!(g.eval(Vec3A::new(0.49, 0.5, 0.5), true).x, 1.0);
        assert_eq!(g.eval(Vec3A::new(0.51, 0.5, 0.5), true).x, 3.0);
        // Three channels, x fastest after the channels.
        let g = Grid::new([1, 2, 1], 3, vec![1.0, 2.0, 3.0, 5.0, 6.0, 7.0]).unwrap();
        assert_eq!(
            g.eval(Vec3A::new(0.5, 0.75, 0.5), false),
            Vec3A::new(5.0, 6.0, 7.0)
        );
        assert_eq!(g.max(), 7.0);
    }

    #[test]
    fn bad_grids_are_refused() {
        assert!(Grid::new([0, 1, 1], 1, vec![]).is_err());
        assert!(Grid::new([1, 1, 1], 2, vec![1.0, 1.0]).is_err());
        assert!(Grid::new([2, 1, 1], 1, vec![1.0]).is_err());
        assert!(Grid::new([1, 1, 1], 1, vec![-1.0]).is_err());
        assert!(Grid::new([1, 1, 1], 1, vec![f32::NAN]).is_err());
    }

    #[test]
    fn a_field_is_placed_by_its_transform() {
        let g = Arc::new(Grid::new([2, 1, 1], 1, vec![1.0, 3.0]).unwrap());
        let to_world = Affine3A::from_scale_rotation_translation(
            glam::Vec3::splat(2.0),
            glam::Quat::IDENTITY,
            glam::Vec3::new(-1.0, -1.0, -1.0),
        );
        let f = Field::new(
            FieldValues::Grid {
                grid: g,
                nearest: false,
            },
            to_world,
        );
        assert_eq!(f.bounds, (Vec3A::splat(-1.0), Vec3A::splat(1.0)));
        assert_eq!(f.eval(Vec3A::new(-0.5, 0.0, 0.0)).x, 1.0);
        assert_eq!(f.eval(Vec3A::new(0.5, 0.0, 0.0)).x, 3.0);
    }
}
