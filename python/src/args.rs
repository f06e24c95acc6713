//! Keyword arguments into `raylab render`'s command line: the options clap
//! defines (`spec`), a Python value's text on the command line (`text`,
//! `items`), the closest option to a misspelt keyword (`unexpected`), and the
//! parse that checks them as `raylab render` does (`parse`).

use std::path::PathBuf;
use std::sync::OnceLock;

use clap::{ArgAction, FromArgMatches};
use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList, PyString, PyTuple};
use raylab::job::JobOptions;

/// How an option is given on the command line.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Kind {
    /// A switch (`--quiet`): `True` gives it, `False` leaves it out.
    Flag,
    /// One value (`--spp=64`).
    Value,
    /// Repeatable (`--add`): a list gives each item.
    Repeat,
}

/// One option of `raylab render`, as clap defines it.
pub(crate) struct Opt {
    /// The keyword (clap's id: the field name, `max_depth`).
    pub(crate) name: String,
    /// The long option (`max-depth`).
    long: String,
    kind: Kind,
    /// What the value looks like (`X,Y,Z`), if it takes one.
    pub(crate) value_name: Option<String>,
    /// The help text.
    pub(crate) help: String,
    /// The default clap fills in, if any.
    pub(crate) default: Option<String>,
}

/// `raylab render`'s options, from clap's definition.
fn command() -> clap::Command {
    <JobOptions as clap::Args>::augment_args(clap::Command::new("raylab"))
}

/// The options of `raylab render` but the scene (every keyword argument).
pub(crate) fn spec() -> &'static [Opt] {
    static SPEC: OnceLock<Vec<Opt>> = OnceLock::new();
    SPEC.get_or_init(|| {
        command()
            .get_arguments()
            .filter(|a| !a.is_positional())
            .filter_map(|a| {
                let long = a.get_long()?.to_string();
                let kind = match a.get_action() {
                    ArgAction::SetTrue => Kind::Flag,
                    ArgAction::Append => Kind::Repeat,
                    _ => Kind::Value,
                };
                let help = a.get_long_help().or(a.get_help())?.to_string();
                Some(Opt {
                    name: a.get_id().as_str().to_string(),
                    long,
                    kind,
                    value_name: a
                        .get_value_names()
                        .and_then(|v| v.first())
                        .map(|v| v.to_string())
                        .filter(|_| kind != Kind::Flag),
                    help,
                    default: a
                        .get_default_values()
                        .first()
                        .map(|v| v.to_string_lossy().into_owned()),
                })
            })
            .filter(|o| o.name != "help")
            .collect()
    })
}

/// The separator of a list's items in a value that looks like `value_name`
/// (`X,Y,Z` and `AOV,...`: `,`; `K/N`: `/`; `A..B`: `..`), if it is a list.
fn separator(value_name: &str) -> Option<&'static str> {
    let word = |s: &str| !s.is_empty() && s.chars().all(char::is_alphanumeric);
    if let Some((a, b)) = value_name.split_once("..")
        && word(a)
        && word(b)
    {
        return Some("..");
    }
    [",", "/"].into_iter().find(|s| value_name.contains(s))
}

/// The command line's text of a Python value: strings and paths as they
/// are, `True`/`False` as `true`/`false`, sequences joined by `sep`, numbers
/// as Python writes them (floats in their shortest exact form).
fn text(key: &str, value: &Bound<'_, PyAny>, sep: Option<&str>) -> PyResult<String> {
    if value.is_instance_of::<PyString>() {
        return value.extract();
    }
    if value.is_instance_of::<pyo3::types::PyBool>() {
        return Ok(value.is_truthy()?.to_string());
    }
    if value.hasattr("__fspath__")? {
        let path: PathBuf = value.extract()?;
        return Ok(path.to_string_lossy().into_owned());
    }
    let value = if value.hasattr("tolist")? {
        value.call_method0("tolist")?
    } else {
        value.clone()
    };
    if value.is_instance_of::<PyList>() || value.is_instance_of::<PyTuple>() {
        let Some(sep) = sep else {
            return Err(PyTypeError::new_err(format!(
                "{key} takes one value, not a sequence"
            )));
        };
        let items = value
            .try_iter()?
            .map(|item| text(key, &item?, None))
            .collect::<PyResult<Vec<_>>>()?;
        return Ok(items.join(sep));
    }
    if value.is_instance_of::<PyDict>() {
        return Err(PyTypeError::new_err(format!(
            "{key} takes no dict (material takes one: {{\"tall\": \"mirror\"}})"
        )));
    }
    value.str()?.extract()
}

