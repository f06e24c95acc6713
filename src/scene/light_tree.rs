//! A bounding volume hierarchy over the lights that have a place (emitting
//! triangles, point and spot lights), for choosing one in proportion to a
//! bound on what it can send to the point being lit: distance, the lights'
//! orientation cones and the surface's side (Conty Estevez & Kulla 2018,
//! "Importance Sampling of Many Lights with Adaptive Tree Splitting", as
//! pbrt-v4's `BVHLightSampler` builds and walks it).
//!
//! Each node bounds its lights by a box, their summed intensity `phi`, a cone
//! of normals (`axis`, `cos_o`) and the spread of emission about a normal
//! (`cos_e`). Walking down from the root, the sampler picks a child in
//! proportion to [`LightBounds::importance`] at the point; the product of the
//! choices is the light's probability, which [`LightTree::pmf`] recomputes
//! from the light's path of left/right turns for multiple importance sampling.
//! An importance is zero only where no light below can send anything: behind
//! every one-sided emitter, outside every spot's cone, below the horizon of the
//! surface being lit. That keeps the estimator unbiased: a light left out
//! there contributes nothing.
//!
//! [`Facing`], what the surface being lit lets through, is defined here: the
//! bounds take it, and `light_sampling.rs` weighs the other lights by it.

use std::f32::consts::{FRAC_PI_2, PI};

use glam::{Vec3A, Vec4};

/// What the surface being lit lets through, for choosing among punctual lights
/// ([`Scene::sample_light`](crate::scene::Scene::sample_light)).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Facing {
    /// Nothing known: every direction counts alike.
    Any,
    /// A reflecting surface: light arrives from the side this unit shading
    /// normal points to (the side the path leaves by).
    Side(Vec3A),
    /// A surface that also transmits: light arrives from either side of this
    /// unit shading normal.
    Both(Vec3A),
}

impl Facing {
    /// How much a surface so facing takes of light arriving along `to_light`
    /// (towards the light): `n · to_light`, its absolute value for a surface
    /// that transmits, 1 for [`Facing::Any`]; a cosine when `to_light` is unit.
    #[inline]
    pub fn cosine(self, to_light: Vec3A) -> f32 {
        match self {
            Facing::Any => 1.0,
            Facing::Side(n) => n.dot(to_light),
            Facing::Both(n) => n.dot(to_light).abs(),
        }
    }
}

/// Where, how much and which way a set of lights emits.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct LightBounds {
    /// Box around the lights.
    pub(super) lo: Vec3A,
    /// (Its upper corner.)
    pub(super) hi: Vec3A,
    /// Summed intensity, W/sr averaged over the colour channels: `I` of a
    /// point or spot light (on its axis), `Le·A` of an emitting triangle.
    pub(super) phi: f32,
    /// Unit axis of the cone holding every light's normal (a spot's axis).
    pub(super) axis: Vec3A,
    /// Cosine of that cone's half angle (−1: every direction).
    pub(super) cos_o: f32,
    /// Cosine of how far beyond its normal a light emits (0 for a surface,
    /// which emits over its hemisphere).
    pub(super) cos_e: f32,
    /// Whether some light emits on both sides of its normal.
    pub(super) two_sided: bool,
}

impl LightBounds {
    /// An isotropic point light of intensity `phi` at `p`.
    pub(super) fn point(p: Vec3A, phi: f32) -> Self {
        Self {
            lo: p,
            hi: p,
            phi,
            axis: Vec3A::Z,
            cos_o: -1.0,
            cos_e: 0.0,
            two_sided: false,
        }
    }

    /// A spot light at `p` along unit `axis`, full intensity `phi` inside the
    /// cone of cosine `cos_inner`, nothing beyond `cos_outer`.
    pub(super) fn spot(p: Vec3A, axis: Vec3A, phi: f32, cos_inner: f32, cos_outer: f32) -> Self {
        let inner = cos_inner.clamp(-1.0, 1.0).acos();
        let outer = cos_outer.clamp(-1.0, 1.0).acos();
        // (A hair wider than the cone, so that rounding never cuts off a
        // point the falloff still reaches.)
        let spread = ((outer - inner).max(0.0) + 1e-3).min(PI);
        Self {
            lo: p,
            hi: p,
            phi,
            axis,
            cos_o: inner.cos(),
            cos_e: spread.cos(),
            two_sided: false,
        }
    }

    /// A sphere in the box `lo`–`hi` (or anything that sends intensity
    /// `phi` every way from inside it).
    pub(super) fn sphere(lo: Vec3A, hi: Vec3A, phi: f32) -> Self {
        Self {
            lo,
            hi,
            phi,
            axis: Vec3A::Z,
            cos_o: -1.0,
            cos_e: 0.0,
            two_sided: false,
        }
    }

