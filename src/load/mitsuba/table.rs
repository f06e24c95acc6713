//! The flat table the files are read into before the tree is made: one
//! [`Node`] per object, its children as indices or still unresolved ids.

use super::tree::{Location, Property, Tag};
use crate::guard::quote;

/// An object while the files are read: its children are still indices or
/// unresolved ids.
pub(super) struct Node {
    pub tag: Tag,
    pub plugin: String,
    pub id: Option<String>,
    pub name: Option<String>,
    pub props: Vec<Property>,
    pub edges: Vec<Edge>,
    pub location: Location,
    /// Index of the file it was written in (into the reader's versions).
    pub file: usize,
}

impl Node {
    /// Whether a property or a child has this name.
    pub fn has(&self, name: &str) -> bool {
        self.props.iter().any(|p| p.name == name)
            || self.edges.iter().any(|e| e.name.as_deref() == Some(name))
    }

    /// Where the property or child of this name was given.
    pub fn first(&self, name: &str) -> Option<&Location> {
        let prop = self.props.iter().find(|p| p.name == name);
        let edge = self.edges.iter().find(|e| e.name.as_deref() == Some(name));
        prop.map(|p| &p.location).or(edge.map(|e| &e.location))
    }

    pub fn describe(&self) -> String {
        format!("{} '{}'", self.tag, quote(&self.plugin))
    }
}

/// A child of a [`Node`].
pub(super) struct Edge {
    pub name: Option<String>,
    pub target: Target,
    pub location: Location,
    pub by_ref: bool,
}

/// What an [`Edge`] leads to.
pub(super) enum Target {
    /// A node of the table.
    Node(usize),
    /// An id, until references are resolved.
    Ref(String),
}
