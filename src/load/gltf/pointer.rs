//! `KHR_animation_pointer`: animation channels whose target is a JSON
//! pointer to any animatable property of the glTF Asset Object Model
//! (material factors and texture transforms, lights, cameras, node
//! visibility, node transforms and weights), sampled at the chosen moment
//! and written into the objects they animate before the scene is built.
//!
//! How: the channels of the chosen animation are read from the JSON text
//! itself (`gltf-json` has no place for a target without a `node`; the
//! loader drops such channels from its typed document). Each pointer is
//! resolved against the Object Model's tables (`object_model.rs`), checked
//! against the file (the object exists; the property is defined, or has a
//! default inside an object the file writes; the output accessor's type and
//! count fit the property; a `bool` is animated by `STEP` alone; no property
//! is animated twice in one animation), and sampled with the same code as
//! node channels (`animation.rs`: `STEP`, `LINEAR` — slerp for a node's
//! rotation — and `CUBICSPLINE`). The value is then written into the
//! animated object's JSON form: the object (a material, a camera, a node, a
//! light) is serialized, the value set at the pointer's path, and the object
//! read back into the typed document. Every reader downstream (materials,
//! textures, lights, cameras, node transforms, morph weights, visibility)
//! thus sees the animated value exactly as if the file had written it, with
//! no table of setters per field, and a file without pointer channels is
//! read exactly as before (nothing here runs unless an animation is asked
//! for and the text names the extension).
//!
//! A bad channel (a pointer that is not a JSON pointer, names no animatable
//! property, or names an object or property the file lacks; an accessor of
//! the wrong type or count; an interpolation the type does not allow) is
//! refused in one line naming the animation and the channel. A property
//! raylab does not render (a camera's clipping planes, a light's range,
//! occlusion) and anything in `extras` or in an extension raylab does not
//! read is skipped with one warning per kind of property.

use std::collections::{BTreeMap, HashMap};

use gltf::json;
use serde_json::Value;

use super::accessor::read_floats;
use super::animation::{
    self, AnimationOptions, Interpolation, Track, check_output, chosen, components,
    interpolation_of, label, morph_targets,
};
use super::buffers::{Buffers, Unreadable};
use super::document::SUPPORTED_EXTENSIONS;
use super::error::{GltfError, valid};
use super::object_model::{self, Named, Owner, Property, ValueType};

/// The extension's name.
pub(crate) const EXTENSION: &str = "KHR_animation_pointer";

/// The animations as the JSON text writes them, unread (only the chosen
/// one is read further).
#[derive(serde::Deserialize)]
struct Document<'a> {
    #[serde(default, borrow)]
    animations: Vec<&'a serde_json::value::RawValue>,
}

/// One animation's channels as the JSON text writes them.
#[derive(serde::Deserialize)]
struct RawAnimation {
    #[serde(default)]
    channels: Vec<Value>,
}

/// Samples the pointer channels of the animation `options` choose at its
/// time and writes their values into `root`'s objects (see the module's
/// documentation). `json_bytes` is the file's JSON text; `data` and
/// `unreadable` its buffers. Does nothing unless an animation is asked for
/// and the text names `KHR_animation_pointer`.
pub(crate) fn apply(
    json_bytes: &[u8],
    root: &mut json::Root,
    data: &[Vec<u8>],
    unreadable: &[Option<Unreadable>],
    options: &AnimationOptions,
    warnings: &mut Vec<String>,
) -> Result<(), GltfError> {
    let t = options.time.unwrap_or(0.0);
    // A time that is not finite is refused by `animation::pose`.
    if !options.is_given() || !t.is_finite() || !names_extension(json_bytes) {
        return Ok(());
    }
    let buffers = Buffers {
        root,
        data,
        unreadable,
    };
    let Some(a) = chosen(root, &buffers, options)? else {
        return Ok(());
    };
    let document: Document = serde_json::from_slice(json_bytes)
        .map_err(|e| GltfError::invalid(format!("animations: {e}")))?;
    let Some(raw) = document.animations.get(a) else {
        return Ok(());
    };
    let raw: RawAnimation = serde_json::from_str(raw.get())
        .map_err(|e| GltfError::invalid(format!("animation {}: {e}", label(root, a))))?;
    let mut pass = Pass {
        root,
        buffers: &buffers,
        a,
        name: label(root, a),
        time: t,
        objects: BTreeMap::new(),
        claims: HashMap::new(),
        warnings,
    };
    let typed_pointers = pass.run(&raw.channels)?;
    let objects = pass.objects;
    // The typed document keeps a channel only if its target has a `node`:
    // a pointer channel that (against the specification) names one too is
    // left out of the node animation, which cannot read its path.
    if !typed_pointers.is_empty() {
        let channels = &mut root.animations[a].channels;
        for &k in typed_pointers.iter().rev() {
            if k < channels.len() {
                channels.remove(k);
            }
        }
    }
    for (owner, (value, written)) in objects {
        if written {
            store(root, owner, value)?;
        }
    }
    Ok(())
}

