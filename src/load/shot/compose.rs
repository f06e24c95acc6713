//! A scene file composed into scene parts ([`Shot`]): its models loaded,
//! placed and their materials overridden, its lights added, its camera and
//! environment checked, its glTF models posed and their material variants
//! shown as the command line and the file ask.

use std::collections::BTreeMap;
use std::ops::Range;
use std::path::Path;

use glam::Vec3A;

use super::camera::{ShotCamera, camera};
use super::error::{ShotError, check, invalid};
use super::materials::{file_material, override_material};
use super::model::{load_model, placement};
use super::schema::{
    AnimationKey, EnvironmentSection, LightSection, MediumSection, ModelSection, Scale, ShotFile,
    parse,
};
use super::settings::{ShotSettings, settings};
use crate::camera::SceneCamera;
use crate::geometry::triangle::Triangle;
use crate::lights::Light;
use crate::load::error::LoadError;
use crate::load::gltf::AnimationOptions;
use crate::materials::surface::SurfaceMaterial;
use crate::media::Phase;
use crate::media::phase::MAX_G;
use crate::scene::{PointLight, SceneParts};

/// A scene file read and composed into scene parts.
#[derive(Clone, Debug)]
pub struct Shot {
    /// Everything, in world space.
    pub parts: SceneParts,
    /// The camera.
    pub camera: ShotCamera,
    /// The lab box's camera, if the first model is a built-in box (placed).
    pub box_camera: Option<SceneCamera>,
    /// The environment section (paths resolved against the file's folder).
    pub environment: Option<EnvironmentSection>,
    /// Render settings.
    pub settings: ShotSettings,
    /// Whether any light was given or came from a model (punctual lights and
    /// area quads; emitting materials are counted by the scene).
    pub has_lights: bool,
    /// Things worth telling the user.
    pub warnings: Vec<String>,
    /// The material variants of the glTF models (each name once, in the
    /// models' order).
    pub variants: Vec<String>,
    /// The `--variant` shown, when one was asked for (the models' own
    /// `variant` keys are not listed here).
    pub variant: Option<String>,
    /// The glTF models' animations' names (each once, in the models'
    /// order): empty when no model is animated.
    pub animations: Vec<String>,
}

/// Reads and composes a scene file: loads its models, places them, applies
/// material overrides, adds its lights. The environment is returned as
/// written (the caller loads it, so that the command line can replace it).
pub fn load_shot(path: &Path) -> Result<Shot, LoadError> {
    load_shot_with(path, &crate::memory::Ledger::unlimited())
}

/// [`load_shot`], charging the models' decoded textures to `ledger` before
/// decoding them.
pub fn load_shot_with(path: &Path, ledger: &crate::memory::Ledger) -> Result<Shot, LoadError> {
    load_shot_variant(path, ledger, None)
}

/// [`load_shot_with`] with the command line's `--variant`: every glTF model
/// that has a material variant of that name shows it (whatever its own
/// `variant` key says); a scene none of whose models has it is refused, with
/// the names they have.
pub fn load_shot_variant(
    path: &Path,
    ledger: &crate::memory::Ledger,
    variant: Option<&str>,
) -> Result<Shot, LoadError> {
    let text = std::fs::read_to_string(path).map_err(|cause| ShotError::Io {
        path: path.to_owned(),
        cause,
    })?;
    let file = parse(&text, path)?;
    compose_posed(file, path, ledger, variant, &AnimationOptions::default())
}

/// [`load_shot_variant`] with the command line's `--at` and `--animation`
/// (`animation`): see [`compose_posed`].
pub fn load_shot_posed(
    path: &Path,
    ledger: &crate::memory::Ledger,
    variant: Option<&str>,
    animation: &AnimationOptions,
) -> Result<Shot, LoadError> {
    let text = std::fs::read_to_string(path).map_err(|cause| ShotError::Io {
        path: path.to_owned(),
        cause,
    })?;
    let file = parse(&text, path)?;
    compose_posed(file, path, ledger, variant, animation)
}

