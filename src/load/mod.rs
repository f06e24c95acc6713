//! Loading a scene by name or file: the built-in boxes, Wavefront OBJ and glTF
//! 2.0, with what the command line can add (meshes placed in the box, light
//! overrides, box materials). A program using the crate gets exactly what
//! `raylab render` gets.
//!
//! The loaders sit above the scene model ([`crate::scene`]), which knows
//! nothing of files: [`cornell`] (the lab's boxes), [`obj`] with its MTL,
//! [`gltf`], the scene files of [`shot`], Mitsuba 3's XML scenes read into
//! a tree ([`mitsuba`]; not yet turned into a scene), and what they share: the default
//! view of a mesh ([`framing`]) and the placing of one ([`transform`]); why a
//! load fails is [`LoadError`] (`error.rs`).

pub mod cornell;
mod error;
pub mod framing;
pub mod gltf;
pub mod mitsuba;
pub mod obj;
pub mod shot;
pub mod transform;
pub mod vdb;
mod volumes;

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use glam::{Mat3A, Vec3A};

use crate::camera::{DepthOfField, FilmWindow, Lens, SceneCamera, Y_UP_TOWARDS_MINUS_Z};
use crate::geometry::triangle::Triangle;
use crate::lights::environment::Environment;
use crate::media::Medium;
use crate::memory::{GEOMETRY_BYTES_PER_TRIANGLE, Ledger, MemoryBudget, MemoryError, Needs};
use crate::scene::{PointLight, Scene};
use cornell::MaterialChoice;
use gltf::{AnimationOptions, VariantChoice, load_gltf_posed};
use obj::{load_obj, load_obj_scene_with};
use shot::{ShotCamera, ShotSettings, load_shot_posed};
use transform::Transform;

pub use error::LoadError;

/// What a scene was made from; decides defaults (integrator, image size, tone
/// mapping) that differ between the lab's scenes and real ones.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SceneKind {
    /// `cornell` or `cornell-area`.
    Lab,
    /// A Wavefront OBJ mesh.
    Mesh,
    /// A glTF 2.0 file.
    Gltf,
    /// A scene file (`.toml`) composing models, lights and a camera.
    Shot,
    /// A Mitsuba 3 scene (`.xml`).
    Mitsuba,
}

impl SceneKind {
    /// Whether the scene is in physical units with real-world defaults (glTF
    /// and scene files: `path`, tone mapping, 600-pixel-high images), rather
    /// than one of the lab's scenes.
    pub fn is_physical(self) -> bool {
        matches!(self, SceneKind::Gltf | SceneKind::Shot | SceneKind::Mitsuba)
    }
}

/// Options of [`load`].
#[derive(Clone, Debug, Default, PartialEq)]
pub struct LoadOptions {
    /// OBJ meshes to place in the built-in box.
    pub add: Vec<PathBuf>,
    /// Their placement: one for all, or one per mesh.
    pub transforms: Vec<Transform>,
    /// Materials of the box's parts.
    pub materials: Vec<(String, MaterialChoice)>,
    /// The key point light's power per channel, replacing the scene's.
    pub light_power: Option<f32>,
    /// The key point light's position, replacing the scene's.
    pub light_pos: Option<Vec3A>,
    /// The lab's ambient term, replacing the default.
    pub ambient: Option<f32>,
    /// Which of the file's cameras to start from (depth-first order).
    pub camera: Option<usize>,
    /// When a glTF scene gets raylab's default lighting.
    pub default_light: DefaultLight,
    /// The environment around the scene.
    pub environment: EnvironmentOptions,
    /// The most memory the scene (geometry, textures, environment map) may
    /// need, checked from headers and counts before the big allocations
    /// (default: unlimited; `raylab` passes `--max-memory`, by default
    /// [`MemoryBudget::machine_default`]).
    pub max_memory: MemoryBudget,
    /// How `path` chooses among the lights (default: the light tree).
    pub light_selection: crate::scene::LightSelection,
    /// How the light tree's choice gets its number (default: stratified for
    /// Mitsuba scenes, independent for the rest, whose images stay as they
    /// were).
    pub light_numbers: Option<crate::scene::LightNumbers>,
    /// The glTF material variant (`KHR_materials_variants`) to show: a glTF
    /// file without it is refused; in a scene file, the models that have it
    /// show it (at least one must).
    pub variant: Option<String>,
    /// A glTF file's animation and the moment to pose it at (default: the
    /// file as written).
    pub animation: AnimationOptions,
    /// A Mitsuba scene's `$NAME` values (`-D NAME=VALUE`).
    pub defines: Vec<(String, String)>,
    /// Fog filling the scene's bounding box (`--fog`): its density (per
    /// scene unit) and albedo ([`Scene::add_fog`]).
    pub fog: Option<(f32, Vec3A)>,
}

