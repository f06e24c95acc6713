//! The scene's analytic spheres ([`SceneSphere`], held as [`Spheres`]): a
//! small binary hierarchy of their bounds beside the triangles' eight-wide
//! one, queried after it with the distance it found. A sphere is primitive
//! `triangles + k` of the scene (so hits, materials and light tables name it
//! as they name triangles); its hit's two barycentric slots hold its
//! spherical coordinates `(φ/2π, θ/π)`.

use glam::Vec3A;

use crate::geometry::ray::Ray;
use crate::geometry::sphere::Sphere;

/// A sphere of the scene with its material.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SceneSphere {
    /// The shape.
    pub sphere: Sphere,
    /// Whether its front (the side it emits from and a one-sided material
    /// shows) is the inside (Mitsuba's `flip_normals`).
    pub flip: bool,
    /// Index of its material.
    pub material: u32,
}

impl SceneSphere {
    /// The point at spherical coordinates `uv` with its error bound and its
    /// front normal (outwards, inwards when flipped).
    #[inline]
    pub fn front_point(&self, uv: glam::Vec2) -> crate::geometry::ray::SurfacePoint {
        let mut point = self.sphere.point_at(uv);
        if self.flip {
            point.n = -point.n;
        }
        point
    }
}

/// A node of the spheres' hierarchy: a box and either two children (`count
/// == 0`: `first` and `first + 1`) or `count` spheres from `first` in order.
#[derive(Clone, Copy, Debug)]
struct Node {
    lo: Vec3A,
    hi: Vec3A,
    first: u32,
    count: u32,
}

/// Spheres per leaf at most.
const LEAF: usize = 4;
/// Depth of the traversal stack (the build halves by count, so 2⁶⁴ spheres
/// would fit).
const STACK: usize = 64;

/// The scene's spheres, reordered for their hierarchy.
#[derive(Clone, Debug, Default)]
pub struct Spheres {
    /// The spheres in hierarchy order, with their index in the input.
    items: Vec<(SceneSphere, u32)>,
    /// Where each input sphere sits in `items`.
    position: Vec<u32>,
    nodes: Vec<Node>,
}

impl Spheres {
    /// The hierarchy over `spheres` (split at the median of the longest axis
    /// of their centres' box).
    pub fn build(spheres: &[SceneSphere]) -> Self {
        let mut items: Vec<(SceneSphere, u32)> = spheres
            .iter()
            .enumerate()
            .map(|(i, s)| (*s, i as u32))
            .collect();
        let mut nodes = Vec::new();
        if !items.is_empty() {
            nodes.push(Node {
                lo: Vec3A::ZERO,
                hi: Vec3A::ZERO,
                first: 0,
                count: 0,
            });
            let n = items.len();
            build(&mut nodes, &mut items, 0, 0, n);
        }
        let mut position = vec![0u32; items.len()];
        for (at, &(_, k)) in items.iter().enumerate() {
            position[k as usize] = at as u32;
        }
        Self {
            items,
            position,
            nodes,
        }
    }

    /// Whether the scene has no sphere.
    #[inline]
    pub fn is_empty(&self) -> bool {
        self.items.is_empty()
    }

    /// How many spheres.
    #[inline]
    pub fn len(&self) -> usize {
        self.items.len()
    }

    /// Sphere `k` in input order.
    #[inline]
    pub fn get(&self, k: u32) -> &SceneSphere {
        &self.items[self.position[k as usize] as usize].0
    }

    /// The input spheres in input order.
    pub fn in_order(&self) -> Vec<SceneSphere> {
        let mut v = self.items.clone();
        v.sort_by_key(|&(_, i)| i);
        v.into_iter().map(|(s, _)| s).collect()
    }

