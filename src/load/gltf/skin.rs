//! Skins and morph targets: a primitive's vertices deformed for one node at
//! one pose, before its triangles are made.
//!
//! Morph targets first (glTF 2.0 §3.7.2.2): each target's `POSITION`,
//! `NORMAL` and `TANGENT` deltas are added, times the node's weights (its
//! animated ones, else its `weights`, else its mesh's); normals and tangents
//! are normalized after. Then the skin (§3.7.3): each vertex is moved by the
//! weighted sum of its joints' matrices, `globalTransform(joint) ·
//! inverseBindMatrix(joint)`, straight into world space — the transform of
//! the skinned mesh's own node is ignored, as the specification says
//! (equivalently, its joint matrices carry `inverse(globalTransform(node))`
//! and the node's transform is applied after). Normals go through the
//! inverse transpose of the vertex's matrix, tangents through the matrix,
//! both normalized.
//!
//! Weights of a vertex are divided by their sum (a file's weights should sum
//! to 1 already; quantized ones rarely do exactly); a vertex whose weights
//! are all 0 follows the mesh's node.

use glam::{Mat3, Mat4, Vec3};
use gltf::json::{self, validation::Checked};

use super::accessor::{read_floats, type_components};
use super::buffers::Buffers;
use super::error::{GltfError, MAX_NODE_DEPTH, valid};
use crate::scene::mesh::{MeshData, Tangents};

/// Every node's global transform (parent × child down from the roots, the
/// nodes that are nobody's child), `None` for nodes that no root reaches (a
/// cycle). `local(i)` gives node `i`'s local transform. A node that is the
/// child of two nodes, or a missing child, is an error.
pub(crate) fn node_globals(
    root: &json::Root,
    local: impl Fn(usize) -> Result<Mat4, GltfError>,
) -> Result<Vec<Option<Mat4>>, GltfError> {
    let n = root.nodes.len();
    let mut parent: Vec<Option<usize>> = vec![None; n];
    for (i, node) in root.nodes.iter().enumerate() {
        for child in node.children.iter().flatten() {
            let c = child.value();
            let slot = parent
                .get_mut(c)
                .ok_or_else(|| GltfError::invalid(format!("node {i}: child {c} does not exist")))?;
            if slot.replace(i).is_some() || c == i {
                return Err(GltfError::invalid(format!(
                    "node {c} is the child of more than one node (or of itself)"
                )));
            }
        }
    }
    let mut globals: Vec<Option<Mat4>> = vec![None; n];
    // (node, its parent's global, depth), depth first from each root.
    let mut stack: Vec<(usize, Mat4, usize)> = (0..n)
        .rev()
        .filter(|&i| parent[i].is_none())
        .map(|i| (i, Mat4::IDENTITY, 0))
        .collect();
    while let Some((i, above, depth)) = stack.pop() {
        if depth >= MAX_NODE_DEPTH {
            return Err(GltfError::invalid(format!(
                "the node tree is deeper than {MAX_NODE_DEPTH} levels"
            )));
        }
        let global = above * local(i)?;
        globals[i] = Some(global);
        for child in root.nodes[i].children.iter().flatten().rev() {
            stack.push((child.value(), global, depth + 1));
        }
    }
    Ok(globals)
}

/// Skin `s`'s joint matrices, `globalTransform(joint) ·
/// inverseBindMatrix(joint)` (inverse bind matrices default to the
/// identity), from the nodes' `globals`.
pub(crate) fn joint_matrices(
    root: &json::Root,
    buffers: &Buffers,
    s: usize,
    globals: &[Option<Mat4>],
) -> Result<Vec<Mat4>, GltfError> {
    let what = format!("skin {s}");
    let skin = root
        .skins
        .get(s)
        .ok_or_else(|| GltfError::invalid(format!("{what} does not exist")))?;
    let joints = skin.joints.len();
    if joints == 0 {
        return Err(GltfError::invalid(format!("{what} has no joints")));
    }
    let inverse_binds: Vec<Mat4> = match skin.inverse_bind_matrices {
        None => vec![Mat4::IDENTITY; joints],
        Some(a) => {
            let a = a.value();
            let ibm_what = format!("{what} inverseBindMatrices");
            if components(root, a) != Some(16) {
                return Err(GltfError::invalid(format!(
                    "{ibm_what}: accessor {a} must hold 4×4 matrices"
                )));
            }
            let m: Vec<Mat4> = read_floats::<16>(buffers, a, &ibm_what)?
                .iter()
                .map(Mat4::from_cols_array)
                .collect();
            if m.len() < joints {
                return Err(GltfError::invalid(format!(
                    "{ibm_what}: {} matrices for {joints} joints",
                    m.len()
                )));
            }
            if let Some(k) = m.iter().position(|x| !x.is_finite()) {
                return Err(GltfError::invalid(format!(
                    "{ibm_what}: matrix {k} is not finite"
                )));
            }
            m
        }
    };
    skin.joints
        .iter()
        .zip(inverse_binds)
        .map(|(joint, inverse_bind)| {
            let j = joint.value();
            match globals.get(j) {
                Some(Some(global)) => Ok(*global * inverse_bind),
                Some(None) => Err(GltfError::invalid(format!(
                    "{what}: joint node {j} is in a cycle of nodes"
                ))),
                None => Err(GltfError::invalid(format!(
                    "{what}: joint node {j} does not exist"
                ))),
            }
        })
        .collect()
}

