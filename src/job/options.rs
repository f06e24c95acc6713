//! The options of a render job, as the command line takes them: one
//! definition (with `clap`'s derive) for `raylab render`, `raylab view`, the
//! library and the Python package, so that names, defaults, limits and help
//! texts cannot drift apart; the parsers of their values; and the rules that
//! merge them with a scene file's `[render]` settings and the scene's kind.
// The fields' doc comments are the command line's help texts, shown as
// written (`glass[:IOR]`, `[default: ...]`), not Markdown links.
#![allow(rustdoc::broken_intra_doc_links)]

use std::path::PathBuf;

use clap::Args;
use glam::Vec3A;

use crate::camera::{Aperture, DepthOfField, Focus};
use crate::integrators::Integrator;
use crate::load::SceneKind;
use crate::load::cornell::{self, MaterialChoice};

pub use crate::limits::{MAX_PIXELS, MAX_SIDE, MAX_SPP, MAX_TIME};

/// What to render and how to light and show it: the scene, image size,
/// camera and light options of `raylab render` and `raylab view`. Each field
/// is the command-line option of the same name (`max_depth` is `--max-depth`),
/// with the same default and the same help text.
#[derive(Debug, Clone, Args)]
pub struct SceneOptions {
    /// Scene to load: `cornell` (the lab's box, built in), `cornell-area` (the box
    /// lit by a ceiling area light instead of the point light), a Wavefront OBJ
    /// file or a glTF 2.0 file (.gltf or .glb).
    #[arg(default_value = "cornell")]
    pub scene: String,
    /// Image width in pixels [default: 500 for the box and OBJ meshes; for glTF
    /// 600 × the camera's aspect ratio, else 800].
    #[arg(long, value_name = "W", allow_hyphen_values = true, value_parser = parse_side)]
    pub width: Option<u32>,
    /// Image height in pixels [default: 500 for the box and OBJ meshes, 600 for glTF].
    #[arg(long, value_name = "H", allow_hyphen_values = true, value_parser = parse_side)]
    pub height: Option<u32>,
    /// How to light the image: `flat` (surface colour), `direct` (the lab's model),
    /// `path` (global illumination in physical units), `bdpt` (bidirectional path
    /// tracing: caustics from small lights) or `vcm` (`bdpt` with vertex merging:
    /// also caustics seen through glass or in mirrors; consistent) [default: path
    /// for glTF, direct otherwise].
    #[arg(long, value_parser = parse_integrator)]
    pub integrator: Option<Integrator>,
    /// Which of a glTF file's cameras to look through (depth-first order of the
    /// node tree, from 0).
    #[arg(long, value_name = "N", allow_hyphen_values = true, value_parser = parse_camera)]
    pub camera: Option<usize>,
    /// glTF: which material variant (`KHR_materials_variants`) to show, by
    /// name; the load summary lists a file's variants. In a scene file, the
    /// models that have a variant of that name show it.
    #[arg(long, value_name = "NAME")]
    pub variant: Option<String>,
    /// Mitsuba scenes: a value for a `$NAME` in the file (as `mitsuba -D
    /// NAME=VALUE`), replacing its `<default>`; repeat for more.
    #[arg(short = 'D', long = "define", value_name = "NAME=VALUE", value_parser = parse_define)]
    pub define: Vec<(String, String)>,
    /// glTF: when to add raylab's default lighting (a key light and a grey sky):
    /// `auto` (when the file has no punctual light and no emitters strong enough
    /// to light it), `on` or `off`.
    #[arg(long, value_name = "WHEN", default_value = "auto", value_parser = parse_default_light)]
    pub default_light: crate::load::DefaultLight,
    /// How `path` chooses a light for each shading point: `tree` (a light tree
    /// that weighs distance, orientation and the surface's side), `power` (by
    /// each light's power) or `uniform` (for comparisons).
    #[arg(long, value_name = "HOW", default_value = "tree", value_parser = parse_light_selection)]
    pub light_selection: crate::scene::LightSelection,
    /// How the light tree's choice gets its number: `stratified` (the light
    /// sample's own, so that Sobol' points stay stratified across the
    /// lights: less noise with several lights) or `independent` (as raylab
    /// always chose) [default: stratified for Mitsuba scenes, independent
    /// for the rest, whose images stay as they were].
    #[arg(long, value_name = "HOW", value_parser = parse_light_numbers)]
    pub light_numbers: Option<crate::scene::LightNumbers>,
    /// Tone mapping of PNG output and the viewer: `clamp`, `aces` or
    /// `khronos-pbr-neutral` [default: khronos-pbr-neutral for glTF, clamp otherwise].
    #[arg(long, value_name = "OP", value_parser = parse_tonemap)]
    pub tonemap: Option<crate::film::ToneMap>,
    /// Longest path for `path`, in segments as in Mitsuba (1: emitters only, 2:
    /// direct light, ...) [default: unbounded; Russian roulette ends paths].
    #[arg(long, value_name = "N", allow_hyphen_values = true, value_parser = parse_max_depth)]
    pub max_depth: Option<u32>,
    /// Sample points of `path`: `sobol` (Owen-scrambled Sobol' for the pixel and
    /// the first two bounces) or `independent` (PCG32 only).
    #[arg(long, default_value = "sobol", value_parser = parse_sampler)]
    pub sampler: crate::integrators::path::SamplerKind,
    /// Pixel filter of `path`: `box` (each pixel averages its own square),
    /// `gaussian[:STDDEV]` (Mitsuba's, σ 0.5 by default, out to 4σ) or
    /// `tent[:RADIUS]` (radius 1 by default); samples are drawn from it, so
    /// pixels stay plain means [default: the scene file's, else box].
    #[arg(long, value_name = "FILTER", value_parser = parse_filter)]
    pub filter: Option<crate::sampling::filter::PixelFilter>,
    /// How `path` uses a filter other than the box: `sample` (each sample's
    /// point drawn from the filter, counted in its own pixel) or `splat`
    /// (each sample added to every pixel within the filter's radius, weighted,
    /// as Mitsuba's film does: the same image, less noise per pixel; filters
    /// reaching more than 4 pixels, adaptive sampling and `--aov variance`
    /// sample) [default: splat for Mitsuba scenes, sample otherwise].
    #[arg(long, value_name = "HOW", value_parser = parse_reconstruction)]
    pub reconstruction: Option<crate::sampling::filter::Reconstruction>,
    /// Materials of the built-in box's parts for `path`, e.g.
    /// `tall=mirror,short=glass,floor=gold:0.2`. Parts: floor, ceiling, back, left,
    /// right, short, tall. Materials: diffuse, mirror, glass[:IOR], gold, copper,
    /// silver, aluminium, conductor (metals take :ALPHA, the GGX width; 0 polished).
    #[arg(long, value_name = "PART=MATERIAL,...", value_delimiter = ',', value_parser = parse_assignment)]
    pub material: Vec<(String, MaterialChoice)>,
    /// PNG exposure in stops: PNG values are multiplied by 2^E (and by π for
    /// `path`, see README) before the sRGB encoding; EXR is never scaled.
    #[arg(long, value_name = "E", allow_hyphen_values = true, value_parser = parse_exposure)]
    pub exposure: Option<f32>,
    /// Camera position [default: 0,0,-3 in the box; framing the mesh otherwise].
    #[arg(long, value_name = "X,Y,Z", allow_hyphen_values = true, value_parser = parse_vec3)]
    pub camera_pos: Option<Vec3A>,
    /// Camera yaw in degrees (positive turns towards +x).
    #[arg(long, default_value_t = 0.0, value_name = "DEG", allow_hyphen_values = true, value_parser = parse_angle)]
    pub yaw: f32,
    /// Camera pitch in degrees (positive looks up), within ±89.
    #[arg(long, default_value_t = 0.0, value_name = "DEG", allow_hyphen_values = true, value_parser = parse_pitch)]
    pub pitch: f32,
    /// A thin lens of this radius in scene units, for depth of field (0: a
    /// pinhole) [default: a pinhole, or the scene file's lens].
    #[arg(long, value_name = "RADIUS", conflicts_with = "f_number", allow_hyphen_values = true, value_parser = parse_aperture)]
    pub aperture: Option<f32>,
    /// A thin lens of this f-number: its diameter is the focal length over N,
    /// the focal length that of a 36 mm sensor across the image's longer side,
    /// scene units taken as metres (as in Blender); perspective cameras only.
    #[arg(long, value_name = "N", allow_hyphen_values = true, value_parser = parse_f_number)]
    pub f_number: Option<f32>,
    /// Distance of the thin lens's focus plane along the view axis, in scene
    /// units [default: the first hit through the image's centre].
    #[arg(long, value_name = "D", conflicts_with = "focus_pixel", allow_hyphen_values = true, value_parser = parse_focus_distance)]
    pub focus_distance: Option<f32>,
    /// Focus the thin lens on the first hit through the centre of pixel X,Y
    /// (column and row from the top-left corner), at its distance along the
    /// view axis.
    #[arg(long, value_name = "X,Y", allow_hyphen_values = true, value_parser = parse_pixel)]
    pub focus_pixel: Option<[u32; 2]>,
    /// Blades of a polygonal aperture, 3 to 64 (0: round) [default: round].
    #[arg(long, value_name = "N", allow_hyphen_values = true, value_parser = parse_blades)]
    pub aperture_blades: Option<u32>,
    /// Point light position [default: 0,-0.5,-0.7 in the box; near the camera otherwise].
    #[arg(long, value_name = "X,Y,Z", allow_hyphen_values = true, value_parser = parse_vec3)]
    pub light_pos: Option<Vec3A>,
    /// Point light power P per colour channel [default: 14 in the box; for a mesh,
    /// enough for a direct light of 0.5 at its centre].
    #[arg(long, value_name = "P", allow_hyphen_values = true, value_parser = parse_non_negative)]
    pub light_power: Option<f32>,
    /// Light the scene with an equirectangular environment map (Radiance .hdr or
    /// OpenEXR .exr, +y up), also seen as the background.
    #[arg(long, value_name = "FILE.hdr|FILE.exr", conflicts_with = "env_color")]
    pub env: Option<PathBuf>,
    /// Fill the scene's bounding box with fog for `path`: extinction DENSITY
    /// per scene unit (a mean free path of 1/DENSITY), scattering
    /// isotropically with albedo R,G,B [default: 1,1,1]. The sky and the
    /// sun light it from outside. See docs/media.md.
    #[arg(long, value_name = "DENSITY[,R,G,B]", value_parser = parse_fog)]
    pub fog: Option<(f32, Vec3A)>,
    /// A constant sky of radiance R,G,B (W/sr/m²) instead of a map.
    #[arg(long, value_name = "R,G,B", allow_hyphen_values = true, value_parser = parse_color)]
    pub env_color: Option<Vec3A>,
    /// Multiply the environment's radiance by S, at most 1e6 [default: 1].
    #[arg(long, value_name = "S", allow_hyphen_values = true, value_parser = parse_strength)]
    pub env_strength: Option<f32>,
    /// Turn the environment about +y by DEG degrees (positive: counter-clockwise
    /// seen from above).
    #[arg(long, value_name = "DEG", allow_hyphen_values = true, value_parser = parse_angle)]
    pub env_rotate: Option<f32>,
    /// Add a Wavefront OBJ mesh to the scene (repeatable), e.g. into the lab box.
    #[arg(long, value_name = "MESH.obj")]
    pub add: Vec<PathBuf>,
    /// Place the added meshes: operations in order, separated by ';': `scale S`,
    /// `scale X Y Z`, `rotate x|y|z DEG`, `translate X Y Z`, `fit HEIGHT` (base at
    /// y = 0, centred, scaled to the height). One for all meshes, or one per --add.
    /// The bunny on the lab box's floor: "fit 0.8; rotate x 180; translate 0.3 1 -0.3".
    #[arg(long, value_name = "OPS", allow_hyphen_values = true)]
    pub transform: Vec<crate::load::transform::Transform>,
    /// Ambient term N added to the direct light (the lab's stand-in for indirect
    /// light) [default: 0.5 in the box, 0.15 for a mesh].
    #[arg(long, value_name = "N", allow_hyphen_values = true, value_parser = parse_non_negative)]
    pub ambient: Option<f32>,
    /// Most memory the scene, textures, environment map and film may need
    /// (e.g. 4G, 512M; 0 or none: no limit) [default: 3/4 of physical memory, or of a lower cgroup limit].
    #[arg(long, value_name = "SIZE", allow_hyphen_values = true, value_parser = crate::memory::parse_budget)]
    pub max_memory: Option<crate::memory::MemoryBudget>,
    /// Keep decoded textures and built BVHs in DIR (created if missing) and
    /// reuse them: the tasks of a render farm then decode and build once.
    /// Entries are keyed by content and by this raylab build, so they never
    /// go stale.
    #[arg(long, value_name = "DIR")]
    pub cache: Option<PathBuf>,
    /// Denoise with Intel Open Image Denoise, guided by the render's albedo
    /// and normal (loaded at run time: `pip install pyoidn`, or set
    /// RAYLAB_OIDN to the library); `--denoise=false` turns a scene file's
    /// `denoise = true` off. The viewer shows the denoised frame once the
    /// camera rests (key N toggles it).
    #[arg(long, value_name = "BOOL", num_args = 0..=1, default_missing_value = "true", require_equals = true)]
    pub denoise: Option<bool>,
    /// A glTF file's animation: `--at` and `--animation`.
    #[command(flatten)]
    pub animation: super::animate::AnimationArgs,
}