    /// A triangle with vertices `v`, unit front normal `n`, emitting intensity
    /// `phi` along its normal, from the front or from both sides.
    pub(super) fn triangle(v: &[Vec3A; 3], n: Vec3A, phi: f32, two_sided: bool) -> Self {
        let (lo, hi) = (v[0].min(v[1]).min(v[2]), v[0].max(v[1]).max(v[2]));
        Self::flat(lo, hi, n, phi, two_sided)
    }

    /// A flat emitter (a triangle, a disk) in the box `lo`–`hi` with unit
    /// front normal `n`, emitting intensity `phi` along its normal, from the
    /// front or from both sides.
    pub(super) fn flat(lo: Vec3A, hi: Vec3A, n: Vec3A, phi: f32, two_sided: bool) -> Self {
        Self {
            lo,
            hi,
            phi,
            axis: n,
            cos_o: 1.0,
            cos_e: 0.0,
            two_sided,
        }
    }

    /// The bounds of both sets.
    fn union(&self, other: &Self) -> Self {
        if self.phi == 0.0 {
            return *other;
        }
        if other.phi == 0.0 {
            return *self;
        }
        let (axis, cos_o) = cone_union(self.axis, self.cos_o, other.axis, other.cos_o);
        Self {
            lo: self.lo.min(other.lo),
            hi: self.hi.max(other.hi),
            phi: self.phi + other.phi,
            axis,
            cos_o,
            cos_e: self.cos_e.min(other.cos_e),
            two_sided: self.two_sided || other.two_sided,
        }
    }

    /// The box's centre.
    #[inline]
    fn centre(&self) -> Vec3A {
        0.5 * (self.lo + self.hi)
    }

    /// A bound on what the lights send to a surface at `p` that `facing`
    /// describes ([`Importance::at`]).
    #[cfg(test)]
    pub(super) fn importance(&self, p: Vec3A, facing: Facing) -> f32 {
        Importance4::of(std::slice::from_ref(self)).at(p, facing).x
    }

    /// pbrt-v4's cost of a set for the split search: power times the
    /// solid angle its emission covers times the box's surface area.
    fn cost(&self, regularise: f32) -> f32 {
        let theta_o = self.cos_o.clamp(-1.0, 1.0).acos();
        let theta_e = self.cos_e.clamp(-1.0, 1.0).acos();
        let theta_w = (theta_o + theta_e).min(PI);
        let sin_o = (1.0 - self.cos_o * self.cos_o).max(0.0).sqrt();
        let m_omega = 2.0 * PI * (1.0 - self.cos_o)
            + FRAC_PI_2
                * (2.0 * theta_w * sin_o - (theta_o - 2.0 * theta_w).cos() - 2.0 * theta_o * sin_o
                    + self.cos_o);
        let d = self.hi - self.lo;
        let area = 2.0 * (d.x * d.y + d.y * d.z + d.z * d.x);
        self.phi * m_omega * regularise * area
    }
}

/// Up to four [`LightBounds`] as the importance needs them, one per lane
/// (a lane of zero `phi` is empty); a node of the tree holds its children's.
#[derive(Clone, Copy, Debug)]
pub(super) struct Importance4 {
    centre: [Vec4; 3],
    axis: [Vec4; 3],
    /// The squared radius of the sphere around each box.
    r2: Vec4,
    phi: Vec4,
    cos_o: Vec4,
    sin_o: Vec4,
    cos_e: Vec4,
    /// 1 where the lights emit on both sides, else 0.
    two_sided: Vec4,
}

impl Importance4 {
    /// The bounds `b` in the lanes they fill (the others empty).
    pub(super) fn of(b: &[LightBounds]) -> Self {
        debug_assert!(b.len() <= 4);
        // (Empty lanes: zero, but a unit axis and a point cone.)
        let lane_or = |f: &dyn Fn(&LightBounds) -> f32, empty: f32| {
            Vec4::from_array(std::array::from_fn(|k| b.get(k).map_or(empty, f)))
        };
        let lane = |f: &dyn Fn(&LightBounds) -> f32| lane_or(f, 0.0);
        Self {
            centre: [
                lane(&|b| b.centre().x),
                lane(&|b| b.centre().y),
                lane(&|b| b.centre().z),
            ],
            axis: [
                lane(&|b| b.axis.x),
                lane(&|b| b.axis.y),
                lane_or(&|b| b.axis.z, 1.0),
            ],
            r2: lane(&|b| (0.5 * (b.hi - b.lo)).length_squared()),
            phi: lane(&|b| b.phi),
            cos_o: lane_or(&|b| b.cos_o, 1.0),
            sin_o: lane(&|b| (1.0 - b.cos_o * b.cos_o).max(0.0).sqrt()),
            cos_e: lane(&|b| b.cos_e),
            two_sided: lane(&|b| f32::from(u8::from(b.two_sided))),
        }
    }