/// Whether the JSON text names the extension (a file without it has no
/// pointer channels, and is not read again).
fn names_extension(json_bytes: &[u8]) -> bool {
    let name = EXTENSION.as_bytes();
    json_bytes
        .windows(name.len())
        .any(|w| w[0] == name[0] && w == name)
}

/// One animation's pointer channels being read.
struct Pass<'a, 'b> {
    root: &'a json::Root,
    buffers: &'a Buffers<'a>,
    /// The animation's index and its name in messages.
    a: usize,
    name: String,
    /// The moment sampled.
    time: f32,
    /// The animated objects as JSON, and whether a value was written.
    objects: BTreeMap<Owner, (Value, bool)>,
    /// Every property animated so far (its pointer's members) and by which
    /// channel.
    claims: HashMap<Vec<String>, usize>,
    warnings: &'b mut Vec<String>,
}

impl Pass<'_, '_> {
    /// Reads every channel of `channels` (the animation's, from the text).
    /// Returns the indices, in the typed document's channels, of pointer
    /// channels whose target names a node too.
    fn run(&mut self, channels: &[Value]) -> Result<Vec<usize>, GltfError> {
        // Node channels first, so that a pointer to a property a node
        // channel animates is refused whichever comes first.
        let mut pointers = Vec::new();
        let mut typed_pointers = Vec::new();
        let mut typed = 0;
        for (c, channel) in channels.iter().enumerate() {
            let target = channel.get("target");
            let path = target.and_then(|t| t.get("path")).and_then(Value::as_str);
            let node = target.and_then(|t| t.get("node"));
            if path == Some("pointer") {
                pointers.push(c);
                if node.is_some() {
                    typed_pointers.push(typed);
                }
            } else if let (Some(n), Some(p @ ("translation" | "rotation" | "scale" | "weights"))) =
                (node.and_then(index_of), path)
            {
                self.claims
                    .entry(vec!["nodes".into(), n.to_string(), p.into()])
                    .or_insert(c);
            }
            if node.is_some() {
                typed += 1;
            }
        }
        for c in pointers {
            self.channel(c, &channels[c])?;
        }
        Ok(typed_pointers)
    }

    /// Warns once with `message`.
    fn warn(&mut self, message: String) {
        if !self.warnings.contains(&message) {
            self.warnings.push(message);
        }
    }