/// Everything a render job takes: the scene options and what `raylab render`
/// adds (output, AOVs, samples, time, seed, threads, checkpoints, parts,
/// frames). Each field is the command-line option of the same name, with the
/// same default; [`JobOptions::new`] gives the defaults for a scene.
#[derive(Debug, Clone, Args)]
pub struct JobOptions {
    /// The scene and how to light and show it.
    #[command(flatten)]
    pub scene: SceneOptions,
    /// Output file; `.png` (8-bit sRGB) or `.exr` (linear float32) [default: SCENE.png].
    #[arg(short, long, value_name = "FILE")]
    pub output: Option<PathBuf>,
    /// Also write AOVs as extra EXR channels, averaged over each pixel's
    /// samples: any of albedo, normal (the denoiser's guides, through mirrors
    /// and glass), depth, position (of the camera ray's hit), variance (of
    /// the pixel's value), e.g. `albedo,normal` (needs an .exr output;
    /// SCENE.exr without -o).
    #[arg(long, value_name = "AOV,...", value_parser = parse_aovs)]
    pub aov: Option<crate::aov::AovSet>,
    /// Samples per pixel: sample 0 goes through the pixel centre, others are
    /// jittered (`path` jitters all). With --time: at most this many [default: no limit].
    #[arg(long, value_name = "N", allow_hyphen_values = true, value_parser = parse_spp)]
    pub spp: Option<u32>,
    /// Render progressively until this many seconds are spent, then write.
    #[arg(long, value_name = "SECONDS", allow_hyphen_values = true, value_parser = parse_time)]
    pub time: Option<f64>,
    /// Adaptive sampling: after a minimum of samples (32 at 0.1, 64 at 0.01),
    /// pixels whose estimated error is below T stop taking samples, checked
    /// every 16 samples; --spp caps them, --time bounds the render. The error
    /// is Blender Cycles' (the difference of two halves of the samples over
    /// the square root of the brightness), so that T means what Cycles'
    /// noise threshold means (0.01 is Blender's default). The summary says
    /// how many samples the pixels took on average; `--aov samples` shows
    /// where.
    #[arg(long, value_name = "T", allow_hyphen_values = true, value_parser = parse_threshold)]
    pub noise_threshold: Option<f32>,
    /// Seed of the sample positions; the same seed gives the same image on any
    /// number of threads.
    #[arg(long, value_name = "S", allow_hyphen_values = true)]
    pub seed: Option<u64>,
    /// Worker threads [default: one per core].
    #[arg(long, value_name = "N", allow_hyphen_values = true, value_parser = parse_threads)]
    pub threads: Option<usize>,
    /// Save the render's sums to FILE every --checkpoint-every seconds and when
    /// stopped, and resume from FILE if it holds samples of the same render:
    /// the image is then the same, bit for bit, as without a stop. A FILE made
    /// for another scene or settings is refused. Removed once the image is
    /// written. Without it, a render stopped by Ctrl-C or SIGTERM saves its sums
    /// to .NAME.raylab-checkpoint beside the output, and the same command
    /// resumes from there.
    #[arg(long, value_name = "FILE")]
    pub checkpoint: Option<PathBuf>,
    /// Seconds between saves of --checkpoint (longer when a save takes more
    /// than a twentieth of that).
    #[arg(long, value_name = "SECONDS", default_value_t = 10.0, requires = "checkpoint", allow_hyphen_values = true, value_parser = parse_every)]
    pub checkpoint_every: f64,
    /// After the render, find the first sample that came out NaN or infinite
    /// and say where it went bad (pixel, sample, path vertex); exit code 3 if
    /// there is one.
    #[arg(long)]
    pub nan_check: bool,
    /// Render only tile K (from 0) of N: the image's blocks of 4 rows K, K+N,
    /// K+2N, ... (interleaved, so that tiles cost about the same). Writes a
    /// part (-o must be .exr) that `raylab merge` combines with the other
    /// tiles into the image one render gives, bit for bit.
    #[arg(long, value_name = "K/N", value_parser = parse_tile)]
    pub tile: Option<(u32, u32)>,
    /// Render only samples A to B-1 of every pixel, of the --spp the whole
    /// render takes. Writes a part (-o must be .exr) that `raylab merge`
    /// combines with the other sample ranges, bit for bit.
    #[arg(long, value_name = "A..B", value_parser = parse_range)]
    pub samples: Option<(u32, u32)>,
    /// Render frames A to B-1 of an animation (or `F` for frame F alone), one
    /// file each: -o needs a frame-number field, e.g. `out-%04d.png`. Frames
    /// are independent, so a job array can give each task one.
    #[arg(long, value_name = "A..B", value_parser = parse_frames)]
    pub frames: Option<(u32, u32)>,
    /// Turntable: frame F is seen from the scene's camera turned F × DEG
    /// degrees around the vertical axis through the centre of the scene's
    /// bounds (counter-clockwise seen from above).
    #[arg(long, value_name = "DEG", requires = "frames", allow_hyphen_values = true, value_parser = parse_finite)]
    pub orbit: Option<f32>,
    /// Frames per second of an animated glTF file's --frames: frame F shows
    /// the animation at F / FPS seconds [default: 24].
    #[arg(long, value_name = "FPS", requires = "frames", value_parser = super::animate::parse_fps)]
    pub fps: Option<f64>,
    /// No progress bar and no summary line.
    #[arg(short, long)]
    pub quiet: bool,
}