    /// A bound, per lane, on what its lights send to a surface at `p` that
    /// `facing` describes, for choosing among sets of lights:
    /// `phi · cos θ' / d²`, with `d` the distance to the box's centre (at
    /// least the radius of the sphere around the box), `θ'` the smallest
    /// angle between any normal of the cone and any direction from the box to
    /// `p` (zero beyond the emission spread), and, for a surface, the cosine
    /// of the smallest angle between its normal and any direction from `p` to
    /// the box (zero below its horizon). Empty lanes give 0. In `Vec4` lanes
    /// (SSE2 on x86-64, plain floats elsewhere: the same IEEE operations, so
    /// the same values on every machine).
    #[inline]
    pub(super) fn at(&self, p: Vec3A, facing: Facing) -> Vec4 {
        let (zero, one) = (Vec4::ZERO, Vec4::ONE);
        let d = [
            Vec4::splat(p.x) - self.centre[0],
            Vec4::splat(p.y) - self.centre[1],
            Vec4::splat(p.z) - self.centre[2],
        ];
        let d2_centre = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
        let r2 = self.r2;
        let d2 = d2_centre.max(r2);
        let inv = one / sqrt4(d2_centre);
        let f = [d[0] * inv, d[1] * inv, d[2] * inv];
        let finite = f[0].is_finite_mask() & f[1].is_finite_mask() & f[2].is_finite_mask();
        // Every direction of the box as seen from `p` lies within `θb` of
        // the centre's (the bounding sphere's cone; all of them from inside;
        // none but the centre's for a point).
        let inside = d2_centre.cmplt(r2) | !finite;
        let point = r2.cmpeq(zero);
        let sin2 = r2 / d2_centre;
        let sin_b = Vec4::select(inside | point, zero, sqrt4(sin2));
        let cos_b = Vec4::select(
            inside,
            -one,
            Vec4::select(point, one, sqrt4((one - sin2).max(zero))),
        );
        let f = [
            Vec4::select(inside, self.axis[0], f[0]),
            Vec4::select(inside, self.axis[1], f[1]),
            Vec4::select(inside, self.axis[2], f[2]),
        ];
        // The angle between the cone's axis and the direction to `p`, less
        // the cone (`θo`) and the directions' spread (`θb`), as cosines:
        // `cos(max(0, θw − θo − θb))`.
        let cos_w = self.axis[0] * f[0] + self.axis[1] * f[1] + self.axis[2] * f[2];
        let cos_w = Vec4::select(self.two_sided.cmpne(zero), cos_w.abs(), cos_w);
        let sin_w = sqrt4((one - cos_w * cos_w).max(zero));
        let cos_x = cos_w * self.cos_o + sin_w * self.sin_o;
        let sin_x = sin_w * self.cos_o - cos_w * self.sin_o;
        let cos_p = Vec4::select(
            cos_w.cmpgt(self.cos_o) | cos_x.cmpgt(cos_b),
            one,
            cos_x * cos_b + sin_x * sin_b,
        );
        let importance = self.phi * cos_p / d2;
        let cos_i = match facing {
            Facing::Any => one,
            Facing::Side(n) => {
                -(Vec4::splat(n.x) * f[0] + Vec4::splat(n.y) * f[1] + Vec4::splat(n.z) * f[2])
            }
            Facing::Both(n) => {
                (Vec4::splat(n.x) * f[0] + Vec4::splat(n.y) * f[1] + Vec4::splat(n.z) * f[2]).abs()
            }
        };
        let sin_i = sqrt4((one - cos_i * cos_i).max(zero));
        let towards = Vec4::select(cos_i.cmpgt(cos_b), one, cos_i * cos_b + sin_i * sin_b);
        let importance = importance * towards;
        let counts = cos_p.cmpgt(self.cos_e)
            & d2.cmpgt(zero)
            & importance.cmpgt(zero)
            & importance.is_finite_mask();
        Vec4::select(counts, importance, zero)
    }
}

/// The angle between unit vectors, accurate near 0 and π.
fn angle_between(a: Vec3A, b: Vec3A) -> f32 {
    if a.dot(b) < 0.0 {
        PI - 2.0 * ((a + b).length() / 2.0).min(1.0).asin()
    } else {
        2.0 * ((b - a).length() / 2.0).min(1.0).asin()
    }
}

