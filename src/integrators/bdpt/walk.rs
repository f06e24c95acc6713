//! The two subpaths' random walks: from the camera (its ray given) and
//! from a light chosen by power, each vertex with the densities that
//! multiple importance sampling compares.

use glam::{Vec2, Vec3A};

use super::super::path::{PathSampler, RR_DEPTH, RR_SCALE, emission, vertex_frame};
use super::vertex::{
    Kind, Scatter, Vertex, emission_dir_pdf, infinite_disk_pdf, light_scatter, to_area,
};
use crate::camera::Camera;
use crate::geometry::ray::{Ray, SurfacePoint};
use crate::materials::Material;
use crate::scene::{Emitter, InfiniteEmitter, Scene};

/// Which way a walk carries its quantity.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Mode {
    /// From the camera: radiance is gathered back along it.
    Camera,
    /// From a light: light flows along it (the adjoint BSDF).
    Light,
}

/// The camera subpath for the camera ray `ray`: the camera vertex and up to
/// `max - 1` more.
pub(super) fn camera_subpath(
    scene: &Scene,
    camera: &Camera,
    ray: &Ray,
    max: usize,
    sampler: &mut impl PathSampler,
    path: &mut Vec<Vertex>,
    rays: &mut u64,
) {
    path.clear();
    let origin = SurfacePoint::bare(ray.origin);
    path.push(Vertex::new(Kind::Camera, origin, Vec3A::ONE, 1.0));
    if max < 2 {
        return;
    }
    let pdf_dir = camera.direction_density(ray.dir);
    walk(
        scene,
        *ray,
        Vec3A::ONE,
        pdf_dir,
        Mode::Camera,
        max,
        sampler,
        path,
        rays,
    );
}

/// The light subpath: a light chosen by power, a point on it and a
/// direction, and up to `max - 1` vertices after it. Empty when nothing
/// emits.
pub(super) fn light_subpath(
    scene: &Scene,
    max: usize,
    sampler: &mut impl PathSampler,
    path: &mut Vec<Vertex>,
    rays: &mut u64,
) {
    path.clear();
    if max == 0 {
        return;
    }
    let u_choice = sampler.next_2d_minor();
    let u_pos = sampler.next_2d();
    let u_dir = sampler.next_2d();
    let Some(vertex) = light_start(scene, u_choice, u_pos) else {
        return;
    };
    path.push(vertex);
    if max < 2 {
        return;
    }
    // A direction from it, and what it sends along it over the densities.
    // The first ray, its density (of its direction, or for a light at
    // infinity of its origin on the disk) and what the light sends along it.
    let (ray, pdf, sent) = match vertex.kind {
        Kind::PointLight(e) => {
            let Some(em) = scene.punctual_emission(e, u_dir) else {
                return;
            };
            let ray = Ray::new(vertex.point.offset_origin(em.dir), em.dir);
            (ray, em.pdf, em.intensity)
        }
        Kind::AreaLight { prim, .. } => {
            let two_sided = scene.material(prim).emits_both_sides;
            let n = vertex.point.n;
            let (u, flip) = if two_sided {
                if u_dir.x < 0.5 {
                    (Vec2::new(u_dir.x * 2.0, u_dir.y), false)
                } else {
                    (Vec2::new(u_dir.x * 2.0 - 1.0, u_dir.y), true)
                }
            } else {
                (u_dir, false)
            };
            let local = cosine_hemisphere(u);
            let frame = crate::materials::Frame::from_normal(if flip { -n } else { n });
            let dir = frame.to_world(local).normalize();
            let pdf = emission_dir_pdf(n, two_sided, dir);
            let ray = Ray::new(vertex.point.offset_origin(dir), dir);
            (ray, pdf, super::vertex::light_sends(scene, &vertex, dir))
        }
        Kind::Infinite { dir, .. } => {
            // A point on the disk facing the light, one scene radius out,
            // with its density per unit area (which the walk's first step
            // projects onto the surface it meets).
            let (centre, r) = scene.infinite_disk();
            let frame = crate::materials::Frame::from_normal(dir);
            let d = crate::materials::concentric_disk(u_dir) * r;
            let origin = centre - dir * r + frame.t * d.x + frame.b * d.y;
            path[0].point.p = origin;
            let sent = super::vertex::light_sends(scene, &vertex, dir);
            (Ray::new(origin, dir), infinite_disk_pdf(scene), sent)
        }
        _ => return,
    };
    if !pdf.gt(&0.0) || sent == Vec3A::ZERO {
        return;
    }
    let beta = vertex.beta * sent / pdf;
    walk(scene, ray, beta, pdf, Mode::Light, max, sampler, path, rays);
}