/// The items of a repeatable option: each of a list, `PART=VALUE` of a
/// dict, or the one value.
fn items(key: &str, value: &Bound<'_, PyAny>) -> PyResult<Vec<String>> {
    if let Ok(d) = value.cast::<PyDict>() {
        return d
            .iter()
            .map(|(k, v)| Ok(format!("{}={}", text(key, &k, None)?, text(key, &v, None)?)))
            .collect();
    }
    if value.is_instance_of::<PyList>() || value.is_instance_of::<PyTuple>() {
        return value
            .try_iter()?
            .map(|item| text(key, &item?, None))
            .collect();
    }
    Ok(vec![text(key, value, None)?])
}

/// `render()`'s error for a keyword that is no option, with the closest
/// option's name when one is close.
fn unexpected(function: &str, key: &str) -> PyErr {
    let close = spec()
        .iter()
        .map(|o| (edit_distance(&o.name, key), &o.name))
        .filter(|(d, _)| *d <= 2)
        .min();
    let hint = match close {
        Some((_, name)) => format!(" (did you mean '{name}'?)"),
        None => String::new(),
    };
    PyTypeError::new_err(format!(
        "{function}() got an unexpected keyword argument '{key}'{hint}"
    ))
}

/// Levenshtein distance.
fn edit_distance(a: &str, b: &str) -> usize {
    let b: Vec<char> = b.chars().collect();
    let mut row: Vec<usize> = (0..=b.len()).collect();
    for (i, ca) in a.chars().enumerate() {
        let mut diagonal = row[0];
        row[0] = i + 1;
        for (j, cb) in b.iter().enumerate() {
            let next = (row[j + 1] + 1)
                .min(row[j] + 1)
                .min(diagonal + usize::from(ca != *cb));
            diagonal = row[j + 1];
            row[j + 1] = next;
        }
    }
    row[b.len()]
}

/// The scene's name or path.
pub(crate) fn scene_name(scene: &Bound<'_, PyAny>) -> PyResult<String> {
    if scene.is_instance_of::<PyString>() {
        return scene.extract();
    }
    if scene.hasattr("__fspath__")? {
        let path: PathBuf = scene.extract()?;
        return Ok(path.to_string_lossy().into_owned());
    }
    Err(PyTypeError::new_err(format!(
        "scene must be a raylab.Scene, a name (\"cornell\") or a path, not {}",
        scene.get_type().name()?
    )))
}

/// The command line of `scene` and `kwargs` (`raylab render`'s, without
/// `render`).
pub(crate) fn arguments(
    function: &str,
    scene: &str,
    kwargs: &Bound<'_, PyDict>,
) -> PyResult<Vec<String>> {
    let mut argv = vec!["raylab".to_string()];
    for (key, value) in kwargs.iter() {
        let key: String = key.extract()?;
        if value.is_none() {
            continue;
        }
        let name = if key == "aovs" { "aov" } else { key.as_str() };
        let opt = spec()
            .iter()
            .find(|o| o.name == name)
            .ok_or_else(|| unexpected(function, &key))?;
        match opt.kind {
            Kind::Flag => {
                if !value.is_instance_of::<pyo3::types::PyBool>() {
                    return Err(PyTypeError::new_err(format!(
                        "{key} takes True or False, not {}",
                        value.repr()?
                    )));
                }
                if value.is_truthy()? {
                    argv.push(format!("--{}", opt.long));
                }
            }
            Kind::Repeat => {
                for item in items(&key, &value)? {
                    argv.push(format!("--{}={item}", opt.long));
                }
            }
            Kind::Value => {
                let sep = opt.value_name.as_deref().and_then(separator);
                argv.push(format!("--{}={}", opt.long, text(&key, &value, sep)?));
            }
        }
    }
    argv.push("--".to_string());
    argv.push(scene.to_string());
    Ok(argv)
}

/// The options of a command line, parsed and checked as `raylab render`
/// does (a `ValueError` with its message otherwise).
pub(crate) fn parse(argv: &[String]) -> PyResult<JobOptions> {
    let value_error = |e: clap::Error| {
        let text = e.render().to_string();
        let line = text.lines().next().unwrap_or_default();
        // Which keyword it was, for Python's eyes.
        let keyword = match e.get(clap::error::ContextKind::InvalidArg) {
            Some(clap::error::ContextValue::String(arg)) => spec()
                .iter()
                .find(|o| {
                    arg.starts_with(&format!("--{} ", o.long)) || *arg == format!("--{}", o.long)
                })
                .map(|o| format!("{}: ", o.name)),
            _ => None,
        };
        PyValueError::new_err(format!(
            "{}{}",
            keyword.unwrap_or_default(),
            line.trim_start_matches("error: ")
        ))
    };
    let matches = command().try_get_matches_from(argv).map_err(value_error)?;
    let options = JobOptions::from_arg_matches(&matches).map_err(value_error)?;
    let clean = |e: String| PyValueError::new_err(e.trim_start_matches("error: ").to_string());
    options.scene.validate().map_err(clean)?;
    options.validate().map_err(clean)?;
    Ok(options)
}
