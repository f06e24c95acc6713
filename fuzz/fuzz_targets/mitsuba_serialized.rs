//! A `.serialized` file `in.serialized`, its shapes 0 to 3 read as Mitsuba
//! 3's `serialized` shape reads them.
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| raylab_fuzz::targets::mitsuba_serialized(data));
