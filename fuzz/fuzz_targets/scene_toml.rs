//! A scene file `in.toml` (it may refer to the fixtures), its settings read
//! and the scene loaded and rendered.
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| raylab_fuzz::targets::scene_toml(data));
