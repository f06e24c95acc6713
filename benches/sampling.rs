//! `cargo bench --bench sampling`: light-sampling strategies at equal time on
//! the scenes the tests compare them on at equal samples
//! (`tests/common/sampling_scenes.rs`): the light tree against power and
//! uniform selection among 10,000 emitters, and environment importance
//! sampling against uniform sphere sampling under a small sun. Each strategy
//! is timed in interleaved rounds in this one run (median of the rounds);
//! relMSE falls as 1 / time, so relMSE × seconds is the cost of a quality and
//! the ratio of two costs is the equal-time gain.

#[path = "../tests/common/mod.rs"]
mod common;
#[path = "../tests/common/sampling_scenes.rs"]
mod sampling_scenes;

use std::time::Instant;

use raylab::film::{Film, rel_mse};
use raylab::lights::environment::EnvSampling;
use raylab::scene::LightSelection;
use raylab::{Camera, Scene};

/// Rounds of timing; each round renders every strategy once.
const ROUNDS: usize = 7;

/// Times `spp`-sample renders of each strategy (`set` switches the scene to
/// it) in interleaved rounds and prints relMSE, median time and the cost
/// relMSE × seconds of each, relative to the first.
fn compare<S: Copy + std::fmt::Debug>(
    name: &str,
    scene: &mut Scene,
    camera: &Camera,
    spp: u32,
    strategies: &[S],
    set: impl Fn(&mut Scene, S),
) {
    let reference = common::path_film(scene, camera, 1024, 99);
    let mut times = vec![Vec::new(); strategies.len()];
    let mut errors = vec![0.0; strategies.len()];
    for round in 0..=ROUNDS {
        for (k, &strategy) in strategies.iter().enumerate() {
            set(scene, strategy);
            let start = Instant::now();
            let film: Film = common::path_film(scene, camera, spp, 7 + round as u64);
            let seconds = start.elapsed().as_secs_f64();
            // Round 0 warms up (caches, the thread pool, lazy tables).
            if round > 0 {
                times[k].push(seconds);
                errors[k] += rel_mse(&film, &reference) / ROUNDS as f64;
            }
        }
    }
    let costs: Vec<f64> = times
        .iter_mut()
        .zip(&errors)
        .map(|(t, e)| {
            t.sort_by(f64::total_cmp);
            t[t.len() / 2] * e
        })
        .collect();
    for (k, strategy) in strategies.iter().enumerate() {
        let median = times[k][times[k].len() / 2];
        println!(
            "sampling scene={name} strategy={strategy:?} spp={spp} relmse={:.3e} median_ms={:.1} \
             ms_per_sample_vs_first={:.2} equal_time_gain_of_first={:.1}",
            errors[k],
            median * 1e3,
            median / times[0][times[0].len() / 2],
            costs[k] / costs[0],
        );
    }
}

fn main() {
    let threads = rayon::current_num_threads();
    println!("sampling threads={threads}");
    let (mut scene, camera) = sampling_scenes::city_at_night();
    compare(
        "city_at_night",
        &mut scene,
        &camera,
        8,
        &[
            LightSelection::Tree,
            LightSelection::Power,
            LightSelection::Uniform,
        ],
        |s, selection| s.set_light_selection(selection),
    );
    let (mut scene, camera) = sampling_scenes::sun_patch();
    compare(
        "sun_patch",
        &mut scene,
        &camera,
        16,
        &[EnvSampling::Importance, EnvSampling::Uniform],
        |s, sampling| {
            let env = s.environment().clone().with_sampling(sampling);
            s.set_environment(env);
        },
    );
}