/// A light subpath's first vertex: a light chosen with `u_choice` by power
/// and a point on it with `u_pos`, its throughput `1/(pmf · pdf_pos)` (the
/// light's emission enters at the next step) and its density
/// `pmf · pdf_pos` (`pdf_pos` 1 for a point light). A light at infinity gets
/// its direction from `u_pos` instead (the environment's importance
/// sampling, a directional light's own), with the density of that direction
/// in the place of `pdf_pos` (1 for a directional light, whose vertex's
/// density is then 0: no other walk finds it); its point is left for the
/// caller to place.
pub(super) fn light_start(scene: &Scene, u_choice: Vec2, u_pos: Vec2) -> Option<Vertex> {
    let (emitter, pmf) = scene.pick_emitter(u_choice)?;
    if !pmf.gt(&0.0) {
        return None;
    }
    if let Some(infinite) = scene.infinite_emitter(emitter) {
        let (dir, pdf_dir, pdf_fwd) = match infinite {
            InfiniteEmitter::Directional { direction, .. } => (direction, 1.0, 0.0),
            InfiniteEmitter::Environment => {
                let (to_light, _, pdf) = scene.environment().sample(u_pos)?;
                (-to_light, pdf, pmf * pdf)
            }
        };
        if !pdf_dir.gt(&0.0) {
            return None;
        }
        let point = SurfacePoint::bare(Vec3A::ZERO);
        let kind = Kind::Infinite { emitter, dir };
        let beta = Vec3A::splat(1.0 / (pmf * pdf_dir));
        return Some(Vertex::new(kind, point, beta, pdf_fwd));
    }
    match emitter {
        Emitter::Key | Emitter::Punctual(_) => {
            let em = scene.punctual_emission(emitter, Vec2::ZERO)?;
            let point = SurfacePoint::bare(em.position);
            let v = Vertex::new(
                Kind::PointLight(emitter),
                point,
                Vec3A::splat(1.0 / pmf),
                pmf,
            );
            Some(v)
        }
        Emitter::Shape(prim) => {
            let at = scene.emitter_point(prim, u_pos)?;
            if !at.area.gt(&0.0) {
                return None;
            }
            let pdf = pmf / at.area;
            let kind = Kind::AreaLight { prim, uv: at.uv };
            Some(Vertex::new(kind, at.point, Vec3A::splat(1.0 / pdf), pdf))
        }
        Emitter::Environment => None,
    }
}

/// A direction about `+z` with density `cos θ / π`.
#[inline]
fn cosine_hemisphere(u: Vec2) -> Vec3A {
    let r = u.x.sqrt();
    let phi = 2.0 * std::f32::consts::PI * u.y;
    Vec3A::new(r * phi.cos(), r * phi.sin(), (1.0 - u.x).max(0.0).sqrt())
}

