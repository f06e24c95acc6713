//! Mitsuba 3's `direct` integrator with its sample counts
//! (`emitter_samples`, `bsdf_samples`, `shading_samples`): every count
//! renders the same expected image (Veach's multi-sample MIS), a point
//! light is counted once whatever `emitter_samples` is (where Mitsuba
//! 3.7.1 counts it `emitter_samples` times: docs/mitsuba-scenes.md), and
//! bad counts are refused in one line. Mitsuba's own statistical test of
//! the counts is `tools/mitsuba_suite.py` on
//! `tests/data/mitsuba/suite/counted_direct.xml`.

use std::path::Path;

mod common;

use raylab::job::JobOptions;

/// Writes `xml` as `name` in `dir`; its path.
fn write(dir: &Path, name: &str, xml: &str) -> String {
    let path = dir.join(name);
    std::fs::write(&path, xml).unwrap();
    path.to_str().unwrap().to_string()
}

/// A 40 × 30 view of a grey floor under `lights`, rendered by `direct`
/// with `counts` (its attributes) at `spp` samples: the image's pixels.
fn render(dir: &Path, name: &str, counts: &str, lights: &str, spp: u32) -> Vec<[f32; 3]> {
    let xml = format!(
        r#"<scene version="3.0.0">
    <integrator type="direct">{counts}</integrator>
    <sensor type="perspective">
        <float name="fov" value="60"/>
        <transform name="to_world"><lookat origin="0, -3, 2" target="0, 0, 0" up="0, 0, 1"/></transform>
        <film type="hdrfilm"><integer name="width" value="40"/><integer name="height" value="30"/></film>
    </sensor>
    <shape type="rectangle">
        <transform name="to_world"><scale value="3"/></transform>
        <bsdf type="roughplastic">
            <rgb name="diffuse_reflectance" value="0.5, 0.4, 0.3"/>
            <float name="alpha" value="0.3"/>
        </bsdf>
    </shape>
    {lights}
</scene>"#
    );
    let path = write(dir, name, &xml);
    let mut options = JobOptions::new(&path);
    options.spp = Some(spp);
    options.quiet = true;
    common::job_pixels(options)
}

/// The mean of each channel over the image.
fn mean(pixels: &[[f32; 3]]) -> [f64; 3] {
    let mut m = [0.0f64; 3];
    for p in pixels {
        for c in 0..3 {
            m[c] += f64::from(p[c]);
        }
    }
    m.map(|v| v / pixels.len() as f64)
}

/// An emitting rectangle above the floor, facing down onto it (its back,
/// black, is in view).
const AREA: &str = r#"<shape type="rectangle">
        <transform name="to_world"><scale value="0.6"/><rotate x="1" angle="180"/><translate x="0.5" z="1.5"/></transform>
        <bsdf type="diffuse"/>
        <emitter type="area"><rgb name="radiance" value="4, 5, 6"/></emitter>
    </shape>"#;

#[test]
fn every_count_renders_the_same_image() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let reference = mean(&render(d, "one.xml", "", AREA, 256));
    for (name, counts, spp) in [
        (
            "lights.xml",
            r#"<integer name="emitter_samples" value="4"/><integer name="bsdf_samples" value="0"/>"#,
            64,
        ),
        (
            "bsdf.xml",
            r#"<integer name="emitter_samples" value="0"/><integer name="bsdf_samples" value="4"/>"#,
            256,
        ),
        (
            "both.xml",
            r#"<integer name="emitter_samples" value="3"/><integer name="bsdf_samples" value="2"/>"#,
            64,
        ),
        (
            "shading.xml",
            r#"<integer name="shading_samples" value="3"/>"#,
            64,
        ),
    ] {
        let m = mean(&render(d, name, counts, AREA, spp));
        for c in 0..3 {
            let rel = (m[c] - reference[c]).abs() / reference[c];
            // Measured: within 0.04–0.12 % (the BSDF-only image is the noisiest).
            assert!(
                rel < 0.01,
                "{name}: channel {c}: {} against {}",
                m[c],
                reference[c]
            );
        }
    }
}

#[test]
fn more_samples_of_a_point_light_count_it_once() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let point = r#"<emitter type="point">
        <point name="position" x="0.3" y="0.2" z="1.2"/>
        <rgb name="intensity" value="2, 3, 4"/>
    </emitter>"#;
    let one = render(d, "one.xml", "", point, 4);
    let four = render(
        d,
        "four.xml",
        r#"<integer name="emitter_samples" value="4"/>"#,
        point,
        4,
    );
    let none = render(
        d,
        "none.xml",
        r#"<integer name="emitter_samples" value="0"/>"#,
        point,
        4,
    );
    assert!(mean(&one)[0] > 0.01, "the floor is lit");
    for (a, b) in one.iter().zip(&four) {
        for c in 0..3 {
            // Four samples of weight ¼ each: the same value to rounding.
            assert!(
                (a[c] - b[c]).abs() <= 1e-5 * a[c].abs().max(1e-3),
                "{a:?} {b:?}"
            );
        }
    }
    // BSDF samples cannot find a point light.
    assert!(none.iter().all(|p| p == &[0.0; 3]));
}

#[test]
fn bad_counts_are_refused_in_one_line() {
    let dir = tempfile::tempdir().unwrap();
    for (name, counts, message) in [
        (
            "zero.xml",
            r#"<integer name="emitter_samples" value="0"/><integer name="bsdf_samples" value="0"/>"#,
            "at least one emitter or BSDF sample",
        ),
        (
            "negative.xml",
            r#"<integer name="bsdf_samples" value="-1"/>"#,
            "must be from 0 to 4096",
        ),
        (
            "huge.xml",
            r#"<integer name="emitter_samples" value="100000000000"/>"#,
            "must be from 0 to 4096",
        ),
        (
            "both.xml",
            r#"<integer name="shading_samples" value="2"/><integer name="bsdf_samples" value="1"/>"#,
            "not both",
        ),
    ] {
        let xml = format!(
            r#"<scene version="3.0.0">
    <integrator type="direct">{counts}</integrator>
    <emitter type="constant"/>
</scene>"#
        );
        let path = write(dir.path(), name, &xml);
        let e = raylab::load::load(&path, &Default::default())
            .unwrap_err()
            .to_string();
        assert!(
            !e.contains('\n') && e.contains(&format!("{name}:")) && e.contains(message),
            "{name}: {e}"
        );
    }
}
