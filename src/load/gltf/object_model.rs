//! The glTF 2.0 Asset Object Model's animatable properties, as
//! `KHR_animation_pointer` names them: a JSON pointer (RFC 6901) read into
//! its members, and what it names — the object that owns the property (a
//! material, a camera, a node or a `KHR_lights_punctual` light), the path
//! from that object down to the property, the property's type, and whether
//! raylab renders it.
//!
//! The tables follow the Object Model specification
//! (`specification/2.0/ObjectModel.adoc` in KhronosGroup/glTF) and the
//! pointers the extensions define for themselves (`KHR_node_visibility`).
//! `KHR_materials_diffuse_transmission`, a release candidate the Object
//! Model does not list yet, is animatable the way the other material
//! extensions are: its two factors and its textures' transforms.
//! `KHR_texture_transform`'s `offset`, `rotation` and `scale` are animatable
//! on every texture of a material (the Object Model: "all properties of
//! textureInfo type, including texture properties defined in other
//! extensions").
//!
//! What a pointer names is decided from the pointer alone; whether the file
//! has that object and property is checked by the caller
//! (`pointer.rs`).

use std::borrow::Cow;
use std::fmt;

use ValueType::{Bool, Float, Float3, Float4, Quaternion};

/// The Object Model's data type of an animatable property.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum ValueType {
    /// One number.
    Float,
    /// Two numbers (a texture's offset or scale).
    Float2,
    /// Three numbers (a colour, a translation).
    Float3,
    /// Four numbers (the base colour with alpha).
    Float4,
    /// A node's rotation: four numbers x, y, z, w, interpolated as a
    /// rotation (slerp) and normalized, as core `rotation` channels are.
    Quaternion,
    /// `true` or `false`; keyframes of unsigned bytes (0 is `false`), `STEP`
    /// only.
    Bool,
    /// A node's morph-target weights: one number per target.
    FloatArray,
}

impl ValueType {
    /// Components per element of the output accessor: `SCALAR` 1, `VEC2`
    /// 2, `VEC3` 3, `VEC4` 4 (an array's elements are scalars).
    pub fn accessor_components(self) -> usize {
        match self {
            Self::Float | Self::Bool | Self::FloatArray => 1,
            Self::Float2 => 2,
            Self::Float3 => 3,
            Self::Float4 | Self::Quaternion => 4,
        }
    }

    /// The Object Model's name of the type.
    pub fn name(self) -> &'static str {
        match self {
            Self::Float => "float",
            Self::Float2 => "float2",
            Self::Float3 => "float3",
            Self::Float4 | Self::Quaternion => "float4",
            Self::Bool => "bool",
            Self::FloatArray => "float[]",
        }
    }
}

/// The glTF object an animated property belongs to (an index into its
/// array).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub(crate) enum Owner {
    /// `materials[i]`.
    Material(usize),
    /// `cameras[i]`.
    Camera(usize),
    /// `nodes[i]`.
    Node(usize),
    /// `extensions.KHR_lights_punctual.lights[i]`.
    Light(usize),
}

impl fmt::Display for Owner {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Material(i) => write!(f, "material {i}"),
            Self::Camera(i) => write!(f, "camera {i}"),
            Self::Node(i) => write!(f, "node {i}"),
            Self::Light(i) => write!(f, "light {i}"),
        }
    }
}

/// An animatable property a pointer names.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Property {
    /// The object it belongs to.
    pub owner: Owner,
    /// JSON members from the owner down to it (a node's weight: `weights`
    /// and the element's index).
    pub path: Vec<String>,
    /// Its type.
    pub value: ValueType,
    /// Whether it has a default value, so that it is defined (and may be
    /// animated) where the file leaves it out but writes the object that
    /// holds it.
    pub has_default: bool,
    /// Why raylab does not render it, if it does not: such a channel is
    /// checked, then skipped with a warning.
    pub unrendered: Option<&'static str>,
}