/// Where an environment's radiance comes from.
#[derive(Clone, Debug, PartialEq)]
pub enum EnvSource {
    /// An equirectangular Radiance `.hdr` or OpenEXR `.exr` map.
    File(PathBuf),
    /// The same radiance (RGB, W·sr⁻¹·m⁻²) from every direction.
    Color(Vec3A),
}

/// The environment options (`--env`, `--env-color`, `--env-strength`,
/// `--env-rotate`).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct EnvironmentOptions {
    /// The map or colour; `None` keeps the scene's own (if any).
    pub source: Option<EnvSource>,
    /// Multiplies the radiance (default 1).
    pub strength: Option<f32>,
    /// Degrees about +y, counter-clockwise seen from above (default 0).
    pub rotation: Option<f32>,
}

impl EnvironmentOptions {
    /// Whether any option is given.
    pub fn is_given(&self) -> bool {
        self.source.is_some() || self.strength.is_some() || self.rotation.is_some()
    }

    /// The environment these options make of the scene's own `current`:
    /// the source replaced if given, then strength and rotation applied.
    /// Strength or rotation without any environment is a usage error.
    pub fn apply(&self, current: &Environment) -> Result<Environment, LoadError> {
        self.apply_with(current, &Ledger::unlimited())
    }

    /// [`apply`](Self::apply), charging a map read from a file to `ledger`.
    pub fn apply_with(
        &self,
        current: &Environment,
        ledger: &Ledger,
    ) -> Result<Environment, LoadError> {
        let mut env = match &self.source {
            Some(EnvSource::File(path)) => Environment::load_with(path, ledger)?,
            Some(EnvSource::Color(c)) => Environment::constant(*c),
            None => current.clone(),
        };
        if self.source.is_none()
            && env.is_black()
            && (self.strength.is_some() || self.rotation.is_some())
        {
            return Err(LoadError::Usage(
                "--env-strength and --env-rotate need an environment (--env FILE or --env-color R,G,B)"
                    .into(),
            ));
        }
        if let Some(s) = self.strength {
            env = env.with_strength(s);
        }
        if let Some(r) = self.rotation {
            env = env.with_rotation(r);
        }
        Ok(env)
    }
}

/// When a glTF scene gets raylab's default lighting (a key light and a grey sky).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum DefaultLight {
    /// When the file has no punctual light and its emitting surfaces are too
    /// weak to light it (see [`DEFAULT_LIGHT_EMITTER_RATIO`]): an emitter-lit
    /// room renders as the file says, a model with a few glowing details gets
    /// light.
    #[default]
    Auto,
    /// Always (punctual lights and emitters in the file shine too).
    On,
    /// Never: only the file's own lights.
    Off,
}

impl std::str::FromStr for DefaultLight {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s {
            "auto" => Ok(Self::Auto),
            "on" => Ok(Self::On),
            "off" => Ok(Self::Off),
            _ => Err(format!("unknown choice '{s}' (expected auto, on or off)")),
        }
    }
}

