//! A sparse grid of samples: OpenVDB's leaves of 8³ voxels and its constant
//! tiles, kept as a table of 8³ blocks over the box they cover (a block is
//! empty, a leaf, or a tile's value), for the density of a cloud or smoke
//! read from a `.vdb` file.
//!
//! Samples sit at integer index coordinates (OpenVDB's convention: voxel
//! `(i, j, k)` is the point `(i, j, k)` of index space) and a point between
//! them is interpolated trilinearly (OpenVDB's `BoxSampler`); everywhere
//! outside the leaves and tiles the grid is 0 (its background).

/// Voxels along a leaf's side.
pub const LEAF_DIM: i32 = 8;
/// Voxels in a leaf.
pub const LEAF_VOXELS: usize = 512;

/// Most blocks the table may hold: 2²⁶ (256 MiB of table), a box of
/// 4096 × 4096 × 2048 voxels.
pub const MAX_BLOCKS: u64 = 1 << 26;

/// A table entry: nothing (the background, 0).
const EMPTY: u32 = 0;
/// A table entry's flag: the rest indexes `tiles`, not `leaves`.
const TILE: u32 = 1 << 31;

/// A constant region: `dim`³ voxels from `origin` (a multiple of 8 along
/// each axis, as are `dim` and `origin` in an OpenVDB tree) of one value.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Tile {
    /// Its first voxel.
    pub origin: [i32; 3],
    /// Voxels along each side (8, 128 or 4096 in an OpenVDB tree).
    pub dim: i32,
    /// Its value.
    pub value: f32,
}

/// A block-sparse grid of one channel.
#[derive(Clone, PartialEq)]
pub struct SparseGrid {
    /// The first voxel of block (0, 0, 0).
    origin: [i32; 3],
    /// Blocks along x, y and z.
    blocks: [u32; 3],
    /// Per block, x fastest: [`EMPTY`], `TILE | index` or `1 + leaf`.
    table: Vec<u32>,
    /// 512 values a leaf, OpenVDB's order: `(x & 7) << 6 | (y & 7) << 3 | (z & 7)`.
    leaves: Vec<f32>,
    tiles: Vec<f32>,
    /// The voxels that hold a value (min, max), inclusive.
    voxels: ([i32; 3], [i32; 3]),
    max: f32,
}

impl std::fmt::Debug for SparseGrid {
    /// Its size and a hash of its values (for fingerprints).
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let mut h = 0xcbf2_9ce4_8422_2325u64;
        for v in self.leaves.iter().chain(&self.tiles) {
            h = (h ^ u64::from(v.to_bits())).wrapping_mul(0x100_0000_01b3);
        }
        for e in &self.table {
            h = (h ^ u64::from(*e)).wrapping_mul(0x100_0000_01b3);
        }
        write!(
            f,
            "SparseGrid {{ origin: {:?}, blocks: {:?}, leaves: {}, values: {h:016x} }}",
            self.origin,
            self.blocks,
            self.leaves.len() / LEAF_VOXELS
        )
    }
}

