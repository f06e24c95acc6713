//! MTL materials as raylab's glTF-style material: [`material_from_mtl`]
//! with the textures a material uses ([`MtlTextures`]), and bump maps that
//! are height fields turned into normal maps.

use glam::{Vec2, Vec3, Vec3A, Vec4};

use super::mtl::{MapRef, MtlMaterial, phong_roughness};
use crate::materials::surface::{AlphaMode, GltfMaterial, MaterialKind, SurfaceMaterial};
use crate::textures::{ColorSpace, Image, TextureRef, TextureTransform, Wrap};

/// Reflectance of triangles without an MTL colour.
pub const DEFAULT_REFLECTANCE: f32 = 0.75;

/// Slope of a bump map's height field per unit of height difference between
/// neighbouring texels, before `-bm`: a step of 1/10 of the height range
/// across one texel tilts the normal by 45°.
pub const BUMP_SLOPE_SCALE: f32 = 10.0;

/// Every texture statement of a material.
pub(super) fn maps(m: &MtlMaterial) -> [&Option<MapRef>; 8] {
    [
        &m.map_kd, &m.map_ks, &m.map_d, &m.bump, &m.norm, &m.map_pr, &m.map_pm, &m.map_ke,
    ]
}

/// A texture reference with the statement's options: `-o`/`-s` as a texture
/// transform (converted from OBJ's v-up coordinates), `-clamp on`.
pub(super) fn texture_ref(image: u32, map: &MapRef) -> TextureRef {
    let wrap = if map.clamp {
        Wrap::ClampToEdge
    } else {
        Wrap::Repeat
    };
    // OBJ: u' = s·u + o with v up; ours: v_ours = 1 − v_obj, so
    // v'_ours = s_v·v_ours + (1 − s_v − o_v).
    let transform = TextureTransform {
        offset: Vec2::new(map.offset.x, 1.0 - map.scale.y - map.offset.y),
        rotation: 0.0,
        scale: map.scale,
    };
    TextureRef {
        wrap_s: wrap,
        wrap_t: wrap,
        transform,
        ..TextureRef::new(image)
    }
}

/// Whether an image is a tangent-space normal map rather than a height field:
/// RGB whose mean is near (0.5, 0.5, 1) (mostly "blue").
pub(super) fn looks_like_normal_map(image: &Image) -> bool {
    if image.channels() < 3 {
        return false;
    }
    let mean = image.average(ColorSpace::Linear);
    (mean.x - 0.5).abs() < 0.15 && (mean.y - 0.5).abs() < 0.15 && mean.z > 0.7
}

/// A tangent-space normal map of a height field (the image's mean of R, G, B):
/// slopes from central differences, times `multiplier` and
/// [`BUMP_SLOPE_SCALE`]; +x along increasing u, +y towards the image's top
/// (decreasing v), as the normal maps raylab reads.
pub(super) fn height_to_normal_map(image: &Image, multiplier: f32) -> Image {
    use rayon::prelude::*;
    let (w, h) = (image.width() as usize, image.height() as usize);
    let k = 0.5 * multiplier * BUMP_SLOPE_SCALE;
    // Bands of rows in parallel; each reads its rows' heights once (and one
    // row either side), so a texel is fetched about once, not five times.
    const BAND: usize = 32;
    let height_row = |y: usize, row: &mut [f32]| {
        for (x, out) in row.iter_mut().enumerate() {
            let t: Vec4 = image.texel(x as u32, y as u32, ColorSpace::Linear);
            *out = (t.x + t.y + t.z) / 3.0;
        }
    };
    let mut texels = vec![0u8; w * h * 3];
    texels
        .par_chunks_mut(BAND * w * 3)
        .enumerate()
        .for_each(|(band, out)| {
            let y0 = band * BAND;
            let rows = out.len() / (w * 3);
            // Heights of rows y0 − 1 ..= y0 + rows, wrapping around.
            let mut heights = vec![0.0f32; (rows + 2) * w];
            for (i, row) in heights.chunks_mut(w).enumerate() {
                height_row((y0 + i + h - 1) % h, row);
            }
            for r in 0..rows {
                let (up, mid, down) = (
                    &heights[r * w..][..w],
                    &heights[(r + 1) * w..][..w],
                    &heights[(r + 2) * w..][..w],
                );
                for x in 0..w {
                    let du = (mid[(x + 1) % w] - mid[(x + w - 1) % w]) * k;
                    // Up in the image is y − 1.
                    let dv = (up[x] - down[x]) * k;
                    let n = Vec3::new(-du, -dv, 1.0).normalize();
                    let texel = &mut out[(r * w + x) * 3..][..3];
                    for (o, c) in texel.iter_mut().zip(n.to_array()) {
                        *o = ((c * 0.5 + 0.5) * 255.0).round() as u8;
                    }
                }
            }
        });
    Image::from_u8(w as u32, h as u32, 3, texels)
}

