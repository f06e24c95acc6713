//! `KHR_texture_transform`: an affine map of texture coordinates.

use glam::{Affine2, Mat2, Vec2};

/// A `KHR_texture_transform` (offset, rotation, scale) of one texture slot's
/// coordinates: `uv' = T(offset) · R(rotation) · S(scale) · uv`.
///
/// The rotation is the one of the extension's specification as implemented by
/// Khronos' glTF-Sample-Viewer and the sample model `TextureTransformTest`:
///
/// ```text
/// u' =  cos(r) · u + sin(r) · v
/// v' = -sin(r) · u + cos(r) · v
/// ```
///
/// i.e. the matrix printed in the specification read row by row, "a rotation of
/// the UVs counter-clockwise" as seen on an image whose v axis points down
/// (see [`TextureTransform::matrix`] for the sources).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TextureTransform {
    /// Translation of the coordinates, in units of the texture's size.
    pub offset: Vec2,
    /// Rotation in radians (see the type's documentation for the direction).
    pub rotation: f32,
    /// Per-axis scale factors.
    pub scale: Vec2,
}

impl Default for TextureTransform {
    /// The identity: no offset, no rotation, unit scale (the extension's defaults).
    fn default() -> Self {
        Self::IDENTITY
    }
}

impl TextureTransform {
    /// The identity transform.
    pub const IDENTITY: Self = Self {
        offset: Vec2::ZERO,
        rotation: 0.0,
        scale: Vec2::ONE,
    };

    /// Whether this is exactly the identity (lookups may skip it).
    pub fn is_identity(&self) -> bool {
        *self == Self::IDENTITY
    }

    /// The map as an affine matrix, `T · R · S`.
    ///
    /// The KHR_texture_transform specification
    /// (KhronosGroup/glTF, `extensions/2.0/Khronos/KHR_texture_transform/README.md`,
    /// ratified version) gives, in GLSL:
    ///
    /// ```glsl
    /// mat3 translation = mat3(1,0,0, 0,1,0, Offset.x, Offset.y, 1);
    /// mat3 rotation = mat3(
    ///     cos(Rotation), sin(Rotation), 0,
    ///    -sin(Rotation), cos(Rotation), 0,
    ///                 0,             0, 1
    /// );
    /// mat3 scale = mat3(Scale.x,0,0, 0,Scale.y,0, 0,0,1);
    /// mat3 matrix = translation * rotation * scale;
    /// ```
    ///
    /// and describes `rotation` as "Rotate the UVs by this many radians
    /// counter-clockwise around the origin. This is equivalent to a similar
    /// rotation of the image clockwise", with (0, 0) the upper left corner of the
    /// image. Taken literally, GLSL's column-major `mat3(...)` would make the
    /// rotation `u' = c·u − s·v`, `v' = s·u + c·v`; but the specification's own
    /// example (offset [0, 1], rotation π/2, scale [0.5, 0.5] "utilizes only the
    /// lower left quadrant of the source image, rotated clockwise 90°") only
    /// holds with the rows as printed, `u' = c·u + s·v`, `v' = −s·u + c·v`, and so
    /// do the implementations: KhronosGroup/glTF issue #1563 ("KHR_texture_transform
    /// has the wrong rotation matrix": the correct one, for a v-down space, is "the
    /// same as a clockwise rotation in a Y-Up space") and glTF-Sample-Viewer's
    /// `source/gltf/material.js`, whose rotation is `jsToGl([c, -s, 0, s, c, 0,
    /// 0, 0, 1])` in column-major gl-matrix, i.e. columns (c, −s) and (s, c).
    /// This is that matrix: columns (c, −s) and (s, c).
    pub fn matrix(&self) -> Affine2 {
        let (s, c) = self.rotation.sin_cos();
        let rotation = Mat2::from_cols(Vec2::new(c, -s), Vec2::new(s, c));
        let scale = Mat2::from_diagonal(self.scale);
        Affine2::from_mat2_translation(rotation * scale, self.offset)
    }

    /// Transforms texture coordinates: `T · R · S · uv`.
    #[inline]
    pub fn apply(&self, uv: Vec2) -> Vec2 {
        let (s, c) = self.rotation.sin_cos();
        let p = uv * self.scale;
        Vec2::new(c * p.x + s * p.y, -s * p.x + c * p.y) + self.offset
    }
}