/// The smallest cone (axis, cosine of the half angle) holding both cones,
/// a little wider (so that rounding never leaves a normal out).
fn cone_union(wa: Vec3A, cos_a: f32, wb: Vec3A, cos_b: f32) -> (Vec3A, f32) {
    let theta_a = cos_a.clamp(-1.0, 1.0).acos();
    let theta_b = cos_b.clamp(-1.0, 1.0).acos();
    let theta_d = angle_between(wa, wb);
    if (theta_d + theta_b).min(PI) <= theta_a {
        return (wa, cos_a);
    }
    if (theta_d + theta_a).min(PI) <= theta_b {
        return (wb, cos_b);
    }
    let theta_o = 0.5 * (theta_a + theta_d + theta_b) + 1e-4;
    if theta_o >= PI {
        return (wa, -1.0);
    }
    // Turn `wa` towards `wb` by `θo − θa` about their common perpendicular.
    let theta_r = theta_o - theta_a;
    let perpendicular = wa.cross(wb);
    if perpendicular.length_squared() < 1e-12 {
        return (wa, -1.0);
    }
    let k = perpendicular.normalize();
    let (s, c) = theta_r.sin_cos();
    // Rodrigues' rotation (`k ⟂ wa`).
    let w = (wa * c + k.cross(wa) * s).normalize();
    (w, theta_o.cos())
}

/// A light the tree holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum TreeLight {
    /// Punctual light `i` of the scene's lights (a point or a spot).
    Punctual(u32),
    /// Emitting triangle `prim`.
    Triangle(u32),
}

/// A node of up to four children, each a light or another node.
#[derive(Clone, Copy, Debug)]
struct Node {
    /// The children's bounds, one lane each.
    bounds: Importance4,
    /// Each child's node (or, where `leaves` has its bit, light) index.
    child: [u32; 4],
    /// Bit `k`: child `k` is a light.
    leaves: u8,
}

/// A node of the binary tree the build makes before it is folded into
/// four-wide nodes.
#[derive(Clone, Copy, Debug)]
struct BinaryNode {
    bounds: LightBounds,
    /// A light's index, or the node's children.
    kind: BinaryKind,
}

#[derive(Clone, Copy, Debug)]
enum BinaryKind {
    Light(u32),
    Inner(u32, u32),
}

/// The hierarchy, and each emitting triangle's path to it.
#[derive(Clone, Debug, Default)]
pub(super) struct LightTree {
    nodes: Vec<Node>,
    lights: Vec<TreeLight>,
    /// Every triangle's path from the root: bits `2k` and `2k + 1` are the
    /// child taken at depth `k`; `u64::MAX` for a triangle the tree does not
    /// hold. Empty when the tree holds no triangle.
    prim_trail: Vec<u64>,
    /// Every punctual light's path from the root, as `prim_trail`'s
    /// (`u64::MAX` for a light the tree does not hold); empty when it holds
    /// none.
    punctual_trail: Vec<u64>,
}

/// Buckets per axis of the split search.
const BUCKETS: usize = 12;

/// Below this depth of the binary tree splits follow the cost; from it,
/// halves by count (so that no path is longer than the 64 bits, two a level
/// of the four-wide tree, that record it).
const COST_DEPTH: u32 = 31;

impl LightTree {
    /// The tree over `lights` (each with bounds of positive `phi`); `triangles`
    /// and `punctuals` are how many triangles and punctual lights the scene
    /// has (for their paths).
    pub(super) fn build(
        mut lights: Vec<(LightBounds, TreeLight)>,
        triangles: usize,
        punctuals: usize,
    ) -> Self {
        lights.retain(|(b, _)| b.phi > 0.0 && b.phi.is_finite());
        let mut tree = Self::default();
        if lights.is_empty() {
            return tree;
        }
        if lights
            .iter()
            .any(|(_, l)| matches!(l, TreeLight::Triangle(_)))
        {
            tree.prim_trail = vec![u64::MAX; triangles];
        }
        if lights
            .iter()
            .any(|(_, l)| matches!(l, TreeLight::Punctual(_)))
        {
            tree.punctual_trail = vec![u64::MAX; punctuals];
        }
        let mut binary = Vec::with_capacity(2 * lights.len() - 1);
        let root = build_binary(&mut binary, &mut lights, 0, 0);
        tree.lights = lights.iter().map(|&(_, l)| l).collect();
        // A lone light is the root's only child.
        let top = match binary[root].kind {
            BinaryKind::Light(_) => vec![root],
            BinaryKind::Inner(a, b) => vec![a as usize, b as usize],
        };
        tree.fold(&binary, &top, 0, 0);
        tree
    }

