//! `raylab bench`: ray-casting throughput of the BVH on a mesh, as
//! `key=value` lines: the build, then each workload (the standard primary,
//! incoherent, shadow, bounce and surface-shadow rays of [`crate::workload`],
//! or a ray file) with each query API, at each thread count.

use std::io::Write;
use std::time::Instant;

use crate::film::write_bytes;
use crate::geometry::bvh::Bvh;
use crate::geometry::ray::{Hit, Ray};
use crate::workload::{
    self, cast_closest, cast_closest_stream, cast_closest4, cast_closest8, cast_occluded,
    cast_occluded_stream, encode_hits,
};
use anyhow::{Context, anyhow};

/// What to measure: the options of `raylab bench`.
#[derive(Clone, Debug, Default)]
pub struct BenchOptions {
    /// The Wavefront OBJ mesh to trace.
    pub mesh: std::path::PathBuf,
    /// A ray file (little-endian f32, six per ray) instead of the standard
    /// workloads.
    pub rays: Option<std::path::PathBuf>,
    /// Where to write the first workload's hits (with `rays`).
    pub hits: Option<std::path::PathBuf>,
    /// Any-hit queries instead of closest hits (with `rays`).
    pub shadow: bool,
    /// Far end of the rays' interval [default: infinity].
    pub tfar: Option<f32>,
    /// Thread counts to run [default: all cores].
    pub threads: Vec<usize>,
    /// The query APIs to time [default: all without `rays`, else single].
    pub api: Option<BenchApi>,
    /// Timed runs per workload after one warm-up; the median is reported.
    pub repeat: usize,
}

/// The query APIs `raylab bench` can time.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BenchApi {
    /// One ray at a time (`Bvh::intersect`, `Bvh::occluded`).
    Single,
    /// Batches (`Bvh::intersect_stream`, `Bvh::occluded_stream`).
    Stream,
    /// Every API.
    All,
}

/// Rays of the generated incoherent and shadow workloads.
const INCOHERENT_RAYS: usize = 1 << 20;

/// One set of rays and how to cast them.
struct Workload {
    name: &'static str,
    rays: Vec<Ray>,
    t_max: f32,
    query: Query,
}

#[derive(Clone, Copy, PartialEq)]
enum Query {
    Closest,
    Closest4,
    Closest8,
    ClosestStream,
    Any,
    AnyStream,
}

impl Query {
    fn api(self) -> &'static str {
        match self {
            Query::Closest | Query::Any => "single",
            Query::Closest4 => "packet4",
            Query::Closest8 => "packet8",
            Query::ClosestStream | Query::AnyStream => "stream",
        }
    }

    /// The queries of `api` for closest hits (`any` false) or any hits.
    fn of(api: BenchApi, any: bool, packets: bool) -> Vec<Query> {
        let single = if any { Query::Any } else { Query::Closest };
        let stream = if any {
            Query::AnyStream
        } else {
            Query::ClosestStream
        };
        match api {
            BenchApi::Single => vec![single],
            BenchApi::Stream => vec![stream],
            BenchApi::All if packets && !any => {
                vec![single, Query::Closest4, Query::Closest8, stream]
            }
            BenchApi::All => vec![single, stream],
        }
    }
}

/// Timed builds, after one warm-up (as many as Embree's harness times).
const BUILD_RUNS: usize = 5;

