//! `<include>` (Mitsuba's `TagType::Include` in `parse_xml_node`): the
//! file looked up in the including file's folder, then the search paths;
//! read into the same table with the including file's folder searched first
//! while it is read; a `<scene>` root's objects given to the including
//! object, any other root attached as one child. Nesting is limited to
//! [`MAX_INCLUDE_DEPTH`] levels and a cycle is named.

use std::path::Path;
use std::sync::Arc;

use super::{Doc, Included, Reader, read_text_file};
use crate::guard::quote;
use crate::load::mitsuba::attrs::Attrs;
use crate::load::mitsuba::table::{Edge, Target};
use crate::load::mitsuba::tree::{MAX_INCLUDE_DEPTH, resolve_in};

impl Reader {
    /// An `<include>` under `parent`: the file found, read into the table
    /// and attached.
    pub(super) fn include(
        &mut self,
        d: &Doc,
        el: roxmltree::Node,
        attrs: &Attrs,
        parent: usize,
    ) -> Result<(), Included> {
        let file = attrs.get("filename").unwrap_or_default();
        if d.depth + 1 >= MAX_INCLUDE_DEPTH {
            return Err(Included::Here(format!(
                "includes nested deeper than {MAX_INCLUDE_DEPTH} levels"
            )));
        }
        // The including file's folder first, then the search paths.
        let mut dirs = vec![d.dir.clone()];
        dirs.extend(self.search.iter().cloned());
        let Some(found) = resolve_in(&dirs, Path::new(file)) else {
            let looked: Vec<String> = dirs.iter().map(|p| p.display().to_string()).collect();
            return Err(Included::Here(format!(
                "included file \"{file}\" not found (looked in {})",
                looked.join(", ")
            )));
        };
        let canonical = std::fs::canonicalize(&found).unwrap_or_else(|_| found.clone());
        if let Some(start) = self.reading.iter().position(|(c, _)| *c == canonical) {
            let mut chain: Vec<String> = self.reading[start..]
                .iter()
                .map(|(_, p)| p.display().to_string())
                .collect();
            chain.push(found.display().to_string());
            return Err(Included::Here(format!(
                "include cycle: {}",
                chain.join(" -> ")
            )));
        }
        let text = read_text_file(&found).map_err(Included::Inside)?;
        let saved = self.search.clone();
        self.search.insert(0, d.dir.clone());
        self.reading.push((canonical, Arc::from(found.as_path())));
        let read = self.document(&text, &found, d.depth + 1);
        self.reading.pop();
        self.search = saved;
        let root = read.map_err(Included::Inside)?;
        if self.nodes[root].plugin == "scene" {
            // Its objects join `parent`; its own values are dropped, as
            // Mitsuba drops them, and so is its id.
            let edges = std::mem::take(&mut self.nodes[root].edges);
            for e in &edges {
                if let Some(n) = &e.name {
                    self.add_name(parent, n).map_err(Included::Here)?;
                }
            }
            self.nodes[parent].edges.extend(edges);
            let dropped: Vec<String> = self.nodes[root]
                .props
                .iter()
                .map(|p| quote(&p.name))
                .collect();
            if !dropped.is_empty() {
                self.warnings.push(crate::guard::one_line(&format!(
                    "{}: the values of an included <scene> are ignored (as Mitsuba ignores them): {}",
                    self.nodes[root].location,
                    dropped.join(", ")
                )).into_owned());
            }
            if let Some(id) = self.nodes[root].id.clone()
                && self.ids.get(&id).is_some_and(|(i, _)| *i == root)
            {
                self.ids.remove(&id);
            }
        } else {
            let name = attrs.get("name").map(str::to_string);
            if let Some(n) = &name {
                self.add_name(parent, n).map_err(Included::Here)?;
            }
            self.nodes[parent].edges.push(Edge {
                name,
                target: Target::Node(root),
                location: d.location(el),
                by_ref: false,
            });
        }
        Ok(())
    }
}