    /// Appends the four-wide node over the binary nodes `children` (each
    /// inner one replaced by its two children while there is room) and its
    /// subtrees; returns its index.
    fn fold(&mut self, binary: &[BinaryNode], children: &[usize], trail: u64, depth: u32) -> usize {
        let mut slots: Vec<usize> = Vec::with_capacity(4);
        // Open inner children into their two while four slots allow.
        let mut room = 4 - children.len();
        for &c in children {
            match binary[c].kind {
                BinaryKind::Inner(a, b) if room > 0 => {
                    slots.push(a as usize);
                    slots.push(b as usize);
                    room -= 1;
                }
                _ => slots.push(c),
            }
        }
        let index = self.nodes.len();
        let bounds: Vec<LightBounds> = slots.iter().map(|&c| binary[c].bounds).collect();
        self.nodes.push(Node {
            bounds: Importance4::of(&bounds),
            child: [u32::MAX; 4],
            leaves: 0,
        });
        for (k, &c) in slots.iter().enumerate() {
            let trail = trail | (k as u64) << (2 * depth);
            match binary[c].kind {
                BinaryKind::Light(light) => {
                    match self.lights[light as usize] {
                        TreeLight::Triangle(prim) => self.prim_trail[prim as usize] = trail,
                        TreeLight::Punctual(i) => self.punctual_trail[i as usize] = trail,
                    }
                    self.nodes[index].child[k] = light;
                    self.nodes[index].leaves |= 1 << k;
                }
                BinaryKind::Inner(a, b) => {
                    let child = self.fold(binary, &[a as usize, b as usize], trail, depth + 1);
                    self.nodes[index].child[k] = child as u32;
                }
            }
        }
        index
    }

    /// The importances of the root's children at `p` ([`Importance4::at`]);
    /// their sum is the tree's. Zero for an empty tree.
    #[inline]
    pub(super) fn root_importances(&self, p: Vec3A, facing: Facing) -> Vec4 {
        self.nodes
            .first()
            .map_or(Vec4::ZERO, |root| root.bounds.at(p, facing))
    }

    /// A light chosen with `u` in `[0, 1)` for a surface at `p` (as `facing`
    /// says), the probability of that choice, and what is left of `u`: where
    /// it fell inside the chosen light's share, again uniform in `[0, 1)`, so
    /// that the caller can reuse it to pick a point on the light and keep
    /// the stratification of `u` across the lights. `None` when no light can
    /// send anything there. `root` is [`LightTree::root_importances`] at `p`.
    /// (`u` is an `f64` when its leftover is reused: each level spends some
    /// of its bits; as an `f32` the walk is the one images were made with
    /// before, bit for bit.)
    #[inline]
    pub(super) fn sample<U: Fraction>(
        &self,
        root: Vec4,
        p: Vec3A,
        facing: Facing,
        mut u: U,
    ) -> Option<(TreeLight, f32, U)> {
        let mut index = 0usize;
        let mut pmf = 1.0f32;
        loop {
            let node = self.nodes.get(index)?;
            let (w, total) = Self::weights(node, (index == 0).then_some(root), p, facing)?;
            let (k, wk, rest) = choose(w, total, u)?;
            u = rest;
            pmf *= wk / total;
            if node.leaves >> k & 1 != 0 {
                return Some((self.lights[node.child[k] as usize], pmf, u));
            }
            index = node.child[k] as usize;
        }
    }

    /// The probability that [`LightTree::sample`] chooses emitting triangle
    /// `prim` for a surface at `p`; zero for a triangle the tree does not hold.
    /// `root` is [`LightTree::root_importances`] at `p`.
    #[inline]
    pub(super) fn triangle_pmf(&self, root: Vec4, prim: u32, p: Vec3A, facing: Facing) -> f32 {
        self.trail_pmf(root, self.prim_trail.get(prim as usize), p, facing)
    }

    /// The probability that [`LightTree::sample`] chooses punctual light `i`
    /// (of the scene's lights) for a surface at `p`; zero for one the tree
    /// does not hold. `root` is [`LightTree::root_importances`] at `p`.
    #[inline]
    pub(super) fn punctual_pmf(&self, root: Vec4, i: u32, p: Vec3A, facing: Facing) -> f32 {
        self.trail_pmf(root, self.punctual_trail.get(i as usize), p, facing)
    }

    /// The probability of the choices down `trail` (none: zero).
    #[inline]
    fn trail_pmf(&self, root: Vec4, trail: Option<&u64>, p: Vec3A, facing: Facing) -> f32 {
        let Some(&trail) = trail else {
            return 0.0;
        };
        if trail == u64::MAX {
            return 0.0;
        }
        let mut trail = trail;
        let mut index = 0usize;
        let mut pmf = 1.0f32;
        loop {
            let node = &self.nodes[index];
            let Some((w, total)) = Self::weights(node, (index == 0).then_some(root), p, facing)
            else {
                return 0.0;
            };
            let k = (trail & 3) as usize;
            pmf *= w[k] / total;
            if node.leaves >> k & 1 != 0 || pmf == 0.0 {
                return pmf;
            }
            index = node.child[k] as usize;
            trail >>= 2;
        }
    }

    /// The weights of a node's children at `p` and their sum: their
    /// importances, or, where none of their bounds reaches `p` though their
    /// parent's did, their intensities (the light chosen then sends nothing,
    /// but every light keeps a probability and they add up to one). `None`
    /// when all are zero. `known`: the importances, already computed.
    #[inline]
    fn weights(
        node: &Node,
        known: Option<Vec4>,
        p: Vec3A,
        facing: Facing,
    ) -> Option<([f32; 4], f32)> {
        let w = known.unwrap_or_else(|| node.bounds.at(p, facing));
        let total = sum(w);
        if total > 0.0 {
            return Some((w.to_array(), total));
        }
        let phi = node.bounds.phi;
        let total = sum(phi);
        (total > 0.0).then(|| (phi.to_array(), total))
    }

