//! Mitsuba 3's `thinlens` sensor, `hdrfilm` crop windows and the
//! integrators' `hide_emitters`, as Mitsuba 3.7.1 defines them: the thin
//! lens's rays checked against Mitsuba's formula (`thinlens.cpp`: a point of
//! a disk of `aperture_radius` in the sensor's plane, through the film
//! point's pinhole ray at `focus_distance` along the view axis), a crop
//! window's pixels against the whole film's, and what the camera sees of
//! hidden emitters in scenes whose every sample has the same value.
//! Mitsuba's own statistical test against its images is
//! `tools/mitsuba_suite.py` (`tests/data/mitsuba/suite/thinlens_crop_path.xml`,
//! `hidden_emitters_path.xml`).

use std::path::Path;

use glam::{Vec2, Vec3A};
use raylab::camera::{Aperture, Camera, FilmWindow, Focus};
use raylab::job::{Hooks, Job, JobOptions};

/// Writes `xml` as `name` in `dir`; its path.
fn write(dir: &Path, name: &str, xml: &str) -> String {
    let path = dir.join(name);
    std::fs::write(&path, xml).unwrap();
    path.to_str().unwrap().to_string()
}

/// Renders the scene at `path` with `spp` samples: its image and the
/// camera it was rendered through.
fn render(path: &str, spp: u32) -> (raylab::film::Film, Camera) {
    let mut options = JobOptions::new(path);
    options.spp = Some(spp);
    options.quiet = true;
    let mut job = Job::new(options).unwrap();
    let image = job.render_with(&Hooks::default()).unwrap().finished.image;
    let session = job.session().unwrap();
    let camera = session.view.camera(session.size.0, session.size.1);
    (image, camera)
}

/// Checks that `xml`, written as `name` in `dir`, is refused in one line
/// naming the file, its `line` (`":7:"`) and `message`.
fn refused(dir: &Path, name: &str, xml: &str, line: &str, message: &str) {
    let path = write(dir, name, xml);
    let e = raylab::load::load(&path, &Default::default())
        .unwrap_err()
        .to_string();
    assert!(
        !e.contains('\n') && e.contains(&format!("{name}{line}")) && e.contains(message),
        "{name}: {e}"
    );
}

/// A thin lens camera of a 96 × 64 film (`film` adds to the film), looking
/// from (1, −5, 2) at (0.2, 0, 0.5) with z up, over an empty scene
/// (`extra` adds to the sensor).
fn thin_lens_scene(extra: &str, film: &str) -> String {
    format!(
        r#"<scene version="3.0.0">
    <integrator type="path"/>
    <sensor type="thinlens">
        <float name="fov" value="35"/>
        <string name="fov_axis" value="y"/>
        {extra}
        <transform name="to_world">
            <lookat origin="1, -5, 2" target="0.2, 0, 0.5" up="0, 0, 1"/>
        </transform>
        <film type="hdrfilm">
            <integer name="width" value="96"/>
            <integer name="height" value="64"/>
            {film}
        </film>
    </sensor>
    <emitter type="constant"/>
</scene>"#
    )
}

/// Mitsuba's thin lens ray family for film point `(u, v)` (in [0, 1]², from
/// the film's top-left): the point the ray passes through in world space
/// (on the focus plane), the lens's centre and its axes. Written from
/// `thinlens.cpp` and `perspective_projection` (`sensor.h`): camera space
/// has +x to the image's left, +y up and +z along the view; the film point
/// is at `(tan_x (1 − 2u), tan_y (1 − 2v), 1)` on the plane z = 1, and
/// the ray from aperture point `a` goes through it scaled to z = F.
fn mitsuba_focus_point(u: f32, v: f32, focus: f32, aspect: f32) -> (Vec3A, [Vec3A; 4]) {
    let origin = Vec3A::new(1.0, -5.0, 2.0);
    let dir = (Vec3A::new(0.2, 0.0, 0.5) - origin).normalize();
    let left = Vec3A::Z.cross(dir).normalize();
    let up = dir.cross(left);
    let tan_y = (35f32.to_radians() / 2.0).tan();
    let tan_x = tan_y * aspect;
    let local = Vec3A::new(tan_x * (1.0 - 2.0 * u), tan_y * (1.0 - 2.0 * v), 1.0) * focus;
    let world = origin + left * local.x + up * local.y + dir * local.z;
    (world, [origin, left, up, dir])
}

