//! A `.vol` file `in.vol` read as Mitsuba 3's `VolumeGrid` reads it, as
//! a medium's grid and as an `sdfgrid`'s.
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| raylab_fuzz::targets::mitsuba_vol(data));
