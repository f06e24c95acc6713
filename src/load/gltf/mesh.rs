//! A mesh's primitives, each read once whatever number of nodes instance it:
//! the mode, the attributes (positions, normals, texture coordinates, colours,
//! tangents, made with MikkTSpace where a material needs them) and the
//! indices into [`MeshData`], and the material it shows
//! (`KHR_materials_variants`).

use glam::{Vec2, Vec3, Vec4};
use gltf::json::{self, validation::Checked};

use super::accessor::{read_floats, read_indices};
use super::error::{GltfError, valid};
use super::loader::Loader;
use super::material::ANISOTROPY;
use super::tangents;
use crate::scene::mesh::{MeshData, Tangents};

impl Loader<'_> {
    /// Reads primitive `p` of mesh `m` once (instances share it); `None` when
    /// it is skipped (points, lines).
    pub(super) fn primitive(&mut self, m: usize, p: usize) -> Result<Option<u32>, GltfError> {
        use json::mesh::{Mode, Semantic};
        if let Some(&id) = self.mesh_ids.get(&(m, p)) {
            return Ok(Some(id));
        }
        let prim = &self.root.meshes[m].primitives[p];
        let what = format!("mesh {m} primitive {p}");
        let mode = *valid(&prim.mode)
            .ok_or_else(|| GltfError::invalid(format!("{what}: unknown mode")))?;
        if !matches!(
            mode,
            Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan
        ) {
            self.warn_once(
                &format!("{mode:?}"),
                format!("skipping primitives of mode {mode:?} (only triangles are rendered)"),
            );
            return Ok(None);
        }
        let attr = |s: Semantic| prim.attributes.get(&Checked::Valid(s)).map(|a| a.value());
        let positions_acc = attr(Semantic::Positions)
            .ok_or_else(|| GltfError::invalid(format!("{what} has no POSITION")))?;
        // Vertices in a buffer with no data at all (no URI, and no GLB chunk
        // for it): a placeholder the glTF-Validator accepts, with nothing to
        // render. (A buffer whose file is missing is an error when read.)
        if let Some(b) = self.buffers.placeholder_of(positions_acc) {
            self.warn_once(
                &format!("placeholder buffer {b}"),
                format!(
                    "skipping the primitives whose vertices lie in buffer {b}, which has no data (no URI and no GLB binary chunk)"
                ),
            );
            return Ok(None);
        }
        let positions: Vec<Vec3> =
            read_floats::<3>(self.buffers, positions_acc, &format!("{what} POSITION"))?
                .into_iter()
                .map(Vec3::from)
                .collect();
        if let Some(i) = positions.iter().position(|v| !v.is_finite()) {
            return Err(GltfError::invalid(format!(
                "{what}: POSITION {i} is not finite (NaN or infinite)"
            )));
        }
        let n = positions.len();
        let read_attr = |name: &str, s: Semantic| -> Result<Option<usize>, GltfError> {
            match attr(s) {
                None => Ok(None),
                Some(a) => {
                    let count = self.root.accessors.get(a).map_or(0, |x| x.count.0);
                    if count != n as u64 {
                        return Err(GltfError::invalid(format!(
                            "{what}: {name} has {count} elements but POSITION has {n}"
                        )));
                    }
                    Ok(Some(a))
                }
            }
        };
        let mut data = MeshData {
            positions,
            ..MeshData::default()
        };
        if let Some(a) = read_attr("NORMAL", Semantic::Normals)? {
            data.normals = read_floats::<3>(self.buffers, a, &format!("{what} NORMAL"))?
                .into_iter()
                .map(|v| Vec3::from(v).normalize_or_zero())
                .collect();
            if data.normals.iter().any(|v| !v.is_finite()) {
                data.normals.clear();
            }
        }
        for set in 0..2u32 {
            if let Some(a) = read_attr(&format!("TEXCOORD_{set}"), Semantic::TexCoords(set))? {
                data.uvs[set as usize] =
                    read_floats::<2>(self.buffers, a, &format!("{what} TEXCOORD_{set}"))?
                        .into_iter()
                        .map(|v| {
                            let v = Vec2::from(v);
                            if v.is_finite() { v } else { Vec2::ZERO }
                        })
                        .collect();
            }
        }
        if let Some(a) = read_attr("COLOR_0", Semantic::Colors(0))? {
            data.colors = read_floats::<4>(self.buffers, a, &format!("{what} COLOR_0"))?
                .into_iter()
                .map(|v| Vec4::from(v).clamp(Vec4::ZERO, Vec4::ONE))
                .collect();
        }
        // Triangles from the index list (or 0..n) by the primitive's mode.
        let indices = match prim.indices {
            Some(a) => read_indices(self.buffers, a.value(), &format!("{what} indices"))?,
            None => (0..n as u32).collect(),
        };
        if let Some(&bad) = indices.iter().find(|&&i| i as usize >= n) {
            return Err(GltfError::invalid(format!(
                "{what}: index {bad} is out of range (the primitive has {n} vertices)"
            )));
        }
        data.indices = match mode {
            Mode::Triangles => indices
                .chunks_exact(3)
                .map(|c| [c[0], c[1], c[2]])
                .collect(),
            Mode::TriangleStrip => (0..indices.len().saturating_sub(2))
                .map(|i| {
                    // glTF: p_i = {v_i, v_(i+(1+i%2)), v_(i+(2−i%2))}.
                    let k = i % 2;
                    [indices[i], indices[i + 1 + k], indices[i + 2 - k]]
                })
                .collect(),
            _ => (0..indices.len().saturating_sub(2))
                // glTF: p_i = {v_(i+1), v_(i+2), v_0}.
                .map(|i| [indices[i + 1], indices[i + 2], indices[0]])
                .collect(),
        };
        data.material = self.material(self.primitive_material(prim, &what)?)?;
        let material = &self.parts.materials[data.material as usize];
        if let Some(set) = material.tangent_set() {
            data.tangents = match read_attr("TANGENT", Semantic::Tangents)? {
                Some(a) => Tangents::PerVertex(
                    read_floats::<4>(self.buffers, a, &format!("{what} TANGENT"))?
                        .into_iter()
                        .map(Vec4::from)
                        .collect(),
                ),
                None if !data.uvs[set.min(1)].is_empty() => tangents::generate(&data, set.min(1)),
                None => Tangents::None,
            };
        }
        if matches!(data.tangents, Tangents::None) && material.has_anisotropy() {
            // The specification requires tangents (or a normal map's UVs to
            // make them from); without them there is no direction.
            self.warn_once(
                &format!("{ANISOTROPY} {what}"),
                format!(
                    "{what}: its material is anisotropic ({ANISOTROPY}) but the \
                     primitive has neither TANGENT nor texture coordinates: rendered isotropic"
                ),
            );
        }
        let id = self.parts.meshes.len() as u32;
        self.parts.meshes.push(data);
        self.mesh_ids.insert((m, p), id);
        Ok(Some(id))
    }

    /// The glTF material a primitive shows: its own, or the one its
    /// `KHR_materials_variants` mappings give the variant shown.
    fn primitive_material(
        &self,
        prim: &json::mesh::Primitive,
        what: &str,
    ) -> Result<Option<usize>, GltfError> {
        let own = prim.material.map(|m| m.value());
        let Some(mappings) = prim
            .extensions
            .as_ref()
            .and_then(|e| e.khr_materials_variants.as_ref())
        else {
            return Ok(own);
        };
        let mut shown = own;
        for mapping in &mappings.mappings {
            if let Some(&v) = mapping
                .variants
                .iter()
                .find(|&&v| v as usize >= self.variant_count)
            {
                return Err(GltfError::invalid(format!(
                    "{what}: a KHR_materials_variants mapping names variant {v}, but the file defines {}",
                    self.variant_count
                )));
            }
            if let Some(k) = self.variant
                && mapping.variants.contains(&(k as u32))
            {
                shown = Some(mapping.material as usize);
            }
        }
        Ok(shown)
    }
}
