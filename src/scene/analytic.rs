//! The scene's analytic shapes: Mitsuba's spheres, disks and cylinders as
//! exact surfaces, and the cells of its signed distance grids (`sdfgrid`:
//! one primitive per cell the surface may cross, each an exact ray test of
//! its trilinear interpolant) ([`AnalyticShape`], a closed set), each with its material
//! and side ([`SceneShape`]), held as [`AnalyticShapes`]: a small binary
//! hierarchy of their bounds beside the triangles' eight-wide one, queried
//! after it with the distance it found (so a scene of triangles alone does
//! no extra work). Shape `k` is primitive `triangles + k` of the scene (so
//! hits, materials and light tables name it as they name triangles); its
//! hit's two barycentric slots hold its Mitsuba texture coordinates `(u, v)`
//! (a grid cell's: the hit point's coordinates in the cell, see
//! [`SdfVoxel`]; its texture coordinates are `(0, 0)`, as Mitsuba's). The
//! grids' samples are held once, beside the shapes, for the cells' smooth
//! normals ([`AnalyticShapes::grid`]).

use glam::{Vec2, Vec3A};

use crate::geometry::cylinder::{self, Cylinder};
use crate::geometry::disk::{self, Disk};
use crate::geometry::ray::{Ray, SurfacePoint};
use crate::geometry::sdf_voxel::SdfVoxel;
use crate::geometry::sdfgrid::SdfGrid;
use crate::geometry::sphere::Sphere;

/// An analytic surface.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum AnalyticShape {
    /// A sphere (a similarity of the unit sphere).
    Sphere(Sphere),
    /// The unit disk under an affine map (an ellipse).
    Disk(Disk),
    /// The open unit cylinder under an affine map.
    Cylinder(Cylinder),
    /// A cell of a signed distance grid (Mitsuba's `sdfgrid`).
    SdfVoxel(SdfVoxel),
}

impl AnalyticShape {
    /// The ray parameter of the first crossing in `(0, t_max]`.
    #[inline]
    pub fn intersect(&self, ray: &Ray, t_max: f32) -> Option<f32> {
        match self {
            Self::Sphere(s) => s.intersect(ray, t_max),
            Self::Disk(d) => d.intersect(ray, t_max),
            Self::Cylinder(c) => c.intersect(ray, t_max),
            Self::SdfVoxel(v) => v.intersect(ray, t_max),
        }
    }

    /// Texture coordinates `(u, v)` of the point at `t` along `ray` (a
    /// grid cell's: the point's coordinates in the cell).
    #[inline]
    pub fn uv_at(&self, ray: &Ray, t: f32) -> Vec2 {
        match self {
            Self::Sphere(s) => s.uv_of(ray.at(t)),
            Self::Disk(d) => disk::uv_of_local(d.placement.local_at(ray, t)),
            Self::Cylinder(c) => cylinder::uv_of_local(c.placement.local_at(ray, t)),
            Self::SdfVoxel(v) => v.hit_code(ray, t),
        }
    }

    /// The point at `uv` with its error bound and its unit normal (outwards
    /// for a sphere or cylinder, the placed `+z` for a disk, the gradient
    /// of a grid cell's interpolant).
    #[inline]
    pub fn point_at(&self, uv: Vec2) -> SurfacePoint {
        match self {
            Self::Sphere(s) => s.point_at(uv),
            Self::Disk(d) => d.point_at(uv),
            Self::Cylinder(c) => c.point_at(uv),
            Self::SdfVoxel(v) => v.point_at(uv),
        }
    }

    /// `∂p/∂u` and `∂p/∂v` at `uv` (Mitsuba's parameterisations; zero on a
    /// grid cell, which has none).
    #[inline]
    pub fn derivatives(&self, uv: Vec2) -> (Vec3A, Vec3A) {
        match self {
            Self::Sphere(s) => s.derivatives(uv),
            Self::Disk(d) => d.derivatives(uv),
            Self::Cylinder(c) => c.derivatives(uv),
            Self::SdfVoxel(_) => (Vec3A::ZERO, Vec3A::ZERO),
        }
    }

    /// Surface area (zero for a grid cell, as Mitsuba's `sdfgrid` says:
    /// it cannot emit).
    #[inline]
    pub fn area(&self) -> f32 {
        match self {
            Self::Sphere(s) => s.area(),
            Self::Disk(d) => d.area(),
            Self::Cylinder(c) => c.area(),
            Self::SdfVoxel(_) => 0.0,
        }
    }