/// What a pointer names.
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum Named {
    /// An animatable property.
    Property(Property),
    /// Something raylab does not read (`extras`, an extension it does not
    /// know): a channel animating it is skipped with a warning saying why.
    Unread {
        /// The object it lies in, if raylab knows that kind of object.
        owner: Option<Owner>,
        /// Why it is skipped.
        why: String,
    },
}

/// Why an occlusion texture's animation is not rendered.
const OCCLUSION: &str = "raylab does not read occlusion textures (the path tracer finds occlusion)";
/// Why a camera's clipping planes are not rendered.
const CLIPPING: &str = "raylab's cameras have no clipping planes (znear and zfar are ignored)";
/// Why a light's range is not rendered.
const RANGE: &str = "raylab ignores a light's range (inverse-square falloff everywhere)";
/// Why a volume's thickness texture is not rendered.
const THICKNESS: &str = "raylab reads only KHR_materials_volume's thicknessFactor, not its texture";

/// Animatable properties of one kind of object: groups of (the members
/// leading to them joined by `/`, with a trailing `/`; the properties' names
/// and types).
type Table = &'static [(&'static str, &'static [(&'static str, ValueType)])];

/// A material's animatable factors.
const MATERIAL: Table = &[
    ("", &[("alphaCutoff", Float), ("emissiveFactor", Float3)]),
    ("normalTexture/", &[("scale", Float)]),
    ("occlusionTexture/", &[("strength", Float)]),
    (
        "pbrMetallicRoughness/",
        &[
            ("baseColorFactor", Float4),
            ("metallicFactor", Float),
            ("roughnessFactor", Float),
        ],
    ),
    (
        "extensions/KHR_materials_anisotropy/",
        &[("anisotropyStrength", Float), ("anisotropyRotation", Float)],
    ),
    (
        "extensions/KHR_materials_clearcoat/",
        &[
            ("clearcoatFactor", Float),
            ("clearcoatRoughnessFactor", Float),
        ],
    ),
    (
        "extensions/KHR_materials_clearcoat/clearcoatNormalTexture/",
        &[("scale", Float)],
    ),
    (
        "extensions/KHR_materials_diffuse_transmission/",
        &[
            ("diffuseTransmissionFactor", Float),
            ("diffuseTransmissionColorFactor", Float3),
        ],
    ),
    (
        "extensions/KHR_materials_dispersion/",
        &[("dispersion", Float)],
    ),
    (
        "extensions/KHR_materials_emissive_strength/",
        &[("emissiveStrength", Float)],
    ),
    ("extensions/KHR_materials_ior/", &[("ior", Float)]),
    (
        "extensions/KHR_materials_iridescence/",
        &[
            ("iridescenceFactor", Float),
            ("iridescenceIor", Float),
            ("iridescenceThicknessMinimum", Float),
            ("iridescenceThicknessMaximum", Float),
        ],
    ),
    (
        "extensions/KHR_materials_sheen/",
        &[
            ("sheenColorFactor", Float3),
            ("sheenRoughnessFactor", Float),
        ],
    ),
    (
        "extensions/KHR_materials_specular/",
        &[("specularFactor", Float), ("specularColorFactor", Float3)],
    ),
    (
        "extensions/KHR_materials_transmission/",
        &[("transmissionFactor", Float)],
    ),
    (
        "extensions/KHR_materials_volume/",
        &[
            ("thicknessFactor", Float),
            ("attenuationDistance", Float),
            ("attenuationColor", Float3),
        ],
    ),
];

