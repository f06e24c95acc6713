//! Eight-wide nodes and the slab test of one ray against a node's eight boxes:
//! one AVX2 pass where the CPU has AVX2 (chosen at run time), otherwise two
//! four-wide passes (SSE2 on x86-64 through glam, scalar elsewhere). Both give
//! bit-identical answers: the same operations in the same order, lane by lane.

use glam::{Vec3A, Vec4};

use crate::geometry::ray::gamma;

/// Children per node.
pub(super) const WIDTH: usize = 8;

/// A reference to a child: an index into `nodes`, or, with [`LEAF`] set, the first
/// packet (bits 4..31) and packet count (bits 0..4) of a leaf.
pub(super) type ChildRef = u32;
pub(super) const LEAF: u32 = 1 << 31;
/// An unused child slot (never a valid leaf: leaves start below packet 2^27).
pub(super) const EMPTY: ChildRef = u32::MAX;

/// The reference to a leaf of `count` (below 16) items from `start` (below 2^27).
/// The builder also uses it for a provisional reference to a run of triangles.
#[inline(always)]
pub(super) fn leaf_ref(start: usize, count: usize) -> ChildRef {
    debug_assert!(start < 1 << 27 && count < 16);
    LEAF | (start as u32) << 4 | count as u32
}

/// The `(start, count)` of a leaf reference.
#[inline(always)]
pub(super) fn leaf_parts(r: ChildRef) -> (usize, usize) {
    (((r & !LEAF) >> 4) as usize, (r & 15) as usize)
}

/// Eight children's boxes, by coordinate: `bounds[0..3]` are the minima in x, y, z
/// and `bounds[3..6]` the maxima, one lane per child. Empty lanes have min = +inf
/// and max = -inf, which no ray can hit. 224 bytes of data (four cache
/// lines), 256 with the alignment padding.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(64))]
pub(super) struct Node {
    pub(super) bounds: [[f32; WIDTH]; 6],
    pub(super) children: [ChildRef; WIDTH],
}

/// A node's eight boxes as traversal reads them: [`Node::bounds`] alone, 192
/// bytes (three cache lines), with the children in an array of their own. Kept
/// apart, a node costs 224 bytes instead of 256 with the padding, and the box
/// test touches three lines, not four.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(64))]
pub(super) struct NodeBoxes {
    pub(super) bounds: [[f32; WIDTH]; 6],
}

impl Node {
    /// A node with every slot empty.
    pub(super) const EMPTY: Node = Node {
        bounds: [
            [f32::INFINITY; WIDTH],
            [f32::INFINITY; WIDTH],
            [f32::INFINITY; WIDTH],
            [f32::NEG_INFINITY; WIDTH],
            [f32::NEG_INFINITY; WIDTH],
            [f32::NEG_INFINITY; WIDTH],
        ],
        children: [EMPTY; WIDTH],
    };
}

/// Which box test the CPU runs, decided once per tree.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Isa {
    /// Two four-wide passes per node.
    Portable,
    /// One eight-wide AVX2 pass per node.
    #[cfg(target_arch = "x86_64")]
    Avx2,
}

impl Isa {
    /// The widest test this CPU supports; `RAYLAB_NO_AVX2=1` forces the portable
    /// one (to compare the two, and to test the fallback on an AVX2 machine).
    pub(super) fn detect() -> Isa {
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx2")
            && std::env::var_os("RAYLAB_NO_AVX2").is_none_or(|v| v.is_empty() || v == "0")
        {
            return Isa::Avx2;
        }
        Isa::Portable
    }
}

/// Per-ray constants of the slab test.
pub(super) struct BoxQuery {
    origin: [f32; 3],
    /// `1 / dir` for the near planes, and enlarged by [`EXIT_SCALE`] for the far ones.
    inv_near: [f32; 3],
    inv_far: [f32; 3],
    /// Offset in `f32`s into `Node::bounds` of the near and far plane, per axis.
    near: [usize; 3],
    far: [usize; 3],
}

/// `1 / dir` with every zero component first made the smallest normal number of
/// the same sign, so that the inverse is finite and a slab test never computes
/// 0 · inf = NaN.
#[inline(always)]
pub(super) fn safe_inverse(dir: Vec3A) -> Vec3A {
    let tiny = Vec3A::splat(f32::MIN_POSITIVE);
    Vec3A::select(dir.abs().cmplt(tiny), tiny.copysign(dir), dir).recip()
}

