//! Values that vary over a surface by their texture coordinates, as
//! Mitsuba's texture plugins define them ([`Pattern`]): an image looked up
//! bilinearly or at the nearest texel after a 2-D affine map of the
//! coordinates (`bitmap` with `to_uv`, `filter_type`, `wrap_mode`, `raw`),
//! the two-colour `checkerboard`, and a mesh's own per-vertex or per-face
//! values (`mesh_attribute`, which the loader stores as the mesh's colours).

use glam::{Affine2, Vec2, Vec3, Vec4, Vec4Swizzles};

use super::store::TextureStore;
use super::texel::{ColorSpace, Wrap};

/// A value over the surface, looked up at a hit's texture coordinates.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Pattern {
    /// An image of the scene's [`TextureStore`].
    Image {
        /// The image's id.
        image: u32,
        /// How coordinates outside `[0, 1]` wrap (both ways).
        wrap: Wrap,
        /// Nearest texel instead of bilinear filtering.
        nearest: bool,
        /// How RGB is decoded (sRGB unless Mitsuba's `raw`).
        space: ColorSpace,
        /// Applied to the surface's coordinates first (Mitsuba's `to_uv`).
        to_uv: Affine2,
    },
    /// Mitsuba's `checkerboard`: `color0` where the fractional parts of u and
    /// v are both above ½ or both not, else `color1`.
    Checkerboard {
        /// One colour (RGBA, alpha 1).
        color0: Vec4,
        /// The other.
        color1: Vec4,
        /// Applied to the surface's coordinates first.
        to_uv: Affine2,
    },
    /// The mesh's own value at the hit, interpolated from its vertices (or
    /// constant over a face): Mitsuba's `mesh_attribute`, held as the
    /// mesh's vertex colours.
    MeshAttribute,
    /// The same value everywhere (Mitsuba's `rawconstant`, or a constant
    /// where a pattern is expected).
    Constant(Vec4),
}

impl Pattern {
    /// The value at a hit of texture coordinates `uv` and interpolated
    /// vertex colour `color` (linear RGBA).
    ///
    /// # Panics
    ///
    /// If an image pattern names an image `textures` does not hold.
    #[inline]
    pub fn eval(&self, uv: Vec2, color: Vec4, textures: &TextureStore) -> Vec4 {
        match *self {
            Pattern::Image {
                image,
                wrap,
                nearest,
                space,
                to_uv,
            } => {
                let uv = to_uv.transform_point2(uv);
                let image = textures.get(image);
                match nearest {
                    true => image.nearest(uv, wrap, wrap, space),
                    false => image.lookup(uv, wrap, wrap, space),
                }
            }
            Pattern::Checkerboard {
                color0,
                color1,
                to_uv,
            } => {
                let uv = to_uv.transform_point2(uv);
                let f = uv - uv.floor();
                if (f.x > 0.5) == (f.y > 0.5) {
                    color0
                } else {
                    color1
                }
            }
            Pattern::MeshAttribute => color,
            Pattern::Constant(c) => c,
        }
    }

    /// The value at a hit read as one number, as Mitsuba's `eval_1` reads a
    /// texture for a scalar parameter (a microfacet width, a weight): the
    /// luminance of [`Pattern::eval`]'s RGB (Mitsuba's weights; a grey value
    /// is itself), except that Mitsuba 3.7.1's `checkerboard` gives its two
    /// colours the other way round there (`color0` where exactly one of the
    /// fractional parts is above ½), which scenes made for Mitsuba rely on.
    #[inline]
    pub fn eval_1(&self, uv: Vec2, color: Vec4, textures: &TextureStore) -> f32 {
        let c = match *self {
            Pattern::Checkerboard {
                color0,
                color1,
                to_uv,
            } => Pattern::Checkerboard {
                color0: color1,
                color1: color0,
                to_uv,
            }
            .eval(uv, color, textures),
            _ => self.eval(uv, color, textures),
        };
        mitsuba_luminance(c.xyz())
    }