impl JobOptions {
    /// Whether this renders a part of an image (--tile or --samples).
    pub fn is_part(&self) -> bool {
        self.tile.is_some() || self.samples.is_some()
    }

    /// Checks what clap cannot: AOVs and parts need an EXR output, frames a
    /// frame-number pattern.
    pub fn validate(&self) -> Result<(), String> {
        if self.is_part() {
            let what = if self.tile.is_some() {
                "--tile"
            } else {
                "--samples"
            };
            match &self.output {
                Some(o)
                    if crate::film::Format::from_path(o).ok() == Some(crate::film::Format::Exr) => {
                }
                Some(o) => {
                    return Err(format!(
                        "error: {what} writes a part of the image for `raylab merge`: the output must be .exr, not {}",
                        o.display()
                    ));
                }
                None => {
                    return Err(format!(
                        "error: {what} writes a part of the image for `raylab merge`: name it with -o PART.exr"
                    ));
                }
            }
            if self.time.is_some() {
                return Err(format!(
                    "error: {what} cannot be combined with --time: every part must take the same samples"
                ));
            }
        }
        if let (Some((a, b)), Some(t)) = (self.samples, self.noise_threshold) {
            return Err(format!(
                "error: --samples {a}..{b} cannot be combined with --noise-threshold {t}: \
                 which pixels stop depends on all of their earlier samples (split by --tile instead)"
            ));
        }
        if let Some((a, b)) = self.samples {
            let Some(spp) = self.spp else {
                return Err(format!(
                    "error: --samples {a}..{b} needs --spp, the samples per pixel of the whole render"
                ));
            };
            if b > spp {
                return Err(format!(
                    "error: --samples {a}..{b} goes past --spp {spp} (the whole render's samples)"
                ));
            }
        }
        if let (Some(at), Some((a, b))) = (self.scene.animation.at, self.frames) {
            return Err(format!(
                "error: --at {at} renders one moment; --frames {a}..{b} renders frame F at F / --fps seconds: give one of them"
            ));
        }
        if let Some((a, _)) = self.frames {
            let pattern = self
                .output
                .as_ref()
                .and_then(|o| crate::farm::frame_path(o, a));
            if pattern.is_none() {
                return Err(
                    "error: --frames writes a file per frame: -o needs a frame-number field, e.g. -o out-%04d.png"
                        .to_string(),
                );
            }
        }
        if let (Some(aovs), Some(output)) = (&self.aov, &self.output)
            && crate::film::Format::from_path(output).ok() != Some(crate::film::Format::Exr)
        {
            return Err(format!(
                "error: --aov {aovs} writes extra EXR channels: the output must be .exr, not {}",
                output.display()
            ));
        }
        Ok(())
    }
}

