//! The media inside glTF-style volumes that scatter light (glTF's
//! `KHR_materials_volume_scatter`, the Khronos draft of glTF pull request
//! 2453, on top of `KHR_materials_volume`; a scene file's `[[material]]`
//! with `subsurface`).
//!
//! A material with a volume (`thicknessFactor` > 0) and transmission
//! (`KHR_materials_transmission` or `KHR_materials_diffuse_transmission`)
//! bounds a homogeneous medium whose extinction is `KHR_materials_volume`'s
//! attenuation, `σt = −ln(attenuationColor) / attenuationDistance`. With
//! the scatter extension, a share of it scatters: the single-scattering
//! albedo is the one whose half-space shows `multiscatterColor`
//! ([`crate::media::albedo`]), with a Henyey–Greenstein phase function of
//! mean cosine `scatterAnisotropy`, and paths cross it by a random walk
//! ([`crate::media::Medium::subsurface`]). A diffusely transmitting
//! boundary (`diffuseTransmissionFactor` 1, no transmission) makes it dense
//! subsurface scattering (skin, wax, marble); a refracting one, murky water
//! or jade behind glass.
//!
//! Models without such a material get no media at all (the glTF volume's
//! absorption stays the path tracer's Beer–Lambert term, and images are as
//! before). With one, every volume material's inside becomes a medium
//! (absorbing only, without scattering), since the volumetric path tracer
//! renders the scene. A scattering volume must be closed: the triangles of
//! its materials may have no edge that an odd number of them use.

use std::collections::HashMap;

use glam::Vec3A;

use crate::materials::surface::{GltfMaterial, MaterialKind};
use crate::media::{Medium, Phase};
use crate::scene::{MediumInterface, SceneParts};

/// The glTF material behind `kind`, if it has a volume that light enters.
fn volume(kind: &MaterialKind) -> Option<&GltfMaterial> {
    match kind {
        MaterialKind::Gltf(g)
            if !g.thin_walled && (g.transmission > 0.0 || g.diffuse_transmission > 0.0) =>
        {
            Some(g)
        }
        _ => None,
    }
}

/// Gives every volume material of `parts` that has no interior medium
/// yet its medium, if any of them scatters (else changes nothing), after
/// checking that the scattering ones are closed; the error is one line.
pub(crate) fn add_volume_media(parts: &mut SceneParts) -> Result<(), String> {
    let media = &parts.media;
    let unbound = |m: usize| media.interface(m as u32).interior.is_none();
    let scatters: Vec<bool> = (parts.materials.iter().enumerate())
        .map(|(i, m)| unbound(i) && volume(&m.kind).is_some_and(|g| g.multiscatter_color.is_some()))
        .collect();
    if !scatters.contains(&true) {
        return Ok(());
    }
    check_closed(parts, |m| {
        scatters.get(m as usize).copied().unwrap_or(false)
    })?;
    let media = &mut parts.media;
    // (Overrides may have added materials since the interfaces were made.)
    media
        .interfaces
        .resize(parts.materials.len(), MediumInterface::default());
    for (i, m) in parts.materials.iter().enumerate() {
        if media.interfaces[i].interior.is_some() {
            continue;
        }
        let Some(g) = volume(&m.kind) else {
            continue;
        };
        let medium = match g.multiscatter_color {
            Some(rho) => Medium::subsurface(g.attenuation, rho, g.scatter_anisotropy),
            None if g.attenuation != Vec3A::ZERO => {
                Medium::homogeneous(g.attenuation, Vec3A::ZERO, Phase::Isotropic)
            }
            None => continue,
        };
        media.interfaces[i].interior = Some(media.media.len() as u32);
        media.media.push(medium);
    }
    Ok(())
}

/// Fills the model `parts` with `medium`: the interior of every one of its
/// materials (a material that bounds a medium already is refused), after
/// checking that its meshes are closed.
pub(crate) fn fill(parts: &mut SceneParts, medium: Medium) -> Result<(), String> {
    medium.check()?;
    if parts.triangles.is_empty() {
        return Err("the model has no triangles to hold it".into());
    }
    check_closed(parts, |_| true)?;
    let media = &mut parts.media;
    // (Overrides may have added materials since the interfaces were made.)
    media
        .interfaces
        .resize(parts.materials.len(), MediumInterface::default());
    let index = media.media.len() as u32;
    for (i, f) in media.interfaces.iter_mut().enumerate() {
        if f.interior.is_some() {
            return Err(format!(
                "its material \"{}\" bounds a medium already",
                crate::guard::one_line(&parts.materials[i].name)
            ));
        }
        f.interior = Some(index);
    }
    media.media.push(medium);
    Ok(())
}

/// Refuses a scattering volume whose triangles leave an edge open: an
/// edge (between positions welded by their bits) used by an odd number of
/// the triangles whose material `scatters`.
fn check_closed(parts: &SceneParts, scatters: impl Fn(u32) -> bool) -> Result<(), String> {
    let mut ids: HashMap<[u32; 3], u32> = HashMap::new();
    let mut edges: HashMap<(u32, u32), (u32, u32)> = HashMap::new();
    for (tri, &material) in parts.triangles.iter().zip(&parts.material_of) {
        if !scatters(material) {
            continue;
        }
        let [a, b, c] = tri.v.map(|p| {
            let next = ids.len() as u32;
            *ids.entry(p.to_array().map(f32::to_bits)).or_insert(next)
        });
        for (p, q) in [(a, b), (b, c), (c, a)] {
            if p != q {
                edges.entry((p.min(q), p.max(q))).or_insert((0, material)).0 += 1;
            }
        }
    }
    let open = edges.values().filter(|(n, _)| n % 2 == 1);
    if let Some(&(_, material)) = open.clone().next() {
        let name = &parts.materials[material as usize].name;
        let named = if name.is_empty() {
            "a material without a name".to_string()
        } else {
            format!("material \"{}\"", crate::guard::one_line(name))
        };
        return Err(format!(
            "{named} bounds a medium, which needs closed meshes, but {} of their edges \
             are open (used by an odd number of triangles)",
            open.count()
        ));
    }
    Ok(())
}
