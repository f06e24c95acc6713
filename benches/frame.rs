//! `cargo bench --bench frame`: time per frame of the lab's box at 500×500, the
//! viewer's workload (target: `direct` under 15 ms on two cores). Prints the median
//! of 40 frames after a warm-up, for one thread and for all cores, so that the two
//! can be compared within one run on a noisy machine.

use std::time::Instant;

use raylab::render::{RenderSettings, render};
use raylab::{Camera, Integrator, load::cornell};

fn main() {
    let scene = cornell::scene();
    let camera = Camera::lab(cornell::CAMERA_POSITION, 0.0, 0.0, 500, 500);
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    for integrator in Integrator::ALL {
        for threads in [1, cores] {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .expect("thread pool");
            let settings = RenderSettings {
                integrator,
                ..RenderSettings::default()
            };
            let (mut times, mut rays) = (Vec::new(), 0);
            pool.install(|| {
                for frame in 0..50 {
                    let start = Instant::now();
                    let out = render(&scene, &camera, &settings, &|_| {});
                    if frame >= 10 {
                        times.push(start.elapsed().as_secs_f64());
                        rays = out.rays;
                    }
                }
            });
            times.sort_by(f64::total_cmp);
            let median = times[times.len() / 2];
            println!(
                "frame integrator={integrator} size=500x500 threads={threads} median_ms={:.2} fps={:.0} mrays_per_s={:.1}",
                median * 1e3,
                1.0 / median,
                rays as f64 / median / 1e6
            );
        }
    }
}
