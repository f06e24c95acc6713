//! The tree a scene file is read into ([`SceneTree`] of [`Object`]s with
//! their [`Value`]s), the reader's limits, and the file lookup Mitsuba's
//! file resolver does.

use std::collections::{BTreeMap, HashSet};
use std::fmt;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use glam::{Mat4, Vec3};

use crate::guard::quote;

/// The most `<include>` levels (Mitsuba's `max_include_depth`): the main
/// file is level 0 and a file at level 15 is refused.
pub const MAX_INCLUDE_DEPTH: usize = 15;

/// The deepest chain of objects, counting those reached through `<ref>`s
/// (real scenes nest fewer than ten); deeper is refused (Mitsuba has no
/// limit, but would recurse as deep when building).
pub const MAX_NESTING: usize = 100;

/// The longest an attribute may grow by `$name` substitution (definitions
/// may hold `$` themselves, so a few bytes could otherwise grow without
/// bound).
pub const MAX_ATTRIBUTE_BYTES: usize = 1 << 20;

/// The most all attributes together may grow by `$name` substitution (real
/// scenes grow by a few kilobytes at most; this keeps a small file from
/// making thousands of attributes of [`MAX_ATTRIBUTE_BYTES`]).
pub const MAX_SUBSTITUTION_BYTES: usize = 16 << 20;

/// The first of `dirs` that holds `name` (an absolute `name` if it
/// exists), as Mitsuba's `FileResolver::resolve`; `None` if none does.
pub(super) fn resolve_in(dirs: &[PathBuf], name: &Path) -> Option<PathBuf> {
    if name.is_absolute() {
        return name.exists().then(|| name.to_owned());
    }
    dirs.iter().map(|d| d.join(name)).find(|p| p.exists())
}

/// A scene file read into a tree: the root object (usually a `<scene>`)
/// and what is needed to find the files its strings name.
#[derive(Clone, Debug)]
pub struct SceneTree {
    /// The root element's object.
    pub root: Arc<Object>,
    /// The main file's format version (`<scene version=…>`, as written; the
    /// tree is already upgraded).
    pub version: Version,
    /// Every file read: the main file first, then included ones in the
    /// order they were read.
    pub files: Vec<PathBuf>,
    /// The folders a relative file name (a mesh, a texture) is looked up in,
    /// first to last: the main file's `<path>` folders (latest first), then
    /// its own folder; see [`SceneTree::resolve`].
    pub search_paths: Vec<PathBuf>,
    /// Things worth telling that Mitsuba accepts silently (properties of an
    /// included `<scene>` root, which are dropped).
    pub warnings: Vec<String>,
}

impl SceneTree {
    /// The file a relative (or absolute) `name` from the scene means: the
    /// first of the search paths that holds it, as Mitsuba's file resolver
    /// finds it at load time; `None` if none does.
    pub fn resolve(&self, name: &str) -> Option<PathBuf> {
        resolve_in(&self.search_paths, Path::new(name))
    }

    /// Every object of the tree once (a shared one once however often it is
    /// referenced), parents before children.
    pub fn objects(&self) -> Vec<Arc<Object>> {
        let mut seen = HashSet::new();
        let mut out = Vec::new();
        let mut stack = vec![self.root.clone()];
        while let Some(o) = stack.pop() {
            if !seen.insert(Arc::as_ptr(&o)) {
                continue;
            }
            for c in o.children.iter().rev() {
                stack.push(c.object.clone());
            }
            out.push(o);
        }
        out
    }

    /// A one-line count of the objects by kind and plugin, for a load
    /// summary: `2 shapes (obj, sphere), 1 bsdf (diffuse), 1 sensor
    /// (perspective)`. Shared objects count once; the root is left out.
    pub fn summary(&self) -> String {
        let mut by_tag: BTreeMap<Tag, BTreeMap<&str, usize>> = BTreeMap::new();
        let objects = self.objects();
        for o in objects.iter().skip(1) {
            *by_tag
                .entry(o.tag)
                .or_default()
                .entry(o.plugin.as_str())
                .or_default() += 1;
        }
        let parts: Vec<String> = by_tag
            .iter()
            .map(|(tag, plugins)| {
                let n: usize = plugins.values().sum();
                let list: Vec<String> = plugins
                    .iter()
                    .map(|(p, k)| match k {
                        1 => quote(p),
                        _ => format!("{} ×{k}", quote(p)),
                    })
                    .collect();
                let noun = if n == 1 {
                    tag.name().to_string()
                } else {
                    tag.plural()
                };
                format!("{n} {noun} ({})", list.join(", "))
            })
            .collect();
        match parts.is_empty() {
            true => "no objects".to_string(),
            false => crate::guard::one_line(&parts.join(", ")).into_owned(),
        }
    }
}

