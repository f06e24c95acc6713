//! The `raylab` command: `render`, `view`, and a sensible default without arguments.

mod args;
mod bench;
mod keys;
mod render_cmd;
mod viewer;

use std::process::ExitCode;

use clap::Parser;
use clap::error::ErrorKind;

use args::{Cli, Command, RenderArgs, SceneArgs};

fn main() -> ExitCode {
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) => match e.kind() {
            ErrorKind::DisplayHelp
            | ErrorKind::DisplayVersion
            | ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand => e.exit(),
            _ => {
                // clap's message spans several lines: its first paragraph, on one line.
                let text = e.render().to_string();
                let first: Vec<&str> = text
                    .lines()
                    .skip_while(|l| l.trim().is_empty())
                    .take_while(|l| !l.trim().is_empty())
                    .map(str::trim)
                    .collect();
                eprintln!("{}", first.join(" "));
                return ExitCode::from(2);
            }
        },
    };
    let scene_args = match &cli.command {
        Some(Command::Render(a)) => Some(&a.scene),
        Some(Command::View(a)) => Some(&a.scene),
        Some(Command::Bench(_)) | None => None,
    };
    if let Some(Err(message)) = scene_args.map(SceneArgs::validate) {
        eprintln!("{message}");
        return ExitCode::from(2);
    }
    match run(cli) {
        Ok(()) => ExitCode::SUCCESS,
        // A reader that stopped early (`raylab bench ... | head -1`) is not a failure.
        Err(e) if is_broken_pipe(&e) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::from(1)
        }
    }
}

fn is_broken_pipe(e: &anyhow::Error) -> bool {
    e.chain()
        .filter_map(|c| c.downcast_ref::<std::io::Error>())
        .any(|io| io.kind() == std::io::ErrorKind::BrokenPipe)
}

fn run(cli: Cli) -> anyhow::Result<()> {
    match cli.command {
        Some(Command::Render(args)) => render_cmd::run(&args),
        Some(Command::View(args)) => viewer::run(&args.scene),
        Some(Command::Bench(args)) => bench::run(&args),
        None => run_default(),
    }
}

/// No subcommand: the viewer where there is a display, else a render of the box.
fn run_default() -> anyhow::Result<()> {
    let scene = SceneArgs {
        scene: "cornell".into(),
        width: 500,
        height: 500,
        integrator: raylab::Integrator::Direct,
        max_depth: None,
        sampler: raylab::integrators::path::SamplerKind::DEFAULT,
        material: Vec::new(),
        exposure: 0.0,
        camera_pos: None,
        yaw: 0.0,
        pitch: 0.0,
        light_pos: None,
        light_power: None,
        add: Vec::new(),
        transform: Vec::new(),
        ambient: None,
    };
    if let Ok(event_loop) = viewer::open_display() {
        let (loaded, initial) = load(&scene)?;
        return viewer::run_on(event_loop, loaded, initial, &scene);
    }
    let args = RenderArgs {
        scene,
        output: None,
        spp: None,
        time: None,
        seed: 0,
        threads: None,
        quiet: false,
    };
    render_cmd::run(&args)?;
    eprintln!(
        "no display found, so raylab rendered an image instead of opening the viewer; \
         run `raylab view` where an X display is available"
    );
    Ok(())
}

/// Factor applied to PNG values (not EXR) for `exposure` stops: `2^E`, and `π`
/// more for `path`, so that a diffuse surface lit by the point light alone shows
/// the lab's `ρ·D` (radiance is `ρ·E/π`, the lab's `D` is the irradiance `E`).
pub fn png_scale(integrator: raylab::Integrator, exposure: f32) -> f32 {
    let physical = if integrator.is_physical() {
        std::f32::consts::PI
    } else {
        1.0
    };
    physical * exposure.exp2()
}

/// Reads a mesh file, telling the user what it had to guess (missing materials).
fn load_mesh(path: &std::path::Path) -> anyhow::Result<raylab::scene::obj::Mesh> {
    let mesh = raylab::scene::obj::load_obj(path)?;
    for w in &mesh.warnings {
        eprintln!("warning: {w}");
    }
    Ok(mesh)
}

/// Ambient term of mesh scenes unless the user gives one.
const MESH_AMBIENT: f32 = 0.15;

/// Builds the scene and the initial view from the shared arguments.
fn load(args: &SceneArgs) -> anyhow::Result<(raylab::Scene, raylab::controls::ViewState)> {
    use glam::{Mat3A, Vec3A};
    use raylab::{Triangle, scene::cornell};
    let is_obj = std::path::Path::new(&args.scene)
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("obj"));
    let area = args.scene == "cornell-area";
    let (mut scene, camera_pos, base, step) = if args.scene == "cornell" || area {
        let (mut tris, mut rho) = cornell::triangles();
        if area {
            cornell::push_area_light(&mut tris, &mut rho);
        }
        for (i, path) in args.add.iter().enumerate() {
            let mut mesh = load_mesh(path)?;
            if let Some(t) = args.transform.get(i).or(args.transform.first()) {
                t.apply(&mut mesh.triangles);
            }
            // OBJ faces are counter-clockwise seen from outside; the lab's one-sided
            // normal wants the opposite order.
            tris.extend(
                mesh.triangles
                    .iter()
                    .map(|t| Triangle::new(t.v[0], t.v[2], t.v[1])),
            );
            rho.extend(mesh.reflectance);
        }
        // cornell-area's point light is off unless given a power.
        let default_power = if area { 0.0 } else { cornell::LIGHT_POWER };
        let light = raylab::PointLight {
            position: cornell::LIGHT_POSITION,
            power: Vec3A::splat(args.light_power.unwrap_or(default_power)),
        };
        let mut scene = raylab::Scene::new(tris, rho, light, Vec3A::ZERO)?;
        let default_ambient = if area { 0.0 } else { cornell::AMBIENT };
        scene.ambient = Vec3A::splat(args.ambient.unwrap_or(default_ambient));
        if area {
            cornell::light_area_patch(&mut scene);
        }
        for (part, material) in &args.material {
            let range = cornell::part(part).expect("validated by the argument parser");
            material.apply(&mut scene, range);
        }
        let step = raylab::controls::LAB_STEP;
        (scene, cornell::CAMERA_POSITION, Mat3A::IDENTITY, step)
    } else if is_obj {
        if !args.add.is_empty() {
            anyhow::bail!(
                "--add places meshes in the cornell scene; {} is a mesh",
                args.scene
            );
        }
        let mesh = load_mesh(std::path::Path::new(&args.scene))?;
        let ambient = args.ambient.unwrap_or(MESH_AMBIENT);
        let (mut scene, framing) = raylab::scene::framing::mesh_scene(mesh, ambient)
            .map_err(|e| anyhow::anyhow!("{}: {e}", args.scene))?;
        if let Some(p) = args.light_power {
            scene.light.power = Vec3A::splat(p);
        }
        (scene, framing.camera_pos, framing.base, framing.step)
    } else {
        anyhow::bail!(
            "scene '{}': unknown scene (built in: cornell, cornell-area; or a Wavefront .obj file)",
            args.scene
        );
    };
    if let Some(p) = args.light_pos {
        scene.light.position = p;
    }
    let view = raylab::controls::ViewState {
        camera_pos: args.camera_pos.unwrap_or(camera_pos),
        base,
        step,
        yaw_deg: args.yaw,
        pitch_deg: args.pitch,
        light_pos: scene.light.position,
        integrator: args.integrator(),
    };
    Ok((scene, view))
}
