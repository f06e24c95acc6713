//! A loaded scene with what showing it needs: the view (camera, light,
//! integrator), image size and tone mapping that the options and the scene's
//! kind give, and how its values are scaled for display; and an animated
//! file's scene loaded again, posed at a frame's time.

use std::sync::Arc;

use super::animate::AnimationArgs;
use super::hooks::Hooks;
use super::options::SceneOptions;
use crate::camera::{Aperture, Camera, DepthOfField, Focus, FocusedLens};
use crate::film::{Display, ToneMap};
use crate::load::{InitialView, SceneKind};

/// A loaded scene with everything the commands need to show it. A clone is
/// cheap (the scene is shared): one load serves many renders
/// ([`Session::shown`], [`super::Job::with_session`]).
#[derive(Clone)]
pub struct Session {
    /// The scene.
    pub scene: Arc<crate::scene::Scene>,
    /// What it was made from.
    pub kind: SceneKind,
    /// The starting view (camera, light, integrator).
    pub view: crate::controls::ViewState,
    /// Image size.
    pub size: (u32, u32),
    /// Tone mapping for PNG output and the screen.
    pub tonemap: ToneMap,
    /// The scene's own view, before the options' camera and size.
    pub initial: InitialView,
    /// The options it was loaded with.
    pub loaded_with: SceneOptions,
    /// The memory the scene needs (without a film).
    pub needs: crate::memory::Needs,
    /// The names of a glTF file's animations (empty for other scenes): the
    /// job poses each frame of such a file at its time.
    pub animations: Vec<String>,
}

impl Session {
    /// Whether `args` load this scene: the same scene, load options (`add`,
    /// `env`, lights, materials, `camera`, `max_memory`, ...) and cache.
    pub fn loads(&self, args: &SceneOptions) -> bool {
        let was = &self.loaded_with;
        was.scene == args.scene
            && was.cache == args.cache
            && was.load_options() == args.load_options()
    }

    /// The same scene shown as `args` show it (image size, camera, integrator,
    /// tone mapping), without loading it again, for a film with
    /// `aov_channels` AOV channels (checked against the memory budget). The
    /// options that load ([`Session::loads`]) are those it was loaded with.
    pub fn shown(&self, args: &SceneOptions, aov_channels: usize) -> anyhow::Result<Session> {
        let (view, size, tonemap) = frame(
            args,
            self.kind,
            &self.initial,
            &self.scene,
            self.needs,
            aov_channels,
        )?;
        Ok(Session {
            view,
            size,
            tonemap,
            ..self.clone()
        })
    }
}

/// How pixel values are shown (PNG, screen) for `exposure` stops. The lab's
/// scenes and OBJ meshes: `2^E`, and `π` more for `path`, so that a diffuse
/// surface lit by the point light alone shows the lab's `ρ·D` (radiance is
/// `ρ·E/π`, the lab's `D` is the irradiance `E`). glTF scenes show radiance:
/// `path` as it is, `direct`'s `ρ·(D + N)` divided by `π` (the radiance of a
/// diffuse surface under that irradiance), `flat`'s base colour as it is.
pub fn display(
    kind: SceneKind,
    integrator: crate::integrators::Integrator,
    exposure: f32,
    tonemap: ToneMap,
) -> Display {
    let factor = match (kind, integrator) {
        (k, crate::integrators::Integrator::Direct) if k.is_physical() => {
            1.0 / std::f32::consts::PI
        }
        (k, _) if k.is_physical() => 1.0,
        (_, i) if i.is_physical() => std::f32::consts::PI,
        _ => 1.0,
    };
    Display {
        scale: factor * exposure.exp2(),
        tonemap,
    }
}