/// Components per element of accessor `index`, if it exists and is valid.
fn components(root: &json::Root, index: usize) -> Option<usize> {
    let acc = root.accessors.get(index)?;
    valid(&acc.type_).map(|t| type_components(*t))
}

/// The morph weights of node `node` showing mesh `m`: the pose's, else the
/// node's `weights`, else the mesh's, else none (all 0). Checked finite.
pub(crate) fn morph_weights(
    root: &json::Root,
    node: usize,
    m: usize,
    posed: Option<&Vec<f32>>,
) -> Result<Vec<f32>, GltfError> {
    let weights = posed
        .or(root.nodes[node].weights.as_ref())
        .or(root.meshes[m].weights.as_ref())
        .cloned()
        .unwrap_or_default();
    if weights.iter().any(|w| !w.is_finite()) {
        return Err(GltfError::invalid(format!(
            "node {node}: morph target weights must be finite"
        )));
    }
    Ok(weights)
}

/// How one node deforms its mesh's primitives.
pub(crate) struct Deformation<'a> {
    /// The skin's joint matrices, if the node has a skin.
    pub joints: Option<&'a [Mat4]>,
    /// Morph target weights (missing ones are 0).
    pub weights: &'a [f32],
    /// Where a skinned vertex without any weight goes: the mesh node's
    /// global transform.
    pub node_global: Mat4,
}

impl Deformation<'_> {
    /// Whether primitive `prim` changes at all under this deformation.
    pub fn applies_to(&self, prim: &json::mesh::Primitive) -> bool {
        let morphs = prim
            .targets
            .as_ref()
            .is_some_and(|t| t.iter().zip(self.weights).any(|(_, &w)| w != 0.0));
        morphs || self.skins(prim)
    }

    /// Whether `prim` is skinned by this node (a skin and `JOINTS_0`).
    pub fn skins(&self, prim: &json::mesh::Primitive) -> bool {
        self.joints.is_some() && prim.attributes.contains_key(&joints_semantic(0))
    }
}

fn joints_semantic(set: u32) -> Checked<json::mesh::Semantic> {
    Checked::Valid(json::mesh::Semantic::Joints(set))
}

fn weights_semantic(set: u32) -> Checked<json::mesh::Semantic> {
    Checked::Valid(json::mesh::Semantic::Weights(set))
}

/// Reads a morph target's deltas (`count` VEC3s, one per vertex).
fn deltas(buffers: &Buffers, a: usize, count: usize, what: &str) -> Result<Vec<Vec3>, GltfError> {
    if components(buffers.root, a) != Some(3) {
        return Err(GltfError::invalid(format!(
            "{what}: accessor {a} must hold 3-component deltas"
        )));
    }
    let d = read_floats::<3>(buffers, a, what)?;
    if d.len() != count {
        return Err(GltfError::invalid(format!(
            "{what} has {} elements but POSITION has {count}",
            d.len()
        )));
    }
    if d.iter().flatten().any(|v| !v.is_finite()) {
        return Err(GltfError::invalid(format!("{what}: a delta is not finite")));
    }
    Ok(d.into_iter().map(Vec3::from).collect())
}