/// Where the view starts and how far the viewer's keys move it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct InitialView {
    /// Camera position.
    pub position: Vec3A,
    /// Camera-to-world rotation (columns: right, down, forward).
    pub rotation: Mat3A,
    /// Projection.
    pub lens: Lens,
    /// Width over height the scene's camera asks for, if any.
    pub aspect_ratio: Option<f32>,
    /// The thin lens the scene's camera asks for (a scene file's).
    pub depth_of_field: DepthOfField,
    /// The window of the film the scene's camera renders (a Mitsuba
    /// scene's crop window); `None`: the whole image.
    pub window: Option<FilmWindow>,
    /// Viewer travel per key press.
    pub step: f32,
}

/// How big the loaded scene is.
#[derive(Clone, Debug, PartialEq)]
pub struct LoadSummary {
    /// Triangles after instancing.
    pub triangles: usize,
    /// Entries in the material table.
    pub materials: usize,
    /// Decoded images.
    pub textures: usize,
    /// Bytes of decoded images.
    pub texture_bytes: usize,
    /// Bytes of geometry, attributes and BVH.
    pub geometry_bytes: usize,
    /// Punctual lights (the key light included when it has power).
    pub punctual_lights: usize,
    /// Emitting triangles.
    pub emitters: usize,
    /// Analytic shapes (spheres, disks, cylinders).
    pub analytic_shapes: usize,
    /// Emitting analytic shapes.
    pub emitting_shapes: usize,
    /// The environment map's size in texels, if the environment is a map.
    pub environment_size: Option<[usize; 2]>,
    /// Bytes of the environment map and its sampling tables.
    pub environment_bytes: usize,
    /// Time to read the environment map and build its sampling tables
    /// (included in `time`).
    pub environment_time: Duration,
    /// Time to read, decode and build.
    pub time: Duration,
    /// The memory estimate the load was checked against (no film yet).
    pub needs: Needs,
    /// The glTF material variants (`KHR_materials_variants`) `--variant` can
    /// pick, in the file's order.
    pub variants: Vec<String>,
    /// The variant shown, if one was picked.
    pub variant: Option<String>,
    /// A Mitsuba scene's objects by kind and plugin (`4 shapes (obj ×3,
    /// rectangle), 2 bsdfs (diffuse ×2)`), for the load line.
    pub plugins: Option<String>,
}

/// A loaded scene with its starting view.
#[derive(Clone, Debug)]
pub struct Loaded {
    /// The scene.
    pub scene: Scene,
    /// What it was made from.
    pub kind: SceneKind,
    /// The starting view.
    pub view: InitialView,
    /// Its size and load time.
    pub summary: LoadSummary,
    /// Things worth telling that did not stop the load.
    pub warnings: Vec<String>,
    /// Whether raylab added its default lighting (a key point light and a grey
    /// sky; see [`DefaultLight`]).
    pub default_light: bool,
    /// A scene file's render settings (empty for other scenes): what the
    /// command line leaves out is taken from here.
    pub settings: ShotSettings,
    /// The names of a glTF file's animations (empty for other scenes).
    pub animations: Vec<String>,
}

/// Charges `triangles` triangles' geometry to `ledger`, less what the loader
/// has already charged (glTF charges each instance as it makes it).
fn charge_geometry(ledger: &Ledger, name: &str, triangles: usize) -> Result<(), MemoryError> {
    let estimate = triangles as u64 * GEOMETRY_BYTES_PER_TRIANGLE;
    let more = estimate.saturating_sub(ledger.needs().geometry);
    ledger.charge(
        name,
        Needs {
            geometry: more,
            ..Needs::default()
        },
    )
}

/// Ambient term of mesh and glTF scenes unless the user gives one.
pub const MESH_AMBIENT: f32 = 0.15;

/// Irradiance (W/m²) of the default key light at the centre of a glTF scene
/// that has no punctual light: a white diffuse surface facing it has radiance
/// 2/π ≈ 0.64 from it.
pub const DEFAULT_LIGHT_IRRADIANCE: f32 = 2.0;

/// `auto` adds the default lighting to a glTF file without punctual lights
/// when its emitters' power spread over the scene's bounding sphere,
/// `P / (4πr²)` (a mean irradiance, independent of the scene's scale), is below
/// this fraction of [`DEFAULT_LIGHT_IRRADIANCE`]: the emitters are then details
/// (the DamagedHelmet's lamps), not the scene's lighting.
pub const DEFAULT_LIGHT_EMITTER_RATIO: f32 = 0.02;

