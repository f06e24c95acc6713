//! A KTX2 texture (Basis Universal).
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| raylab_fuzz::targets::ktx2(data));