    /// The partial derivatives of [`Pattern::eval`] with respect to the
    /// surface's `u` and `v`: a bilinear image's (through `to_uv` by the chain
    /// rule), zero for what is constant or piecewise constant (nearest
    /// images, checkerboards, constants) and for mesh attributes (whose
    /// derivative is not a function of `uv`). Mitsuba's `eval_1_grad`, per
    /// channel.
    #[inline]
    pub fn gradient(&self, uv: Vec2, textures: &TextureStore) -> (Vec4, Vec4) {
        match *self {
            Pattern::Image {
                image,
                wrap,
                nearest: false,
                space,
                to_uv,
            } => {
                let (gx, gy) = textures.get(image).lookup_gradient(
                    to_uv.transform_point2(uv),
                    wrap,
                    wrap,
                    space,
                );
                // d/du = ∂f/∂u' ∂u'/∂u + ∂f/∂v' ∂v'/∂u: the transpose of the map.
                let m = to_uv.matrix2;
                (
                    gx * m.x_axis.x + gy * m.x_axis.y,
                    gx * m.y_axis.x + gy * m.y_axis.y,
                )
            }
            _ => (Vec4::ZERO, Vec4::ZERO),
        }
    }

    /// The image it reads, if any.
    pub fn image(&self) -> Option<u32> {
        match self {
            Pattern::Image { image, .. } => Some(*image),
            Pattern::Checkerboard { .. } | Pattern::MeshAttribute | Pattern::Constant(_) => None,
        }
    }

    /// The image it reads, for changing it (when images move to another store).
    pub fn image_mut(&mut self) -> Option<&mut u32> {
        match self {
            Pattern::Image { image, .. } => Some(image),
            Pattern::Checkerboard { .. } | Pattern::MeshAttribute | Pattern::Constant(_) => None,
        }
    }
}

/// Mitsuba's luminance of linear sRGB (its `eval_1` of a colour texture,
/// with the sRGB primaries' exact weights rather than Rec. 709's rounded
/// ones); a grey value is its own luminance.
#[inline]
pub fn mitsuba_luminance(c: Vec3) -> f32 {
    c.x * 0.212_671 + c.y * 0.715_160 + c.z * 0.072_169
}

#[cfg(test)]
mod tests {
    use super::*;

    impl Pattern {
        fn eval_uv(&self, uv: Vec2, t: &TextureStore) -> Vec4 {
            self.eval(uv, Vec4::ONE, t)
        }
    }
    use crate::textures::Image;

    #[test]
    fn checkerboard_alternates_by_halves_of_each_period() {
        let p = Pattern::Checkerboard {
            color0: Vec4::splat(0.4),
            color1: Vec4::splat(0.2),
            to_uv: Affine2::from_scale(Vec2::splat(5.0)),
        };
        let t = TextureStore::new();
        // uv × 5: (0.05, 0.05) → (0.25, 0.25): both low halves → color0.
        assert_eq!(p.eval_uv(Vec2::new(0.05, 0.05), &t).x, 0.4);
        // (0.15, 0.05) → (0.75, 0.25): one high, one low → color1.
        assert_eq!(p.eval_uv(Vec2::new(0.15, 0.05), &t).x, 0.2);
        // (0.15, 0.15) → both high → color0; negative coordinates wrap.
        assert_eq!(p.eval_uv(Vec2::new(0.15, 0.15), &t).x, 0.4);
        assert_eq!(p.eval_uv(Vec2::new(-0.05, 0.05), &t).x, 0.2);
    }

    #[test]
    fn nearest_and_bilinear_image_lookups_after_the_map() {
        let mut t = TextureStore::new();
        // 2 × 1 grey image: 0 and 255.
        let id = t.push(Image::from_u8(2, 1, 1, vec![0, 255]));
        let image = |nearest| Pattern::Image {
            image: id,
            wrap: Wrap::Repeat,
            nearest,
            space: ColorSpace::Linear,
            to_uv: Affine2::from_translation(Vec2::new(0.5, 0.0)),
        };
        // u = 0.2 + 0.5 = 0.7: the second texel (centre 0.75) nearest; bilinear
        // between the centres 0.25 and 0.75 gives 0.9.
        assert_eq!(image(true).eval_uv(Vec2::new(0.2, 0.5), &t).x, 1.0);
        let b = image(false).eval_uv(Vec2::new(0.2, 0.5), &t).x;
        assert!((b - 0.9).abs() < 1e-4, "{b}");
        // u = 0.9 + 0.5 = 1.4 wraps to 0.4: the first texel.
        assert_eq!(image(true).eval_uv(Vec2::new(0.9, 0.5), &t).x, 0.0);
    }