/// The thin lens is Mitsuba's: every ray starts on the disk of
/// `aperture_radius` across the view at the sensor's position and passes
/// through the point Mitsuba's ray through the same film point reaches on
/// the focus plane, so points there are sharp (the rays of one image point
/// through different lens points meet there); the lens points spread over
/// the whole disk. A crop window keeps the film's rays.
#[test]
fn a_thin_lens_is_mitsubas_and_a_crop_window_keeps_the_films_rays() {
    let dir = tempfile::tempdir().unwrap();
    let lens = r#"<float name="aperture_radius" value="0.25"/>
        <float name="focus_distance" value="4.5"/>"#;
    let crop = r#"<integer name="crop_offset_x" value="40"/>
            <integer name="crop_offset_y" value="7"/>
            <integer name="crop_width" value="33"/>
            <integer name="crop_height" value="50"/>"#;
    for (name, film, offset) in [("whole.xml", "", [0, 0]), ("crop.xml", crop, [40, 7])] {
        let path = write(dir.path(), name, &thin_lens_scene(lens, film));
        let loaded = raylab::load::load(&path, &Default::default()).unwrap();
        let dof = loaded.view.depth_of_field;
        assert_eq!(dof.aperture, Some(Aperture::Radius(0.25)));
        assert_eq!(dof.focus, Some(Focus::Distance(4.5)));
        let (image, camera) = render(&path, 1);
        let size = if film.is_empty() { [96, 64] } else { [33, 50] };
        assert_eq!([image.width, image.height], size, "{name}");
        assert_eq!([camera.width, camera.height], size, "{name}");
        let thin = camera.thin_lens.expect("a thin lens");
        assert_eq!((thin.radius, thin.focus_distance), (0.25, 4.5));
        let mut farthest = 0.0f32;
        for (px, py) in [(0.5, 0.5), (16.25, 30.75), (32.9, 49.9), (3.0, 41.5)] {
            let (u, v) = (
                (px + offset[0] as f32) / 96.0,
                (py + offset[1] as f32) / 64.0,
            );
            let (focus_point, [origin, left, up, forward]) = mitsuba_focus_point(u, v, 4.5, 1.5);
            for i in 0..16 {
                for j in 0..16 {
                    let sample = Vec2::new((i as f32 + 0.5) / 16.0, (j as f32 + 0.5) / 16.0);
                    let ray = camera.lens_ray(px, py, sample);
                    let offset = ray.origin - origin;
                    // On the lens: in the plane across the view, within R.
                    assert!(offset.dot(forward).abs() < 1e-5, "{offset}");
                    let on_lens = Vec2::new(offset.dot(left), offset.dot(up));
                    assert!(on_lens.length() <= 0.25 * (1.0 + 1e-5), "{on_lens}");
                    farthest = farthest.max(on_lens.length());
                    // Through Mitsuba's focus point.
                    let t = (focus_point - ray.origin).dot(ray.dir);
                    let miss = (ray.origin + t * ray.dir - focus_point).length();
                    assert!(miss < 2e-5, "{name} ({px}, {py}) {sample}: {miss}");
                }
            }
        }
        assert!(
            farthest > 0.23,
            "the lens reaches out to its rim: {farthest}"
        );
    }
}