    /// The closest sphere crossing along `ray` in `(0, t_max]`: its `t` and
    /// the sphere's input index.
    #[inline]
    pub fn intersect(&self, ray: &Ray, t_max: f32) -> Option<(f32, u32)> {
        let mut best: Option<(f32, u32)> = None;
        let mut t_max = t_max;
        self.walk(ray, &mut t_max, &mut |s, k, t_max| {
            if let Some(t) = s.sphere.intersect(ray, *t_max) {
                *t_max = t;
                best = Some((t, k));
            }
            false
        });
        best
    }

    /// Whether a sphere crosses `ray` in `(0, t_max]`.
    #[inline]
    pub fn occluded(&self, ray: &Ray, t_max: f32) -> bool {
        let mut t_max = t_max;
        self.walk(ray, &mut t_max, &mut |s, _, t_max| {
            s.sphere.intersect(ray, *t_max).is_some()
        })
    }

    /// Visits the spheres whose boxes `ray` meets within `t_max` (which the
    /// visitor may shorten) until the visitor returns `true`; returns whether
    /// it did.
    fn walk(
        &self,
        ray: &Ray,
        t_max: &mut f32,
        visit: &mut impl FnMut(&SceneSphere, u32, &mut f32) -> bool,
    ) -> bool {
        if self.nodes.is_empty() {
            return false;
        }
        let inv = Vec3A::ONE / ray.dir;
        let mut stack = [0u32; STACK];
        let mut top = 1;
        while top > 0 {
            top -= 1;
            let node = &self.nodes[stack[top] as usize];
            if !slab(ray.origin, inv, node.lo, node.hi, *t_max) {
                continue;
            }
            if node.count > 0 {
                let (a, b) = (node.first as usize, (node.first + node.count) as usize);
                for (s, k) in &self.items[a..b] {
                    if visit(s, *k, t_max) {
                        return true;
                    }
                }
            } else if top + 2 <= STACK {
                stack[top] = node.first;
                stack[top + 1] = node.first + 1;
                top += 2;
            }
        }
        false
    }
}

/// Whether the ray `origin + t·dir` (with `inv = 1/dir`) meets the box for
/// some `t` in `[0, t_max]` (conservatively: the box is widened by a few
/// ulps so rounding never loses a sphere).
#[inline]
fn slab(origin: Vec3A, inv: Vec3A, lo: Vec3A, hi: Vec3A, t_max: f32) -> bool {
    let a = (lo - origin) * inv;
    let b = (hi - origin) * inv;
    // NaN (0 · ∞ on a box face) compares false in min/max's favour.
    let near = a.min(b).max_element().max(0.0);
    let far = a.max(b).min_element().min(t_max) * (1.0 + 4.0 * f32::EPSILON);
    near <= far
}

/// Mitsuba's unit sphere as a mesh of `segments` around and `segments / 2`
/// from pole to pole: (u, v) = (φ/2π, θ/π) of `(sin θ cos φ, sin θ sin φ,
/// cos θ)`, normals outwards (inwards, and wound so, when `flip`).
pub fn unit_sphere_mesh(segments: u32, flip: bool) -> super::mesh::MeshData {
    use std::f32::consts::PI;
    let mut mesh = super::mesh::grid(segments, segments / 2, |s, t| {
        let phi = 2.0 * PI * s;
        // The poles exactly (sin π is not 0 in f32): their triangles are
        // then exactly degenerate and left out.
        let (sin_t, cos_t) = match t {
            0.0 => (0.0, 1.0),
            1.0 => (0.0, -1.0),
            _ => (PI * t).sin_cos(),
        };
        let p = glam::Vec3::new(sin_t * phi.cos(), sin_t * phi.sin(), cos_t);
        (p, p, glam::Vec2::new(s, t))
    });
    if flip {
        for t in &mut mesh.indices {
            t.swap(1, 2);
        }
        for n in &mut mesh.normals {
            *n = -*n;
        }
    }
    mesh
}

