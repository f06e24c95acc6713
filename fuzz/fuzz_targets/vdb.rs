//! An OpenVDB file read as a medium's density grid, then looked up.
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| raylab_fuzz::targets::vdb(data));
