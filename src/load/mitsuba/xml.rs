//! The walk over a Mitsuba XML file (Mitsuba's `parse_xml_node`,
//! `parse_file_impl` and `transform_resolve` in `parser.cpp`): elements
//! become objects and properties of a flat table ([`Node`]s), `<include>`d
//! files are read into the same table, and at the end references are
//! resolved, cycles refused, old files upgraded and the table turned into
//! the tree of shared objects ([`super::SceneTree`]).
//!
//! Elements are handled as Mitsuba does, in document order: `$name`
//! substitution first (so a `<default>` must come before its use), then the
//! attribute check (every attribute known, the required ones present),
//! then the element itself. References are resolved only at the end, so a
//! `<ref>` may name an object written after it.

mod include;

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use glam::DMat4;
use roxmltree::{Document, ParsingOptions};

use super::attrs::Attrs;
use super::build;
use super::error::MitsubaError;
use super::table::{Edge, Node, Target};
use super::transform;
use super::tree::{
    Location, MAX_ATTRIBUTE_BYTES, MAX_NESTING, MAX_SUBSTITUTION_BYTES, Property, SceneTree,
    Spectrum, Tag, Value, Version, resolve_in,
};
use super::upgrade;
use super::values;
use crate::guard::quote;

/// A `$name` definition: from `-D` or a `<default>`.
struct Param {
    /// `$name`.
    key: String,
    value: String,
    used: bool,
    /// Given with `-D` (an unused one is an error).
    defined: bool,
}

/// One file being read.
struct Doc<'a, 'input> {
    doc: &'a Document<'input>,
    /// Byte offsets of the line breaks, for line numbers.
    breaks: Vec<usize>,
    path: Arc<Path>,
    dir: PathBuf,
    file: usize,
    depth: usize,
}

impl Doc<'_, '_> {
    fn line(&self, node: roxmltree::Node) -> u32 {
        let at = node.range().start;
        let line = self.breaks.partition_point(|&b| b < at) + 1;
        u32::try_from(line).unwrap_or(u32::MAX)
    }

    fn location(&self, node: roxmltree::Node) -> Location {
        Location {
            file: self.path.clone(),
            line: self.line(node),
        }
    }
}

/// The reader's state across files.
struct Reader {
    nodes: Vec<Node>,
    ids: HashMap<String, (usize, Location)>,
    /// Longest key first (Mitsuba's order, so that `$ab` is replaced before
    /// `$a`).
    params: Vec<Param>,
    versions: Vec<Version>,
    files: Vec<PathBuf>,
    /// The folders files are looked up in, first to last.
    search: Vec<PathBuf>,
    /// The files being read (canonical paths and names), outermost first.
    reading: Vec<(PathBuf, Arc<Path>)>,
    warnings: Vec<String>,
    /// How much substitution has grown the attributes so far.
    grown: usize,
}

/// The folder of `path` (`.` for a bare file name).
fn dir_of(path: &Path) -> PathBuf {
    match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_owned(),
        _ => PathBuf::from("."),
    }
}

/// Reads the scene file `path`.
pub(crate) fn read_file(
    path: &Path,
    defines: &[(String, String)],
) -> Result<SceneTree, MitsubaError> {
    let text = read_text_file(path)?;
    read_text(&text, path, defines)
}

/// The text of `path`; not UTF-8 is an error naming the line.
fn read_text_file(path: &Path) -> Result<String, MitsubaError> {
    let bytes = std::fs::read(path).map_err(|cause| MitsubaError::Io {
        path: path.to_owned(),
        cause,
    })?;
    String::from_utf8(bytes).map_err(|e| {
        let good = &e.as_bytes()[..e.utf8_error().valid_up_to()];
        let line = good.iter().filter(|&&b| b == b'\n').count() + 1;
        MitsubaError::at(
            path,
            u32::try_from(line).unwrap_or(u32::MAX),
            "the file is not UTF-8 text (raylab reads UTF-8 and ASCII scenes)",
        )
    })
}