    /// The gradient is the derivative of the bilinear value: central
    /// differences inside a texel cell agree, through a rotating, scaling
    /// `to_uv` and on a non-square image.
    #[test]
    fn gradient_is_the_derivative_of_the_bilinear_value() {
        let mut t = TextureStore::new();
        let texels: Vec<u8> = (0..5 * 3).map(|i| ((i * 97 + 13) % 251) as u8).collect();
        let id = t.push(Image::from_u8(5, 3, 1, texels));
        let p = Pattern::Image {
            image: id,
            wrap: Wrap::Repeat,
            nearest: false,
            space: ColorSpace::Linear,
            to_uv: Affine2::from_scale_angle_translation(
                Vec2::new(1.7, 0.6),
                0.4,
                Vec2::new(0.1, -0.3),
            ),
        };
        let h = 1e-3;
        let mut checked = 0;
        for k in 0..200 {
            let uv = Vec2::new((k as f32 * 0.618).fract(), (k as f32 * 0.414).fract());
            let (du, dv) = p.gradient(uv, &t);
            let fd = |d: Vec2| (p.eval_uv(uv + d, &t).x - p.eval_uv(uv - d, &t).x) / (2.0 * h);
            let (fu, fv) = (fd(Vec2::new(h, 0.0)), fd(Vec2::new(0.0, h)));
            // Skip points whose stencil crosses a cell edge (a kink).
            let (fu2, fv2) = (
                (p.eval_uv(uv + Vec2::new(h, 0.0), &t).x - p.eval_uv(uv, &t).x) / h,
                (p.eval_uv(uv + Vec2::new(0.0, h), &t).x - p.eval_uv(uv, &t).x) / h,
            );
            if (fu - fu2).abs() > 1e-2 * (1.0 + fu.abs())
                || (fv - fv2).abs() > 1e-2 * (1.0 + fv.abs())
            {
                continue;
            }
            checked += 1;
            assert!(
                (du.x - fu).abs() < 2e-2 * (1.0 + fu.abs()),
                "{uv}: {} vs {fu}",
                du.x
            );
            assert!(
                (dv.x - fv).abs() < 2e-2 * (1.0 + fv.abs()),
                "{uv}: {} vs {fv}",
                dv.x
            );
        }
        assert!(checked > 100, "{checked}");
        // Nearest lookups and constants have none.
        assert_eq!(
            Pattern::Constant(Vec4::ONE).gradient(Vec2::ZERO, &t),
            (Vec4::ZERO, Vec4::ZERO)
        );
    }

    /// Read as a scalar (Mitsuba's `eval_1`), a checkerboard gives its
    /// colours the other way round, as Mitsuba 3.7.1 does; an image gives
    /// its luminance.
    #[test]
    fn scalar_reads_swap_the_checkerboard_as_mitsuba() {
        let p = Pattern::Checkerboard {
            color0: Vec4::splat(0.4),
            color1: Vec4::splat(0.2),
            to_uv: Affine2::IDENTITY,
        };
        let t = TextureStore::new();
        let uv = Vec2::new(0.25, 0.25);
        assert_eq!(p.eval_uv(uv, &t).x, 0.4);
        assert!((p.eval_1(uv, Vec4::ONE, &t) - 0.2).abs() < 1e-6);
        let c = Pattern::Constant(Vec4::new(1.0, 0.0, 0.0, 1.0));
        assert!((c.eval_1(uv, Vec4::ONE, &t) - 0.212_671).abs() < 1e-6);
    }
}
