//! Helpers shared by the integration tests.
// Each test binary uses a subset of these helpers.
#![allow(dead_code)]

use std::path::Path;

use raylab::film::{Film, read_exr};

/// A file of the repository's `assets/` (models, environment maps, reference
/// images; `assets/README.md` says where each comes from), by its path below
/// that folder.
pub fn asset(rel: &str) -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("assets")
        .join(rel)
}

/// The pixels of `image`, row by row from the top-left.
pub fn pixels(image: &Film) -> Vec<[f32; 3]> {
    let (w, h) = (image.width, image.height);
    (0..h)
        .flat_map(|y| (0..w).map(move |x| (x, y)))
        .map(|(x, y)| image.get(x, y).to_array())
        .collect()
}

/// A Mitsuba 3 scene of `body` under a constant sky, seen by an 8 × 8
/// camera at (0, 0, 10) looking at the origin with +y up.
pub fn mitsuba_scene(body: &str) -> String {
    format!(
        r#"<scene version="3.0.0">
    <sensor type="perspective">
        <transform name="to_world"><lookat origin="0, 0, 10" target="0, 0, 0" up="0, 1, 0"/></transform>
        <film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/></film>
    </sensor>
    <emitter type="constant"/>
    {body}
</scene>"#
    )
}

/// Renders the job `options` (with the library, as `raylab render` does):
/// its image's pixels.
pub fn job_pixels(options: raylab::job::JobOptions) -> Vec<[f32; 3]> {
    let image = raylab::job::Job::new(options)
        .unwrap()
        .render_with(&raylab::job::Hooks::default())
        .unwrap()
        .finished
        .image;
    pixels(&image)
}

/// A reference image of `assets/refs` (made by programs other than raylab).
pub fn reference_image(name: &str) -> Film {
    let path = asset("refs").join(name);
    read_exr(&path).unwrap_or_else(|e| panic!("{e}"))
}

/// Whether two images are equal bit for bit (NaN included, -0.0 ≠ 0.0).
pub fn bit_identical(a: &Film, b: &Film) -> bool {
    a.pixels.len() == b.pixels.len()
        && a.pixels
            .iter()
            .zip(&b.pixels)
            .all(|(p, q)| p.to_array().map(f32::to_bits) == q.to_array().map(f32::to_bits))
}

/// A UV sphere of `rings × segments` faces as triangles wound counter-clockwise
/// seen from outside (no degenerate triangles at the poles).
pub fn sphere_triangles(
    centre: glam::Vec3A,
    radius: f32,
    segments: usize,
    rings: usize,
) -> Vec<raylab::Triangle> {
    use std::f32::consts::PI;
    let point = |ring: usize, seg: usize| {
        let theta = PI * ring as f32 / rings as f32;
        let phi = 2.0 * PI * seg as f32 / segments as f32;
        centre
            + radius
                * glam::Vec3A::new(
                    theta.sin() * phi.cos(),
                    theta.cos(),
                    theta.sin() * phi.sin(),
                )
    };
    let mut tris = Vec::new();
    for ring in 0..rings {
        for seg in 0..segments {
            let (a, b) = (point(ring, seg), point(ring, seg + 1));
            let (c, d) = (point(ring + 1, seg), point(ring + 1, seg + 1));
            if ring != 0 {
                tris.push(raylab::Triangle::new(a, b, c));
            }
            if ring != rings - 1 {
                tris.push(raylab::Triangle::new(b, d, c));
            }
        }
    }
    // Wind every triangle counter-clockwise seen from outside.
    for t in &mut tris {
        let n = (t.v[1] - t.v[0]).cross(t.v[2] - t.v[0]);
        if n.dot((t.v[0] + t.v[1] + t.v[2]) / 3.0 - centre) < 0.0 {
            *t = raylab::Triangle::new(t.v[0], t.v[2], t.v[1]);
        }
    }
    tris
}

/// A two-sided scene of bare triangles, each with its material, front normals
/// from the counter-clockwise winding.
pub fn two_sided_scene(
    triangles: Vec<raylab::Triangle>,
    material_of: Vec<u32>,
    materials: Vec<raylab::materials::surface::SurfaceMaterial>,
) -> raylab::Scene {
    let normals = triangles
        .iter()
        .map(|t| (t.v[1] - t.v[0]).cross(t.v[2] - t.v[0]).normalize_or_zero())
        .collect();
    raylab::Scene::from_parts(raylab::scene::SceneParts {
        triangles,
        normals,
        material_of,
        materials,
        two_sided: true,
        ..Default::default()
    })
    .unwrap()
}

/// A `path` render of `spp` samples per pixel with seed `seed`.
pub fn path_film(scene: &raylab::Scene, camera: &raylab::Camera, spp: u32, seed: u64) -> Film {
    let settings = raylab::render::RenderSettings {
        integrator: raylab::Integrator::path(),
        spp,
        seed,
    };
    raylab::render::render(scene, camera, &settings, &|_| {}).film
}

/// Runs the `raylab` binary in `dir` without a display or input.
pub fn raylab(args: &[&str], dir: &Path) -> std::process::Output {
    std::process::Command::new(env!("CARGO_BIN_EXE_raylab"))
        .args(args)
        .current_dir(dir)
        .env_remove("DISPLAY")
        .stdin(std::process::Stdio::null())
        .output()
        .expect("run raylab")
}

/// A perspective camera at `position` looking at `target` (+y up) with a
/// vertical field of view of `fov_deg`.
pub fn look_camera(
    position: glam::Vec3A,
    target: glam::Vec3A,
    fov_deg: f32,
    w: u32,
    h: u32,
) -> raylab::Camera {
    let rotation = raylab::camera::look_at(position, target, glam::Vec3A::Y).unwrap();
    let lens = raylab::camera::Lens::from_yfov(fov_deg.to_radians());
    raylab::Camera::with_lens(position, rotation, lens, w, h)
}

/// A Mitsuba `.vol` grid of 2 × 2 × 2 samples of one channel, all `value`,
/// over the unit box (its `to_world` places it).
pub fn constant_vol(value: f32) -> Vec<u8> {
    let mut vol = b"VOL".to_vec();
    vol.push(3);
    for v in [1i32, 2, 2, 2, 1] {
        vol.extend_from_slice(&v.to_le_bytes());
    }
    for v in [0.0f32, 0.0, 0.0, 1.0, 1.0, 1.0] {
        vol.extend_from_slice(&v.to_le_bytes());
    }
    for _ in 0..8 {
        vol.extend_from_slice(&value.to_le_bytes());
    }
    vol
}

/// The error loading the scene at `path` gives (panicking if it loads),
/// checked to be one line that names the file (its file name).
#[allow(dead_code)]
pub fn load_error(path: &std::path::Path) -> String {
    let err = raylab::load::load(path.to_str().unwrap(), &Default::default())
        .err()
        .map(|e| e.to_string())
        .unwrap_or_else(|| panic!("{} loaded", path.display()));
    assert_eq!(err.trim_end().lines().count(), 1, "{err}");
    let name = path.file_name().unwrap().to_string_lossy();
    assert!(err.contains(&*name), "{err} does not name {name}");
    err
}
