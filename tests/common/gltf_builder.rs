//! A small glTF 2.0 writer for tests: accessors over one binary buffer, meshes,
//! nodes and whatever else as raw JSON, written as `.gltf` (buffer in a data URI
//! or a `.bin` beside it) or `.glb`; and what the glTF tests share besides
//! (loading, a square and a floor, assertions).

use std::path::{Path, PathBuf};

use glam::Vec3A;
use raylab::load::{LoadOptions, Loaded};
use serde_json::{Value, json};

/// glTF component types.
pub const I8: u32 = 5120;
pub const U8: u32 = 5121;
pub const I16: u32 = 5122;
pub const U16: u32 = 5123;
pub const U32: u32 = 5125;
pub const F32: u32 = 5126;

/// A glTF file being built. Everything but the buffer, views and accessors is
/// raw JSON pushed by the test.
#[derive(Default)]
pub struct Gltf {
    pub buffer: Vec<u8>,
    pub views: Vec<Value>,
    pub accessors: Vec<Value>,
    pub meshes: Vec<Value>,
    pub nodes: Vec<Value>,
    pub materials: Vec<Value>,
    pub textures: Vec<Value>,
    pub images: Vec<Value>,
    pub samplers: Vec<Value>,
    pub cameras: Vec<Value>,
    pub lights: Vec<Value>,
    /// The default scene's root nodes.
    pub roots: Vec<usize>,
    pub extensions_used: Vec<String>,
    pub extensions_required: Vec<String>,
}

fn push(list: &mut Vec<Value>, v: Value) -> usize {
    list.push(v);
    list.len() - 1
}

/// The glTF element type of `n` components.
fn type_name(n: usize) -> &'static str {
    match n {
        1 => "SCALAR",
        2 => "VEC2",
        3 => "VEC3",
        4 => "VEC4",
        _ => panic!("no element type of {n} components"),
    }
}

impl Gltf {
    pub fn new() -> Self {
        Self::default()
    }

    /// A buffer view over `bytes` (appended 4-byte aligned).
    pub fn view(&mut self, bytes: &[u8], stride: Option<usize>) -> usize {
        while !self.buffer.len().is_multiple_of(4) {
            self.buffer.push(0);
        }
        let mut v = json!({
            "buffer": 0,
            "byteOffset": self.buffer.len(),
            "byteLength": bytes.len(),
        });
        if let Some(s) = stride {
            v["byteStride"] = json!(s);
        }
        self.buffer.extend_from_slice(bytes);
        push(&mut self.views, v)
    }

    /// An accessor given as raw JSON.
    pub fn accessor(&mut self, v: Value) -> usize {
        push(&mut self.accessors, v)
    }

    /// A float accessor of `N` components per element, in its own view.
    pub fn floats<const N: usize>(&mut self, data: &[[f32; N]]) -> usize {
        let bytes: Vec<u8> = data
            .iter()
            .flatten()
            .flat_map(|x| x.to_le_bytes())
            .collect();
        let view = self.view(&bytes, None);
        self.accessor(json!({
            "bufferView": view,
            "componentType": F32,
            "count": data.len(),
            "type": type_name(N),
        }))
    }

    /// An index accessor of component type `ct` (U8, U16 or U32).
    pub fn indices(&mut self, ct: u32, data: &[u32]) -> usize {
        let bytes: Vec<u8> = data
            .iter()
            .flat_map(|&i| match ct {
                U8 => vec![u8::try_from(i).unwrap()],
                U16 => u16::try_from(i).unwrap().to_le_bytes().to_vec(),
                U32 => i.to_le_bytes().to_vec(),
                _ => panic!("not an index type: {ct}"),
            })
            .collect();
        let view = self.view(&bytes, None);
        self.accessor(json!({
            "bufferView": view,
            "componentType": ct,
            "count": data.len(),
            "type": "SCALAR",
        }))
    }

    pub fn mesh(&mut self, primitives: Vec<Value>) -> usize {
        push(&mut self.meshes, json!({ "primitives": primitives }))
    }

    pub fn node(&mut self, v: Value) -> usize {
        push(&mut self.nodes, v)
    }

    /// A node that is one of the default scene's roots.
    pub fn root(&mut self, v: Value) -> usize {
        let n = self.node(v);
        self.roots.push(n);
        n
    }

    pub fn material(&mut self, v: Value) -> usize {
        push(&mut self.materials, v)
    }

    pub fn camera(&mut self, v: Value) -> usize {
        push(&mut self.cameras, v)
    }

    pub fn light(&mut self, v: Value) -> usize {
        push(&mut self.lights, v)
    }

