//! The targets' bodies, callable from the fuzz targets and from the
//! regression test that replays committed findings (`tests/fuzz_regressions.rs`).

use raylab::load::LoadOptions;

use super::{fuzz_options, load_and_render, load_with_env, put, scratch, split_nul};

/// A Wavefront OBJ (before the first NUL byte) and its material library
/// `in.mtl` (after it), loaded and rendered as `raylab render in.obj` would.
pub fn obj(data: &[u8]) {
    let (obj, mtl) = split_nul(data);
    put("in.mtl", mtl);
    let path = put("in.obj", obj);
    load_and_render(&path, &fuzz_options());
}

const MTL_USER: &str = "mtllib in.mtl\nv -1 -1 0\nv 1 -1 0\nv 0 1 0\nv 1 1 0\nvt 0 0\nvt 1 0\nvt 0.5 1\n\
vn 0 0 1\nusemtl a\nf 1/1/1 2/2/1 3/3/1\nusemtl b\nf 2/2/1 4/1/1 3/3/1\nusemtl m\nf 1 2 4\n";

/// A material library `in.mtl`, used by a fixed OBJ that names the materials
/// `a`, `b` and `m`; loaded and rendered.
pub fn mtl(data: &[u8]) {
    put("in.mtl", data);
    let path = put("mtl-user.obj", MTL_USER.as_bytes());
    load_and_render(&path, &fuzz_options());
}

/// A glTF 2.0 JSON file `in.gltf` (it may refer to the fixtures `fixture.bin`
/// and `fixture.png`, or carry `data:` URIs), loaded and rendered as written
/// and posed by its first animation.
pub fn gltf_json(data: &[u8]) {
    let path = put("in.gltf", data);
    load_and_render(&path, &fuzz_options());
    load_and_render(&path, &posed());
}

/// A binary glTF container `in.glb`, loaded and rendered as written and
/// posed by its first animation.
pub fn glb(data: &[u8]) {
    let path = put("in.glb", data);
    load_and_render(&path, &fuzz_options());
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
        ..fuzz_options()
    }
}