    /// Reads pointer channel `c`, checks it, and writes its value at the
    /// moment into its object.
    fn channel(&mut self, c: usize, channel: &Value) -> Result<(), GltfError> {
        let what = format!("animation {} channel {c}", self.name);
        let target = &channel["target"];
        let Some(pointer) = target
            .get("extensions")
            .and_then(|e| e.get(EXTENSION))
            .and_then(|e| e.get("pointer"))
        else {
            return Err(GltfError::invalid(format!(
                "{what}: its target's path is \"pointer\" but it has no {EXTENSION} pointer"
            )));
        };
        let Some(pointer) = pointer.as_str() else {
            return Err(GltfError::invalid(format!(
                "{what}: its {EXTENSION} pointer is not a string"
            )));
        };
        let refuse = |reason: String| {
            GltfError::invalid(format!(
                "{what}: pointer {}: {reason}",
                object_model::quoted(pointer)
            ))
        };
        if target.get("node").is_some() {
            self.warn(format!(
                "animation {}: a pointer channel's target names a node too ({EXTENSION} says it must not); the node is ignored",
                self.name
            ));
        }
        let members = object_model::parse_pointer(pointer)
            .map_err(|e| refuse(format!("not a valid JSON pointer: {e}")))?;
        let reads = |name: &str| SUPPORTED_EXTENSIONS.contains(&name);
        let property = match object_model::resolve(&members, &reads).map_err(refuse)? {
            Named::Property(p) => p,
            Named::Unread { owner, why } => {
                if let Some(owner) = owner {
                    self.exists(owner).map_err(refuse)?;
                }
                self.warn(format!(
                    "animation {}: skipping the channels that animate {}: {why}",
                    self.name,
                    object_model::template(&members)
                ));
                return Ok(());
            }
        };
        self.exists(property.owner).map_err(refuse)?;
        self.claim(&members, c).map_err(refuse)?;
        let width = self.defined(&property).map_err(refuse)?;
        let samplers = &self.root.animations[self.a].samplers;
        let Some((s, sampler)) = (channel.get("sampler").and_then(index_of))
            .and_then(|s| samplers.get(s).map(|sampler| (s, sampler)))
        else {
            return Err(GltfError::invalid(format!(
                "{what}: sampler {} does not exist",
                channel.get("sampler").map_or("(none)".into(), |s| {
                    crate::guard::quote(&crate::guard::one_line(&s.to_string()))
                })
            )));
        };
        let track = self.track(&what, s, sampler, &property, width)?;
        if let Some(why) = property.unrendered {
            self.warn(format!(
                "animation {}: skipping the channels that animate {}: {why}",
                self.name,
                object_model::template(&members)
            ));
            return Ok(());
        }
        if property.path == ["extensions", "KHR_materials_ior", "ior"]
            && self.value_at(&property).and_then(Value::as_f64) == Some(0.0)
        {
            // KHR_materials_ior: an index of 0 (a perfect mirror) cannot be
            // animated; updates of it are ignored.
            self.warn(format!(
                "animation {}: {} has ior 0, which KHR_materials_ior says animations leave as it is",
                self.name, property.owner
            ));
            return Ok(());
        }
        let value = track.sample(self.time);
        if value.iter().any(|v| !v.is_finite()) {
            return Err(refuse(format!(
                "the value at {} s is not finite",
                self.time
            )));
        }
        self.write(&property, json_value(property.value, &value))
            .map_err(refuse)
    }

    /// Refuses `owner` unless the file has it.
    fn exists(&self, owner: Owner) -> Result<(), String> {
        let (n, kind) = match owner {
            Owner::Material(_) => (self.root.materials.len(), "materials"),
            Owner::Camera(_) => (self.root.cameras.len(), "cameras"),
            Owner::Node(_) => (self.root.nodes.len(), "nodes"),
            Owner::Light(_) => (lights(self.root).map_or(0, <[_]>::len), "lights"),
        };
        let (Owner::Material(i) | Owner::Camera(i) | Owner::Node(i) | Owner::Light(i)) = owner;
        if i < n {
            Ok(())
        } else {
            Err(format!("{owner} does not exist (the file has {n} {kind})"))
        }
    }

    /// Records that channel `c` animates the property of pointer members
    /// `members`, refusing one that another channel of the animation
    /// animates (the same property, a node's weights and one of them, or a
    /// node channel's property).
    fn claim(&mut self, members: &[String], c: usize) -> Result<(), String> {
        let one_weight = |m: &[String]| m.len() == 4 && m[0] == "nodes" && m[2] == "weights";
        let other = self.claims.get(members).copied().or_else(|| {
            if one_weight(members) {
                // One weight: the node's whole weights too.
                self.claims.get(&members[..3]).copied()
            } else if members.len() == 3 && members[0] == "nodes" && members[2] == "weights" {
                // The whole weights: any one of them too.
                (self.claims.iter())
                    .filter(|(k, _)| one_weight(k) && k[..3] == *members)
                    .map(|(_, &d)| d)
                    .min()
            } else {
                None
            }
        });
        if let Some(d) = other {
            return Err(format!(
                "channel {d} animates this property too (an animation may animate a property once)"
            ));
        }
        self.claims.insert(members.to_vec(), c);
        Ok(())
    }

    /// The owner of `p` as JSON (serialized at its first use).
    fn object(&mut self, owner: Owner) -> Result<&mut (Value, bool), String> {
        if !self.objects.contains_key(&owner) {
            let value = load(self.root, owner)?;
            self.objects.insert(owner, (value, false));
        }
        Ok(self.objects.get_mut(&owner).expect("inserted above"))
    }

    /// The value the file gives `p` (none where it takes its default).
    fn value_at(&mut self, p: &Property) -> Option<&Value> {
        let mut here = &self.object(p.owner).ok()?.0;
        for member in &p.path {
            here = here.get(member.as_str())?;
        }
        Some(here)
    }