/// Loads the scene of `args` (from its `--cache` if given), says its
/// warnings and (unless `quiet`) a summary line for files through `hooks`,
/// and sets up the view: the camera, light and integrator of the options,
/// the image size and tone mapping. The scene's memory estimate and that of
/// a film with `aov_channels` AOV channels must fit `max_memory` together.
pub fn load_session(
    args: &SceneOptions,
    quiet: bool,
    aov_channels: usize,
    hooks: &Hooks<'_>,
) -> anyhow::Result<Session> {
    if let Some(dir) = &args.cache {
        crate::cache::set_dir(Some(dir.clone()))
            .map_err(|e| anyhow::anyhow!("--cache {}: {e}", dir.display()))?;
    }
    let loaded = crate::load::load(&args.scene, &args.load_options())?;
    if let Some(dir) = &args.cache
        && !quiet
    {
        let (hits, misses) = crate::cache::stats();
        hooks.say(&format!(
            "cache {}: {hits} of {} entries found (textures and BVHs)",
            dir.display(),
            hits + misses
        ));
    }
    let (view, size, tonemap) = frame(
        args,
        loaded.kind,
        &loaded.view,
        &loaded.scene,
        loaded.summary.needs,
        aov_channels,
    )?;
    for w in &loaded.warnings {
        hooks.say(&format!("warning: {}", crate::guard::one_line(w)));
    }
    let kind = loaded.kind;
    let animations = loaded.animations.clone();
    if !quiet && kind != SceneKind::Lab {
        let s = &loaded.summary;
        let mib = |b: usize| b as f64 / (1024.0 * 1024.0);
        let plural = |n: usize, what: &str| format!("{n} {what}{}", if n == 1 { "" } else { "s" });
        let lights = if loaded.default_light {
            "no lights in the file: default key light and grey sky".to_string()
        } else {
            plural(s.punctual_lights, "light")
        };
        // Analytic shapes (Mitsuba's spheres, disks, cylinders) only where
        // there are any.
        let (shapes, emitting_shapes) = match s.analytic_shapes {
            0 => (String::new(), String::new()),
            n => (
                format!(", {}", plural(n, "analytic shape")),
                format!(", {}", plural(s.emitting_shapes, "emitting analytic shape")),
            ),
        };
        hooks.say(&format!(
            "loaded {}: {}{shapes}, {}, {} ({:.1} MiB), {}, {}{emitting_shapes}, geometry {:.1} MiB, {:.0} ms",
            args.scene,
            plural(s.triangles, "triangle"),
            plural(s.materials, "material"),
            plural(s.textures, "texture"),
            mib(s.texture_bytes),
            lights,
            plural(s.emitters, "emitting triangle"),
            mib(s.geometry_bytes),
            s.time.as_secs_f64() * 1e3,
        ));
        if let Some(p) = &s.plugins {
            hooks.say(&format!("Mitsuba scene: {p}"));
        }
        if !s.variants.is_empty() {
            let shown = match &s.variant {
                Some(v) => format!("showing {v}"),
                None => "showing the default materials; --variant NAME picks one".into(),
            };
            hooks.say(&format!(
                "material variants: {} ({shown})",
                s.variants.join(", ")
            ));
        }
    }
    if !quiet && let Some(lens) = view.camera(size.0, size.1).thin_lens {
        // The focus a pixel gave, and an f-number's radius, are worked out
        // here: say them.
        hooks.say(&format!(
            "thin lens: radius {:.4}, {}focused at {:.4} along the view axis",
            lens.radius,
            match lens.blades {
                0 => String::new(),
                n => format!("{n} blades, "),
            },
            lens.focus_distance
        ));
    }
    if !quiet && let Some([w, h]) = loaded.summary.environment_size {
        let s = &loaded.summary;
        hooks.say(&format!(
            "environment {w}×{h}: {:.1} MiB with its sampling tables, {:.0} ms",
            s.environment_bytes as f64 / (1024.0 * 1024.0),
            s.environment_time.as_secs_f64() * 1e3
        ));
    }
    Ok(Session {
        scene: Arc::new(loaded.scene),
        kind,
        view,
        size,
        tonemap,
        initial: loaded.view,
        loaded_with: args.clone(),
        needs: loaded.summary.needs,
        animations,
    })
}

/// The view, image size and tone mapping of `args` for `scene` of `kind`
/// loaded with the view `initial`, checked (with a film of `aov_channels` AOV
/// channels) against the memory budget; its thin lens focused
/// ([`focused_lens`]).
fn frame(
    args: &SceneOptions,
    kind: SceneKind,
    initial: &InitialView,
    scene: &crate::scene::Scene,
    needs: crate::memory::Needs,
    aov_channels: usize,
) -> anyhow::Result<(crate::controls::ViewState, (u32, u32), ToneMap)> {
    let size = args
        .size(kind, initial.aspect_ratio)
        .map_err(|e| anyhow::anyhow!(e.trim_start_matches("error: ").to_string()))?;
    // The film is allocated when the render starts: check it with the scene
    // (already loaded within the budget) before then.
    let needs = crate::memory::Needs {
        film: crate::memory::film_bytes(size.0, size.1, aov_channels),
        ..needs
    };
    args.memory_budget().check(&args.scene, &needs)?;
    let mut view = crate::controls::ViewState {
        camera_pos: args.camera_pos.unwrap_or(initial.position),
        base: initial.rotation,
        step: initial.step,
        yaw_deg: args.yaw,
        pitch_deg: args.pitch,
        light_pos: scene.light.position,
        integrator: args.integrator(kind),
        lens: initial.lens,
        thin_lens: None,
        window: initial.window,
        fog: if scene.fog().is_some() { 1.0 } else { 0.0 },
    };
    let pinhole = view.camera(size.0, size.1);
    view.thin_lens = focused_lens(args, initial.depth_of_field, &pinhole, scene)?;
    let tonemap = args.tonemap.unwrap_or(match kind {
        SceneKind::Gltf | SceneKind::Shot => ToneMap::KhronosPbrNeutral,
        _ => ToneMap::Clamp,
    });
    Ok((view, size, tonemap))
}