    /// Axis-aligned bounds.
    pub fn bounds(&self) -> (Vec3A, Vec3A) {
        match self {
            Self::Sphere(s) => s.bounds(),
            Self::Disk(d) => d.bounds(),
            Self::Cylinder(c) => c.bounds(),
            Self::SdfVoxel(v) => v.bounds(),
        }
    }

    /// The centre of the bounds (where the hierarchy sorts the shape).
    #[inline]
    fn centre(&self) -> Vec3A {
        let (lo, hi) = self.bounds();
        0.5 * (lo + hi)
    }

    /// Whether every number that places the shape is finite (and a sphere's
    /// radius positive, and a grid cell's values finite and its cell in its
    /// grid).
    pub fn is_finite(&self) -> bool {
        match self {
            Self::Sphere(s) => s.center.is_finite() && s.radius.is_finite() && s.radius > 0.0,
            Self::Disk(d) => d.area().is_finite() && d.area() > 0.0,
            Self::Cylinder(c) => c.area().is_finite() && c.area() > 0.0,
            Self::SdfVoxel(v) => v.is_finite(),
        }
    }
}

/// An analytic shape of the scene with its side and material.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SceneShape {
    /// The surface.
    pub shape: AnalyticShape,
    /// Whether its front (the side it emits from and a one-sided material
    /// shows) is the other side of its normal (Mitsuba's `flip_normals`):
    /// the inside of a sphere or cylinder, a disk's `−z`.
    pub flip: bool,
    /// Index of its material.
    pub material: u32,
}

impl SceneShape {
    /// The point at `uv` with its error bound and its front normal.
    #[inline]
    pub fn front_point(&self, uv: Vec2) -> SurfacePoint {
        let mut point = self.shape.point_at(uv);
        if self.flip {
            point.n = -point.n;
        }
        point
    }
}

/// A node of the shapes' hierarchy: a box and either two children (`count
/// == 0`: `first` and `first + 1`) or `count` shapes from `first` in order.
#[derive(Clone, Copy, Debug)]
struct Node {
    lo: Vec3A,
    hi: Vec3A,
    first: u32,
    count: u32,
}

/// Shapes per leaf at most.
const LEAF: usize = 4;
/// Depth of the traversal stack (the build halves by count, so 2⁶⁴ shapes
/// would fit).
const STACK: usize = 64;

/// The scene's analytic shapes, reordered for their hierarchy.
#[derive(Clone, Debug, Default)]
pub struct AnalyticShapes {
    /// The shapes in hierarchy order, with their index in the input.
    items: Vec<(SceneShape, u32)>,
    /// Where each input shape sits in `items`.
    position: Vec<u32>,
    nodes: Vec<Node>,
    /// The signed distance grids the cells ([`AnalyticShape::SdfVoxel`])
    /// belong to.
    grids: Vec<SdfGrid>,
}