/// Composes a parsed scene file (`path` locates relative paths).
pub fn compose(file: ShotFile, path: &Path) -> Result<Shot, LoadError> {
    compose_with(file, path, &crate::memory::Ledger::unlimited())
}

/// [`compose`], charging the models' decoded textures to `ledger`.
pub fn compose_with(
    file: ShotFile,
    path: &Path,
    ledger: &crate::memory::Ledger,
) -> Result<Shot, LoadError> {
    compose_variant(file, path, ledger, None)
}

/// [`compose_with`] with the command line's `--variant` (see
/// [`load_shot_variant`]).
pub fn compose_variant(
    file: ShotFile,
    path: &Path,
    ledger: &crate::memory::Ledger,
    variant: Option<&str>,
) -> Result<Shot, LoadError> {
    compose_posed(file, path, ledger, variant, &AnimationOptions::default())
}

/// [`compose_variant`] posing the glTF models' animations. The merge, as
/// for `[render]`: the command line's `--at` (`animation.time`) replaces
/// the file's `[render] at`, its `--animation` every model's `animation`.
/// A moment poses each glTF model that has animations by its chosen one
/// (default: its first) and leaves the others as written; a model's own
/// `animation` must name one of its file's. A file that asks for a moment
/// or an animation when no model is animated is refused.
pub fn compose_posed(
    file: ShotFile,
    path: &Path,
    ledger: &crate::memory::Ledger,
    variant: Option<&str>,
    animation: &AnimationOptions,
) -> Result<Shot, LoadError> {
    use crate::load::gltf::VariantChoice;
    let base = path.parent().unwrap_or(Path::new("")).to_path_buf();
    let settings = settings(path, &file.render)?;
    let time = animation.time.or(settings.at);
    let mut animations: Vec<String> = Vec::new();
    let mut defined = BTreeMap::new();
    for m in &file.materials {
        if defined
            .insert(m.name.clone(), file_material(path, m)?)
            .is_some()
        {
            return Err(
                invalid(path, format!("[[material]] '{}' is defined twice", m.name)).into(),
            );
        }
    }
    let volumes = (file.media.iter()).any(|m| matches!(m, MediumSection::Vdb { .. }));
    if file.models.is_empty() && file.lights.is_empty() && !volumes {
        return Err(invalid(
            path,
            "no [[model]], no [[light]] and no .vdb [[medium]]: nothing to render".into(),
        )
        .into());
    }
    let MediaSections {
        fog,
        mut inside,
        vdbs,
    } = media_sections(path, &file.media)?;
    let mut settings = settings;
    settings.fog = fog;
    let mut all = SceneParts {
        two_sided: true,
        ..SceneParts::default()
    };
    let mut warnings = Vec::new();
    let mut variants: Vec<String> = Vec::new();
    let mut shown_variant = false;
    let mut box_camera = None;
    // Per model: its name and the range of its cameras in `all.cameras`.
    let mut model_cameras: Vec<(String, std::ops::Range<usize>)> = Vec::new();
    for (index, m) in file.models.iter().enumerate() {
        let name = m
            .name
            .clone()
            .unwrap_or_else(|| match (&m.file, &m.builtin) {
                (Some(f), _) => f.display().to_string(),
                (_, Some(b)) => b.clone(),
                _ => format!("model {}", index + 1),
            });
        let what = format!("[[model]] '{name}'");
        // The command line's variant wins over the model's own (option
        // merging as for [render]); it applies to the models that have it.
        let choice = match (variant, &m.variant) {
            (Some(v), _) => VariantChoice::IfDefined(v.to_string()),
            (None, Some(v)) => VariantChoice::Named(v.clone()),
            (None, None) => VariantChoice::Default,
        };
        let own = m.animation.as_ref().map(AnimationKey::choice);
        let posed = AnimationOptions {
            animation: animation.animation.clone().or(own),
            time,
            // A model's own choice must be there; a moment alone (or the
            // command line's choice) poses the models that have animations.
            if_animated: m.animation.is_none(),
        };
        let mut model = load_model(path, &base, m, index, ledger, &choice, &posed)?;
        warnings.append(&mut model.warnings);
        for a in model.animations.drain(..) {
            if !animations.contains(&a) {
                animations.push(a);
            }
        }
        for v in model.variants.drain(..) {
            if !variants.contains(&v) {
                variants.push(v);
            }
        }
        shown_variant |= model.variant.is_some();
        // Overrides: "*" for the whole model, a part name, else every material
        // of that name.
        for (target, spec) in &m.materials {
            if target == "*" {
                for k in 0..model.parts.materials.len() {
                    let new = override_material(path, spec, &defined, &model.parts.materials[k])?;
                    model.parts.materials[k] = new;
                }
                continue;
            }
            let ranges: Vec<Range<usize>> = model
                .named_ranges
                .iter()
                .filter(|(n, _)| n == target)
                .map(|(_, r)| r.clone())
                .collect();
            if !ranges.is_empty() {
                // One new material per original one in the part.
                let mut replaced: BTreeMap<u32, u32> = BTreeMap::new();
                for prim in ranges.into_iter().flatten() {
                    let old = model.parts.material_of[prim];
                    let new = match replaced.get(&old) {
                        Some(&m) => m,
                        None => {
                            let m = override_material(
                                path,
                                spec,
                                &defined,
                                &model.parts.materials[old as usize],
                            )?;
                            model.parts.materials.push(m);
                            let id = model.parts.materials.len() as u32 - 1;
                            replaced.insert(old, id);
                            id
                        }
                    };
                    model.parts.material_of[prim] = new;
                }
                continue;
            }
            let mut found = false;
            for k in 0..model.parts.materials.len() {
                if model.parts.materials[k].name == *target {
                    let new = override_material(path, spec, &defined, &model.parts.materials[k])?;
                    model.parts.materials[k] = new;
                    found = true;
                }
            }
            if !found {
                let mut names: Vec<String> = model
                    .named_ranges
                    .iter()
                    .map(|(n, _)| n.clone())
                    .chain(model.parts.materials.iter().map(|m| m.name.clone()))
                    .filter(|n| !n.is_empty())
                    .collect();
                names.dedup();
                return Err(invalid(
                    path,
                    format!(
                        "{what}: no material or part named '{target}' (it has: {})",
                        if names.is_empty() {
                            "none".into()
                        } else {
                            names.join(", ")
                        }
                    ),
                )
                .into());
            }
        }
        let to_world = placement(path, m, &what, &model.parts)?;
        model.parts.transform(to_world);
        // Subsurface [[material]]s given to the model (their mean free
        // paths are in scene units, so after the placement).
        crate::load::volumes::add_volume_media(&mut model.parts)
            .map_err(|e| invalid(path, format!("{what}: {e}")))?;
        if let Some(medium) = inside.remove(&name) {
            crate::load::volumes::fill(&mut model.parts, medium)
                .map_err(|e| invalid(path, format!("{what}: [[medium]] inside it: {e}")))?;
        }
        if let Some(mut c) = model.lab_camera.take()
            && index == 0
        {
            let mut one = SceneParts {
                cameras: vec![c.clone()],
                ..SceneParts::default()
            };
            one.transform(to_world);
            c = one.cameras.remove(0);
            box_camera = Some(c);
        }
        let start = all.cameras.len();
        model_cameras.push((name, start..start + model.parts.cameras.len()));
        all.append(model.parts);
    }
    for v in &vdbs {
        all.append(vdb_parts(path, &base, v, ledger)?);
    }
    if let Some(model) = inside.keys().next() {
        return Err(invalid(
            path,
            format!("[[medium]] inside '{model}': no [[model]] of that name"),
        )
        .into());
    }
    let mut has_lights = !all.lights.is_empty();
    for (i, l) in file.lights.iter().enumerate() {
        let what = format!("[[light]] {}", i + 1);
        has_lights = true;
        let color = |c: Option<[f32; 3]>| -> Result<Vec3A, ShotError> {
            let c = c.unwrap_or([1.0; 3]);
            check(path, &format!("{what} color"), &c, true)?;
            Ok(Vec3A::from(c))
        };
        // Emission beyond the environment's ceiling (1e20, 10^13 suns) only
        // makes estimates overflow (found by fuzzing: a colour of 0.91e38).
        let bounded = |key: &str, v: Vec3A| -> Result<Vec3A, ShotError> {
            let most = crate::lights::environment::MAX_RADIANCE;
            if v.max_element() > most || !v.is_finite() {
                return Err(invalid(
                    path,
                    format!("{what}: {key} {:e} is more than {most:e}", v.max_element()),
                ));
            }
            Ok(v)
        };
        match l {
            LightSection::Point {
                position,
                intensity,
                color: c,
            } => {
                check(path, &format!("{what} position"), position, false)?;
                check(path, &format!("{what} intensity"), &[*intensity], true)?;
                all.lights.push(Light::Point {
                    position: Vec3A::from(*position),
                    intensity: bounded("intensity × color", *intensity * color(*c)?)?,
                });
            }
            LightSection::Spot {
                position,
                target,
                direction,
                intensity,
                color: c,
                inner,
                outer,
            } => {
                check(path, &format!("{what} position"), position, false)?;
                check(path, &format!("{what} intensity"), &[*intensity], true)?;
                let p = Vec3A::from(*position);
                let axis = match (target, direction) {
                    (Some(t), None) => Vec3A::from(*t) - p,
                    (None, Some(d)) => Vec3A::from(*d),
                    _ => {
                        return Err(invalid(
                            path,
                            format!("{what}: give either target or direction"),
                        )
                        .into());
                    }
                }
                .normalize_or_zero();
                if axis == Vec3A::ZERO || !axis.is_finite() {
                    return Err(
                        invalid(path, format!("{what}: the spot's axis has no direction")).into(),
                    );
                }
                let inner = inner.unwrap_or(0.0);
                if !(0.0..=90.0).contains(outer) || !(0.0..=*outer).contains(&inner) {
                    return Err(invalid(
                        path,
                        format!("{what}: expected 0 <= inner <= outer <= 90 degrees, got {inner} and {outer}"),
                    )
                    .into());
                }
                all.lights.push(Light::Spot {
                    position: p,
                    direction: axis,
                    intensity: bounded("intensity × color", *intensity * color(*c)?)?,
                    cos_inner: inner.to_radians().cos(),
                    cos_outer: outer.to_radians().cos(),
                });
            }
            LightSection::Directional {
                direction,
                irradiance,
                color: c,
            } => {
                check(path, &format!("{what} irradiance"), &[*irradiance], true)?;
                let d = Vec3A::from(*direction).normalize_or_zero();
                if d == Vec3A::ZERO || !d.is_finite() {
                    return Err(invalid(path, format!("{what}: direction has no length")).into());
                }
                all.lights.push(Light::Directional {
                    direction: d,
                    irradiance: bounded("irradiance × color", *irradiance * color(*c)?)?,
                });
            }
            LightSection::Area {
                corner,
                u,
                v,
                radiance,
                two_sided,
            } => {
                for (key, x) in [("corner", corner), ("u", u), ("v", v)] {
                    check(path, &format!("{what} {key}"), x, false)?;
                }
                check(path, &format!("{what} radiance"), radiance, true)?;
                let (a, u, v) = (Vec3A::from(*corner), Vec3A::from(*u), Vec3A::from(*v));
                let normal = u.cross(v).normalize_or_zero();
                if normal == Vec3A::ZERO || !normal.is_finite() {
                    return Err(invalid(path, format!("{what}: u and v span no area")).into());
                }
                let mut m = SurfaceMaterial::diffuse(Vec3A::ZERO);
                m.name = what.clone();
                m.emission = bounded("radiance", Vec3A::from(*radiance))?;
                m.emits_both_sides = two_sided.unwrap_or(false);
                all.materials.push(m);
                let material = all.materials.len() as u32 - 1;
                for t in [
                    Triangle::new(a, a + u, a + u + v),
                    Triangle::new(a, a + u + v, a + v),
                ] {
                    all.triangles.push(t);
                    all.normals.push(normal);
                    all.material_of.push(material);
                    if !all.instance_of.is_empty() {
                        all.instance_of.push(crate::scene::NO_INSTANCE);
                    }
                }
            }
        }
    }
    // The first point light is the key light (`direct`'s, the viewer's).
    if let Some(i) = all
        .lights
        .iter()
        .position(|l| matches!(l, Light::Point { .. }))
        && let Light::Point {
            position,
            intensity,
        } = all.lights.remove(i)
    {
        all.light = PointLight {
            position,
            power: intensity * (4.0 * std::f32::consts::PI),
        };
    }
    let camera = match &file.camera {
        None => ShotCamera::Default,
        Some(c) => ShotCamera::Placed(camera(path, c, &model_cameras, &all.cameras)?),
    };
    let environment = file.environment.map(|mut e| {
        e.file = e.file.map(|f| base.join(f));
        e
    });
    if let Some(e) = &environment {
        if e.file.is_some() && e.color.is_some() {
            return Err(invalid(path, "[environment]: give file or color, not both".into()).into());
        }
        if let Some(c) = e.color {
            check(path, "[environment] color", &c, true)?;
        }
        if let Some(s) = e.strength {
            check(path, "[environment] strength", &[s], true)?;
            let most = crate::lights::environment::MAX_STRENGTH;
            if s > most {
                return Err(invalid(
                    path,
                    format!("[environment] strength = {s:?}: expected at most {most:e}"),
                )
                .into());
            }
        }
        if let Some(r) = e.rotate {
            check(path, "[environment] rotate", &[r], false)?;
        }
    }
    let asked = time.is_some()
        || animation.animation.is_some()
        || file.render.fps.is_some()
        || file.models.iter().any(|m| m.animation.is_some());
    if asked && animations.is_empty() {
        let what = match (animation.time, settings.at) {
            (Some(t), _) => format!("--at {t}"),
            (None, Some(t)) => format!("[render] at = {t}"),
            (None, None) if animation.animation.is_some() => "--animation".to_string(),
            (None, None) => "[render] fps".to_string(),
        };
        return Err(invalid(
            path,
            format!("{what} poses glTF models' animations; no model of this scene has one"),
        )
        .into());
    }
    if let Some(v) = variant
        && !shown_variant
    {
        let names = match variants.is_empty() {
            true => "the models have no material variants".to_string(),
            false => format!("variants: {}", variants.join(", ")),
        };
        return Err(invalid(
            path,
            format!("--variant '{v}': no model has a material variant of that name ({names})"),
        )
        .into());
    }
    Ok(Shot {
        parts: all,
        camera,
        box_camera,
        environment,
        settings,
        has_lights,
        warnings,
        variants,
        variant: variant.map(str::to_string),
        animations,
    })
}