/// A scene file `in.toml` (it may refer to the fixtures), its settings read
/// and the scene loaded and rendered.
pub fn scene_toml(data: &[u8]) {
    let path = put("in.toml", data);
    if let Err(e) = raylab::load::shot::read_settings(&path) {
        super::check_message(&e.to_string());
    }
    load_and_render(&path, &fuzz_options());
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
    load_and_render(&path, &fuzz_options());
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

/// A KTX2 texture (`KHR_texture_basisu`'s images, and any texture file):
/// the container checks, then the Basis Universal transcoder.
pub fn ktx2(data: &[u8]) {
    texture(data, "ktx2");
}

/// The compressed buffer views [`meshopt`] tries, one per input's first
/// byte (modulo their number): extension, mode, filter, byte stride, and the
/// component type and type of the accessor reading the decoded bytes.
pub const MESHOPT_VIEWS: [(&str, &str, &str, u32, u32, &str); 13] = [
    ("EXT", "ATTRIBUTES", "NONE", 12, 5126, "VEC3"),
    ("EXT", "ATTRIBUTES", "NONE", 4, 5121, "VEC3"),
    ("KHR", "ATTRIBUTES", "NONE", 8, 5123, "VEC3"),
    ("KHR", "ATTRIBUTES", "EXPONENTIAL", 12, 5126, "VEC3"),
    ("EXT", "ATTRIBUTES", "OCTAHEDRAL", 8, 5122, "VEC3"),
    ("KHR", "ATTRIBUTES", "OCTAHEDRAL", 4, 5120, "VEC3"),
    ("EXT", "ATTRIBUTES", "QUATERNION", 8, 5122, "VEC3"),
    ("KHR", "ATTRIBUTES", "COLOR", 4, 5121, "VEC3"),
    ("KHR", "ATTRIBUTES", "COLOR", 8, 5123, "VEC3"),
    ("EXT", "TRIANGLES", "NONE", 2, 5123, "SCALAR"),
    ("KHR", "TRIANGLES", "NONE", 4, 5125, "SCALAR"),
    ("EXT", "INDICES", "NONE", 2, 5123, "SCALAR"),
    ("KHR", "INDICES", "NONE", 4, 5125, "SCALAR"),
];

/// A `EXT_`/`KHR_meshopt_compression` stream: the input's first byte picks
/// the view's mode, filter and stride ([`MESHOPT_VIEWS`]), the next two
/// (little-endian) the element count (of triangles for `TRIANGLES`), and the
/// rest is the compressed bytes (`meshopt.bin`), read
/// by a glTF as its positions or its indices; the other comes from the
/// fixture buffer. Loaded and rendered.
pub fn meshopt(data: &[u8]) {
    let [pick, c0, c1, stream @ ..] = data else {
        return;
    };
    let count = u16::from_le_bytes([*c0, *c1]) as u32;
    let (ext, mode, filter, stride, component, kind) =
        MESHOPT_VIEWS[*pick as usize % MESHOPT_VIEWS.len()];
    let count = if mode == "TRIANGLES" {
        3 * count
    } else {
        count
    };
    put("meshopt.bin", stream);
    let name = format!("{ext}_meshopt_compression");
    // The fixture's positions (view 0) and indices (view 1), and the
    // compressed view 2 over a placeholder buffer 2.
    let (positions, indices) = if kind == "SCALAR" { (0, 2) } else { (2, 1) };
    let json = format!(
        r#"{{"asset":{{"version":"2.0"}},"extensionsUsed":["{name}","KHR_mesh_quantization"],
"extensionsRequired":["{name}","KHR_mesh_quantization"],"scene":0,"scenes":[{{"nodes":[0]}}],
"nodes":[{{"mesh":0}}],"meshes":[{{"primitives":[{{"attributes":{{"POSITION":{positions}}},"indices":{indices}}}]}}],
"buffers":[{{"uri":"fixture.bin","byteLength":44}},{{"uri":"meshopt.bin","byteLength":{len}}},
{{"byteLength":{decoded},"extensions":{{"{name}":{{"fallback":true}}}}}}],
"bufferViews":[{{"buffer":0,"byteLength":36}},{{"buffer":0,"byteOffset":36,"byteLength":6}},
{{"buffer":2,"byteLength":{decoded},"extensions":{{"{name}":{{"buffer":1,"byteLength":{len},
"byteStride":{stride},"count":{count},"mode":"{mode}","filter":"{filter}"}}}}}}],
"accessors":[{{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3"}},
{{"bufferView":1,"componentType":5123,"count":3,"type":"SCALAR"}},
{{"bufferView":2,"byteOffset":0,"componentType":{component},"count":{count},"type":"{kind}"}}]}}"#,
        len = stream.len(),
        decoded = count * stride,
    );
    let path = put("meshopt.gltf", json.as_bytes());
    load_and_render(&path, &fuzz_options());
}

/// The Draco attribute ids of POSITION, NORMAL and TEXCOORD_0 (or none) and
/// the indices' component type, picked by a draco input's first byte:
/// gltf-transform's ids, DracoPy's, positions alone, and two attributes with
/// 8-bit indices.
pub const DRACO_LAYOUTS: [([Option<u32>; 3], u32); 4] = [
    ([Some(0), Some(1), Some(2)], 5123),
    ([Some(2), Some(1), Some(0)], 5123),
    ([Some(0), None, None], 5125),
    ([Some(2), None, Some(0)], 5121),
];

/// A `KHR_draco_mesh_compression` stream (after a byte picking one of
/// [`DRACO_LAYOUTS`]), `draco.bin`, the only data of a glTF primitive whose
/// accessors agree with the counts its head declares (so that the checks
/// pass and the decoder runs); loaded and rendered.
///
/// The decoder (`draco-oxide-decoder`) panics on some malformed streams;
/// raylab turns such a panic into a one-line error ([`raylab::guard`]), so
/// this target lets a panic caught there unwind instead of aborting, and
/// still aborts on any other.
pub fn draco(data: &[u8]) {
    static HOOK: std::sync::Once = std::sync::Once::new();
    HOOK.call_once(|| {
        let abort = std::panic::take_hook();
        std::panic::set_hook(Box::new(move |info| {
            if !raylab::guard::quiet() {
                abort(info)
            }
        }));
    });
    let [pick, stream @ ..] = data else {
        return;
    };
    let (ids, index_type) = DRACO_LAYOUTS[*pick as usize % DRACO_LAYOUTS.len()];
    // Counts far beyond what the stream could hold are refused before any
    // decoding; they are capped so that the JSON stays small.
    let (faces, vertices) = raylab::load::gltf::draco::stream_counts(stream).unwrap_or((1, 3));
    let (faces, vertices) = (faces.min(1 << 24), vertices.min(1 << 24));
    put("draco.bin", stream);
    let mut attributes = Vec::new();
    let mut accessors = vec![format!(
        r#"{{"componentType":{index_type},"count":{},"type":"SCALAR"}}"#,
        3 * faces
    )];
    for ((name, kind), id) in [
        ("POSITION", "VEC3"),
        ("NORMAL", "VEC3"),
        ("TEXCOORD_0", "VEC2"),
    ]
    .into_iter()
    .zip(ids)
    {
        if let Some(id) = id {
            attributes.push((name, accessors.len(), id));
            accessors.push(format!(
                r#"{{"componentType":5126,"count":{vertices},"type":"{kind}"}}"#
            ));
        }
    }
    let join = |f: &dyn Fn(&(&str, usize, u32)) -> String| {
        attributes.iter().map(f).collect::<Vec<_>>().join(",")
    };
    let json = format!(
        r#"{{"asset":{{"version":"2.0"}},"extensionsUsed":["KHR_draco_mesh_compression"],
"extensionsRequired":["KHR_draco_mesh_compression"],"scene":0,"scenes":[{{"nodes":[0]}}],
"nodes":[{{"mesh":0}}],"meshes":[{{"primitives":[{{"attributes":{{{}}},"indices":0,
"extensions":{{"KHR_draco_mesh_compression":{{"bufferView":0,"attributes":{{{}}}}}}}}}]}}],
"buffers":[{{"uri":"draco.bin","byteLength":{len}}}],"bufferViews":[{{"buffer":0,"byteLength":{len}}}],
"accessors":[{}]}}"#,
        join(&|(n, a, _)| format!(r#""{n}":{a}"#)),
        join(&|(n, _, id)| format!(r#""{n}":{id}"#)),
        accessors.join(","),
        len = stream.len(),
    );
    let path = put("draco.gltf", json.as_bytes());
    load_and_render(&path, &fuzz_options());
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

/// A Mitsuba 3 XML scene `in.xml` (it may include itself, or `fixture.xml`,
/// a scene the seeds refer to), read into its tree: an error is one line,
/// and so are the tree's summary and warnings.
pub fn mitsuba_xml(data: &[u8]) {
    let path = put("in.xml", data);
    match raylab::load::mitsuba::read(&path, &[]) {
        Err(e) => super::check_message(&e.to_string()),
        Ok(tree) => {
            super::check_message(&tree.summary());
            for w in &tree.warnings {
                super::check_message(w);
            }
            assert!(!tree.objects().is_empty());
        }
    }
}

/// The memory budget of the mesh targets: a header asking for more is an
/// error, as `--max-memory` makes it (and the fuzzer's 4 GiB limit is
/// never reached).
fn mesh_ledger() -> raylab::memory::Ledger {
    raylab::memory::Ledger::new(raylab::memory::MemoryBudget::bytes(1 << 30))
}

/// What every mesh a reader returns must be: arrays of the vertex count,
/// indices in range, attributes of their element's count, one-line warnings.
fn check_mesh(m: &raylab::load::mitsuba::MitsubaMesh) {
    let n = m.positions.len();
    assert!(m.normals.as_ref().is_none_or(|v| v.len() == n));
    assert!(m.uvs.as_ref().is_none_or(|v| v.len() == n));
    assert!(m.colors.as_ref().is_none_or(|v| v.len() == n));
    assert!(m.indices.iter().flatten().all(|&i| (i as usize) < n));
    for a in &m.vertex_attributes {
        assert!(a.name.starts_with("vertex_") && (1..=4).contains(&a.channels));
        assert_eq!(a.values.len(), n * a.channels);
    }
    for a in &m.face_attributes {
        assert!(a.name.starts_with("face_") && (1..=4).contains(&a.channels));
        assert_eq!(a.values.len(), m.indices.len() * a.channels);
    }
    for w in &m.warnings {
        super::check_message(w);
    }
}

/// A PLY file `in.ply`, read as Mitsuba's `ply` shape (with
/// `flip_tex_coords`).
pub fn mitsuba_ply(data: &[u8]) {
    let path = put("in.ply", data);
    match raylab::load::mitsuba::read_ply(&path, true, &mesh_ledger()) {
        Err(e) => super::check_message(&e.to_string()),
        Ok(m) => check_mesh(&m),
    }
}

/// A `.serialized` file `in.serialized`, its shapes 0 to 3 read as
/// Mitsuba's `serialized` shape.
pub fn mitsuba_serialized(data: &[u8]) {
    let path = put("in.serialized", data);
    for index in 0..4 {
        match raylab::load::mitsuba::read_serialized(&path, index, &mesh_ledger()) {
            Err(e) => super::check_message(&e.to_string()),
            Ok(m) => check_mesh(&m),
        }
    }
}

/// A `.vol` file `in.vol` read as Mitsuba's `VolumeGrid` reads it, then as
/// a medium's grid (looked up at a few points) and as an `sdfgrid`'s.
pub fn mitsuba_vol(data: &[u8]) {
    let path = put("in.vol", data);
    match raylab::load::mitsuba::read_vol(&path, &mesh_ledger()) {
        Err(e) => super::check_message(&e.to_string()),
        Ok(vol) => match raylab::media::Grid::new(vol.res, vol.channels, vol.values) {
            Err(e) => super::check_message(&e),
            Ok(grid) => {
                for p in [[0.5f32; 3], [-1.0, 0.3, 2.0], [0.999, 0.0, 0.51]] {
                    let v = grid.eval(glam::Vec3A::from(p), false);
                    assert!(v.is_finite() && v.max_element() <= grid.max(), "{v}");
                    let _ = grid.eval(glam::Vec3A::from(p), true);
                }
            }
        },
    }
    if let Err(e) = raylab::load::mitsuba::parse_sdf_vol(data, &path) {
        super::check_message(&e.to_string());
    }
}

/// An OpenVDB file: read as `raylab::load::vdb` reads a density grid (every
/// node, mask and compressed buffer checked), then looked up around its
/// voxels: every value finite, within [0, max].
pub fn vdb(data: &[u8]) {
    match raylab::load::vdb::parse_vdb(data, None) {
        Err(e) => super::check_message(&e),
        Ok(read) => {
            let g = &read.grid;
            let (lo, hi) = g.voxels();
            let lo = glam::Vec3A::new(lo[0] as f32, lo[1] as f32, lo[2] as f32);
            let hi = glam::Vec3A::new(hi[0] as f32, hi[1] as f32, hi[2] as f32);
            for t in [-0.1f32, 0.0, 0.3, 0.5, 0.77, 1.0, 1.2] {
                let v = g.eval(lo + (hi - lo) * t + 0.25);
                assert!(v.is_finite() && v >= 0.0 && v <= g.max(), "{v}");
            }
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
        "webp" => webp,
        "meshopt" => meshopt,
        "draco" => draco,
        "ktx2" => ktx2,
        "rays" => rays,
        "bvh" => bvh,
        "checkpoint" => checkpoint,
        "mitsuba_xml" => mitsuba_xml,
        "mitsuba_ply" => mitsuba_ply,
        "mitsuba_serialized" => mitsuba_serialized,
        "mitsuba_vol" => mitsuba_vol,
        "vdb" => vdb,
        _ => return None,
    })
}