impl AnalyticShapes {
    /// The hierarchy over `shapes` (split at the median of the longest axis
    /// of their bounds' centres' box), with the grids their cells name.
    pub fn build(shapes: &[SceneShape], grids: Vec<SdfGrid>) -> Self {
        let mut items: Vec<(SceneShape, u32)> = shapes
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
            grids,
        }
    }

    /// Signed distance grid `k` (the grid of cells whose `grid` is `k`).
    #[inline]
    pub fn grid(&self, k: u32) -> Option<&SdfGrid> {
        self.grids.get(k as usize)
    }

    /// The signed distance grids.
    pub fn grids(&self) -> &[SdfGrid] {
        &self.grids
    }

    /// Whether the scene has no analytic shape.
    #[inline]
    pub fn is_empty(&self) -> bool {
        self.items.is_empty()
    }

    /// How many shapes.
    #[inline]
    pub fn len(&self) -> usize {
        self.items.len()
    }

    /// Shape `k` in input order.
    #[inline]
    pub fn get(&self, k: u32) -> &SceneShape {
        &self.items[self.position[k as usize] as usize].0
    }

    /// The input shapes in input order.
    pub fn in_order(&self) -> Vec<SceneShape> {
        let mut v = self.items.clone();
        v.sort_by_key(|&(_, i)| i);
        v.into_iter().map(|(s, _)| s).collect()
    }

    /// The closest crossing of a shape along `ray` in `(0, t_max]`: its `t`
    /// and the shape's input index.
    #[inline]
    pub fn intersect(&self, ray: &Ray, t_max: f32) -> Option<(f32, u32)> {
        let mut best: Option<(f32, u32)> = None;
        let mut t_max = t_max;
        self.walk(ray, &mut t_max, &mut |s, k, t_max| {
            if let Some(t) = s.shape.intersect(ray, *t_max) {
                *t_max = t;
                best = Some((t, k));
            }
            false
        });
        best
    }

    /// Whether a shape crosses `ray` in `(0, t_max]`.
    #[inline]
    pub fn occluded(&self, ray: &Ray, t_max: f32) -> bool {
        let mut t_max = t_max;
        self.walk(ray, &mut t_max, &mut |s, _, t_max| {
            s.shape.intersect(ray, *t_max).is_some()
        })
    }

    /// Visits the shapes whose boxes `ray` meets within `t_max` (which the
    /// visitor may shorten) until the visitor returns `true`; returns whether
    /// it did.
    fn walk(
        &self,
        ray: &Ray,
        t_max: &mut f32,
        visit: &mut impl FnMut(&SceneShape, u32, &mut f32) -> bool,
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
/// ulps so rounding never loses a shape).
#[inline]
fn slab(origin: Vec3A, inv: Vec3A, lo: Vec3A, hi: Vec3A, t_max: f32) -> bool {
    let a = (lo - origin) * inv;
    let b = (hi - origin) * inv;
    // NaN (0 · ∞ on a box face) compares false in min/max's favour.
    let near = a.min(b).max_element().max(0.0);
    let far = a.max(b).min_element().min(t_max) * (1.0 + 4.0 * f32::EPSILON);
    near <= far
}

/// Fills node `index` over `items[start..end]`, recursively.
fn build(
    nodes: &mut Vec<Node>,
    items: &mut [(SceneShape, u32)],
    index: usize,
    start: usize,
    end: usize,
) {
    let (mut lo, mut hi) = (Vec3A::splat(f32::INFINITY), Vec3A::splat(f32::NEG_INFINITY));
    let (mut clo, mut chi) = (lo, hi);
    for (s, _) in &items[start..end] {
        let (a, b) = s.shape.bounds();
        lo = lo.min(a);
        hi = hi.max(b);
        let c = s.shape.centre();
        clo = clo.min(c);
        chi = chi.max(c);
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
        a.0.shape.centre()[axis].total_cmp(&b.0.shape.centre()[axis])
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
    use crate::geometry::placement::Placement;
    use crate::sampling::sampler::Rng;
    use glam::Mat3A;

    fn disk(linear: Mat3A, origin: Vec3A) -> AnalyticShape {
        AnalyticShape::Disk(Disk::new(Placement::new(linear, origin).unwrap()))
    }

    fn cylinder(linear: Mat3A, origin: Vec3A) -> AnalyticShape {
        AnalyticShape::Cylinder(Cylinder::new(Placement::new(linear, origin).unwrap()))
    }

    /// The hierarchy answers as a loop over every shape does, on a cloud of
    /// spheres, disks and cylinders and random rays.
    #[test]
    fn the_hierarchy_finds_what_brute_force_finds() {
        let mut rng = Rng::new(11, 5);
        let mut r = || rng.next_f32();
        let shapes: Vec<SceneShape> = (0..300)
            .map(|i| {
                let centre = Vec3A::new(r() * 20.0 - 10.0, r() * 20.0 - 10.0, r() * 20.0 - 10.0);
                let size = 0.05 + r() * 0.8;
                let linear = Mat3A::from_rotation_y(r() * 6.0)
                    * Mat3A::from_rotation_x(r() * 6.0)
                    * Mat3A::from_diagonal(glam::Vec3::new(size, size * (0.3 + r()), 2.0 * size));
                let shape = match i % 3 {
                    0 => AnalyticShape::Sphere(Sphere {
                        center: centre,
                        radius: size,
                        frame: Mat3A::IDENTITY,
                    }),
                    1 => disk(linear, centre),
                    _ => cylinder(linear, centre),
                };
                SceneShape {
                    shape,
                    flip: false,
                    material: i,
                }
            })
            .collect();
        let set = AnalyticShapes::build(&shapes, Vec::new());
        assert_eq!(set.in_order(), shapes);
        let mut hits = [0; 3];
        for _ in 0..5000 {
            let o = Vec3A::new(r() * 30.0 - 15.0, r() * 30.0 - 15.0, r() * 30.0 - 15.0);
            let d = Vec3A::new(r() - 0.5, r() - 0.5, r() - 0.5).normalize();
            let ray = Ray::new(o, d);
            let t_max = if r() < 0.5 { f32::INFINITY } else { r() * 20.0 };
            let brute = shapes
                .iter()
                .enumerate()
                .filter_map(|(k, s)| s.shape.intersect(&ray, t_max).map(|t| (t, k as u32)))
                .min_by(|a, b| a.0.total_cmp(&b.0));
            assert_eq!(set.intersect(&ray, t_max), brute);
            assert_eq!(set.occluded(&ray, t_max), brute.is_some());
            if let Some((_, k)) = brute {
                hits[k as usize % 3] += 1;
            }
        }
        assert!(hits.iter().all(|&h| h > 50), "{hits:?}");
    }

    /// The shapes of the lighting test: object z (a disk's normal) to −y,
    /// centre 3 above the origin.
    fn facing_down() -> Mat3A {
        Mat3A::from_cols(Vec3A::X, Vec3A::Z, -Vec3A::Y)
    }

    /// A floor triangle at y = 0 and `shape` emitting radiance 1: the
    /// irradiance at the origin by light sampling (`sample_light` and the
    /// density the integrator turns its area density into), by
    /// cosine-weighted directions that hit the shape, and by their MIS
    /// combination (weighed by `light_pdf_hit`'s density).
    fn irradiance(shape: SceneShape) -> [f64; 3] {
        use crate::geometry::ray::Hit;
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
            shapes: vec![SceneShape {
                material: 1,
                ..shape
            }],
            ..SceneParts::default()
        };
        let scene = Scene::from_parts(parts).unwrap();
        assert!(
            scene.has_analytic_shapes()
                && scene.emitting_shape_count() == 1
                && scene.emitter_count() == 0
        );
        let p = Vec3A::new(0.0, 1e-4, 0.0);
        let facing = Facing::Side(Vec3A::Y);
        let mut rng = Rng::new(3, 3);
        let n = 200_000;
        let mut sums = [0.0f64; 3];
        let u = |rng: &mut Rng| Vec2::new(rng.next_f32(), rng.next_f32());
        for _ in 0..n {
            let (us, ul, ub) = (u(&mut rng), u(&mut rng), u(&mut rng));
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
                    // Unblocked: nothing lies between (the point is the
                    // first crossing along its direction; at a grazing
                    // silhouette the ray may miss by rounding).
                    if cos_l > 1e-3 {
                        let hit: Hit = scene
                            .intersect(&Ray::new(p, w), f32::INFINITY)
                            .unwrap_or_else(|| panic!("{position} {normal} {w}"));
                        assert!((hit.t - r2.sqrt()).abs() < 1e-3, "{} {}", hit.t, r2.sqrt());
                    }
                    let bsdf_pdf = w.y / std::f32::consts::PI;
                    let f = f64::from(radiance.x * w.y / pdf);
                    sums[0] += f;
                    sums[2] += f * f64::from(pdf * pdf / (pdf * pdf + bsdf_pdf * bsdf_pdf));
                }
            }
            // Cosine-weighted directions (pdf cos/π): L·π where they hit
            // the shape's front.
            let (r, phi) = (ub.x.sqrt(), std::f32::consts::TAU * ub.y);
            let w = Vec3A::new(r * phi.cos(), (1.0 - ub.x).max(0.0).sqrt(), r * phi.sin());
            if let Some(hit) = scene.intersect(&Ray::new(p, w), f32::INFINITY)
                && hit.prim == 1
            {
                let s = scene.surface(&hit);
                let cos_out = -s.ng.dot(w);
                if cos_out <= 0.0 {
                    continue;
                }
                let bsdf_pdf = w.y / std::f32::consts::PI;
                let light_pdf = scene.light_pdf_hit(&hit, p, facing, cos_out);
                sums[1] += std::f64::consts::PI;
                sums[2] += std::f64::consts::PI
                    * f64::from(
                        bsdf_pdf * bsdf_pdf / (bsdf_pdf * bsdf_pdf + light_pdf * light_pdf),
                    );
            }
        }
        sums.map(|s| s / n as f64)
    }

    fn assert_all_near(got: [f64; 3], want: f64, what: &str) {
        for (name, got) in ["light", "bsdf", "mis"].iter().zip(got) {
            assert!(
                (got - want).abs() < 0.015 * want,
                "{what} by {name}: {got} vs {want}"
            );
        }
    }

    /// An emitting sphere (radius 1, centre 3 above the point) gives the
    /// irradiance `π (r/d)²` exactly, by every estimate.
    #[test]
    fn an_emitting_sphere_lights_a_point_as_the_formula_says() {
        let sphere = AnalyticShape::Sphere(Sphere {
            center: Vec3A::new(0.0, 3.0, 0.0),
            radius: 1.0,
            frame: Mat3A::IDENTITY,
        });
        let got = irradiance(SceneShape {
            shape: sphere,
            flip: false,
            material: 0,
        });
        assert_all_near(got, std::f64::consts::PI / 9.0, "sphere");
    }

    /// An emitting disk of radius 1 facing the point from 3 above gives
    /// `π R²/(R² + h²)`, facing down or flipped to face down; an elliptical
    /// one (scaled unevenly, then sheared) and a cylinder above the point
    /// give the same by light sampling as by the directions that hit them.
    #[test]
    fn emitting_disks_and_cylinders_light_a_point_consistently() {
        let above = Vec3A::new(0.0, 3.0, 0.0);
        let want = std::f64::consts::PI / 10.0;
        let down = SceneShape {
            shape: disk(facing_down(), above),
            flip: false,
            material: 0,
        };
        assert_all_near(irradiance(down), want, "disk");
        let up = Mat3A::from_cols(Vec3A::X, -Vec3A::Z, Vec3A::Y);
        let flipped = SceneShape {
            shape: disk(up, above),
            flip: true,
            material: 0,
        };
        assert_all_near(irradiance(flipped), want, "flipped disk");
        // Unlit from behind: the same disk not flipped.
        let behind = irradiance(SceneShape {
            flip: false,
            ..flipped
        });
        assert!(behind.iter().all(|&e| e == 0.0), "{behind:?}");
        let shear = Mat3A::from_cols(Vec3A::X, Vec3A::Y, Vec3A::new(0.6, 0.0, 1.0));
        let ellipse = SceneShape {
            shape: disk(
                shear * facing_down() * Mat3A::from_diagonal(glam::Vec3::new(2.0, 0.5, 1.0)),
                above,
            ),
            flip: false,
            material: 0,
        };
        let e = irradiance(ellipse);
        assert_all_near(e, e[0], "ellipse");
        // A horizontal tube across above the point, radius 0.5, from
        // x = −1 to 1 (z along +x).
        let tube = Mat3A::from_cols(Vec3A::Y * 0.5, Vec3A::Z * 0.5, Vec3A::X * 2.0);
        let c = irradiance(SceneShape {
            shape: cylinder(tube, Vec3A::new(-1.0, 2.0, 0.0)),
            flip: false,
            material: 0,
        });
        assert!(c[0] > 0.05, "{c:?}");
        assert_all_near(c, c[0], "cylinder");
    }

    /// Shadow rays: a disk and a cylinder block what lies behind them, and
    /// nothing beside them.
    #[test]
    fn disks_and_cylinders_occlude() {
        use crate::materials::surface::SurfaceMaterial;
        use crate::scene::{Scene, SceneParts};
        let shape = |shape| SceneShape {
            shape,
            flip: false,
            material: 0,
        };
        let parts = SceneParts {
            materials: vec![SurfaceMaterial::diffuse(Vec3A::splat(0.5))],
            shapes: vec![
                shape(disk(facing_down(), Vec3A::new(0.0, 3.0, 0.0))),
                shape(cylinder(Mat3A::IDENTITY, Vec3A::new(10.0, 0.0, 0.0))),
            ],
            ..SceneParts::default()
        };
        let scene = Scene::from_parts(parts).unwrap();
        let up = Ray::new(Vec3A::ZERO, Vec3A::Y);
        assert!(scene.occluded(&up, 5.0));
        assert!(!scene.occluded(&up, 2.9));
        assert!(!scene.occluded(&Ray::new(Vec3A::new(1.1, 0.0, 0.0), Vec3A::Y), 5.0));
        // From inside the tube out sideways, and out through its open end.
        let inside = Vec3A::new(10.0, 0.0, 0.5);
        assert!(scene.occluded(&Ray::new(inside, Vec3A::Y), 5.0));
        assert!(!scene.occluded(&Ray::new(inside, Vec3A::Z), 5.0));
        let hit = scene.intersect(&Ray::new(inside, Vec3A::Y), 5.0).unwrap();
        assert_eq!(hit.prim, 1);
        assert!((hit.t - 1.0).abs() < 1e-6);
    }
}
