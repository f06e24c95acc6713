//! An element's attributes after `$name` substitution, and Mitsuba's
//! check that every one is known and the required ones are there.

use crate::guard::quote;

/// An element's attributes after substitution, in order.
pub(super) struct Attrs {
    list: Vec<(String, String)>,
}

impl Attrs {
    /// The attributes `(name, value)`, in order.
    pub fn new(list: Vec<(String, String)>) -> Self {
        Attrs { list }
    }

    /// The attribute `key`.
    pub fn get(&self, key: &str) -> Option<&str> {
        self.list
            .iter()
            .find(|(k, _)| k == key)
            .map(|(_, v)| v.as_str())
    }

    /// Removes the attribute `key`.
    pub fn remove(&mut self, key: &str) {
        self.list.retain(|(k, _)| k != key);
    }

    /// Adds an attribute.
    pub fn push(&mut self, key: &str, value: String) {
        self.list.push((key.to_string(), value));
    }

    /// Mitsuba's `check_attributes`: every attribute is one of `spec`, and
    /// those marked `!` are present.
    pub fn check(&self, spec: &[&str]) -> Result<(), String> {
        for (k, _) in &self.list {
            if !spec.iter().any(|s| s.trim_start_matches('!') == k) {
                return Err(format!("unexpected attribute \"{}\"", quote(k)));
            }
        }
        for s in spec {
            if let Some(k) = s.strip_prefix('!')
                && self.get(k).is_none()
            {
                return Err(format!("missing required attribute \"{k}\""));
            }
        }
        Ok(())
    }
}
