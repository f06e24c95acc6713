//! A `KHR_draco_mesh_compression` stream as a glTF primitive's only data.
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| raylab_fuzz::targets::draco(data));
