//! Joining the subpaths: every strategy `(s, t)` (the first `s` vertices of
//! the light subpath, the first `t` of the camera's), its contribution and
//! its multiple importance sampling weight by the power heuristic over all
//! the strategies that could have made the same path.

use glam::{Vec2, Vec3A};

use super::super::path::{PathOptions, PathSampler};
use super::merge::LightPaths;
use super::vertex::{
    Kind, MAX_VERTICES, Vertex, camera_scatter, direction, emission_dir_pdf, light_scatter,
    light_sends, pdf_to, to_area,
};
use super::walk::{camera_subpath, light_start, light_subpath};
use crate::camera::Camera;
use crate::geometry::ray::{Ray, SurfacePoint};
use crate::scene::{Emitter, Scene};

/// A render thread's vertex buffers, reused from sample to sample.
#[derive(Clone, Debug, Default)]
pub struct Scratch {
    camera: Vec<Vertex>,
    light: Vec<Vertex>,
}

/// One sample of bidirectional path tracing for the camera ray `ray`: the
/// radiance of the pixel's own strategies (`t ≥ 2`), returned, and the
/// light subpath's connections to the camera (`t = 1`), handed to `splat`
/// with the image point they land on; a splat's value is already divided
/// by the image's pixel count's share (see [`Camera::direction_density`]),
/// so that the image is the sum of both over the samples per pixel.
///
/// With `merging` (vertex connection and merging), the light subpath is
/// not traced here but given (this pixel's of the iteration's
/// [`LightPaths`]), and each camera vertex also merges with every light
/// vertex near it.
#[allow(clippy::too_many_arguments)]
pub fn sample(
    scene: &Scene,
    camera: &Camera,
    ray: &Ray,
    options: &PathOptions,
    sampler: &mut impl PathSampler,
    scratch: &mut Scratch,
    merging: Option<(&LightPaths, usize)>,
    rays: &mut u64,
    splat: &mut impl FnMut(Vec2, Vec3A),
) -> Vec3A {
    // Segments of a path of s + t vertices: s + t - 1 ≤ max_depth.
    let max_depth = options.max_depth.min(2 * MAX_VERTICES as u32) as usize;
    let Scratch {
        camera: cam,
        light: traced,
    } = scratch;
    camera_subpath(
        scene,
        camera,
        ray,
        (max_depth + 1).min(MAX_VERTICES),
        sampler,
        cam,
        rays,
    );
    let light: &[Vertex] = match merging {
        Some((paths, pixel)) => paths.path(pixel),
        None => {
            light_subpath(scene, max_depth.min(MAX_VERTICES), sampler, traced, rays);
            traced
        }
    };
    let join = Join {
        scene,
        camera,
        light,
        cam,
        eta: merging.map_or(0.0, |(paths, _)| paths.eta()),
    };
    let mut l = Vec3A::ZERO;
    for t in 1..=cam.len() {
        for s in 0..=light.len() {
            if s + t < 2 || s + t - 1 > max_depth {
                continue;
            }
            if t == 1 {
                // (A pinhole draws no lens point.)
                let u_lens = if camera.thin_lens.is_some() {
                    sampler.next_2d()
                } else {
                    Vec2::ZERO
                };
                if let Some((at, v)) = join.seen(s, u_lens, rays)
                    && v.is_finite()
                {
                    splat(at, v);
                }
                continue;
            }
            l += match s {
                0 => join.emitted(t),
                1 => join.light_sampled(t, sampler, rays),
                _ => join.connect(s, t, rays),
            };
        }
    }
    if let Some((paths, _)) = merging {
        for t in 2..=cam.len() {
            l += join.merged(paths, t, max_depth);
        }
    }
    l
}

/// The two subpaths of a sample in the scene and camera they were traced
/// in, ready to be joined.
#[derive(Clone, Copy)]
struct Join<'a> {
    scene: &'a Scene,
    camera: &'a Camera,
    light: &'a [Vertex],
    cam: &'a [Vertex],
    /// Vertex merging's `eta` ([`LightPaths::eta`]); 0 without merging.
    eta: f64,
}

