//! Sample values: PCG32 streams keyed by (seed, pixel, sample) and
//! Owen-scrambled Sobol' points.

pub mod distribution;
pub mod equiangular;
pub mod filter;
pub mod sampler;
pub mod sobol;
pub mod splat;
