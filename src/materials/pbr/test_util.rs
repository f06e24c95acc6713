//! Helpers shared by the glTF BSDF's tests: the materials they run over
//! (plain, transmitting, coated, sheened, filmed, diffusely transmitting,
//! anisotropic) and the χ² test of a list of cases.

use super::params::PbrBsdf;
use crate::materials::material::Material;
use crate::materials::test_util::{chi2_p_value, dir, sidak_threshold};
use glam::{Vec2, Vec3A};

/// All χ² tests of the glTF BSDF (the files of this folder), for the Šidák
/// correction.
pub(super) const CHI2_TESTS: u32 = 3 * 3 * 2 + 4 + 4 + 4 + 2 + 5 + 10 + 5;

pub(super) const COLOR: Vec3A = Vec3A::new(0.8, 0.5, 0.2);

/// A transmitting material with a refracting volume.
pub(super) fn volume(base: Vec3A, metallic: f32, roughness: f32, transmission: f32) -> PbrBsdf {
    PbrBsdf {
        transmission,
        thin_walled: false,
        ..PbrBsdf::new(base, metallic, roughness)
    }
}

/// A thin-walled transmitting material.
pub(super) fn thin(base: Vec3A, metallic: f32, roughness: f32, transmission: f32) -> PbrBsdf {
    PbrBsdf {
        transmission,
        ..PbrBsdf::new(base, metallic, roughness)
    }
}

pub(super) fn flip(w: Vec3A) -> Vec3A {
    Vec3A::new(w.x, w.y, -w.z)
}

/// Schlick's `F` for a grey `F0`, written out independently of the module.
pub(super) fn schlick1(f0: f32, cos: f32) -> f32 {
    f0 + (1.0 - f0) * (1.0 - cos).powi(5)
}

pub(super) fn chi2_cases(cases: &[(PbrBsdf, Vec3A, &str)], key: u64) {
    let mut min_p = 1.0f64;
    for (i, (p, wo, what)) in cases.iter().enumerate() {
        let pv = chi2_p_value(Material::Pbr(*p), *wo, key + i as u64);
        eprintln!("chi2 pbr {what}: p = {pv:.4}");
        assert!(pv > sidak_threshold(CHI2_TESTS), "{what}: p = {pv}, {p:?}");
        min_p = min_p.min(pv);
    }
    eprintln!("chi2 pbr: min p = {min_p:.4}");
}

/// `base` under a clear coat of weight `coat` and roughness
/// `coat_roughness`, its normal tilted by `tilt` degrees from the shading
/// normal.
pub(super) fn coated(base: PbrBsdf, coat: f32, coat_roughness: f32, tilt: f32) -> PbrBsdf {
    PbrBsdf {
        coat,
        coat_alpha: PbrBsdf::alpha_from_roughness(coat_roughness),
        coat_normal: dir(tilt, 1.1),
        ..base
    }
}

/// Coated materials: rough and smooth coats over rough, smooth, metal,
/// dielectric and transmitting bases, with straight and tilted coat
/// normals.
pub(super) fn coated_materials() -> Vec<PbrBsdf> {
    vec![
        coated(PbrBsdf::new(COLOR, 0.0, 0.5), 1.0, 0.2, 0.0),
        coated(PbrBsdf::new(COLOR, 1.0, 0.6), 0.7, 0.4, 20.0),
        coated(PbrBsdf::new(COLOR, 0.0, 0.7), 1.0, 0.0, 0.0),
        coated(PbrBsdf::new(COLOR, 0.3, 0.0), 0.5, 0.3, 10.0),
        coated(thin(COLOR, 0.0, 0.4, 0.6), 1.0, 0.1, 0.0),
        coated(volume(COLOR, 0.0, 0.3, 0.8), 1.0, 0.3, 15.0),
    ]
}

pub(super) fn sheened(base: PbrBsdf, color: Vec3A, roughness: f32) -> PbrBsdf {
    PbrBsdf {
        sheen_color: color,
        sheen_roughness: roughness,
        ..base
    }
}

/// Materials with a sheen: over rough and smooth dielectrics, a smooth
/// metal (the sheen its only non-delta lobe), a black base, thin and
/// volume transmission, and under a clear coat.
pub(super) fn sheened_materials() -> Vec<PbrBsdf> {
    let sheen = Vec3A::new(0.9, 0.4, 0.2);
    vec![
        sheened(PbrBsdf::new(COLOR, 0.0, 0.7), sheen, 0.5),
        sheened(PbrBsdf::new(COLOR, 1.0, 0.0), Vec3A::ONE, 0.3),
        sheened(PbrBsdf::new(Vec3A::ZERO, 0.0, 0.5), sheen, 1.0),
        sheened(thin(COLOR, 0.0, 0.4, 0.6), sheen, 0.2),
        sheened(volume(COLOR, 0.0, 0.3, 0.8), sheen, 0.8),
        coated(
            sheened(PbrBsdf::new(COLOR, 0.0, 0.6), sheen, 0.4),
            1.0,
            0.2,
            10.0,
        ),
    ]
}

/// The gold-like base colour of the iridescence tests.
pub(super) const GOLD: Vec3A = Vec3A::new(0.95, 0.64, 0.54);