/// The kind of an object: its element's name.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Tag {
    /// `<scene>`.
    Scene,
    /// `<integrator>`.
    Integrator,
    /// `<sensor>`.
    Sensor,
    /// `<film>`.
    Film,
    /// `<rfilter>` (a reconstruction filter).
    Rfilter,
    /// `<sampler>`.
    Sampler,
    /// `<shape>`.
    Shape,
    /// `<bsdf>`.
    Bsdf,
    /// `<emitter>`.
    Emitter,
    /// `<texture>`.
    Texture,
    /// `<spectrum type=…>`: a spectrum plugin (`blackbody`, `d65`,
    /// `regular`…), which Mitsuba files under textures. A `<spectrum>`
    /// without `type` is a value ([`Value::Spectrum`]).
    Spectrum,
    /// `<medium>`.
    Medium,
    /// `<phase>` (a phase function).
    Phase,
    /// `<volume>`.
    Volume,
}

impl Tag {
    /// The tag of an object element, `None` for any other element.
    pub fn from_element(name: &str) -> Option<Tag> {
        Some(match name {
            "scene" => Tag::Scene,
            "integrator" => Tag::Integrator,
            "sensor" => Tag::Sensor,
            "film" => Tag::Film,
            "rfilter" => Tag::Rfilter,
            "sampler" => Tag::Sampler,
            "shape" => Tag::Shape,
            "bsdf" => Tag::Bsdf,
            "emitter" => Tag::Emitter,
            "texture" => Tag::Texture,
            "medium" => Tag::Medium,
            "phase" => Tag::Phase,
            "volume" => Tag::Volume,
            _ => return None,
        })
    }

    /// The element's name (`"bsdf"`).
    pub fn name(self) -> &'static str {
        match self {
            Tag::Scene => "scene",
            Tag::Integrator => "integrator",
            Tag::Sensor => "sensor",
            Tag::Film => "film",
            Tag::Rfilter => "rfilter",
            Tag::Sampler => "sampler",
            Tag::Shape => "shape",
            Tag::Bsdf => "bsdf",
            Tag::Emitter => "emitter",
            Tag::Texture => "texture",
            Tag::Spectrum => "spectrum",
            Tag::Medium => "medium",
            Tag::Phase => "phase",
            Tag::Volume => "volume",
        }
    }

    /// The name for several (`"bsdfs"`, `"media"`).
    fn plural(self) -> String {
        match self {
            Tag::Medium => "media".into(),
            t => format!("{}s", t.name()),
        }
    }
}

impl fmt::Display for Tag {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// Where something was written: the file and its 1-based line.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct Location {
    /// The file (as the user named it, or joined to its includer's folder).
    pub file: Arc<Path>,
    /// 1-based line of the element's start.
    pub line: u32,
}

impl fmt::Display for Location {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}:{}", self.file.display(), self.line)
    }
}

/// One object of the scene: an element such as `<bsdf type="diffuse">`, with
/// its properties and the objects inside it or referenced from it.
#[derive(Clone, Debug, PartialEq)]
pub struct Object {
    /// Its kind (the element).
    pub tag: Tag,
    /// The plugin (`type`; `"scene"` for a root without one).
    pub plugin: String,
    /// Its `id`, if given.
    pub id: Option<String>,
    /// Its own `name` attribute, if given (upgraded in a 0.x file); the
    /// name its parent uses is [`Child::name`], which differs for a
    /// referenced object.
    pub name: Option<String>,
    /// Its values, in document order.
    pub props: Vec<Property>,
    /// The objects it holds, nested or referenced, in document order.
    pub children: Vec<Child>,
    /// Where its element starts.
    pub location: Location,
}

impl Object {
    /// The property `name`, if given.
    pub fn prop(&self, name: &str) -> Option<&Property> {
        self.props.iter().find(|p| p.name == name)
    }

    /// The value of the property `name`, if given.
    pub fn value(&self, name: &str) -> Option<&Value> {
        self.prop(name).map(|p| &p.value)
    }

    /// The child object named `name` (by `name=` on it or on its `<ref>`).
    pub fn child(&self, name: &str) -> Option<&Arc<Object>> {
        self.children
            .iter()
            .find(|c| c.name.as_deref() == Some(name))
            .map(|c| &c.object)
    }

    /// The child objects of kind `tag`, in order.
    pub fn children_of(&self, tag: Tag) -> impl Iterator<Item = &Arc<Object>> {
        self.children
            .iter()
            .map(|c| &c.object)
            .filter(move |o| o.tag == tag)
    }

