//! Load time of a 4k environment map and of its sampling tables.
//!
//! `cargo run --release --example env_load_time -- assets/envmaps/venice_sunset_1k.hdr`
//! upsamples the map 4× (to 4096 × 2048, nearest texel), writes it as a Radiance
//! file in the temporary folder, then times reading + decoding it and building
//! its sampling tables, five times each, and prints the medians.

use std::time::Instant;

use raylab::lights::environment::{EnvMap, MAX_SIDE, MAX_TEXELS};
use raylab::lights::rgbe::{self, RgbImage};

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() -> anyhow::Result<()> {
    let source = std::env::args()
        .nth(1)
        .unwrap_or_else(|| "assets/envmaps/venice_sunset_1k.hdr".into());
    let small = rgbe::decode(&std::fs::read(&source)?, MAX_SIDE, MAX_TEXELS)
        .map_err(|e| anyhow::anyhow!("{source}: {e}"))?;
    let (w, h) = (small.width * 4, small.height * 4);
    let pixels = (0..w * h)
        .map(|k| small.pixels[(k / w / 4) * small.width + (k % w) / 4])
        .collect();
    let big = RgbImage {
        width: w,
        height: h,
        pixels,
    };
    let path = std::env::temp_dir().join("raylab-env-4k.hdr");
    rgbe::encode(
        &big,
        &mut std::io::BufWriter::new(std::fs::File::create(&path)?),
    )?;
    let bytes = std::fs::metadata(&path)?.len();
    println!(
        "{w}×{h} map: {} ({:.1} MiB)",
        path.display(),
        bytes as f64 / 1048576.0
    );
    let (mut read, mut tables) = (Vec::new(), Vec::new());
    for _ in 0..5 {
        let start = Instant::now();
        let image = rgbe::decode(&std::fs::read(&path)?, MAX_SIDE, MAX_TEXELS)
            .map_err(|e| anyhow::anyhow!("{e}"))?;
        read.push(start.elapsed().as_secs_f64());
        let start = Instant::now();
        let map = EnvMap::from_image(image);
        tables.push(start.elapsed().as_secs_f64());
        std::hint::black_box(map);
    }
    println!(
        "read + decode: {:.0} ms; sampling tables: {:.0} ms (medians of 5, {} threads)",
        median(read) * 1e3,
        median(tables) * 1e3,
        rayon::current_num_threads()
    );
    std::fs::remove_file(&path)?;
    Ok(())
}
