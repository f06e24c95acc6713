//! Mitsuba 3 scenes rendered: the plugins' definitions checked against
//! numbers worked out by hand (a Lambertian plane under a sun, a flat
//! emission spectrum's RGB, a one-sided plane from behind, a `twosided` one,
//! the fields of view), the file's settings taken as defaults, and bad files
//! refused with their file and line. Mitsuba's own statistical test against
//! Mitsuba's images is `tools/mitsuba_suite.py` (CI runs it on
//! `tests/data/mitsuba/suite`).

use std::path::Path;

use glam::Vec3A;
use raylab::job::{Hooks, Job, JobOptions};

/// Writes `xml` as `name` in `dir` and renders it with `spp` samples.
fn render(dir: &Path, name: &str, xml: &str, spp: u32) -> raylab::film::Film {
    let path = dir.join(name);
    std::fs::write(&path, xml).unwrap();
    let mut options = JobOptions::new(path.to_str().unwrap());
    options.spp = Some(spp);
    let mut job = Job::new(options).unwrap();
    job.render_with(&Hooks::default()).unwrap().finished.image
}

/// A scene of a camera looking straight down at the unit rectangle from
/// above (orthographic, the view inside the rectangle), with `body` added.
fn from_above(integrator: &str, body: &str) -> String {
    format!(
        r#"<scene version="3.0.0">
    <integrator type="{integrator}"/>
    <sensor type="orthographic">
        <transform name="to_world">
            <scale x="0.5" y="0.5"/>
            <lookat origin="0, 0, 2" target="0, 0, 0" up="0, 1, 0"/>
        </transform>
        <film type="hdrfilm">
            <integer name="width" value="8"/>
            <integer name="height" value="8"/>
            <rfilter type="box"/>
        </film>
    </sensor>
    {body}
</scene>"#
    )
}

fn assert_close(got: Vec3A, want: Vec3A, tol: f32, what: &str) {
    assert!(
        (got - want).abs().max_element() <= tol * want.abs().max_element().max(1e-6),
        "{what}: got {got}, want {want}"
    );
}

/// Lambert: a plane of reflectance ρ under a sun of irradiance E straight
/// above shows ρE/π at every pixel, every sample (direct light only).
#[test]
fn a_lambertian_plane_under_the_sun_shows_rho_e_over_pi() {
    let dir = tempfile::tempdir().unwrap();
    let xml = from_above(
        "direct",
        r#"<emitter type="directional">
        <vector name="direction" value="0, 0, -1"/>
        <rgb name="irradiance" value="2, 3, 4"/>
    </emitter>
    <shape type="rectangle">
        <bsdf type="diffuse"><rgb name="reflectance" value="0.5, 0.25, 0.8"/></bsdf>
    </shape>"#,
    );
    let film = render(dir.path(), "sun.xml", &xml, 4);
    let want = Vec3A::new(0.5 * 2.0, 0.25 * 3.0, 0.8 * 4.0) / std::f32::consts::PI;
    for (x, y) in [(0, 0), (3, 4), (7, 7)] {
        assert_close(film.get(x, y), want, 1e-5, "ρE/π");
    }
}