/// Reads `text` as the scene file `path`.
pub(super) fn read_text(
    text: &str,
    path: &Path,
    defines: &[(String, String)],
) -> Result<SceneTree, MitsubaError> {
    let mut params: Vec<Param> = Vec::new();
    for (k, v) in defines {
        let key = format!("${k}");
        match params.iter_mut().find(|p| p.key == key) {
            Some(p) => p.value = v.clone(),
            None => params.push(Param {
                key,
                value: v.clone(),
                used: false,
                defined: true,
            }),
        }
    }
    params.sort_by_key(|p| std::cmp::Reverse(p.key.len()));
    let mut r = Reader {
        nodes: Vec::new(),
        ids: HashMap::new(),
        params,
        versions: Vec::new(),
        files: Vec::new(),
        search: vec![dir_of(path)],
        reading: Vec::new(),
        warnings: Vec::new(),
        grown: 0,
    };
    let canonical = std::fs::canonicalize(path).unwrap_or_else(|_| path.to_owned());
    r.reading.push((canonical, Arc::from(path)));
    let root = r.document(text, path, 0)?;
    let unused: Vec<String> = r
        .params
        .iter()
        .filter(|p| p.defined && !p.used)
        .map(|p| format!("-D {}={}", quote(&p.key[1..]), quote(&p.value)))
        .collect();
    if !unused.is_empty() {
        return Err(MitsubaError::Scene {
            path: path.to_owned(),
            message: crate::guard::one_line(&format!(
                "unused parameter{} {} (no attribute uses it)",
                if unused.len() == 1 { "" } else { "s" },
                unused.join(", ")
            ))
            .into_owned(),
        });
    }
    for node in &mut r.nodes {
        if r.versions[node.file] < Version::V2 {
            upgrade::upgrade_v1(node).map_err(|m| {
                MitsubaError::at(
                    &node.location.file,
                    node.location.line,
                    format!(
                        "{} (upgrading a format {} file): {m}",
                        node.describe(),
                        r.versions[node.file]
                    ),
                )
            })?;
        }
    }
    let root_object = build::build(std::mem::take(&mut r.nodes), &r.ids, root)?;
    Ok(SceneTree {
        root: root_object,
        version: r.versions[0],
        files: r.files,
        search_paths: r.search,
        warnings: r.warnings,
    })
}

impl Reader {
    /// Reads one file's text: its root element becomes a node (returned).
    fn document(&mut self, text: &str, path: &Path, depth: usize) -> Result<usize, MitsubaError> {
        let text = text.strip_prefix('\u{feff}').unwrap_or(text);
        let options = ParsingOptions {
            allow_dtd: true,
            ..ParsingOptions::default()
        };
        let doc = Document::parse_with_options(text, options).map_err(|e| {
            let line = match e {
                roxmltree::Error::UnexpectedEndOfStream => text.lines().count().max(1),
                _ => e.pos().row as usize,
            };
            MitsubaError::at(
                path,
                u32::try_from(line).unwrap_or(u32::MAX),
                format!("malformed XML: {e}"),
            )
        })?;
        let d = Doc {
            doc: &doc,
            breaks: text.match_indices('\n').map(|(i, _)| i).collect(),
            path: Arc::from(path),
            dir: dir_of(path),
            file: self.versions.len(),
            depth,
        };
        let root = doc.root_element();
        let line = d.line(root);
        let version = match root.attribute("version") {
            Some(v) => Version::parse(v).map_err(|m| MitsubaError::at(path, line, m))?,
            None => {
                return Err(MitsubaError::at(
                    path,
                    line,
                    format!(
                        "missing version attribute in the root element <{}> (e.g. <scene version=\"3.0.0\">)",
                        quote(root.tag_name().name())
                    ),
                ));
            }
        };
        self.versions.push(version);
        self.files.push(path.to_owned());
        match self.element(&d, root, None, 0)? {
            Some(index) => Ok(index),
            None => Err(MitsubaError::at(
                path,
                line,
                "the root element must be an object such as <scene>",
            )),
        }
    }

    /// `$name` substitution in one attribute (Mitsuba's
    /// `substitute_parameters`).
    fn substitute(&mut self, text: &str) -> Result<String, String> {
        let mut value = text.to_string();
        for p in &mut self.params {
            let mut pos = 0;
            while let Some(found) = value[pos..].find(&p.key) {
                let at = pos + found;
                if at > 0 && value.as_bytes()[at - 1] == b'\\' {
                    pos = at + p.key.len();
                    continue;
                }
                value.replace_range(at..at + p.key.len(), &p.value);
                p.used = true;
                pos = at + p.value.len();
                if value.len() > MAX_ATTRIBUTE_BYTES {
                    return Err(format!(
                        "an attribute grows beyond {MAX_ATTRIBUTE_BYTES} bytes by $name substitution"
                    ));
                }
            }
        }
        let mut pos = 0;
        while let Some(found) = value[pos..].find('$') {
            let at = pos + found;
            if at > 0 && value.as_bytes()[at - 1] == b'\\' {
                pos = at + 1;
                continue;
            }
            let name: String = value[at + 1..]
                .chars()
                .take_while(|c| c.is_ascii_alphanumeric() || *c == '_')
                .collect();
            return Err(format!(
                "undefined parameter ${} (define it with -D {0}=… or a <default> before this line)",
                quote(&name)
            ));
        }
        self.grown += value.len().saturating_sub(text.len());
        if self.grown > MAX_SUBSTITUTION_BYTES {
            return Err(format!(
                "$name substitution grows the scene's attributes beyond {MAX_SUBSTITUTION_BYTES} bytes"
            ));
        }
        Ok(value.replace("\\$", "$"))
    }

