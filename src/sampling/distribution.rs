//! Discrete and piecewise-constant distributions: an alias table (Walker 1977,
//! Vose 1991) for choosing among many items by weight in constant time, and a
//! 2D piecewise-constant distribution over a grid (a marginal over rows, a
//! conditional per row; pbrt's `PiecewiseConstant2D`) for sampling images.
//!
//! The 2D distribution inverts its running sums with a guide table (Chen &
//! Asau 1974's "cutpoint" method): for each of `K` equal slices of `[0, 1)`,
//! where the search for a value in it starts and ends. A search then reads
//! one guide entry and a few neighbouring sums instead of walking a binary
//! search across a 4 KiB row, whose every step is a dependent load and, in an
//! environment map's tables, a cache miss (perf put 20 % of the helmet's time
//! on that walk). The answer is the binary search's, bit for bit.

use glam::Vec2;
use rayon::prelude::*;

/// Chooses one of `n` items with probability proportional to its weight, in
/// constant time: item `⌊x·n⌋` is kept if a second number falls below its
/// threshold, else its alias is taken.
#[derive(Clone, Debug, Default)]
pub struct AliasTable {
    /// Per bucket: the probability of keeping the bucket's own item.
    threshold: Vec<f32>,
    /// Per bucket: the item taken otherwise.
    alias: Vec<u32>,
    /// Per item: its probability (weight over the total).
    pmf: Vec<f32>,
    /// Sum of the weights.
    total: f64,
}

impl AliasTable {
    /// A table over `weights` (finite, non-negative; others count as zero).
    /// Empty when no weight is positive.
    pub fn new(weights: &[f32]) -> Self {
        let clean = |w: f32| {
            if w.is_finite() && w > 0.0 {
                w as f64
            } else {
                0.0
            }
        };
        let total: f64 = weights.iter().map(|&w| clean(w)).sum();
        let n = weights.len();
        if total <= 0.0 || n == 0 || n > u32::MAX as usize {
            return Self::default();
        }
        let pmf: Vec<f32> = weights.iter().map(|&w| (clean(w) / total) as f32).collect();
        // Vose's construction on scaled probabilities (mean 1), in f64.
        let mut scaled: Vec<f64> = weights
            .iter()
            .map(|&w| clean(w) / total * n as f64)
            .collect();
        let mut threshold = vec![1.0f32; n];
        let mut alias: Vec<u32> = (0..n as u32).collect();
        let (mut small, mut large): (Vec<u32>, Vec<u32>) =
            (0..n as u32).partition(|&i| scaled[i as usize] < 1.0);
        while let (Some(&s), Some(&l)) = (small.last(), large.last()) {
            small.pop();
            threshold[s as usize] = scaled[s as usize] as f32;
            alias[s as usize] = l;
            scaled[l as usize] -= 1.0 - scaled[s as usize];
            if scaled[l as usize] < 1.0 {
                large.pop();
                small.push(l);
            }
        }
        // What is left holds probability 1 up to rounding.
        for i in small.into_iter().chain(large) {
            threshold[i as usize] = 1.0;
        }
        Self {
            threshold,
            alias,
            pmf,
            total,
        }
    }

    /// Whether no item can be chosen.
    pub fn is_empty(&self) -> bool {
        self.pmf.is_empty()
    }

    /// Number of items.
    pub fn len(&self) -> usize {
        self.pmf.len()
    }

    /// Sum of the weights.
    pub fn total(&self) -> f64 {
        self.total
    }

    /// The probability of item `i` (zero out of range).
    #[inline]
    pub fn pmf(&self, i: usize) -> f32 {
        self.pmf.get(i).copied().unwrap_or(0.0)
    }

    /// Picks an item with `u` in `[0, 1)²`: `u.x` chooses the bucket, `u.y`
    /// between the bucket's item and its alias. `None` for an empty table.
    #[inline]
    pub fn sample(&self, u: Vec2) -> Option<usize> {
        let n = self.threshold.len();
        if n == 0 {
            return None;
        }
        let i = ((u.x * n as f32) as usize).min(n - 1);
        Some(if u.y < self.threshold[i] {
            i
        } else {
            self.alias[i] as usize
        })
    }
}

