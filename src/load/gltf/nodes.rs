//! The scene graph: the default scene's node tree walked depth first, each
//! node's transform (posed by the animation), `KHR_node_visibility`, and the
//! meshes placed at the nodes: instances sharing their mesh data,
//! `EXT_mesh_gpu_instancing`, skins and morph targets.

use std::collections::HashSet;

use glam::{Affine3A, Mat4, Quat, Vec3};
use gltf::json;

use super::accessor::{self, read_floats};
use super::animation::Pose;
use super::error::{GltfError, MAX_NODE_DEPTH, valid};
use super::loader::Loader;
use super::skin;
use crate::geometry::triangle::Triangle;
use crate::memory::{GEOMETRY_BYTES_PER_TRIANGLE, Needs};
use crate::scene::mesh::Instance;

/// Most triangles a scene may have after instancing (2^26: about 10 GB with
/// the BVH and per-triangle data, within a workstation's memory).
pub const MAX_TRIANGLES: u64 = 1 << 26;

impl Loader<'_> {
    /// Walks the default scene's node tree depth first (children in array
    /// order), composing transforms parent × child.
    pub(super) fn walk_scene(&mut self) -> Result<(), GltfError> {
        let root = self.root;
        let roots: Vec<usize> = match root
            .scene
            .map(|s| s.value())
            .or((!root.scenes.is_empty()).then_some(0))
        {
            Some(s) => root
                .scenes
                .get(s)
                .ok_or_else(|| GltfError::invalid(format!("the default scene {s} does not exist")))?
                .nodes
                .iter()
                .map(|n| n.value())
                .collect(),
            None => {
                // No scenes: every node that is nobody's child.
                let children: HashSet<usize> = root
                    .nodes
                    .iter()
                    .flat_map(|n| n.children.iter().flatten().map(|c| c.value()))
                    .collect();
                (0..root.nodes.len())
                    .filter(|i| !children.contains(i))
                    .collect()
            }
        };
        let mut visited = vec![false; root.nodes.len()];
        // (node, parent transform, depth, parent visible), popped in
        // depth-first pre-order.
        let mut stack: Vec<(usize, Mat4, usize, bool)> = roots
            .iter()
            .rev()
            .map(|&n| (n, Mat4::IDENTITY, 0, true))
            .collect();
        while let Some((index, parent, depth, parent_visible)) = stack.pop() {
            let node = root
                .nodes
                .get(index)
                .ok_or_else(|| GltfError::invalid(format!("node {index} does not exist")))?;
            if std::mem::replace(&mut visited[index], true) {
                return Err(GltfError::invalid(format!(
                    "node {index} appears twice in the scene's node tree (a cycle or a shared child)"
                )));
            }
            if depth >= MAX_NODE_DEPTH {
                return Err(GltfError::invalid(format!(
                    "the node tree is deeper than {MAX_NODE_DEPTH} levels"
                )));
            }
            let world = parent * local_transform(node, index, self.pose.as_ref())?;
            // `KHR_node_visibility`: a hidden node hides its meshes and
            // lights and all its descendants'; its cameras still see.
            let visible = parent_visible && node_visible(node, index)?;
            if let Some(cam) = node.camera {
                self.camera(cam.value(), &world)?;
            }
            if let Some(light) = node
                .extensions
                .as_ref()
                .and_then(|e| e.khr_lights_punctual.as_ref())
                .filter(|_| visible)
            {
                self.light(light.light.value(), &world)?;
            }
            if let Some(mesh) = node.mesh.filter(|_| visible) {
                match node
                    .extensions
                    .as_ref()
                    .and_then(|e| e.others.get("EXT_mesh_gpu_instancing"))
                {
                    Some(ext) => self.gpu_instances(index, ext, mesh.value(), &world)?,
                    None => self.mesh_instance(index, mesh.value(), &world)?,
                }
            }
            for child in node.children.iter().flatten().rev() {
                stack.push((child.value(), world, depth + 1, visible));
            }
        }
        Ok(())
    }

    /// `EXT_mesh_gpu_instancing` on node `node`: one instance of the node's
    /// mesh per element of its TRANSLATION, ROTATION and SCALE accessors, each
    /// at `world` × the element's T·R·S, sharing the mesh as node instances
    /// do. The node's mesh is drawn only through them.
    fn gpu_instances(
        &mut self,
        node: usize,
        ext: &serde_json::Value,
        mesh: usize,
        world: &Mat4,
    ) -> Result<(), GltfError> {
        let what = format!("node {node} EXT_mesh_gpu_instancing");
        let attributes = ext
            .get("attributes")
            .and_then(|a| a.as_object())
            .ok_or_else(|| GltfError::invalid(format!("{what}: no attributes object")))?;
        let index_of = |name: &str| -> Result<Option<usize>, GltfError> {
            let Some(v) = attributes.get(name) else {
                return Ok(None);
            };
            // An integer, also when written as one with a fraction of zero.
            match v.as_u64().or_else(|| {
                v.as_f64()
                    .filter(|f| f.fract() == 0.0 && *f >= 0.0 && *f < u32::MAX as f64)
                    .map(|f| f as u64)
            }) {
                Some(i) => Ok(Some(i as usize)),
                None => Err(GltfError::invalid(format!(
                    "{what}: {name} is not an accessor index"
                ))),
            }
        };
        let (t, r, s) = (
            index_of("TRANSLATION")?,
            index_of("ROTATION")?,
            index_of("SCALE")?,
        );
        let counts: Vec<(&str, u64)> = [("TRANSLATION", t), ("ROTATION", r), ("SCALE", s)]
            .into_iter()
            .filter_map(|(name, a)| a.map(|a| (name, a)))
            .map(|(name, a)| {
                self.root
                    .accessors
                    .get(a)
                    .map(|acc| (name, acc.count.0))
                    .ok_or_else(|| {
                        GltfError::invalid(format!("{what}: {name} accessor {a} does not exist"))
                    })
            })
            .collect::<Result<_, _>>()?;
        let Some(&(_, count)) = counts.first() else {
            return Err(GltfError::invalid(format!(
                "{what}: none of TRANSLATION, ROTATION and SCALE is given"
            )));
        };
        if let Some((name, n)) = counts.iter().find(|(_, n)| *n != count) {
            return Err(GltfError::invalid(format!(
                "{what}: {name} has {n} elements but {} has {count}",
                counts[0].0
            )));
        }
        if let Some(a) = r {
            // read_floats::<4> would take a VEC3 as a colour without alpha.
            let n = valid(&self.root.accessors[a].type_).map(|&t| accessor::type_components(t));
            if n != Some(4) {
                return Err(GltfError::invalid(format!(
                    "{what}: ROTATION accessor {a} is not VEC4"
                )));
            }
        }
        // Each array is checked against the bytes behind it before it is
        // allocated (read_floats), so `count` is backed by the file.
        let read3 = |a: Option<usize>, name: &str| -> Result<Option<Vec<[f32; 3]>>, GltfError> {
            a.map(|a| read_floats::<3>(self.buffers, a, &format!("{what} {name}")))
                .transpose()
        };
        let translations = read3(t, "TRANSLATION")?;
        let scales = read3(s, "SCALE")?;
        let rotations = r
            .map(|a| read_floats::<4>(self.buffers, a, &format!("{what} ROTATION")))
            .transpose()?;
        let count = count as usize;
        for k in 0..count {
            let t = translations
                .as_ref()
                .map_or(Vec3::ZERO, |v| Vec3::from(v[k]));
            let s = scales.as_ref().map_or(Vec3::ONE, |v| Vec3::from(v[k]));
            let q = rotations
                .as_ref()
                .map_or(Quat::IDENTITY, |v| Quat::from_array(v[k]));
            if !(t.is_finite() && s.is_finite() && q.is_finite()) {
                return Err(GltfError::invalid(format!(
                    "{what}: instance {k}'s transform is not finite"
                )));
            }
            // As a node's rotation: normalized, the identity if zero.
            let q = if q.length_squared() > 0.0 {
                q.normalize()
            } else {
                Quat::IDENTITY
            };
            let before = self.parts.triangles.len();
            let local = Mat4::from_scale_rotation_translation(s, q, t);
            self.mesh_instance(node, mesh, &(*world * local))?;
            let per = self.parts.triangles.len() - before;
            if k == 0 {
                // The first instance read the mesh: the whole count is checked
                // against the ceiling before any more are made (each is also
                // charged to the memory budget as it is made).
                let total = (before as u64).saturating_add(per as u64 * count as u64);
                if total > MAX_TRIANGLES {
                    return Err(GltfError::invalid(format!(
                        "{what}: {count} instances of {per} triangles make more than {MAX_TRIANGLES} triangles"
                    )));
                }
                if per == 0 {
                    // Nothing to place (a mesh of points or lines).
                    break;
                }
            }
        }
        Ok(())
    }

    /// Skin `s`'s joint matrices at the pose (the nodes' global transforms
    /// are made once, for the first skin).
    fn joint_matrices(&mut self, s: usize) -> Result<Vec<Mat4>, GltfError> {
        let (root, pose) = (self.root, self.pose.as_ref());
        let globals = match self.globals.take() {
            Some(g) => g,
            None => skin::node_globals(root, |i| local_transform(&root.nodes[i], i, pose))?,
        };
        let joints = skin::joint_matrices(root, self.buffers, s, &globals);
        self.globals = Some(globals);
        joints
    }

    fn mesh_instance(
        &mut self,
        node: usize,
        mesh_index: usize,
        world: &Mat4,
    ) -> Result<(), GltfError> {
        let mesh = self
            .root
            .meshes
            .get(mesh_index)
            .ok_or_else(|| GltfError::invalid(format!("mesh {mesh_index} does not exist")))?;
        let to_world = Affine3A::from_mat4(*world);
        if !to_world.is_finite() {
            return Err(GltfError::invalid(format!(
                "mesh {mesh_index}'s node transform is not finite"
            )));
        }
        let posed_weights = self.pose.as_ref().and_then(|p| p.weights.get(&node));
        let weights = skin::morph_weights(self.root, node, mesh_index, posed_weights)?;
        let joints = match self.root.nodes[node].skin {
            Some(s) => Some(self.joint_matrices(s.value())?),
            None => None,
        };
        let deformation = skin::Deformation {
            joints: joints.as_deref(),
            weights: &weights,
            node_global: *world,
        };
        for p in 0..mesh.primitives.len() {
            let Some(mut id) = self.primitive(mesh_index, p)? else {
                continue;
            };
            let mut to_world = to_world;
            if deformation.applies_to(&mesh.primitives[p]) {
                id = self.deformed(mesh_index, p, id, &deformation)?;
                if deformation.skins(&mesh.primitives[p]) {
                    // Skinned vertices are in world space already.
                    to_world = Affine3A::IDENTITY;
                }
            }
            let data = &self.parts.meshes[id as usize];
            let first = self.parts.triangles.len();
            if (first + data.indices.len()) as u64 > MAX_TRIANGLES {
                return Err(GltfError::invalid(format!(
                    "the scene has more than {MAX_TRIANGLES} triangles after instancing"
                )));
            }
            // Each instance's triangles are charged before they are made: a
            // small file may instance a big mesh many times.
            self.ledger.charge(
                &self.name,
                Needs {
                    geometry: data.indices.len() as u64 * GEOMETRY_BYTES_PER_TRIANGLE,
                    ..Needs::default()
                },
            )?;
            let instance = Instance::new(id, first as u32, to_world);
            let sign = if instance.mirrors { -1.0 } else { 1.0 };
            let instance_id = self.parts.instances.len() as u32;
            for idx in &data.indices {
                let [a, b, c] = idx.map(|i| instance.point(data.positions[i as usize]));
                self.parts.triangles.push(Triangle::new(a, b, c));
                self.parts
                    .normals
                    .push(sign * (b - a).cross(c - a).normalize_or_zero());
                self.parts.material_of.push(data.material);
                self.parts.instance_of.push(instance_id);
            }
            self.parts.instances.push(instance);
        }
        Ok(())
    }

    /// A copy of mesh data `id` (primitive `p` of mesh `m`) deformed by a
    /// node's skin and morph weights, charged to the budget; its index.
    fn deformed(
        &mut self,
        m: usize,
        p: usize,
        id: u32,
        deformation: &skin::Deformation,
    ) -> Result<u32, GltfError> {
        let base = &self.parts.meshes[id as usize];
        let tangent_set = self.parts.materials[base.material as usize]
            .tangent_set()
            .unwrap_or(0);
        let data = skin::deform(self.buffers, m, p, base, deformation, tangent_set)?;
        self.ledger.charge(
            &self.name,
            Needs {
                geometry: data.memory_bytes() as u64,
                ..Needs::default()
            },
        )?;
        self.parts.meshes.push(data);
        Ok(self.parts.meshes.len() as u32 - 1)
    }
}

