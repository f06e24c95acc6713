//! The limits of what a render accepts: image size, samples per pixel and time.
//! The scene files, the command line and the farm check them; the fixed-point
//! sums ([`crate::fixed`]) and the sample streams ([`crate::sampling`]) count
//! on them.

/// Largest image side accepted from the command line or a scene file, in pixels.
pub const MAX_SIDE: u32 = 16_384;
/// Largest image accepted, in pixels.
pub const MAX_PIXELS: u64 = 1 << 27;
/// Most samples per pixel accepted.
pub const MAX_SPP: u32 = 1 << 20;
/// Longest time budget accepted, in seconds (a week).
pub const MAX_TIME: f64 = 7.0 * 24.0 * 3600.0;
