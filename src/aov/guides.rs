//! The denoiser's guides, `albedo` and `normal`, of one camera ray: taken at
//! the first surface that is not specular, following mirrors, glass and
//! smooth metals there as Open Image Denoise's documentation asks (and as
//! Cycles' denoising passes do), so that what a mirror reflects or glass lets
//! through is denoised as sharply as what the camera sees directly.
//!
//! From the camera ray's hit, each surface is split by
//! [`Material::guide_lobes`] into a rough part and specular lobes (delta, or
//! GGX no wider than [`GUIDE_ALPHA`](crate::materials::GUIDE_ALPHA)):
//!
//! * where the rough part carries more than a quarter of the surface's albedo
//!   (Cycles' rule), or after [`MAX_CHAIN`] specular surfaces, the chain ends:
//!   the guide albedo gains the surface's whole albedo times the tint of the
//!   chain so far, and the guide normal the surface's shading normal (facing
//!   the ray);
//! * otherwise the rough part's albedo is added and the chain goes on along
//!   the specular lobes' directions (mirror reflection, refraction),
//!   multiplied by their values (Fresnel terms, tints). At the camera ray's
//!   surface both the reflection and the transmission are followed (glass
//!   shows both, each by its Fresnel weight, as OIDN's documentation
//!   recommends); further on only the stronger of the two, carrying the
//!   tint of both, so a chain costs one ray per surface.
//!
//! Light seen along the chain joins the albedo too, squashed into `[0, 1)` by
//! `L/(1 + L)`: emitters (a lamp's panel, the helmet's glowing markings) and
//! the environment (the sky behind a model, or seen in a mirror) are features
//! of the image that no surface albedo shows, and a denoiser blurs what its
//! guides do not show. A chain that escapes adds no normal.
//!
//! Media along the chain (fog around the camera, a cloud behind a `null`
//! boundary, a medium inside a model) show in expectation
//! ([`crate::media::expected`]): the albedo where a path first scatters in
//! them and the light they emit join the albedo, and what lies behind is
//! seen times their transmittance (Cycles gives its denoiser a volume's
//! albedo where a path first scatters, from one sample).
//!
//! The guides use no random numbers: a camera ray always gets the same
//! guides, so a pixel's guides, the mean over its first [`GUIDE_SAMPLES`]
//! samples, are antialiased over those sample positions and are otherwise
//! free of noise (OIDN's `cleanAux`).

use glam::Vec3A;

use super::set::luminance;
use crate::geometry::ray::Ray;
use crate::integrators::path::{coat_normal, shading};
use crate::materials::{Frame, Material};
use crate::media::expected;
use crate::scene::{Scene, SurfaceHit};

/// The samples of a pixel (its first ones, by index) that the `albedo` and
/// `normal` guides are the mean of. A camera ray's guides have no noise, only
/// its position in the pixel varies, and the first eight of a pixel's
/// Owen-scrambled Sobol' points already cover it evenly: more would refine
/// the antialiasing of edges that the denoiser does not see, at the full
/// price of the guides' chains through mirrors and glass (on the helmet under
/// the HDRI, guides for every sample of 16 made `--denoise`'s path tracing
/// about 30 % slower; see docs/denoising.md).
pub const GUIDE_SAMPLES: u32 = 8;

/// Whether sample `sample` (its index in the pixel) adds to the guides.
#[inline]
pub(crate) fn adds_guides(sample: u32) -> bool {
    sample < GUIDE_SAMPLES
}

/// Most specular surfaces a chain follows before it takes the last one's
/// albedo as it is (a ray caught between two mirrors, or inside glass).
pub const MAX_CHAIN: u32 = 8;

/// The share of a surface's albedo (by luminance) that must be rough for the
/// chain to end there.
const ROUGH_SHARE: f32 = 0.25;

/// The albedo and normal guides of one camera ray.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Guides {
    /// Albedo in `[0, 1]` per channel.
    pub albedo: Vec3A,
    /// World-space normal, at most of unit length (shorter where the chain
    /// split, or escaped).
    pub normal: Vec3A,
}

/// The guides of camera ray `ray`, whose first hit `s` has the BSDF `bsdf`.
pub fn guides(scene: &Scene, ray: &Ray, s: &SurfaceHit, bsdf: &Material) -> Guides {
    let mut g = Guides::default();
    let medium = scene.media().camera;
    let t = (s.point.p - ray.origin).length();
    let tr = through(scene, medium, ray, t, Vec3A::ONE, &mut g);
    visit(scene, ray.dir, s, bsdf, medium, tr, mean(tr), 0, &mut g);
    g.albedo = g.albedo.clamp(Vec3A::ZERO, Vec3A::ONE);
    if !g.albedo.is_finite() || !g.normal.is_finite() {
        return Guides::default();
    }
    g
}

/// The albedo guide of a camera ray that hits nothing: the camera's medium
/// (if any) in front of the environment.
pub(crate) fn escaped(scene: &Scene, ray: &Ray) -> Vec3A {
    let mut g = Guides::default();
    let tr = through(
        scene,
        scene.media().camera,
        ray,
        f32::INFINITY,
        Vec3A::ONE,
        &mut g,
    );
    g.albedo + tr * sky(scene, ray.dir)
}

