//! A `[[model]]` loaded in its own frame (a glTF or OBJ file, or a built-in
//! box turned to +y up) and its placement in the world (fit, scale, rotate,
//! translate).

use std::ops::Range;
use std::path::Path;

use glam::{Affine3A, EulerRot, Quat, Vec3, Vec3A};

use super::error::{ShotError, check, invalid};
use super::schema::{ModelSection, Scale};
use crate::camera::{DepthOfField, Lens, SceneCamera};
use crate::lights::Light;
use crate::load::cornell;
use crate::load::error::LoadError;
use crate::scene::{PointLight, SceneParts};

/// A model's parts with named triangle ranges (the built-in box's parts).
pub(super) struct ModelParts {
    pub(super) parts: SceneParts,
    pub(super) named_ranges: Vec<(String, Range<usize>)>,
    pub(super) lab_camera: Option<SceneCamera>,
    pub(super) warnings: Vec<String>,
    /// A glTF model's material variants, and the one shown.
    pub(super) variants: Vec<String>,
    pub(super) variant: Option<String>,
    /// A glTF model's animations' names (empty for other models).
    pub(super) animations: Vec<String>,
}

/// Loads one model in its own frame.
pub(super) fn load_model(
    path: &Path,
    base: &Path,
    m: &ModelSection,
    index: usize,
    ledger: &crate::memory::Ledger,
    variant: &crate::load::gltf::VariantChoice,
    animation: &crate::load::gltf::AnimationOptions,
) -> Result<ModelParts, LoadError> {
    let is_gltf = m.file.as_ref().is_some_and(|f| {
        f.extension()
            .and_then(|e| e.to_str())
            .is_some_and(|e| e.eq_ignore_ascii_case("gltf") || e.eq_ignore_ascii_case("glb"))
    });
    if m.animation.is_some() && !is_gltf {
        return Err(invalid(
            path,
            format!(
                "[[model]] {}: animation picks a glTF model's animation; this model is not glTF",
                index + 1
            ),
        )
        .into());
    }
    if m.variant.is_some() && !is_gltf {
        return Err(invalid(
            path,
            format!(
                "[[model]] {}: variant picks a glTF model's material variant; this model is not glTF",
                index + 1
            ),
        )
        .into());
    }
    match (&m.file, &m.builtin) {
        (Some(_), Some(_)) | (None, None) => Err(invalid(
            path,
            format!("[[model]] {}: give either file or builtin", index + 1),
        )
        .into()),
        (None, Some(name)) => {
            let area = match name.as_str() {
                "cornell" => false,
                "cornell-area" => true,
                other => {
                    return Err(invalid(
                        path,
                        format!(
                            "[[model]] {}: unknown builtin '{other}' (cornell, cornell-area)",
                            index + 1
                        ),
                    )
                    .into());
                }
            };
            let mut parts = cornell::parts(area);
            // The box's key light becomes a point light of the shot.
            let power = parts.light.power;
            if power.max_element() > 0.0 {
                parts.lights.push(Light::Point {
                    position: parts.light.position,
                    intensity: power / (4.0 * std::f32::consts::PI),
                });
            }
            parts.light = PointLight::default();
            let named_ranges = cornell::PART_NAMES
                .iter()
                .map(|(n, r)| (n.to_string(), r.clone()))
                .collect();
            // The lab's camera: at (0, 0, −3) looking along +z, image down +y.
            let lab_camera = SceneCamera {
                name: "lab".into(),
                position: cornell::CAMERA_POSITION,
                rotation: glam::Mat3A::IDENTITY,
                lens: Lens::LAB,
                aspect_ratio: Some(1.0),
                depth_of_field: DepthOfField::default(),
                window: None,
            };
            parts.cameras.clear();
            // Turn the lab's y-down box to +y up: half a turn about z.
            let mut model = ModelParts {
                parts,
                named_ranges,
                lab_camera: Some(lab_camera),
                warnings: Vec::new(),
                variants: Vec::new(),
                variant: None,
                animations: Vec::new(),
            };
            let turn = Affine3A::from_rotation_z(std::f32::consts::PI);
            model.parts.transform(turn);
            if let Some(c) = &mut model.lab_camera {
                c.position = turn.transform_point3a(c.position);
                c.rotation = turn.matrix3 * c.rotation;
            }
            Ok(model)
        }
        (Some(file), None) => {
            let file = base.join(file);
            let ext = file
                .extension()
                .and_then(|e| e.to_str())
                .map(str::to_ascii_lowercase);
            match ext.as_deref() {
                Some("gltf" | "glb") => {
                    let g = crate::load::gltf::load_gltf_posed(&file, ledger, variant, animation)?;
                    Ok(ModelParts {
                        parts: g.parts,
                        named_ranges: Vec::new(),
                        lab_camera: None,
                        warnings: g.warnings,
                        variants: g.variants,
                        variant: g.variant,
                        animations: g.animations,
                    })
                }
                Some("obj") => {
                    let obj = crate::load::obj::load_obj_scene_with(&file, ledger)?;
                    Ok(ModelParts {
                        parts: obj.parts,
                        named_ranges: obj.named_parts,
                        lab_camera: None,
                        warnings: obj.warnings,
                        variants: Vec::new(),
                        variant: None,
                        animations: Vec::new(),
                    })
                }
                Some("xml") => {
                    let m = crate::load::mitsuba::load_mitsuba(&file, &[], ledger)?;
                    let mut warnings = m.warnings;
                    let mut parts = m.parts;
                    if !m.environment.is_black() {
                        warnings.push(format!(
                            "[[model]] {}: {}: its environment emitter is not part of a model and is left out (give the scene file an [environment])",
                            index + 1,
                            file.display()
                        ));
                    }
                    parts.cameras.extend(m.camera);
                    Ok(ModelParts {
                        parts,
                        named_ranges: Vec::new(),
                        lab_camera: None,
                        warnings,
                        variants: Vec::new(),
                        variant: None,
                        animations: Vec::new(),
                    })
                }
                _ => Err(invalid(
                    path,
                    format!(
                        "[[model]] {}: {} is neither glTF (.gltf, .glb), OBJ (.obj) nor a Mitsuba scene (.xml)",
                        index + 1,
                        file.display()
                    ),
                )
                .into()),
            }
        }
    }
}