/// Node `index`'s own `KHR_node_visibility` `visible` (true without the
/// extension); anything but a boolean there is refused.
fn node_visible(node: &json::Node, index: usize) -> Result<bool, GltfError> {
    let Some(ext) = node
        .extensions
        .as_ref()
        .and_then(|e| e.others.get("KHR_node_visibility"))
    else {
        return Ok(true);
    };
    match ext.get("visible") {
        None => Ok(true),
        Some(serde_json::Value::Bool(b)) => Ok(*b),
        Some(other) => Err(GltfError::invalid(format!(
            "node {index}: KHR_node_visibility's visible is {}, not true or false",
            crate::guard::one_line(&other.to_string())
        ))),
    }
}

/// A node's local transform: its matrix, or T·R·S (each of them the pose's
/// if it animates them).
fn local_transform(
    node: &json::Node,
    index: usize,
    pose: Option<&Pose>,
) -> Result<Mat4, GltfError> {
    let m = if let Some(m) = node.matrix {
        Mat4::from_cols_array(&m)
    } else {
        let t = pose
            .and_then(|p| p.translation.get(&index).copied())
            .unwrap_or_else(|| Vec3::from(node.translation.unwrap_or([0.0; 3])));
        let r = node.rotation.map_or([0.0, 0.0, 0.0, 1.0], |q| q.0);
        let s = pose
            .and_then(|p| p.scale.get(&index).copied())
            .unwrap_or_else(|| Vec3::from(node.scale.unwrap_or([1.0; 3])));
        let q = pose
            .and_then(|p| p.rotation.get(&index).copied())
            .unwrap_or_else(|| Quat::from_array(r));
        let q = if q.length_squared() > 0.0 {
            q.normalize()
        } else {
            Quat::IDENTITY
        };
        Mat4::from_scale_rotation_translation(s, q, t)
    };
    if !m.is_finite() {
        return Err(GltfError::invalid(format!(
            "node {index}'s transform is not finite"
        )));
    }
    Ok(m)
}
