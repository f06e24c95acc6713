//! A PLY file `in.ply`, read as Mitsuba 3's `ply` shape reads it.
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| raylab_fuzz::targets::mitsuba_ply(data));