    /// Refuses `p` unless the file defines it: every object on its path is
    /// in the file and the property too, or has a default. A node's
    /// weights need a mesh with morph targets; its rotation and scale, a
    /// node given by translation, rotation and scale. Returns the number of
    /// values per keyframe.
    fn defined(&mut self, p: &Property) -> Result<usize, String> {
        let owner = p.owner;
        if let Owner::Node(n) = owner {
            let matrix = self.root.nodes[n].matrix.is_some();
            if matrix && (p.path == ["rotation"] || p.path == ["scale"]) {
                return Err(format!(
                    "{owner} is given by a matrix: only its translation is animatable, not its rotation or scale"
                ));
            }
            if p.path[0] == "weights" {
                let Some(targets) = morph_targets(self.root, n).filter(|&t| t > 0) else {
                    return Err(format!(
                        "{owner} has no mesh with morph targets, so no weights to animate"
                    ));
                };
                if let Some(k) = p.path.get(1) {
                    let k: usize = k.parse().unwrap_or(usize::MAX);
                    if k >= targets {
                        return Err(format!(
                            "{owner}'s mesh has {targets} morph targets: weight {k} does not exist"
                        ));
                    }
                    return Ok(1);
                }
                return Ok(targets);
            }
        }
        let (object, _) = self.object(owner)?;
        let mut here = &*object;
        for (k, member) in p.path.iter().enumerate() {
            let last = k + 1 == p.path.len();
            match here.get(member.as_str()) {
                Some(_) if last => break,
                Some(next) if next.is_object() => here = next,
                Some(_) => {
                    return Err(format!(
                        "{owner}'s {} is not an object",
                        p.path[..=k].join("/")
                    ));
                }
                None if last && p.has_default => break,
                None if last => {
                    return Err(format!(
                        "{owner} has no {} (it has no default value, so the file must give it)",
                        p.path.join("/")
                    ));
                }
                None => {
                    return Err(format!(
                        "{owner} has no {} (a pointer must name a property of an object the file writes)",
                        p.path[..=k].join("/")
                    ));
                }
            }
        }
        Ok(p.value.accessor_components())
    }

    /// The keyframes of sampler `s` for property `p` (`width` values per
    /// keyframe), checked: the output accessor's type and count, a `bool`'s
    /// unsigned bytes and `STEP`, finite values.
    fn track(
        &self,
        what: &str,
        s: usize,
        sampler: &json::animation::Sampler,
        p: &Property,
        width: usize,
    ) -> Result<Track, GltfError> {
        let interpolation = interpolation_of(sampler, s, what)?;
        let ty = p.value;
        if ty == ValueType::Bool && interpolation != Interpolation::Step {
            return Err(GltfError::invalid(format!(
                "{what}: {} is a bool, which only STEP interpolation animates (sampler {s} is {})",
                p.path.join("/"),
                if interpolation == Interpolation::Linear {
                    "LINEAR"
                } else {
                    "CUBICSPLINE"
                }
            )));
        }
        let times = animation::times(self.root, self.buffers, self.a, s)?;
        let output = sampler.output.value();
        let out_what = format!("{what} output");
        let n = ty.accessor_components();
        match components(self.root, output) {
            Some(k) if k == n => {}
            Some(k) => {
                return Err(GltfError::invalid(format!(
                    "{out_what}: accessor {output} has {k} components per element, but {} is a {} ({n} per element)",
                    p.path.join("/"),
                    ty.name()
                )));
            }
            None => {
                return Err(GltfError::invalid(format!(
                    "{out_what}: accessor {output} does not exist or has an unknown type"
                )));
            }
        }
        if ty == ValueType::Bool {
            let c = valid(&self.root.accessors[output].component_type).map(|c| c.0);
            if c != Some(json::accessor::ComponentType::U8) {
                return Err(GltfError::invalid(format!(
                    "{out_what}: accessor {output} must hold unsigned bytes for a bool (0 false, else true)"
                )));
            }
        }
        let values: Vec<f32> = match n {
            1 => read_floats::<1>(self.buffers, output, &out_what)?.concat(),
            2 => read_floats::<2>(self.buffers, output, &out_what)?.concat(),
            3 => read_floats::<3>(self.buffers, output, &out_what)?.concat(),
            _ => read_floats::<4>(self.buffers, output, &out_what)?.concat(),
        };
        check_output(&out_what, &values, times.len(), interpolation, width)?;
        Ok(Track {
            // Unused: the track is sampled, not applied to a node.
            node: 0,
            // A rotation is interpolated as one (slerp, normalized); every
            // other type component-wise, as weights are.
            property: if ty == ValueType::Quaternion {
                animation::Property::Rotation
            } else {
                animation::Property::Weights
            },
            interpolation,
            times,
            values,
            width,
        })
    }