/// The `[[medium]]` sections checked (at most one fog, one medium inside
/// a model).
fn media_sections(path: &Path, sections: &[MediumSection]) -> Result<MediaSections, ShotError> {
    let mut fog = None;
    let mut inside = BTreeMap::new();
    let mut vdbs = Vec::new();
    for (i, m) in sections.iter().enumerate() {
        let what = format!("[[medium]] {}", i + 1);
        let (sigma_t, color, anisotropy) = match m {
            MediumSection::Fog {
                density,
                color,
                anisotropy,
            }
            | MediumSection::Inside {
                density,
                color,
                anisotropy,
                ..
            } => (
                match density {
                    Scale::Uniform(d) => Vec3A::splat(*d),
                    Scale::PerAxis(d) => Vec3A::from(*d),
                },
                color,
                anisotropy,
            ),
            MediumSection::Vdb {
                density,
                color,
                anisotropy,
                ..
            } => (Vec3A::splat(*density), color, anisotropy),
        };
        check(path, &format!("{what} density"), &sigma_t.to_array(), true)?;
        let albedo = color.unwrap_or([1.0; 3]);
        if !albedo.iter().all(|a| (0.0..=1.0).contains(a)) {
            return Err(invalid(
                path,
                format!("{what} color = {albedo:?}: each channel is an albedo from 0 to 1"),
            ));
        }
        let g = anisotropy.unwrap_or(0.0);
        if !(-MAX_G..=MAX_G).contains(&g) {
            return Err(invalid(
                path,
                format!("{what} anisotropy = {g}: expected -{MAX_G} to {MAX_G}"),
            ));
        }
        let phase = Phase::of_mean_cosine(g);
        let albedo3 = Vec3A::from(albedo);
        // What it emits with, checked: a medium emits σa Le per unit
        // length, so one that absorbs nothing where it emits is an error.
        let emits = |le: Vec3A, name: &str| -> Result<(), ShotError> {
            check(path, &format!("{what} {name}"), &le.to_array(), true)?;
            if le != Vec3A::ZERO && !(le.cmpgt(Vec3A::ZERO) & albedo3.cmplt(Vec3A::ONE)).any() {
                return Err(invalid(
                    path,
                    format!(
                        "{what}: {name} needs absorption (a medium emits absorption x emission per unit length): set a color below 1"
                    ),
                ));
            }
            Ok(())
        };
        // `emission_scale`, checked (default 1).
        let scale_of = |s: &Option<f32>| -> Result<f32, ShotError> {
            let s = s.unwrap_or(1.0);
            check(path, &format!("{what} emission_scale"), &[s], true)?;
            Ok(s)
        };
        let both = || {
            invalid(
                path,
                format!("{what}: emission and temperature both given (one or the other)"),
            )
        };
        match m {
            MediumSection::Fog { .. } => {
                if fog.is_some() {
                    return Err(invalid(path, format!("{what}: a second fog")));
                }
                fog = Some((sigma_t, Vec3A::from(albedo), phase));
            }
            MediumSection::Vdb {
                file,
                grid,
                scale,
                rotate,
                translate,
                emission,
                temperature,
                temperature_scale,
                temperature_offset,
                emission_scale,
                ..
            } => {
                let emission_scale = scale_of(emission_scale)?;
                let glow = match (emission, temperature) {
                    (Some(_), Some(_)) => return Err(both()),
                    (Some(le), None) => {
                        let le = Vec3A::from(*le) * emission_scale;
                        emits(le, "emission")?;
                        Some(VdbGlow::Radiance(le))
                    }
                    (None, Some(grid)) => {
                        let t_scale = temperature_scale.unwrap_or(1.0);
                        let offset = temperature_offset.unwrap_or(0.0);
                        check(path, &format!("{what} temperature_scale"), &[t_scale], true)?;
                        check(
                            path,
                            &format!("{what} temperature_offset"),
                            &[offset],
                            false,
                        )?;
                        emits(Vec3A::splat(emission_scale), "temperature")?;
                        Some(VdbGlow::Temperature {
                            grid: grid.clone(),
                            offset,
                            t_scale,
                            scale: emission_scale,
                        })
                    }
                    (None, None) => {
                        if temperature_scale.is_some() || temperature_offset.is_some() {
                            return Err(invalid(
                                path,
                                format!(
                                    "{what}: temperature_scale or temperature_offset without temperature"
                                ),
                            ));
                        }
                        None
                    }
                };
                let placed = ModelSection {
                    scale: scale.clone(),
                    rotate: *rotate,
                    translate: *translate,
                    ..ModelSection::default()
                };
                let to_world = placement(path, &placed, &what, &SceneParts::default())?;
                vdbs.push(VdbMedium {
                    what,
                    file: file.clone(),
                    grid: grid.clone(),
                    density: sigma_t.x,
                    albedo: Vec3A::from(albedo),
                    phase,
                    to_world,
                    glow,
                });
            }
            MediumSection::Inside {
                model,
                emission,
                temperature,
                emission_scale,
                ..
            } => {
                let mut medium =
                    crate::media::Medium::homogeneous(sigma_t, Vec3A::from(albedo), phase);
                let scale = scale_of(emission_scale)?;
                let le = match (emission, temperature) {
                    (Some(_), Some(_)) => return Err(both()),
                    (Some(le), None) => Some((Vec3A::from(*le) * scale, "emission")),
                    (None, Some(kelvin)) => {
                        check(path, &format!("{what} temperature"), &[*kelvin], true)?;
                        let le = crate::materials::blackbody::blackbody_color(*kelvin);
                        Some((le * scale, "temperature"))
                    }
                    (None, None) => None,
                };
                if let (Some((le, name)), crate::media::Medium::Homogeneous(h)) = (le, &mut medium)
                {
                    emits(le, name)?;
                    h.emission = le;
                }
                if inside.insert(model.clone(), medium).is_some() {
                    return Err(invalid(
                        path,
                        format!("{what}: a second medium inside '{model}'"),
                    ));
                }
            }
        }
    }
    Ok(MediaSections { fog, inside, vdbs })
}

