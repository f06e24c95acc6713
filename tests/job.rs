//! The library's render job against the command line: the same files, byte
//! for byte, and the same rules.

mod common;

use std::path::Path;

use raylab::job::{Event, Hooks, Job, JobOptions};

#[path = "../examples/render_gltf.rs"]
#[allow(dead_code)]
mod example;

fn helmet() -> String {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("assets/models/DamagedHelmet/DamagedHelmet.gltf")
        .to_string_lossy()
        .into_owned()
}

/// `examples/render_gltf.rs` writes the PNG `raylab render` writes of the
/// DamagedHelmet with the defaults (800×600 would do, but the example's
/// five lines take any scene: the defaults are what is compared).
#[test]
fn the_example_writes_the_command_lines_png() {
    let dir = tempfile::tempdir().unwrap();
    let (lib, cli) = (dir.path().join("lib.png"), dir.path().join("cli.png"));
    example::render(&helmet(), lib.to_str().unwrap()).unwrap();
    let out = common::raylab(
        &["render", &helmet(), "-o", cli.to_str().unwrap()],
        dir.path(),
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let (a, b) = (std::fs::read(&lib).unwrap(), std::fs::read(&cli).unwrap());
    assert_eq!(image::image_dimensions(&lib).unwrap(), (800, 600));
    assert!(a == b, "the example's PNG differs from raylab render's");
}

/// The job says what the command line prints, and a scene file's settings
/// fill in what the options leave out (one side keeps the file's aspect).
#[test]
fn the_job_merges_a_scene_file_and_says_what_it_did() {
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("s.toml");
    std::fs::write(
        &scene,
        "[render]\nwidth = 40\nheight = 30\nspp = 2\nintegrator = \"flat\"\n[[model]]\nbuiltin = \"cornell\"\n",
    )
    .unwrap();
    let mut options = JobOptions::new(scene.to_str().unwrap());
    options.scene.width = Some(64);
    options.output = Some(dir.path().join("a.exr"));
    let mut job = Job::new(options).unwrap();
    assert_eq!(job.options().scene.height, Some(48));
    assert_eq!(job.options().spp, Some(2));
    let lines = std::sync::Mutex::new(Vec::new());
    let on_event = |e: Event<'_>| {
        if let Event::Line(l) = e {
            lines.lock().unwrap().push(l.to_string())
        }
    };
    let report = job
        .run_with(&Hooks {
            on_event: &on_event,
            stop: None,
        })
        .unwrap();
    assert_eq!(report.images.len(), 1);
    assert_eq!(report.images[0].spp, 2);
    let film = raylab::film::read_exr(&dir.path().join("a.exr")).unwrap();
    assert_eq!((film.width, film.height), (64, 48));
    let lines = lines.into_inner().unwrap();
    assert!(
        lines
            .iter()
            .any(|l| l.starts_with("wrote ") && l.contains("64x48, flat, 2 spp")),
        "{lines:?}"
    );
}

/// Bad options are refused by `Job::new` with the command line's message.
#[test]
fn bad_options_are_refused_before_any_work() {
    let mut options = JobOptions::new("cornell");
    options.tile = Some((0, 2));
    let e = Job::new(options)
        .err()
        .expect("a part needs an .exr output");
    assert!(e.to_string().contains("name it with -o PART.exr"), "{e}");
    let e = Job::new(JobOptions::new("no-such-scene.toml"))
        .err()
        .expect("a missing scene file");
    assert!(e.to_string().contains("no-such-scene.toml"), "{e}");
}

/// A job rendered in memory gives the values of the EXR the same job
/// writes, bit for bit, AOVs included; the file's job writes nothing else.
#[test]
fn in_memory_equals_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let exr = dir.path().join("box.exr");
    let mut options = JobOptions::new("cornell");
    options.scene.integrator = Some(raylab::Integrator::path());
    options.scene.width = Some(48);
    options.spp = Some(3);
    options.aov = Some("albedo,depth".parse().unwrap());
    let kept = Job::new(options.clone())
        .unwrap()
        .render_with(&Hooks::default())
        .unwrap();
    options.output = Some(exr.clone());
    Job::new(options).unwrap().run().unwrap();
    let file = raylab::film::read_exr(&exr).unwrap();
    assert_eq!((file.width, file.height), (48, 48));
    assert!(common::bit_identical(&kept.finished.image, &file));
    assert_eq!(kept.report.spp, 3);
    let aovs = kept.finished.aovs.expect("the AOVs asked for");
    assert_eq!(aovs.layers.len(), 2);
    assert!(kept.finished.noisy.is_none());
}

/// One loaded scene serves renders of other sizes, cameras and integrators,
/// each the image a job that loads the scene itself renders, bit for bit;
/// options that load another scene (here the light's power) load it.
#[test]
fn a_session_serves_many_views() {
    let quiet = Hooks::default();
    let base = JobOptions::new("cornell");
    let session = raylab::job::load_session(&base.scene, true, 0, &quiet).unwrap();
    let mut views = Vec::new();
    for (width, yaw, integrator) in [(24, 0.0, "direct"), (32, 12.5, "path")] {
        let mut options = base.clone();
        options.scene.width = Some(width);
        options.scene.yaw = yaw;
        options.scene.integrator = Some(integrator.parse().unwrap());
        options.spp = Some(2);
        views.push(options);
    }
    let mut brighter = views[1].clone();
    brighter.scene.light_power = Some(30.0);
    views.push(brighter);
    for options in views {
        assert_eq!(
            session.loads(&options.scene),
            options.scene.light_power.is_none()
        );
        let shared = Job::with_session(session.clone(), options.clone())
            .unwrap()
            .render_with(&quiet)
            .unwrap();
        let own = Job::new(options).unwrap().render_with(&quiet).unwrap();
        assert!(common::bit_identical(
            &shared.finished.image,
            &own.finished.image
        ));
    }
    // The session itself is unchanged: its first view, 500×500 direct.
    assert_eq!(session.size, (500, 500));
    assert_eq!(session.view.yaw_deg, 0.0);
}
