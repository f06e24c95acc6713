//! Rays and triangles from raw bytes (the first byte: how many rays, 24 bytes
//! each, then triangles of 36 bytes), every query kind against brute force.
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| raylab_fuzz::targets::bvh(data));
