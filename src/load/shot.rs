//! Scene files ("shots"): a small TOML format that composes a whole picture —
//! models (glTF, OBJ, the built-in boxes) with transforms and material
//! overrides, lights, the environment, the camera and render settings — so
//! that it renders the same way every time. README.md documents the format;
//! `scenes/` has examples.
//!
//! Every key is checked: a key the format does not know is an error with its
//! line and column (the parser's spans). Paths are relative to the file.

use std::collections::BTreeMap;
use std::ops::Range;
use std::path::{Path, PathBuf};

use glam::{Affine3A, EulerRot, Quat, Vec3, Vec3A};
use serde::Deserialize;
use thiserror::Error;

use super::cornell::{self, MaterialChoice};
use super::gltf::AnimationOptions;
use crate::camera::{
    Aperture, DepthOfField, Focus, Lens, MAX_LENS_LENGTH, SceneCamera, lens_length_is_valid,
};
use crate::film::ToneMap;
use crate::geometry::triangle::Triangle;
use crate::integrators::Integrator;
use crate::lights::Light;
use crate::materials::Material;
use crate::materials::surface::{GltfMaterial, MaterialKind, SurfaceMaterial};
use crate::scene::{PointLight, SceneParts};

/// Why a scene file cannot be used; the message starts with the file (and the
/// line and column where the parser knows them).
#[derive(Debug, Error)]
pub enum ShotError {
    /// The file could not be read.
    #[error("{}: {cause}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// What the system said.
        cause: std::io::Error,
    },
    /// The TOML is malformed, or a key is unknown or has the wrong type.
    #[error("{}:{line}:{column}: {message}", path.display())]
    Syntax {
        /// The file.
        path: PathBuf,
        /// 1-based line.
        line: usize,
        /// 1-based column (in characters).
        column: usize,
        /// What is wrong.
        message: String,
    },
    /// A value is out of range or the parts do not fit together.
    #[error("{}: {message}", path.display())]
    Invalid {
        /// The file.
        path: PathBuf,
        /// What is wrong, naming the section.
        message: String,
    },
}

/// A scene file as written.
#[derive(Clone, Debug, Default, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ShotFile {
    /// `[render]`: settings the command line can override.
    #[serde(default)]
    pub render: RenderSection,
    /// `[camera]`.
    pub camera: Option<CameraSection>,
    /// `[environment]`.
    pub environment: Option<EnvironmentSection>,
    /// `[[model]]`, in order.
    #[serde(default, rename = "model")]
    pub models: Vec<ModelSection>,
    /// `[[material]]`: materials the overrides can name.
    #[serde(default, rename = "material")]
    pub materials: Vec<MaterialSection>,
    /// `[[light]]`.
    #[serde(default, rename = "light")]
    pub lights: Vec<LightSection>,
}

/// `[render]`: each key optional; the command line's options win.
#[derive(Clone, Debug, Default, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct RenderSection {
    /// Image width in pixels.
    pub width: Option<u32>,
    /// Image height in pixels.
    pub height: Option<u32>,
    /// Samples per pixel (with `time`: the most to take).
    pub spp: Option<u32>,
    /// Seconds to render for.
    pub time: Option<f64>,
    /// Seed of the sample positions.
    pub seed: Option<u64>,
    /// `flat`, `direct` or `path`.
    pub integrator: Option<String>,
    /// `clamp`, `aces` or `khronos-pbr-neutral`.
    pub tonemap: Option<String>,
    /// PNG exposure in stops.
    pub exposure: Option<f32>,
    /// Longest path in segments (`path`).
    pub max_depth: Option<u32>,
    /// Denoise the image (Open Image Denoise; see `raylab::denoise`).
    pub denoise: Option<bool>,
    /// The moment, in seconds, at which the glTF models' animations pose
    /// them (`--at`; `--frames` replaces it by each frame's time).
    pub at: Option<f64>,
    /// Frames per second of `--frames` (`--fps`).
    pub fps: Option<f64>,
}

/// A `[[model]]`'s `animation`: an index (from 0) or a name.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(untagged)]
pub enum AnimationKey {
    /// The animation at this index of the file's `animations`.
    Index(u32),
    /// The animation of this name.
    Name(String),
}

