//! The scene file as written: the TOML sections ([`ShotFile`] and the
//! sections under it), every key known (an unknown one is an error with its
//! line and column, from the parser's spans), and [`parse`].

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use serde::Deserialize;

use super::error::{ShotError, invalid};

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
    /// `[[medium]]`: participating media.
    #[serde(default, rename = "medium")]
    pub media: Vec<MediumSection>,
}

/// `[[medium]]`, by `type`: what fills space (see docs/media.md).
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(tag = "type", rename_all = "lowercase", deny_unknown_fields)]
pub enum MediumSection {
    /// Fog wherever no other medium is, within the scene's bounds (as
    /// `--fog`).
    Fog {
        /// Extinction per scene unit: one number or one per channel.
        density: Scale,
        /// The single-scattering albedo (default white).
        color: Option<[f32; 3]>,
        /// The Henyey–Greenstein mean cosine (default 0: isotropic).
        anisotropy: Option<f32>,
    },
    /// An OpenVDB file's float grid (the extinction, times `density`) in
    /// an invisible box around it, placed as a model is.
    Vdb {
        /// The `.vdb` file (relative to the scene file).
        file: PathBuf,
        /// The grid's name (default: the file's first float grid).
        grid: Option<String>,
        /// Multiplies the grid's values into the extinction per scene unit.
        density: f32,
        /// The single-scattering albedo (default white).
        color: Option<[f32; 3]>,
        /// The Henyey–Greenstein mean cosine (default 0: isotropic).
        anisotropy: Option<f32>,
        /// Scale (after the file's own transform).
        scale: Option<Scale>,
        /// Then rotate by these degrees about x, then y, then z.
        rotate: Option<[f32; 3]>,
        /// Then move.
        translate: Option<[f32; 3]>,
        /// The radiance it emits with where it is thick (light per unit
        /// length `σa · Le`: it needs a `color` below 1), times
        /// `emission_scale`.
        emission: Option<[f32; 3]>,
        /// Or a grid of the same file holding temperatures: it glows as a
        /// blackbody at `(T − temperature_offset) · temperature_scale`
        /// kelvin, times `emission_scale` (pbrt-v4's temperature grids:
        /// [`crate::materials::blackbody::blackbody_rgb`]).
        temperature: Option<String>,
        /// Multiplies the temperature after the offset, to kelvin
        /// (default 1).
        temperature_scale: Option<f32>,
        /// Subtracted from the grid's temperature (default 0).
        temperature_offset: Option<f32>,
        /// Multiplies the emission (default 1).
        emission_scale: Option<f32>,
    },
    /// A homogeneous medium filling a model (whose meshes must be closed).
    Inside {
        /// The `[[model]]`'s name.
        model: String,
        /// Extinction per scene unit: one number or one per channel.
        density: Scale,
        /// The single-scattering albedo (default white).
        color: Option<[f32; 3]>,
        /// The Henyey–Greenstein mean cosine (default 0: isotropic).
        anisotropy: Option<f32>,
        /// The radiance it emits with where it is thick (light per unit
        /// length `σa · Le`: it needs a `color` below 1), times
        /// `emission_scale`.
        emission: Option<[f32; 3]>,
        /// Or it glows with the colour of a blackbody at this many kelvin
        /// at luminance `emission_scale` (pbrt-v4's `"blackbody Le"`:
        /// [`crate::materials::blackbody::blackbody_color`]).
        temperature: Option<f32>,
        /// Multiplies the emission (default 1).
        emission_scale: Option<f32>,
    },
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
    /// Adaptive sampling's noise threshold (`--noise-threshold`).
    pub noise_threshold: Option<f32>,
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
    pub fn choice(&self) -> crate::load::gltf::AnimationChoice {
        match self {
            AnimationKey::Index(i) => crate::load::gltf::AnimationChoice::Index(*i as usize),
            AnimationKey::Name(n) => crate::load::gltf::AnimationChoice::Name(n.clone()),
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
    /// Subsurface scattering: the mean free path inside, per channel, in
    /// scene units (the base colour is then the colour a thick piece
    /// shows); the model's meshes must be closed.
    pub subsurface: Option<[f32; 3]>,
    /// The Henyey–Greenstein mean cosine of the scattering inside
    /// (default 0).
    pub subsurface_anisotropy: Option<f32>,
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
}
