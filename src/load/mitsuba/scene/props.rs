//! An object's properties read by name and type, as Mitsuba's `Properties`
//! gives them to a plugin, remembering which were read: a property or a
//! nested object no plugin reads is an error, as in Mitsuba ("unreferenced
//! property"), so a misspelt name never passes silently.

use std::cell::RefCell;
use std::sync::Arc;

use glam::{Mat4, Vec3, Vec3A};

use super::super::error::MitsubaError;
use super::super::tree::{Object, Spectrum, Tag, Value};
use super::color::{Role, constant_to_rgb, sampled_to_rgb};
use crate::guard::quote;

/// A colour property: a value, or a texture object.
#[derive(Clone, Debug)]
pub(super) enum ColorProp {
    /// A constant RGB.
    Value(Vec3A),
    /// A nested or referenced `<texture>` (or `<spectrum type=…>`).
    Texture(Arc<Object>),
}

/// An object's properties, with what has been read.
pub(super) struct Props<'a> {
    /// The object.
    pub obj: &'a Object,
    props_read: RefCell<Vec<bool>>,
    children_read: RefCell<Vec<bool>>,
}

impl<'a> Props<'a> {
    /// The properties of `obj`, none read yet.
    pub fn new(obj: &'a Object) -> Self {
        Self {
            obj,
            props_read: RefCell::new(vec![false; obj.props.len()]),
            children_read: RefCell::new(vec![false; obj.children.len()]),
        }
    }

    /// An error about the object (at its line).
    pub fn error(&self, message: impl AsRef<str>) -> MitsubaError {
        MitsubaError::at(
            &self.obj.location.file,
            self.obj.location.line,
            format!("{}: {}", self.obj.describe(), message.as_ref()),
        )
    }

    /// An error about property `name` (at its line, else the object's).
    pub fn error_at(&self, name: &str, message: impl AsRef<str>) -> MitsubaError {
        let location = self
            .obj
            .prop(name)
            .map_or(&self.obj.location, |p| &p.location);
        MitsubaError::at(
            &location.file,
            location.line,
            format!(
                "{} parameter '{}': {}",
                self.obj.describe(),
                quote(name),
                message.as_ref()
            ),
        )
    }

