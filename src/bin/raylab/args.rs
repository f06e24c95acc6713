//! The subcommands and the arguments only the binary has; the render and
//! scene options are the library's ([`raylab::job::options`]).

use std::path::PathBuf;

use clap::{Args, Parser, Subcommand};
use raylab::job::options::parse_threads;
use raylab::job::{JobOptions, SceneOptions};

#[derive(Debug, Parser)]
#[command(
    name = "raylab",
    version,
    about = "A fast, physically based CPU ray tracer, grown from the Cornell-box lab",
    long_about = "A fast, physically based CPU ray tracer, grown from the Cornell-box lab.\n\n\
                  Without a subcommand raylab opens the viewer when a display is available, \
                  and otherwise renders cornell.png."
)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Option<Command>,
}

#[derive(Debug, Subcommand)]
pub enum Command {
    /// Render a scene to an image file (PNG or EXR).
    Render(JobOptions),
    /// Open an interactive window that re-renders as you move the camera and light.
    View(ViewArgs),
    /// Measure ray-casting throughput on a mesh (standard workloads or a ray file).
    Bench(BenchArgs),
    /// Merge the parts of a render split with --tile/--samples into its image.
    Merge(MergeArgs),
}

#[derive(Debug, Args)]
pub struct BenchArgs {
    /// Wavefront OBJ mesh to trace.
    pub mesh: PathBuf,
    /// Ray file: little-endian f32, six per ray (ox oy oz dx dy dz) [default: the
    /// standard primary, incoherent and shadow workloads].
    #[arg(long, value_name = "FILE")]
    pub rays: Option<PathBuf>,
    /// Write per ray `f32 t, u32 prim` (with --shadow one `u8`, 1 = occluded); needs --rays.
    #[arg(long, value_name = "FILE", requires = "rays")]
    pub hits: Option<PathBuf>,
    /// Any-hit queries over [0, T] instead of closest hits (with --rays).
    #[arg(long, requires = "rays")]
    pub shadow: bool,
    /// Far end of the rays' interval [default: infinity].
    #[arg(long, value_name = "T", allow_hyphen_values = true, value_parser = parse_positive)]
    pub tfar: Option<f32>,
    /// Thread counts to run, e.g. `1,2` [default: all cores].
    #[arg(long, value_name = "N[,N...]", value_delimiter = ',', allow_hyphen_values = true, value_parser = parse_threads)]
    pub threads: Vec<usize>,
    /// Which query API to time: `single` (one ray at a time), `stream` (batches
    /// with several rays in flight) or `all` (both, and four-ray packets on the
    /// built-in primary workload) [default: all without --rays, else single].
    #[arg(long, value_enum, value_name = "API")]
    pub api: Option<BenchApi>,
    /// Timed runs per workload after one warm-up; the median is reported.
    #[arg(long, default_value_t = 5, value_name = "K", allow_hyphen_values = true, value_parser = parse_repeat)]
    pub repeat: usize,
}

/// The query APIs `raylab bench` can time.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum BenchApi {
    /// One ray at a time (`Bvh::intersect`, `Bvh::occluded`).
    Single,
    /// Batches (`Bvh::intersect_stream`, `Bvh::occluded_stream`).
    Stream,
    /// Every API.
    All,
}

#[derive(Debug, Args)]
pub struct MergeArgs {
    /// The parts (`raylab render --tile/--samples` outputs) of one render.
    #[arg(required = true, value_name = "PART")]
    pub parts: Vec<PathBuf>,
    /// The merged image: `.png` or `.exr`.
    #[arg(short, long, value_name = "FILE")]
    pub output: PathBuf,
    /// Most memory the merge may take (e.g. 4G; 0 or none: no limit) [default: 3/4 of physical memory, or of a lower cgroup limit].
    #[arg(long, value_name = "SIZE", allow_hyphen_values = true, value_parser = raylab::memory::parse_budget)]
    pub max_memory: Option<raylab::memory::MemoryBudget>,
    /// Denoise the merged image (never the parts apart: seams), as
    /// `raylab render --denoise` denoises the whole [default: as the parts
    /// were rendered: parts of a `--denoise` render are denoised once
    /// merged]; the parts must carry the guides, which `--denoise` gathers.
    #[arg(long, value_name = "BOOL", num_args = 0..=1, default_missing_value = "true", require_equals = true)]
    pub denoise: Option<bool>,
    /// No summary line.
    #[arg(short, long)]
    pub quiet: bool,
}

#[derive(Debug, Args)]
pub struct ViewArgs {
    #[command(flatten)]
    pub scene: SceneOptions,
}

fn parse_repeat(s: &str) -> Result<usize, String> {
    match s.parse::<usize>() {
        Ok(v) if (1..=1000).contains(&v) => Ok(v),
        _ => Err("expected a whole number of runs from 1 to 1000".into()),
    }
}

fn parse_positive(s: &str) -> Result<f32, String> {
    match s.trim().parse::<f32>() {
        Ok(v) if v > 0.0 => Ok(v),
        _ => Err("expected a number > 0 (inf allowed)".into()),
    }
}