    /// A texture of an embedded PNG (data URI) with an optional sampler.
    pub fn png_texture(&mut self, png: &[u8], sampler: Option<Value>) -> usize {
        let image = push(
            &mut self.images,
            json!({ "uri": format!("data:image/png;base64,{}", base64(png)) }),
        );
        let mut t = json!({ "source": image });
        if let Some(s) = sampler {
            t["sampler"] = json!(push(&mut self.samplers, s));
        }
        push(&mut self.textures, t)
    }

    /// The JSON, with the buffer at `uri` (None: the GLB's binary chunk).
    pub fn to_json(&self, uri: Option<String>) -> Value {
        let mut root = json!({
            "asset": { "version": "2.0" },
            "scene": 0,
            "scenes": [{ "nodes": self.roots }],
            "nodes": self.nodes,
            "meshes": self.meshes,
            "accessors": self.accessors,
            "bufferViews": self.views,
            "materials": self.materials,
            "textures": self.textures,
            "images": self.images,
            "samplers": self.samplers,
            "cameras": self.cameras,
        });
        let mut buffer = json!({ "byteLength": self.buffer.len() });
        if let Some(uri) = uri {
            buffer["uri"] = json!(uri);
        }
        if !self.buffer.is_empty() {
            root["buffers"] = json!([buffer]);
        }
        if !self.lights.is_empty() {
            root["extensions"] = json!({ "KHR_lights_punctual": { "lights": self.lights } });
        }
        if !self.extensions_used.is_empty() {
            root["extensionsUsed"] = json!(self.extensions_used);
        }
        if !self.extensions_required.is_empty() {
            root["extensionsRequired"] = json!(self.extensions_required);
        }
        root
    }

    /// Writes `dir/name` (a `.gltf`) with the buffer as a data URI.
    pub fn write(&self, dir: &Path, name: &str) -> PathBuf {
        let uri = format!(
            "data:application/octet-stream;base64,{}",
            base64(&self.buffer)
        );
        write_json(dir, name, &self.to_json(Some(uri)))
    }

    /// Writes `dir/name` (a `.gltf`) with the buffer in `dir/bin`, referred to
    /// by `uri` (the file name, percent-encoded as URIs are).
    pub fn write_with_bin(&self, dir: &Path, name: &str, bin: &str, uri: &str) -> PathBuf {
        std::fs::write(dir.join(bin), &self.buffer).unwrap();
        write_json(dir, name, &self.to_json(Some(uri.to_string())))
    }

    /// The file as GLB bytes.
    pub fn glb(&self) -> Vec<u8> {
        let mut json = serde_json::to_vec(&self.to_json(None)).unwrap();
        while !json.len().is_multiple_of(4) {
            json.push(b' ');
        }
        let mut bin = self.buffer.clone();
        while !bin.len().is_multiple_of(4) {
            bin.push(0);
        }
        let total = 12 + 8 + json.len() + 8 + bin.len();
        let mut out = Vec::with_capacity(total);
        out.extend_from_slice(b"glTF");
        out.extend_from_slice(&2u32.to_le_bytes());
        out.extend_from_slice(&(total as u32).to_le_bytes());
        out.extend_from_slice(&(json.len() as u32).to_le_bytes());
        out.extend_from_slice(b"JSON");
        out.extend_from_slice(&json);
        out.extend_from_slice(&(bin.len() as u32).to_le_bytes());
        out.extend_from_slice(b"BIN\0");
        out.extend_from_slice(&bin);
        out
    }
}

/// A quad primitive over `corners` (counter-clockwise seen from the front),
/// indexed as two triangles (0, 1, 2) and (0, 2, 3), with extra attributes.
pub fn quad(g: &mut Gltf, corners: [[f32; 3]; 4], extra: &[(&str, usize)]) -> Value {
    let pos = g.floats(&corners);
    let idx = g.indices(U16, &[0, 1, 2, 0, 2, 3]);
    let mut attributes = json!({ "POSITION": pos });
    for (name, acc) in extra {
        attributes[*name] = json!(acc);
    }
    json!({ "attributes": attributes, "indices": idx })
}

/// The square of side 2 centred on the origin in the z = 0 plane, front +z.
pub const XY_SQUARE: [[f32; 3]; 4] = [
    [-1.0, -1.0, 0.0],
    [1.0, -1.0, 0.0],
    [1.0, 1.0, 0.0],
    [-1.0, 1.0, 0.0],
];

