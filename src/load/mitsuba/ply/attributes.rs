//! Mitsuba's grouping of the other properties of a PLY element into mesh
//! attributes (`find_other_fields` of `src/shapes/ply.h`).

use std::collections::HashSet;

use crate::guard::one_line;

use super::header::Element;

/// The postfix schemes of Mitsuba's attribute grouping: column `s` is
/// scheme `s` (`x y z w`, `r g b a`, `0 1 2 3`, `1 2 3 4`), row `k` the
/// `k`-th field's postfix.
const POSTFIXES: [&[u8; 4]; 4] = [b"xr01", b"yg12", b"zb23", b"wa34"];

/// The state of Mitsuba's attribute grouping (`find_other_fields`) over an
/// element's fields.
struct Grouping<'a> {
    /// `vertex_` or `face_`.
    kind: &'a str,
    file: &'a str,
    /// The attributes found: name and the names of their fields.
    found: Vec<(String, Vec<String>)>,
    /// The prefixes of the attributes found.
    encountered: HashSet<String>,
    /// The attribute being read: its prefix, scheme (a column of
    /// [`POSTFIXES`]) and how many fields so far.
    prefix: String,
    scheme: usize,
    level: usize,
    reading: bool,
}

impl Grouping<'_> {
    fn reset(&mut self) {
        self.prefix.clear();
        self.scheme = 0;
        self.level = 0;
        self.reading = false;
    }

    /// Ends the attribute being read: kept with 1 or 3 fields.
    fn flush(&mut self, current_int: bool, warnings: &mut Vec<String>) {
        let (file, kind, prefix, level) =
            (self.file, self.kind, one_line(&self.prefix), self.level);
        if level != 1 && level != 3 {
            warnings.push(format!(
                "{file}: attribute must have either 1 or 3 fields (had {level}): attribute \"{kind}{prefix}\" ignored"
            ));
        } else {
            if current_int && level == 3 {
                warnings.push(format!(
                    "{file}: attribute \"{kind}{prefix}\" has integer fields: color attributes are expected to be in the [0, 1] range"
                ));
            }
            let names = (0..level)
                .map(|i| format!("{}_{}", self.prefix, POSTFIXES[i][self.scheme] as char))
                .collect();
            let suffix = if self.scheme == 1 { "_color" } else { "" };
            self.found
                .push((format!("{kind}{}{suffix}", self.prefix), names));
            self.encountered.insert(self.prefix.clone());
        }
        self.reset();
    }
}

/// An attribute found among an element's fields: its name and the fields
/// of its channels.
pub(super) struct Descriptor {
    /// `vertex_…` or `face_…`.
    pub(super) name: String,
    /// The fields of its channels.
    pub(super) fields: Vec<usize>,
}

/// Mitsuba's `find_other_fields`: the colour attribute, then every
/// group of consecutive fields named `PREFIX_<postfix>` (see the module
/// comment), with Mitsuba's warnings for what it ignores. `kind` is
/// `vertex_` or `face_`.
pub(super) fn find_other_fields(
    kind: &str,
    el: &mut Element,
    reserved: &mut HashSet<String>,
    file: &str,
    warnings: &mut Vec<String>,
) -> Result<Vec<Descriptor>, String> {
    // (name, output field names)
    let mut found: Vec<(String, Vec<String>)> = Vec::new();
    if !(el.has("r") && el.has("g") && el.has("b"))
        && el.has("red")
        && el.has("green")
        && el.has("blue")
    {
        el.rename("red", "r");
        el.rename("green", "g");
        el.rename("blue", "b");
        el.rename("alpha", "a");
    }
    if el.has("r") && el.has("g") && el.has("b") {
        let mut names: Vec<String> = ["r", "g", "b"].map(String::from).into();
        if el.has("a") {
            names.push("a".into());
        }
        found.push((format!("{kind}color"), names));
        if el.fields[el.field("r").unwrap_or(0)].ty.is_int() {
            warnings.push(format!(
                "{file}: mesh attribute \"{kind}color\" has integer fields: color attributes are expected to be in the [0, 1] range"
            ));
        }
    }
    for n in ["r", "g", "b", "a"] {
        reserved.insert(n.to_owned());
    }

    let mut g = Grouping {
        kind,
        file,
        found,
        encountered: HashSet::new(),
        prefix: String::new(),
        scheme: 0,
        level: 0,
        reading: false,
    };
    let count = el.fields.len();
    // Mitsuba's `current_type`: the type of the last field looked at,
    // also when it ends (flushes) the attribute before it.
    let mut current_int = false;
    let mut i = 0;
    while i < count {
        let name = el.fields[i].name.clone();
        if reserved.contains(&name) {
            i += 1;
            continue;
        }
        current_int = el.fields[i].ty.is_int();
        let Some(pos) = name.rfind('_') else {
            warnings.push(format!(
                "{file}: attributes without postfix are not handled for now: attribute \"{}\" ignored",
                one_line(&name)
            ));
            if g.reading {
                g.flush(current_int, warnings);
            }
            i += 1;
            continue;
        };
        let postfix = &name.as_bytes()[pos + 1..];
        if postfix.len() != 1 {
            warnings.push(format!(
                "{file}: attribute postfix can only be one letter long: attribute \"{}\" ignored",
                one_line(&name)
            ));
            if g.reading {
                g.flush(current_int, warnings);
            }
            i += 1;
            continue;
        }
        let this_prefix = name[..pos].to_owned();
        if g.reading && this_prefix != g.prefix {
            g.flush(current_int, warnings);
        }
        if !g.reading && g.encountered.contains(&this_prefix) {
            warnings.push(format!(
                "{file}: attribute prefix has already been encountered: attribute \"{}\" ignored",
                one_line(&name)
            ));
            while i < count && el.fields[i].name.starts_with(&this_prefix) {
                i += 1;
            }
            // Mitsuba's loop then steps over the field after them too.
            i += 1;
            continue;
        }
        let c = postfix[0];
        if !g.reading {
            let Some(s) = POSTFIXES[0].iter().position(|&p| p == c) else {
                warnings.push(format!(
                    "{file}: attribute can't start with postfix {}: attribute \"{}\" ignored",
                    one_line(&(c as char).to_string()),
                    one_line(&name)
                ));
                i += 1;
                continue;
            };
            g.reading = true;
            g.scheme = s;
            g.prefix = this_prefix;
        } else if g.level >= 4 || c != POSTFIXES[g.level][g.scheme] {
            warnings.push(format!(
                "{file}: attribute postfix sequence is invalid: attribute \"{kind}{}\" ignored",
                one_line(&g.prefix)
            ));
            g.reset();
            while i < count && el.fields[i].name.starts_with(&this_prefix) {
                i += 1;
            }
            if i >= count {
                break;
            }
        }
        g.level += 1;
        i += 1;
    }
    if g.reading {
        g.flush(current_int, warnings);
    }
    let found = g.found;

    let mut out = Vec::new();
    for (name, fields) in found {
        if out.iter().any(|d: &Descriptor| d.name == name) {
            return Err(format!("attribute \"{}\" already exists", one_line(&name)));
        }
        let fields = fields
            .iter()
            .map(|f| {
                el.field(f).ok_or_else(|| {
                    format!("{} has no field \"{}\"", one_line(&el.name), one_line(f))
                })
            })
            .collect::<Result<_, _>>()?;
        out.push(Descriptor { name, fields });
    }
    Ok(out)
}
