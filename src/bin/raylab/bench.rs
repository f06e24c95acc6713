//! `raylab bench`: the library's [`raylab::bench`] with its lines on stdout.

use crate::args::{BenchApi, BenchArgs};

pub fn run(args: &BenchArgs) -> anyhow::Result<()> {
    let options = raylab::bench::BenchOptions {
        mesh: args.mesh.clone(),
        rays: args.rays.clone(),
        hits: args.hits.clone(),
        shadow: args.shadow,
        tfar: args.tfar,
        threads: args.threads.clone(),
        api: args.api.map(|a| match a {
            BenchApi::Single => raylab::bench::BenchApi::Single,
            BenchApi::Stream => raylab::bench::BenchApi::Stream,
            BenchApi::All => raylab::bench::BenchApi::All,
        }),
        repeat: args.repeat,
    };
    let mut out = std::io::stdout().lock();
    raylab::bench::run(&options, &mut out, &mut |w| eprintln!("{w}"))
}