impl SceneOptions {
    /// The `path` integrator with the options given (for the viewer's key 3).
    pub fn integrator_for_path(&self) -> Integrator {
        Self {
            integrator: Some(Integrator::path()),
            ..self.clone()
        }
        .integrator(SceneKind::Lab)
    }

    /// The integrator with its options from the other arguments; without
    /// `--integrator`, `path` for glTF scenes and `direct` for the others.
    pub fn integrator(&self, kind: SceneKind) -> Integrator {
        let default = match kind {
            SceneKind::Gltf | SceneKind::Shot | SceneKind::Mitsuba => Integrator::path(),
            SceneKind::Lab | SceneKind::Mesh => Integrator::Direct,
        };
        let chosen = self.integrator.unwrap_or(default);
        match chosen.path_options() {
            Some(mut options) => {
                if let Some(d) = self.max_depth {
                    options.max_depth = d;
                }
                options.sampler = self.sampler;
                if let Some(f) = self.filter {
                    options.filter = f;
                }
                options.reconstruction = self.reconstruction.unwrap_or(match kind {
                    SceneKind::Mitsuba => crate::sampling::filter::Reconstruction::Splat,
                    _ => crate::sampling::filter::Reconstruction::Sample,
                });
                chosen.with_path_options(options)
            }
            None => chosen,
        }
    }

    /// Checks what single arguments cannot: the image's total size, and that
    /// transforms pair with the added meshes.
    pub fn validate(&self) -> Result<(), String> {
        let (adds, transforms) = (self.add.len(), self.transform.len());
        if transforms > 1 && transforms != adds || transforms == 1 && adds == 0 {
            return Err(format!(
                "error: --transform given {transforms} times for {adds} --add meshes \
                 (give one for all, or one per mesh)"
            ));
        }
        if !self.material.is_empty() && !matches!(self.scene.as_str(), "cornell" | "cornell-area") {
            return Err(format!(
                "error: --material names parts of the built-in box, not of {}",
                self.scene
            ));
        }
        if self.camera.is_some() && !is_gltf(&self.scene) {
            return Err(format!(
                "error: --camera picks a camera of a glTF file; {} has none",
                self.scene
            ));
        }
        if let (Some(w), Some(h)) = (self.width, self.height) {
            check_pixels(w, h)?;
        }
        Ok(())
    }