/// Follows `ray` from the subpath's last vertex (whose walk chose the
/// ray's direction with solid-angle density `pdf_dir`; `beta` is the
/// throughput after that choice), adding a vertex at each surface met until
/// the subpath has `max` vertices, the ray escapes, a BSDF absorbs it or
/// Russian roulette ends it.
#[allow(clippy::too_many_arguments)]
fn walk(
    scene: &Scene,
    mut ray: Ray,
    mut beta: Vec3A,
    mut pdf_dir: f32,
    mode: Mode,
    max: usize,
    sampler: &mut impl PathSampler,
    path: &mut Vec<Vertex>,
    rays: &mut u64,
) {
    let textures = scene.textures();
    loop {
        *rays += 1;
        let Some(hit) = scene.intersect(&ray, f32::INFINITY) else {
            // A camera subpath that escapes ends at the environment.
            if mode == Mode::Camera && !scene.environment().is_black() {
                let prev = path.last().expect("a walk starts at a vertex");
                let point = SurfacePoint::bare(ray.origin + ray.dir);
                let kind = Kind::Infinite {
                    emitter: Emitter::Environment,
                    dir: -ray.dir,
                };
                let mut v = Vertex::new(kind, point, beta, 0.0);
                v.pdf_fwd = to_area(pdf_dir, prev, &v);
                v.emitted = scene.environment_radiance(ray.dir);
                path.push(v);
            }
            return;
        };
        let surface = scene.surface(&hit);
        let material = &scene.materials()[surface.material as usize];
        let prev = *path.last().expect("a walk starts at a vertex");
        let mut v = Vertex::new(Kind::Surface, surface.point, beta, 0.0);
        v.pdf_fwd = to_area(pdf_dir, &prev, &v);
        v.prim = hit.prim;
        if mode == Mode::Camera {
            let cos_out = -surface.ng.dot(ray.dir);
            if let Some(le) = emission(scene, &surface, material, ray.dir, cos_out) {
                v.emitted = le;
            }
            if material.is_unlit() {
                v.emitted = material.unlit_color(&surface.attrs, textures);
                v.unlit = true;
                path.push(v);
                return;
            }
        } else if material.is_unlit() {
            // Unlit surfaces scatter nothing.
            return;
        }
        let mut bsdf = material.bsdf(&surface.attrs, textures);
        let wo = -ray.dir;
        let (shading, frame, wo_local, _) = vertex_frame(scene, &surface, &mut bsdf, wo);
        let scatter = Scatter {
            bsdf,
            frame,
            shading,
            wo,
        };
        v.scatter = Some(scatter);
        path.push(v);
        if path.len() >= max {
            return;
        }
        let u_choice = sampler.next_2d_minor();
        let u_bsdf = sampler.next_2d();
        let Some(bs) = bsdf.sample(wo_local, u_choice.y, u_bsdf) else {
            return;
        };
        let wi = frame.to_world(bs.wi);
        let ng = surface.point.n;
        let weight = match mode {
            Mode::Camera => {
                let side = shading.weight(wi);
                if !side.gt(&0.0) {
                    return;
                }
                bs.weight * side
            }
            Mode::Light if bs.specular => {
                let side = shading.weight(wi);
                let (cos_wo_g, cos_wi_s) = (wo.dot(ng).abs(), bs.wi.z.abs());
                if !(side > 0.0 && cos_wo_g > 0.0 && cos_wi_s > 0.0) {
                    return;
                }
                let correction = wo_local.z.abs() * wi.dot(ng).abs() / (cos_wo_g * cos_wi_s);
                bs.weight * (side * correction * adjoint_delta_scale(&bsdf, wo_local, bs.wi))
            }
            Mode::Light => {
                if !bs.pdf.gt(&0.0) {
                    return;
                }
                light_scatter(&scatter, ng, wi) / bs.pdf
            }
        };
        // The densities of this step, forward, and backward (of reaching
        // the vertex before from here), zero through a delta lobe.
        let (pdf_fwd, pdf_rev) = if bs.specular {
            (0.0, 0.0)
        } else {
            (bs.pdf, bsdf.pdf(bs.wi, wo_local))
        };
        let n = path.len();
        let here = path[n - 1];
        path[n - 1].delta = bs.specular;
        path[n - 2].pdf_rev = to_area(pdf_rev, &here, &path[n - 2]);
        beta *= weight;
        if beta == Vec3A::ZERO || !beta.is_finite() {
            return;
        }
        // Russian roulette, as the path tracer's, counted in vertices past
        // the endpoint.
        if n > RR_DEPTH as usize {
            let survive = (beta.max_element() * RR_SCALE).min(0.95);
            if sampler.next_1d() >= survive || survive.is_nan() {
                return;
            }
            beta /= survive;
        }
        pdf_dir = pdf_fwd;
        ray = Ray::new(surface.point.offset_origin(wi), wi);
    }
}

/// What a light subpath's weight through a delta lobe is multiplied by so
/// that it is the adjoint's: Mitsuba's smooth dielectric scales what it
/// transmits by `η_ti²` for radiance ([`crate::materials::mitsuba`]), which
/// light flowing the other way does not see. 1 for every other material.
#[inline]
fn adjoint_delta_scale(bsdf: &Material, wo: Vec3A, wi: Vec3A) -> f32 {
    match bsdf {
        Material::MiDielectric(d) if wo.z * wi.z < 0.0 => {
            let eta_ti = if wo.z > 0.0 { 1.0 / d.eta } else { d.eta };
            1.0 / (eta_ti * eta_ti)
        }
        _ => 1.0,
    }
}
