//! The thin-lens camera through the job, as `raylab render` takes it: the
//! focus on a pixel's first hit, a closed lens that leaves the pinhole's
//! image bit for bit, lens images the same on any number of threads, scene
//! files' `[camera]` lenses with the command line's options over them, and
//! bad values refused with the option named.

mod common;

use raylab::camera::{Aperture, FocusedLens};
use raylab::job::{Hooks, Job, JobOptions, SceneOptions, load_session};

/// The thin lens the session of `options` focuses, or its error.
fn lens_of(options: &SceneOptions) -> Result<Option<FocusedLens>, String> {
    load_session(options, true, 0, &Hooks::default())
        .map(|s| s.view.thin_lens)
        .map_err(|e| format!("{e:#}"))
}

fn box_with_lens(aperture: f32) -> SceneOptions {
    let mut options = SceneOptions::new("cornell");
    options.aperture = Some(aperture);
    options
}

/// The box's camera at (0, 0, −3) looks along +z with f = 500 px on its
/// 500×500 image: the back wall (z = 1) is 4 away along the axis, and the
/// left wall (x = −1) 500/219.5 away where pixel column 30 meets it.
#[test]
fn the_focus_pixel_focuses_at_its_first_hit_along_the_view_axis() {
    for ((x, y), want) in [((250, 200), 4.0f32), ((30, 200), 500.0 / 219.5)] {
        let mut options = box_with_lens(0.05);
        options.focus_pixel = Some([x, y]);
        let lens = lens_of(&options).unwrap().expect("a thin lens");
        assert!(
            (lens.focus_distance - want).abs() < 1e-4 * want,
            "pixel {x},{y}: {} against {want}",
            lens.focus_distance
        );
        assert_eq!(lens.aperture, Aperture::Radius(0.05));
    }
    // Without a focus, the image's centre pixel's first hit.
    let mut centre = box_with_lens(0.05);
    centre.focus_pixel = Some([250, 250]);
    assert_eq!(lens_of(&box_with_lens(0.05)), lens_of(&centre));
    // A focus distance is taken as it is.
    let mut given = box_with_lens(0.05);
    given.focus_distance = Some(2.5);
    assert_eq!(lens_of(&given).unwrap().unwrap().focus_distance, 2.5);
}

#[test]
fn bad_lens_values_are_refused_naming_the_option() {
    let mut outside = box_with_lens(0.1);
    outside.focus_pixel = Some([500, 3]);
    let e = lens_of(&outside).unwrap_err();
    assert!(
        e.contains("--focus-pixel 500,3") && e.contains("outside"),
        "{e}"
    );
    // Looking out of the open box's front: nothing to focus on.
    let mut away = box_with_lens(0.1);
    away.yaw = 180.0;
    let e = lens_of(&away).unwrap_err();
    assert!(e.contains("hits nothing"), "{e}");
    let mut no_lens = SceneOptions::new("cornell");
    no_lens.focus_distance = Some(3.0);
    let e = lens_of(&no_lens).unwrap_err();
    assert!(e.starts_with("--focus-distance needs a thin lens"), "{e}");
    // What clap refuses, as the command line does.
    let dir = tempfile::tempdir().unwrap();
    for (args, option) in [
        (&["--aperture", "-1"][..], "--aperture"),
        (&["--f-number", "0"][..], "--f-number"),
        (
            &["--aperture", "0.1", "--focus-distance", "0"][..],
            "--focus-distance",
        ),
        (
            &["--aperture", "0.1", "--focus-distance", "-2"][..],
            "--focus-distance",
        ),
        (
            &["--aperture", "0.1", "--aperture-blades", "2"][..],
            "--aperture-blades",
        ),
        (
            &["--aperture", "0.1", "--focus-pixel", "1;2"][..],
            "--focus-pixel",
        ),
        (
            &["--aperture", "0.1", "--focus-pixel", "600,2"][..],
            "--focus-pixel",
        ),
    ] {
        let mut all = vec!["render", "cornell", "--width", "16", "-o", "x.png", "-q"];
        all.extend_from_slice(args);
        let out = common::raylab(&all, dir.path());
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{args:?}");
        assert_eq!(err.trim().lines().count(), 1, "{args:?}: {err}");
        assert!(
            err.contains(option) && !err.contains("panicked"),
            "{args:?}: {err}"
        );
    }
}

/// The image of a job's options, rendered in memory.
fn render(options: JobOptions) -> raylab::film::Film {
    Job::new(options)
        .unwrap()
        .render_with(&Hooks::default())
        .unwrap()
        .finished
        .image
}