impl Join<'_> {
    /// Strategy `(0, t)`: the camera subpath's last vertex is on a light
    /// (or an unlit surface, whose colour counts in full).
    fn emitted(&self, t: usize) -> Vec3A {
        let z = &self.cam[t - 1];
        if z.emitted == Vec3A::ZERO {
            return Vec3A::ZERO;
        }
        if z.unlit {
            return z.beta * z.emitted;
        }
        z.beta * z.emitted * self.weight(0, t)
    }

    /// Strategy `(1, t)`: a point on a light chosen afresh for the camera
    /// subpath's vertex `t - 1` (next-event estimation, with the light
    /// subpath's own choice of light and point).
    fn light_sampled(&self, t: usize, sampler: &mut impl PathSampler, rays: &mut u64) -> Vec3A {
        let u_choice = sampler.next_2d_minor();
        let u_pos = sampler.next_2d();
        if !self.cam[t - 1].connectible() {
            return Vec3A::ZERO;
        }
        let Some(y) = light_start(self.scene, u_choice, u_pos) else {
            return Vec3A::ZERO;
        };
        let light = [y];
        Join {
            light: &light,
            ..*self
        }
        .connect(1, t, rays)
    }

    /// What the camera subpath's vertex `t - 1` takes from merging with
    /// the light vertices near it (paths of at most `max_depth` segments):
    /// each one's light arriving (its throughput, flux per light path),
    /// scattered by the camera vertex's BSDF towards the vertex before it
    /// (with the ratio of the shading to the geometric cosine, the flux
    /// being per unit of the geometric surface), over `eta`, weighted.
    fn merged(&self, paths: &LightPaths, t: usize, max_depth: usize) -> Vec3A {
        let z = &self.cam[t - 1];
        let Some(zs) = &z.scatter else {
            return Vec3A::ZERO;
        };
        if !z.connectible() || !matches!(z.kind, Kind::Surface) {
            return Vec3A::ZERO;
        }
        let mut sum = Vec3A::ZERO;
        paths.near(z.point.p, |light| {
            let s = light.len();
            let y = &light[s - 1];
            let Some(ys) = &y.scatter else {
                return;
            };
            if s + t - 2 > max_depth {
                return;
            }
            // Light arrived from `wi`'s side of the light vertex's surface;
            // it must be the same side of the camera vertex's.
            let wi = ys.wo;
            let (cos_z, cos_y) = (wi.dot(z.point.n), wi.dot(y.point.n));
            if !(cos_z * cos_y).gt(&0.0) {
                return;
            }
            let f = camera_scatter(zs, wi) / cos_z.abs();
            let c = z.beta * f * y.beta;
            if c == Vec3A::ZERO || !c.is_finite() {
                return;
            }
            let join = Join { light, ..*self };
            sum += c * join.merge_weight(s, t);
        });
        sum / self.eta as f32
    }

    /// The value of strategy `(s, t)` with `s ≥ 1`, `t ≥ 2`: the subpaths'
    /// last vertices joined by a shadow ray, weighted.
    fn connect(&self, s: usize, t: usize, rays: &mut u64) -> Vec3A {
        let (y, z) = (&self.light[s - 1], &self.cam[t - 1]);
        // A light at infinity is joined only by next-event estimation
        // (`light_sampled`), along its direction.
        let at_infinity = s == 1 && y.is_infinite();
        if !(y.connectible() || at_infinity) || !z.connectible() {
            return Vec3A::ZERO;
        }
        let Some(w) = direction(z, y) else {
            return Vec3A::ZERO;
        };
        let Some(zs) = &z.scatter else {
            return Vec3A::ZERO;
        };
        let fz = camera_scatter(zs, w);
        if fz == Vec3A::ZERO {
            return Vec3A::ZERO;
        }
        let fy = sends(self.scene, y, -w);
        let (shadow, t_max, falloff) = if at_infinity {
            let ray = Ray::new(z.point.offset_origin(w), w);
            (ray, f32::INFINITY, 1.0)
        } else {
            let (ray, t_max) = z.point.ray_to(y.point.p);
            (ray, t_max, 1.0 / (y.point.p - z.point.p).length_squared())
        };
        let c = y.beta * fy * fz * z.beta * falloff;
        if c == Vec3A::ZERO {
            return Vec3A::ZERO;
        }
        *rays += 1;
        if self.scene.occluded(&shadow, t_max) {
            return Vec3A::ZERO;
        }
        c * self.weight(s, t)
    }

    /// Strategy `(s, 1)`: the light subpath's vertex `s - 1` seen by the
    /// camera through the point of its lens `u_lens` picks (a thin lens's
    /// point is uniform over its area: its importance over that density
    /// leaves the pinhole's value), and the image point it lands on.
    fn seen(&self, s: usize, u_lens: Vec2, rays: &mut u64) -> Option<(Vec2, Vec3A)> {
        let (scene, camera) = (self.scene, self.camera);
        let y = &self.light[s - 1];
        // A light seen by the camera is found by both subpaths (a point
        // light by neither; one at infinity by the camera's alone).
        if !y.connectible() || s == 1 && y.is_delta_light() {
            return None;
        }
        let (origin, at, dir) = camera.seen_at(y.point.p, u_lens)?;
        let d2 = (y.point.p - origin).length_squared();
        let fy = sends(scene, y, -dir);
        let c = y.beta * fy * (camera.direction_density(dir) / d2);
        if c == Vec3A::ZERO || !c.is_finite() {
            return None;
        }
        let (shadow, t_max) = if y.has_area() {
            y.point.ray_to(origin)
        } else {
            let d = y.point.p - origin;
            let dist = d.length();
            (Ray::new(origin, d / dist), dist * (1.0 - 1e-4))
        };
        *rays += 1;
        if scene.occluded(&shadow, t_max) {
            return None;
        }
        // The camera vertex at that lens point.
        let lens = [Vertex::new(
            Kind::Camera,
            SurfacePoint::bare(origin),
            Vec3A::ONE,
            1.0,
        )];
        let join = Join {
            cam: &lens,
            ..*self
        };
        Some((at, c * join.weight(s, 1)))
    }

    /// The power heuristic weight of strategy `(s, t)` among all strategies
    /// that make the same path (Veach's thesis §10.2; pbrt-v4's `MISWeight`
    /// computes the same ratios; with vertex merging, Georgiev et al.
    /// 2012's merges at every vertex too): the densities of the
    /// connection's vertices as the other walk would reach them are worked
    /// out here, the rest were recorded by the walks.
    fn weight(&self, s: usize, t: usize) -> f32 {
        let (scene, camera, light, cam) = (self.scene, self.camera, self.light, self.cam);
        // The four densities a connection changes.
        let z = &cam[t - 1];
        let z_prev = (t >= 2).then(|| &cam[t - 2]);
        let y = (s >= 1).then(|| &light[s - 1]);
        let y_prev = (s >= 2).then(|| &light[s - 2]);
        // A light at infinity seen straight from the camera: the camera's
        // is the only strategy (light tracing cannot end at it).
        if s + t == 2 && z.is_infinite() {
            return 1.0;
        }
        let z_rev = match y {
            Some(y) => pdf_to(scene, camera, y, y_prev, z),
            // (0, t): the density of starting a light subpath at z.
            None => match z.kind {
                Kind::Infinite { dir, .. } => scene.infinite_origin_pdf(-dir),
                _ => emitter_at(scene, z).map_or(0.0, |prim| scene.emitter_origin_pdf(prim)),
            },
        };
        let z_prev_rev = z_prev.map_or(0.0, |zp| match y {
            Some(y) => pdf_to(scene, camera, z, Some(y), zp),
            // The light's own choice of where its light goes from z
            // towards zp.
            None if z.is_infinite() => pdf_to(scene, camera, z, None, zp),
            None => emitter_at(scene, z).map_or(0.0, |prim| {
                let w = (zp.point.p - z.point.p).normalize_or_zero();
                let two_sided = scene.material(prim).emits_both_sides;
                to_area(emission_dir_pdf(z.point.n, two_sided, w), z, zp)
            }),
        });
        let y_rev = y.map_or(0.0, |y| pdf_to(scene, camera, z, z_prev, y));
        let y_prev_rev = match (y, y_prev) {
            (Some(y), Some(yp)) => pdf_to(scene, camera, y, Some(z), yp),
            _ => 0.0,
        };
        let mut d = Densities::default();
        d.push_light(&light[..s], y_rev, y_prev_rev);
        for i in (0..t).rev() {
            let v = &cam[i];
            let pl = if i + 1 == t {
                z_rev
            } else if i + 2 == t {
                z_prev_rev
            } else {
                v.pdf_rev
            };
            d.push(pl, v.pdf_fwd, i + 1 < t && v.delta);
        }
        let end = if s >= 1 { &light[0] } else { z };
        d.light_delta = s >= 1 && end.is_delta_light();
        d.light_infinite = end.is_infinite();
        d.weight(Used::Connect(s), self.eta)
    }

    /// The power heuristic weight of merging the light subpath's vertex
    /// `s - 1` (a surface) with the camera subpath's vertex `t - 1` near it
    /// (Georgiev et al. 2012): the path of the light subpath's `s` vertices
    /// and the camera subpath's first `t - 1`, its shared vertex sampled by
    /// both walks. The densities at the shared vertex are each walk's own;
    /// those of the next vertex on either side as the other walk would
    /// reach it are worked out from that walk's BSDF there.
    fn merge_weight(&self, s: usize, t: usize) -> f32 {
        let (scene, camera, light, cam) = (self.scene, self.camera, self.light, self.cam);
        let (y, z) = (&light[s - 1], &cam[t - 1]);
        let (y_prev, z_prev) = (&light[s - 2], &cam[t - 2]);
        // The camera walk going on from the shared vertex to the light's
        // vertex before it, and the light walk to the camera's.
        let y_prev_rev = pdf_to(scene, camera, z, Some(z_prev), y_prev);
        let z_prev_rev = pdf_to(scene, camera, y, Some(y_prev), z_prev);
        let mut d = Densities::default();
        d.push_light(&light[..s], z.pdf_fwd, y_prev_rev);
        for i in (0..t - 1).rev() {
            let v = &cam[i];
            let pl = if i + 2 == t { z_prev_rev } else { v.pdf_rev };
            d.push(pl, v.pdf_fwd, v.delta);
        }
        d.light_delta = light[0].is_delta_light();
        d.light_infinite = light[0].is_infinite();
        d.weight(Used::Merge(s - 1), self.eta)
    }
}