/// A material's textures (their paths below the material) whose
/// `KHR_texture_transform` is animatable: groups as in [`Table`].
const TEXTURES: &[(&str, &[&str])] = &[
    (
        "",
        &["normalTexture", "occlusionTexture", "emissiveTexture"],
    ),
    (
        "pbrMetallicRoughness/",
        &["baseColorTexture", "metallicRoughnessTexture"],
    ),
    (
        "extensions/KHR_materials_anisotropy/",
        &["anisotropyTexture"],
    ),
    (
        "extensions/KHR_materials_clearcoat/",
        &[
            "clearcoatTexture",
            "clearcoatRoughnessTexture",
            "clearcoatNormalTexture",
        ],
    ),
    (
        "extensions/KHR_materials_diffuse_transmission/",
        &[
            "diffuseTransmissionTexture",
            "diffuseTransmissionColorTexture",
        ],
    ),
    (
        "extensions/KHR_materials_iridescence/",
        &["iridescenceTexture", "iridescenceThicknessTexture"],
    ),
    (
        "extensions/KHR_materials_pbrSpecularGlossiness/",
        &["diffuseTexture", "specularGlossinessTexture"],
    ),
    (
        "extensions/KHR_materials_sheen/",
        &["sheenColorTexture", "sheenRoughnessTexture"],
    ),
    (
        "extensions/KHR_materials_specular/",
        &["specularTexture", "specularColorTexture"],
    ),
    (
        "extensions/KHR_materials_transmission/",
        &["transmissionTexture"],
    ),
    ("extensions/KHR_materials_volume/", &["thicknessTexture"]),
];

/// A camera's animatable numbers.
const CAMERA: Table = &[
    (
        "perspective/",
        &[
            ("yfov", Float),
            ("aspectRatio", Float),
            ("znear", Float),
            ("zfar", Float),
        ],
    ),
    (
        "orthographic/",
        &[
            ("xmag", Float),
            ("ymag", Float),
            ("znear", Float),
            ("zfar", Float),
        ],
    ),
];

/// A `KHR_lights_punctual` light's animatable numbers.
const LIGHT: Table = &[
    (
        "",
        &[("color", Float3), ("intensity", Float), ("range", Float)],
    ),
    (
        "spot/",
        &[("innerConeAngle", Float), ("outerConeAngle", Float)],
    ),
];

/// A node's animatable properties (its weights, by array or element, are
/// matched apart).
const NODE: Table = &[
    (
        "",
        &[
            ("translation", Float3),
            ("rotation", Quaternion),
            ("scale", Float3),
        ],
    ),
    ("extensions/KHR_node_visibility/", &[("visible", Bool)]),
];

/// Animatable properties without a default value (paths below their
/// object): a camera's are required or optional without a default
/// (`aspectRatio`, a perspective `zfar`), a light's `range` is infinite
/// when left out. Every other animatable property has a default.
fn has_default(owner: Owner, path: &str) -> bool {
    !matches!(owner, Owner::Camera(_)) && !matches!((owner, path), (Owner::Light(_), "range"))
}

/// Why raylab does not render the property at `path` below `owner`, if it
/// does not (texture paths end in `/KHR_texture_transform`).
fn unrendered(owner: Owner, path: &str) -> Option<&'static str> {
    match owner {
        Owner::Material(_) if path.starts_with("occlusionTexture/") => Some(OCCLUSION),
        Owner::Material(_)
            if path.starts_with("extensions/KHR_materials_volume/thicknessTexture/") =>
        {
            Some(THICKNESS)
        }
        Owner::Camera(_) if path.ends_with("/znear") || path.ends_with("/zfar") => Some(CLIPPING),
        Owner::Light(_) if path == "range" => Some(RANGE),
        _ => None,
    }
}

/// The type of the property at `path` below an object with properties
/// `table`, if it has one there.
fn lookup(table: Table, path: &str) -> Option<ValueType> {
    table.iter().find_map(|(prefix, names)| {
        let name = path.strip_prefix(prefix)?;
        names.iter().find(|n| n.0 == name).map(|n| n.1)
    })
}

/// Whether `texture` (its path below a material) is a material texture.
fn is_texture(texture: &str) -> bool {
    TEXTURES.iter().any(|(prefix, names)| {
        texture
            .strip_prefix(prefix)
            .is_some_and(|name| names.contains(&name))
    })
}

