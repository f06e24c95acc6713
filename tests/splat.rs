//! Splatting (`--reconstruction splat`, the default for Mitsuba scenes): each
//! `path` sample is added to every pixel within the filter's radius,
//! weighted by the filter normalised over the image. It renders the same
//! expected image as drawing the samples from the filter (edges and tile
//! borders included), with less noise per pixel; the box filter is never
//! splatted. Farms and passes stay exact: tests/farm.rs.

use std::path::Path;

mod common;

use raylab::job::JobOptions;
use raylab::sampling::filter::Reconstruction;

/// Writes `xml` as `name` in `dir`; its path.
fn write(dir: &Path, name: &str, xml: &str) -> String {
    let path = dir.join(name);
    std::fs::write(&path, xml).unwrap();
    path.to_str().unwrap().to_string()
}

/// Renders the scene at `path` with `spp` samples, `seed` and
/// `reconstruction` (the scene's default if `None`): its pixels.
fn render(
    path: &str,
    spp: u32,
    seed: u64,
    reconstruction: Option<Reconstruction>,
) -> Vec<[f32; 3]> {
    let mut options = JobOptions::new(path);
    options.spp = Some(spp);
    options.seed = Some(seed);
    options.quiet = true;
    options.scene.reconstruction = reconstruction;
    common::job_pixels(options)
}

/// A furnace seen through a camera: only a constant sky of radiance 0.5,
/// 37 × 29 pixels (eight row tiles, the last short), `filter` its film's.
fn furnace(dir: &Path, filter: &str) -> String {
    write(
        dir,
        "furnace.xml",
        &format!(
            r#"<scene version="3.0.0">
    <integrator type="path"/>
    <sensor type="perspective">
        <float name="fov" value="50"/>
        <film type="hdrfilm">
            <integer name="width" value="37"/><integer name="height" value="29"/>
            {filter}
        </film>
    </sensor>
    <emitter type="constant"><rgb name="radiance" value="0.5"/></emitter>
</scene>"#
        ),
    )
}

/// Every pixel of the furnace, corners, edges and the rows beside tile
/// borders included, is 0.5 up to the noise of its weights: the
/// normalisation over the image is right everywhere, and every tile's
/// border rows reached their pixels. (A lost border row would leave the
/// rows beside it about a fifth short; edges normalised over the whole
/// filter, a sixth.)
#[test]
fn a_furnace_stays_even_to_its_edges() {
    let dir = tempfile::tempdir().unwrap();
    for filter in [
        "",
        r#"<rfilter type="tent"><float name="radius" value="1.5"/></rfilter>"#,
    ] {
        let path = furnace(dir.path(), filter);
        let sampled = render(&path, 64, 0, Some(Reconstruction::Sample));
        let splatted = render(&path, 64, 0, None);
        assert!(sampled.iter().flatten().all(|&v| v == 0.5));
        let worst = splatted
            .iter()
            .flatten()
            .map(|v| (v - 0.5).abs() / 0.5)
            .fold(0.0f32, f32::max);
        assert!(worst < 0.01, "{filter}: a pixel {worst} from 0.5");
        // Not the sampled image: the splat did happen.
        assert!(splatted.iter().flatten().any(|&v| v != 0.5), "{filter}");
    }
}

/// A floor lit by a small sphere lamp (sharp light falloff and a shadow
/// edge), Mitsuba's default gaussian filter.
fn lit_floor(dir: &Path, filter: &str) -> String {
    write(
        dir,
        "floor.xml",
        &format!(
            r#"<scene version="3.0.0">
    <integrator type="path"><integer name="max_depth" value="3"/></integrator>
    <sensor type="perspective">
        <float name="fov" value="55"/>
        <transform name="to_world"><lookat origin="0.5, -3, 2.5" target="0, 0, 0" up="0, 0, 1"/></transform>
        <film type="hdrfilm">
            <integer name="width" value="40"/><integer name="height" value="30"/>
            {filter}
        </film>
    </sensor>
    <shape type="rectangle">
        <transform name="to_world"><scale value="3"/></transform>
        <bsdf type="roughconductor"><float name="alpha" value="0.4"/></bsdf>
    </shape>
    <shape type="cube">
        <transform name="to_world"><scale value="0.3"/><translate x="0.2" y="0.3" z="0.3"/></transform>
        <bsdf type="diffuse"/>
    </shape>
    <shape type="sphere">
        <point name="center" x="-0.5" y="0.5" z="1.2"/><float name="radius" value="0.3"/>
        <emitter type="area"><rgb name="radiance" value="5"/></emitter>
    </shape>
</scene>"#
        ),
    )
}

fn mean(pixels: &[[f32; 3]]) -> f64 {
    pixels.iter().flatten().map(|&v| f64::from(v)).sum::<f64>() / (3 * pixels.len()) as f64
}

/// Mean square error against `reference`, relative to its mean.
fn error(pixels: &[[f32; 3]], reference: &[[f32; 3]]) -> f64 {
    let m = mean(reference);
    let sq: f64 = (pixels.iter().flatten().zip(reference.iter().flatten()))
        .map(|(&a, &b)| (f64::from(a) - f64::from(b)).powi(2))
        .sum();
    sq / (3 * pixels.len()) as f64 / (m * m)
}

/// Splatted and sampled renders agree in expectation (against a
/// high-sample sampled render: their mean error is the noise of their own
/// samples, which is far above any difference of the images they converge
/// to), and the splatted one's per-pixel error is well below the sampled
/// one's (each pixel averages its neighbours' samples too). With the box
/// filter both are the same image, bit for bit.
#[test]
fn splatting_renders_the_same_image_with_less_noise() {
    let dir = tempfile::tempdir().unwrap();
    let path = lit_floor(dir.path(), "");
    let reference = render(&path, 1024, 99, Some(Reconstruction::Sample));
    let seeds = [1u64, 2, 3, 4];
    let (mut e_sample, mut e_splat) = (0.0, 0.0);
    let (mut m_sample, mut m_splat) = (0.0, 0.0);
    for &seed in &seeds {
        let sampled = render(&path, 16, seed, Some(Reconstruction::Sample));
        let splatted = render(&path, 16, seed, Some(Reconstruction::Splat));
        e_sample += error(&sampled, &reference) / seeds.len() as f64;
        e_splat += error(&splatted, &reference) / seeds.len() as f64;
        m_sample += mean(&sampled) / seeds.len() as f64;
        m_splat += mean(&splatted) / seeds.len() as f64;
    }
    let m_ref = mean(&reference);
    for (name, m) in [("sampled", m_sample), ("splatted", m_splat)] {
        assert!(
            (m / m_ref - 1.0).abs() < 0.01,
            "{name} mean {m} against the reference's {m_ref}"
        );
    }
    assert!(
        e_splat < 0.6 * e_sample,
        "splatted error {e_splat:.3e}, sampled {e_sample:.3e}"
    );
    // The box: one image.
    let boxed = lit_floor(dir.path(), r#"<rfilter type="box"/>"#);
    assert_eq!(
        render(&boxed, 4, 5, Some(Reconstruction::Splat)),
        render(&boxed, 4, 5, Some(Reconstruction::Sample))
    );
}