/// Measures what `args` asks for, writing the `key=value` lines to `out`
/// and the mesh's warnings (one line each) to `warn`.
pub fn run(
    args: &BenchOptions,
    out: &mut dyn Write,
    warn: &mut dyn FnMut(&str),
) -> anyhow::Result<()> {
    let mesh = crate::load::obj::load_obj(&args.mesh)?;
    for w in &mesh.warnings {
        warn(&format!("warning: {}", crate::guard::one_line(w)));
    }
    let tris = &mesh.triangles;

    // Build a few times and report the median (the first build also warms up);
    // the previous tree is freed outside the timed part.
    let mut times = Vec::new();
    let mut bvh = Bvh::build(tris);
    for _ in 0..BUILD_RUNS {
        let start = Instant::now();
        let built = Bvh::build(tris);
        times.push(start.elapsed().as_secs_f64() * 1e3);
        bvh = built;
    }
    times.sort_by(f64::total_cmp);
    writeln!(
        out,
        "build triangles={} build_ms={:.1} bytes_per_triangle={:.1} nodes={}",
        tris.len(),
        times[BUILD_RUNS / 2],
        bvh.memory_bytes() as f64 / tris.len() as f64,
        bvh.node_count()
    )?;

    let workloads = match &args.rays {
        Some(path) => {
            let rays = workload::read_rays(path).map_err(|e| anyhow!(e))?;
            let t_max = args.tfar.unwrap_or(f32::INFINITY);
            let name = if args.shadow { "shadow" } else { "rays" };
            Query::of(args.api.unwrap_or(BenchApi::Single), args.shadow, true)
                .into_iter()
                .map(|query| Workload {
                    name,
                    rays: rays.clone(),
                    t_max,
                    query,
                })
                .collect()
        }
        None => {
            let (lo, hi) = crate::geometry::triangle::bounds(tris);
            let diag = (hi - lo).length();
            let incoherent = workload::incoherent(lo, hi, INCOHERENT_RAYS);
            let primary = workload::primary(lo, hi);
            let surface = workload::surface(&bvh, tris, &incoherent, lo, hi);
            let api = args.api.unwrap_or(BenchApi::All);
            let mut all = Vec::new();
            let mut add = |name, rays: &Vec<Ray>, t_max: f32, any: bool, packets: bool| {
                for query in Query::of(api, any, packets) {
                    all.push(Workload {
                        name,
                        rays: rays.clone(),
                        t_max,
                        query,
                    });
                }
            };
            let t_max = args.tfar.unwrap_or(f32::INFINITY);
            add("primary", &primary, t_max, false, true);
            add("incoherent", &incoherent, t_max, false, false);
            add(
                "shadow",
                &incoherent,
                args.tfar.unwrap_or(diag),
                true,
                false,
            );
            add("bounce", &surface.bounce, t_max, false, false);
            add(
                "surface_shadow",
                &surface.shadow,
                workload::SURFACE_SHADOW_TFAR,
                true,
                false,
            );
            all
        }
    };

    let threads = if args.threads.is_empty() {
        vec![rayon::current_num_threads()]
    } else {
        args.threads.clone()
    };
    let mut hits: Vec<Option<Hit>> = Vec::new();
    let mut blocked: Vec<bool> = Vec::new();
    for &n in &threads {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build()
            .context("cannot start worker threads")?;
        for w in &workloads {
            hits.resize(w.rays.len(), None);
            blocked.resize(w.rays.len(), false);
            let mut times = Vec::with_capacity(args.repeat);
            pool.install(|| {
                for run in 0..=args.repeat {
                    let start = Instant::now();
                    match w.query {
                        Query::Closest => cast_closest(&bvh, &w.rays, w.t_max, &mut hits),
                        Query::Closest4 => cast_closest4(&bvh, &w.rays, w.t_max, &mut hits),
                        Query::Closest8 => cast_closest8(&bvh, &w.rays, w.t_max, &mut hits),
                        Query::ClosestStream => {
                            cast_closest_stream(&bvh, &w.rays, w.t_max, &mut hits)
                        }
                        Query::Any => cast_occluded(&bvh, &w.rays, w.t_max, &mut blocked),
                        Query::AnyStream => {
                            cast_occluded_stream(&bvh, &w.rays, w.t_max, &mut blocked)
                        }
                    }
                    if run > 0 {
                        times.push(start.elapsed().as_secs_f64());
                    }
                }
            });
            times.sort_by(f64::total_cmp);
            let median = times[times.len() / 2];
            writeln!(
                out,
                "workload={} threads={n} rays={} mrays_per_s={:.2} median_ms={:.1} api={}",
                w.name,
                w.rays.len(),
                w.rays.len() as f64 / median / 1e6,
                median * 1e3,
                w.query.api()
            )?;
        }
    }
    if let (Some(path), Some(w)) = (&args.hits, workloads.first()) {
        let bytes = match w.query {
            Query::Any | Query::AnyStream => blocked.iter().map(|&b| b as u8).collect(),
            _ => encode_hits(&hits),
        };
        write_bytes(&bytes, path)?;
    }
    Ok(())
}