/// Mitsuba's defaults and refusals: the focus at `far_clip` when not given
/// (10⁴ by default), an `aperture_radius` of 0 a pinhole, and one line
/// naming the file and line for a missing radius, a negative one, a
/// `to_world` that scales (Mitsuba's rule for thin lenses) and bad clip
/// planes.
#[test]
fn thin_lens_defaults_and_errors() {
    let dir = tempfile::tempdir().unwrap();
    let focus_of = |name: &str, extra: &str| {
        let path = write(dir.path(), name, &thin_lens_scene(extra, ""));
        let loaded = raylab::load::load(&path, &Default::default()).unwrap();
        loaded.view.depth_of_field
    };
    let dof = focus_of("far.xml", r#"<float name="aperture_radius" value="0.1"/>"#);
    assert_eq!(dof.focus, Some(Focus::Distance(1e4)));
    let dof = focus_of(
        "far_clip.xml",
        r#"<float name="aperture_radius" value="0.1"/><float name="far_clip" value="50"/>"#,
    );
    assert_eq!(dof.focus, Some(Focus::Distance(50.0)));
    let path = write(
        dir.path(),
        "zero.xml",
        &thin_lens_scene(r#"<float name="aperture_radius" value="0"/>"#, ""),
    );
    let (_, camera) = render(&path, 1);
    assert_eq!(camera.thin_lens, None, "a radius of 0 is a pinhole");
    let cases = [
        ("missing.xml", "", ":3:", "needs an 'aperture_radius'"),
        (
            "negative.xml",
            "<float name=\"aperture_radius\" value=\"-1\"/>",
            ":6:",
            "'aperture_radius': must be at least 0",
        ),
        (
            "focus.xml",
            "<float name=\"aperture_radius\" value=\"1\"/>\n<float name=\"focus_distance\" value=\"0\"/>",
            ":7:",
            "'focus_distance': must be above 0",
        ),
        (
            "near.xml",
            "<float name=\"aperture_radius\" value=\"1\"/>\n<float name=\"near_clip\" value=\"0\"/>",
            ":7:",
            "'near_clip': must be greater than zero",
        ),
    ];
    for (name, extra, line, message) in cases {
        refused(dir.path(), name, &thin_lens_scene(extra, ""), line, message);
    }
    let scaled = thin_lens_scene(r#"<float name="aperture_radius" value="1"/>"#, "")
        .replace("<lookat", "<scale value=\"2\"/>\n            <lookat");
    refused(dir.path(), "scaled.xml", &scaled, ":7:", "scale factors");
}

/// A crop window out of the film is refused in one line naming the file
/// and the parameter's line, as Mitsuba refuses it.
#[test]
fn crop_windows_outside_the_film_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let lens = r#"<float name="aperture_radius" value="0.1"/>"#;
    let cases = [
        (
            "x.xml",
            "<integer name=\"crop_offset_x\" value=\"96\"/>",
            ":13:",
            "'crop_offset_x': 96 is outside the film",
        ),
        (
            "w.xml",
            "<integer name=\"crop_offset_x\" value=\"90\"/>\n<integer name=\"crop_width\" value=\"7\"/>",
            ":14:",
            "'crop_width': 7 does not fit the film",
        ),
        (
            "h.xml",
            "<integer name=\"crop_height\" value=\"0\"/>",
            ":13:",
            "'crop_height': 0 does not fit the film",
        ),
        (
            "y.xml",
            "<integer name=\"crop_offset_y\" value=\"-1\"/>",
            ":13:",
            "'crop_offset_y': -1 is outside the film",
        ),
    ];
    for (name, film, line, message) in cases {
        refused(
            dir.path(),
            name,
            &thin_lens_scene(lens, film),
            line,
            message,
        );
    }
    // The window a film of another size takes: the same part of it.
    let window = FilmWindow {
        film: [96, 64],
        offset: [40, 7],
        size: [33, 50],
    };
    assert_eq!(window.at(96, 64), window);
    assert_eq!(
        window.at(192, 128),
        FilmWindow {
            film: [192, 128],
            offset: [80, 14],
            size: [66, 100],
        }
    );
}

/// An orthographic view from above of the square [−1, 1]² in 8 × 8 pixels
/// (box filter): on the left half a black floor with a lamp of radiance 10
/// over pixels (1–2, 3–4) facing the camera; on the right a sky of
/// radiance 2; a `null` pane over columns 2–6 (x from −0.5 to 0.75) above
/// both. Every sample of a pixel has the same value.
fn hidden_scene(integrator: &str, hide: bool) -> String {
    format!(
        r#"<scene version="3.0.0">
    <integrator type="{integrator}">
        <boolean name="hide_emitters" value="{hide}"/>
    </integrator>
    <sensor type="orthographic">
        <transform name="to_world">
            <lookat origin="0, 0, 3" target="0, 0, 0" up="0, 1, 0"/>
        </transform>
        <film type="hdrfilm">
            <integer name="width" value="8"/>
            <integer name="height" value="8"/>
            <rfilter type="box"/>
        </film>
    </sensor>
    <emitter type="constant"><rgb name="radiance" value="2"/></emitter>
    <shape type="rectangle">
        <transform name="to_world"><scale x="0.5"/><translate x="-0.5"/></transform>
        <bsdf type="diffuse"><rgb name="reflectance" value="0"/></bsdf>
    </shape>
    <shape type="rectangle">
        <transform name="to_world">
            <scale x="0.25" y="0.25"/><translate x="-0.5" z="0.5"/>
        </transform>
        <emitter type="area"><rgb name="radiance" value="10"/></emitter>
    </shape>
    <shape type="rectangle">
        <transform name="to_world">
            <scale x="0.625" y="1"/><translate x="0.125" z="1"/>
        </transform>
        <bsdf type="null"/>
    </shape>
</scene>"#
    )
}

/// `hide_emitters` as Mitsuba 3.7.1's `path` and `direct` define it: the
/// camera sees through a lamp (here to the black floor) and not the sky;
/// through a `null` surface `direct` sees both, `path` neither when the
/// path ends at the lamp (`max_depth` 2: it never scatters off a surface
/// of its own) and the lamp once it goes on (3).
#[test]
fn hidden_emitters_follow_mitsubas_path_and_direct() {
    let dir = tempfile::tempdir().unwrap();
    // Columns: 0 floor, 1 lamp, 2 lamp through the pane, 3 floor through
    // the pane, 4–6 sky through the pane, 7 sky (rows 3 and 4).
    let cases = [
        (
            "shown.xml",
            "path",
            false,
            2,
            [0.0, 10.0, 10.0, 0.0, 2.0, 2.0, 2.0, 2.0],
        ),
        (
            "direct.xml",
            "direct",
            true,
            0,
            [0.0, 0.0, 10.0, 0.0, 2.0, 2.0, 2.0, 0.0],
        ),
        ("path2.xml", "path", true, 2, [0.0; 8]),
        (
            "path3.xml",
            "path",
            true,
            3,
            [0.0, 0.0, 10.0, 0.0, 0.0, 0.0, 0.0, 0.0],
        ),
    ];
    for (name, integrator, hide, depth, row) in cases {
        let mut xml = hidden_scene(integrator, hide);
        if depth > 0 {
            xml = xml.replace(
                "<boolean name=\"hide_emitters\"",
                &format!(
                    "<integer name=\"max_depth\" value=\"{depth}\"/><boolean name=\"hide_emitters\""
                ),
            );
        }
        let path = write(dir.path(), name, &xml);
        let (image, _) = render(&path, 4);
        for y in [3, 4] {
            for (x, want) in row.iter().enumerate() {
                let got = image.get(x as u32, y);
                assert!(
                    (got - Vec3A::splat(*want)).abs().max_element() < 1e-5,
                    "{name}: pixel ({x}, {y}) is {got}, Mitsuba's rule gives {want}"
                );
            }
        }
    }
    // `ptracer` keeps its hidden emitters opaque: not yet read.
    let xml = hidden_scene("ptracer", true);
    refused(dir.path(), "ptracer.xml", &xml, ":3:", "hide_emitters");
}