/// Exit distances are enlarged by this factor so that rounding never culls a box
/// the ray grazes (Ize 2013, pbrt-v4). Each computed distance is within a factor
/// `(1 ± u)^3` of the exact one and folding the factor into the inverse direction
/// costs one more rounding: `(1 - u)^4 (1 + 4γ(3)) > (1 + u)^3`, so a computed
/// exit never falls below a computed entry that the exact ones would order.
pub(super) const EXIT_SCALE: f32 = 1.0 + 4.0 * gamma(3);

/// Where in `Node::bounds` each axis's near and far plane start, as offsets in
/// `f32`s (row × [`WIDTH`]: an address then needs no shift a plane), by the
/// direction's sign bits (bit `a` set: negative along axis `a`). A table: the
/// arithmetic version cost about 80 instructions a ray.
const PLANES: [([usize; 3], [usize; 3]); 8] = {
    let mut table = [([0; 3], [0; 3]); 8];
    let mut neg = 0;
    while neg < 8 {
        let mut a = 0;
        while a < 3 {
            let flip = (neg >> a) & 1;
            table[neg].0[a] = (a + 3 * flip) * WIDTH;
            table[neg].1[a] = (a + 3 * (1 - flip)) * WIDTH;
            a += 1;
        }
        neg += 1;
    }
    table
};

impl BoxQuery {
    #[inline(always)]
    pub(super) fn new(origin: Vec3A, dir: Vec3A) -> Self {
        // The sign comes from the inverse so that -0.0 counts as negative.
        let inv = safe_inverse(dir);
        let neg = inv.cmplt(Vec3A::ZERO).bitmask() as usize;
        let (near, far) = PLANES[neg & 7];
        Self {
            origin: origin.to_array(),
            inv_near: inv.to_array(),
            inv_far: (inv * EXIT_SCALE).to_array(),
            near,
            far,
        }
    }

    /// The query of a ray whose inverse directions and their sign bits
    /// (`negative`, bit `a` for axis `a`) are made elsewhere, as [`BoxQuery::new`]
    /// makes them (`bvh::single8`, eight rays at a time).
    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    pub(super) fn from_parts(
        origin: [f32; 3],
        inv_near: [f32; 3],
        inv_far: [f32; 3],
        negative: usize,
    ) -> Self {
        let (near, far) = PLANES[negative & 7];
        Self {
            origin,
            inv_near,
            inv_far,
            near,
            far,
        }
    }

    /// Slab test of the eight boxes: entry distances (`t_near`, written for every
    /// lane) and a bit mask of the boxes hit within `[0, t_max]`.
    #[inline(always)]
    pub(super) fn hit(
        &self,
        isa: Isa,
        node: &NodeBoxes,
        t_max: f32,
        t_near: &mut [f32; WIDTH],
    ) -> u32 {
        match isa {
            // SAFETY: `Isa::Avx2` is only chosen when the CPU has AVX2.
            #[cfg(target_arch = "x86_64")]
            Isa::Avx2 => unsafe { self.hit_avx2(node, t_max, t_near) },
            Isa::Portable => self.hit_halves(node, t_max, t_near),
        }
    }