/// A `[[medium]] type = "vdb"`, checked and placed.
struct VdbMedium {
    /// `[[medium]] N`, for messages.
    what: String,
    file: std::path::PathBuf,
    grid: Option<String>,
    density: f32,
    albedo: Vec3A,
    phase: Phase,
    to_world: glam::Affine3A,
    glow: Option<VdbGlow>,
}

/// What a `.vdb` volume emits with (`Le`, scaled).
enum VdbGlow {
    /// A constant radiance.
    Radiance(Vec3A),
    /// A blackbody at the temperature of a grid of the file.
    Temperature {
        grid: String,
        offset: f32,
        t_scale: f32,
        scale: f32,
    },
}

/// The `[[medium]]` sections checked.
struct MediaSections {
    /// The fog: extinction, albedo, phase function.
    fog: Option<(Vec3A, Vec3A, Phase)>,
    /// The media inside models, by model name.
    inside: BTreeMap<String, crate::media::Medium>,
    /// The `.vdb` volumes.
    vdbs: Vec<VdbMedium>,
}

/// A `.vdb` volume as scene parts: the grid's medium inside an
/// index-matched box around the grid's world bounds.
fn vdb_parts(
    path: &Path,
    base: &Path,
    v: &VdbMedium,
    ledger: &crate::memory::Ledger,
) -> Result<SceneParts, ShotError> {
    use crate::materials::Material;
    use crate::media::{Emission, Field, FieldValues, Heterogeneous, Medium};
    use crate::scene::{MediumInterface, SceneMedia};
    let vdb = crate::load::vdb::read_vdb(&base.join(&v.file), v.grid.as_deref(), ledger)
        .map_err(|e| invalid(path, format!("{}: {e}", v.what)))?;
    let sigma_t = Field::sparse(vdb.grid, v.to_world * vdb.index_to_world);
    let (lo, hi) = sigma_t.bounds;
    if !(lo.is_finite() && hi.is_finite() && lo.cmplt(hi).all()) {
        return Err(invalid(
            path,
            format!(
                "{}: the grid has no extent (an empty grid, or a zero scale)",
                v.what
            ),
        ));
    }
    let albedo = Field::new(FieldValues::Constant(v.albedo), glam::Affine3A::IDENTITY);
    let constant = |c: Vec3A| Field::new(FieldValues::Constant(c), glam::Affine3A::IDENTITY);
    let emission = match &v.glow {
        None => None,
        Some(VdbGlow::Radiance(le)) => Some(Emission::Radiance {
            le: constant(*le),
            scale: 1.0,
        }),
        Some(VdbGlow::Temperature {
            grid,
            offset,
            t_scale,
            scale,
        }) => {
            let t = crate::load::vdb::read_vdb(&base.join(&v.file), Some(grid), ledger)
                .map_err(|e| invalid(path, format!("{} temperature: {e}", v.what)))?;
            Some(Emission::Temperature {
                temperature: Field::sparse(t.grid, v.to_world * t.index_to_world),
                offset: *offset,
                t_scale: *t_scale,
                scale: *scale,
            })
        }
    };
    let medium = Medium::Heterogeneous(Box::new(Heterogeneous {
        sigma_t,
        albedo,
        scale: v.density,
        phase: v.phase,
        sample_emitters: true,
        emission,
    }));
    medium
        .check()
        .map_err(|e| invalid(path, format!("{}: {e}", v.what)))?;
    // The box: 12 triangles facing out.
    let corner = |i: usize| {
        Vec3A::new(
            if i & 1 == 0 { lo.x } else { hi.x },
            if i & 2 == 0 { lo.y } else { hi.y },
            if i & 4 == 0 { lo.z } else { hi.z },
        )
    };
    let faces: [[usize; 4]; 6] = [
        [0, 2, 3, 1],
        [4, 5, 7, 6],
        [0, 1, 5, 4],
        [2, 6, 7, 3],
        [0, 4, 6, 2],
        [1, 3, 7, 5],
    ];
    let mut triangles = Vec::new();
    for f in faces {
        for [a, b, c] in [[f[0], f[1], f[2]], [f[0], f[2], f[3]]] {
            triangles.push(Triangle::new(corner(a), corner(b), corner(c)));
        }
    }
    let normals = triangles
        .iter()
        .map(|t| (t.v[1] - t.v[0]).cross(t.v[2] - t.v[0]).normalize())
        .collect();
    let mut boundary = SurfaceMaterial::diffuse(Vec3A::ZERO);
    boundary.name = format!("{} boundary", v.what);
    boundary.kind =
        crate::materials::surface::MaterialKind::Fixed(Material::Dielectric { ior: 1.0 });
    Ok(SceneParts {
        material_of: vec![0; triangles.len()],
        triangles,
        normals,
        materials: vec![boundary],
        media: SceneMedia {
            media: vec![medium],
            interfaces: vec![MediumInterface {
                interior: Some(0),
                exterior: None,
            }],
            camera: None,
        },
        ..SceneParts::default()
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::load::shot::schema::Scale;

    #[test]
    fn a_full_file_parses() {
        let text = r#"
            [render]
            width = 64
            spp = 2
            integrator = "path"
            [camera]
            position = [0, 1, 3]
            target = [0, 0, 0]
            [environment]
            color = [0.1, 0.2, 0.3]
            [[model]]
            builtin = "cornell"
            scale = 2
            rotate = [0, 90, 0]
            materials = { tall = "glass", short = "gold:0.1", floor = "red" }
            [[material]]
            name = "red"
            base_color = [0.8, 0.1, 0.1]
            roughness = 0.3
            [[light]]
            type = "spot"
            position = [0, 2, 0]
            target = [0, 0, 0]
            intensity = 10
            outer = 30
            [[light]]
            type = "area"
            corner = [0, 1.9, 0]
            u = [0.2, 0, 0]
            v = [0, 0, 0.2]
            radiance = [5, 5, 5]
        "#;
        let file = parse(text, Path::new("x.toml")).unwrap();
        assert_eq!(file.models[0].scale, Some(Scale::Uniform(2.0)));
        let shot = compose(file, Path::new("x.toml")).unwrap();
        // 30 box triangles + 2 of the area light; the box's point light became
        // the key light, the spot stays.
        assert_eq!(shot.parts.triangles.len(), 32);
        assert_eq!(shot.parts.lights.len(), 1);
        assert!(shot.parts.light.power.x > 0.0);
        assert_eq!(shot.settings.spp, Some(2));
        // The box stands up (+y): its light is above its centre, at y = +0.5 × 2.
        assert!((shot.parts.light.position.y - 1.0).abs() < 1e-5);
    }
}