/// A piecewise-constant density over `[0, 1)²`, constant on each cell of a
/// `width × height` grid and proportional to the cell's weight.
#[derive(Clone, Debug, Default)]
pub struct Distribution2D {
    width: usize,
    height: usize,
    /// Per row, the running sums of its cells' weights, normalised to end at 1.
    conditional_cdf: Vec<f32>,
    /// Running sums of the rows' weights, normalised to end at 1.
    marginal_cdf: Vec<f32>,
    /// The guide of `marginal_cdf` ([`guide`]).
    marginal_guide: Vec<u32>,
    /// Per row, the guide of its running sums, `conditional_slices + 1`
    /// entries each.
    conditional_guide: Vec<u32>,
    /// The slices of a row's guide.
    conditional_slices: usize,
    /// Sum of all weights times the cell area (the integral of the function).
    integral: f64,
}

/// The probability mass between two running sums `cdf[i − 1]` and `cdf[i]`.
#[inline]
fn mass(cdf: &[f32], i: usize) -> f32 {
    cdf[i] - if i == 0 { 0.0 } else { cdf[i - 1] }
}

/// The guide of running sums `cdf` with `slices` slices (a power of two):
/// entry `b` counts the sums at most `b / slices`, for `b` in
/// `0..=slices`. A value `u` of slice `b` (`b/K ≤ u < (b+1)/K`) has every
/// sum before entry `b` at most `u` and every sum from entry `b + 1` on above
/// it, so its search can be confined to `cdf[guide[b]..guide[b + 1]]`.
fn guide(cdf: &[f32], slices: usize) -> Vec<u32> {
    debug_assert!(slices.is_power_of_two());
    (0..=slices)
        .map(|b| cdf.partition_point(|&c| c <= b as f32 / slices as f32) as u32)
        .collect()
}

/// Slices for a guide of `n` running sums: about one per eight sums (one
/// cache line of them), a power of two so that `u · K` and `b / K` are exact.
fn slices_for(n: usize) -> usize {
    (n / 8).clamp(1, 1 << 20).next_power_of_two()
}

/// The number of sums of `cdf` at most `u` (`cdf.partition_point(|c| c ≤
/// u)`), searched within the slice of `guide` that `u` falls in.
#[inline]
fn count_at_most(cdf: &[f32], guide: &[u32], u: f32) -> usize {
    let slices = guide.len() - 1;
    if !(0.0..1.0).contains(&u) {
        // Outside the guide's range (never for a sampler's numbers): search
        // everything.
        return cdf.partition_point(|&c| c <= u);
    }
    // Exact: `slices` is a power of two.
    let b = ((u * slices as f32) as usize).min(slices - 1);
    let (lo, hi) = (guide[b] as usize, guide[b + 1] as usize);
    lo + cdf[lo..hi].partition_point(|&c| c <= u)
}

/// The index of the bin of `cdf` (guided by `guide`) that `u` falls in, and
/// where in it (`[0, 1)`).
#[inline]
fn find(cdf: &[f32], guide: &[u32], u: f32) -> (usize, f32) {
    let i = count_at_most(cdf, guide, u).min(cdf.len() - 1);
    let lo = if i == 0 { 0.0 } else { cdf[i - 1] };
    let m = cdf[i] - lo;
    let t = if m > 0.0 {
        ((u - lo) / m).clamp(0.0, 1.0 - f32::EPSILON)
    } else {
        0.5
    };
    (i, t)
}

impl Distribution2D {
    /// The distribution of the cell weights `weight(i, j)` (column `i`, row
    /// `j`), evaluated for every row in parallel. Weights that are negative or
    /// not finite count as zero. Empty (no samples) when every weight is zero.
    pub fn new(width: usize, height: usize, weight: impl Fn(usize, usize) -> f32 + Sync) -> Self {
        if width == 0 || height == 0 {
            return Self::default();
        }
        let mut conditional_cdf = vec![0.0f32; width * height];
        let row_sums: Vec<f64> = conditional_cdf
            .par_chunks_mut(width)
            .enumerate()
            .map(|(j, row)| {
                for (i, slot) in row.iter_mut().enumerate() {
                    let w = weight(i, j);
                    *slot = if w.is_finite() && w > 0.0 { w } else { 0.0 };
                }
                let sum: f64 = row.iter().map(|&w| w as f64).sum();
                let inv = if sum > 0.0 { 1.0 / sum } else { 0.0 };
                let mut running = 0.0f64;
                for slot in row.iter_mut() {
                    running += *slot as f64;
                    *slot = (running * inv) as f32;
                }
                if sum > 0.0 {
                    row[width - 1] = 1.0;
                }
                sum
            })
            .collect();
        let total: f64 = row_sums.iter().sum();
        if total <= 0.0 || !total.is_finite() {
            return Self::default();
        }
        let mut running = 0.0f64;
        let mut marginal_cdf: Vec<f32> = row_sums
            .iter()
            .map(|s| {
                running += s;
                (running / total) as f32
            })
            .collect();
        marginal_cdf[height - 1] = 1.0;
        let marginal_guide = guide(&marginal_cdf, slices_for(height));
        let conditional_slices = slices_for(width);
        let conditional_guide: Vec<u32> = conditional_cdf
            .par_chunks(width)
            .flat_map_iter(|row| guide(row, conditional_slices))
            .collect();
        Self {
            width,
            height,
            conditional_cdf,
            marginal_cdf,
            marginal_guide,
            conditional_guide,
            conditional_slices,
            integral: total / (width * height) as f64,
        }
    }

