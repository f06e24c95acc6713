//! `cargo run --release --example path_convergence [-- THREADS [SAMPLER]]`: how
//! fast `path` converges to the Mitsuba 3 reference of the lab box
//! (`assets/refs/cornell-path-mitsuba-256.exr`): relMSE at 16, 64, 256 and 1024
//! spp, and the time a progressive render needs to reach relMSE 1e-2 and 1e-3
//! (the numbers in docs/path-tracing.md).

use std::path::Path;
use std::time::{Duration, Instant};

use raylab::film::{Film, read_exr, rel_mse};
use raylab::integrators::Integrator;
use raylab::integrators::path::{PathOptions, SamplerKind};
use raylab::render::accumulate;
use raylab::{Camera, load::cornell};

fn main() {
    let mut args = std::env::args().skip(1);
    let threads: usize = args.next().map_or(2, |a| a.parse().expect("THREADS"));
    let sampler = match args.next().as_deref() {
        None => SamplerKind::DEFAULT,
        Some(name) => SamplerKind::ALL
            .into_iter()
            .find(|k| k.name() == name)
            .expect("sampler name"),
    };
    let reference = read_exr(
        &Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/refs/cornell-path-mitsuba-256.exr"),
    )
    .expect("reference image");
    let scene = cornell::scene();
    let camera = Camera::lab(cornell::CAMERA_POSITION, 0.0, 0.0, 256, 256);
    let integrator = Integrator::Path(PathOptions {
        sampler,
        ..PathOptions::default()
    });
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap();
    println!("sampler={} threads={threads}", sampler.name());
    // Progressive: passes of doubling size; relMSE after each pass, with the time
    // spent rendering (the relMSE itself is not timed).
    let mut sums = Film::new(256, 256);
    let mut spp = 0u32;
    let mut spent = Duration::ZERO;
    let mut targets = vec![1e-2, 1e-3];
    let mut avg = Film::new(256, 256);
    let mut rays = 0u64;
    for pass in [1u32, 1, 2, 4, 8, 16, 32, 64, 128, 256, 512, 1024, 2048] {
        let start = Instant::now();
        rays += pool.install(|| {
            accumulate(
                &scene,
                &camera,
                integrator,
                0,
                spp..spp + pass,
                &mut sums,
                &|_| {},
            )
            .rays
        });
        spent += start.elapsed();
        spp += pass;
        avg.pixels.clone_from(&sums.pixels);
        avg.scale(1.0 / spp as f32);
        let e = rel_mse(&avg, &reference);
        // The time the same rate would need for 1e-2 and 1e-3 (relMSE ≈ c/spp).
        let per_spp = spent.as_secs_f64() / spp as f64;
        println!(
            "spp={spp} rel_mse={e:.3e} spp_x_rel_mse={:.3} seconds={:.2} est_seconds_1e-2={:.2} est_seconds_1e-3={:.2} rays_per_path={:.2}",
            e * spp as f64,
            spent.as_secs_f64(),
            e * spp as f64 / 1e-2 * per_spp,
            e * spp as f64 / 1e-3 * per_spp,
            rays as f64 / (spp as f64 * 65536.0),
        );
        while targets.first().is_some_and(|&t| e <= t) {
            println!(
                "reached rel_mse<={:e} at spp={spp} seconds={:.2}",
                targets[0],
                spent.as_secs_f64()
            );
            targets.remove(0);
        }
        let quick = std::env::var("QUICK")
            .ok()
            .and_then(|q| q.parse::<u32>().ok());
        if targets.is_empty() && spp >= 1024 || quick.is_some_and(|q| spp >= q) {
            break;
        }
    }
}