    /// The image size: the options, else the scene's defaults (500×500 for the
    /// box and meshes; for glTF height 600 and the width from the camera's
    /// aspect ratio, else 800×600); with only one side given, the other follows
    /// the aspect ratio.
    pub fn size(&self, kind: SceneKind, aspect_ratio: Option<f32>) -> Result<(u32, u32), String> {
        let (default, aspect) = match kind {
            SceneKind::Gltf | SceneKind::Shot | SceneKind::Mitsuba => match aspect_ratio {
                Some(a) => (
                    ((600.0 * a).round().clamp(1.0, MAX_SIDE as f32) as u32, 600),
                    a,
                ),
                None => ((800, 600), 4.0 / 3.0),
            },
            SceneKind::Lab | SceneKind::Mesh => ((500, 500), 1.0),
        };
        let side = |x: f32| x.round().clamp(1.0, MAX_SIDE as f32) as u32;
        let (w, h) = match (self.width, self.height) {
            (Some(w), Some(h)) => (w, h),
            (Some(w), None) => (w, side(w as f32 / aspect)),
            (None, Some(h)) => (side(h as f32 * aspect), h),
            (None, None) => default,
        };
        check_pixels(w, h)?;
        Ok((w, h))
    }
}

/// Refuses images of more than [`MAX_PIXELS`].
fn check_pixels(w: u32, h: u32) -> Result<(), String> {
    let pixels = w as u64 * h as u64;
    if pixels > MAX_PIXELS {
        return Err(format!(
            "error: --width {w} × --height {h} is {pixels} pixels, more than the limit of {MAX_PIXELS}"
        ));
    }
    Ok(())
}

impl SceneOptions {
    /// The library's load options from the arguments.
    pub fn load_options(&self) -> crate::load::LoadOptions {
        crate::load::LoadOptions {
            add: self.add.clone(),
            transforms: self.transform.clone(),
            materials: self.material.clone(),
            light_power: self.light_power,
            light_pos: self.light_pos,
            ambient: self.ambient,
            camera: self.camera,
            default_light: self.default_light,
            light_selection: self.light_selection,
            light_numbers: self.light_numbers,
            variant: self.variant.clone(),
            defines: self.define.clone(),
            fog: self.fog,
            environment: crate::load::EnvironmentOptions {
                source: match (&self.env, self.env_color) {
                    (Some(path), _) => Some(crate::load::EnvSource::File(path.clone())),
                    (None, Some(c)) => Some(crate::load::EnvSource::Color(c)),
                    (None, None) => None,
                },
                strength: self.env_strength,
                rotation: self.env_rotate,
            },
            max_memory: self.memory_budget(),
            animation: self.animation.load_options(),
        }
    }

    /// The thin lens the options ask for (each part `None` where they leave
    /// it to the scene file).
    pub fn depth_of_field(&self) -> DepthOfField {
        DepthOfField {
            aperture: self
                .aperture
                .map(Aperture::Radius)
                .or(self.f_number.map(Aperture::FNumber)),
            focus: self
                .focus_distance
                .map(Focus::Distance)
                .or(self.focus_pixel.map(Focus::Pixel)),
            blades: self.aperture_blades,
        }
    }

    /// `--max-memory`, or its default.
    pub fn memory_budget(&self) -> crate::memory::MemoryBudget {
        self.max_memory
            .unwrap_or_else(crate::memory::MemoryBudget::machine_default)
    }
}

/// Whether a scene name is a glTF file or a scene file (which have cameras).
fn is_gltf(scene: &str) -> bool {
    std::path::Path::new(scene)
        .extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| {
            ["gltf", "glb", "toml", "xml"]
                .iter()
                .any(|x| e.eq_ignore_ascii_case(x))
        })
}

/// Whether a scene name is a scene file (raylab's `.toml` or a Mitsuba
/// `.xml`), which may carry render settings.
pub fn is_scene_file(scene: &str) -> bool {
    std::path::Path::new(scene)
        .extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("toml") || e.eq_ignore_ascii_case("xml"))
}

/// A scene file's render settings: a `.toml`'s `[render]`, a Mitsuba
/// file's film, sampler and integrator (with `defines`).
pub fn read_file_settings(
    scene: &str,
    defines: &[(String, String)],
) -> anyhow::Result<crate::load::shot::ShotSettings> {
    let path = std::path::Path::new(scene);
    let is_xml = path
        .extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("xml"));
    Ok(match is_xml {
        true => crate::load::mitsuba::read_settings(path, defines)?,
        false => crate::load::shot::read_settings(path)?,
    })
}

/// `NAME=VALUE` of `-D`.
fn parse_define(s: &str) -> Result<(String, String), String> {
    match s.split_once('=') {
        Some((name, value)) if !name.is_empty() => Ok((name.to_string(), value.to_string())),
        _ => Err(format!(
            "expected NAME=VALUE, got '{}'",
            crate::guard::quote(s)
        )),
    }
}

impl SceneOptions {
    /// These options with what they leave out taken from a scene file's
    /// `[render]` settings. A side of the image given here replaces the
    /// file's size: the other side then follows the file's aspect ratio when
    /// the file gives both (else the camera's, see [`SceneOptions::size`]).
    pub fn with_file_settings(&self, s: &crate::load::shot::ShotSettings) -> Self {
        let side = |x: f64| x.round().clamp(1.0, MAX_SIDE as f64) as u32;
        let file_aspect = match (s.width, s.height) {
            (Some(w), Some(h)) => Some(f64::from(w) / f64::from(h)),
            _ => None,
        };
        let (width, height) = match (self.width, self.height, file_aspect) {
            (None, None, _) => (s.width, s.height),
            (Some(w), None, Some(a)) => (Some(w), Some(side(f64::from(w) / a))),
            (None, Some(h), Some(a)) => (Some(side(f64::from(h) * a)), Some(h)),
            (w, h, _) => (w, h),
        };
        Self {
            width,
            height,
            integrator: self.integrator.or(s.integrator),
            max_depth: self.max_depth.or(s.max_depth),
            filter: self.filter.or(s.filter),
            tonemap: self.tonemap.or(s.tonemap),
            exposure: self.exposure.or(s.exposure),
            denoise: self.denoise.or(s.denoise),
            ..self.clone()
        }
    }

