//! Participating media (issue 44) against numbers known without raylab:
//! the transmittance of an absorbing sphere, a white furnace (a sphere of
//! scattering, non-absorbing medium under a uniform sky stays exactly the
//! sky), a heterogeneous medium that is constant (delta and ratio
//! tracking) against its homogeneous twin, and Mitsuba's rule that only
//! `volpath` sees media.

mod common;

#[allow(dead_code)]
#[path = "common/gltf_builder.rs"]
mod builder;

use std::path::Path;

use raylab::job::JobOptions;

/// Renders the Mitsuba scene `xml` (written into `dir`) at `spp` samples.
fn render(dir: &Path, name: &str, xml: &str, spp: u32) -> Vec<[f32; 3]> {
    let path = dir.join(name);
    std::fs::write(&path, xml).unwrap();
    let mut options = JobOptions::new(path.to_str().unwrap());
    options.spp = Some(spp);
    options.seed = Some(7);
    common::job_pixels(options)
}

/// A scene of `medium` filling a unit sphere (a `null` boundary) at the
/// origin, seen through an orthographic 16 × 16 camera spanning
/// [−1.25, 1.25]² under a constant sky of radiance `sky`, rendered by
/// `integrator` (`volpath` with `max_depth` −1 unless given).
fn sphere_of(medium: &str, sky: f32, integrator: &str) -> String {
    format!(
        r#"<scene version="3.0.0">
    <integrator type="{integrator}"/>
    <sensor type="orthographic">
        <transform name="to_world">
            <scale x="1.25" y="1.25" z="1"/>
            <lookat origin="0, 0, 10" target="0, 0, 0" up="0, 1, 0"/>
        </transform>
        <film type="hdrfilm">
            <integer name="width" value="16"/><integer name="height" value="16"/>
            <rfilter type="box"/>
        </film>
    </sensor>
    <emitter type="constant"><rgb name="radiance" value="{sky}"/></emitter>
    {medium}
    <shape type="sphere">
        <bsdf type="null"/>
        <ref name="interior" id="m"/>
    </shape>
</scene>"#
    )
}

/// A heterogeneous medium `m` whose extinction is a constant grid of
/// value `value` (an XML property) over the unit sphere's box, with the
/// medium's other properties `rest`: delta and ratio tracking, null
/// collisions, the majorant.
fn constant_grid(value: &str, rest: &str) -> String {
    format!(
        r#"<medium type="heterogeneous" id="m">
        <volume type="constvolume" name="sigma_t">
            {value}
            <transform name="to_world"><scale value="2"/><translate value="-1, -1, -1"/></transform>
        </volume>{rest}</medium>"#
    )
}

/// The mean of `exp(−σ · chord)` over pixel `(x, y)` of [`sphere_of`]'s
/// camera (16 × 16 points per pixel), for the chord through the unit sphere.
fn absorbed(x: usize, y: usize, sigma: f32) -> f32 {
    let n = 16;
    let mut sum = 0.0f64;
    for i in 0..n {
        for j in 0..n {
            let px = -1.25 + 2.5 * (x as f64 + (i as f64 + 0.5) / n as f64) / 16.0;
            let py = 1.25 - 2.5 * (y as f64 + (j as f64 + 0.5) / n as f64) / 16.0;
            let r2 = px * px + py * py;
            let chord = if r2 < 1.0 {
                2.0 * (1.0 - r2).sqrt()
            } else {
                0.0
            };
            sum += (-f64::from(sigma) * chord).exp();
        }
    }
    (sum / (n * n) as f64) as f32
}