    /// Whether the distribution has no mass (nothing can be sampled).
    pub fn is_empty(&self) -> bool {
        self.marginal_cdf.is_empty()
    }

    /// The integral of the weight function over `[0, 1)²` (the mean weight).
    pub fn integral(&self) -> f64 {
        self.integral
    }

    /// A point of `[0, 1)²` distributed by the density, from `u` in `[0, 1)²`,
    /// with its density. `None` for an empty distribution.
    #[inline]
    pub fn sample(&self, u: Vec2) -> Option<(Vec2, f32)> {
        if self.is_empty() {
            return None;
        }
        let (j, dv) = find(&self.marginal_cdf, &self.marginal_guide, u.y);
        let row = &self.conditional_cdf[j * self.width..(j + 1) * self.width];
        let stride = self.conditional_slices + 1;
        let row_guide = &self.conditional_guide[j * stride..(j + 1) * stride];
        let (i, du) = find(row, row_guide, u.x);
        let p = Vec2::new(
            (i as f32 + du) / self.width as f32,
            (j as f32 + dv) / self.height as f32,
        );
        Some((p, self.cell_pdf(i, j)))
    }

    /// The density at a point of `[0, 1)²` (zero for an empty distribution).
    #[inline]
    pub fn pdf(&self, p: Vec2) -> f32 {
        if self.is_empty() {
            return 0.0;
        }
        let i = ((p.x * self.width as f32) as usize).min(self.width - 1);
        let j = ((p.y * self.height as f32) as usize).min(self.height - 1);
        self.cell_pdf(i, j)
    }

    /// The density on cell `(i, j)`: exactly the probability [`Self::sample`]
    /// lands in it (the differences of the stored running sums) over its area.
    #[inline]
    fn cell_pdf(&self, i: usize, j: usize) -> f32 {
        let row = &self.conditional_cdf[j * self.width..(j + 1) * self.width];
        mass(&self.marginal_cdf, j) * mass(row, i) * (self.width * self.height) as f32
    }