    /// How deep the four-wide tree is (for tests).
    #[cfg(test)]
    fn depth(&self) -> u32 {
        fn walk(t: &LightTree, i: usize) -> u32 {
            let n = &t.nodes[i];
            (0..4)
                .filter(|&k| n.child[k] != u32::MAX && n.leaves >> k & 1 == 0)
                .map(|k| 1 + walk(t, n.child[k] as usize))
                .max()
                .unwrap_or(1)
        }
        if self.nodes.is_empty() {
            0
        } else {
            walk(self, 0)
        }
    }
}

/// The lanes' square roots (correctly rounded, as `f32::sqrt`).
#[inline(always)]
fn sqrt4(v: Vec4) -> Vec4 {
    #[cfg(target_arch = "x86_64")]
    {
        // SAFETY: SSE is part of x86-64.
        Vec4::from(unsafe { std::arch::x86_64::_mm_sqrt_ps(v.into()) })
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        v.map(f32::sqrt)
    }
}

/// The lanes' sum, in a fixed order.
#[inline]
pub(super) fn sum(v: Vec4) -> f32 {
    (v.x + v.y) + (v.z + v.w)
}

/// Appends the binary subtree over `lights` (reordering them; they are
/// lights `offset..` of the tree) to `nodes`, `depth` deep; returns its index.
/// A leaf's light index is its place in `lights` after the build.
fn build_binary(
    nodes: &mut Vec<BinaryNode>,
    lights: &mut [(LightBounds, TreeLight)],
    offset: u32,
    depth: u32,
) -> usize {
    let index = nodes.len();
    if lights.len() == 1 {
        nodes.push(BinaryNode {
            bounds: lights[0].0,
            kind: BinaryKind::Light(offset),
        });
        return index;
    }
    let mut bounds = lights[0].0;
    let (mut c_lo, mut c_hi) = (bounds.centre(), bounds.centre());
    for (b, _) in &lights[1..] {
        bounds = bounds.union(b);
        c_lo = c_lo.min(b.centre());
        c_hi = c_hi.max(b.centre());
    }
    let mid = split(lights, &bounds, c_lo, c_hi, depth);
    nodes.push(BinaryNode {
        bounds,
        kind: BinaryKind::Inner(0, 0),
    });
    let (first, second) = lights.split_at_mut(mid);
    let a = build_binary(nodes, first, offset, depth + 1);
    let b = build_binary(nodes, second, offset + mid as u32, depth + 1);
    nodes[index].kind = BinaryKind::Inner(a as u32, b as u32);
    index
}

/// Orders `lights` into two non-empty groups and returns the size of the
/// first: the bucket boundary of least cost (pbrt-v4's), or halves by count.
fn split(
    lights: &mut [(LightBounds, TreeLight)],
    bounds: &LightBounds,
    c_lo: Vec3A,
    c_hi: Vec3A,
    depth: u32,
) -> usize {
    let n = lights.len();
    let extent = bounds.hi - bounds.lo;
    let bucket = |b: &LightBounds, axis: usize| {
        let x = (b.centre()[axis] - c_lo[axis]) / (c_hi[axis] - c_lo[axis]);
        ((x * BUCKETS as f32) as usize).min(BUCKETS - 1)
    };
    // (cost, axis, first bucket of the second group)
    let mut best: Option<(f32, usize, usize)> = None;
    if depth < COST_DEPTH {
        for axis in 0..3 {
            if c_hi[axis] <= c_lo[axis] {
                continue;
            }
            let mut buckets = [None::<LightBounds>; BUCKETS];
            for (b, _) in lights.iter() {
                let k = bucket(b, axis);
                buckets[k] = Some(buckets[k].map_or(*b, |a| a.union(b)));
            }
            let regularise = extent.max_element() / extent[axis].max(f32::MIN_POSITIVE);
            let cost_of = |range: &[Option<LightBounds>]| {
                range
                    .iter()
                    .flatten()
                    .copied()
                    .reduce(|a, b| a.union(&b))
                    .map_or(0.0, |b| b.cost(regularise))
            };
            for split in 1..BUCKETS {
                let cost = cost_of(&buckets[..split]) + cost_of(&buckets[split..]);
                if cost.is_finite() && best.is_none_or(|(c, _, _)| cost < c) {
                    best = Some((cost, axis, split));
                }
            }
        }
    }
    if let Some((_, axis, split)) = best {
        let mut first = 0;
        for i in 0..n {
            if bucket(&lights[i].0, axis) < split {
                lights.swap(i, first);
                first += 1;
            }
        }
        if first > 0 && first < n {
            return first;
        }
    }
    // Halves by count along the widest spread of centres.
    let axis = (c_hi - c_lo).max_position();
    let mid = n / 2;
    lights.select_nth_unstable_by(mid, |a, b| {
        a.0.centre()[axis].total_cmp(&b.0.centre()[axis])
    });
    mid
}