/// `base` under a thin film (`KHR_materials_iridescence`) of weight
/// `iridescence`, index `ior` and thickness `d` nm.
pub(super) fn filmed(base: PbrBsdf, iridescence: f32, ior: f32, d: f32) -> PbrBsdf {
    PbrBsdf {
        iridescence,
        film_ior: ior,
        film_thickness: d,
        ..base
    }
}

/// Filmed materials: rough and smooth, metal, dielectric, mixed,
/// transmitting (thin-walled and a volume) and under a clear coat.
pub(super) fn iridescent_materials() -> Vec<PbrBsdf> {
    vec![
        filmed(PbrBsdf::new(COLOR, 0.0, 0.5), 1.0, 1.8, 350.0),
        filmed(PbrBsdf::new(GOLD, 1.0, 0.3), 1.0, 1.3, 500.0),
        filmed(PbrBsdf::new(COLOR, 0.4, 0.0), 0.7, 1.5, 250.0),
        filmed(thin(COLOR, 0.0, 0.4, 0.8), 1.0, 1.3, 550.0),
        filmed(volume(Vec3A::ONE, 0.0, 0.3, 1.0), 1.0, 1.3, 520.0),
        filmed(
            coated(PbrBsdf::new(COLOR, 0.2, 0.5), 1.0, 0.2, 0.0),
            1.0,
            1.3,
            400.0,
        ),
    ]
}

/// `base` with `KHR_materials_diffuse_transmission`'s share `dt` and
/// colour `color`.
pub(super) fn translucent(base: PbrBsdf, dt: f32, color: Vec3A) -> PbrBsdf {
    PbrBsdf {
        diffuse_transmission: dt,
        diffuse_transmission_color: color,
        ..base
    }
}

/// Diffusely transmitting materials: alone, smooth and rough, with
/// (thin-walled and volume) transmission, metal, and a coat.
pub(super) fn translucent_materials() -> Vec<PbrBsdf> {
    let warm = Vec3A::new(1.0, 0.6, 0.3);
    vec![
        translucent(PbrBsdf::new(COLOR, 0.0, 0.5), 0.6, warm),
        translucent(PbrBsdf::new(COLOR, 0.0, 0.0), 1.0, warm),
        translucent(PbrBsdf::new(COLOR, 0.4, 0.3), 0.5, Vec3A::ONE),
        translucent(thin(COLOR, 0.0, 0.4, 0.5), 0.7, warm),
        translucent(volume(COLOR, 0.0, 0.4, 0.3), 0.8, warm),
        translucent(volume(COLOR, 0.0, 0.5, 0.0), 0.5, warm),
        coated(
            translucent(PbrBsdf::new(COLOR, 0.0, 0.6), 0.5, warm),
            1.0,
            0.2,
            10.0,
        ),
    ]
}

/// `base` with `KHR_materials_anisotropy` of `strength`, its direction at
/// `angle` radians from the local `+x` (already in the shading frame).
pub(super) fn aniso(base: PbrBsdf, strength: f32, angle: f32) -> PbrBsdf {
    let (s, c) = angle.sin_cos();
    PbrBsdf {
        anisotropy: strength,
        anisotropy_direction: Vec2::new(c, s),
        ..base
    }
}

/// [`test_materials`] and every layered or extended set: the materials
/// the generic checks (bit-for-bit eval/pdf, weight = eval/pdf, sides,
/// degenerate inputs) run over.
pub(super) fn every_test_material() -> Vec<PbrBsdf> {
    let mut all = test_materials();
    all.extend(coated_materials());
    all.extend(sheened_materials());
    all.extend(iridescent_materials());
    all.extend(translucent_materials());
    all
}

pub(super) fn test_materials() -> Vec<PbrBsdf> {
    vec![
        PbrBsdf::new(COLOR, 0.0, 0.5),
        PbrBsdf::new(COLOR, 1.0, 0.2),
        PbrBsdf::new(COLOR, 0.3, 1.0),
        PbrBsdf::new(Vec3A::ZERO, 1.0, 0.3),
        PbrBsdf {
            ior: 1.8,
            specular: 0.5,
            specular_color: Vec3A::new(1.0, 0.5, 20.0),
            ..PbrBsdf::new(COLOR, 0.1, 0.4)
        },
        volume(Vec3A::ONE, 0.0, 0.3, 1.0),
        PbrBsdf {
            ior: 1.33,
            ..volume(COLOR, 0.2, 0.7, 0.5)
        },
        thin(COLOR, 0.0, 0.35, 0.8),
        // Smooth, with a diffuse part: mixed delta and non-delta lobes.
        PbrBsdf::new(COLOR, 0.3, 0.0),
        thin(COLOR, 0.0, 0.0, 0.5),
        volume(COLOR, 0.0, 0.0, 0.5),
        // Anisotropic: rough, rough mostly along the direction (α_b small),
        // transmitting, and under a coat.
        aniso(PbrBsdf::new(COLOR, 0.4, 0.4), 0.8, 0.6),
        aniso(PbrBsdf::new(COLOR, 1.0, 0.15), 0.7, -1.2),
        aniso(volume(COLOR, 0.0, 0.3, 0.9), 0.9, 2.0),
        aniso(thin(COLOR, 0.0, 0.3, 0.7), 0.5, 0.3),
        aniso(
            coated(PbrBsdf::new(COLOR, 1.0, 0.3), 1.0, 0.2, 10.0),
            1.0,
            0.9,
        ),
    ]
}