/// The most vertices a path joined from two subpaths has.
const MAX_PATH: usize = 2 * MAX_VERTICES;

/// Which strategy made a path.
#[derive(Clone, Copy, Debug)]
enum Used {
    /// The connection of the light subpath's first `s` vertices to the rest
    /// of the path, traced from the camera.
    Connect(usize),
    /// The merge at vertex `j`, which both walks reached.
    Merge(usize),
}

/// One path `x_0` (on the light) … `x_k` (the camera) as the two walks
/// would make it: each vertex's density under the light walk (`pl`) and
/// the camera walk (`pe`), and whether its BSDF scattered through a delta
/// lobe there (no strategy can join or merge at it).
struct Densities {
    pl: [f32; MAX_PATH],
    pe: [f32; MAX_PATH],
    delta: [bool; MAX_PATH],
    n: usize,
    /// The light is a delta in position or direction: no camera walk finds
    /// it.
    light_delta: bool,
    /// The light is at infinity: light tracing cannot see it.
    light_infinite: bool,
}

impl Default for Densities {
    fn default() -> Self {
        Self {
            pl: [0.0; MAX_PATH],
            pe: [0.0; MAX_PATH],
            delta: [false; MAX_PATH],
            n: 0,
            light_delta: false,
            light_infinite: false,
        }
    }
}

