//! A vertex of a camera or light subpath and what it sends along a
//! direction: the camera, a point on a light, or a surface with its BSDF;
//! the densities (per unit area) with which each strategy's walk reaches it.

use glam::Vec3A;

use super::super::path::Shading;
use crate::camera::Camera;
use crate::geometry::ray::SurfacePoint;
use crate::materials::{Frame, Material};
use crate::scene::{Emitter, InfiniteEmitter, Scene};

/// Most vertices of one subpath (a cap on paths Russian roulette keeps).
pub const MAX_VERTICES: usize = 64;

/// What a vertex is.
#[derive(Clone, Copy, Debug)]
pub(super) enum Kind {
    /// The camera's point: a pinhole's centre of projection or a point of
    /// its thin lens.
    Camera,
    /// A point light (a delta in position).
    PointLight(Emitter),
    /// A point on emitting primitive `prim`, at coordinates `uv`
    /// ([`Scene::emission_at`]).
    AreaLight {
        /// The emitting primitive.
        prim: u32,
        /// Its coordinates there.
        uv: glam::Vec2,
    },
    /// A surface the walk met, its BSDF ready to scatter ([`Scatter`]).
    Surface,
    /// A light at infinity (the environment or a directional light), the
    /// end of a light subpath or of a camera subpath that escaped. Its
    /// densities follow pbrt's convention: its own (`pdf_fwd` of a light
    /// subpath, `pdf_rev` of a camera one) are per solid angle, of its
    /// direction; the next vertex's is per unit area of the disk light
    /// leaves by ([`Scene::infinite_disk`]), projected onto that vertex.
    Infinite {
        /// Which light.
        emitter: Emitter,
        /// The unit direction its light travels in (into the scene).
        dir: Vec3A,
    },
}

/// A surface vertex's BSDF in its shading frame.
#[derive(Clone, Copy, Debug)]
pub(super) struct Scatter {
    /// The BSDF at the hit.
    pub bsdf: Material,
    /// Its shading frame.
    pub frame: Frame,
    /// How directions of light meet the shading normal.
    pub shading: Shading,
    /// The unit direction (world) towards the vertex the walk came from.
    pub wo: Vec3A,
}

/// One vertex of a subpath.
#[derive(Clone, Copy, Debug)]
pub(super) struct Vertex {
    pub kind: Kind,
    /// The point, its error bound and geometric normal (zero for the camera
    /// and point lights), for rays leaving it.
    pub point: SurfacePoint,
    /// The subpath's throughput up to this vertex (the walk's estimate of
    /// what arrives here, over its density).
    pub beta: Vec3A,
    /// The density (per unit area, or 1 at an endpoint sampled in
    /// position) with which this subpath's walk reached the vertex.
    pub pdf_fwd: f32,
    /// The density with which the other subpath's walk would reach it.
    pub pdf_rev: f32,
    /// Whether the walk left it through a delta lobe (it cannot be
    /// connected to).
    pub delta: bool,
    /// A camera subpath's surface: the radiance it emits towards the vertex
    /// before (`Le`, or an unlit surface's colour).
    pub emitted: Vec3A,
    /// Whether the surface is unlit (its colour counts in full and the
    /// camera subpath ends there).
    pub unlit: bool,
    /// A surface's BSDF.
    pub scatter: Option<Scatter>,
    /// A surface's primitive (`u32::MAX` for the camera and lights).
    pub prim: u32,
}

impl Vertex {
    /// A vertex at `point` of kind `kind` with throughput `beta` and
    /// forward density `pdf_fwd`.
    pub fn new(kind: Kind, point: SurfacePoint, beta: Vec3A, pdf_fwd: f32) -> Self {
        Self {
            kind,
            point,
            beta,
            pdf_fwd,
            pdf_rev: 0.0,
            delta: false,
            emitted: Vec3A::ZERO,
            unlit: false,
            scatter: None,
            prim: u32::MAX,
        }
    }

    /// Whether the vertex has an area (a surface or a point on an area
    /// light), so that densities at it carry the cosine to its normal.
    #[inline]
    pub fn has_area(&self) -> bool {
        matches!(self.kind, Kind::Surface | Kind::AreaLight { .. })
    }

    /// Whether it is a light no camera subpath can find: a delta in
    /// position (a point light) or in direction (a directional light).
    #[inline]
    pub fn is_delta_light(&self) -> bool {
        match self.kind {
            Kind::PointLight(_) => true,
            Kind::Infinite { emitter, .. } => emitter != Emitter::Environment,
            _ => false,
        }
    }

    /// Whether it is a light at infinity.
    #[inline]
    pub fn is_infinite(&self) -> bool {
        matches!(self.kind, Kind::Infinite { .. })
    }

    /// Whether another subpath's vertex can be joined to it by a segment
    /// (a light at infinity is joined by a direction instead, by next-event
    /// estimation only).
    #[inline]
    pub fn connectible(&self) -> bool {
        !self.delta && !self.unlit && !self.is_infinite()
    }
}

/// The unit direction from vertex `from` to vertex `to`, the direction of
/// a light at infinity at either end; `None` for coincident points.
#[inline]
pub(super) fn direction(from: &Vertex, to: &Vertex) -> Option<Vec3A> {
    if let Kind::Infinite { dir, .. } = to.kind {
        return Some(-dir);
    }
    if let Kind::Infinite { dir, .. } = from.kind {
        return Some(dir);
    }
    let d = to.point.p - from.point.p;
    let d2 = d.length_squared();
    d2.gt(&0.0).then(|| d / d2.sqrt())
}