impl AnimationKey {
    /// As the loader's choice.
    pub fn choice(&self) -> super::gltf::AnimationChoice {
        match self {
            AnimationKey::Index(i) => super::gltf::AnimationChoice::Index(*i as usize),
            AnimationKey::Name(n) => super::gltf::AnimationChoice::Name(n.clone()),
        }
    }
}

/// `[camera]`: a look-at camera, or a glTF model's camera.
#[derive(Clone, Debug, Default, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct CameraSection {
    /// Centre of projection.
    pub position: Option<[f32; 3]>,
    /// The point looked at.
    pub target: Option<[f32; 3]>,
    /// Up in the image (default +y).
    pub up: Option<[f32; 3]>,
    /// Vertical field of view in degrees (default 40).
    pub fov: Option<f32>,
    /// The name of a `[[model]]` whose file's camera to look through.
    pub model: Option<String>,
    /// Which of that file's cameras (depth-first order, default 0).
    pub index: Option<usize>,
    /// A thin lens of this radius in scene units (0: a pinhole).
    pub aperture: Option<f32>,
    /// Or a thin lens of this f-number (a 36 mm sensor's focal length).
    pub f_number: Option<f32>,
    /// The lens's focus distance along the view axis, in scene units.
    pub focus_distance: Option<f32>,
    /// Or focus on the first hit through this pixel's centre, `[x, y]`.
    pub focus_pixel: Option<[u32; 2]>,
    /// Blades of a polygonal aperture (3 or more; 0: round).
    pub aperture_blades: Option<u32>,
}

/// `[environment]`: a map or a constant colour.
#[derive(Clone, Debug, Default, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct EnvironmentSection {
    /// An equirectangular `.hdr` or `.exr` map.
    pub file: Option<PathBuf>,
    /// A constant radiance.
    pub color: Option<[f32; 3]>,
    /// Multiplies the radiance (default 1).
    pub strength: Option<f32>,
    /// Degrees about +y, counter-clockwise seen from above.
    pub rotate: Option<f32>,
}

/// A uniform or per-axis scale.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(untagged)]
pub enum Scale {
    /// The same on every axis.
    Uniform(f32),
    /// Per axis.
    PerAxis([f32; 3]),
}

/// `[[model]]`: a file or a built-in box, placed and with its materials
/// overridden.
#[derive(Clone, Debug, Default, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ModelSection {
    /// A name for `[camera] model` and for messages (default: the file's).
    pub name: Option<String>,
    /// A glTF (`.gltf`, `.glb`) or OBJ file.
    pub file: Option<PathBuf>,
    /// `cornell` or `cornell-area`: the lab's box, turned to +y up.
    pub builtin: Option<String>,
    /// Scale first, so that the model is this tall (y), standing on y = 0,
    /// centred on the y axis.
    pub fit: Option<f32>,
    /// Then scale.
    pub scale: Option<Scale>,
    /// Then rotate by these degrees about x, then y, then z.
    pub rotate: Option<[f32; 3]>,
    /// Then move.
    pub translate: Option<[f32; 3]>,
    /// Material overrides: a material name, a part name or `*` (everything) =
    /// a preset (`glass:1.5`, `gold:0.2`, ...) or a `[[material]]`'s name.
    #[serde(default)]
    pub materials: BTreeMap<String, String>,
    /// A glTF model's material variant (`KHR_materials_variants`) to show;
    /// the command line's `--variant` replaces it.
    pub variant: Option<String>,
    /// A glTF model's animation to pose it by (default: its first); the
    /// command line's `--animation` replaces it.
    pub animation: Option<AnimationKey>,
}

/// `[[material]]`: a glTF-style metallic–roughness material.
#[derive(Clone, Debug, Default, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct MaterialSection {
    /// What overrides call it.
    pub name: String,
    /// Linear RGB (default 0.8 grey).
    pub base_color: Option<[f32; 3]>,
    /// 0 (default) to 1.
    pub metallic: Option<f32>,
    /// 0 to 1 (default 0.5).
    pub roughness: Option<f32>,
    /// Index of refraction (default 1.5).
    pub ior: Option<f32>,
    /// 0 (default) to 1: light passes through into a refracting volume.
    pub transmission: Option<f32>,
    /// Emitted radiance, W·sr⁻¹·m⁻² (front faces).
    pub emission: Option<[f32; 3]>,
}

