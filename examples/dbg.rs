use raylab::*;
fn main() {
    let scene = cornell::scene();
    let cam = Camera::lab(cornell::CAMERA_POSITION, 0.0, 0.0, 500, 500);
    let r = film::read_exr(std::path::Path::new(
        "../shared/refs/cornell-direct-lab-500.exr",
    ))
    .unwrap();
    let mut bad = 0;
    for y in 0..500 {
        for x in 0..500 {
            let c = render::sample_pixel(&scene, &cam, Integrator::Direct, x, y);
            let d = (c - r.get(x, y)).abs().max_element();
            if d > 1e-3 {
                bad += 1;
                let amb = scene.reflectance(
                    scene
                        .intersect(&cam.ray(x as f32 + 0.5, y as f32 + 0.5), f32::INFINITY)
                        .unwrap()
                        .prim,
                ) * 0.5;
                if (c - amb).abs().max_element() < 1e-6 || x == 250 {
                    let ray = cam.ray(x as f32 + 0.5, y as f32 + 0.5);
                    let h = scene.intersect(&ray, f32::INFINITY).unwrap();
                    let sp = scene.surface_point(&h);
                    let (sr, tm) = sp.ray_to(scene.light.position);
                    let occ = scene.intersect(&sr, tm);
                    println!(
                        "{x},{y} ours {c} ref {} prim {} occ {:?}",
                        r.get(x, y),
                        h.prim,
                        occ
                    );
                }
            }
        }
    }
    println!("bad {bad}");
}