    /// The scene options of `raylab view SCENE` (or `raylab render SCENE`)
    /// given no other argument: every default of the command line.
    pub fn new(scene: &str) -> Self {
        JobOptions::new(scene).scene
    }
}

/// Parses the options alone, as the command line does.
#[derive(clap::Parser)]
struct Defaults {
    #[command(flatten)]
    options: JobOptions,
}

impl JobOptions {
    /// The options of `raylab render SCENE` given no other argument: every
    /// default of the command line (the scene file's settings are merged when
    /// the job starts).
    pub fn new(scene: &str) -> Self {
        use clap::Parser;
        let mut options = Defaults::try_parse_from(["raylab"])
            .expect("the options' defaults parse")
            .options;
        options.scene.scene = scene.to_string();
        options
    }

    /// These options with what they leave out taken from the scene file's
    /// `[render]` settings (when the scene is one).
    pub fn with_scene_file(&self) -> anyhow::Result<Self> {
        if !is_scene_file(&self.scene.scene) {
            return Ok(self.clone());
        }
        let s = read_file_settings(&self.scene.scene, &self.scene.define)?;
        Ok(Self {
            scene: self.scene.with_file_settings(&s),
            spp: self.spp.or(s.spp),
            time: self.time.or(s.time),
            noise_threshold: self.noise_threshold.or(s.noise_threshold),
            seed: self.seed.or(s.seed),
            fps: self.fps.or(s.fps),
            ..self.clone()
        })
    }
}

impl Default for JobOptions {
    /// The options of `raylab render`: the lab's box.
    fn default() -> Self {
        Self::new("cornell")
    }
}

fn parse_aovs(s: &str) -> Result<crate::aov::AovSet, String> {
    s.parse()
}

/// Two whole numbers around `sep` (`3/8`, `0..64`), or `expected` as the error.
fn parse_two(s: &str, sep: &str, expected: &str) -> Result<(u32, u32), String> {
    let bad = || format!("expected {expected}; got '{s}'");
    let (a, b) = s.split_once(sep).ok_or_else(bad)?;
    let number = |x: &str| x.trim().parse::<u32>().map_err(|_| bad());
    Ok((number(a)?, number(b)?))
}

/// `K/N` with K < N.
fn parse_tile(s: &str) -> Result<(u32, u32), String> {
    let (k, n) = parse_two(s, "/", "K/N, tile K (from 0) of N, e.g. 0/4")?;
    if n == 0 || k >= n {
        return Err(format!("tile {k}/{n}: K counts from 0 and must be below N"));
    }
    Ok((k, n))
}

/// `A..B` with A < B ≤ the sample limit.
fn parse_range(s: &str) -> Result<(u32, u32), String> {
    let (a, b) = parse_two(s, "..", "A..B, from A up to B-1, e.g. 0..64")?;
    if a >= b {
        return Err(format!("{a}..{b} is empty: B must be above A"));
    }
    if b > MAX_SPP {
        return Err(format!("{a}..{b} goes past the limit of {MAX_SPP} samples"));
    }
    Ok((a, b))
}

/// `A..B` or `F` (for `F..F+1`).
fn parse_frames(s: &str) -> Result<(u32, u32), String> {
    if let Ok(f) = s.trim().parse::<u32>() {
        return f
            .checked_add(1)
            .map(|g| (f, g))
            .ok_or_else(|| format!("frame {f} is too large"));
    }
    let (a, b) = parse_two(s, "..", "A..B (frames A to B-1) or F")?;
    if a >= b {
        return Err(format!("frames {a}..{b} is empty: B must be above A"));
    }
    if b - a > 1_000_000 {
        return Err(format!("frames {a}..{b}: at most 1000000 frames"));
    }
    Ok((a, b))
}

fn parse_camera(s: &str) -> Result<usize, String> {
    s.parse::<usize>()
        .map_err(|_| "expected a camera number from 0".to_string())
}

fn parse_light_selection(s: &str) -> Result<crate::scene::LightSelection, String> {
    use crate::scene::LightSelection;
    match s {
        "tree" => Ok(LightSelection::Tree),
        "power" => Ok(LightSelection::Power),
        "uniform" => Ok(LightSelection::Uniform),
        _ => Err(format!("expected tree, power or uniform, not {s:?}")),
    }
}

fn parse_reconstruction(s: &str) -> Result<crate::sampling::filter::Reconstruction, String> {
    use crate::sampling::filter::Reconstruction;
    [Reconstruction::Sample, Reconstruction::Splat]
        .into_iter()
        .find(|r| r.name() == s)
        .ok_or_else(|| format!("expected sample or splat, not {s:?}"))
}

fn parse_light_numbers(s: &str) -> Result<crate::scene::LightNumbers, String> {
    use crate::scene::LightNumbers;
    match s {
        "stratified" => Ok(LightNumbers::Stratified),
        "independent" => Ok(LightNumbers::Independent),
        _ => Err(format!("expected stratified or independent, not {s:?}")),
    }
}

fn parse_default_light(s: &str) -> Result<crate::load::DefaultLight, String> {
    s.parse()
}

fn parse_tonemap(s: &str) -> Result<crate::film::ToneMap, String> {
    s.parse()
}

fn parse_side(s: &str) -> Result<u32, String> {
    match s.parse::<u32>() {
        Ok(v) if (1..=MAX_SIDE).contains(&v) => Ok(v),
        _ => Err(format!(
            "expected a whole number of pixels from 1 to {MAX_SIDE}"
        )),
    }
}