/// `[[light]]`, by `type`.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(tag = "type", rename_all = "lowercase", deny_unknown_fields)]
pub enum LightSection {
    /// A point light of `intensity` W/sr (times `color`).
    Point {
        /// Where.
        position: [f32; 3],
        /// W/sr.
        intensity: f32,
        /// Multiplies the intensity (default white).
        color: Option<[f32; 3]>,
    },
    /// A spot light pointing at `target` (or along `direction`).
    Spot {
        /// Where.
        position: [f32; 3],
        /// The point its axis goes through.
        target: Option<[f32; 3]>,
        /// Or its axis.
        direction: Option<[f32; 3]>,
        /// W/sr on the axis.
        intensity: f32,
        /// Multiplies the intensity.
        color: Option<[f32; 3]>,
        /// Full intensity inside this half-angle, degrees (default 0).
        inner: Option<f32>,
        /// Nothing outside this half-angle, degrees.
        outer: f32,
    },
    /// Parallel light travelling along `direction`.
    Directional {
        /// The direction light travels in.
        direction: [f32; 3],
        /// W/m² on a surface facing it.
        irradiance: f32,
        /// Multiplies the irradiance.
        color: Option<[f32; 3]>,
    },
    /// A parallelogram `corner`, `corner + u`, `corner + u + v`, `corner + v`
    /// emitting `radiance` from the side `u × v` points to.
    Area {
        /// A corner.
        corner: [f32; 3],
        /// One edge.
        u: [f32; 3],
        /// The other edge.
        v: [f32; 3],
        /// W·sr⁻¹·m⁻².
        radiance: [f32; 3],
        /// Emit from both sides (default false).
        two_sided: Option<bool>,
    },
}

/// Render settings from a scene file, checked: what the command line does not
/// give is taken from here.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ShotSettings {
    /// Image width.
    pub width: Option<u32>,
    /// Image height.
    pub height: Option<u32>,
    /// Samples per pixel.
    pub spp: Option<u32>,
    /// Seconds to render for.
    pub time: Option<f64>,
    /// Seed.
    pub seed: Option<u64>,
    /// Integrator (with `max_depth` applied).
    pub integrator: Option<Integrator>,
    /// Longest path.
    pub max_depth: Option<u32>,
    /// Tone mapping.
    pub tonemap: Option<ToneMap>,
    /// Exposure in stops.
    pub exposure: Option<f32>,
    /// Denoise the image.
    pub denoise: Option<bool>,
    /// The animations' moment in seconds.
    pub at: Option<f32>,
    /// Frames per second of `--frames`.
    pub fps: Option<f64>,
}

/// The camera a scene file asks for, resolved.
#[derive(Clone, Debug, PartialEq)]
pub enum ShotCamera {
    /// Nothing given: the first camera of the models' files, else the built-in
    /// box's camera if the first model is a box, else framing.
    Default,
    /// A camera placed by the file (or taken from a model's file).
    Placed(SceneCamera),
}

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

/// The 1-based line and column of byte `offset` of `text`.
fn line_column(text: &str, offset: usize) -> (usize, usize) {
    let before = &text[..offset.min(text.len())];
    let line = before.matches('\n').count() + 1;
    let column = before.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1;
    (line, column)
}

/// Parses scene-file text; `path` names the file in errors.
pub fn parse(text: &str, path: &Path) -> Result<ShotFile, ShotError> {
    let parsed = crate::guard::catch("toml", || toml::from_str::<ShotFile>(text))
        .map_err(|m| invalid(path, m))?;
    parsed.map_err(|e| {
        let (line, column) = e.span().map_or((1, 1), |s| line_column(text, s.start));
        ShotError::Syntax {
            path: path.to_owned(),
            line,
            column,
            message: e.message().trim().replace('\n', " "),
        }
    })
}

/// Reads only a scene file's `[render]` settings (checked), without loading
/// its models: what a program needs to know before it loads the scene.
pub fn read_settings(path: &Path) -> Result<ShotSettings, ShotError> {
    let text = std::fs::read_to_string(path).map_err(|cause| ShotError::Io {
        path: path.to_owned(),
        cause,
    })?;
    settings(path, &parse(&text, path)?.render)
}

/// Reads and composes a scene file: loads its models, places them, applies
/// material overrides, adds its lights. The environment is returned as
/// written (the caller loads it, so that the command line can replace it).
pub fn load_shot(path: &Path) -> Result<Shot, super::LoadError> {
    load_shot_with(path, &crate::memory::Ledger::unlimited())
}

