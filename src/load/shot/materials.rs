//! Materials of a scene file: a `[[material]]` as a scene material, and the
//! material a model's override names (a `[[material]]` or a preset).

use std::collections::BTreeMap;
use std::path::Path;

use glam::Vec3A;

use super::error::{ShotError, check, invalid};
use super::schema::MaterialSection;
use crate::load::cornell::MaterialChoice;
use crate::materials::Material;
use crate::materials::surface::{GltfMaterial, MaterialKind, SurfaceMaterial};

/// A `[[material]]` as a scene material.
pub(super) fn file_material(
    path: &Path,
    m: &MaterialSection,
) -> Result<SurfaceMaterial, ShotError> {
    let what = format!("[[material]] '{}'", m.name);
    let base = m.base_color.unwrap_or([0.8; 3]);
    check(path, &format!("{what} base_color"), &base, true)?;
    let unit = |key: &str, v: Option<f32>, default: f32| -> Result<f32, ShotError> {
        let v = v.unwrap_or(default);
        if !(0.0..=1.0).contains(&v) {
            return Err(invalid(
                path,
                format!("{what} {key} = {v}: expected 0 to 1"),
            ));
        }
        Ok(v)
    };
    let ior = m.ior.unwrap_or(1.5);
    if !(1.0..=4.0).contains(&ior) {
        return Err(invalid(
            path,
            format!("{what} ior = {ior}: expected 1 to 4"),
        ));
    }
    let emission = m.emission.unwrap_or([0.0; 3]);
    check(path, &format!("{what} emission"), &emission, true)?;
    let transmission = unit("transmission", m.transmission, 0.0)?;
    let mut gltf = GltfMaterial {
        base_color: Vec3A::from(base).extend(1.0),
        metallic: unit("metallic", m.metallic, 0.0)?,
        roughness: unit("roughness", m.roughness, 0.5)?,
        ior,
        transmission,
        // A transmitting material is a solid: it refracts.
        thin_walled: false,
        ..GltfMaterial::default()
    };
    if let Some(mfp) = m.subsurface {
        if !mfp.iter().all(|d| d.is_finite() && *d > 0.0) {
            return Err(invalid(
                path,
                format!("{what} subsurface = {mfp:?}: expected mean free paths > 0"),
            ));
        }
        let g = m.subsurface_anisotropy.unwrap_or(0.0);
        if !(-0.99..=0.99).contains(&g) {
            return Err(invalid(
                path,
                format!("{what} subsurface_anisotropy = {g}: expected -0.99 to 0.99"),
            ));
        }
        // Light enters by a Lambertian lobe (unless it refracts in) and
        // walks inside (`crate::load::volumes`).
        if transmission == 0.0 {
            gltf.diffuse_transmission = 1.0;
        }
        gltf.attenuation = Vec3A::ONE / Vec3A::from(mfp);
        gltf.multiscatter_color = Some(Vec3A::from(base).min(Vec3A::ONE));
        gltf.scatter_anisotropy = g;
    } else if m.subsurface_anisotropy.is_some() {
        return Err(invalid(
            path,
            format!("{what}: subsurface_anisotropy without subsurface"),
        ));
    }
    Ok(SurfaceMaterial {
        name: m.name.clone(),
        reflectance: Vec3A::from(base).min(Vec3A::ONE),
        kind: MaterialKind::Gltf(Box::new(gltf)),
        emission: Vec3A::from(emission),
        emission_texture: None,
        emits_both_sides: false,
        alpha: crate::materials::surface::AlphaMode::Opaque,
    })
}

/// The material an override names: a `[[material]]` or a preset.
pub(super) fn override_material(
    path: &Path,
    spec: &str,
    defined: &BTreeMap<String, SurfaceMaterial>,
    old: &SurfaceMaterial,
) -> Result<SurfaceMaterial, ShotError> {
    if let Some(m) = defined.get(spec) {
        return Ok(m.clone());
    }
    let choice = MaterialChoice::parse(spec).map_err(|e| {
        invalid(
            path,
            format!("material override '{spec}': {e}, or the name of a [[material]]"),
        )
    })?;
    let bsdf = match choice {
        MaterialChoice::Diffuse => Material::Diffuse {
            reflectance: old.reflectance,
        },
        MaterialChoice::Other(m) => m,
    };
    Ok(SurfaceMaterial {
        kind: MaterialKind::Fixed(bsdf),
        ..old.clone()
    })
}