/// `base` (primitive `p` of mesh `m` as read) deformed by `how`: morphed,
/// then skinned into world space. Generated tangents (one per corner) are
/// made again from the deformed mesh with texture coordinates `tangent_set`.
pub(crate) fn deform(
    buffers: &Buffers,
    m: usize,
    p: usize,
    base: &MeshData,
    how: &Deformation,
    tangent_set: usize,
) -> Result<MeshData, GltfError> {
    let prim = &buffers.root.meshes[m].primitives[p];
    let what = format!("mesh {m} primitive {p}");
    let n = base.positions.len();
    let mut data = base.clone();
    if let Some(targets) = &prim.targets {
        for (t, (target, &w)) in targets.iter().zip(how.weights).enumerate() {
            if w == 0.0 {
                continue;
            }
            let name = |attr: &str| format!("{what} morph target {t} {attr}");
            if let Some(a) = target.positions {
                for (v, d) in
                    data.positions
                        .iter_mut()
                        .zip(deltas(buffers, a.value(), n, &name("POSITION"))?)
                {
                    *v += w * d;
                }
            }
            if let Some(a) = target.normals
                && !data.normals.is_empty()
            {
                for (v, d) in
                    data.normals
                        .iter_mut()
                        .zip(deltas(buffers, a.value(), n, &name("NORMAL"))?)
                {
                    *v += w * d;
                }
            }
            if let (Some(a), Tangents::PerVertex(tangents)) = (target.tangents, &mut data.tangents)
            {
                for (v, d) in
                    tangents
                        .iter_mut()
                        .zip(deltas(buffers, a.value(), n, &name("TANGENT"))?)
                {
                    *v += (w * d).extend(0.0);
                }
            }
        }
        for v in &mut data.normals {
            *v = v.normalize_or_zero();
        }
        if let Tangents::PerVertex(tangents) = &mut data.tangents {
            for v in tangents {
                *v = v.truncate().normalize_or_zero().extend(v.w);
            }
        }
    }
    if how.skins(prim)
        && let Some(joints) = how.joints
    {
        skin(buffers, prim, &what, &mut data, joints, how.node_global)?;
    }
    if let Some(i) = data.positions.iter().position(|v| !v.is_finite()) {
        return Err(GltfError::invalid(format!(
            "{what}: vertex {i} is not finite once morphed and skinned"
        )));
    }
    if matches!(data.tangents, Tangents::PerCorner(_)) {
        data.tangents = super::tangents::generate(&data, tangent_set);
    }
    Ok(data)
}

/// Moves `data`'s vertices, normals and tangents by the weighted joint
/// matrices of each vertex's `JOINTS_n`/`WEIGHTS_n` sets.
fn skin(
    buffers: &Buffers,
    prim: &json::mesh::Primitive,
    what: &str,
    data: &mut MeshData,
    joints: &[Mat4],
    node_global: Mat4,
) -> Result<(), GltfError> {
    let n = data.positions.len();
    // The blended matrix of each vertex, summed over the sets.
    let mut blend = vec![Mat4::ZERO; n];
    let mut total = vec![0.0f32; n];
    let mut set = 0u32;
    while let Some(j) = prim.attributes.get(&joints_semantic(set)) {
        let set_what = |name: &str| format!("{what} {name}_{set}");
        let w = prim.attributes.get(&weights_semantic(set)).ok_or_else(|| {
            GltfError::invalid(format!("{} has no WEIGHTS_{set}", set_what("JOINTS")))
        })?;
        let mut sets = Vec::with_capacity(2);
        for (a, name) in [(j.value(), "JOINTS"), (w.value(), "WEIGHTS")] {
            if components(buffers.root, a) != Some(4) {
                return Err(GltfError::invalid(format!(
                    "{}: accessor {a} must have 4 components per element",
                    set_what(name)
                )));
            }
            let v = read_floats::<4>(buffers, a, &set_what(name))?;
            if v.len() != n {
                return Err(GltfError::invalid(format!(
                    "{} has {} elements but POSITION has {n}",
                    set_what(name),
                    v.len()
                )));
            }
            sets.push(v);
        }
        let (ids, weights) = (&sets[0], &sets[1]);
        for v in 0..n {
            for k in 0..4 {
                let (id, weight) = (ids[v][k], weights[v][k]);
                if weight == 0.0 {
                    continue;
                }
                if !weight.is_finite() || weight < 0.0 {
                    return Err(GltfError::invalid(format!(
                        "{}: vertex {v} has weight {weight} (must be finite and >= 0)",
                        set_what("WEIGHTS")
                    )));
                }
                let joint = joints
                    .get(id as usize)
                    .filter(|_| id.fract() == 0.0 && id >= 0.0)
                    .ok_or_else(|| {
                        GltfError::invalid(format!(
                            "{}: vertex {v} names joint {id}, but the skin has {}",
                            set_what("JOINTS"),
                            joints.len()
                        ))
                    })?;
                blend[v] += *joint * weight;
                total[v] += weight;
            }
        }
        set += 1;
    }
    for v in 0..n {
        let m = if total[v] > 0.0 {
            blend[v] * (1.0 / total[v])
        } else {
            node_global
        };
        data.positions[v] = m.transform_point3(data.positions[v]);
        let linear = Mat3::from_mat4(m);
        // The inverse transpose keeps normals perpendicular under
        // non-uniform scale; a singular matrix falls back to the linear part.
        let for_normals = match linear.determinant() {
            d if d != 0.0 && d.is_finite() => linear.inverse().transpose(),
            _ => linear,
        };
        if let Some(normal) = data.normals.get_mut(v) {
            *normal = (for_normals * *normal).normalize_or_zero();
        }
        if let Tangents::PerVertex(tangents) = &mut data.tangents
            && let Some(t) = tangents.get_mut(v)
        {
            *t = (linear * t.truncate()).normalize_or_zero().extend(t.w);
        }
    }
    Ok(())
}