/// The model's placement: fit, scale, rotate (x, y, z), translate.
pub(super) fn placement(
    path: &Path,
    m: &ModelSection,
    what: &str,
    parts: &SceneParts,
) -> Result<Affine3A, ShotError> {
    let mut to_world = Affine3A::IDENTITY;
    if let Some(h) = m.fit {
        if !(h.is_finite() && h > 0.0) {
            return Err(invalid(
                path,
                format!("{what} fit = {h}: expected a height > 0"),
            ));
        }
        let (lo, hi) = parts.triangles.iter().fold(
            (Vec3A::splat(f32::INFINITY), Vec3A::splat(f32::NEG_INFINITY)),
            |(lo, hi), t| (lo.min(t.min()), hi.max(t.max())),
        );
        let height = hi.y - lo.y;
        if !(height > 0.0 && height.is_finite()) {
            return Err(invalid(
                path,
                format!("{what}: fit needs a model with some height"),
            ));
        }
        let s = h / height;
        let centre = (lo + hi) * 0.5;
        to_world = Affine3A::from_scale(Vec3::splat(s))
            * Affine3A::from_translation(Vec3::new(-centre.x, -lo.y, -centre.z));
    }
    if let Some(scale) = &m.scale {
        let s = match *scale {
            Scale::Uniform(s) => [s; 3],
            Scale::PerAxis(s) => s,
        };
        check(path, &format!("{what} scale"), &s, false)?;
        if s.contains(&0.0) {
            return Err(invalid(path, format!("{what} scale: {s:?} has a zero")));
        }
        to_world = Affine3A::from_scale(Vec3::from(s)) * to_world;
    }
    if let Some(r) = m.rotate {
        check(path, &format!("{what} rotate"), &r, false)?;
        let [x, y, z] = r.map(f32::to_radians);
        // x first, then y, then z: R = Rz · Ry · Rx.
        let q = Quat::from_euler(EulerRot::ZYX, z, y, x);
        to_world = Affine3A::from_quat(q) * to_world;
    }
    if let Some(t) = m.translate {
        check(path, &format!("{what} translate"), &t, false)?;
        to_world = Affine3A::from_translation(Vec3::from(t)) * to_world;
    }
    Ok(to_world)
}