/// The textures a material uses, as references into the scene's store.
#[derive(Clone, Debug, Default)]
pub struct MtlTextures {
    /// `map_Kd`.
    pub kd: Option<TextureRef>,
    /// `map_Ks`.
    pub ks: Option<TextureRef>,
    /// `map_d`, and whether the image has an alpha channel (else its red).
    pub d: Option<(TextureRef, bool)>,
    /// `norm`, or `map_Bump` as a normal map, with the scale of its x and y.
    pub normal: Option<(TextureRef, f32)>,
    /// `map_Pr`.
    pub pr: Option<TextureRef>,
    /// `map_Pm`.
    pub pm: Option<TextureRef>,
    /// `map_Ke`.
    pub ke: Option<TextureRef>,
}

/// An MTL material as raylab's glTF-style material. The mapping (README.md,
/// "OBJ/MTL"):
///
/// * base colour `Kd` × `map_Kd` (sRGB); metallic `Pm` × `map_Pm` (else 0);
///   roughness `Pr` × `map_Pr`, else from `Ns` by [`phong_roughness`];
/// * `Ks` scales the specular reflectance at normal incidence: `F0 = 0.08 Ks`
///   (Ks 0.5 is the usual dielectric's 0.04; Ks 0 turns specular off; without
///   `Ks`, 0.04), times `map_Ks` (sRGB);
/// * `illum` 3 and 5: a mirror-like metal of colour `Ks` (white without it);
///   `illum` 4, 6, 7, 9: glass, refracting with index `Ni` (1.5 when absent or
///   below 1), tinted by `Tf`;
/// * `Ke` × `map_Ke`: emission (front faces); `map_Ke` without `Ke` emits the
///   map as radiance;
/// * `d` < 1 (or `Tr` > 0): stochastic transparency (blend); `map_d`: a cut-out
///   at 0.5 from the map's alpha (its red channel without alpha);
/// * `norm` (or `map_Bump`/`bump`, see [`load_obj_scene`](crate::load::obj::load_obj_scene)): a tangent-space
///   normal map with `-bm` scaling x and y.
pub fn material_from_mtl(m: &MtlMaterial, t: &MtlTextures) -> SurfaceMaterial {
    let kd =
        m.kd.unwrap_or(Vec3A::splat(DEFAULT_REFLECTANCE))
            .min(Vec3A::ONE);
    let roughness = m.pr.unwrap_or_else(|| m.ns.map_or(1.0, phong_roughness));
    let mirror = matches!(m.illum, Some(3 | 5));
    let glass = matches!(m.illum, Some(4 | 6 | 7 | 9));
    let ior = match m.ni {
        Some(n) if glass && n > 1.0 && n.is_finite() => n.min(4.0),
        _ => 1.5,
    };
    // F0 = 0.04 · specular_color at ior 1.5: 2 Ks gives 0.08 Ks.
    let f0_ior = ((ior - 1.0) / (ior + 1.0)).powi(2);
    let specular_color = match (glass, m.ks) {
        (false, Some(ks)) => ks * (0.08 / f0_ior),
        _ => Vec3A::ONE,
    };
    let mut g = GltfMaterial {
        base_color: kd.extend(m.dissolve.unwrap_or(1.0)),
        base_color_texture: t.kd,
        metallic: m.pm.unwrap_or(0.0),
        roughness,
        ior,
        specular_color,
        specular_color_texture: t.ks,
        normal_texture: t.normal.map(|(texture, _)| texture),
        normal_scale: t.normal.map_or(1.0, |(_, scale)| scale),
        roughness_texture: t.pr,
        metallic_texture: t.pm,
        alpha_texture: t.d.map(|(texture, _)| texture),
        alpha_from_red: t.d.is_some_and(|(_, has_alpha)| !has_alpha),
        ..GltfMaterial::default()
    };
    if mirror {
        g.base_color = m.ks.unwrap_or(Vec3A::ONE).min(Vec3A::ONE).extend(1.0);
        g.base_color_texture = None;
        g.metallic = 1.0;
        g.roughness = m.pr.unwrap_or_else(|| m.ns.map_or(0.0, phong_roughness));
    }
    if glass {
        g.base_color = m.tf.unwrap_or(Vec3A::ONE).extend(1.0);
        g.metallic = 0.0;
        g.transmission = 1.0;
        g.thin_walled = false;
        g.roughness = m.pr.unwrap_or_else(|| m.ns.map_or(0.0, phong_roughness));
    }
    let alpha = if t.d.is_some() {
        AlphaMode::Mask(0.5)
    } else if m.dissolve.is_some_and(|d| d < 1.0) && !glass {
        AlphaMode::Blend
    } else {
        AlphaMode::Opaque
    };
    let emission = match (m.ke, t.ke) {
        (Some(ke), _) => ke,
        (None, Some(_)) => Vec3A::ONE,
        (None, None) => Vec3A::ZERO,
    };
    SurfaceMaterial {
        name: m.name.clone(),
        reflectance: kd,
        kind: MaterialKind::Gltf(Box::new(g)),
        emission,
        emission_texture: if emission.max_element() > 0.0 {
            t.ke
        } else {
            None
        },
        emits_both_sides: false,
        alpha,
    }
}

