//! Checks the analytic shapes' tests share: derivatives against finite
//! differences of the points, and area sampling against the ray test.

use glam::{Vec2, Vec3A};

use super::ray::{Ray, SurfacePoint};
use crate::sampling::sampler::Rng;

/// Asserts that the point `sp` rebuilt from coordinates lies within its
/// error bound of the exact point `exact`.
pub(crate) fn assert_within_bound(sp: &SurfacePoint, exact: glam::DVec3) {
    let err = (sp.p.as_dvec3() - exact).abs();
    assert!(
        err.cmple(sp.error.as_dvec3()).all(),
        "{err} beyond {}",
        sp.error
    );
}

/// Asserts that `derivatives` at `uv` are central differences of `point`.
pub(crate) fn assert_derivatives(
    point: impl Fn(Vec2) -> SurfacePoint,
    derivatives: (Vec3A, Vec3A),
    uv: Vec2,
) {
    let (du, dv) = derivatives;
    let h = 1e-3;
    let fd = |a: Vec2, b: Vec2| (point(a).p - point(b).p) / (2.0 * h);
    let fdu = fd(uv + Vec2::new(h, 0.0), uv - Vec2::new(h, 0.0));
    let fdv = fd(uv + Vec2::new(0.0, h), uv - Vec2::new(0.0, h));
    assert!((du - fdu).length() < 1e-3 * du.length(), "{du} {fdu}");
    assert!((dv - fdv).length() < 1e-3 * dv.length(), "{dv} {fdv}");
}

/// Asserts that uniform area sampling (`sample`: a point from `u` in
/// `[0, 1)²`, of a shape of area `area`) agrees with the ray test
/// (`intersect`): seen from `p`, the solid angle the shape covers by area
/// samples (∑ cos/(d² pdf) over the samples that are the first crossing
/// along their direction) and by the share of uniform directions that hit
/// it, times 4π, agree to 2 %.
pub(crate) fn assert_area_sampling_sees_what_rays_see(
    p: Vec3A,
    area: f32,
    sample: impl Fn(Vec2) -> SurfacePoint,
    intersect: impl Fn(&Ray) -> Option<f32>,
) {
    let mut rng = Rng::new(8, 2);
    let n = 400_000;
    let (mut by_area, mut by_rays) = (0.0f64, 0usize);
    for _ in 0..n {
        let sp = sample(Vec2::new(rng.next_f32(), rng.next_f32()));
        let to = sp.p - p;
        let t = intersect(&Ray::new(p, to.normalize()));
        if t.is_some_and(|t| (t - to.length()).abs() < 1e-4) {
            let cos = sp.n.dot(to).abs() / to.length();
            by_area += f64::from(cos * area / to.length_squared());
        }
        let z = 1.0 - 2.0 * rng.next_f32();
        let phi = std::f32::consts::TAU * rng.next_f32();
        let s = (1.0 - z * z).max(0.0).sqrt();
        let w = Vec3A::new(s * phi.cos(), s * phi.sin(), z);
        by_rays += usize::from(intersect(&Ray::new(p, w)).is_some());
    }
    let a = by_area / n as f64;
    let b = by_rays as f64 / n as f64 * 4.0 * std::f64::consts::PI;
    assert!(a > 0.0 && (a - b).abs() < 0.02 * a, "{p}: {a} vs {b}");
}
