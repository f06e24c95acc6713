//! An `EXT_`/`KHR_meshopt_compression` stream in a glTF's buffer view.
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| raylab_fuzz::targets::meshopt(data));