    /// How the object is named in messages: `bsdf 'diffuse'` (with its id
    /// if it has one).
    pub fn describe(&self) -> String {
        let plugin = quote(&self.plugin);
        match &self.id {
            Some(id) => format!("{} '{plugin}' (id '{}')", self.tag, quote(id)),
            None => format!("{} '{plugin}'", self.tag),
        }
    }
}

/// An object as its parent holds it.
#[derive(Clone, Debug, PartialEq)]
pub struct Child {
    /// The name the parent knows it by: the `name` of the nested element,
    /// of the `<ref>`, or of the `<include>`; `None` for an unnamed one
    /// (Mitsuba's `_arg_N`).
    pub name: Option<String>,
    /// The object. A referenced one is the same [`Arc`] wherever it is
    /// referenced (compare with [`Arc::ptr_eq`]): a material or a shape
    /// group used a thousand times is one object, built once.
    pub object: Arc<Object>,
    /// Where the nested element or the `<ref>` is.
    pub location: Location,
    /// Whether it came from a `<ref>` (else it is nested, or included).
    pub by_ref: bool,
}

/// A named value of an object.
#[derive(Clone, Debug, PartialEq)]
pub struct Property {
    /// The name (`name=`, upgraded in a 0.x file).
    pub name: String,
    /// The value.
    pub value: Value,
    /// Where its element is.
    pub location: Location,
}

/// A property's value. Numbers are read in `f64` (as Mitsuba's parser
/// does) and stored in the `f32` of Mitsuba's `scalar_rgb` plugins.
#[derive(Clone, Debug, PartialEq)]
pub enum Value {
    /// `<float>`.
    Float(f32),
    /// `<integer>`.
    Integer(i64),
    /// `<boolean>`.
    Boolean(bool),
    /// `<string>` (named presets such as `int_ior="bk7"` or
    /// `material="Au"` are strings in Mitsuba too).
    String(String),
    /// `<rgb>` (one value is a grey: all three the same).
    Rgb([f32; 3]),
    /// `<spectrum>` without `type`.
    Spectrum(Spectrum),
    /// `<point>`.
    Point(Vec3),
    /// `<vector>`.
    Vector(Vec3),
    /// `<transform>`: the composed matrix (column vectors: a point `p`
    /// becomes `m * p`).
    Transform(Mat4),
}

impl Value {
    /// The element name of the value's kind (`"float"`), for messages.
    pub fn kind(&self) -> &'static str {
        match self {
            Value::Float(_) => "float",
            Value::Integer(_) => "integer",
            Value::Boolean(_) => "boolean",
            Value::String(_) => "string",
            Value::Rgb(_) => "rgb",
            Value::Spectrum(_) => "spectrum",
            Value::Point(_) => "point",
            Value::Vector(_) => "vector",
            Value::Transform(_) => "transform",
        }
    }
}

/// A `<spectrum>` value.
#[derive(Clone, Debug, PartialEq)]
pub enum Spectrum {
    /// `value="0.5"`: the same at every wavelength.
    Constant(f32),
    /// `value="400:0.1, 500:0.5, …"`: (wavelength in nm, value) pairs, at
    /// least two, wavelengths increasing; linear between them and zero
    /// outside, in Mitsuba.
    Sampled(Vec<(f32, f32)>),
    /// `filename="…"`: a measured spectrum (`.spd` text or `.spb`), the
    /// path found through the search paths; not read yet.
    File(PathBuf),
}

/// A scene format version (`version="3.0.0"`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct Version {
    /// Major version.
    pub major: u32,
    /// Minor version.
    pub minor: u32,
    /// Patch version.
    pub patch: u32,
}

impl Version {
    /// The first version of the current format: files older than this are
    /// upgraded.
    pub const V2: Version = Version {
        major: 2,
        minor: 0,
        patch: 0,
    };

    /// Reads `major.minor.patch` (Mitsuba splits at dots and spaces and
    /// wants exactly three parts; raylab also wants each to be digits).
    pub fn parse(text: &str) -> Result<Version, String> {
        let parts: Vec<&str> = text
            .split(['.', ' '])
            .filter(|p| !p.is_empty())
            .take(4)
            .collect();
        let bad = || {
            format!(
                "invalid version number \"{}\" (expected major.minor.patch, e.g. \"3.0.0\")",
                quote(text)
            )
        };
        let [a, b, c] = parts.as_slice() else {
            return Err(bad());
        };
        let n = |p: &str| match p.bytes().all(|b| b.is_ascii_digit()) {
            true => p.parse::<u32>().map_err(|_| bad()),
            false => Err(bad()),
        };
        Ok(Version {
            major: n(a)?,
            minor: n(b)?,
            patch: n(c)?,
        })
    }
}

impl fmt::Display for Version {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}.{}.{}", self.major, self.minor, self.patch)
    }
}