fn small(integrator: &str, spp: u32) -> JobOptions {
    let mut options = JobOptions::new("cornell");
    options.scene.width = Some(36);
    options.scene.height = Some(28);
    options.scene.integrator = Some(integrator.parse().unwrap());
    options.spp = Some(spp);
    options
}

/// A lens of radius 0 (and blades, and a focus) renders the pinhole's image
/// bit for bit, with every integrator; an open lens changes it.
#[test]
fn a_closed_lens_renders_the_pinhole_image_bit_for_bit() {
    for integrator in ["flat", "direct", "path"] {
        let pinhole = render(small(integrator, 3));
        let mut closed = small(integrator, 3);
        closed.scene.aperture = Some(0.0);
        closed.scene.focus_distance = Some(2.0);
        closed.scene.aperture_blades = Some(6);
        assert!(
            common::bit_identical(&pinhole, &render(closed)),
            "{integrator}"
        );
        let mut open = small(integrator, 3);
        open.scene.aperture = Some(0.2);
        open.scene.focus_distance = Some(2.0);
        assert!(
            !common::bit_identical(&pinhole, &render(open)),
            "{integrator}"
        );
    }
}

/// Lens samples come from each sample's own numbers: the same image on 1 and
/// 3 threads, for the lab's blocks and quads and the path tracer's lanes.
#[test]
fn lens_images_are_the_same_on_any_number_of_threads() {
    for (integrator, sampler) in [
        ("flat", "sobol"),
        ("direct", "sobol"),
        ("path", "sobol"),
        ("path", "independent"),
    ] {
        let mut options = small(integrator, 4);
        options.scene.f_number = Some(0.5);
        options.scene.aperture_blades = Some(5);
        options.scene.focus_pixel = Some([10, 20]);
        options.scene.sampler = raylab::integrators::path::SamplerKind::ALL
            .into_iter()
            .find(|k| k.name() == sampler)
            .unwrap();
        options.seed = Some(9);
        let images: Vec<_> = [1, 3]
            .map(|threads| {
                let mut o = options.clone();
                o.threads = Some(threads);
                render(o)
            })
            .into();
        assert!(
            common::bit_identical(&images[0], &images[1]),
            "{integrator} {sampler}"
        );
    }
}

/// A scene file's `[camera]` lens applies to its camera; the command line's
/// options replace it part by part; its bad values are refused with the key.
#[test]
fn scene_files_give_a_lens_the_command_line_overrides() {
    let dir = tempfile::tempdir().unwrap();
    let file = |name: &str, camera: &str| {
        let path = dir.path().join(name);
        let text = format!(
            "[camera]\nposition = [0, 0, -3.5]\ntarget = [0, 0, 0]\n{camera}\n\n[[model]]\nbuiltin = \"cornell\"\n"
        );
        std::fs::write(&path, text).unwrap();
        SceneOptions::new(path.to_str().unwrap())
    };
    let options = file(
        "lens.toml",
        "f_number = 1.4\nfocus_distance = 3\naperture_blades = 7",
    );
    let lens = lens_of(&options).unwrap().expect("the file's lens");
    assert_eq!(lens.aperture, Aperture::FNumber(1.4));
    assert_eq!((lens.focus_distance, lens.blades), (3.0, 7));
    let mut closed = options.clone();
    closed.aperture = Some(0.0);
    assert_eq!(lens_of(&closed), Ok(None));
    let mut refocused = options.clone();
    refocused.focus_distance = Some(1.5);
    assert_eq!(lens_of(&refocused).unwrap().unwrap().focus_distance, 1.5);
    // The box (turned y up about z, its back wall still at z = 1) seen
    // through its open front from 4.5 units before that wall, focused on a
    // pixel of the 800×600 image above the blocks.
    let options = file("pixel.toml", "aperture = 0.02\nfocus_pixel = [400, 150]");
    let lens = lens_of(&options).unwrap().unwrap();
    assert!(
        (lens.focus_distance - 4.5).abs() < 1e-4,
        "{}",
        lens.focus_distance
    );
    for (camera, key) in [
        ("aperture = -1", "[camera] aperture"),
        ("aperture = 0.1\nf_number = 2", "aperture or f_number"),
        ("f_number = 0", "[camera] f_number"),
        (
            "aperture = 0.1\nfocus_distance = 0",
            "[camera] focus_distance",
        ),
        (
            "aperture = 0.1\naperture_blades = 1",
            "[camera] aperture_blades",
        ),
        (
            "aperture = 0.1\nfocus_pixel = [9000, 1]",
            "[camera] focus_pixel 9000,1",
        ),
    ] {
        let e = lens_of(&file("bad.toml", camera)).unwrap_err();
        assert!(
            e.contains("bad.toml") && e.contains(key) && !e.contains('\n'),
            "{camera}: {e}"
        );
    }
}