/// A purely absorbing sphere under a white sky: each pixel is the mean
/// transmittance over its footprint, per channel (three extinctions at
/// once: chromatic spectral MIS, whose weights reach 3 on the clearest
/// channel), within 0.04 at 16384 samples (about five standard errors;
/// measured: 0.029 at most homogeneous, 0.017 heterogeneous, whose flights
/// carry spectral MIS over the whole of delta tracking); a grey medium
/// within 0.015 (four); each both as a homogeneous and as a heterogeneous
/// medium (delta tracking, ratio tracking).
#[test]
fn an_absorbing_sphere_transmits_exp_minus_sigma_chord() {
    let dir = tempfile::tempdir().unwrap();
    for (sigma, tolerance) in [([0.3f32, 1.0, 2.5], 0.04), ([0.7f32; 3], 0.015)] {
        for (name, medium) in [
            (
                "homogeneous",
                format!(
                    r#"<medium type="homogeneous" id="m"><rgb name="sigma_t" value="{}, {}, {}"/><float name="albedo" value="0"/></medium>"#,
                    sigma[0], sigma[1], sigma[2]
                ),
            ),
            (
                // Constant over the sphere's box: delta tracking's nulls and
                // ratio tracking (no scattering: only the camera's flights).
                "heterogeneous",
                constant_grid(
                    &format!(
                        r#"<rgb name="value" value="{}, {}, {}"/>"#,
                        sigma[0], sigma[1], sigma[2]
                    ),
                    r#"<float name="albedo" value="0"/>"#,
                ),
            ),
        ] {
            let pixels = render(
                dir.path(),
                &format!("{name}.xml"),
                &sphere_of(&medium, 1.0, "volpath"),
                16384,
            );
            for y in 0..16 {
                for x in 0..16 {
                    let got = pixels[y * 16 + x];
                    for c in 0..3 {
                        let want = absorbed(x, y, sigma[c]);
                        assert!(
                            (got[c] - want).abs() <= tolerance,
                            "{name}: pixel ({x}, {y}) channel {c}: {} vs exp(-σ chord) {want}",
                            got[c]
                        );
                    }
                }
            }
        }
    }
}