    /// Writes `value` at `p` in its object's JSON: a node given by a matrix
    /// takes a translation into the matrix's last column; one weight of a
    /// node without its own takes the others from its mesh's (else 0); the
    /// iridescence index goes where the file wrote it (`iridescenceIOR` is
    /// read as well).
    fn write(&mut self, p: &Property, value: Value) -> Result<(), String> {
        let mesh_weights = match p.owner {
            Owner::Node(n) => (self.root.nodes[n].mesh)
                .and_then(|m| self.root.meshes.get(m.value()))
                .and_then(|m| m.weights.clone()),
            _ => None,
        };
        let targets = match p.owner {
            Owner::Node(n) => morph_targets(self.root, n).unwrap_or(0),
            _ => 0,
        };
        let path: Vec<&str> = p.path.iter().map(String::as_str).collect();
        let (object, written) = self.object(p.owner)?;
        *written = true;
        let Some(map) = object.as_object_mut() else {
            return Err(format!("{} is not a JSON object", p.owner));
        };
        if let (Owner::Node(_), ["translation"]) = (p.owner, path.as_slice())
            && let Some(Value::Array(matrix)) = map.get_mut("matrix")
            && let (16, Value::Array(t)) = (matrix.len(), &value)
        {
            matrix[12..15].clone_from_slice(t);
            return Ok(());
        }
        if let (Owner::Node(_), ["weights", k]) = (p.owner, path.as_slice()) {
            let k: usize = k
                .parse()
                .map_err(|_| format!("weight {k} does not exist"))?;
            let weights = map.entry("weights").or_insert_with(|| {
                let w = mesh_weights.unwrap_or_default();
                Value::Array(w.iter().map(|&x| number(x)).collect())
            });
            let Value::Array(weights) = weights else {
                return Err(format!("{}'s weights are not an array", p.owner));
            };
            if weights.len() < targets.max(k + 1) {
                weights.resize(targets.max(k + 1), number(0.0));
            }
            weights[k] = value;
            return Ok(());
        }
        let (last, parents) = p.path.split_last().expect("a property has a path");
        let mut here = map;
        for member in parents {
            here = match here.get_mut(member).and_then(Value::as_object_mut) {
                Some(next) => next,
                None => return Err(format!("{} has no {member}", p.owner)),
            };
        }
        let key = if last == "iridescenceIor"
            && !here.contains_key(last)
            && here.contains_key("iridescenceIOR")
        {
            "iridescenceIOR"
        } else {
            last
        };
        here.insert(key.to_string(), value);
        Ok(())
    }
}

/// `v` as an index (a whole number from 0; JSON writes integers as
/// numbers, possibly with a fraction of 0).
fn index_of(v: &Value) -> Option<usize> {
    if let Some(i) = v.as_u64() {
        return usize::try_from(i).ok();
    }
    let x = v.as_f64()?;
    (x >= 0.0 && x.fract() == 0.0 && x < 4_294_967_296.0).then_some(x as usize)
}

/// The file's `KHR_lights_punctual` lights, if any.
fn lights(root: &json::Root) -> Option<&[json::extensions::scene::khr_lights_punctual::Light]> {
    root.extensions
        .as_ref()
        .and_then(|e| e.khr_lights_punctual.as_ref())
        .map(|l| l.lights.as_slice())
}

/// `x` as a JSON number (finite: checked before).
fn number(x: f32) -> Value {
    serde_json::Number::from_f64(f64::from(x)).map_or(Value::Null, Value::Number)
}

/// The sampled `values` as the JSON of a property of type `ty`.
fn json_value(ty: ValueType, values: &[f32]) -> Value {
    match ty {
        ValueType::Bool => Value::Bool(values[0] != 0.0),
        ValueType::Float => number(values[0]),
        _ => Value::Array(values.iter().map(|&x| number(x)).collect()),
    }
}

