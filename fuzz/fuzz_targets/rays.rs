//! A `raylab bench --rays` file, read as the bench reads it and cast at a
//! small mesh by every query kind, each answer compared with brute force.
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| raylab_fuzz::targets::rays(data));