/// Mitsuba's RGB variants turn a flat emission spectrum `v` into
/// `v · xyz_to_srgb(1, 1, 1)`; an `<rgb>` stays as written. Seen directly
/// (a path of one segment), the sky is that colour.
#[test]
fn a_flat_emission_spectrum_has_mitsubas_tint_and_rgb_does_not() {
    let dir = tempfile::tempdir().unwrap();
    let sky = |value: &str| {
        format!(
            r#"<scene version="3.0.0">
    <integrator type="path"><integer name="max_depth" value="1"/></integrator>
    <sensor type="perspective"><float name="fov" value="30"/>
        <film type="hdrfilm"><integer name="width" value="4"/><integer name="height" value="4"/>
            <rfilter type="box"/></film>
    </sensor>
    <emitter type="constant">{value}</emitter>
</scene>"#
        )
    };
    let spectrum = render(
        dir.path(),
        "a.xml",
        &sky(r#"<spectrum name="radiance" value="2"/>"#),
        2,
    );
    assert_close(
        spectrum.get(1, 1),
        Vec3A::new(1.204_794, 0.948_291, 0.908_916) * 2.0,
        1e-5,
        "spectrum",
    );
    let rgb = render(
        dir.path(),
        "b.xml",
        &sky(r#"<rgb name="radiance" value="2"/>"#),
        2,
    );
    assert_close(rgb.get(2, 3), Vec3A::splat(2.0), 1e-6, "rgb");
}

/// Mitsuba's BSDFs are one-sided: a plane seen from behind is black, even
/// lit from behind; `twosided` reflects there as on its front.
#[test]
fn one_sided_planes_are_black_from_behind_and_twosided_ones_are_not() {
    let dir = tempfile::tempdir().unwrap();
    let scene = |bsdf: &str| {
        from_above(
            "direct",
            &format!(
                r#"<emitter type="directional">
        <vector name="direction" value="0, 0, -1"/>
        <rgb name="irradiance" value="1"/>
    </emitter>
    <shape type="rectangle">
        <boolean name="flip_normals" value="true"/>
        {bsdf}
    </shape>"#
            ),
        )
    };
    let one = render(
        dir.path(),
        "one.xml",
        &scene(r#"<bsdf type="diffuse"/>"#),
        4,
    );
    assert_eq!(one.get(4, 4), Vec3A::ZERO);
    let two = render(
        dir.path(),
        "two.xml",
        &scene(r#"<bsdf type="twosided"><bsdf type="diffuse"/></bsdf>"#),
        4,
    );
    assert_close(
        two.get(4, 4),
        Vec3A::splat(0.5 / std::f32::consts::PI),
        1e-5,
        "twosided",
    );
}

/// The film, sampler, integrator and filter of the file are the render's
/// defaults; `-D` fills a `$name`; the fields of view follow Mitsuba's
/// `fov_axis` and `focal_length` rules.
#[test]
fn the_files_settings_and_fields_of_view() {
    use raylab::camera::Lens;
    let dir = tempfile::tempdir().unwrap();
    let camera = |fov: &str, w: u32, h: u32| {
        format!(
            r#"<scene version="3.0.0">
    <default name="spp" value="3"/>
    <integrator type="path"><integer name="max_depth" value="4"/></integrator>
    <sensor type="perspective">{fov}
        <film type="hdrfilm"><integer name="width" value="{w}"/><integer name="height" value="{h}"/>
            <rfilter type="tent"/></film>
        <sampler type="independent"><integer name="sample_count" value="$spp"/></sampler>
    </sensor>
</scene>"#
        )
    };
    let focal = |xml: String, name: &str, defines: &[(String, String)]| {
        let path = dir.path().join(name);
        std::fs::write(&path, xml).unwrap();
        let settings = raylab::load::mitsuba::read_settings(&path, defines).unwrap();
        let options = raylab::load::LoadOptions {
            defines: defines.to_vec(),
            ..Default::default()
        };
        let loaded = raylab::load::load(path.to_str().unwrap(), &options).unwrap();
        let Lens::Perspective { focal_scale } = loaded.view.lens else {
            panic!("not a perspective lens");
        };
        (settings, focal_scale)
    };
    let t = |deg: f32| (deg.to_radians() / 2.0).tan();
    // fov 60 along x of a 200 × 100 film: tan(yfov/2) = tan(30°)/2.
    let (s, f) = focal(
        camera(r#"<float name="fov" value="60"/>"#, 200, 100),
        "x.xml",
        &[],
    );
    assert!((f - 0.5 / (t(60.0) / 2.0)).abs() < 1e-5, "{f}");
    assert_eq!(
        (s.width, s.height, s.spp, s.max_depth),
        (Some(200), Some(100), Some(3), Some(4))
    );
    assert_eq!(
        s.filter,
        Some(raylab::sampling::filter::PixelFilter::tent(1.0))
    );
    // Along y: the focal length is the field's own.
    let (s, f) = focal(
        camera(
            r#"<float name="fov" value="40"/><string name="fov_axis" value="y"/>"#,
            100,
            50,
        ),
        "y.xml",
        &[("spp".into(), "9".into())],
    );
    assert!((f - 0.5 / t(40.0)).abs() < 1e-5, "{f}");
    assert_eq!(s.spp, Some(9));
    // 50 mm: a diagonal field of 2·atan(√(36² + 24²)/100) on a square film.
    let (_, f) = focal(camera("", 64, 64), "f.xml", &[]);
    let diagonal = 2.0 * ((36.0f32 * 36.0 + 24.0 * 24.0).sqrt() / 100.0).atan();
    let tan_y = (diagonal / 2.0).tan() / 2.0f32.sqrt();
    assert!((f - 0.5 / tan_y).abs() < 1e-4, "{f}");
}

/// A bad file is one line naming the file and the line: an unknown
/// parameter (Mitsuba's rule), a plugin raylab does not read, a missing mesh.
#[test]
fn bad_scenes_name_the_file_and_line() {
    let dir = tempfile::tempdir().unwrap();
    let cases = [
        (
            "unused.xml",
            "<scene version=\"3.0.0\">\n<shape type=\"rectangle\">\n<bsdf type=\"diffuse\">\n<float name=\"roughness\" value=\"1\"/>\n</bsdf></shape></scene>",
            ":4:",
            "unused parameter 'roughness'",
        ),
        (
            "plugin.xml",
            "<scene version=\"3.0.0\">\n<shape type=\"rectangle\">\n<bsdf type=\"hair\"/></shape></scene>",
            ":3:",
            "the BSDF 'hair' is not supported",
        ),
        (
            "mesh.xml",
            "<scene version=\"3.0.0\">\n<shape type=\"obj\">\n<string name=\"filename\" value=\"nowhere.obj\"/>\n</shape></scene>",
            ":2:",
            "cannot find 'nowhere.obj'",
        ),
    ];
    for (name, xml, line, message) in cases {
        let path = dir.path().join(name);
        std::fs::write(&path, xml).unwrap();
        let e = raylab::load::load(path.to_str().unwrap(), &Default::default())
            .unwrap_err()
            .to_string();
        assert!(
            e.contains(name) && e.contains(line) && e.contains(message) && !e.contains('\n'),
            "{name}: {e}"
        );
    }
}

/// A Mitsuba scene is a model of a scene file like a glTF one: its shapes,
/// materials, lights and camera come in, and its one-sided materials stay
/// one-sided in a two-sided scene.
#[test]
fn a_scene_file_places_a_mitsuba_scene() {
    let dir = tempfile::tempdir().unwrap();
    let xml = from_above(
        "direct",
        r#"<emitter type="directional">
        <vector name="direction" value="0, 0, -1"/>
        <rgb name="irradiance" value="2"/>
    </emitter>
    <shape type="rectangle">
        <bsdf type="diffuse"><rgb name="reflectance" value="0.5"/></bsdf>
    </shape>
    <shape type="rectangle">
        <boolean name="flip_normals" value="true"/>
        <transform name="to_world"><translate x="10"/></transform>
        <bsdf type="diffuse"/>
    </shape>"#,
    );
    std::fs::write(dir.path().join("sun.xml"), xml).unwrap();
    let toml = dir.path().join("s.toml");
    std::fs::write(
        &toml,
        "[render]\nwidth = 8\nheight = 8\nspp = 2\n[[model]]\nfile = \"sun.xml\"\n",
    )
    .unwrap();
    let options = JobOptions::new(toml.to_str().unwrap());
    let mut job = Job::new(options).unwrap();
    let film = job.render_with(&Hooks::default()).unwrap().finished.image;
    // Through the Mitsuba camera (the first), the plane in full sun.
    assert_close(
        film.get(4, 4),
        Vec3A::splat(1.0 / std::f32::consts::PI),
        1e-5,
        "ρE/π",
    );
    // Its materials decide their sides: one-sided, even were the scene
    // two-sided (as glTF models make it).
    let mut loaded = raylab::load::load(toml.to_str().unwrap(), &Default::default()).unwrap();
    loaded.scene.two_sided = true;
    let materials = loaded.scene.materials().len() as u32;
    assert!(materials >= 2);
    assert!((0..materials).all(|m| !loaded.scene.material_turns(m)));
}