impl Densities {
    /// Appends the next vertex towards the camera.
    #[inline]
    fn push(&mut self, pl: f32, pe: f32, delta: bool) {
        self.pl[self.n] = pl;
        self.pe[self.n] = pe;
        self.delta[self.n] = delta;
        self.n += 1;
    }

    /// Appends a light subpath's vertices, from the light: each with its
    /// walk's density and the camera walk's recorded for it, except the
    /// last two's camera densities, `last` and `prev`, which the path's
    /// join decides; the last is not a delta (the join uses its BSDF).
    fn push_light(&mut self, light: &[Vertex], last: f32, prev: f32) {
        let s = light.len();
        for (j, v) in light.iter().enumerate() {
            let pe = if j + 1 == s {
                last
            } else if j + 2 == s {
                prev
            } else {
                v.pdf_rev
            };
            self.push(v.pdf_fwd, pe, j + 1 < s && v.delta);
        }
    }

    /// The power heuristic weight of strategy `used` among every strategy
    /// that can make the path: the connections `s = 0 … k` (the first `s`
    /// vertices from the light walk, the rest from the camera's) and, when
    /// `eta > 0`, the merges at the inner vertices, each merge's density
    /// that of the connection whose light part ends at the merged vertex
    /// times the camera walk's density there and `eta` (the light paths
    /// per image times the merge disk's area). Densities are compared as
    /// ratios, a delta's (recorded as 0) counting as 1 (pbrt's rule): a
    /// delta vertex's density appears in every strategy that can make the
    /// path, once.
    fn weight(&self, used: Used, eta: f64) -> f32 {
        let n = self.n;
        let remap = |p: f32| f64::from(if p == 0.0 { 1.0 } else { p });
        // q[s]: connection s's density over that of the reference.
        let reference = match used {
            Used::Connect(s) => s,
            Used::Merge(j) => j + 1,
        };
        let mut q = [0.0f64; MAX_PATH];
        q[reference] = 1.0;
        for s in reference + 1..n {
            q[s] = q[s - 1] * remap(self.pl[s - 1]) / remap(self.pe[s - 1]);
        }
        for s in (0..reference).rev() {
            q[s] = q[s + 1] * remap(self.pe[s]) / remap(self.pl[s]);
        }
        let k = n - 1;
        let connects = |s: usize| match s {
            0 => !self.light_delta,
            1 if k == 1 => !self.light_delta && !self.light_infinite,
            _ => !self.delta[s - 1] && !self.delta[s],
        };
        let merge = |j: usize| q[j + 1] * remap(self.pe[j]) * eta;
        let mut sum = 0.0;
        for s in (0..n).filter(|&s| connects(s)) {
            sum += q[s] * q[s];
        }
        if eta > 0.0 {
            for j in (1..k).filter(|&j| !self.delta[j]) {
                let m = merge(j);
                sum += m * m;
            }
        }
        let mine = match used {
            Used::Connect(s) => q[s],
            Used::Merge(j) => merge(j),
        };
        let w = mine * mine / sum;
        if w.is_finite() { w as f32 } else { 0.0 }
    }
}

