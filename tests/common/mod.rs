//! Helpers shared by the integration tests.

use std::path::Path;

use raylab::film::{Film, read_exr};

/// A reference image from `../shared/refs`, which must sit beside the project.
pub fn shared_ref(name: &str) -> Film {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../shared/refs")
        .join(name);
    read_exr(&path).unwrap_or_else(|e| {
        panic!("{e}: the shared folder must sit beside the project (see README)")
    })
}

/// Whether two images are equal bit for bit (NaN included, -0.0 ≠ 0.0).
pub fn bit_identical(a: &Film, b: &Film) -> bool {
    a.pixels.len() == b.pixels.len()
        && a.pixels
            .iter()
            .zip(&b.pixels)
            .all(|(p, q)| p.to_array().map(f32::to_bits) == q.to_array().map(f32::to_bits))
}