/// [`load_shot`], charging the models' decoded textures to `ledger` before
/// decoding them.
pub fn load_shot_with(
    path: &Path,
    ledger: &crate::memory::Ledger,
) -> Result<Shot, super::LoadError> {
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
) -> Result<Shot, super::LoadError> {
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
) -> Result<Shot, super::LoadError> {
    let text = std::fs::read_to_string(path).map_err(|cause| ShotError::Io {
        path: path.to_owned(),
        cause,
    })?;
    let file = parse(&text, path)?;
    compose_posed(file, path, ledger, variant, animation)
}

/// A scene-file error; names quoted from the file (which may hold a newline)
/// are escaped, so that the message stays one line.
fn invalid(path: &Path, message: String) -> ShotError {
    ShotError::Invalid {
        path: path.to_owned(),
        message: crate::guard::one_line(&message).into_owned(),
    }
}

/// Checks that every number of a list is finite (and `>= 0` if `non_negative`).
fn check(path: &Path, what: &str, values: &[f32], non_negative: bool) -> Result<(), ShotError> {
    for &v in values {
        if !v.is_finite() || (non_negative && v < 0.0) {
            let need = if non_negative {
                "finite and >= 0"
            } else {
                "finite"
            };
            return Err(invalid(path, format!("{what}: {v} (must be {need})")));
        }
    }
    Ok(())
}

fn settings(path: &Path, r: &RenderSection) -> Result<ShotSettings, ShotError> {
    let bad = |m: String| invalid(path, format!("[render] {m}"));
    use crate::limits::{MAX_PIXELS, MAX_SIDE, MAX_SPP, MAX_TIME};
    for (key, v) in [("width", r.width), ("height", r.height)] {
        if let Some(v) = v
            && !(1..=MAX_SIDE).contains(&v)
        {
            return Err(bad(format!("{key} = {v}: expected 1 to {MAX_SIDE} pixels")));
        }
    }
    if let (Some(w), Some(h)) = (r.width, r.height)
        && u64::from(w) * u64::from(h) > MAX_PIXELS
    {
        return Err(bad(format!(
            "width × height = {w} × {h}: expected at most {MAX_PIXELS} pixels"
        )));
    }
    if let Some(spp) = r.spp
        && !(1..=MAX_SPP).contains(&spp)
    {
        return Err(bad(format!("spp = {spp}: expected 1 to {MAX_SPP}")));
    }
    if let Some(t) = r.time
        && !(t > 0.0 && t <= MAX_TIME)
    {
        return Err(bad(format!(
            "time = {t:?}: expected seconds > 0 and at most {MAX_TIME}"
        )));
    }
    if r.max_depth == Some(0) {
        return Err(bad("max_depth = 0: expected at least 1".into()));
    }
    if let Some(e) = r.exposure {
        check(path, "[render] exposure", &[e], false)?;
    }
    use super::gltf::{AT_EXPECTED, MAX_FPS, at_in_range, fps_in_range};
    if let Some(at) = r.at
        && !at_in_range(at)
    {
        return Err(bad(format!("at = {at:?}: {AT_EXPECTED}")));
    }
    if let Some(fps) = r.fps
        && !fps_in_range(fps)
    {
        return Err(bad(format!(
            "fps = {fps:?}: expected frames per second above 0 and at most {}",
            MAX_FPS
        )));
    }
    let integrator = r
        .integrator
        .as_deref()
        .map(|s| {
            s.parse::<Integrator>()
                .map_err(|e| bad(format!("integrator: {e}")))
        })
        .transpose()?;
    let integrator = integrator.map(|i| match (i, r.max_depth) {
        (Integrator::Path(mut o), Some(d)) => {
            o.max_depth = d;
            Integrator::Path(o)
        }
        (i, _) => i,
    });
    let tonemap = r
        .tonemap
        .as_deref()
        .map(|s| {
            s.parse::<ToneMap>()
                .map_err(|e| bad(format!("tonemap: {e}")))
        })
        .transpose()?;
    Ok(ShotSettings {
        width: r.width,
        height: r.height,
        spp: r.spp,
        time: r.time,
        seed: r.seed,
        integrator,
        max_depth: r.max_depth,
        tonemap,
        exposure: r.exposure,
        denoise: r.denoise,
        at: r.at.map(|t| t as f32),
        fps: r.fps,
    })
}

