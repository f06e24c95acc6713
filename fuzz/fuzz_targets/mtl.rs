//! A material library `in.mtl`, used by a fixed OBJ that names the materials
//! `a`, `b` and `m`; loaded and rendered.
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| raylab_fuzz::targets::mtl(data));