/// Adds to `g` what medium `medium` (if any) between `ray`'s origin and
/// `t_max` shows, seen with tint `tint`: the albedo where a path first
/// scatters in it and the light it emits, both in expectation
/// ([`crate::media::expected`]; Cycles gives its denoiser a volume's albedo
/// where a path scatters first, from one sample). Returns the medium's
/// transmittance, the factor of what lies behind.
fn through(
    scene: &Scene,
    medium: Option<u32>,
    ray: &Ray,
    t_max: f32,
    tint: Vec3A,
    g: &mut Guides,
) -> Vec3A {
    let Some(m) = medium.and_then(|m| scene.media().media.get(m as usize)) else {
        return Vec3A::ONE;
    };
    let e = expected::along(m, ray, t_max);
    g.albedo += tint * (e.scattered + squash(e.emitted));
    e.transmittance
}

/// The mean of the three channels.
#[inline]
fn mean(v: Vec3A) -> f32 {
    v.element_sum() / 3.0
}

/// `L/(1 + L)` per channel: light as a guide value in `[0, 1)`.
#[inline]
fn squash(l: Vec3A) -> Vec3A {
    let l = l.max(Vec3A::ZERO);
    l / (Vec3A::ONE + l)
}

/// The albedo guide of a ray that escapes along `dir`: the environment's
/// radiance squashed (zero for a black one).
#[inline]
pub(crate) fn sky(scene: &Scene, dir: Vec3A) -> Vec3A {
    if scene.environment().is_black() {
        Vec3A::ZERO
    } else {
        squash(scene.environment_radiance(dir))
    }
}

/// Adds to `g` what surface `s` (reached along `dir` through medium
/// `medium`, with the chain's tint `tint` and normal weight `share`) and the
/// chain beyond it contribute.
#[allow(clippy::too_many_arguments)]
fn visit(
    scene: &Scene,
    dir: Vec3A,
    s: &SurfaceHit,
    bsdf: &Material,
    medium: Option<u32>,
    tint: Vec3A,
    share: f32,
    depth: u32,
    g: &mut Guides,
) {
    let material = &scene.materials()[s.material as usize];
    let cos_out = -s.ng.dot(dir);
    if material.is_emissive() && (cos_out > 0.0 || material.emits_both_sides) {
        g.albedo += tint * squash(material.emitted(&s.attrs, scene.textures()));
    }
    let wo_world = -dir;
    let n = shading(scene, s, bsdf, wo_world).n;
    let frame = Frame::from_normal(n);
    let mut bsdf = *bsdf;
    bsdf.orient_coat(&frame, coat_normal(s, n));
    bsdf.orient_anisotropy(&frame, s.tangent, s.bitangent);
    let lobes = bsdf.guide_lobes(frame.to_local(wo_world));
    let specular = |l: Option<(Vec3A, Vec3A)>| l.map_or(Vec3A::ZERO, |(_, v)| v);
    let (reflect, transmit) = (specular(lobes.reflect), specular(lobes.transmit));
    let total = luminance(lobes.rough + reflect + transmit);
    let ends = total.is_nan()
        || total <= 0.0
        || luminance(lobes.rough) > ROUGH_SHARE * total
        || depth + 1 >= MAX_CHAIN;
    if ends {
        // The side the ray sees, by the geometric normal (a shading normal
        // may tilt past the ray).
        let facing = if s.ng.dot(dir) > 0.0 { -s.ns } else { s.ns };
        g.albedo += tint * (lobes.rough + reflect + transmit);
        g.normal += share * facing;
        return;
    }
    g.albedo += tint * lobes.rough;
    let both = [lobes.reflect, lobes.transmit];
    let split = luminance(reflect + transmit);
    if depth == 0 {
        for (wi, value) in both.into_iter().flatten() {
            follow(
                scene,
                s,
                frame.to_world(wi),
                medium,
                tint * value,
                share * luminance(value) / split,
                depth,
                g,
            );
        }
    } else {
        let stronger = match both {
            [Some(r), Some(t)] => Some(if luminance(r.1) >= luminance(t.1) {
                r
            } else {
                t
            }),
            [r, t] => r.or(t),
        };
        if let Some((wi, _)) = stronger {
            let value = reflect + transmit;
            follow(
                scene,
                s,
                frame.to_world(wi),
                medium,
                tint * value,
                share,
                depth,
                g,
            );
        }
    }
}

/// Follows the chain from `s` (reached through medium `medium`) along `wi`
/// (world space), into the medium on that side of `s`.
#[allow(clippy::too_many_arguments)]
fn follow(
    scene: &Scene,
    s: &SurfaceHit,
    wi: Vec3A,
    medium: Option<u32>,
    tint: Vec3A,
    share: f32,
    depth: u32,
    g: &mut Guides,
) {
    if !wi.is_finite() || wi == Vec3A::ZERO {
        return;
    }
    let wi = wi.normalize();
    let interface = scene.media().interface(s.material);
    let medium = if interface.is_transition() {
        interface.target(s.ng, wi)
    } else {
        medium
    };
    let ray = Ray::new(s.point.offset_origin(wi), wi);
    let hit = scene.intersect(&ray, f32::INFINITY);
    let t = hit.as_ref().map_or(f32::INFINITY, |h| h.t);
    let tr = through(scene, medium, &ray, t, tint, g);
    let (tint, share) = (tint * tr, share * mean(tr));
    match hit {
        Some(hit) => {
            let next = scene.surface(&hit);
            let material = &scene.materials()[next.material as usize];
            let bsdf = material.bsdf(&next.attrs, scene.textures());
            visit(scene, wi, &next, &bsdf, medium, tint, share, depth + 1, g);
        }
        None => g.albedo += tint * sky(scene, wi),
    }
}