/// A white furnace: a sphere of medium that scatters but never absorbs
/// (albedo 1, forward-scattering Henyey–Greenstein or isotropic) under a
/// uniform sky of radiance 0.7 is invisible, with unlimited depth, with
/// and without light samples from the medium. Grey
/// media: every pixel 0.7 within 5 % at 1024 samples (measured: within
/// 4 %), the image's mean within 0.5 %. A chromatic medium (extinctions
/// 1.5, 3 and 0.5), whose spectral-MIS weights have heavy tails: each
/// channel's mean within 1.5 %.
#[test]
fn a_non_absorbing_medium_under_a_uniform_sky_is_invisible() {
    let dir = tempfile::tempdir().unwrap();
    for (name, sigma_t, phase) in [
        ("isotropic", "2", r#"<phase type="isotropic"/>"#),
        (
            "hg",
            "2",
            r#"<phase type="hg"><float name="g" value="0.6"/></phase>"#,
        ),
        // Mitsuba's `sample_emitters` off: the sky is found by phase
        // sampling alone, in full.
        (
            "unlit",
            "2",
            r#"<boolean name="sample_emitters" value="false"/>"#,
        ),
        (
            "chromatic",
            "1.5, 3, 0.5",
            r#"<phase type="hg"><float name="g" value="-0.3"/></phase>"#,
        ),
    ] {
        let medium = format!(
            r#"<medium type="homogeneous" id="m"><rgb name="sigma_t" value="{sigma_t}"/><float name="albedo" value="1"/>{phase}</medium>"#
        );
        let pixels = render(
            dir.path(),
            &format!("{name}.xml"),
            &sphere_of(&medium, 0.7, "volpath"),
            1024,
        );
        let grey = name != "chromatic";
        for c in 0..3 {
            let mean: f32 = pixels.iter().map(|p| p[c]).sum::<f32>() / 256.0;
            let tolerance = if grey { 0.005 } else { 0.015 };
            assert!(
                (mean - 0.7).abs() < tolerance * 0.7,
                "{name}: channel {c}'s mean {mean}"
            );
        }
        if grey {
            for (i, p) in pixels.iter().enumerate() {
                assert!((p[0] - 0.7).abs() < 0.05 * 0.7, "{name}: pixel {i}: {p:?}");
            }
        }
    }
}

/// A heterogeneous medium whose fields are constant (a `gridvolume` of
/// equal samples, a constant albedo) renders as its homogeneous twin, in a
/// sphere lit by the sky and seen at its scattering's full depth: the two
/// images' means agree within 1 % per channel and each 4 × 4 block of
/// pixels within 3 % (measured noise: about 1 %).
#[test]
fn a_constant_grid_renders_as_a_homogeneous_medium() {
    let dir = tempfile::tempdir().unwrap();
    // A 2×2×2 grid of one channel, all 0.8 (× scale 2.5 = 2).
    std::fs::write(dir.path().join("flat.vol"), common::constant_vol(0.8)).unwrap();
    let homogeneous = r#"<medium type="homogeneous" id="m"><float name="sigma_t" value="2"/><rgb name="albedo" value="0.9, 0.6, 0.3"/></medium>"#;
    let grid = r#"<medium type="heterogeneous" id="m">
        <float name="scale" value="2.5"/>
        <volume type="gridvolume" name="sigma_t">
            <string name="filename" value="flat.vol"/>
            <transform name="to_world"><scale value="2"/><translate value="-1, -1, -1"/></transform>
        </volume>
        <rgb name="albedo" value="0.9, 0.6, 0.3"/></medium>"#;
    let a = render(
        dir.path(),
        "homogeneous.xml",
        &sphere_of(homogeneous, 1.0, "volpath"),
        2048,
    );
    let b = render(
        dir.path(),
        "grid.xml",
        &sphere_of(grid, 1.0, "volpath"),
        2048,
    );
    for c in 0..3 {
        let (ma, mb): (f32, f32) = (
            a.iter().map(|p| p[c]).sum::<f32>() / 256.0,
            b.iter().map(|p| p[c]).sum::<f32>() / 256.0,
        );
        assert!((ma - mb).abs() < 0.01 * ma, "channel {c}: {ma} vs {mb}");
    }
    let block = |img: &[[f32; 3]], bx: usize, by: usize, c: usize| -> f32 {
        let mut sum = 0.0;
        for y in 0..4 {
            for x in 0..4 {
                sum += img[(by * 4 + y) * 16 + bx * 4 + x][c];
            }
        }
        sum / 16.0
    };
    for by in 0..4 {
        for bx in 0..4 {
            for c in 0..3 {
                let (p, q) = (block(&a, bx, by, c), block(&b, bx, by, c));
                assert!(
                    (p - q).abs() < 0.03 * p,
                    "block ({bx}, {by}) channel {c}: {p} vs {q}"
                );
            }
        }
    }
    // The medium matters: without it the sphere would show the sky (1).
    assert!(a[8 * 16 + 8][2] < 0.8, "{:?}", a[8 * 16 + 8]);
}

/// Mitsuba's `path` ignores media (a `null` surface is then nothing): the
/// sky shows unchanged through the sphere, with a warning, as in Mitsuba.
#[test]
fn only_volpath_sees_media() {
    let dir = tempfile::tempdir().unwrap();
    let medium = r#"<medium type="homogeneous" id="m"><float name="sigma_t" value="3"/><float name="albedo" value="0"/></medium>"#;
    let path = dir.path().join("path.xml");
    std::fs::write(&path, sphere_of(medium, 1.0, "path")).unwrap();
    let loaded = raylab::load::load(path.to_str().unwrap(), &Default::default()).unwrap();
    assert!(!loaded.scene.has_media());
    assert!(
        loaded
            .warnings
            .iter()
            .any(|w| w.contains("media are ignored")),
        "{:?}",
        loaded.warnings
    );
    let pixels = render(dir.path(), "path2.xml", &sphere_of(medium, 1.0, "path"), 4);
    assert!(
        pixels
            .iter()
            .all(|p| p.iter().all(|&v| (v - 1.0).abs() < 1e-5)),
        "{pixels:?}"
    );
}

/// Media: bad coefficients, phase functions and volumes, each one line
/// naming the file, the line and the object.
#[test]
fn bad_media_are_refused_with_one_line() {
    let cases = [
        (
            r#"<medium type="homogeneous" id="m"><float name="albedo" value="1.5"/></medium>
<shape type="sphere"><ref name="interior" id="m"/></shape>"#,
            "medium 'homogeneous' (id 'm') parameter 'albedo': must lie in [0, 1]",
        ),
        (
            r#"<medium type="homogeneous" id="m"><rgb name="sigma_t" value="-1, 0, 0"/></medium>
<shape type="sphere"><ref name="interior" id="m"/></shape>"#,
            "parameter 'sigma_t': must be finite and >= 0",
        ),
        (
            r#"<medium type="homogeneous" id="m"><phase type="rayleigh"/></medium>
<shape type="sphere"><ref name="interior" id="m"/></shape>"#,
            "the phase function 'rayleigh' is not supported (isotropic and hg are)",
        ),
        (
            r#"<medium type="homogeneous" id="m"><phase type="hg"><float name="g" value="1"/></phase></medium>
<shape type="sphere"><ref name="interior" id="m"/></shape>"#,
            "parameter 'g': must lie in [-0.999, 0.999]",
        ),
        (
            r#"<medium type="fog" id="m"/>
<shape type="sphere"><ref name="interior" id="m"/></shape>"#,
            "the medium 'fog' is not supported (homogeneous is)",
        ),
        (
            r#"<medium type="heterogeneous" id="m"><volume type="gridvolume" name="sigma_t"><string name="filename" value="missing.vol"/></volume></medium>
<shape type="sphere"><ref name="interior" id="m"/></shape>"#,
            "cannot find 'missing.vol'",
        ),
        (
            r#"<medium type="heterogeneous" id="m"><volume type="perlin" name="sigma_t"/></medium>
<shape type="sphere"><ref name="interior" id="m"/></shape>"#,
            "the volume 'perlin' is not supported (gridvolume and constvolume are)",
        ),
        (
            r#"<medium type="homogeneous" id="m"><float name="density" value="1"/></medium>
<shape type="sphere"><ref name="interior" id="m"/></shape>"#,
            "unused parameter 'density'",
        ),
        (
            r#"<bsdf type="diffuse" id="b"/>
<shape type="sphere"><ref name="interior" id="b"/></shape>"#,
            "its interior must be a medium",
        ),
        (r#"<phase type="isotropic"/>"#, "belongs inside a medium"),
    ];
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("bad.xml");
    for (body, want) in cases {
        let xml =
            format!("<scene version=\"3.0.0\">\n<integrator type=\"volpath\"/>\n{body}\n</scene>");
        std::fs::write(&path, xml).unwrap();
        let e = match raylab::load::load(path.to_str().unwrap(), &Default::default()) {
            Ok(_) => panic!("no error for {body}"),
            Err(e) => e.to_string(),
        };
        assert!(
            e.contains("bad.xml:") && e.contains(want) && !e.contains('\n'),
            "{e} (wanted {want})"
        );
    }
}

/// `--fog`: fog filling the scene's bounding box (here the unit sphere's,
/// [−1, 1]³, the sphere itself an empty `null` surface) with the camera
/// outside it. Albedo 0: every ray through the box's face crosses 2 units
/// of it, so those pixels are `exp(−2σ)` exactly in expectation (within
/// 0.03, four standard errors of 4096 samples of a path that passes or
/// not) and the others the sky. Albedo 1: a white furnace,
/// every pixel the sky's 0.7 (the image's mean within 0.5 %).
#[test]
fn fog_fills_the_scene_bounds() {
    let dir = tempfile::tempdir().unwrap();
    let xml = sphere_of("", 1.0, "path").replace("<ref name=\"interior\" id=\"m\"/>", "");
    let path = dir.path().join("fog.xml");
    std::fs::write(&path, &xml).unwrap();
    let sigma = 0.6f32;
    let mut options = JobOptions::new(path.to_str().unwrap());
    options.spp = Some(4096);
    options.scene.fog = Some((sigma, glam::Vec3A::ZERO));
    let pixels = common::job_pixels(options);
    for y in 0..16 {
        for x in 0..16 {
            // Pixel (x, y) spans [−1.25 + 0.15625 x, …] in x and y: inside
            // the box's face when it spans [−1, 1] wholly.
            let inside = (2..14).contains(&x) && (2..14).contains(&y);
            let outside = x == 0 || x == 15 || y == 0 || y == 15;
            let p = pixels[y * 16 + x];
            if inside {
                let want = (-2.0 * sigma).exp();
                assert!((p[0] - want).abs() < 0.03, "({x}, {y}): {p:?} vs {want}");
            } else if outside {
                assert_eq!(p, [1.0; 3], "({x}, {y})");
            }
        }
    }
    std::fs::write(
        &path,
        xml.replace("value=\"1\"/></emitter>", "value=\"0.7\"/></emitter>"),
    )
    .unwrap();
    let mut options = JobOptions::new(path.to_str().unwrap());
    options.spp = Some(1024);
    options.scene.fog = Some((1.5, glam::Vec3A::ONE));
    let pixels = common::job_pixels(options);
    let mean: f32 = pixels.iter().map(|p| p[0]).sum::<f32>() / 256.0;
    assert!((mean - 0.7).abs() < 0.005 * 0.7, "furnace mean {mean}");
    // Bad values are one line.
    let options = raylab::load::LoadOptions {
        fog: Some((-1.0, glam::Vec3A::ONE)),
        ..Default::default()
    };
    let e = raylab::load::load(path.to_str().unwrap(), &options)
        .err()
        .map(|e| e.to_string());
    assert!(
        e.as_deref()
            .is_some_and(|e| e.contains("--fog") && !e.contains('\n')),
        "{e:?}"
    );
}

/// A scene file of one glTF cube ([−1, 1]³, made invisible: `glass:1.0`,
/// an index-matched boundary) under a uniform sky of radiance 1, seen from
/// +z by a 16 × 16 camera, with `extra` sections.
fn cube_scene(dir: &Path, extra: &str) -> std::path::PathBuf {
    use builder::Gltf;
    use serde_json::json;
    let mut g = Gltf::new();
    let m = g.material(json!({ "pbrMetallicRoughness": { "metallicFactor": 0 } }));
    let cube = builder::cuboid(&mut g, [-1.0; 3], [1.0; 3], m);
    let mesh = g.mesh(vec![cube]);
    g.root(json!({ "mesh": mesh }));
    g.write(dir, "cube.gltf");
    let path = dir.join("cube.toml");
    std::fs::write(
        &path,
        format!(
            "[render]\nwidth = 16\nheight = 16\n\n[environment]\ncolor = [1, 1, 1]\n\n\
             [camera]\nposition = [0, 0, 6]\ntarget = [0, 0, 0]\nfov = 30\n\n\
             [[model]]\nname = \"cube\"\nfile = \"cube.gltf\"\nmaterials = {{ \"*\" = \"glass:1.0\" }}\n\n{extra}"
        ),
    )
    .unwrap();
    path
}

/// `[[medium]]` in scene files: fog is `--fog` (the same image, bit for
/// bit), and an absorbing medium inside a model transmits `exp(−σ·2)`
/// straight through the cube (the mean of 20,000 paths within 4 standard
/// errors); bad sections are one line naming the file.
#[test]
fn scene_file_media_are_fog_and_media_inside_models() {
    let dir = tempfile::tempdir().unwrap();
    let sigma = 0.6f32;
    let fog = cube_scene(
        dir.path(),
        &format!("[[medium]]\ntype = \"fog\"\ndensity = {sigma}\ncolor = [0, 0, 0]\n"),
    );
    let mut options = JobOptions::new(fog.to_str().unwrap());
    options.spp = Some(16);
    let from_file = common::job_pixels(options);
    let plain = cube_scene(dir.path(), "");
    let mut options = JobOptions::new(plain.to_str().unwrap());
    options.spp = Some(16);
    options.scene.fog = Some((sigma, glam::Vec3A::ZERO));
    let from_option = common::job_pixels(options);
    assert_eq!(from_file, from_option, "[[medium]] fog is --fog");
    assert!(from_file.iter().any(|p| p[0] < 0.9), "the fog shows");

    let inside = cube_scene(
        dir.path(),
        &format!(
            "[[medium]]\ntype = \"inside\"\nmodel = \"cube\"\ndensity = [{sigma}, {sigma}, {}]\ncolor = [0, 0, 0]\n",
            2.0 * sigma
        ),
    );
    let loaded = raylab::load::load(inside.to_str().unwrap(), &Default::default()).unwrap();
    let opts = raylab::integrators::path::PathOptions::default();
    let n = 20_000u64;
    let mut sum = glam::DVec3::ZERO;
    let mut rays = 0;
    for i in 0..n {
        let (x, y) = (
            (i % 101) as f32 / 101.0 - 0.5,
            (i / 101 % 97) as f32 / 97.0 - 0.5,
        );
        let ray = raylab::Ray::new(glam::Vec3A::new(x, y, 5.0), glam::Vec3A::NEG_Z);
        let mut rng = raylab::sampling::sampler::Rng::new(i, 3);
        let l =
            raylab::integrators::path::radiance(&loaded.scene, &ray, &opts, &mut rng, &mut rays);
        sum += glam::DVec3::new(l.x.into(), l.y.into(), l.z.into());
    }
    let mean = sum / n as f64;
    eprintln!(
        "through the cube: {mean} (exp(-2 sigma): {}, {})",
        (-1.2f64).exp(),
        (-2.4f64).exp()
    );
    for (c, s) in [(0, sigma), (2, 2.0 * sigma)] {
        let p = (-2.0 * f64::from(s)).exp();
        // A path passes with probability p (weight 1 each for a grey
        // medium; a chromatic one weighs by the mean of the channels').
        let se = (p * (1.0 - p) / n as f64).sqrt() * 3.0;
        assert!(
            (mean[c] - p).abs() < 4.0 * se,
            "channel {c}: {} vs exp(-2 sigma) {p}",
            mean[c]
        );
    }

    for (extra, says) in [
        (
            "[[medium]]\ntype = \"inside\"\nmodel = \"teapot\"\ndensity = 1\n",
            "no [[model]] of that name",
        ),
        (
            "[[medium]]\ntype = \"fog\"\ndensity = 1\n\n[[medium]]\ntype = \"fog\"\ndensity = 2\n",
            "a second fog",
        ),
        (
            "[[medium]]\ntype = \"fog\"\ndensity = 1\ncolor = [2, 0, 0]\n",
            "albedo from 0 to 1",
        ),
        ("[[medium]]\ntype = \"fog\"\ndensity = -1\n", "density"),
        ("[[medium]]\ntype = \"smoke\"\ndensity = 1\n", "smoke"),
    ] {
        let err = common::load_error(&cube_scene(dir.path(), extra));
        assert!(err.contains(says), "{extra}: {err}");
    }
}

/// Radiance along `n` rays down −z through `(x, y)` points of a 101 × 97
/// lattice over `[−w, w]²` (or one point if `w` is 0), one path each: the
/// mean, and the per-channel standard error of the mean.
fn mean_down_z(
    scene: &raylab::Scene,
    centre: glam::Vec3A,
    w: f32,
    n: u64,
) -> (glam::DVec3, glam::DVec3) {
    let opts = raylab::integrators::path::PathOptions::default();
    let (mut sum, mut sq) = (glam::DVec3::ZERO, glam::DVec3::ZERO);
    let mut rays = 0;
    for i in 0..n {
        let (x, y) = (
            ((i % 101) as f32 / 100.0 * 2.0 - 1.0) * w,
            ((i / 101 % 97) as f32 / 96.0 * 2.0 - 1.0) * w,
        );
        let ray = raylab::Ray::new(centre + glam::Vec3A::new(x, y, 50.0), glam::Vec3A::NEG_Z);
        let mut rng = raylab::sampling::sampler::Rng::new(i, 5);
        let l = raylab::integrators::path::radiance(scene, &ray, &opts, &mut rng, &mut rays);
        let l = glam::DVec3::new(l.x.into(), l.y.into(), l.z.into());
        sum += l;
        sq += l * l;
    }
    let mean = sum / n as f64;
    let se = ((sq / n as f64 - mean * mean) / n as f64).map(f64::sqrt);
    (mean, se)
}

/// Emissive media (`emission` or `temperature` in `[[medium]]`): a purely
/// absorbing cube that glows, under a black sky, shows `Le (1 − e^{−2σ})`
/// straight through (exact on every path: a homogeneous medium's emission
/// is integrated in closed form), per channel of a chromatic medium, for
/// an RGB `Le` and for a blackbody at 3000 K times `emission_scale`; the
/// scene needs no other light (no default lighting is added).
#[test]
fn a_glowing_absorbing_cube_shows_le_times_its_opacity() {
    let dir = tempfile::tempdir().unwrap();
    let blackbody = raylab::materials::blackbody::blackbody_color(3000.0) * 2.5;
    for (glow, le) in [
        ("emission = [2, 1, 0.5]", glam::Vec3A::new(2.0, 1.0, 0.5)),
        ("temperature = 3000\nemission_scale = 2.5", blackbody),
    ] {
        let path = cube_scene(
            dir.path(),
            &format!(
                "[[medium]]\ntype = \"inside\"\nmodel = \"cube\"\ndensity = [0.3, 0.6, 1.2]\n\
                 color = [0, 0, 0]\n{glow}\n"
            ),
        );
        let text = std::fs::read_to_string(&path)
            .unwrap()
            .replace("color = [1, 1, 1]", "color = [0, 0, 0]");
        std::fs::write(&path, text).unwrap();
        let loaded = raylab::load::load(path.to_str().unwrap(), &Default::default()).unwrap();
        assert!(!loaded.default_light, "a glowing medium is a light");
        let (mean, _) = mean_down_z(&loaded.scene, glam::Vec3A::ZERO, 0.5, 2000);
        for (c, sigma) in [0.3f64, 0.6, 1.2].into_iter().enumerate() {
            let want = f64::from(le[c]) * (1.0 - (-2.0 * sigma).exp());
            assert!(
                want > 0.0 && (mean[c] - want).abs() < 1e-4 * want,
                "{glow}: channel {c}: {} vs Le (1 - exp(-2 sigma)) {want}",
                mean[c]
            );
        }
    }
    let err = common::load_error(&cube_scene(
        dir.path(),
        "[[medium]]\ntype = \"inside\"\nmodel = \"cube\"\ndensity = 1\ncolor = [0, 0, 0]\n\
         temperature = 2000\nemission = [1, 1, 1]\n",
    ));
    assert!(err.contains("both"), "{err}");
}

/// A `.vdb` that glows by its temperature grid (`temperature = "…"`,
/// OpenVDB's own file with a `density` and a `temperature` grid): a purely
/// absorbing volume under a black sky, seen along rays through it, shows
/// `∫ T σa Le dt` with `Le` the blackbody at `(T − offset) · scale`, by
/// quadrature over the grids as raylab reads them, within four standard
/// errors (and 0.5 % for the quadrature); bad glow settings are one line
/// naming the file.
#[test]
fn a_vdb_glows_by_its_temperature_grid() {
    use raylab::media::{Emission, Field};
    let dir = tempfile::tempdir().unwrap();
    let vdb = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/vdb/two-grids.vdb");
    std::fs::copy(&vdb, dir.path().join("two-grids.vdb")).unwrap();
    let glow = "temperature = \"temperature\"\ntemperature_offset = 50\n\
                temperature_scale = 8\nemission_scale = 3";
    let scene = |extra: &str| {
        let path = dir.path().join("glow.toml");
        std::fs::write(
            &path,
            format!(
                "[environment]\ncolor = [0, 0, 0]\n\n[[medium]]\ntype = \"vdb\"\n\
                 file = \"two-grids.vdb\"\ngrid = \"density\"\ndensity = 0.6\n{extra}\n"
            ),
        )
        .unwrap();
        path
    };
    let path = scene(&format!("color = [0, 0, 0]\n{glow}"));
    let loaded = raylab::load::load(path.to_str().unwrap(), &Default::default()).unwrap();
    assert!(!loaded.default_light);
    // The same fields, from the file as raylab reads it.
    let ledger = raylab::memory::Ledger::unlimited();
    let read = |name| raylab::load::vdb::read_vdb(&vdb, Some(name), &ledger).unwrap();
    let (d, t) = (read("density"), read("temperature"));
    let density = Field::sparse(d.grid, d.index_to_world);
    let le = Emission::Temperature {
        temperature: Field::sparse(t.grid, t.index_to_world),
        offset: 50.0,
        t_scale: 8.0,
        scale: 3.0,
    };
    let (lo, hi) = density.bounds;
    let centre = (lo + hi) * 0.5;
    for (k, (dx, dy)) in [(0.0f32, 0.0f32), (0.1, -0.05), (0.05, 0.1)]
        .into_iter()
        .enumerate()
    {
        let o = centre + (hi - lo) * glam::Vec3A::new(dx, dy, 0.0);
        // Quadrature down −z from above the box.
        let steps = 20_000;
        let (z0, z1) = (hi.z + 1.0, lo.z - 1.0);
        let dt = f64::from(z0 - z1) / f64::from(steps);
        let (mut depth, mut want) = (0.0f64, glam::DVec3::ZERO);
        for i in 0..steps {
            let z = z0 - (i as f32 + 0.5) * (z0 - z1) / steps as f32;
            let p = glam::Vec3A::new(o.x, o.y, z);
            if !(p.cmpge(lo).all() && p.cmple(hi).all()) {
                continue;
            }
            let sigma = 0.6 * f64::from(density.eval(p).x);
            let l = le.eval(p).as_dvec3();
            want += (-(depth + 0.5 * sigma * dt)).exp() * sigma * l * dt;
            depth += sigma * dt;
        }
        let (mean, se) = mean_down_z(&loaded.scene, glam::Vec3A::new(o.x, o.y, 0.0), 0.0, 40_000);
        eprintln!("ray {k}: {mean} vs quadrature {want} (standard errors {se})");
        assert!(want.x > 0.01, "ray {k} crosses the glow: {want}");
        for c in 0..3 {
            assert!(
                (mean[c] - want[c]).abs() <= 4.0 * se[c] + 5e-3 * want[c],
                "ray {k} channel {c}: {mean} vs quadrature {want} (standard errors {se})"
            );
        }
    }

    for (extra, says) in [
        (glow.to_string(), "needs absorption"),
        (
            format!("color = [0, 0, 0]\nemission = [1, 1, 1]\n{glow}"),
            "emission and temperature both",
        ),
        ("color = [0, 0, 0]\ntemperature = \"heat\"".into(), "heat"),
        (
            "color = [0, 0, 0]\ntemperature_scale = 2".into(),
            "without temperature",
        ),
        (
            "color = [0, 0, 0]\nemission = [1, -1, 1]".into(),
            "emission",
        ),
    ] {
        let err = common::load_error(&scene(&extra));
        assert!(err.contains(says), "{extra}: {err}");
    }
}

/// The denoiser's albedo guide sees media inside models (Cycles' approach,
/// in expectation): through a `null` sphere of scattering medium (albedo
/// `a`, extinction 1.2) in front of a constant sky `L`, a pixel's guide is
/// `(1 − T) a + T L/(1 + L)` with `T` the chord's transmittance (the mean
/// over the pixel, [`absorbed`]), within 0.02 on pixels wholly inside the
/// sphere's disc (the guides average a pixel's first 8 samples; the
/// quadrature its whole footprint); for a homogeneous and a heterogeneous
/// (constant grid) medium alike.
#[test]
fn media_inside_models_show_in_the_albedo_guide() {
    let dir = tempfile::tempdir().unwrap();
    let (sigma, a, sky) = (1.2f32, [0.9f32, 0.6, 0.3], 0.5f32);
    let albedo = format!(
        r#"<rgb name="albedo" value="{}, {}, {}"/>"#,
        a[0], a[1], a[2]
    );
    for (name, medium) in [
        (
            "homogeneous",
            format!(
                r#"<medium type="homogeneous" id="m"><float name="sigma_t" value="{sigma}"/>{albedo}</medium>"#
            ),
        ),
        (
            "heterogeneous",
            constant_grid(
                &format!(r#"<float name="value" value="{sigma}"/>"#),
                &albedo,
            ),
        ),
    ] {
        let path = dir.path().join(format!("{name}.xml"));
        std::fs::write(&path, sphere_of(&medium, sky, "volpath")).unwrap();
        let mut options = JobOptions::new(path.to_str().unwrap());
        options.spp = Some(8);
        options.aov = Some("albedo".parse().unwrap());
        let aovs = raylab::job::Job::new(options)
            .unwrap()
            .render_with(&raylab::job::Hooks::default())
            .unwrap()
            .finished
            .aovs
            .expect("the albedo asked for");
        let behind = sky / (1.0 + sky);
        let mut checked = 0;
        for y in 0..16 {
            for x in 0..16 {
                // The pixel's farthest corner from the centre.
                let corner = |i: usize| (2.5 * ((i as f32 - 7.5).abs() + 0.5) / 16.0).powi(2);
                if corner(x) + corner(y) > 0.95 * 0.95 {
                    continue;
                }
                let got = aovs
                    .get(raylab::aov::Aov::Albedo, x as u32, y as u32)
                    .unwrap();
                let t = absorbed(x, y, sigma);
                for c in 0..3 {
                    let want = (1.0 - t) * a[c] + t * behind;
                    assert!(
                        (got[c] - want).abs() <= 0.02,
                        "{name}: pixel ({x}, {y}) channel {c}: albedo guide {} vs {want} (T {t})",
                        got[c]
                    );
                }
                checked += 1;
            }
        }
        assert!(checked > 80, "{checked} pixels inside the disc");
    }
}