/// A `[[material]]` as a scene material.
fn file_material(path: &Path, m: &MaterialSection) -> Result<SurfaceMaterial, ShotError> {
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
    let gltf = GltfMaterial {
        base_color: Vec3A::from(base).extend(1.0),
        metallic: unit("metallic", m.metallic, 0.0)?,
        roughness: unit("roughness", m.roughness, 0.5)?,
        ior,
        transmission,
        // A transmitting material is a solid: it refracts.
        thin_walled: false,
        ..GltfMaterial::default()
    };
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
fn override_material(
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

/// A model's parts with named triangle ranges (the built-in box's parts).
struct ModelParts {
    parts: SceneParts,
    named_ranges: Vec<(String, Range<usize>)>,
    lab_camera: Option<SceneCamera>,
    warnings: Vec<String>,
    /// A glTF model's material variants, and the one shown.
    variants: Vec<String>,
    variant: Option<String>,
    /// A glTF model's animations' names (empty for other models).
    animations: Vec<String>,
}

/// Loads one model in its own frame.
fn load_model(
    path: &Path,
    base: &Path,
    m: &ModelSection,
    index: usize,
    ledger: &crate::memory::Ledger,
    variant: &super::gltf::VariantChoice,
    animation: &super::gltf::AnimationOptions,
) -> Result<ModelParts, super::LoadError> {
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
                    let g = super::gltf::load_gltf_posed(&file, ledger, variant, animation)?;
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
                    let obj = super::obj::load_obj_scene_with(&file, ledger)?;
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
                _ => Err(invalid(
                    path,
                    format!(
                        "[[model]] {}: {} is neither glTF (.gltf, .glb) nor OBJ (.obj)",
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
fn placement(
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

/// Composes a parsed scene file (`path` locates relative paths).
pub fn compose(file: ShotFile, path: &Path) -> Result<Shot, super::LoadError> {
    compose_with(file, path, &crate::memory::Ledger::unlimited())
}

/// [`compose`], charging the models' decoded textures to `ledger`.
pub fn compose_with(
    file: ShotFile,
    path: &Path,
    ledger: &crate::memory::Ledger,
) -> Result<Shot, super::LoadError> {
    compose_variant(file, path, ledger, None)
}

/// [`compose_with`] with the command line's `--variant` (see
/// [`load_shot_variant`]).
pub fn compose_variant(
    file: ShotFile,
    path: &Path,
    ledger: &crate::memory::Ledger,
    variant: Option<&str>,
) -> Result<Shot, super::LoadError> {
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
) -> Result<Shot, super::LoadError> {
    use super::gltf::VariantChoice;
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
    if file.models.is_empty() && file.lights.is_empty() {
        return Err(invalid(
            path,
            "no [[model]] and no [[light]]: nothing to render".into(),
        )
        .into());
    }
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

/// The `[camera]` section resolved.
fn camera(
    path: &Path,
    c: &CameraSection,
    model_cameras: &[(String, std::ops::Range<usize>)],
    cameras: &[SceneCamera],
) -> Result<SceneCamera, ShotError> {
    if let Some(model) = &c.model {
        if c.position.is_some() || c.target.is_some() || c.up.is_some() || c.fov.is_some() {
            return Err(invalid(
                path,
                "[camera]: give model (and index) or position/target/up/fov, not both".into(),
            ));
        }
        let Some((_, range)) = model_cameras.iter().find(|(n, _)| n == model) else {
            let names: Vec<&str> = model_cameras.iter().map(|(n, _)| n.as_str()).collect();
            return Err(invalid(
                path,
                format!(
                    "[camera] model = '{model}': no such model (models: {})",
                    names.join(", ")
                ),
            ));
        };
        let index = c.index.unwrap_or(0);
        if index >= range.len() {
            return Err(invalid(
                path,
                format!(
                    "[camera] model '{model}' has {} camera(s); index {index} is out of range",
                    range.len()
                ),
            ));
        }
        return Ok(SceneCamera {
            depth_of_field: depth_of_field(path, c)?,
            ..cameras[range.start + index].clone()
        });
    }
    if c.index.is_some() {
        return Err(invalid(path, "[camera] index needs model".into()));
    }
    let (Some(position), Some(target)) = (c.position, c.target) else {
        return Err(invalid(
            path,
            "[camera]: give position and target (or model)".into(),
        ));
    };
    let up = c.up.unwrap_or([0.0, 1.0, 0.0]);
    for (key, v) in [("position", position), ("target", target), ("up", up)] {
        check(path, &format!("[camera] {key}"), &v, false)?;
    }
    let fov = c.fov.unwrap_or(40.0);
    if !(fov > 0.0 && fov < 180.0) {
        return Err(invalid(
            path,
            format!("[camera] fov = {fov}: expected degrees between 0 and 180"),
        ));
    }
    let rotation =
        crate::camera::look_at(position.into(), target.into(), up.into()).ok_or_else(|| {
            invalid(
                path,
                "[camera]: position equals target, or up is along the view".into(),
            )
        })?;
    Ok(SceneCamera {
        name: "[camera]".into(),
        position: position.into(),
        rotation,
        lens: Lens::from_yfov(fov.to_radians()),
        aspect_ratio: None,
        depth_of_field: depth_of_field(path, c)?,
    })
}

/// The `[camera]` section's thin lens, checked (a focus pixel is checked
/// against the image once its size is known).
fn depth_of_field(path: &Path, c: &CameraSection) -> Result<DepthOfField, ShotError> {
    let aperture = match (c.aperture, c.f_number) {
        (Some(_), Some(_)) => {
            return Err(invalid(
                path,
                "[camera]: give aperture or f_number, not both".into(),
            ));
        }
        (Some(r), None) if lens_length_is_valid(r, false) => Some(Aperture::Radius(r)),
        (None, Some(n)) if lens_length_is_valid(n, true) => Some(Aperture::FNumber(n)),
        (Some(r), None) => {
            return Err(invalid(
                path,
                format!("[camera] aperture = {r}: expected a radius from 0 to {MAX_LENS_LENGTH:e}"),
            ));
        }
        (None, Some(n)) => {
            return Err(invalid(
                path,
                format!(
                    "[camera] f_number = {n}: expected a number above 0, at most {MAX_LENS_LENGTH:e}"
                ),
            ));
        }
        (None, None) => None,
    };
    let focus = match (c.focus_distance, c.focus_pixel) {
        (Some(_), Some(_)) => {
            return Err(invalid(
                path,
                "[camera]: give focus_distance or focus_pixel, not both".into(),
            ));
        }
        (Some(d), None) if lens_length_is_valid(d, true) => Some(Focus::Distance(d)),
        (Some(d), None) => {
            return Err(invalid(
                path,
                format!(
                    "[camera] focus_distance = {d}: expected a distance above 0, at most {MAX_LENS_LENGTH:e}"
                ),
            ));
        }
        (None, Some(p)) => Some(Focus::Pixel(p)),
        (None, None) => None,
    };
    if let Some(n) = c.aperture_blades
        && !crate::camera::blades_are_valid(n)
    {
        return Err(invalid(
            path,
            format!(
                "[camera] aperture_blades = {n}: expected 0 (round) or 3 to {}",
                crate::camera::MAX_BLADES
            ),
        ));
    }
    Ok(DepthOfField {
        aperture,
        focus,
        blades: c.aperture_blades,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unknown_keys_are_errors_with_line_and_column() {
        let text = "[render]\nspp = 4\n\n[[model]]\nbuiltin = \"cornell\"\ncolour = 1\n";
        let err = parse(text, Path::new("s.toml")).unwrap_err().to_string();
        assert!(
            err.starts_with("s.toml:6:1: unknown field `colour`"),
            "{err}"
        );
        let light = "[[light]]\ntype = \"point\"\nposition = [0, 1, 0]\nintensity = 2\npower = 3\n";
        let err = parse(light, Path::new("l.toml")).unwrap_err().to_string();
        assert!(err.contains("l.toml:") && err.contains("power"), "{err}");
        let typo = "[camera]\nposition = [0, 0, 1]\ntarget = \"origin\"\n";
        let err = parse(typo, Path::new("c.toml")).unwrap_err().to_string();
        assert!(err.starts_with("c.toml:3:10:"), "{err}");
        assert_eq!(line_column("ab\ncdé\nx", 8), (3, 1));
    }

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
