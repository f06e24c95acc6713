//! The command line's parsing and validation: the input, split at NUL bytes,
//! is the argument list after `raylab`. What parses is checked as the render
//! job checks it (`raylab::job`: scene options, a scene file's settings,
//! image size) without rendering.
#![no_main]
use clap::Parser;
use libfuzzer_sys::fuzz_target;

#[allow(dead_code)]
#[path = "../../src/bin/raylab/args.rs"]
mod args;

fuzz_target!(|data: &[u8]| {
    let words: Vec<String> = std::iter::once("raylab".to_string())
        .chain(data.split(|&b| b == 0).map(|w| String::from_utf8_lossy(w).into_owned()))
        .collect();
    match args::Cli::try_parse_from(&words) {
        Err(e) => {
            // Usage errors name the argument on their first line.
            let text = e.to_string();
            assert!(!text.trim().is_empty());
        }
        Ok(cli) => {
            let scene = match &cli.command {
                Some(args::Command::Render(r)) => {
                    // What `Job::new` does before any work (but loading Open
                    // Image Denoise): the checks, then the scene file.
                    let checked = r.scene.validate().and_then(|()| r.validate());
                    if let Err(e) = checked.map_err(anyhow::Error::msg).and_then(|()| r.with_scene_file()) {
                        // The file name comes from the arguments, control
                        // characters and all: one line as the binary prints it.
                        raylab_fuzz::check_message(&raylab::guard::one_line(&format!("{e:#}")));
                    }
                    &r.scene
                }
                Some(args::Command::View(v)) => &v.scene,
                _ => return,
            };
            let _ = scene.load_options();
            for kind in [
                raylab::load::SceneKind::Lab,
                raylab::load::SceneKind::Gltf,
            ] {
                for aspect in [None, Some(0.0), Some(1.5), Some(f32::MAX)] {
                    if let Ok((w, h)) = scene.size(kind, aspect) {
                        assert!((1..=raylab::job::options::MAX_SIDE).contains(&w) && (1..=raylab::job::options::MAX_SIDE).contains(&h));
                        assert!(u64::from(w) * u64::from(h) <= raylab::job::options::MAX_PIXELS);
                    }
                }
            }
        }
    }
});