/// Converts a density at `from` of the direction to `to` into a density
/// per unit area at `to`: a solid-angle density over the squared distance
/// and times the cosine at `to`. Towards a light at infinity it stays per
/// solid angle; from one, `pdf` is per unit area of the disk light leaves
/// by, and only the cosine at `to` applies.
#[inline]
pub(super) fn to_area(pdf: f32, from: &Vertex, to: &Vertex) -> f32 {
    if to.is_infinite() {
        return pdf;
    }
    let cos = |w: Vec3A| {
        if to.has_area() {
            to.point.n.dot(w).abs()
        } else {
            1.0
        }
    };
    if let Kind::Infinite { dir, .. } = from.kind {
        return pdf * cos(dir);
    }
    let d = to.point.p - from.point.p;
    let d2 = d.length_squared();
    if !d2.gt(&0.0) {
        return 0.0;
    }
    pdf / d2 * cos(d / d2.sqrt())
}

/// The density per unit area of the disk from infinity with which a light
/// subpath leaves a light at infinity ([`Scene::infinite_disk`]).
#[inline]
pub(super) fn infinite_disk_pdf(scene: &Scene) -> f32 {
    let (_, r) = scene.infinite_disk();
    1.0 / (std::f32::consts::PI * r * r)
}

/// The solid-angle density with which an area light at `light` (normal
/// `n`, emitting from both sides or not) sends light along the unit `w`:
/// cosine-weighted over the emitting side (half of it on each side of a
/// two-sided emitter).
#[inline]
pub(super) fn emission_dir_pdf(n: Vec3A, two_sided: bool, w: Vec3A) -> f32 {
    let c = n.dot(w);
    if two_sided {
        0.5 * c.abs() * std::f32::consts::FRAC_1_PI
    } else if c > 0.0 {
        c * std::f32::consts::FRAC_1_PI
    } else {
        0.0
    }
}

/// The density (per unit area at `next`) with which a walk at `v`, having
/// come from `prev` (none at an endpoint), continues to `next`.
pub(super) fn pdf_to(
    scene: &Scene,
    camera: &Camera,
    v: &Vertex,
    prev: Option<&Vertex>,
    next: &Vertex,
) -> f32 {
    let Some(w) = direction(v, next) else {
        return 0.0;
    };
    let pdf_dir = match v.kind {
        Kind::Camera => camera.direction_density(w),
        Kind::PointLight(e) => scene.punctual_pdf(e, w),
        Kind::AreaLight { prim, .. } => {
            emission_dir_pdf(v.point.n, scene.material(prim).emits_both_sides, w)
        }
        Kind::Infinite { .. } => infinite_disk_pdf(scene),
        Kind::Surface => {
            let (Some(s), Some(prev)) = (&v.scatter, prev) else {
                return 0.0;
            };
            let Some(wo) = direction(v, prev) else {
                return 0.0;
            };
            s.bsdf.pdf(s.frame.to_local(wo), s.frame.to_local(w))
        }
    };
    to_area(pdf_dir, v, next)
}

/// What a light endpoint sends along the unit `w`: an area light's radiance
/// times the cosine at its surface, a point light's intensity, the
/// environment's radiance from `-w`, a directional light's irradiance.
pub(super) fn light_sends(scene: &Scene, v: &Vertex, w: Vec3A) -> Vec3A {
    match v.kind {
        Kind::Infinite { emitter, .. } => match scene.infinite_emitter(emitter) {
            Some(InfiniteEmitter::Directional { irradiance, .. }) => irradiance,
            Some(InfiniteEmitter::Environment) => scene.environment_radiance(-w),
            None => Vec3A::ZERO,
        },
        Kind::PointLight(e) => scene.punctual_intensity(e, w),
        Kind::AreaLight { prim, uv } => {
            let c = v.point.n.dot(w);
            let material = scene.material(prim);
            if !(c > 0.0 || (material.emits_both_sides && c < 0.0)) {
                return Vec3A::ZERO;
            }
            scene.emission_at(prim, uv.x, uv.y) * scene.coat_dimming(prim, uv.x, uv.y, w) * c.abs()
        }
        _ => Vec3A::ZERO,
    }
}

/// What a surface vertex of the *camera* subpath sends back towards the
/// vertex before it of light arriving along `-w` from `w`'s side: the BSDF
/// value with the cosine at the surface (raylab's [`Material::eval`]).
#[inline]
pub(super) fn camera_scatter(s: &Scatter, w: Vec3A) -> Vec3A {
    let side = s.shading.weight(w);
    if !side.gt(&0.0) {
        return Vec3A::ZERO;
    }
    s.bsdf.eval(s.frame.to_local(s.wo), s.frame.to_local(w)) * side
}

/// What a surface vertex of the *light* subpath sends along `w` of the
/// light that arrived from `s.wo`'s side: the BSDF seen from `w` (radiance
/// flows towards `w`, so `w` is the BSDF's outgoing direction: the
/// transport is the adjoint's), with Veach's correction for shading normals
/// (`|wo·ns| |w·ng| / (|wo·ng| |w·ns|)`, which with raylab's cosine inside
/// `eval` leaves `|w·ng| / |wo·ng|`).
#[inline]
pub(super) fn light_scatter(s: &Scatter, ng: Vec3A, w: Vec3A) -> Vec3A {
    let side = s.shading.weight(w);
    let cos_in = s.wo.dot(ng).abs();
    if !(side > 0.0 && cos_in > 0.0) {
        return Vec3A::ZERO;
    }
    let f = s.bsdf.eval(s.frame.to_local(w), s.frame.to_local(s.wo));
    f * (side * w.dot(ng).abs() / cos_in)
}