/// What the light subpath's vertex `y` sends along `w`: a light's emission
/// (times the cosine at an area light), a surface's adjoint scattering.
#[inline]
fn sends(scene: &Scene, y: &Vertex, w: Vec3A) -> Vec3A {
    match (&y.kind, &y.scatter) {
        (Kind::Surface, Some(s)) => light_scatter(s, y.point.n, w),
        (Kind::PointLight(_) | Kind::AreaLight { .. } | Kind::Infinite { .. }, _) => {
            light_sends(scene, y, w)
        }
        _ => Vec3A::ZERO,
    }
}

/// The emitting primitive a camera subpath's surface vertex lies on.
fn emitter_at(scene: &Scene, z: &Vertex) -> Option<u32> {
    let prim = match z.kind {
        Kind::AreaLight { prim, .. } => prim,
        _ => z.prim,
    };
    (prim != u32::MAX && scene.emitter_pmf(Emitter::Shape(prim)) > 0.0).then_some(prim)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::integrators::bdpt::vertex::Scatter;
    use crate::load::cornell::{self, MaterialChoice};
    use crate::sampling::sampler::Rng;

    /// The light subpath that makes the same path as camera subpath `cam`
    /// (whose last vertex is on a light) joined at `t`: its vertices from
    /// the light back to `cam[t]`, with the densities a light walk records.
    fn light_side(scene: &Scene, camera: &Camera, cam: &[Vertex], t: usize) -> Vec<Vertex> {
        let k = cam.len() - 1;
        let mut light: Vec<Vertex> = Vec::new();
        for j in 0..=k - t {
            let z = &cam[k - j];
            let mut y = *z;
            if j == 0 {
                y = if let Kind::Infinite { dir, .. } = z.kind {
                    Vertex::new(z.kind, z.point, Vec3A::ONE, scene.infinite_origin_pdf(-dir))
                } else {
                    let kind = Kind::AreaLight {
                        prim: z.prim,
                        uv: glam::Vec2::ZERO,
                    };
                    Vertex::new(kind, z.point, Vec3A::ONE, scene.emitter_origin_pdf(z.prim))
                };
            } else {
                let prev = &light[j - 1];
                let wo = direction(&y, prev).expect("distinct vertices");
                y.scatter = y.scatter.map(|s| Scatter { wo, ..s });
                let before = (j >= 2).then(|| &light[j - 2]);
                y.pdf_fwd = pdf_to(scene, camera, prev, before, &y);
            }
            // The camera walk's density of the vertex, as the light walk's
            // `pdf_rev`.
            y.pdf_rev = z.pdf_fwd;
            light.push(y);
        }
        light
    }

    /// Veach's condition for an unbiased combination: for every path, the
    /// weights of the strategies that can make it sum to one. Paths of the
    /// area-lit box with a glossy gold block, a mirror block (delta
    /// vertices) and diffuse walls, under a sky seen through the box's open
    /// front, traced from the camera until they reach the light or the sky;
    /// each split into every pair of subpaths the strategies would have
    /// made.
    #[test]
    fn mis_weights_of_a_path_sum_to_one() {
        let mut scene = cornell::area_scene();
        let tall = cornell::part("tall").expect("a part");
        let short = cornell::part("short").expect("a part");
        MaterialChoice::parse("gold:0.3")
            .unwrap()
            .apply(&mut scene, tall);
        MaterialChoice::parse("mirror")
            .unwrap()
            .apply(&mut scene, short);
        scene.set_environment(crate::lights::environment::Environment::constant(
            Vec3A::splat(0.5),
        ));
        let camera = Camera::lab(cornell::CAMERA_POSITION, 0.0, 0.0, 32, 32);
        let mut rng = Rng::new(11, 2);
        let mut cam = Vec::new();
        let (mut paths, mut with_delta, mut to_sky, mut merges) = (0, 0, 0, 0);
        let mut rays = 0;
        for i in 0..60000 {
            let (x, y) = (
                (i % 32) as f32 + rng.next_f32(),
                (i / 32 % 32) as f32 + rng.next_f32(),
            );
            let ray = camera.ray(x, y);
            super::camera_subpath(&scene, &camera, &ray, 8, &mut rng, &mut cam, &mut rays);
            let k = cam.len() - 1;
            if k < 2 || cam[k].emitted == Vec3A::ZERO || cam[k].unlit {
                continue;
            }
            // Rays leave a surface from its point pushed out by its error
            // bound; across a segment shorter than 1 % of the scene's
            // radius (into a corner) the direction a density is rebuilt
            // from differs from the one sampled enough to move the sum
            // (by up to 4 % measured, on 5 % of such paths).
            let shortest = cam[..=k]
                .windows(2)
                .filter(|w| !w[1].is_infinite())
                .map(|w| (w[1].point.p - w[0].point.p).length())
                .fold(f32::INFINITY, f32::min);
            if shortest < 0.01 * scene.radius() {
                continue;
            }
            paths += 1;
            with_delta += usize::from(cam.iter().any(|v| v.delta));
            to_sky += usize::from(cam[k].is_infinite());
            // Without merging, and with merges as likely as a connection
            // and far likelier.
            for eta in [0.0, 0.3, 40.0] {
                let mut sum = 0.0f64;
                for t in 1..=k + 1 {
                    let s = k + 1 - t;
                    let light = if s > 0 {
                        light_side(&scene, &camera, &cam, t)
                    } else {
                        Vec::new()
                    };
                    let join = Join {
                        scene: &scene,
                        camera: &camera,
                        light: &light,
                        cam: &cam[..t],
                        eta,
                    };
                    // A strategy that would join at a delta vertex cannot
                    // make the path.
                    let joins_delta = (s > 0 && light[s - 1].delta) || (t > 1 && cam[t - 1].delta);
                    if !joins_delta {
                        sum += f64::from(join.weight(s, t));
                    }
                    // Merging at the camera's vertex t - 1 (both walks
                    // reach it: the light's as its vertex s).
                    if eta > 0.0 && t >= 2 && t <= k && !cam[t - 1].delta {
                        let light = light_side(&scene, &camera, &cam, t - 1);
                        let join = Join {
                            light: &light,
                            ..join
                        };
                        sum += f64::from(join.merge_weight(s + 1, t));
                        merges += 1;
                    }
                }
                // (The densities rebuilt from positions differ from the
                // walk's in the last digits: sums off by up to 7.5e-5
                // without merges, 1.3e-4 with merges far likelier,
                // measured; a strategy left out or counted twice moves a
                // sum by its weight.)
                let tolerance = if eta > 1.0 { 2.5e-4 } else { 1e-4 };
                assert!(
                    (sum - 1.0).abs() < tolerance,
                    "path of {k} segments, eta {eta}: weights sum to {sum}"
                );
            }
        }
        assert!(
            paths > 500 && with_delta > 50 && to_sky > 100 && merges > 1000,
            "{paths} paths, {with_delta} with a mirror, {to_sky} to the sky, {merges} merges"
        );
    }
}