#[cfg(test)]
mod tests {
    use std::collections::BTreeMap;
    use std::path::Path;

    use super::*;
    use crate::load::obj::mtl::parse_mtl;

    fn mtl(text: &str) -> MtlMaterial {
        let mut skipped = BTreeMap::new();
        parse_mtl(text, Path::new("m.mtl"), &mut skipped)
            .unwrap()
            .remove(0)
    }

    fn gltf(m: &SurfaceMaterial) -> &GltfMaterial {
        match &m.kind {
            MaterialKind::Gltf(g) => g,
            _ => panic!("not a metallic–roughness material"),
        }
    }

    #[test]
    fn mtl_statements_map_onto_the_gltf_material() {
        let none = MtlTextures::default();
        // Phong: Kd the base colour, Ks 0.5 the usual F0 of 0.04, Ns a roughness.
        let m = material_from_mtl(
            &mtl("newmtl p\nKd 0.8 0.2 0.1\nKs 0.5 0.5 0.5\nNs 98\n"),
            &none,
        );
        let g = gltf(&m);
        assert_eq!(g.base_color, Vec4::new(0.8, 0.2, 0.1, 1.0));
        assert_eq!((g.metallic, g.transmission), (0.0, 0.0));
        assert!((g.roughness - phong_roughness(98.0)).abs() < 1e-7);
        let f0 = ((g.ior - 1.0) / (g.ior + 1.0)).powi(2) * g.specular_color;
        assert!((f0 - Vec3A::splat(0.04)).abs().max_element() < 1e-6, "{f0}");
        assert_eq!(m.alpha, AlphaMode::Opaque);
        // Ks 0: no specular reflection.
        let m = material_from_mtl(&mtl("newmtl p\nKs 0 0 0\n"), &none);
        assert_eq!(gltf(&m).specular_color, Vec3A::ZERO);
        // PBR extension.
        let m = material_from_mtl(&mtl("newmtl m\nKd 1 0.8 0.3\nPm 1\nPr 0.25\n"), &none);
        assert_eq!((gltf(&m).metallic, gltf(&m).roughness), (1.0, 0.25));
        // Mirror and glass.
        let m = material_from_mtl(&mtl("newmtl m\nKs 0.9 0.9 0.9\nNs 10000\nillum 3\n"), &none);
        assert_eq!(gltf(&m).metallic, 1.0);
        assert_eq!(gltf(&m).base_color, Vec4::new(0.9, 0.9, 0.9, 1.0));
        assert!(gltf(&m).roughness < 0.12);
        let m = material_from_mtl(
            &mtl("newmtl g\nNi 1.33\nTf 1 0.9 0.8\nillum 7\nd 0.1\n"),
            &none,
        );
        let g = gltf(&m);
        assert_eq!((g.transmission, g.ior, g.thin_walled), (1.0, 1.33, false));
        assert_eq!(g.base_color.truncate(), glam::Vec3::new(1.0, 0.9, 0.8));
        assert_eq!(m.alpha, AlphaMode::Opaque, "a glass's d is not a cut-out");
        // Emission, dissolve and a cut-out.
        let m = material_from_mtl(&mtl("newmtl e\nKe 5 4 3\nd 0.5\n"), &none);
        assert_eq!(m.emission, Vec3A::new(5.0, 4.0, 3.0));
        assert_eq!(m.alpha, AlphaMode::Blend);
        assert_eq!(gltf(&m).base_color.w, 0.5);
        let cut = MtlTextures {
            d: Some((TextureRef::new(0), false)),
            ..MtlTextures::default()
        };
        let m = material_from_mtl(&mtl("newmtl c\n"), &cut);
        assert_eq!(m.alpha, AlphaMode::Mask(0.5));
        assert!(gltf(&m).alpha_from_red);
    }

