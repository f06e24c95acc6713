//! Arbitrary output variables (AOVs): per-pixel data gathered with the image,
//! written next to it as extra EXR channels: the guides a denoiser takes
//! (`albedo`, `normal`; [`crate::denoise`] uses them with Open Image
//! Denoise), what compositors use for depth effects and masks (`depth`,
//! `position`), and the pixels' noise (`variance`).
//!
//! Every AOV is gathered from the camera rays of the beauty pass itself (the
//! same sample positions, hence the same antialiased edges), from the hit the
//! render already found. `path` also hands over the hit's shading (surface
//! and BSDF), so its textures are not looked up twice; for `flat` and
//! `direct` the AOVs shade the hit themselves. Per pixel sample:
//!
//! * `albedo` and `normal`: the denoiser's guides ([`guides`]): the albedo
//!   and the world-space shading normal (interpolated, normal-mapped, turned
//!   to the side the ray sees) of the first surface that is not specular,
//!   found by following mirrors, glass and smooth metals from the camera
//!   ray's hit (the only AOVs that cast rays of their own, and only there),
//!   with emitters and the environment seen along the way squashed into the
//!   albedo. The albedo is a surface's directional albedo as seen by the ray,
//!   [`Material::albedo`](crate::materials::Material::albedo) (diffuse: the
//!   reflectance; glTF: an estimate from the lobe weights; conductors: their
//!   tint), in `[0, 1]`; on a miss it is the environment's squashed radiance
//!   and the normal zero. They do not depend on the integrator: `flat` and
//!   `direct` get the guides of the BSDFs that `path` uses.
//! * `depth`: camera-space depth of the camera ray's hit, the distance of the
//!   hit point from the camera along its viewing axis (not along the ray),
//!   for perspective and orthographic cameras alike.
//! * `position`: the world-space hit point of the camera ray.
//! * `variance`: the estimated variance of the pixel's value, of its
//!   luminance (Rec. 709): the samples' variance over their number,
//!   `(Σ L² − (Σ L)²/n) / (n (n − 1))`, from the same exact sums as the image
//!   (each sample's `L` clamped to 2²⁰ in `Σ L²`); `+∞` below two samples.
//!   It is what a pixel's noise is, and what [`crate::denoise`] weighs the
//!   noisy image against the denoised one by.
//!
//! A pixel's value is the mean over its samples, so that noise-free geometry
//! gives noise-free AOVs and edges are antialiased as in the image: `albedo`
//! and `normal` over the pixel's first [`GUIDE_SAMPLES`] samples (a miss
//! counts, so an edge pixel blends towards the background and its normal is
//! shorter than 1, as OIDN expects);
//! `depth` and `position` over the samples that hit (a mean with a miss's
//! infinity would be infinite, one with zero meaningless), and `+∞` (every
//! component) where no sample hits. Sums are kept per pixel in sample order, so
//! AOVs are bit-identical for any number of threads, like the image.

pub mod guides;
mod image;
mod set;
mod sums;

pub use guides::{GUIDE_SAMPLES, Guides};
pub use image::{AovImage, AovLayer};
pub use set::{Aov, AovSet, in_half, luminance};
pub use sums::{AovSums, VARIANCE_CLAMP};
pub(crate) use sums::{FirstHit, Layout};