    /// The element's attributes, substituted.
    fn attributes(&mut self, d: &Doc, el: roxmltree::Node) -> Result<Attrs, MitsubaError> {
        let mut list = Vec::new();
        for a in el.attributes() {
            let key = match a.namespace() {
                Some(_) => format!("{{namespaced}}{}", a.name()),
                None => a.name().to_string(),
            };
            let value = match a.value().contains('$') {
                true => self.substitute(a.value()).map_err(|m| {
                    MitsubaError::at(
                        &d.path,
                        d.line(el),
                        format!("<{}>: {m}", el.tag_name().name()),
                    )
                })?,
                false => a.value().to_string(),
            };
            list.push((key, value));
        }
        Ok(Attrs::new(list))
    }

    /// Handles one element under `parent` (`None` for a file's root);
    /// returns the node an object element became.
    fn element(
        &mut self,
        d: &Doc,
        el: roxmltree::Node,
        parent: Option<usize>,
        nesting: usize,
    ) -> Result<Option<usize>, MitsubaError> {
        let line = d.line(el);
        let tag_name = el.tag_name().name();
        let mut attrs = self.attributes(d, el)?;
        let context = match parent {
            Some(p) if self.nodes[p].tag != Tag::Scene => {
                format!(" (in {})", self.nodes[p].describe())
            }
            _ => String::new(),
        };
        let what = match attrs.get("name") {
            Some(n) if !matches!(tag_name, "default") => {
                format!("<{} name=\"{}\">", quote(tag_name), quote(n))
            }
            _ => format!("<{}>", quote(tag_name)),
        };
        let fail = |m: String| MitsubaError::at(&d.path, line, format!("{what}: {m}{context}"));
        let tag = match (el.tag_name().namespace(), tag_name) {
            (Some(_), _) => None,
            (None, "spectrum") if attrs.get("type").is_some() => Some(Tag::Spectrum),
            (None, name) => Tag::from_element(name),
        };
        if el.tag_name().namespace().is_some() {
            return Err(fail("unsupported XML element (a namespaced name)".into()));
        }
        if let Some(tag) = tag {
            return self.object(d, el, tag, attrs, parent, nesting).map(Some);
        }
        let Some(parent) = parent else {
            return Err(fail(
                "the root element must be an object such as <scene>".into(),
            ));
        };
        let location = Location {
            file: d.path.clone(),
            line,
        };
        let name = attrs.get("name").map(str::to_string).unwrap_or_default();
        let value = match tag_name {
            "float" | "integer" | "boolean" | "string" | "rgb" => {
                attrs.check(&["!name", "!value"]).map_err(&fail)?;
                let text = attrs.get("value").unwrap_or_default();
                Some(match tag_name {
                    "float" => Value::Float(values::float(text).map_err(&fail)?),
                    "integer" => Value::Integer(values::integer(text).map_err(&fail)?),
                    "boolean" => Value::Boolean(values::boolean(text).map_err(&fail)?),
                    "rgb" => Value::Rgb(values::rgb(text).map_err(&fail)?),
                    _ => Value::String(text.to_string()),
                })
            }
            "point" | "vector" => {
                if let Some(v) = attrs.get("value") {
                    if ["x", "y", "z"].iter().any(|k| attrs.get(k).is_some()) {
                        return Err(fail(
                            "cannot mix \"value\" and \"x\"/\"y\"/\"z\" attributes".into(),
                        ));
                    }
                    let [x, y, z] = values::expand_xyz(v).map_err(&fail)?.map(str::to_string);
                    attrs.remove("value");
                    attrs.push("x", x);
                    attrs.push("y", y);
                    attrs.push("z", z);
                }
                attrs.check(&["!name", "!x", "!y", "!z"]).map_err(&fail)?;
                let xyz = ["x", "y", "z"].map(|k| attrs.get(k).unwrap_or_default());
                let v = values::vec3(xyz).map_err(&fail)?;
                Some(match tag_name {
                    "point" => Value::Point(v),
                    _ => Value::Vector(v),
                })
            }
            "spectrum" => {
                attrs
                    .check(&["!name", "value", "filename"])
                    .map_err(&fail)?;
                let value = attrs.get("value").unwrap_or_default();
                let file = attrs.get("filename").unwrap_or_default();
                if value.is_empty() == file.is_empty() {
                    return Err(fail(
                        "needs either a \"value\" or a \"filename\" attribute (not both)".into(),
                    ));
                }
                let spectrum = match value.is_empty() {
                    false => values::spectrum(value).map_err(&fail)?,
                    true => match resolve_in(&self.search, Path::new(file)) {
                        Some(p) => Spectrum::File(p),
                        None => {
                            return Err(fail(format!("spectrum file \"{file}\" not found")));
                        }
                    },
                };
                Some(Value::Spectrum(spectrum))
            }
            "transform" => {
                attrs.check(&["!name"]).map_err(&fail)?;
                Some(Value::Transform(self.transform(d, el, &what, &context)?))
            }
            _ => None,
        };
        if let Some(value) = value {
            self.check_leaf(d, el, &what)?;
            self.add_name(parent, &name).map_err(&fail)?;
            self.nodes[parent].props.push(Property {
                name,
                value,
                location,
            });
            return Ok(None);
        }
        match tag_name {
            "ref" => {
                attrs.check(&["!id", "name"]).map_err(&fail)?;
                let name = attrs.get("name").map(str::to_string);
                if let Some(n) = &name {
                    self.add_name(parent, n).map_err(&fail)?;
                }
                let id = attrs.get("id").unwrap_or_default().to_string();
                self.nodes[parent].edges.push(Edge {
                    name,
                    target: Target::Ref(id),
                    location,
                    by_ref: true,
                });
            }
            "include" => {
                attrs.check(&["!filename", "name"]).map_err(&fail)?;
                self.include(d, el, &attrs, parent).map_err(|e| match e {
                    Included::Here(m) => fail(m),
                    Included::Inside(e) => e.included_from(&d.path, line),
                })?;
            }
            "alias" => {
                attrs.check(&["!id", "!as"]).map_err(&fail)?;
                let (src, dst) = (
                    attrs.get("id").unwrap_or_default(),
                    attrs.get("as").unwrap_or_default(),
                );
                if let Some((_, at)) = self.ids.get(dst) {
                    return Err(fail(format!(
                        "alias destination id \"{}\" already exists (at {at})",
                        quote(dst)
                    )));
                }
                let Some(&(index, _)) = self.ids.get(src) else {
                    return Err(fail(format!(
                        "alias source id \"{}\" not found (it must come before)",
                        quote(src)
                    )));
                };
                self.ids.insert(dst.to_string(), (index, location));
            }
            "default" => {
                attrs.check(&["!name", "!value"]).map_err(&fail)?;
                let name = attrs.get("name").unwrap_or_default();
                if name.is_empty() {
                    return Err(fail("name must be non-empty".into()));
                }
                let key = format!("${name}");
                if !self.params.iter().any(|p| p.key == key) {
                    let value = attrs.get("value").unwrap_or_default().to_string();
                    let at = self.params.partition_point(|p| p.key.len() >= key.len());
                    self.params.insert(
                        at,
                        Param {
                            key,
                            value,
                            used: true,
                            defined: false,
                        },
                    );
                }
            }
            "path" => {
                attrs.check(&["!value"]).map_err(&fail)?;
                if el.parent_element() != Some(d.doc.root_element()) {
                    return Err(fail(
                        "<path> can only be a child of the root element".into(),
                    ));
                }
                let value = attrs.get("value").unwrap_or_default();
                let v = Path::new(value);
                let folder = match v.is_absolute() {
                    true => v.to_owned(),
                    false => {
                        let local = d.dir.join(v);
                        match local.exists() {
                            true => local,
                            false => resolve_in(&self.search, v).unwrap_or(local),
                        }
                    }
                };
                if !folder.exists() {
                    return Err(fail(format!("folder \"{}\" not found", folder.display())));
                }
                self.search.insert(0, folder);
            }
            "translate" | "rotate" | "scale" | "lookat" | "matrix" => {
                return Err(fail(
                    "a transform operation can only appear inside a <transform>".into(),
                ));
            }
            _ => return Err(fail("unsupported XML element".into())),
        }
        self.check_leaf(d, el, &what)?;
        Ok(None)
    }