    #[inline(always)]
    fn hit_halves(&self, node: &NodeBoxes, t_max: f32, t_near: &mut [f32; WIDTH]) -> u32 {
        let mut mask = 0;
        for half in 0..2 {
            let lanes = half * 4..half * 4 + 4;
            let slab = |plane: usize, a: usize, inv: &[f32; 3]| {
                let b = Vec4::from_slice(&node.bounds[plane / WIDTH][lanes.clone()]);
                (b - Vec4::splat(self.origin[a])) * Vec4::splat(inv[a])
            };
            let near = |a: usize| slab(self.near[a], a, &self.inv_near);
            let far = |a: usize| slab(self.far[a], a, &self.inv_far);
            // Balanced trees of min/max: two steps deep, not four.
            let t0 = near(0).max(near(1)).max(near(2).max(Vec4::ZERO));
            let t1 = far(0).min(far(1)).min(far(2).min(Vec4::splat(t_max)));
            let hit = t0.cmple(t1);
            t0.write_to_slice(&mut t_near[lanes.clone()]);
            mask |= hit.bitmask() << (half * 4);
        }
        mask
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    #[inline]
    fn hit_avx2(&self, node: &NodeBoxes, t_max: f32, t_near: &mut [f32; WIDTH]) -> u32 {
        use std::arch::x86_64::*;
        // `max`/`min` take the second operand when either is NaN, as glam's SSE
        // path does, so both tests treat NaN alike.
        let b = node.bounds.as_ptr() as *const f32;
        // SAFETY: each row of `bounds` is eight f32 at a 32-byte aligned offset of a
        // 64-byte aligned node.
        let slab = |plane: usize, a: usize, inv: &[f32; 3]| unsafe {
            let bound = _mm256_load_ps(b.add(plane));
            _mm256_mul_ps(
                _mm256_sub_ps(bound, _mm256_set1_ps(self.origin[a])),
                _mm256_set1_ps(inv[a]),
            )
        };
        let near = |a: usize| slab(self.near[a], a, &self.inv_near);
        let far = |a: usize| slab(self.far[a], a, &self.inv_far);
        let t0 = _mm256_max_ps(
            _mm256_max_ps(near(0), near(1)),
            _mm256_max_ps(near(2), _mm256_setzero_ps()),
        );
        let t1 = _mm256_min_ps(
            _mm256_min_ps(far(0), far(1)),
            _mm256_min_ps(far(2), _mm256_set1_ps(t_max)),
        );
        let hit = _mm256_cmp_ps::<_CMP_LE_OQ>(t0, t1);
        // SAFETY: `t_near` holds eight f32.
        unsafe { _mm256_storeu_ps(t_near.as_mut_ptr(), t0) };
        _mm256_movemask_ps(hit) as u32
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::sampler::Rng;

    /// Random nodes (some slots empty, some boxes flat) against random rays,
    /// including axis-parallel ones and ones starting inside a box: both tests
    /// give the same mask and the same entry distances, bit for bit, and every
    /// box that a point of the ray provably lies in is reported hit.
    #[test]
    fn avx2_and_portable_box_tests_agree() {
        let mut rng = Rng::new(5, 2);
        let mut f = |s: f32| (rng.next_f32() * 2.0 - 1.0) * s;
        let (mut hits, mut checked) = (0, 0);
        for round in 0..20_000 {
            let mut node = Node::EMPTY;
            let used = 1 + round % WIDTH;
            let mut centres = [Vec3A::ZERO; WIDTH];
            for (lane, centre) in centres.iter_mut().enumerate().take(used) {
                let c = Vec3A::new(f(2.0), f(2.0), f(2.0));
                let flat = round % 7;
                let h = Vec3A::new(f(0.5).abs(), f(0.5).abs(), f(0.5).abs())
                    * if flat < 3 {
                        Vec3A::ONE - Vec3A::AXES[flat]
                    } else {
                        Vec3A::ONE
                    };
                *centre = c;
                for a in 0..3 {
                    node.bounds[a][lane] = c[a] - h[a];
                    node.bounds[a + 3][lane] = c[a] + h[a];
                }
                node.children[lane] = lane as u32;
            }
            let origin = Vec3A::new(f(3.0), f(3.0), f(3.0));
            let mut dir = Vec3A::new(f(1.0), f(1.0), f(1.0));
            if round % 5 == 0 {
                dir[round % 3] = 0.0;
            }
            // Sometimes aim at a box's centre, which the ray then must hit.
            let aim = round % 2 == 0;
            if aim {
                dir = centres[round % used] - origin;
            }
            let q = BoxQuery::new(origin, dir);
            let t_max = if round % 3 == 0 { 2.0 } else { f32::INFINITY };
            let (mut a, mut b) = ([0.0; WIDTH], [0.0; WIDTH]);
            let boxes = NodeBoxes {
                bounds: node.bounds,
            };
            let portable = q.hit(Isa::Portable, &boxes, t_max, &mut a);
            if aim && t_max.is_infinite() {
                checked += 1;
                assert!(portable >> (round % used) & 1 == 1, "round {round}");
            }
            hits += portable.count_ones();
            assert_eq!(portable >> used, 0, "empty slots are never hit");
            if Isa::detect() == Isa::Portable {
                continue;
            }
            #[cfg(target_arch = "x86_64")]
            {
                let wide = q.hit(Isa::Avx2, &boxes, t_max, &mut b);
                assert_eq!(wide, portable, "round {round}");
                for lane in 0..WIDTH {
                    if portable >> lane & 1 == 1 {
                        assert_eq!(a[lane].to_bits(), b[lane].to_bits(), "round {round}");
                    }
                }
            }
        }
        assert!(
            hits > 8000 && checked > 3000,
            "{hits} hits, {checked} aimed"
        );
    }
}