fn parse_spp(s: &str) -> Result<u32, String> {
    match s.parse::<u32>() {
        Ok(v) if (1..=MAX_SPP).contains(&v) => Ok(v),
        _ => Err(format!(
            "expected a whole number of samples from 1 to {MAX_SPP}"
        )),
    }
}

fn parse_assignment(s: &str) -> Result<(String, MaterialChoice), String> {
    let Some((part, material)) = s.split_once('=') else {
        return Err(format!("expected PART=MATERIAL, got '{s}'"));
    };
    let part = part.trim();
    if cornell::part(part).is_none() {
        let names: Vec<&str> = cornell::PART_NAMES.iter().map(|(n, _)| *n).collect();
        return Err(format!(
            "unknown part '{part}' (expected {})",
            names.join(", ")
        ));
    }
    Ok((part.to_string(), MaterialChoice::parse(material.trim())?))
}

fn parse_sampler(s: &str) -> Result<crate::integrators::path::SamplerKind, String> {
    crate::integrators::path::SamplerKind::ALL
        .into_iter()
        .find(|k| k.name() == s)
        .ok_or_else(|| format!("unknown sampler '{s}' (expected sobol or independent)"))
}

/// `box`, `gaussian[:STDDEV]` or `tent[:RADIUS]`.
pub fn parse_filter(s: &str) -> Result<crate::sampling::filter::PixelFilter, String> {
    use crate::sampling::filter::PixelFilter;
    let (name, width) = match s.split_once(':') {
        Some((n, w)) => (n, Some(w)),
        None => (s, None),
    };
    let given = width;
    let width = |default: f32| -> Result<f32, String> {
        match given {
            None => Ok(default),
            Some(w) => match w.parse::<f32>() {
                Ok(v) if v.is_finite() && v > 0.0 && v <= 64.0 => Ok(v),
                _ => Err(format!(
                    "filter width '{}' must be a number in (0, 64]",
                    crate::guard::quote(w)
                )),
            },
        }
    };
    match name {
        "box" if given.is_none() => Ok(PixelFilter::Box),
        "gaussian" => Ok(PixelFilter::gaussian(width(0.5)?)),
        "tent" => Ok(PixelFilter::tent(width(1.0)?)),
        _ => Err(format!(
            "unknown filter '{}' (expected box, gaussian[:STDDEV] or tent[:RADIUS])",
            crate::guard::quote(s)
        )),
    }
}

fn parse_max_depth(s: &str) -> Result<u32, String> {
    match s.parse::<u32>() {
        Ok(v) if v >= 1 => Ok(v),
        _ => Err("expected a whole number of path segments >= 1".into()),
    }
}

fn parse_time(s: &str) -> Result<f64, String> {
    match s.trim().parse::<f64>() {
        Ok(v) if v > 0.0 && v <= MAX_TIME => Ok(v),
        _ => Err(format!(
            "expected a time in seconds > 0 and at most {MAX_TIME}"
        )),
    }
}

/// A noise threshold: above 0, at most 1.
pub fn parse_threshold(s: &str) -> Result<f32, String> {
    match s.trim().parse::<f32>() {
        Ok(v) if v > 0.0 && v <= 1.0 => Ok(v),
        _ => Err(format!(
            "expected a noise threshold above 0 and at most 1 (e.g. 0.01), got '{s}'"
        )),
    }
}

fn parse_every(s: &str) -> Result<f64, String> {
    match s.trim().parse::<f64>() {
        Ok(v) if (0.0..=MAX_TIME).contains(&v) => Ok(v),
        _ => Err(format!("expected seconds from 0 to {MAX_TIME}")),
    }
}

fn parse_exposure(s: &str) -> Result<f32, String> {
    match parse_finite(s) {
        Ok(v) if v.abs() <= 64.0 => Ok(v),
        _ => Err("expected a finite number of stops from -64 to 64".into()),
    }
}

/// A thread count from 1 to 1024 (`--threads`).
pub fn parse_threads(s: &str) -> Result<usize, String> {
    match s.parse::<usize>() {
        Ok(v) if (1..=1024).contains(&v) => Ok(v),
        _ => Err("expected a whole number of threads from 1 to 1024".into()),
    }
}

fn parse_integrator(s: &str) -> Result<Integrator, String> {
    s.parse()
}

fn parse_finite(s: &str) -> Result<f32, String> {
    match s.trim().parse::<f32>() {
        Ok(v) if v.is_finite() => Ok(v),
        _ => Err("expected a finite number".into()),
    }
}

fn parse_angle(s: &str) -> Result<f32, String> {
    parse_finite(s).map_err(|_| "expected a finite angle in degrees".into())
}

fn parse_pitch(s: &str) -> Result<f32, String> {
    let limit = crate::controls::MAX_PITCH_DEG;
    match parse_angle(s)? {
        v if v.abs() <= limit => Ok(v),
        _ => Err(format!(
            "expected an angle from -{limit} to {limit} degrees"
        )),
    }
}

fn parse_strength(s: &str) -> Result<f32, String> {
    use crate::lights::environment::MAX_STRENGTH;
    match parse_finite(s) {
        Ok(v) if (0.0..=MAX_STRENGTH).contains(&v) => Ok(v),
        _ => Err(format!("expected a number from 0 to {MAX_STRENGTH:e}")),
    }
}

fn parse_non_negative(s: &str) -> Result<f32, String> {
    match parse_finite(s) {
        Ok(v) if v >= 0.0 => Ok(v),
        _ => Err("expected a finite number >= 0".into()),
    }
}

/// A lens length (`positive`: above 0, else at least 0) up to
/// [`crate::camera::MAX_LENS_LENGTH`], or `expected` as the error.
fn parse_lens_length(s: &str, positive: bool, expected: &str) -> Result<f32, String> {
    match parse_finite(s) {
        Ok(v) if crate::camera::lens_length_is_valid(v, positive) => Ok(v),
        _ => Err(format!(
            "expected {expected}, at most {:e}",
            crate::camera::MAX_LENS_LENGTH
        )),
    }
}

