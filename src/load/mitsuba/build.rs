//! The table of objects the files were read into, turned into the tree
//! (Mitsuba's `transform_resolve`, then raylab's own building): every
//! `<ref>` resolved to its object (an unknown id is an error at the
//! `<ref>`), cycles of references refused (Mitsuba's `check_cycles`), and
//! each object made once, children first, so that an object referenced
//! from many places is one shared [`Arc`].

use std::collections::HashMap;
use std::sync::Arc;

use super::error::MitsubaError;
use super::table::{Edge, Node, Target};
use super::tree::{Child, Location, MAX_NESTING, Object};
use crate::guard::quote;

/// The tree under `root` made of `nodes`, references looked up in `ids`.
pub(super) fn build(
    mut nodes: Vec<Node>,
    ids: &HashMap<String, (usize, Location)>,
    root: usize,
) -> Result<Arc<Object>, MitsubaError> {
    // References, in every node (as Mitsuba checks them all).
    for node in &mut nodes {
        let describe = format!("{} '{}'", node.tag, quote(&node.plugin));
        for e in &mut node.edges {
            if let Target::Ref(id) = &e.target {
                let Some(&(index, _)) = ids.get(id) else {
                    let name = match &e.name {
                        Some(n) => format!(" \"{}\"", quote(n)),
                        None => String::new(),
                    };
                    return Err(MitsubaError::at(
                        &e.location.file,
                        e.location.line,
                        format!(
                            "<ref{name}> to unknown id \"{}\" (in {describe}; no object has id=\"{0}\")",
                            quote(id)
                        ),
                    ));
                };
                e.target = Target::Node(index);
            }
        }
    }
    let order = post_order(&nodes, root)?;
    // Children before parents: each object is made once and shared.
    let mut made: Vec<Option<Arc<Object>>> = vec![None; nodes.len()];
    for i in order {
        let node = &mut nodes[i];
        let children = node
            .edges
            .iter()
            .map(|e| Child {
                name: e.name.clone(),
                object: made[target(e)].clone().expect("children are made first"),
                location: e.location.clone(),
                by_ref: e.by_ref,
            })
            .collect();
        made[i] = Some(Arc::new(Object {
            tag: node.tag,
            plugin: std::mem::take(&mut node.plugin),
            id: node.id.take(),
            name: node.name.take(),
            props: std::mem::take(&mut node.props),
            children,
            location: node.location.clone(),
        }));
    }
    Ok(made[root].take().expect("the root is made"))
}

fn target(e: &Edge) -> usize {
    match e.target {
        Target::Node(i) => i,
        Target::Ref(_) => unreachable!("references are resolved before"),
    }
}

/// The nodes reachable from `root`, each after all its children; a cycle
/// or a chain deeper than [`MAX_NESTING`] is an error. Iterative, so that
/// no input can exhaust the stack.
fn post_order(nodes: &[Node], root: usize) -> Result<Vec<usize>, MitsubaError> {
    #[derive(Clone, Copy, PartialEq)]
    enum State {
        New,
        Open,
        Done,
    }
    let mut state = vec![State::New; nodes.len()];
    let mut height = vec![0usize; nodes.len()];
    let mut order = Vec::new();
    // (node, next edge to follow)
    let mut stack: Vec<(usize, usize)> = vec![(root, 0)];
    state[root] = State::Open;
    while let Some(&mut (n, ref mut next)) = stack.last_mut() {
        if let Some(e) = nodes[n].edges.get(*next) {
            *next += 1;
            let c = target(e);
            match state[c] {
                State::Done => {}
                State::New => {
                    state[c] = State::Open;
                    stack.push((c, 0));
                }
                State::Open => {
                    let start = stack.iter().position(|&(s, _)| s == c).unwrap_or(0);
                    let mut chain: Vec<String> = stack[start..]
                        .iter()
                        .map(|&(s, _)| label(&nodes[s]))
                        .collect();
                    chain.push(label(&nodes[c]));
                    return Err(MitsubaError::at(
                        &e.location.file,
                        e.location.line,
                        format!("circular reference: {}", chain.join(" -> ")),
                    ));
                }
            }
            continue;
        }
        stack.pop();
        let h = 1 + nodes[n]
            .edges
            .iter()
            .map(|e| height[target(e)])
            .max()
            .unwrap_or(0);
        if h > MAX_NESTING {
            let l = &nodes[n].location;
            return Err(MitsubaError::at(
                &l.file,
                l.line,
                format!(
                    "{} '{}': objects nested more than {MAX_NESTING} deep (through references)",
                    nodes[n].tag,
                    quote(&nodes[n].plugin)
                ),
            ));
        }
        height[n] = h;
        state[n] = State::Done;
        order.push(n);
    }
    Ok(order)
}

/// A node in a cycle's message: its id, or its kind and plugin.
fn label(node: &Node) -> String {
    match &node.id {
        Some(id) => format!("\"{}\"", quote(id)),
        None => format!("{} '{}'", node.tag, quote(&node.plugin)),
    }
}