/// The members of JSON pointer `pointer` (RFC 6901): `""` is the whole
/// document (no members); otherwise it starts with `/`, members are
/// separated by `/`, and `~1` and `~0` stand for `/` and `~` (any other `~`
/// is an error).
pub(crate) fn parse_pointer(pointer: &str) -> Result<Vec<String>, String> {
    if pointer.is_empty() {
        return Ok(Vec::new());
    }
    let Some(rest) = pointer.strip_prefix('/') else {
        return Err("a JSON pointer starts with '/'".into());
    };
    rest.split('/')
        .map(|token| {
            let mut out = String::with_capacity(token.len());
            let mut chars = token.chars();
            while let Some(c) = chars.next() {
                if c != '~' {
                    out.push(c);
                    continue;
                }
                match chars.next() {
                    Some('0') => out.push('~'),
                    Some('1') => out.push('/'),
                    _ => return Err("'~' must be followed by 0 or 1 (RFC 6901)".into()),
                }
            }
            Ok(out)
        })
        .collect()
}

/// `member` as an array index (RFC 6901: `0`, or digits without a leading
/// zero).
fn array_index(member: &str) -> Result<usize, String> {
    let digits = !member.is_empty() && member.bytes().all(|b| b.is_ascii_digit());
    if !digits || (member.len() > 1 && member.starts_with('0')) {
        return Err(format!(
            "'{}' is not an array index",
            crate::guard::quote(member)
        ));
    }
    member.parse().map_err(|_| {
        format!(
            "array index {} is out of range",
            crate::guard::quote(member)
        )
    })
}

/// The refusal of a pointer that names nothing animatable.
fn not_animatable() -> String {
    "names no animatable property (see the glTF Object Model)".into()
}

/// What the pointer of members `members` names. `reads(name)` says whether
/// raylab reads the extension `name`: a pointer into an extension it does
/// not read, or into `extras`, names something [`Named::Unread`]; a
/// pointer into one it reads must name an animatable property.
pub(crate) fn resolve(members: &[String], reads: &dyn Fn(&str) -> bool) -> Result<Named, String> {
    let m: Vec<&str> = members.iter().map(String::as_str).collect();
    let (owner, rest) = match m.as_slice() {
        ["materials", i, rest @ ..] => (Owner::Material(array_index(i)?), rest),
        ["cameras", i, rest @ ..] => (Owner::Camera(array_index(i)?), rest),
        ["nodes", i, rest @ ..] => (Owner::Node(array_index(i)?), rest),
        ["extensions", "KHR_lights_punctual", "lights", i, rest @ ..] => {
            (Owner::Light(array_index(i)?), rest)
        }
        _ => {
            return match unread(&m, reads) {
                Some(why) => Ok(Named::Unread { owner: None, why }),
                None => Err(not_animatable()),
            };
        }
    };
    if let Some(why) = unread(rest, reads) {
        return Ok(Named::Unread {
            owner: Some(owner),
            why,
        });
    }
    let joined = rest.join("/");
    let property = |value| {
        Ok(Named::Property(Property {
            owner,
            path: rest.iter().map(|s| s.to_string()).collect(),
            value,
            has_default: has_default(owner, &joined),
            unrendered: unrendered(owner, &joined),
        }))
    };
    let table = match owner {
        Owner::Material(_) => MATERIAL,
        Owner::Camera(_) => CAMERA,
        Owner::Node(_) => NODE,
        Owner::Light(_) => LIGHT,
    };
    if let Some(value) = lookup(table, &joined) {
        return property(value);
    }
    match (owner, rest) {
        (Owner::Node(_), ["weights"]) => property(ValueType::FloatArray),
        (Owner::Node(_), ["weights", k]) => {
            array_index(k)?;
            property(ValueType::Float)
        }
        (Owner::Material(_), [texture @ .., "extensions", "KHR_texture_transform", member])
            if is_texture(&texture.join("/")) =>
        {
            match *member {
                "offset" | "scale" => property(ValueType::Float2),
                "rotation" => property(ValueType::Float),
                _ => Err(not_animatable()),
            }
        }
        _ => Err(not_animatable()),
    }
}