/// Radiance of the default sky around a glTF scene without punctual lights (a
/// white diffuse surface open to it has radiance 0.4 from it; it is also the
/// grey background).
pub const DEFAULT_SKY_RADIANCE: f32 = 0.4;

/// The kind of file `name` is, by extension.
fn file_kind(name: &str) -> Option<SceneKind> {
    let ext = Path::new(name).extension()?.to_str()?.to_ascii_lowercase();
    match ext.as_str() {
        "obj" => Some(SceneKind::Mesh),
        "gltf" | "glb" => Some(SceneKind::Gltf),
        "toml" => Some(SceneKind::Shot),
        "xml" => Some(SceneKind::Mitsuba),
        _ => None,
    }
}

/// Loads `name`: `cornell`, `cornell-area`, a `.obj`, `.gltf` or `.glb` file.
pub fn load(name: &str, options: &LoadOptions) -> Result<Loaded, LoadError> {
    let start = Instant::now();
    let scene_err = |cause| LoadError::Scene {
        name: name.to_string(),
        cause,
    };
    let kind = match name {
        "cornell" | "cornell-area" => SceneKind::Lab,
        _ => file_kind(name).ok_or_else(|| LoadError::Unknown(name.to_string()))?,
    };
    if kind != SceneKind::Lab && !options.add.is_empty() {
        return Err(LoadError::Usage(format!(
            "--add places meshes in the cornell scene; {name} is a file"
        )));
    }
    if !kind.is_physical()
        && let Some(v) = &options.variant
    {
        return Err(LoadError::Usage(format!(
            "--variant {}: material variants are glTF's; {name} is neither a glTF file nor a scene file",
            crate::guard::one_line(v)
        )));
    }
    if !matches!(kind, SceneKind::Gltf | SceneKind::Shot) && options.animation.is_given() {
        return Err(LoadError::Usage(format!(
            "--at and --animation pose a glTF file's animation; {name} is neither a glTF file nor a scene file"
        )));
    }
    if kind != SceneKind::Lab && !options.materials.is_empty() {
        return Err(LoadError::Usage(format!(
            "--material names parts of the built-in box, not of {name}"
        )));
    }
    let mut warnings = Vec::new();
    let mut default_light = false;
    let mut settings = ShotSettings::default();
    let (mut variants, mut variant) = (Vec::new(), None);
    let mut animations = Vec::new();
    let mut plugins = None;
    // The environment first: a scene lit by one gets no default lighting.
    let ledger = Ledger::new(options.max_memory);
    let env_start = Instant::now();
    let environment = match &options.environment.source {
        Some(_) => Some(
            options
                .environment
                .apply_with(&Environment::none(), &ledger)?,
        ),
        None => None,
    };
    let mut environment_time = env_start.elapsed();
    let (mut scene, view) = match kind {
        SceneKind::Lab => {
            let area = name == "cornell-area";
            let (mut tris, mut rho) = cornell::triangles();
            if area {
                cornell::push_area_light(&mut tris, &mut rho);
            }
            for (i, path) in options.add.iter().enumerate() {
                let mut mesh = load_obj(path)?;
                warnings.append(&mut mesh.warnings);
                if let Some(t) = options.transforms.get(i).or(options.transforms.first()) {
                    t.apply(&mut mesh.triangles);
                }
                // OBJ faces are counter-clockwise seen from outside; the lab's
                // one-sided normal wants the opposite order.
                tris.extend(
                    mesh.triangles
                        .iter()
                        .map(|t| Triangle::new(t.v[0], t.v[2], t.v[1])),
                );
                rho.extend(mesh.reflectance);
            }
            // cornell-area's point light is off unless given a power.
            let default_power = if area { 0.0 } else { cornell::LIGHT_POWER };
            let light = PointLight {
                position: cornell::LIGHT_POSITION,
                power: Vec3A::splat(options.light_power.unwrap_or(default_power)),
            };
            let default_ambient = if area { 0.0 } else { cornell::AMBIENT };
            let ambient = Vec3A::splat(options.ambient.unwrap_or(default_ambient));
            charge_geometry(&ledger, name, tris.len())?;
            let mut scene = Scene::new(tris, rho, light, ambient).map_err(scene_err)?;
            if area {
                cornell::light_area_patch(&mut scene);
            }
            for (part, material) in &options.materials {
                let range = cornell::part(part)
                    .ok_or_else(|| LoadError::Usage(format!("unknown part '{part}' of the box")))?;
                material.apply(&mut scene, range);
            }
            let view = InitialView {
                position: cornell::CAMERA_POSITION,
                rotation: Mat3A::IDENTITY,
                lens: Lens::LAB,
                aspect_ratio: None,
                depth_of_field: DepthOfField::default(),
                window: None,
                step: cornell::LAB_STEP,
            };
            (scene, view)
        }
        SceneKind::Mesh => {
            let obj = load_obj_scene_with(Path::new(name), &ledger)?;
            warnings.extend(obj.warnings);
            let mut parts = obj.parts;
            parts.ambient = Vec3A::splat(options.ambient.unwrap_or(MESH_AMBIENT));
            // An empty OBJ (a warning) is framed as a point at the origin.
            let (lo, hi) = match parts.triangles.is_empty() {
                true => (Vec3A::ZERO, Vec3A::ZERO),
                false => crate::geometry::triangle::bounds(&parts.triangles),
            };
            let framing = framing::frame(lo, hi);
            parts.light = framing.light;
            charge_geometry(&ledger, name, parts.triangles.len())?;
            let mut scene = Scene::from_parts(parts).map_err(scene_err)?;
            // The framing light lights a bare mesh; an OBJ whose emitters
            // light it (a room with a ceiling lamp) keeps only those, unless
            // asked (`--default-light on`).
            let keep_light = match options.default_light {
                DefaultLight::On => true,
                DefaultLight::Off => false,
                DefaultLight::Auto => !emitters_light(&scene) && environment.is_none(),
            };
            if !keep_light {
                scene.light.power = Vec3A::ZERO;
            }
            if let Some(p) = options.light_power {
                scene.light.power = Vec3A::splat(p);
            }
            let view = InitialView {
                position: framing.camera_pos,
                rotation: framing.base,
                lens: Lens::LAB,
                aspect_ratio: None,
                depth_of_field: DepthOfField::default(),
                window: None,
                step: framing.step,
            };
            (scene, view)
        }
        SceneKind::Gltf => {
            let choice = match &options.variant {
                Some(v) => VariantChoice::Named(v.clone()),
                None => VariantChoice::Default,
            };
            let loaded = load_gltf_posed(Path::new(name), &ledger, &choice, &options.animation)?;
            warnings.extend(loaded.warnings);
            (variants, variant) = (loaded.variants, loaded.variant);
            animations = loaded.animations;
            let mut parts = loaded.parts;
            parts.ambient = Vec3A::splat(options.ambient.unwrap_or(MESH_AMBIENT));
            let cameras = parts.cameras.len();
            charge_geometry(&ledger, name, parts.triangles.len())?;
            let mut scene = Scene::from_parts(parts).map_err(scene_err)?;
            let (lo, hi) = scene.bounds();
            let framing = framing::frame(lo, hi);
            let view = match options.camera {
                Some(i) if i >= cameras => {
                    return Err(LoadError::Usage(format!(
                        "--camera {i}: {name} has {cameras} camera{}",
                        if cameras == 1 { "" } else { "s" }
                    )));
                }
                _ => view_through(scene.cameras.get(options.camera.unwrap_or(0)), &framing),
            };
            default_light = add_default_light(
                &mut scene,
                &view,
                options.default_light,
                loaded.has_punctual_lights || environment.is_some(),
            );
            if let Some(p) = options.light_power {
                scene.light.power = Vec3A::splat(p);
            }
            (scene, view)
        }
        SceneKind::Mitsuba => {
            let m = mitsuba::load_mitsuba(Path::new(name), &options.defines, &ledger)?;
            warnings.extend(m.warnings);
            plugins = Some(m.summary);
            settings = m.settings;
            let mut parts = m.parts;
            parts.ambient = Vec3A::splat(options.ambient.unwrap_or(0.0));
            charge_geometry(&ledger, name, parts.triangles.len())?;
            let mut scene = Scene::from_parts(parts).map_err(scene_err)?;
            if environment.is_none() {
                scene.set_environment(m.environment);
            }
            let (lo, hi) = scene.bounds();
            let framing = framing::frame(lo, hi);
            let view = view_through(m.camera.as_ref(), &framing);
            if let Some(p) = options.light_power {
                scene.light.power = Vec3A::splat(p);
            }
            (scene, view)
        }
        SceneKind::Shot => {
            let shot = load_shot_posed(
                Path::new(name),
                &ledger,
                options.variant.as_deref(),
                &options.animation,
            )?;
            warnings.extend(shot.warnings);
            animations = shot.animations;
            (variants, variant) = (shot.variants, shot.variant);
            settings = shot.settings;
            let mut parts = shot.parts;
            parts.ambient = Vec3A::splat(options.ambient.unwrap_or(MESH_AMBIENT));
            let cameras = parts.cameras.len();
            charge_geometry(&ledger, name, parts.triangles.len())?;
            let mut scene = Scene::from_parts(parts).map_err(scene_err)?;
            if environment.is_none()
                && let Some(e) = shot.environment
            {
                let from_file = EnvironmentOptions {
                    source: match (e.file, e.color) {
                        (Some(f), _) => Some(EnvSource::File(f)),
                        (None, Some(c)) => Some(EnvSource::Color(Vec3A::from(c))),
                        (None, None) => None,
                    },
                    strength: e.strength,
                    rotation: e.rotate,
                };
                let env_start = Instant::now();
                let env = from_file.apply_with(&Environment::none(), &ledger)?;
                environment_time = env_start.elapsed();
                scene.set_environment(env);
            }
            let (lo, hi) = scene.bounds();
            let framing = framing::frame(lo, hi);
            let camera = match options.camera {
                Some(i) if i >= cameras => {
                    return Err(LoadError::Usage(format!(
                        "--camera {i}: {name}'s models have {cameras} camera{}",
                        if cameras == 1 { "" } else { "s" }
                    )));
                }
                Some(i) => Some(scene.cameras[i].clone()),
                None => match shot.camera {
                    ShotCamera::Placed(c) => Some(c),
                    ShotCamera::Default => scene.cameras.first().cloned().or(shot.box_camera),
                },
            };
            let view = view_through(camera.as_ref(), &framing);
            let lit = shot.has_lights || !scene.environment().is_black() || environment.is_some();
            default_light = add_default_light(&mut scene, &view, options.default_light, lit);
            if let Some(p) = options.light_power {
                scene.light.power = Vec3A::splat(p);
            }
            (scene, view)
        }
    };
    if let Some(p) = options.light_pos {
        scene.light.position = p;
    }
    match environment {
        Some(env) => scene.set_environment(env),
        None if options.environment.is_given() => {
            let env = options
                .environment
                .apply_with(scene.environment(), &ledger)?;
            scene.set_environment(env);
        }
        None => {}
    }
    let summary = LoadSummary {
        triangles: scene.triangles().len(),
        materials: scene.materials().len(),
        textures: scene.textures().len(),
        texture_bytes: scene.textures().memory_bytes(),
        geometry_bytes: scene.geometry_bytes(),
        punctual_lights: scene.lights().len() + usize::from(scene.point_power() > 0.0),
        emitters: scene.emitter_count(),
        analytic_shapes: scene.analytic_shape_count(),
        emitting_shapes: scene.emitting_shape_count(),
        environment_size: scene
            .environment()
            .env_map()
            .map(|m| [m.width(), m.height()]),
        environment_bytes: scene
            .environment()
            .env_map()
            .map_or(0, |m| m.memory_bytes()),
        environment_time,
        time: start.elapsed(),
        needs: ledger.needs(),
        variants,
        variant,
        plugins,
    };
    if let Some((density, albedo)) = options.fog {
        scene
            .add_fog(density, albedo)
            .map_err(|e| LoadError::Usage(format!("--fog: {e}")))?;
    } else if let Some((sigma_t, albedo, phase)) = settings.fog {
        // The scene file's fog (checked when the file was read).
        scene
            .add_fog_with(sigma_t, albedo, phase)
            .map_err(|e| LoadError::Usage(format!("[[medium]] fog: {e}")))?;
    }
    if options.light_selection != scene.light_selection() {
        scene.set_light_selection(options.light_selection);
    }
    scene.set_light_numbers(options.light_numbers.unwrap_or(match kind {
        SceneKind::Mitsuba => crate::scene::LightNumbers::Stratified,
        _ => crate::scene::LightNumbers::Independent,
    }));
    Ok(Loaded {
        scene,
        kind,
        view,
        summary,
        warnings,
        default_light,
        settings,
        animations,
    })
}