    /// Bytes held.
    pub fn memory_bytes(&self) -> usize {
        4 * (self.conditional_cdf.len()
            + self.marginal_cdf.len()
            + self.marginal_guide.len()
            + self.conditional_guide.len())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::sampler::Rng;

    #[test]
    fn alias_table_picks_items_by_weight() {
        let weights = [0.0, 1.0, 7.0, 0.5, 0.0, 1.5, 30.0];
        let table = AliasTable::new(&weights);
        let total: f32 = weights.iter().sum();
        let mut counts = [0u32; 7];
        let n = 400_000;
        let mut rng = Rng::for_sample(1, 2, 3);
        for _ in 0..n {
            let u = Vec2::new(rng.next_f32(), rng.next_f32());
            counts[table.sample(u).unwrap()] += 1;
        }
        // χ² over the items with weight (6 dof: < 22.5 at p = 0.001).
        let mut chi2 = 0.0;
        for (i, &w) in weights.iter().enumerate() {
            assert_eq!(table.pmf(i), w / total);
            if w == 0.0 {
                assert_eq!(counts[i], 0, "item {i} has no weight");
                continue;
            }
            let expected = n as f64 * (w / total) as f64;
            chi2 += (counts[i] as f64 - expected).powi(2) / expected;
        }
        assert!(chi2 < 22.5, "χ² = {chi2}, counts {counts:?}");
        assert!(AliasTable::new(&[0.0, f32::NAN, -1.0]).is_empty());
        assert_eq!(AliasTable::new(&[]).sample(Vec2::ZERO), None);
    }

    #[test]
    fn alias_table_is_exact_on_the_bucket_grid() {
        // With x on a grid finer than the buckets and y exhaustive, every item is
        // chosen with its probability to within the grid's resolution.
        let weights: Vec<f32> = (0..100).map(|i| ((i * 37) % 11) as f32).collect();
        let table = AliasTable::new(&weights);
        let total: f32 = weights.iter().sum();
        let mut counts = vec![0u32; 100];
        let steps = 1000;
        for a in 0..steps {
            for b in 0..steps {
                let u = Vec2::new(
                    (a as f32 + 0.5) / steps as f32,
                    (b as f32 + 0.5) / steps as f32,
                );
                counts[table.sample(u).unwrap()] += 1;
            }
        }
        for (i, &w) in weights.iter().enumerate() {
            let p = counts[i] as f32 / (steps * steps) as f32;
            assert!(
                (p - w / total).abs() < 2e-3,
                "item {i}: {p} vs {}",
                w / total
            );
        }
    }

    #[test]
    fn guided_search_equals_binary_search() {
        // Running sums with flat runs (zero weights), steep steps (one bright
        // cell, like a sun), ties and an exact 1 at the end; values on the
        // slices' edges, just beside them, at random, and outside [0, 1).
        let mut rng = Rng::for_sample(11, 0, 0);
        for (n, spike) in [
            (1usize, 0usize),
            (5, 2),
            (64, 63),
            (1000, 0),
            (1024, 517),
            (4097, 4000),
        ] {
            let weights: Vec<f64> = (0..n)
                .map(|i| match (i == spike, rng.next_f32()) {
                    (true, _) => 1e4,
                    (false, r) if r < 0.3 => 0.0,
                    (false, r) => r as f64,
                })
                .collect();
            let total: f64 = weights.iter().sum();
            let mut running = 0.0;
            let mut cdf: Vec<f32> = weights
                .iter()
                .map(|w| {
                    running += w;
                    (running / total) as f32
                })
                .collect();
            cdf[n - 1] = 1.0;
            let slices = slices_for(n);
            let g = guide(&cdf, slices);
            let mut values = vec![
                -0.5,
                -0.0,
                0.0,
                1.0,
                1.5,
                f32::NAN,
                1.0 - f32::EPSILON / 2.0,
            ];
            for b in 0..=slices {
                let edge = b as f32 / slices as f32;
                values.extend([edge, edge.next_up(), edge.next_down()]);
            }
            values.extend(cdf.iter().flat_map(|&c| [c, c.next_up(), c.next_down()]));
            values.extend((0..10_000).map(|_| rng.next_f32()));
            for u in values {
                assert_eq!(
                    count_at_most(&cdf, &g, u),
                    cdf.partition_point(|&c| c <= u),
                    "n = {n}, u = {u}"
                );
            }
        }
    }

    #[test]
    fn distribution_2d_samples_its_density() {
        let (w, h) = (8, 4);
        let weight = |i: usize, j: usize| ((i * 3 + j * 5) % 7) as f32;
        let d = Distribution2D::new(w, h, weight);
        let sum: f32 = (0..h).flat_map(|j| (0..w).map(move |i| weight(i, j))).sum();
        assert!((d.integral() - sum as f64 / 32.0).abs() < 1e-9);
        let mut counts = vec![0u32; w * h];
        let n = 320_000;
        let mut rng = Rng::for_sample(7, 0, 0);
        for _ in 0..n {
            let (p, pdf) = d.sample(Vec2::new(rng.next_f32(), rng.next_f32())).unwrap();
            assert!((0.0..1.0).contains(&p.x) && (0.0..1.0).contains(&p.y));
            assert!(
                (pdf - d.pdf(p)).abs() <= 1e-6 * pdf,
                "{pdf} vs {}",
                d.pdf(p)
            );
            let (i, j) = ((p.x * w as f32) as usize, (p.y * h as f32) as usize);
            counts[j * w + i] += 1;
        }
        let mut chi2 = 0.0;
        let mut dof = 0;
        for j in 0..h {
            for i in 0..w {
                let expected_p = weight(i, j) / sum;
                let pdf = d.pdf(Vec2::new(
                    (i as f32 + 0.5) / w as f32,
                    (j as f32 + 0.5) / h as f32,
                ));
                assert!((pdf / (w * h) as f32 - expected_p).abs() < 1e-6);
                if expected_p == 0.0 {
                    assert_eq!(counts[j * w + i], 0);
                    continue;
                }
                let expected = n as f64 * expected_p as f64;
                chi2 += (counts[j * w + i] as f64 - expected).powi(2) / expected;
                dof += 1;
            }
        }
        // 27 nonzero cells: 26 dof, χ² < 54.1 at p = 0.001.
        assert!(dof > 20 && chi2 < 54.1, "χ² = {chi2} ({dof} cells)");
        assert!(Distribution2D::new(3, 3, |_, _| 0.0).is_empty());
    }
}