    /// An element other than an object or a transform holds no elements.
    fn check_leaf(&self, d: &Doc, el: roxmltree::Node, what: &str) -> Result<(), MitsubaError> {
        if el.tag_name().name() == "transform" {
            return Ok(());
        }
        match el.children().find(|c| c.is_element()) {
            Some(c) => Err(MitsubaError::at(
                &d.path,
                d.line(c),
                format!(
                    "<{}> cannot occur inside {what}",
                    quote(c.tag_name().name())
                ),
            )),
            None => Ok(()),
        }
    }

    /// Checks that `parent` has nothing named `name` yet (Mitsuba refuses a
    /// value given twice; raylab refuses an object too).
    fn add_name(&self, parent: usize, name: &str) -> Result<(), String> {
        match self.nodes[parent].first(name) {
            Some(first) => Err(format!(
                "\"{}\" is given twice in {} (first at {first})",
                quote(name),
                self.nodes[parent].describe()
            )),
            None => Ok(()),
        }
    }

    /// A `<transform>`'s operations composed (`transform.rs`), in single
    /// precision.
    fn transform(
        &mut self,
        d: &Doc,
        el: roxmltree::Node,
        what: &str,
        context: &str,
    ) -> Result<glam::Mat4, MitsubaError> {
        let mut m = DMat4::IDENTITY;
        let old = self.versions[d.file] < Version::V2;
        for op in el.children().filter(|c| c.is_element()) {
            let mut attrs = self.attributes(d, op)?;
            let name = match (op.tag_name().namespace(), op.tag_name().name()) {
                (Some(_), n) => format!("{{namespaced}}{n}"),
                (None, "lookAt") if old => "lookat".to_string(),
                (None, n) => n.to_string(),
            };
            transform::apply(&name, &mut attrs, &mut m).map_err(|msg| {
                MitsubaError::at(
                    &d.path,
                    d.line(op),
                    format!(
                        "<{}> in {what}: {msg}{context}",
                        quote(op.tag_name().name())
                    ),
                )
            })?;
        }
        let single = m.as_mat4();
        if !single.is_finite() {
            return Err(MitsubaError::at(
                &d.path,
                d.line(el),
                format!("{what}: the matrix is not finite in single precision{context}"),
            ));
        }
        Ok(single)
    }