    #[test]
    fn height_fields_become_normal_maps() {
        // A ramp rising to the right: normals lean left (−x), y stays 0.
        let w = 16;
        let texels: Vec<u8> = (0..w * w).map(|k| ((k % w) * 8) as u8).collect();
        let ramp = Image::from_u8(w as u32, w as u32, 1, texels);
        assert!(!looks_like_normal_map(&ramp));
        let n = height_to_normal_map(&ramp, 1.0);
        let t = n.texel(5, 7, ColorSpace::Linear);
        let slope = 8.0 / 255.0 * BUMP_SLOPE_SCALE;
        let want = Vec3::new(-slope, 0.0, 1.0).normalize() * 0.5 + Vec3::splat(0.5);
        assert!(
            (t.truncate() - want).abs().max_element() < 1.0 / 255.0,
            "{t} vs {want}"
        );
        assert!(looks_like_normal_map(&n));
    }

    #[test]
    fn bands_of_a_normal_map_join_without_seams() {
        // Every texel against the central differences taken texel by texel,
        // wrapping at the edges, on an image several bands tall whose height
        // is not a multiple of a band.
        let (w, h) = (23u32, 101u32);
        let mut state = 12345u32;
        let texels: Vec<u8> = (0..w * h * 3)
            .map(|_| {
                state = state.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
                (state >> 24) as u8
            })
            .collect();
        let image = Image::from_u8(w, h, 3, texels);
        let n = height_to_normal_map(&image, 0.7);
        let height = |x: i64, y: i64| {
            let t = image.texel(
                x.rem_euclid(i64::from(w)) as u32,
                y.rem_euclid(i64::from(h)) as u32,
                ColorSpace::Linear,
            );
            (t.x + t.y + t.z) / 3.0
        };
        let k = 0.5 * 0.7 * BUMP_SLOPE_SCALE;
        for y in 0..i64::from(h) {
            for x in 0..i64::from(w) {
                let du = (height(x + 1, y) - height(x - 1, y)) * k;
                let dv = (height(x, y - 1) - height(x, y + 1)) * k;
                let want = Vec3::new(-du, -dv, 1.0).normalize();
                let got = n.texel(x as u32, y as u32, ColorSpace::Linear).truncate();
                let want = (want * 0.5 + Vec3::splat(0.5)) * 255.0;
                assert_eq!(got * 255.0, want.round(), "texel ({x}, {y})");
            }
        }
    }
}
