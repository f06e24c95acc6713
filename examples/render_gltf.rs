//! A glTF file to a PNG from Rust, the same file, byte for byte, as
//! `raylab render SCENE -o OUTPUT` writes:
//!
//! `cargo run --release --example render_gltf -- [SCENE] [OUTPUT]`
//!
//! (by default the DamagedHelmet of `assets/models` to `helmet.png`). Every
//! option of `raylab render` is a field of `JobOptions` with the same name
//! (`--max-depth` is `max_depth`) and the same default, and a scene file's
//! `[render]` settings apply as on the command line.

use raylab::job::{Job, JobOptions};

fn main() -> anyhow::Result<()> {
    let mut args = std::env::args().skip(1);
    let scene = args.next();
    let output = args.next();
    render(
        scene
            .as_deref()
            .unwrap_or("assets/models/DamagedHelmet/DamagedHelmet.gltf"),
        output.as_deref().unwrap_or("helmet.png"),
    )
}

/// Renders `scene` to `output` with the command line's defaults.
pub fn render(scene: &str, output: &str) -> anyhow::Result<()> {
    let mut options = JobOptions::new(scene);
    options.output = Some(output.into());
    Job::new(options)?.run()?;
    Ok(())
}