    /// An object element: a node, registered under its id, a child of
    /// `parent`, with its own children read.
    fn object(
        &mut self,
        d: &Doc,
        el: roxmltree::Node,
        tag: Tag,
        attrs: Attrs,
        parent: Option<usize>,
        nesting: usize,
    ) -> Result<usize, MitsubaError> {
        let location = d.location(el);
        let line = location.line;
        let fail = |m: String| {
            let plugin = attrs.get("type").map(|t| format!(" type=\"{}\"", quote(t)));
            MitsubaError::at(
                &d.path,
                line,
                format!("<{tag}{}>: {m}", plugin.unwrap_or_default()),
            )
        };
        let spec: &[&str] = match parent {
            None => &["!version", "type", "id", "name"],
            Some(_) => &["!type", "id", "name"],
        };
        attrs.check(spec).map_err(&fail)?;
        if nesting >= MAX_NESTING {
            return Err(fail(format!("objects nested more than {MAX_NESTING} deep")));
        }
        let name = attrs.get("name").map(str::to_string);
        let id = attrs.get("id").map(str::to_string);
        let index = self.nodes.len();
        if let Some(id) = &id {
            if let Some((_, first)) = self.ids.get(id) {
                return Err(fail(format!(
                    "duplicate id \"{}\" (first at {first})",
                    quote(id)
                )));
            }
            self.ids.insert(id.clone(), (index, location.clone()));
        }
        if let (Some(p), Some(n)) = (parent, &name) {
            self.add_name(p, n).map_err(&fail)?;
        }
        self.nodes.push(Node {
            tag,
            plugin: attrs.get("type").unwrap_or("scene").to_string(),
            id,
            name: name.clone(),
            props: Vec::new(),
            edges: Vec::new(),
            location: location.clone(),
            file: d.file,
        });
        if let Some(p) = parent {
            self.nodes[p].edges.push(Edge {
                name,
                target: Target::Node(index),
                location,
                by_ref: false,
            });
        }
        for child in el.children().filter(|c| c.is_element()) {
            self.element(d, child, Some(index), nesting + 1)?;
        }
        Ok(index)
    }
}

/// Why an `<include>` failed: at the include itself, or inside the file.
pub(super) enum Included {
    /// At the `<include>` element.
    Here(String),
    /// Inside the included file (or reading it).
    Inside(MitsubaError),
}
