//! A glTF 2.0 JSON file `in.gltf` (it may refer to the fixtures `fixture.bin`
//! and `fixture.png`, or carry `data:` URIs), loaded and rendered.
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| raylab_fuzz::targets::gltf_json(data));