impl SparseGrid {
    /// The grid of the leaves at `leaf_origins` (multiples of 8; their
    /// values, 512 a leaf in OpenVDB's order, in `leaf_values`) and the
    /// `tiles`; every value finite and ≥ 0, no two leaves or tiles on the
    /// same block. Tiles of value 0 are left out. Errors say what is wrong in
    /// words a reader of the file understands.
    pub fn new(
        leaf_origins: &[[i32; 3]],
        leaf_values: Vec<f32>,
        tiles: &[Tile],
    ) -> Result<SparseGrid, String> {
        if leaf_values.len() != leaf_origins.len() * LEAF_VOXELS {
            return Err(format!(
                "{} leaves need {} values, not {}",
                leaf_origins.len(),
                leaf_origins.len() * LEAF_VOXELS,
                leaf_values.len()
            ));
        }
        if let Some(i) = leaf_values
            .iter()
            .position(|v| !(v.is_finite() && *v >= 0.0))
        {
            let o = leaf_origins[i / LEAF_VOXELS];
            return Err(format!(
                "voxel {} of the leaf at ({}, {}, {}) is {} (a medium's density must be finite and >= 0)",
                i % LEAF_VOXELS,
                o[0],
                o[1],
                o[2],
                leaf_values[i]
            ));
        }
        let aligned = |o: &[i32; 3]| o.iter().all(|c| c.rem_euclid(LEAF_DIM) == 0);
        if let Some(o) = leaf_origins.iter().find(|o| !aligned(o)) {
            return Err(format!(
                "a leaf at ({}, {}, {}) is not on the 8-voxel lattice",
                o[0], o[1], o[2]
            ));
        }
        let tiles: Vec<Tile> = tiles.iter().copied().filter(|t| t.value != 0.0).collect();
        for t in &tiles {
            if !(t.value.is_finite() && t.value >= 0.0) {
                return Err(format!(
                    "the tile at ({}, {}, {}) is {} (a medium's density must be finite and >= 0)",
                    t.origin[0], t.origin[1], t.origin[2], t.value
                ));
            }
            if !aligned(&t.origin) || t.dim < LEAF_DIM || t.dim % LEAF_DIM != 0 {
                return Err(format!(
                    "a tile at ({}, {}, {}) of {} voxels is not on the 8-voxel lattice",
                    t.origin[0], t.origin[1], t.origin[2], t.dim
                ));
            }
        }
        // The voxels covered, in i64 (a tile may end past i32::MAX).
        let mut lo = [i64::MAX; 3];
        let mut hi = [i64::MIN; 3];
        let mut cover = |o: [i32; 3], dim: i32| {
            for k in 0..3 {
                lo[k] = lo[k].min(i64::from(o[k]));
                hi[k] = hi[k].max(i64::from(o[k]) + i64::from(dim) - 1);
            }
        };
        for o in leaf_origins {
            cover(*o, LEAF_DIM);
        }
        for t in &tiles {
            cover(t.origin, t.dim);
        }
        if lo[0] > hi[0] {
            return Err(
                "the grid holds no voxels (no leaf and no tile of a value other than 0)".into(),
            );
        }
        let blocks: Vec<u64> = (0..3)
            .map(|k| ((hi[k] - lo[k] + 1) / i64::from(LEAF_DIM)) as u64)
            .collect();
        let count = blocks.iter().try_fold(1u64, |a, &b| a.checked_mul(b));
        let count = match count {
            Some(c) if c <= MAX_BLOCKS && hi.iter().all(|&h| h <= i64::from(i32::MAX)) => c,
            _ => {
                return Err(format!(
                    "its voxels span {} x {} x {} blocks of 8^3, more than raylab's {MAX_BLOCKS}",
                    blocks[0], blocks[1], blocks[2]
                ));
            }
        };
        let origin = [lo[0] as i32, lo[1] as i32, lo[2] as i32];
        let blocks = [blocks[0] as u32, blocks[1] as u32, blocks[2] as u32];
        let mut table = vec![EMPTY; count as usize];
        let slot = |p: [i32; 3]| -> usize {
            let b = |k: usize| ((i64::from(p[k]) - lo[k]) / i64::from(LEAF_DIM)) as usize;
            (b(2) * blocks[1] as usize + b(1)) * blocks[0] as usize + b(0)
        };
        let taken = |p: [i32; 3]| {
            format!(
                "two leaves or tiles hold the voxel ({}, {}, {})",
                p[0], p[1], p[2]
            )
        };
        for (i, o) in leaf_origins.iter().enumerate() {
            let s = slot(*o);
            if table[s] != EMPTY {
                return Err(taken(*o));
            }
            table[s] = 1 + i as u32;
        }
        let mut tile_values = Vec::with_capacity(tiles.len());
        for t in &tiles {
            let id = TILE | tile_values.len() as u32;
            tile_values.push(t.value);
            let n = t.dim / LEAF_DIM;
            for z in 0..n {
                for y in 0..n {
                    for x in 0..n {
                        let p = [
                            t.origin[0] + x * LEAF_DIM,
                            t.origin[1] + y * LEAF_DIM,
                            t.origin[2] + z * LEAF_DIM,
                        ];
                        let s = slot(p);
                        if table[s] != EMPTY {
                            return Err(taken(p));
                        }
                        table[s] = id;
                    }
                }
            }
        }
        let max = leaf_values
            .iter()
            .chain(&tile_values)
            .copied()
            .fold(0.0f32, f32::max);
        Ok(SparseGrid {
            origin,
            blocks,
            table,
            leaves: leaf_values,
            tiles: tile_values,
            voxels: (origin, [hi[0] as i32, hi[1] as i32, hi[2] as i32]),
            max,
        })
    }