/// A number in `[0, 1)` that chooses among weights ([`choose`]): `f32`, or
/// `f64` where what is left of it after the choice is used again.
pub(super) trait Fraction:
    Copy
    + PartialOrd
    + From<f32>
    + std::ops::Add<Output = Self>
    + std::ops::Sub<Output = Self>
    + std::ops::Mul<Output = Self>
    + std::ops::Div<Output = Self>
{
    /// Zero.
    const ZERO: Self;
    /// The largest value below 1.
    const ONE_BELOW: Self;
    /// The value as an `f32` in `[0, 1)`.
    fn to_unit_f32(self) -> f32;
    /// The value clamped to `[0, ONE_BELOW]` (as `clamp`: a NaN stays).
    #[inline(always)]
    fn clamp_unit(self) -> Self {
        if self < Self::ZERO {
            Self::ZERO
        } else if self > Self::ONE_BELOW {
            Self::ONE_BELOW
        } else {
            self
        }
    }
}

impl Fraction for f32 {
    const ZERO: Self = 0.0;
    const ONE_BELOW: Self = 1.0 - f32::EPSILON / 2.0;
    #[inline(always)]
    fn to_unit_f32(self) -> f32 {
        self
    }
}

impl Fraction for f64 {
    const ZERO: Self = 0.0;
    const ONE_BELOW: Self = 1.0 - f64::EPSILON / 2.0;
    #[inline(always)]
    fn to_unit_f32(self) -> f32 {
        (self as f32).min(<f32 as Fraction>::ONE_BELOW)
    }
}

