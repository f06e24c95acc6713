//! A render checkpoint (`--checkpoint FILE`), its checksum appended so that
//! inputs get past it to the header and the sums: read as a resume reads it.
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| raylab_fuzz::targets::checkpoint(data));
