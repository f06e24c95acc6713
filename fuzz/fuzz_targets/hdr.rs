//! A Radiance RGBE map `in.hdr` lighting the fixture OBJ.
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| raylab_fuzz::targets::hdr(data));