/// Why raylab skips what members `m` name, if they lie in `extras` or in
/// an extension it does not read.
fn unread(m: &[&str], reads: &dyn Fn(&str) -> bool) -> Option<String> {
    if m.contains(&"extras") {
        return Some("raylab reads no extras".into());
    }
    let name = m
        .windows(2)
        .find(|w| w[0] == "extensions" && !reads(w[1]))
        .map(|w| w[1])?;
    Some(format!(
        "raylab does not read the extension {}",
        crate::guard::quote(&crate::guard::one_line(name))
    ))
}

/// The pointer of `members` with every array index written `{}`, as the
/// Object Model writes its templates (for warnings that name a kind of
/// property once).
pub(crate) fn template(members: &[String]) -> String {
    let mut out = String::new();
    for m in members {
        out.push('/');
        if !m.is_empty() && m.bytes().all(|b| b.is_ascii_digit()) {
            out.push_str("{}");
        } else {
            out.push_str(&m.replace('~', "~0").replace('/', "~1"));
        }
    }
    crate::guard::one_line(&out).into_owned()
}

/// A pointer as quoted in messages: on one line, cut after 200 characters,
/// and `""` when empty.
pub(crate) fn quoted(pointer: &str) -> Cow<'_, str> {
    const MOST: usize = 200;
    if pointer.is_empty() {
        return "\"\"".into();
    }
    let line = crate::guard::one_line(pointer);
    match line.char_indices().nth(MOST) {
        None => line,
        Some((cut, _)) => format!("{}… ({} bytes)", &line[..cut], pointer.len()).into(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn reads(name: &str) -> bool {
        name.starts_with("KHR_") && name != "KHR_materials_unknown"
    }

    fn named(pointer: &str) -> Result<Named, String> {
        resolve(&parse_pointer(pointer)?, &reads)
    }

    fn property(pointer: &str) -> Property {
        match named(pointer) {
            Ok(Named::Property(p)) => p,
            other => panic!("{pointer}: {other:?}"),
        }
    }

    #[test]
    fn pointers_follow_rfc_6901() {
        assert_eq!(parse_pointer(""), Ok(vec![]));
        assert_eq!(parse_pointer("/"), Ok(vec![String::new()]));
        assert_eq!(
            parse_pointer("/a~1b/c~0d/~01"),
            Ok(vec!["a/b".into(), "c~d".into(), "~1".into()])
        );
        assert!(
            parse_pointer("materials/0")
                .unwrap_err()
                .contains("starts with '/'")
        );
        assert!(
            parse_pointer("/a~2")
                .unwrap_err()
                .contains("'~' must be followed")
        );
        assert!(parse_pointer("/a~").is_err());
    }

    #[test]
    fn core_properties_have_their_types() {
        let p = property("/materials/3/pbrMetallicRoughness/baseColorFactor");
        assert_eq!(
            (p.owner, p.value, p.has_default),
            (Owner::Material(3), ValueType::Float4, true)
        );
        assert_eq!(p.path, ["pbrMetallicRoughness", "baseColorFactor"]);
        assert_eq!(property("/nodes/0/rotation").value, ValueType::Quaternion);
        assert_eq!(property("/nodes/0/weights").value, ValueType::FloatArray);
        assert_eq!(property("/nodes/0/weights/2").value, ValueType::Float);
        let c = property("/cameras/1/perspective/aspectRatio");
        assert_eq!((c.owner, c.has_default), (Owner::Camera(1), false));
        let l = property("/extensions/KHR_lights_punctual/lights/2/spot/outerConeAngle");
        assert_eq!((l.owner, l.value), (Owner::Light(2), ValueType::Float));
        let v = property("/nodes/4/extensions/KHR_node_visibility/visible");
        assert_eq!(v.value, ValueType::Bool);
        // What raylab does not render, and what has no default.
        let z = property("/cameras/0/orthographic/zfar");
        assert_eq!((z.unrendered, z.has_default), (Some(CLIPPING), false));
        let r = property("/extensions/KHR_lights_punctual/lights/0/range");
        assert_eq!((r.unrendered, r.has_default), (Some(RANGE), false));
        let t = property(
            "/materials/0/extensions/KHR_materials_volume/thicknessTexture/extensions/KHR_texture_transform/offset",
        );
        assert_eq!((t.unrendered, t.has_default), (Some(THICKNESS), true));
        assert_eq!(property("/materials/0/alphaCutoff").unrendered, None);
    }

    #[test]
    fn texture_transforms_of_every_material_texture_are_animatable() {
        let p = property(
            "/materials/0/pbrMetallicRoughness/baseColorTexture/extensions/KHR_texture_transform/offset",
        );
        assert_eq!((p.value, p.unrendered), (ValueType::Float2, None));
        let p = property(
            "/materials/0/extensions/KHR_materials_sheen/sheenColorTexture/extensions/KHR_texture_transform/rotation",
        );
        assert_eq!(p.value, ValueType::Float);
        let p = property("/materials/0/occlusionTexture/extensions/KHR_texture_transform/scale");
        assert_eq!(p.unrendered, Some(OCCLUSION));
        // texCoord is not animatable.
        assert!(
            named("/materials/0/emissiveTexture/extensions/KHR_texture_transform/texCoord")
                .is_err()
        );
    }

    #[test]
    fn what_is_not_animatable_is_refused() {
        for pointer in [
            "",
            "/materials/0/doubleSided",
            "/materials/0/pbrMetallicRoughness/baseColorFactor/0",
            "/meshes/0/weights",
            "/nodes/0/mesh",
            "/nodes/0/matrix",
            "/materials/01/alphaCutoff",
            "/materials/-1/alphaCutoff",
            "/materials/x/alphaCutoff",
            "/nodes/0/weights/01",
            "/extensions/KHR_lights_punctual/lights/0/type",
            "/materials/0/extensions/KHR_materials_unlit/x",
        ] {
            assert!(named(pointer).is_err(), "{pointer}");
        }
        assert!(
            named("/materials/x/alphaCutoff")
                .unwrap_err()
                .contains("'x' is not an array index")
        );
    }

    #[test]
    fn extras_and_unread_extensions_are_skipped_with_a_reason() {
        for (pointer, owner, why) in [
            (
                "/materials/0/extras/glow",
                Some(Owner::Material(0)),
                "extras",
            ),
            (
                "/extensions/EXT_lights_image_based/lights/0/intensity",
                None,
                "EXT_lights_image_based",
            ),
            (
                "/nodes/1/extensions/EXT_lights_ies/multiplier",
                Some(Owner::Node(1)),
                "EXT_lights_ies",
            ),
            (
                "/materials/2/extensions/KHR_materials_unknown/x",
                Some(Owner::Material(2)),
                "KHR_materials_unknown",
            ),
        ] {
            match named(pointer) {
                Ok(Named::Unread { owner: o, why: w }) => {
                    assert_eq!(o, owner, "{pointer}");
                    assert!(w.contains(why), "{pointer}: {w}");
                }
                other => panic!("{pointer}: {other:?}"),
            }
        }
    }

    #[test]
    fn templates_hide_indices() {
        let m = parse_pointer("/materials/12/occlusionTexture/strength").unwrap();
        assert_eq!(template(&m), "/materials/{}/occlusionTexture/strength");
        assert_eq!(quoted(""), "\"\"");
        assert_eq!(
            quoted(&"x".repeat(300)).chars().count(),
            200 + " (300 bytes)".len() + 1
        );
    }
}