/// Which of `weights` (summing to `total` > 0) the number `u` in `[0, 1)`
/// falls in, walking them in order and no further (rounding past the end
/// takes the last one with weight): its index, its weight, and where `u`
/// fell inside its share, in `[0, 1)`. `None` when no weight is positive.
#[inline(always)]
pub(super) fn choose<U: Fraction>(
    weights: impl IntoIterator<Item = f32>,
    total: f32,
    u: U,
) -> Option<(usize, f32, U)> {
    let target = u * U::from(total);
    let mut start = U::ZERO;
    let mut chosen = None;
    for (k, wk) in weights.into_iter().enumerate() {
        if wk <= 0.0 {
            continue;
        }
        chosen = Some((k, start, wk));
        start = start + U::from(wk);
        if target < start {
            break;
        }
    }
    let (k, start, wk) = chosen?;
    Some((k, wk, ((target - start) / U::from(wk)).clamp_unit()))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A deterministic stream of numbers in `[0, 1)`.
    struct Lcg(u64);
    impl Lcg {
        fn next(&mut self) -> f32 {
            self.0 = self
                .0
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            (self.0 >> 40) as f32 / (1u64 << 24) as f32
        }
        fn vec(&mut self, s: f32) -> Vec3A {
            Vec3A::new(self.next(), self.next(), self.next()) * 2.0 * s - s
        }
        fn unit(&mut self) -> Vec3A {
            loop {
                let v = self.vec(1.0);
                if v.length_squared() > 0.01 && v.length_squared() <= 1.0 {
                    return v.normalize();
                }
            }
        }
    }

    fn random_lights(rng: &mut Lcg, n: usize) -> Vec<(LightBounds, TreeLight)> {
        (0..n)
            .map(|i| {
                let c = rng.vec(10.0);
                let phi = 0.01 + 10.0 * rng.next() * rng.next();
                let b = match i % 4 {
                    0 => LightBounds::point(c, phi),
                    1 => LightBounds::spot(c, rng.unit(), phi, 0.9, 0.7),
                    _ => {
                        let v = [c, c + rng.vec(0.3), c + rng.vec(0.3)];
                        let n = (v[1] - v[0]).cross(v[2] - v[0]).normalize();
                        LightBounds::triangle(&v, n, phi, i % 8 == 2)
                    }
                };
                (b, TreeLight::Triangle(i as u32))
            })
            .collect()
    }

    #[test]
    fn the_choices_add_up_to_one_and_sampling_follows_them() {
        let mut rng = Lcg(7);
        let n = 300;
        let tree = LightTree::build(random_lights(&mut rng, n), n, 0);
        assert!(tree.depth() < 64);
        for trial in 0..40 {
            let p = rng.vec(12.0);
            let facing = match trial % 3 {
                0 => Facing::Any,
                1 => Facing::Side(rng.unit()),
                _ => Facing::Both(rng.unit()),
            };
            let pmfs: Vec<f64> = (0..n as u32)
                .map(|i| {
                    f64::from(tree.triangle_pmf(tree.root_importances(p, facing), i, p, facing))
                })
                .collect();
            let sum: f64 = pmfs.iter().sum();
            assert!((sum - 1.0).abs() < 1e-5, "pmfs sum to {sum} at {p}");
            // Sampling picks each light as often as its pmf says (χ² over
            // the lights with an expected count of at least 5).
            let draws = 20_000;
            let mut counts = vec![0u32; n];
            let mut rests = vec![Vec::new(); n];
            for k in 0..draws {
                let u = (k as f64 + 0.5) / draws as f64;
                let (light, pmf, rest) = tree
                    .sample(tree.root_importances(p, facing), p, facing, u)
                    .expect("a light");
                let TreeLight::Triangle(i) = light else {
                    unreachable!()
                };
                assert!((0.0..1.0).contains(&rest), "leftover {rest}");
                rests[i as usize].push(rest);
                assert_eq!(
                    pmf,
                    tree.triangle_pmf(tree.root_importances(p, facing), i, p, facing),
                    "pmf of {i}"
                );
                counts[i as usize] += 1;
            }
            let mut chi2 = 0.0;
            let mut cells = 0;
            let (mut rest_expected, mut rest_seen) = (0.0, 0.0);
            for (i, &pmf) in pmfs.iter().enumerate() {
                let expected = pmf * draws as f64;
                if expected >= 5.0 {
                    chi2 += (f64::from(counts[i]) - expected).powi(2) / expected;
                    cells += 1;
                } else {
                    rest_expected += expected;
                    rest_seen += f64::from(counts[i]);
                    // A light of zero probability is never chosen.
                    assert!(pmf > 0.0 || counts[i] == 0);
                }
            }
            if rest_expected > 0.0 {
                chi2 += (rest_seen - rest_expected).powi(2) / rest_expected.max(1.0);
                cells += 1;
            }
            // Stratified draws: far below the χ² bound of `cells` degrees.
            let bound = cells as f64 + 5.0 * (2.0 * cells as f64).sqrt();
            assert!(chi2 < bound, "χ² {chi2} over {cells} cells at {p}");
            // Each light's share of `u` is one interval, mapped onto [0, 1):
            // the evenly spaced draws that chose it leave evenly spaced
            // leftovers, c of them at (j + ½)/c within two steps.
            for r in rests.iter_mut().filter(|r| r.len() >= 20) {
                r.sort_by(f64::total_cmp);
                let c = r.len() as f64;
                let worst = r
                    .iter()
                    .enumerate()
                    .map(|(j, &x)| (x - (j as f64 + 0.5) / c).abs())
                    .fold(0.0, f64::max);
                assert!(worst <= 2.0 / c, "leftovers off by {worst} over {c}");
            }
        }
    }

    #[test]
    fn importance_is_zero_only_where_nothing_arrives() {
        let mut rng = Lcg(3);
        // A one-sided triangle facing +z at the origin.
        let v = [Vec3A::ZERO, Vec3A::X, Vec3A::Y];
        let tri = LightBounds::triangle(&v, Vec3A::Z, 1.0, false);
        assert_eq!(tri.importance(Vec3A::new(0.3, 0.3, -2.0), Facing::Any), 0.0);
        assert!(tri.importance(Vec3A::new(0.3, 0.3, 2.0), Facing::Any) > 0.0);
        // A surface facing away from the light gets nothing.
        let above = Vec3A::new(0.3, 0.3, 2.0);
        assert_eq!(tri.importance(above, Facing::Side(Vec3A::Z)), 0.0);
        assert!(tri.importance(above, Facing::Side(-Vec3A::Z)) > 0.0);
        assert!(tri.importance(above, Facing::Both(Vec3A::Z)) > 0.0);
        // Bounds of many lights are positive wherever one light is.
        let lights = random_lights(&mut rng, 64);
        let all = lights
            .iter()
            .map(|(b, _)| *b)
            .reduce(|a, b| a.union(&b))
            .unwrap();
        for _ in 0..2000 {
            let p = rng.vec(15.0);
            let facing = Facing::Side(rng.unit());
            if lights.iter().any(|(b, _)| b.importance(p, facing) > 0.0) {
                assert!(all.importance(p, facing) > 0.0, "at {p}");
            }
        }
        // A spot sends nothing outside its outer cone.
        let spot = LightBounds::spot(Vec3A::ZERO, -Vec3A::Y, 1.0, 0.95, 0.9);
        assert_eq!(
            spot.importance(Vec3A::new(2.0, -1.0, 0.0), Facing::Any),
            0.0
        );
        assert!(spot.importance(Vec3A::new(0.1, -1.0, 0.0), Facing::Any) > 0.0);
    }
}