/// A 20 × 20 floor in the y = 0 plane, front +y.
pub const FLOOR: [[f32; 3]; 4] = [
    [-10.0, 0.0, 10.0],
    [10.0, 0.0, 10.0],
    [10.0, 0.0, -10.0],
    [-10.0, 0.0, -10.0],
];

/// A floor for scenes that only need something to look at.
pub fn add_floor(g: &mut Gltf, material: Option<usize>) -> usize {
    let mut p = quad(g, FLOOR, &[]);
    if let Some(m) = material {
        p["material"] = json!(m);
    }
    let mesh = g.mesh(vec![p]);
    g.root(json!({ "mesh": mesh }))
}

/// Loads a file as `raylab render` would, the error as its message.
pub fn load_with(path: &Path, options: &LoadOptions) -> Result<Loaded, String> {
    raylab::load::load(path.to_str().unwrap(), options).map_err(|e| e.to_string())
}

/// Loads a file that must load.
pub fn load(path: &Path) -> Loaded {
    load_with(path, &LoadOptions::default()).unwrap_or_else(|e| panic!("{e}"))
}

/// The error message of a file that must not load.
pub fn load_err(path: &Path) -> String {
    match load_with(path, &LoadOptions::default()) {
        Ok(_) => panic!("{} loaded but should not have", path.display()),
        Err(e) => e,
    }
}

#[track_caller]
pub fn assert_near(got: Vec3A, want: Vec3A, tol: f32, what: &str) {
    assert!(
        (got - want).abs().max_element() <= tol,
        "{what}: got {got}, want {want} (tolerance {tol})"
    );
}

/// Writes `value` as `dir/name`.
pub fn write_json(dir: &Path, name: &str, value: &Value) -> PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, serde_json::to_vec_pretty(value).unwrap()).unwrap();
    path
}

/// Little-endian bytes of `v`.
pub fn bytes_f32(v: &[f32]) -> Vec<u8> {
    v.iter().flat_map(|x| x.to_le_bytes()).collect()
}

/// Standard base64 with padding.
pub fn base64(bytes: &[u8]) -> String {
    const ALPHABET: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut out = String::with_capacity(bytes.len().div_ceil(3) * 4);
    for chunk in bytes.chunks(3) {
        let b = [
            chunk[0],
            *chunk.get(1).unwrap_or(&0),
            *chunk.get(2).unwrap_or(&0),
        ];
        let n = (b[0] as u32) << 16 | (b[1] as u32) << 8 | b[2] as u32;
        for k in 0..4 {
            if k <= chunk.len() {
                out.push(ALPHABET[(n >> (18 - 6 * k) & 63) as usize] as char);
            } else {
                out.push('=');
            }
        }
    }
    out
}

/// A PNG of `w × h` texels of `channels` 8-bit channels (3: RGB, 4: RGBA).
pub fn png(w: u32, h: u32, channels: usize, texels: &[u8]) -> Vec<u8> {
    use image::ImageEncoder;
    use image::codecs::png::PngEncoder;
    assert_eq!(texels.len(), (w * h) as usize * channels);
    let color = match channels {
        3 => image::ExtendedColorType::Rgb8,
        4 => image::ExtendedColorType::Rgba8,
        _ => panic!("{channels} channels"),
    };
    let mut out = Vec::new();
    PngEncoder::new(&mut out)
        .write_image(texels, w, h, color)
        .unwrap();
    out
}

/// An axis-aligned box from `lo` to `hi`, outward-facing.
pub fn cuboid(g: &mut Gltf, lo: [f32; 3], hi: [f32; 3], material: usize) -> Value {
    let p = |i: usize| {
        [
            if i & 1 == 0 { lo[0] } else { hi[0] },
            if i & 2 == 0 { lo[1] } else { hi[1] },
            if i & 4 == 0 { lo[2] } else { hi[2] },
        ]
    };
    let corners: Vec<[f32; 3]> = (0..8).map(p).collect();
    let pos = g.floats(&corners);
    // Counter-clockwise seen from outside.
    let faces: [[u32; 4]; 6] = [
        [0, 2, 3, 1], // -z
        [4, 5, 7, 6], // +z
        [0, 1, 5, 4], // -y
        [2, 6, 7, 3], // +y
        [0, 4, 6, 2], // -x
        [1, 3, 7, 5], // +x
    ];
    let idx: Vec<u32> = faces
        .iter()
        .flat_map(|f| [f[0], f[1], f[2], f[0], f[2], f[3]])
        .collect();
    let idx = g.indices(U32, &idx);
    json!({ "attributes": { "POSITION": pos }, "indices": idx, "material": material })
}