    /// Calls `f(origin, side, largest value)` for every block of 8³ voxels
    /// that holds a value (a leaf, or a tile's part).
    pub fn for_each_block(&self, mut f: impl FnMut([i32; 3], i32, f32)) {
        let [nx, ny, _] = self.blocks.map(|b| b as usize);
        for (i, &e) in self.table.iter().enumerate() {
            if e == EMPTY {
                continue;
            }
            let b = [i % nx, (i / nx) % ny, i / (nx * ny)];
            let origin = [0, 1, 2].map(|k| self.origin[k] + b[k] as i32 * LEAF_DIM);
            let max = if e & TILE != 0 {
                self.tiles[(e & !TILE) as usize]
            } else {
                let leaf = &self.leaves[(e - 1) as usize * LEAF_VOXELS..][..LEAF_VOXELS];
                leaf.iter().copied().fold(0.0, f32::max)
            };
            f(origin, LEAF_DIM, max);
        }
    }

    /// The largest value.
    pub fn max(&self) -> f32 {
        self.max
    }

    /// The voxels the leaves and tiles cover (min, max), inclusive: the grid
    /// is 0 beyond one voxel outside them.
    pub fn voxels(&self) -> ([i32; 3], [i32; 3]) {
        self.voxels
    }

    /// [`SparseGrid::voxels`] grown by one voxel each way, as points of
    /// index space: the box beyond which lookups are 0.
    #[inline]
    pub fn index_box(&self) -> (glam::Vec3A, glam::Vec3A) {
        let f = |v: [i32; 3]| glam::Vec3A::new(v[0] as f32, v[1] as f32, v[2] as f32);
        (f(self.voxels.0) - 1.0, f(self.voxels.1) + 1.0)
    }

    /// The bytes it takes.
    pub fn bytes(&self) -> u64 {
        ((self.table.len() + self.leaves.len() + self.tiles.len()) * 4) as u64
    }

    /// The value of voxel `p`.
    #[inline]
    pub fn voxel(&self, p: [i32; 3]) -> f32 {
        let mut s = 0usize;
        let mut stride = 1usize;
        for ((&c, &o), &n) in p.iter().zip(&self.origin).zip(&self.blocks) {
            let b = (i64::from(c) - i64::from(o)) >> 3;
            if b < 0 || b >= i64::from(n) {
                return 0.0;
            }
            s += b as usize * stride;
            stride *= n as usize;
        }
        match self.table[s] {
            EMPTY => 0.0,
            e if e & TILE != 0 => self.tiles[(e & !TILE) as usize],
            e => {
                let at = ((p[0] & 7) << 6 | (p[1] & 7) << 3 | (p[2] & 7)) as usize;
                self.leaves[(e - 1) as usize * LEAF_VOXELS + at]
            }
        }
    }