/// `owner` as JSON: the typed object serialized, with members whose value
/// is `null` dropped (a default that JSON cannot write, such as an infinite
/// attenuation distance, serializes as `null` and reads back as the
/// default when left out). A light's own `extensions` stay aside (see
/// [`store`]).
fn load(root: &json::Root, owner: Owner) -> Result<Value, String> {
    let value = match owner {
        Owner::Material(i) => serde_json::to_value(&root.materials[i]),
        Owner::Camera(i) => serde_json::to_value(&root.cameras[i]),
        Owner::Node(i) => serde_json::to_value(&root.nodes[i]),
        Owner::Light(i) => {
            let mut light = lights(root).expect("the light exists")[i].clone();
            light.extensions = None;
            serde_json::to_value(&light)
        }
    };
    let mut value = value.map_err(|e| format!("{owner} cannot be animated: {e}"))?;
    let mut stack = vec![&mut value];
    while let Some(v) = stack.pop() {
        match v {
            Value::Object(members) => {
                members.retain(|_, m| !m.is_null());
                stack.extend(members.values_mut());
            }
            Value::Array(items) => stack.extend(items.iter_mut()),
            _ => {}
        }
    }
    Ok(value)
}

/// Reads the animated `value` back into `owner` in `root` (a light keeps
/// its own `extensions`, which `gltf-json` holds as raw JSON).
fn store(root: &mut json::Root, owner: Owner, value: Value) -> Result<(), GltfError> {
    fn read<T: serde::de::DeserializeOwned>(owner: Owner, value: Value) -> Result<T, GltfError> {
        serde_json::from_value(value).map_err(|e| {
            GltfError::invalid(format!("{owner}: its animated values cannot be read: {e}"))
        })
    }
    match owner {
        Owner::Material(i) => root.materials[i] = read(owner, value)?,
        Owner::Camera(i) => root.cameras[i] = read(owner, value)?,
        Owner::Node(i) => root.nodes[i] = read(owner, value)?,
        Owner::Light(i) => {
            let light = root
                .extensions
                .as_mut()
                .and_then(|e| e.khr_lights_punctual.as_mut())
                .and_then(|l| l.lights.get_mut(i))
                .expect("the light exists");
            let mut animated: json::extensions::scene::khr_lights_punctual::Light =
                read(owner, value)?;
            animated.extensions = light.extensions.take();
            *light = animated;
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_material_reads_back_as_it_was_even_with_an_infinite_default() {
        let text = br#"{"asset": {"version": "2.0"}, "materials": [{
            "pbrMetallicRoughness": {"baseColorFactor": [0.1, 0.2, 0.3, 0.4]},
            "extensions": {"KHR_materials_volume": {"thicknessFactor": 1.0},
                           "KHR_materials_clearcoat": {"clearcoatFactor": 0.5}},
            "alphaMode": "MASK"}],
            "extensions": {"KHR_lights_punctual": {"lights": [
                {"type": "spot", "spot": {"outerConeAngle": 0.5}, "extensions": {"X": {"y": 1}}}]}}}"#;
        let mut root = json::Root::from_slice(text).unwrap();
        let before = format!("{:?}", root.materials[0]);
        let value = load(&root, Owner::Material(0)).unwrap();
        assert!(
            value
                .pointer("/extensions/KHR_materials_volume/attenuationDistance")
                .is_none()
        );
        store(&mut root, Owner::Material(0), value).unwrap();
        assert_eq!(format!("{:?}", root.materials[0]), before);
        let volume = root.materials[0]
            .extensions
            .as_ref()
            .unwrap()
            .volume
            .as_ref()
            .unwrap();
        assert_eq!(volume.attenuation_distance.0, f32::INFINITY);
        // A light keeps its raw extensions.
        let before = format!("{:?}", lights(&root).unwrap()[0]);
        let value = load(&root, Owner::Light(0)).unwrap();
        store(&mut root, Owner::Light(0), value).unwrap();
        assert_eq!(format!("{:?}", lights(&root).unwrap()[0]), before);
    }

    #[test]
    fn indices_may_be_written_with_a_zero_fraction() {
        assert_eq!(index_of(&serde_json::json!(3)), Some(3));
        assert_eq!(index_of(&serde_json::json!(3.0)), Some(3));
        assert_eq!(index_of(&serde_json::json!(3.5)), None);
        assert_eq!(index_of(&serde_json::json!(-1)), None);
        assert_eq!(index_of(&serde_json::json!("3")), None);
    }
}
