//! Values that vary over a surface by their texture coordinates, as
//! Mitsuba's texture plugins define them ([`Pattern`]): an image looked up
//! bilinearly or at the nearest texel after a 2-D affine map of the
//! coordinates (`bitmap` with `to_uv`, `filter_type`, `wrap_mode`, `raw`),
//! the two-colour `checkerboard`, and a mesh's own per-vertex or per-face
//! values (`mesh_attribute`, which the loader stores as the mesh's colours).

use glam::{Affine2, Vec2, Vec4};

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
        }
    }

    /// The image it reads, if any.
    pub fn image(&self) -> Option<u32> {
        match self {
            Pattern::Image { image, .. } => Some(*image),
            Pattern::Checkerboard { .. } | Pattern::MeshAttribute => None,
        }
    }

    /// The image it reads, for changing it (when images move to another store).
    pub fn image_mut(&mut self) -> Option<&mut u32> {
        match self {
            Pattern::Image { image, .. } => Some(image),
            Pattern::Checkerboard { .. } | Pattern::MeshAttribute => None,
        }
    }
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
}