    /// The value of `name`, marked read.
    fn take(&self, name: &str) -> Option<&'a Value> {
        let i = self.obj.props.iter().position(|p| p.name == name)?;
        self.props_read.borrow_mut()[i] = true;
        Some(&self.obj.props[i].value)
    }

    /// Whether `name` is given (as a value or an object), without reading it.
    pub fn has(&self, name: &str) -> bool {
        self.obj.prop(name).is_some() || self.obj.child(name).is_some()
    }

    fn wrong(&self, name: &str, want: &str, got: &Value) -> MitsubaError {
        self.error_at(name, format!("expected {want}, got <{}>", got.kind()))
    }

    /// A float (an integer is read as one, as Mitsuba does).
    pub fn float_opt(&self, name: &str) -> Result<Option<f32>, MitsubaError> {
        match self.take(name) {
            None => Ok(None),
            Some(Value::Float(f)) => Ok(Some(*f)),
            Some(Value::Integer(i)) => Ok(Some(*i as f32)),
            Some(v) => Err(self.wrong(name, "a <float>", v)),
        }
    }

    /// A float, `default` if not given.
    pub fn float(&self, name: &str, default: f32) -> Result<f32, MitsubaError> {
        Ok(self.float_opt(name)?.unwrap_or(default))
    }

    /// An integer, `default` if not given.
    pub fn integer(&self, name: &str, default: i64) -> Result<i64, MitsubaError> {
        match self.take(name) {
            None => Ok(default),
            Some(Value::Integer(i)) => Ok(*i),
            Some(v) => Err(self.wrong(name, "an <integer>", v)),
        }
    }

    /// A boolean, `default` if not given.
    pub fn boolean(&self, name: &str, default: bool) -> Result<bool, MitsubaError> {
        match self.take(name) {
            None => Ok(default),
            Some(Value::Boolean(b)) => Ok(*b),
            Some(v) => Err(self.wrong(name, "a <boolean>", v)),
        }
    }

    /// A string, if given.
    pub fn string_opt(&self, name: &str) -> Result<Option<&'a str>, MitsubaError> {
        match self.take(name) {
            None => Ok(None),
            Some(Value::String(s)) => Ok(Some(s)),
            Some(v) => Err(self.wrong(name, "a <string>", v)),
        }
    }

    /// A string, `default` if not given.
    pub fn string(&self, name: &str, default: &'a str) -> Result<&'a str, MitsubaError> {
        Ok(self.string_opt(name)?.unwrap_or(default))
    }

    /// A string that must be one of `choices`, `default` if not given.
    pub fn choice(
        &self,
        name: &str,
        default: &'a str,
        choices: &[&str],
    ) -> Result<&'a str, MitsubaError> {
        let s = self.string(name, default)?;
        match choices.contains(&s) {
            true => Ok(s),
            false => Err(self.error_at(
                name,
                format!("'{}' is not one of {}", quote(s), choices.join(", ")),
            )),
        }
    }

    /// A transform, the identity if not given.
    pub fn transform(&self, name: &str) -> Result<Mat4, MitsubaError> {
        match self.take(name) {
            None => Ok(Mat4::IDENTITY),
            Some(Value::Transform(m)) => Ok(*m),
            Some(v) => Err(self.wrong(name, "a <transform>", v)),
        }
    }

    /// A `<point>` or `<vector>`, if given.
    pub fn vector_opt(&self, name: &str) -> Result<Option<Vec3>, MitsubaError> {
        match self.take(name) {
            None => Ok(None),
            Some(Value::Point(p) | Value::Vector(p)) => Ok(Some(*p)),
            Some(v) => Err(self.wrong(name, "a <point> or <vector>", v)),
        }
    }

    /// A colour or texture in `role`, if given.
    pub fn color_opt(&self, name: &str, role: Role) -> Result<Option<ColorProp>, MitsubaError> {
        if let Some(child) = self.child_opt(name) {
            return match child.tag {
                Tag::Texture | Tag::Spectrum => Ok(Some(ColorProp::Texture(child))),
                other => Err(self.error_at(
                    name,
                    format!("expected a texture or a colour, got a {other}"),
                )),
            };
        }
        let rgb = match self.take(name) {
            None => return Ok(None),
            Some(Value::Rgb(c)) => Vec3A::from(*c),
            Some(Value::Float(f)) => Vec3A::splat(*f),
            Some(Value::Integer(i)) => Vec3A::splat(*i as f32),
            Some(Value::Spectrum(Spectrum::Constant(c))) => constant_to_rgb(*c, role),
            Some(Value::Spectrum(Spectrum::Sampled(points))) => sampled_to_rgb(points, role),
            Some(Value::Spectrum(Spectrum::File(path))) => {
                return Err(self.error_at(
                    name,
                    format!(
                        "spectra read from files ({}) are not supported yet; give an <rgb> or wavelength:value pairs",
                        path.display()
                    ),
                ));
            }
            Some(v) => {
                return Err(self.wrong(
                    name,
                    "a colour (<rgb>, <spectrum>, <float>) or a texture",
                    v,
                ));
            }
        };
        if !rgb.is_finite() {
            return Err(self.error_at(name, "is not finite"));
        }
        Ok(Some(ColorProp::Value(rgb)))
    }

    /// A constant colour in `role` (a texture is refused), `default` if not given.
    pub fn constant_color(
        &self,
        name: &str,
        role: Role,
        default: Vec3A,
    ) -> Result<Vec3A, MitsubaError> {
        match self.color_opt(name, role)? {
            None => Ok(default),
            Some(ColorProp::Value(c)) => Ok(c),
            Some(ColorProp::Texture(t)) => Err(self.error_at(
                name,
                format!(
                    "a texture ({}) is not supported here yet; give a constant",
                    t.describe()
                ),
            )),
        }
    }

    /// The child object named `name`, marked read.
    pub fn child_opt(&self, name: &str) -> Option<Arc<Object>> {
        let i = self
            .obj
            .children
            .iter()
            .position(|c| c.name.as_deref() == Some(name))?;
        self.children_read.borrow_mut()[i] = true;
        Some(self.obj.children[i].object.clone())
    }

    /// The child objects of kind `tag`, marked read.
    pub fn children_of(&self, tag: Tag) -> Vec<Arc<Object>> {
        let mut read = self.children_read.borrow_mut();
        self.obj
            .children
            .iter()
            .enumerate()
            .filter(|(_, c)| c.object.tag == tag)
            .map(|(i, c)| {
                read[i] = true;
                c.object.clone()
            })
            .collect()
    }

    /// Marks properties as read without using them (what raylab knows and
    /// deliberately ignores, such as a film's pixel format).
    pub fn ignore(&self, names: &[&str]) {
        for name in names {
            let _ = self.take(name);
            let _ = self.child_opt(name);
        }
    }

    /// Fails on the first property or nested object nothing read.
    pub fn finish(&self) -> Result<(), MitsubaError> {
        let read = self.props_read.borrow();
        if let Some((p, _)) = self.obj.props.iter().zip(read.iter()).find(|(_, r)| !**r) {
            return Err(MitsubaError::at(
                &p.location.file,
                p.location.line,
                format!(
                    "{}: unused parameter '{}' (raylab does not read it; Mitsuba would refuse an unknown one too)",
                    self.obj.describe(),
                    quote(&p.name)
                ),
            ));
        }
        let read = self.children_read.borrow();
        if let Some((c, _)) = self
            .obj
            .children
            .iter()
            .zip(read.iter())
            .find(|(_, r)| !**r)
        {
            return Err(MitsubaError::at(
                &c.location.file,
                c.location.line,
                format!(
                    "{}: unused {} inside it",
                    self.obj.describe(),
                    c.object.describe()
                ),
            ));
        }
        Ok(())
    }
}