    /// The value at `p` in index space, trilinear between voxels.
    #[inline]
    pub fn eval(&self, p: glam::Vec3A) -> f32 {
        // Far outside (or NaN): 0, before any conversion to i32 overflows.
        let (lo, hi) = self.voxels;
        let inside = (0..3).all(|k| p[k] > lo[k] as f32 - 1.0 && p[k] < hi[k] as f32 + 1.0);
        if !inside {
            return 0.0;
        }
        let f = p.floor();
        let w = p - f;
        let (x, y, z) = (f.x as i32, f.y as i32, f.z as i32);
        let v = |dx: i32, dy: i32, dz: i32| self.voxel([x + dx, y + dy, z + dz]);
        let lerp = |a: f32, b: f32, t: f32| a * (1.0 - t) + b * t;
        let c00 = lerp(v(0, 0, 0), v(1, 0, 0), w.x);
        let c10 = lerp(v(0, 1, 0), v(1, 1, 0), w.x);
        let c01 = lerp(v(0, 0, 1), v(1, 0, 1), w.x);
        let c11 = lerp(v(0, 1, 1), v(1, 1, 1), w.x);
        // (Rounding may carry `a(1 − t) + b t` an ulp past both ends; the
        // largest value stays a bound, as majorants need.)
        lerp(lerp(c00, c10, w.y), lerp(c01, c11, w.y), w.z).min(self.max)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3A;

    fn leaf(f: impl Fn(i32, i32, i32) -> f32) -> Vec<f32> {
        let mut v = vec![0.0; LEAF_VOXELS];
        for x in 0..8 {
            for y in 0..8 {
                for z in 0..8 {
                    v[(x << 6 | y << 3 | z) as usize] = f(x, y, z);
                }
            }
        }
        v
    }

    /// Voxels are read from the leaf or tile that holds them, in OpenVDB's
    /// order; between voxels the value is trilinear, and it falls to 0
    /// within one voxel of the last.
    #[test]
    fn voxels_come_from_their_leaves_and_tiles() {
        let mut values = leaf(|x, y, z| (x + 10 * y + 100 * z) as f32);
        values.extend(leaf(|_, _, _| 2.0));
        let tiles = [
            Tile {
                origin: [0, 0, 16],
                dim: 16,
                value: 5.0,
            },
            Tile {
                origin: [64, 0, 0],
                dim: 8,
                value: 0.0,
            },
        ];
        let g = SparseGrid::new(&[[-8, 0, 0], [0, 8, 0]], values, &tiles).unwrap();
        assert_eq!(g.voxel([-8 + 3, 4, 5]), 543.0);
        assert_eq!(g.voxel([-1, 7, 7]), 777.0);
        assert_eq!(g.voxel([2, 9, 3]), 2.0);
        assert_eq!(g.voxel([15, 15, 31]), 5.0);
        assert_eq!(g.voxel([2, 2, 2]), 0.0, "an empty block");
        assert_eq!(g.voxel([2, 2, 200]), 0.0, "beyond the table");
        assert_eq!(g.voxel([i32::MIN, 0, 0]), 0.0);
        assert_eq!(g.voxels(), ([-8, 0, 0], [15, 15, 31]));
        assert_eq!(g.max(), 777.0);
        // Trilinear along x inside the first leaf, and down to 0 past its
        // edge.
        assert_eq!(g.eval(Vec3A::new(-8.0 + 2.25, 1.0, 0.0)), 12.25);
        assert_eq!(g.eval(Vec3A::new(-8.0 + 2.0, 1.5, 0.0)), 17.0);
        assert_eq!(g.eval(Vec3A::new(-0.5, 0.0, 0.0)), 3.5);
        assert_eq!(g.eval(Vec3A::new(-9.5, 0.0, 0.0)), 0.0);
        assert_eq!(g.eval(Vec3A::new(f32::NAN, 0.0, 0.0)), 0.0);
        assert_eq!(g.eval(Vec3A::new(3e9, 0.0, 0.0)), 0.0);
    }

    #[test]
    fn bad_grids_are_refused() {
        let one = leaf(|_, _, _| 1.0);
        assert!(SparseGrid::new(&[[0, 0, 0]], vec![1.0; 3], &[]).is_err());
        assert!(SparseGrid::new(&[[1, 0, 0]], one.clone(), &[]).is_err());
        let mut nan = one.clone();
        nan[7] = f32::NAN;
        assert!(SparseGrid::new(&[[0, 0, 0]], nan, &[]).is_err());
        let mut negative = one.clone();
        negative[7] = -1.0;
        assert!(SparseGrid::new(&[[0, 0, 0]], negative, &[]).is_err());
        let two = [one.clone(), one.clone()].concat();
        assert!(SparseGrid::new(&[[0, 0, 0], [0, 0, 0]], two.clone(), &[]).is_err());
        // Leaves 2^30 voxels apart: a table far over the limit.
        let e = SparseGrid::new(&[[0, 0, 0], [1 << 30, 1 << 30, 0]], two, &[]).unwrap_err();
        assert!(e.contains("blocks"), "{e}");
        assert!(SparseGrid::new(&[], vec![], &[]).is_err());
        let huge = Tile {
            origin: [i32::MAX - 7, 0, 0],
            dim: 4096,
            value: 1.0,
        };
        assert!(SparseGrid::new(&[], vec![], &[huge]).is_err());
    }
}