/// The starting view through `camera`, or framing the scene from +z (y up)
/// without one.
fn view_through(camera: Option<&SceneCamera>, framing: &framing::Framing) -> InitialView {
    match camera {
        Some(c) => InitialView {
            position: c.position,
            rotation: c.rotation,
            lens: c.lens,
            aspect_ratio: c.aspect_ratio,
            depth_of_field: c.depth_of_field,
            window: c.window,
            step: framing.step,
        },
        None => InitialView {
            position: framing.camera_pos,
            rotation: Y_UP_TOWARDS_MINUS_Z,
            lens: Lens::LAB,
            aspect_ratio: None,
            depth_of_field: DepthOfField::default(),
            window: None,
            step: framing.step,
        },
    }
}

/// Whether a scene's emitters are strong enough to light it: their power
/// spread over the bounding sphere, `P / (4πr²)`, is at least
/// [`DEFAULT_LIGHT_EMITTER_RATIO`] of [`DEFAULT_LIGHT_IRRADIANCE`].
fn emitters_light(scene: &Scene) -> bool {
    let r = scene.radius().max(1e-6);
    let emitter_irradiance = scene.emitted_power() / (4.0 * std::f32::consts::PI * r * r);
    emitter_irradiance >= DEFAULT_LIGHT_EMITTER_RATIO * DEFAULT_LIGHT_IRRADIANCE
}

