//! A Mitsuba 3 XML scene `in.xml`, read into its tree (includes, `$name`
//! substitution, references, transforms, the 0.x upgrade).
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| raylab_fuzz::targets::mitsuba_xml(data));