/// Fills node `index` over `items[start..end]`, recursively.
fn build(
    nodes: &mut Vec<Node>,
    items: &mut [(SceneSphere, u32)],
    index: usize,
    start: usize,
    end: usize,
) {
    let (mut lo, mut hi) = (Vec3A::splat(f32::INFINITY), Vec3A::splat(f32::NEG_INFINITY));
    let (mut clo, mut chi) = (lo, hi);
    for (s, _) in &items[start..end] {
        let (a, b) = s.sphere.bounds();
        lo = lo.min(a);
        hi = hi.max(b);
        clo = clo.min(s.sphere.center);
        chi = chi.max(s.sphere.center);
    }
    if end - start <= LEAF {
        nodes[index] = Node {
            lo,
            hi,
            first: start as u32,
            count: (end - start) as u32,
        };
        return;
    }
    let extent = chi - clo;
    let axis = if extent.x >= extent.y && extent.x >= extent.z {
        0
    } else if extent.y >= extent.z {
        1
    } else {
        2
    };
    let mid = (start + end) / 2;
    items[start..end].select_nth_unstable_by(mid - start, |a, b| {
        a.0.sphere.center[axis].total_cmp(&b.0.sphere.center[axis])
    });
    let first = nodes.len();
    let blank = Node {
        lo,
        hi,
        first: 0,
        count: 0,
    };
    nodes.push(blank);
    nodes.push(blank);
    nodes[index] = Node {
        lo,
        hi,
        first: first as u32,
        count: 0,
    };
    build(nodes, items, first, start, mid);
    build(nodes, items, first + 1, mid, end);
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::sampler::Rng;
    use glam::Mat3A;

    /// The hierarchy answers as a loop over every sphere does, on a cloud of
    /// spheres and random rays.
    #[test]
    fn the_hierarchy_finds_what_brute_force_finds() {
        let mut rng = Rng::new(11, 5);
        let mut r = || rng.next_f32();
        let spheres: Vec<SceneSphere> = (0..300)
            .map(|i| SceneSphere {
                sphere: Sphere {
                    center: Vec3A::new(r() * 20.0 - 10.0, r() * 20.0 - 10.0, r() * 20.0 - 10.0),
                    radius: 0.05 + r() * 0.8,
                    frame: Mat3A::IDENTITY,
                },
                flip: false,
                material: i,
            })
            .collect();
        let set = Spheres::build(&spheres);
        assert_eq!(set.in_order(), spheres);
        let mut hits = 0;
        for _ in 0..5000 {
            let o = Vec3A::new(r() * 30.0 - 15.0, r() * 30.0 - 15.0, r() * 30.0 - 15.0);
            let d = Vec3A::new(r() - 0.5, r() - 0.5, r() - 0.5).normalize();
            let ray = Ray::new(o, d);
            let t_max = if r() < 0.5 { f32::INFINITY } else { r() * 20.0 };
            let brute = spheres
                .iter()
                .enumerate()
                .filter_map(|(k, s)| s.sphere.intersect(&ray, t_max).map(|t| (t, k as u32)))
                .min_by(|a, b| a.0.total_cmp(&b.0));
            assert_eq!(set.intersect(&ray, t_max), brute);
            assert_eq!(set.occluded(&ray, t_max), brute.is_some());
            hits += usize::from(brute.is_some());
        }
        assert!(hits > 500, "{hits}");
    }

    /// A scene with one emitting sphere (radiance 1, radius 1, centre 3
    /// above the origin) and a floor triangle: the irradiance at the origin
    /// is `π (r/d)²` exactly. Light sampling (`sample_light` and the density
    /// the integrator turns its area density into) and cosine-weighted
    /// directions that hit the sphere (weighed by `light_pdf_hit`'s MIS
    /// density) must both give it, and their MIS combination too.
    #[test]
    fn an_emitting_sphere_lights_a_point_as_the_formula_says() {
        use crate::materials::surface::SurfaceMaterial;
        use crate::scene::{Facing, LightSample, Scene, SceneParts};
        let mut light = SurfaceMaterial::diffuse(Vec3A::ZERO);
        light.emission = Vec3A::ONE;
        let floor = crate::geometry::triangle::Triangle::new(
            Vec3A::new(-10.0, 0.0, -10.0),
            Vec3A::new(10.0, 0.0, -10.0),
            Vec3A::new(0.0, 0.0, 10.0),
        );
        let parts = SceneParts {
            triangles: vec![floor],
            normals: vec![Vec3A::Y],
            material_of: vec![0],
            materials: vec![SurfaceMaterial::diffuse(Vec3A::splat(0.5)), light],
            spheres: vec![SceneSphere {
                sphere: Sphere {
                    center: Vec3A::new(0.0, 3.0, 0.0),
                    radius: 1.0,
                    frame: Mat3A::IDENTITY,
                },
                flip: false,
                material: 1,
            }],
            ..SceneParts::default()
        };
        let scene = Scene::from_parts(parts).unwrap();
        assert!(scene.has_spheres() && scene.emitter_count() == 1);
        let p = Vec3A::new(0.0, 1e-4, 0.0);
        let facing = Facing::Side(Vec3A::Y);
        let want = std::f64::consts::PI / 9.0;
        let mut rng = Rng::new(3, 3);
        let n = 100_000;
        let (mut by_light, mut by_bsdf, mut mis) = (0.0f64, 0.0f64, 0.0f64);
        for _ in 0..n {
            let u = |rng: &mut Rng| glam::Vec2::new(rng.next_f32(), rng.next_f32());
            let (us, ul, ub) = (u(&mut rng), u(&mut rng), u(&mut rng));
            // Light sampling, as the path integrator reads an area sample.
            if let Some(LightSample::Area {
                position,
                normal,
                radiance,
                pdf_area,
                ..
            }) = scene.sample_light(p, facing, us, ul)
            {
                let d = position - p;
                let r2 = d.length_squared();
                let w = d / r2.sqrt();
                let cos_l = -normal.dot(w);
                if cos_l > 0.0 && w.y > 0.0 {
                    let pdf = pdf_area * r2 / cos_l;
                    // Unblocked: nothing lies between.
                    let hit = scene.intersect(&Ray::new(p, w), f32::INFINITY).unwrap();
                    assert!((hit.t - r2.sqrt()).abs() < 1e-3, "{} {}", hit.t, r2.sqrt());
                    let bsdf_pdf = w.y / std::f32::consts::PI;
                    let f = f64::from(radiance.x * w.y / pdf);
                    by_light += f;
                    mis += f * f64::from(pdf * pdf / (pdf * pdf + bsdf_pdf * bsdf_pdf));
                }
            }
            // Cosine-weighted directions (pdf cos/π): L·π where they hit.
            let (r, phi) = (ub.x.sqrt(), 2.0 * std::f32::consts::PI * ub.y);
            let w = Vec3A::new(r * phi.cos(), (1.0 - ub.x).max(0.0).sqrt(), r * phi.sin());
            if let Some(hit) = scene.intersect(&Ray::new(p, w), f32::INFINITY)
                && hit.prim == 1
            {
                let s = scene.surface(&hit);
                let cos_out = -s.ng.dot(w);
                assert!(cos_out > 0.0);
                let bsdf_pdf = w.y / std::f32::consts::PI;
                let light_pdf = scene.light_pdf_hit(&hit, p, facing, cos_out);
                by_bsdf += std::f64::consts::PI;
                mis += std::f64::consts::PI
                    * f64::from(
                        bsdf_pdf * bsdf_pdf / (bsdf_pdf * bsdf_pdf + light_pdf * light_pdf),
                    );
            }
        }
        for (name, got) in [("light", by_light), ("bsdf", by_bsdf), ("mis", mis)] {
            let got = got / n as f64;
            assert!((got - want).abs() < 0.01 * want, "{name}: {got} vs {want}");
        }
    }
}