fn parse_aperture(s: &str) -> Result<f32, String> {
    parse_lens_length(s, false, "a lens radius >= 0 in scene units")
}

fn parse_f_number(s: &str) -> Result<f32, String> {
    parse_lens_length(s, true, "an f-number above 0, e.g. 2.8")
}

fn parse_focus_distance(s: &str) -> Result<f32, String> {
    parse_lens_length(s, true, "a distance above 0 in scene units")
}

/// `X,Y`: a pixel's column and row (checked against the image later).
fn parse_pixel(s: &str) -> Result<[u32; 2], String> {
    let (x, y) = parse_two(s, ",", "X,Y, a pixel's column and row from 0")?;
    Ok([x, y])
}

fn parse_blades(s: &str) -> Result<u32, String> {
    let most = crate::camera::MAX_BLADES;
    match s.trim().parse::<u32>() {
        Ok(n) if crate::camera::blades_are_valid(n) => Ok(n),
        _ => Err(format!("expected 0 (round) or 3 to {most} blades")),
    }
}

fn parse_vec3(s: &str) -> Result<Vec3A, String> {
    let parts: Vec<&str> = s.split(',').collect();
    let err = || "expected three finite numbers X,Y,Z".to_string();
    if parts.len() != 3 {
        return Err(err());
    }
    let v: Vec<f32> = parts
        .iter()
        .map(|p| parse_finite(p))
        .collect::<Result<_, _>>()
        .map_err(|_| err())?;
    Ok(Vec3A::new(v[0], v[1], v[2]))
}

/// `DENSITY` or `DENSITY,R,G,B` (`--fog`).
fn parse_fog(s: &str) -> Result<(f32, Vec3A), String> {
    let parts: Vec<&str> = s.split(',').collect();
    let density: f32 = parts[0]
        .trim()
        .parse()
        .ok()
        .filter(|d: &f32| d.is_finite() && *d >= 0.0)
        .ok_or("expected a density >= 0, then optionally ,R,G,B (an albedo in [0, 1])")?;
    let albedo = match parts.len() {
        1 => Vec3A::ONE,
        4 => parse_vec3(&parts[1..].join(","))
            .ok()
            .filter(|c| c.min_element() >= 0.0 && c.max_element() <= 1.0)
            .ok_or("the fog's colour is an albedo: three numbers in [0, 1]")?,
        _ => return Err("expected DENSITY or DENSITY,R,G,B".into()),
    };
    Ok((density, albedo))
}

fn parse_color(s: &str) -> Result<Vec3A, String> {
    match parse_vec3(s) {
        Ok(c) if c.min_element() >= 0.0 => Ok(c),
        _ => Err("expected three finite numbers >= 0, R,G,B".into()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn image_size_defaults_follow_the_scene_and_the_camera() {
        let args = |w: Option<u32>, h: Option<u32>| {
            let r = JobOptions::new("cornell");
            SceneOptions {
                width: w,
                height: h,
                ..r.scene
            }
        };
        let none = args(None, None);
        assert_eq!(none.size(SceneKind::Lab, None), Ok((500, 500)));
        assert_eq!(none.size(SceneKind::Gltf, None), Ok((800, 600)));
        assert_eq!(none.size(SceneKind::Gltf, Some(1.5)), Ok((900, 600)));
        assert_eq!(none.size(SceneKind::Gltf, Some(1.777)), Ok((1066, 600)));
        assert_eq!(
            args(Some(300), None).size(SceneKind::Gltf, Some(1.5)),
            Ok((300, 200))
        );
        assert_eq!(
            args(None, Some(100)).size(SceneKind::Gltf, None),
            Ok((133, 100))
        );
        assert_eq!(
            args(Some(64), Some(48)).size(SceneKind::Gltf, Some(1.5)),
            Ok((64, 48))
        );
        assert!(
            args(None, Some(16000))
                .size(SceneKind::Gltf, Some(1.5))
                .is_err()
        );
    }

    #[test]
    fn vectors_need_three_finite_numbers() {
        assert_eq!(parse_vec3("-0.3,0.2,-2"), Ok(Vec3A::new(-0.3, 0.2, -2.0)));
        assert_eq!(parse_vec3(" 1, 2 ,3"), Ok(Vec3A::new(1.0, 2.0, 3.0)));
        for bad in ["1,2", "1,2,3,4", "1,,3", "a,b,c", "NaN,0,0", "0,inf,0", ""] {
            assert!(parse_vec3(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn sizes_and_counts_are_bounded() {
        assert_eq!(parse_side("500"), Ok(500));
        for bad in ["0", "-1", "16385", "1e3", "x"] {
            assert!(parse_side(bad).is_err(), "{bad}");
        }
        assert!(parse_spp("0").is_err());
        assert!(parse_threads("0").is_err());
        assert!(parse_pitch("90").is_err());
        assert_eq!(parse_pitch("-89"), Ok(-89.0));
        assert!(parse_non_negative("-1").is_err());
        assert!(parse_angle("nan").is_err());
        assert_eq!(
            parse_assignment("tall=glass:1.4"),
            Ok((
                "tall".into(),
                MaterialChoice::Other(crate::materials::Material::Dielectric { ior: 1.4 })
            ))
        );
        for bad in ["tall", "wall=mirror", "tall=plastic", "tall=gold:7"] {
            assert!(parse_assignment(bad).is_err(), "{bad}");
        }
        assert_eq!(parse_max_depth("1"), Ok(1));
        for bad in ["0", "-1", "nan", "1.5", ""] {
            assert!(parse_max_depth(bad).is_err(), "{bad}");
        }
        assert_eq!(parse_time("0.5"), Ok(0.5));
        for bad in ["0", "-1", "nan", "inf", "1e9"] {
            assert!(parse_time(bad).is_err(), "{bad}");
        }
        assert!(parse_exposure("nan").is_err());
        assert_eq!(parse_exposure("-1.5"), Ok(-1.5));
    }
}
