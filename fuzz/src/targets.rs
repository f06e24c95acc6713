//! The targets' bodies, callable from the fuzz targets and from the
//! regression test that replays committed findings (`tests/fuzz_regressions.rs`).

use raylab::load::LoadOptions;

use super::{load_and_render, load_with_env, put, scratch, split_nul};

/// A Wavefront OBJ (before the first NUL byte) and its material library
/// `in.mtl` (after it), loaded and rendered as `raylab render in.obj` would.
pub fn obj(data: &[u8]) {
    let (obj, mtl) = split_nul(data);
    put("in.mtl", mtl);
    let path = put("in.obj", obj);
    load_and_render(&path, &LoadOptions::default());
}

const MTL_USER: &str = "mtllib in.mtl\nv -1 -1 0\nv 1 -1 0\nv 0 1 0\nv 1 1 0\nvt 0 0\nvt 1 0\nvt 0.5 1\n\
vn 0 0 1\nusemtl a\nf 1/1/1 2/2/1 3/3/1\nusemtl b\nf 2/2/1 4/1/1 3/3/1\nusemtl m\nf 1 2 4\n";

/// A material library `in.mtl`, used by a fixed OBJ that names the materials
/// `a`, `b` and `m`; loaded and rendered.
pub fn mtl(data: &[u8]) {
    put("in.mtl", data);
    let path = put("mtl-user.obj", MTL_USER.as_bytes());
    load_and_render(&path, &LoadOptions::default());
}

/// A glTF 2.0 JSON file `in.gltf` (it may refer to the fixtures `fixture.bin`
/// and `fixture.png`, or carry `data:` URIs), loaded and rendered as written
/// and posed by its first animation.
pub fn gltf_json(data: &[u8]) {
    let path = put("in.gltf", data);
    load_and_render(&path, &LoadOptions::default());
    load_and_render(&path, &posed());
}

/// A binary glTF container `in.glb`, loaded and rendered as written and
/// posed by its first animation.
pub fn glb(data: &[u8]) {
    let path = put("in.glb", data);
    load_and_render(&path, &LoadOptions::default());
    load_and_render(&path, &posed());
}

/// The options of `--at 0.7`: a glTF file's first animation between
/// keyframes (a file without animations is refused in one line).
fn posed() -> LoadOptions {
    LoadOptions {
        animation: raylab::load::gltf::AnimationOptions {
            animation: None,
            time: Some(0.7),
            if_animated: false,
        },
        ..LoadOptions::default()
    }
}

/// A scene file `in.toml` (it may refer to the fixtures), its settings read
/// and the scene loaded and rendered.
pub fn scene_toml(data: &[u8]) {
    let path = put("in.toml", data);
    if let Err(e) = raylab::load::shot::read_settings(&path) {
        super::check_message(&e.to_string());
    }
    load_and_render(&path, &LoadOptions::default());
}

/// A Radiance RGBE map `in.hdr` lighting the fixture OBJ.
pub fn hdr(data: &[u8]) {
    load_with_env(&put("in.hdr", data));
}

/// An OpenEXR map `in.exr` lighting the fixture OBJ.
pub fn exr(data: &[u8]) {
    load_with_env(&put("in.exr", data));
}

/// An image `in.EXT` used by a fixed OBJ as every kind of map (sRGB base
/// colour, linear roughness, opacity, a normal map, emission and a bump map).
fn texture(data: &[u8], ext: &str) {
    put(&format!("in.{ext}"), data);
    let mtl = format!(
        "newmtl a\nKd 1 1 1\nmap_Kd in.{ext}\nmap_Pr in.{ext}\nmap_d in.{ext}\nnorm in.{ext}\n\
         newmtl b\nKd 1 1 1\nmap_Ke in.{ext}\nKe 1 1 1\nbump -bm 2 in.{ext}\n"
    );
    put(&format!("tex-{ext}.mtl"), mtl.as_bytes());
    let obj = format!(
        "mtllib tex-{ext}.mtl\nv -1 -1 0\nv 1 -1 0\nv 0 1 0\nv 1 1 0\nvt 0 0\nvt 1 0\nvt 0.5 1\n\
         vn 0 0 1\nusemtl a\nf 1/1/1 2/2/1 3/3/1\nusemtl b\nf 2/2/1 4/1/1 3/3/1\n"
    );
    let path = put(&format!("tex-{ext}.obj"), obj.as_bytes());
    load_and_render(&path, &LoadOptions::default());
}

/// A PNG texture.
pub fn png(data: &[u8]) {
    texture(data, "png");
}

/// A JPEG texture.
pub fn jpeg(data: &[u8]) {
    texture(data, "jpg");
}

/// A WebP texture (`EXT_texture_webp`'s images, and any texture file).
pub fn webp(data: &[u8]) {
    texture(data, "webp");
}

/// A `raylab bench --rays` file, read as the bench reads it and cast at a
/// small mesh by every query kind, each answer compared with brute force.
pub fn rays(data: &[u8]) {
    let path = put("in.rays", data);
    match raylab::workload::read_rays(&path) {
        Err(e) => super::check_message(&e),
        Ok(rays) => super::bvh::check_queries(super::bvh::fixture_mesh(), &rays),
    }
}

/// Rays and triangles from raw bytes (the first byte: how many rays, 24 bytes
/// each, then triangles of 36 bytes), every query kind against brute force.
pub fn bvh(data: &[u8]) {
    let Some((&n, rest)) = data.split_first() else {
        return;
    };
    let n = (n as usize % 17).min(rest.len() / 24);
    let (ray_bytes, tri_bytes) = rest.split_at(n * 24);
    let rays = super::bvh::rays_from(ray_bytes);
    let triangles = super::bvh::triangles_from(tri_bytes);
    super::bvh::check_queries(&triangles, &rays);
}

/// A render checkpoint (`--checkpoint FILE`), its checksum appended so that
/// inputs get past it to the header and the sums: read as a resume reads it.
pub fn checkpoint(data: &[u8]) {
    let mut f = raylab::fingerprint::Fingerprint::new();
    f.update(data);
    let mut bytes = data.to_vec();
    bytes.extend_from_slice(&f.value().to_le_bytes());
    let path = put("in.ckpt", &bytes);
    if let Err(e) = raylab::checkpoint::read_header(&path) {
        super::check_message(&e.to_string());
    }
    match raylab::checkpoint::read(&path) {
        Err(e) => super::check_message(&e.to_string()),
        Ok(c) => {
            let h = c.header;
            assert_eq!(c.accumulator.spp(), h.spp);
            let _ = (h.width, h.height, h.aovs);
        }
    }
}

/// The target of this name (all but `cli`, which needs the binary's argument
/// parser), for replaying inputs.
pub fn by_name(name: &str) -> Option<fn(&[u8])> {
    let _ = scratch();
    Some(match name {
        "obj" => obj,
        "mtl" => mtl,
        "gltf_json" => gltf_json,
        "glb" => glb,
        "scene_toml" => scene_toml,
        "hdr" => hdr,
        "exr" => exr,
        "png" => png,
        "jpeg" => jpeg,
        "rays" => rays,
        "bvh" => bvh,
        "checkpoint" => checkpoint,
        _ => return None,
    })
}