/// The thin lens that the options (else the scene file's camera, `file`) ask
/// for, focused for `camera` (the pinhole, at the image's size) in `scene`:
/// at the focus distance given, else on the first hit of the ray through the
/// centre of the focus pixel given, else of the image's centre pixel (its
/// distance along the view axis). `None` for a pinhole. A focus or blades
/// without an aperture, an f-number for an orthographic camera, a focus
/// pixel outside the image or one whose ray hits nothing are refused, naming
/// the option (or the file's key).
pub fn focused_lens(
    args: &SceneOptions,
    file: DepthOfField,
    camera: &Camera,
    scene: &crate::scene::Scene,
) -> anyhow::Result<Option<FocusedLens>> {
    let given = args.depth_of_field();
    let wanted = given.or(file);
    let Some(aperture) = wanted.aperture else {
        let without = [
            (args.focus_distance.is_some(), "--focus-distance"),
            (args.focus_pixel.is_some(), "--focus-pixel"),
            (args.aperture_blades.is_some(), "--aperture-blades"),
        ];
        if let Some((_, option)) = without.iter().find(|(given, _)| *given) {
            anyhow::bail!("{option} needs a thin lens: give --aperture RADIUS or --f-number N");
        }
        return Ok(None);
    };
    if !wanted.is_open() {
        return Ok(None);
    }
    // What the file gave is named with the file.
    let in_file = |key: &str| format!("{}: [camera] {key}", args.scene);
    if matches!(aperture, Aperture::FNumber(_)) && camera.ortho_px.is_some() {
        let option = match given.aperture {
            Some(_) => "--f-number".to_string(),
            None => in_file("f_number"),
        };
        anyhow::bail!(
            "{option}: an orthographic camera has no focal length; give the lens's radius (--aperture)"
        );
    }
    let (w, h) = (camera.width, camera.height);
    let (pixel, option) = match (wanted.focus, given.focus) {
        (Some(Focus::Distance(d)), _) => {
            return Ok(Some(FocusedLens {
                aperture,
                focus_distance: d,
                blades: wanted.blades.unwrap_or(0),
            }));
        }
        (Some(Focus::Pixel(p)), Some(_)) => (p, "--focus-pixel".to_string()),
        (Some(Focus::Pixel(p)), None) => (p, in_file("focus_pixel")),
        (None, _) => (
            [w / 2, h / 2],
            "the thin lens's focus (the image's centre pixel)".to_string(),
        ),
    };
    let [x, y] = pixel;
    if x >= w || y >= h {
        anyhow::bail!("{option} {x},{y} is outside the {w}×{h} image");
    }
    let ray = camera.ray(x as f32 + 0.5, y as f32 + 0.5);
    let hit = scene.intersect(&ray, f32::INFINITY);
    let focus_distance = hit.map_or(0.0, |h| h.t * ray.dir.dot(camera.forward()));
    if !(focus_distance.is_finite() && focus_distance > 0.0) {
        anyhow::bail!(
            "{option} {x},{y}: the ray through that pixel hits nothing to focus on; give --focus-distance D"
        );
    }
    Ok(Some(FocusedLens {
        aperture,
        focus_distance,
        blades: wanted.blades.unwrap_or(0),
    }))
}

/// The scene of `options` loaded posed at `time`, quietly (the first load
/// of the job, `first`, said its summary and warnings). A file without
/// cameras keeps `first`'s view (framed once), so that the camera stays put
/// while the scene moves.
pub(super) fn posed_session(
    options: &SceneOptions,
    first: &Session,
    time: f32,
    aov_channels: usize,
    hooks: &Hooks<'_>,
) -> anyhow::Result<Session> {
    let at_time = SceneOptions {
        animation: AnimationArgs {
            at: Some(time),
            ..options.animation.clone()
        },
        ..options.clone()
    };
    let quiet = Hooks {
        on_event: &|_| {},
        stop: hooks.stop,
    };
    let mut posed = load_session(&at_time, true, aov_channels, &quiet)?;
    if posed.scene.cameras.is_empty() {
        posed.view = first.view;
    }
    Ok(posed)
}
