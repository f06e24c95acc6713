//! GGX (Trowbridge–Reitz) microfacets, isotropic: the distribution `D`,
//! Smith's `Λ` for height-correlated masking–shadowing, the sampling of the
//! visible normals (Heitz 2018), and the width below which a lobe is smooth
//! (a delta). The glTF BSDF's anisotropic GGX builds on these
//! (`pbr/ggx.rs`). Mitsuba 3's Beckmann and GGX, with separable masking,
//! are in the submodule `mitsuba` ([`MicrofacetDistribution`]).

use glam::{Vec2, Vec3A};
use std::f32::consts::PI;

mod mitsuba;

pub(crate) use mitsuba::gauss_legendre;
pub use mitsuba::{MicrofacetDistribution, MicrofacetKind};

/// Conductors with `alpha` below this are treated as perfectly smooth (a delta
/// lobe): GGX at such roughness is numerically a spike that f32 cannot resolve.
pub const ALPHA_SMOOTH: f32 = 1e-3;

/// Whether a lobe of GGX width `alpha` is smooth (a delta lobe): `alpha`
/// below [`ALPHA_SMOOTH`]. NaN counts as smooth too: never a NaN in the
/// microfacet code.
#[inline]
pub(super) fn is_smooth(alpha: f32) -> bool {
    alpha.is_nan() || alpha < ALPHA_SMOOTH
}

/// GGX / Trowbridge–Reitz microfacet distribution for a unit microfacet normal
/// `m` in the local frame (zero below the horizon).
#[inline]
pub(super) fn ggx_d(alpha: f32, m: Vec3A) -> f32 {
    if m.z <= 0.0 {
        return 0.0;
    }
    // α² / (π (z²(α²−1) + 1)²), written without the cancellation of 1 − z² near
    // the pole: (x² + y²)/α² + z² is accurate for m close to +z.
    let a2 = alpha * alpha;
    let s = (m.x * m.x + m.y * m.y) / a2 + m.z * m.z;
    1.0 / (PI * a2 * s * s)
}

/// Smith's Λ for GGX: `(√(1 + α² tan² θ) − 1) / 2`; infinite at the horizon.
#[inline]
pub(super) fn ggx_lambda(alpha: f32, w: Vec3A) -> f32 {
    let z2 = w.z * w.z;
    let xy2 = w.x * w.x + w.y * w.y;
    if z2 == 0.0 {
        return f32::INFINITY;
    }
    let a2_tan2 = alpha * alpha * xy2 / z2;
    // (√(1+x) − 1)/2 = x / (2 (√(1+x) + 1)), without cancellation for small x.
    a2_tan2 / (2.0 * ((1.0 + a2_tan2).sqrt() + 1.0))
}

/// Samples a GGX normal visible from `wo` (`wo.z > 0`) with density
/// `G1(wo) max(0, wo·m) D(m) / cos θo` (Heitz 2018, "Sampling the GGX
/// Distribution of Visible Normals").
#[inline]
pub(super) fn ggx_sample_visible_normal(alpha: f32, wo: Vec3A, u: Vec2) -> Vec3A {
    ggx_sample_visible_normal_xy(alpha, alpha, wo, u)
}

/// [`ggx_sample_visible_normal`] of the anisotropic GGX of widths `alpha_x`
/// along local `x` and `alpha_y` along `y` (the same arithmetic: with equal
/// widths, the isotropic sample bit for bit).
#[inline]
pub(super) fn ggx_sample_visible_normal_xy(
    alpha_x: f32,
    alpha_y: f32,
    wo: Vec3A,
    u: Vec2,
) -> Vec3A {
    // Stretch the view direction to the hemisphere configuration (α = 1).
    let vh = Vec3A::new(alpha_x * wo.x, alpha_y * wo.y, wo.z).normalize();
    // An orthonormal basis around it (T1 lies in the tangent plane).
    let len2 = vh.x * vh.x + vh.y * vh.y;
    let t1 = if len2 > 0.0 {
        Vec3A::new(-vh.y, vh.x, 0.0) * len2.sqrt().recip()
    } else {
        Vec3A::X
    };
    let t2 = vh.cross(t1);
    // A point on the projected disk, warped to the visible half.
    let r = u.x.sqrt();
    let phi = 2.0 * PI * u.y;
    let (sin_phi, cos_phi) = phi.sin_cos();
    let p1 = r * cos_phi;
    let p2 = r * sin_phi;
    let s = 0.5 * (1.0 + vh.z);
    let p2 = (1.0 - s) * (1.0 - p1 * p1).max(0.0).sqrt() + s * p2;
    let nh = p1 * t1 + p2 * t2 + (1.0 - p1 * p1 - p2 * p2).max(0.0).sqrt() * vh;
    // Unstretch.
    Vec3A::new(alpha_x * nh.x, alpha_y * nh.y, nh.z.max(0.0)).normalize()
}
