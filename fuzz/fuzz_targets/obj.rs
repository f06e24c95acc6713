//! A Wavefront OBJ (before the first NUL byte) and its material library
//! `in.mtl` (after it), loaded and rendered as `raylab render in.obj` would.
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| raylab_fuzz::targets::obj(data));
