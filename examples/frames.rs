use raylab::*;
fn main() {
    let scene = cornell::scene();
    let cam = Camera::lab(cornell::CAMERA_POSITION, 0.0, 0.0, 500, 500);
    let s = render::RenderSettings::default();
    for _ in 0..3 {
        let t = std::time::Instant::now();
        let n = 50;
        let mut rays = 0;
        for _ in 0..n {
            rays += render::render(&scene, &cam, &s, &|_| {}).rays;
        }
        let dt = t.elapsed().as_secs_f64() / n as f64;
        println!(
            "{:.2} ms/frame {:.1} Mrays/s",
            dt * 1e3,
            rays as f64 / n as f64 / dt / 1e6
        );
    }
}