/// Adds raylab's default lighting (a key light above and to the right of the
/// starting camera giving [`DEFAULT_LIGHT_IRRADIANCE`] at the scene's centre,
/// and a grey sky) when `when` says so: `auto` adds it to a scene that is not
/// `lit` (no punctual lights, no environment), whose emitters are too weak
/// to light it and whose media emit nothing. Returns whether it was added.
fn add_default_light(scene: &mut Scene, view: &InitialView, when: DefaultLight, lit: bool) -> bool {
    let add = match when {
        DefaultLight::On => true,
        DefaultLight::Off => false,
        // (A medium that glows lights the scene as an emitter does.)
        DefaultLight::Auto => {
            !lit && !emitters_light(scene) && !scene.media().media.iter().any(Medium::emits)
        }
    };
    if add {
        // A key light above and to the right of the starting camera,
        // giving DEFAULT_LIGHT_IRRADIANCE at the scene's centre.
        let (lo, hi) = scene.bounds();
        let centre = (lo + hi) * 0.5;
        let radius = scene.radius().max(1e-3);
        let offset = view.rotation * Vec3A::new(0.5, -0.7, 0.0) * radius;
        let position = view.position + offset;
        let r2 = (position - centre).length_squared().max(1e-6);
        scene.light = PointLight {
            position,
            power: Vec3A::splat(DEFAULT_LIGHT_IRRADIANCE * 4.0 * std::f32::consts::PI * r2),
        };
        scene.set_environment(Environment::constant(Vec3A::splat(DEFAULT_SKY_RADIANCE)));
    }
    add
}
