//! The scene: one representation for every source (the lab's built-in boxes,
//! OBJ, glTF). Triangles in world space for the BVH, with a material index
//! each; meshes whose vertex attributes (shading normals, two UV sets, tangents,
//! colours) are looked up from a hit; a material table; a texture store shared
//! by the materials; lights (the key point light, other punctual lights,
//! emitting triangles); cameras. Rays see it through one query seam
//! ([`Scene::intersect`], [`Scene::occluded`]), which also makes alpha-masked
//! surfaces holes. The loaders that make scenes from files are in
//! [`crate::load`], above this model.

pub mod compose;
mod lanes;
pub mod mesh;

use std::collections::HashMap;
use std::f32::consts::PI;

use glam::{Vec2, Vec3A, Vec4};
use rayon::prelude::*;
use thiserror::Error;

use crate::camera::SceneCamera;
use crate::geometry::bvh::Bvh;
use crate::geometry::ray::{Hit, Ray, SurfacePoint};
use crate::geometry::triangle::Triangle;
use crate::lights::environment::Environment;
use crate::lights::{Incident, Light};
use crate::materials::Material;
use crate::materials::surface::{AlphaMode, HitAttributes, SurfaceMaterial};
use crate::sampling::distribution::AliasTable;
use crate::textures::TextureStore;
pub use mesh::{Instance, MeshData, Tangents};

/// The lab's point light: position and power per colour channel.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PointLight {
    /// Where the light is.
    pub position: Vec3A,
    /// Emitted power `P` per colour channel (the lab's "light colour"); its
    /// intensity is `P/(4π)` W/sr.
    pub power: Vec3A,
}

/// Why a scene cannot be built.
#[derive(Debug, Error, PartialEq)]
pub enum SceneError {
    /// A vertex has a NaN or infinite coordinate.
    #[error("triangle {index} has a non-finite vertex")]
    NonFiniteVertex {
        /// Index of the triangle.
        index: usize,
    },
    /// A reflectance is outside `[0, 1]` or not finite.
    #[error("triangle {index} has reflectance {value:?} outside [0, 1]")]
    BadReflectance {
        /// Index of the triangle.
        index: usize,
        /// The offending value.
        value: [f32; 3],
    },
    /// An emitted radiance is negative or not finite.
    #[error("triangle {index} has emitted radiance {value:?} (must be finite and >= 0)")]
    BadEmission {
        /// Index of the triangle.
        index: usize,
        /// The offending value.
        value: [f32; 3],
    },
    /// Per-triangle lists differ in length.
    #[error("{triangles} triangles but {reflectances} reflectances")]
    LengthMismatch {
        /// Number of triangles.
        triangles: usize,
        /// Number of entries in the other list.
        reflectances: usize,
    },
    /// A triangle names a material, instance or texture that does not exist.
    #[error("{what}")]
    BadReference {
        /// What is wrong.
        what: String,
    },
}

/// Everything a scene is made of, for loaders; [`Scene::from_parts`] checks it
/// and builds the BVH and the light tables.
#[derive(Clone, Debug, Default)]
pub struct SceneParts {
    /// Triangles in world space, in the order of the per-triangle lists.
    pub triangles: Vec<Triangle>,
    /// Unit front normal of each triangle (light leaves emitters on this side;
    /// one-sided scenes reflect only on it). Zero for degenerate triangles.
    pub normals: Vec<Vec3A>,
    /// Material of each triangle.
    pub material_of: Vec<u32>,
    /// Instance of each triangle, or [`NO_INSTANCE`] for bare triangles (face
    /// normal, no texture coordinates); may be empty when all are bare.
    pub instance_of: Vec<u32>,
    /// Meshes with their vertex attributes.
    pub meshes: Vec<MeshData>,
    /// Meshes placed in the world.
    pub instances: Vec<Instance>,
    /// The material table.
    pub materials: Vec<SurfaceMaterial>,
    /// Images the materials' textures refer to.
    pub textures: TextureStore,
    /// The key point light (`direct`'s light, the viewer's movable light).
    pub light: PointLight,
    /// Other punctual lights.
    pub lights: Vec<Light>,
    /// The lab's ambient term.
    pub ambient: Vec3A,
    /// Whether surfaces reflect on both sides (everything but the lab box).
    pub two_sided: bool,
    /// Cameras from the file.
    pub cameras: Vec<SceneCamera>,
}

impl SceneParts {
    /// The parts of a scene of bare triangles with diffuse reflectances in the
    /// lab's form (one-sided, lab normals `cross(v2 − v0, v1 − v0)`, one
    /// material per distinct colour); see [`Scene::new`].
    pub fn lab(
        triangles: Vec<Triangle>,
        reflectance: Vec<Vec3A>,
        light: PointLight,
        ambient: Vec3A,
    ) -> Result<Self, SceneError> {
        if triangles.len() != reflectance.len() {
            return Err(SceneError::LengthMismatch {
                triangles: triangles.len(),
                reflectances: reflectance.len(),
            });
        }
        let valid = |r: &Vec3A| r.is_finite() && r.min_element() >= 0.0 && r.max_element() <= 1.0;
        if let Some(index) = reflectance.iter().position(|r| !valid(r)) {
            return Err(SceneError::BadReflectance {
                index,
                value: reflectance[index].into(),
            });
        }
        // One material per distinct colour.
        let mut ids: HashMap<[u32; 3], u32> = HashMap::new();
        let mut materials = Vec::new();
        let material_of = reflectance
            .iter()
            .map(|r| {
                *ids.entry(r.to_array().map(f32::to_bits))
                    .or_insert_with(|| {
                        materials.push(SurfaceMaterial::diffuse(*r));
                        materials.len() as u32 - 1
                    })
            })
            .collect();
        let normals = triangles.iter().map(Triangle::lab_normal).collect();
        Ok(SceneParts {
            triangles,
            normals,
            material_of,
            materials,
            light,
            ambient,
            ..SceneParts::default()
        })
    }
}

/// Marks a bare triangle in [`SceneParts::instance_of`].
pub const NO_INSTANCE: u32 = u32::MAX;

/// Alpha-masked layers a ray passes through at most before the next surface
/// counts as solid (a bound, so a pathological file cannot hang a render).
pub const MAX_ALPHA_LAYERS: usize = 256;

/// Triangles, their materials and attributes, textures, lights and cameras,
/// with an acceleration structure.
#[derive(Clone, Debug)]
pub struct Scene {
    triangles: Vec<Triangle>,
    normals: Vec<Vec3A>,
    material_of: Vec<u32>,
    instance_of: Vec<u32>,
    meshes: Vec<MeshData>,
    instances: Vec<Instance>,
    materials: Vec<SurfaceMaterial>,
    textures: TextureStore,
    lights: Vec<Light>,
    area_lights: AreaLights,
    has_alpha: bool,
    environment: Environment,
    selection: LightSelection,
    /// The lights other than the key light, for choosing one.
    light_table: LightTable,
    bounds: (Vec3A, Vec3A),
    bvh: Bvh,
    /// The key point light: the lab's light, `direct`'s light and the one the
    /// viewer moves (power 0 when the scene has none).
    pub light: PointLight,
    /// The lab's constant ambient term `N` (indirect light stand-in).
    pub ambient: Vec3A,
    /// Whether surfaces are lit from both sides. The lab box is one-sided, as in
    /// the lab (its normal is `cross(v2 − v0, v1 − v0)`); meshes are two-sided,
    /// since their windings vary (and OBJ's is the opposite of the lab's).
    pub two_sided: bool,
    /// Cameras from the file, in depth-first node order.
    pub cameras: Vec<SceneCamera>,
}

/// What a hit looks like: its point, normals and interpolated attributes.
#[derive(Clone, Copy, Debug)]
pub struct SurfaceHit {
    /// The hit point with its error bound; its normal is `ng`.
    pub point: SurfacePoint,
    /// Unit front geometric normal.
    pub ng: Vec3A,
    /// Unit shading normal (interpolated, normal-mapped), on `ng`'s side.
    pub ns: Vec3A,
    /// Texture coordinates and colour.
    pub attrs: HitAttributes,
    /// Index of the material.
    pub material: u32,
}

impl Scene {
    /// A 64-bit fingerprint of everything that decides the scene's images:
    /// triangles, normals, meshes with all their attributes, instances,
    /// materials, texture texels, lights, the environment (its map's texels
    /// included), the ambient term, sidedness and cameras. Equal scenes loaded
    /// from the same files give the same value on any machine and thread
    /// count; a change of any texel or coordinate changes it. Checkpoints use
    /// it to refuse samples of another scene. Measured: 83 ms for 1.1 million
    /// triangles, 10 ms for the DamagedHelmet (15k triangles, 48 MiB of
    /// texels).
    pub fn fingerprint(&self) -> u64 {
        use std::fmt::Write;
        let mut f = crate::fingerprint::Fingerprint::new();
        let v3 = |v: &Vec3A| v.to_array();
        f.floats(self.triangles.iter().flat_map(|t| t.v.iter().flat_map(v3)));
        f.floats(self.normals.iter().flat_map(v3));
        f.words32(self.material_of.iter().copied());
        f.words32(self.instance_of.iter().copied());
        for m in &self.meshes {
            f.floats(m.positions.iter().flat_map(|p| p.to_array()));
            f.words32(m.indices.iter().flatten().copied());
            f.floats(m.normals.iter().flat_map(|n| n.to_array()));
            match &m.tangents {
                Tangents::None => f.update(b"none"),
                Tangents::PerVertex(t) => f.floats(t.iter().flat_map(|t| t.to_array())),
                Tangents::PerCorner(t) => f.floats(t.iter().flatten().flat_map(|t| t.to_array())),
            }
            for set in &m.uvs {
                f.floats(set.iter().flat_map(|uv| uv.to_array()));
            }
            f.floats(m.colors.iter().flat_map(|c| c.to_array()));
            f.words32([m.material]);
        }
        // The small parts by their Debug text (exact: floats print round-trip).
        let _ = write!(
            f,
            "{:?}|{:?}|{:?}|{}|{:?}|{:?}|{}|{:?}",
            self.instances,
            self.materials,
            self.lights,
            self.has_alpha,
            self.light,
            self.ambient,
            self.two_sided,
            self.cameras
        );
        self.textures.fingerprint_into(&mut f);
        self.environment.fingerprint_into(&mut f);
        f.value()
    }

    /// Builds a scene of bare triangles with diffuse reflectances (the lab's
    /// form: one-sided, lab normals `cross(v2 − v0, v1 − v0)`). Degenerate
    /// (zero-area) triangles are kept, so indices stay those of the input, but
    /// can never be hit.
    pub fn new(
        triangles: Vec<Triangle>,
        reflectance: Vec<Vec3A>,
        light: PointLight,
        ambient: Vec3A,
    ) -> Result<Self, SceneError> {
        Self::from_parts(SceneParts::lab(triangles, reflectance, light, ambient)?)
    }

    /// Checks the parts (finite vertices, references in range) and builds the
    /// BVH and the light tables.
    pub fn from_parts(parts: SceneParts) -> Result<Self, SceneError> {
        let n = parts.triangles.len();
        if let Some(index) = parts.triangles.iter().position(|t| !t.is_finite()) {
            return Err(SceneError::NonFiniteVertex { index });
        }
        for (what, len) in [
            ("normals", parts.normals.len()),
            ("material indices", parts.material_of.len()),
        ] {
            if len != n {
                return Err(SceneError::BadReference {
                    what: format!("{n} triangles but {len} {what}"),
                });
            }
        }
        if !parts.instance_of.is_empty() && parts.instance_of.len() != n {
            return Err(SceneError::BadReference {
                what: format!(
                    "{n} triangles but {} instance indices",
                    parts.instance_of.len()
                ),
            });
        }
        if let Some(i) = parts
            .material_of
            .iter()
            .position(|&m| m as usize >= parts.materials.len())
        {
            return Err(SceneError::BadReference {
                what: format!(
                    "triangle {i} has material {} of {}",
                    parts.material_of[i],
                    parts.materials.len()
                ),
            });
        }
        for (i, inst) in parts.instances.iter().enumerate() {
            let Some(mesh) = parts.meshes.get(inst.mesh as usize) else {
                return Err(SceneError::BadReference {
                    what: format!(
                        "instance {i} has mesh {} of {}",
                        inst.mesh,
                        parts.meshes.len()
                    ),
                });
            };
            let end = inst.first_triangle as usize + mesh.indices.len();
            let owned = parts.instance_of.get(inst.first_triangle as usize..end);
            if owned.is_none_or(|o| o.iter().any(|&k| k as usize != i)) {
                return Err(SceneError::BadReference {
                    what: format!("instance {i}'s triangles are not marked as its own"),
                });
            }
        }
        let image_count = parts.textures.len();
        for m in &parts.materials {
            if !(m.emission.is_finite() && m.emission.min_element() >= 0.0) {
                return Err(SceneError::BadReference {
                    what: format!(
                        "material '{}' has emission {} (must be finite and >= 0)",
                        m.name, m.emission
                    ),
                });
            }
            if crate::materials::surface::texture_refs(m).any(|t| t.image as usize >= image_count) {
                return Err(SceneError::BadReference {
                    what: format!("material '{}' refers to a missing image", m.name),
                });
            }
        }
        let has_alpha = parts.materials.iter().any(|m| m.alpha != AlphaMode::Opaque);
        let bounds = parts
            .triangles
            .par_iter()
            .fold(
                || (Vec3A::splat(f32::INFINITY), Vec3A::splat(f32::NEG_INFINITY)),
                |(lo, hi), t| (lo.min(t.min()), hi.max(t.max())),
            )
            .reduce(
                || (Vec3A::splat(f32::INFINITY), Vec3A::splat(f32::NEG_INFINITY)),
                |a, b| (a.0.min(b.0), a.1.max(b.1)),
            );
        let bounds = if n == 0 {
            (Vec3A::ZERO, Vec3A::ZERO)
        } else {
            bounds
        };
        let bvh = Bvh::build(&parts.triangles);
        let mut scene = Self {
            triangles: parts.triangles,
            normals: parts.normals,
            material_of: parts.material_of,
            instance_of: parts.instance_of,
            meshes: parts.meshes,
            instances: parts.instances,
            materials: parts.materials,
            textures: parts.textures,
            lights: Vec::new(),
            area_lights: AreaLights::default(),
            has_alpha,
            environment: Environment::none(),
            selection: LightSelection::Power,
            light_table: LightTable::default(),
            bounds,
            bvh,
            light: parts.light,
            ambient: parts.ambient,
            two_sided: parts.two_sided,
            cameras: parts.cameras,
        };
        scene.area_lights = AreaLights::build(&scene);
        scene.set_lights(parts.lights);
        Ok(scene)
    }

    /// The closest hit along `ray` with `t` in `(0, t_max]`; alpha-masked holes
    /// are passed through.
    #[inline]
    pub fn intersect(&self, ray: &Ray, t_max: f32) -> Option<Hit> {
        let hit = self.bvh.intersect(ray, t_max)?;
        if !self.has_alpha {
            return Some(hit);
        }
        self.through_holes(ray, t_max, hit)
    }

    /// Whether anything blocks `ray` for `t` in `(0, t_max]` (holes do not).
    #[inline]
    pub fn occluded(&self, ray: &Ray, t_max: f32) -> bool {
        if self.has_alpha {
            return self.occluded_through_holes(ray, t_max);
        }
        self.bvh.occluded(ray, t_max)
    }

    /// [`Scene::occluded`] in a scene with alpha holes.
    #[cold]
    #[inline(never)]
    fn occluded_through_holes(&self, ray: &Ray, t_max: f32) -> bool {
        self.intersect(ray, t_max).is_some()
    }

    /// The closest hits of four coherent rays (say, a 2×2 pixel quad), traced
    /// together; the same answers as four calls of [`Scene::intersect`] except
    /// which triangle is reported at an exact tie.
    #[inline]
    pub fn intersect4(&self, rays: &[Ray; 4], t_max: f32) -> [Option<Hit>; 4] {
        if self.has_alpha {
            return self.intersect4_one_by_one(rays, t_max);
        }
        self.bvh.intersect4(rays, t_max)
    }

    /// [`Scene::intersect4`] in a scene with alpha holes: ray by ray (kept out of
    /// line so that the common path stays small).
    #[cold]
    #[inline(never)]
    fn intersect4_one_by_one(&self, rays: &[Ray; 4], t_max: f32) -> [Option<Hit>; 4] {
        rays.map(|r| self.intersect(&r, t_max))
    }

    /// Whether anything blocks each of four rays within its own `t_max`; lanes
    /// not `active` answer `false`.
    #[inline]
    pub fn occluded4(&self, rays: &[Ray; 4], t_max: [f32; 4], active: [bool; 4]) -> [bool; 4] {
        if self.has_alpha {
            return self.occluded4_one_by_one(rays, t_max, active);
        }
        self.bvh.occluded4(rays, t_max, active)
    }

    /// [`Scene::occluded4`] in a scene with alpha holes: ray by ray.
    #[cold]
    #[inline(never)]
    fn occluded4_one_by_one(
        &self,
        rays: &[Ray; 4],
        t_max: [f32; 4],
        active: [bool; 4],
    ) -> [bool; 4] {
        std::array::from_fn(|i| active[i] && self.occluded(&rays[i], t_max[i]))
    }

    /// The closest hits of eight coherent rays (a 4×2 pixel block), traced
    /// together where the CPU has AVX2; as [`Scene::intersect4`] otherwise.
    #[inline]
    pub fn intersect8(&self, rays: &[Ray; 8], t_max: f32) -> [Option<Hit>; 8] {
        if self.has_alpha {
            return self.intersect8_one_by_one(rays, t_max);
        }
        self.bvh.intersect8(rays, t_max)
    }

    #[cold]
    #[inline(never)]
    fn intersect8_one_by_one(&self, rays: &[Ray; 8], t_max: f32) -> [Option<Hit>; 8] {
        rays.map(|r| self.intersect(&r, t_max))
    }

    /// Whether anything blocks each of eight rays within its own `t_max`; lanes
    /// not `active` answer `false`.
    #[inline]
    pub fn occluded8(&self, rays: &[Ray; 8], t_max: [f32; 8], active: [bool; 8]) -> [bool; 8] {
        if self.has_alpha {
            return self.occluded8_one_by_one(rays, t_max, active);
        }
        self.bvh.occluded8(rays, t_max, active)
    }

    #[cold]
    #[inline(never)]
    fn occluded8_one_by_one(
        &self,
        rays: &[Ray; 8],
        t_max: [f32; 8],
        active: [bool; 8],
    ) -> [bool; 8] {
        std::array::from_fn(|i| active[i] && self.occluded(&rays[i], t_max[i]))
    }

    /// Follows a ray past alpha holes: `first` is its closest hit; returns the
    /// first hit that is not a hole, with `t` measured along the original ray.
    #[cold]
    #[inline(never)]
    fn through_holes(&self, ray: &Ray, t_max: f32, first: Hit) -> Option<Hit> {
        let mut hit = first;
        let mut current = *ray;
        let inv_len2 = 1.0 / ray.dir.length_squared();
        for _ in 0..MAX_ALPHA_LAYERS {
            let p = self.hit_point(&hit);
            if !self.is_hole(&current, &hit, &p) {
                hit.t = (p.p - ray.origin).dot(ray.dir) * inv_len2;
                return Some(hit);
            }
            // Start again just past the surface, on the far side.
            let origin = p.offset_origin(ray.dir);
            let travelled = (origin - ray.origin).dot(ray.dir) * inv_len2;
            current = Ray::new(origin, ray.dir);
            hit = self.bvh.intersect(&current, t_max - travelled)?;
        }
        let p = self.hit_point(&hit);
        hit.t = (p.p - ray.origin).dot(ray.dir) * inv_len2;
        Some(hit)
    }

    /// The point of a hit, reconstructed from its barycentrics.
    #[inline]
    fn hit_point(&self, hit: &Hit) -> SurfacePoint {
        let prim = hit.prim as usize;
        SurfacePoint::on_triangle(&self.triangles[prim].v, hit.b1, hit.b2, self.normals[prim])
    }

    /// Whether `ray` passes through its hit: alpha below a mask's cut-off, or a
    /// blended surface's coverage test failed.
    fn is_hole(&self, ray: &Ray, hit: &Hit, p: &SurfacePoint) -> bool {
        let m = &self.materials[self.material_of[hit.prim as usize] as usize];
        match m.alpha {
            AlphaMode::Opaque => false,
            AlphaMode::Mask(cutoff) => m.alpha_at(&self.attributes(hit), &self.textures) < cutoff,
            AlphaMode::Blend => {
                let alpha = m.alpha_at(&self.attributes(hit), &self.textures);
                coverage_number(ray, hit.prim, p.p) >= alpha
            }
        }
    }

    /// The triangles, in input order.
    pub fn triangles(&self) -> &[Triangle] {
        &self.triangles
    }

    /// Front normal of triangle `prim` (for the built-in boxes the lab's
    /// convention; for glTF the counter-clockwise side after the transform).
    #[inline]
    pub fn normal(&self, prim: u32) -> Vec3A {
        self.normals[prim as usize]
    }

    /// Reflectance ρ of triangle `prim` for `flat` and `direct`, without
    /// textures (see [`Scene::base_color`]).
    #[inline]
    pub fn reflectance(&self, prim: u32) -> Vec3A {
        self.material(prim).reflectance
    }

    /// The material of triangle `prim`.
    #[inline]
    pub fn material(&self, prim: u32) -> &SurfaceMaterial {
        &self.materials[self.material_of[prim as usize] as usize]
    }

    /// The material table.
    pub fn materials(&self) -> &[SurfaceMaterial] {
        &self.materials
    }

    /// The images the materials use.
    pub fn textures(&self) -> &TextureStore {
        &self.textures
    }

    /// Meshes with vertex attributes.
    pub fn meshes(&self) -> &[MeshData] {
        &self.meshes
    }

    /// Placed meshes.
    pub fn instances(&self) -> &[Instance] {
        &self.instances
    }

    /// Punctual lights other than the key light.
    pub fn lights(&self) -> &[Light] {
        &self.lights
    }

    /// Replaces the punctual lights other than the key light.
    pub fn set_lights(&mut self, lights: Vec<Light>) {
        self.lights = lights;
        self.rebuild_light_table();
    }

    /// The environment that surrounds the scene (rays that escape see it;
    /// `path` samples it as a light).
    pub fn environment(&self) -> &Environment {
        &self.environment
    }

    /// Surrounds the scene with `environment`. Its selection weight among the
    /// lights is the power it sends into the scene's bounding sphere,
    /// `π r² ∫ L dω` (`4π² r² L` for a constant `L`).
    pub fn set_environment(&mut self, environment: Environment) {
        self.environment = environment;
        self.rebuild_light_table();
    }

    /// How lights are chosen for next-event estimation.
    pub fn light_selection(&self) -> LightSelection {
        self.selection
    }

    /// Chooses lights as `selection` says (by power, the default, or uniformly:
    /// for comparisons).
    pub fn set_light_selection(&mut self, selection: LightSelection) {
        self.selection = selection;
        self.rebuild_light_table();
    }

    /// Radiance arriving from the environment along `dir` (unit, away from the
    /// scene).
    #[inline]
    pub fn environment_radiance(&self, dir: Vec3A) -> Vec3A {
        self.environment.radiance(dir)
    }

    /// The solid-angle density with which [`Scene::sample_light`] picks
    /// direction `dir` of the environment (selection included).
    #[inline]
    pub fn environment_pdf(&self, dir: Vec3A) -> f32 {
        let Some(entry) = self.light_table.environment else {
            return 0.0;
        };
        self.entry_probability(entry as usize) * self.environment.pdf(dir)
    }

    /// Builds the table that chooses among the lights other than the key light:
    /// punctual lights, the environment and the emitting triangles, weighted by
    /// power (or equally).
    fn rebuild_light_table(&mut self) {
        let radius = self.radius().max(1e-3);
        let mut entries = Vec::new();
        let mut weights = Vec::new();
        let weigh = |power: f32| match self.selection {
            LightSelection::Power => power,
            LightSelection::Uniform => 1.0,
        };
        for (i, l) in self.lights.iter().enumerate() {
            let power = l.power(radius);
            if power > 0.0 {
                entries.push(LightRef::Punctual(i as u32));
                weights.push(weigh(power));
            }
        }
        let env_power = PI * radius * radius * self.environment.radiance_integral();
        let mut environment = None;
        if env_power.is_finite() && env_power > 0.0 {
            environment = Some(entries.len() as u32);
            entries.push(LightRef::Environment);
            weights.push(weigh(env_power));
        }
        let mut prim_entry = Vec::new();
        if !self.area_lights.prims.is_empty() {
            prim_entry = vec![u32::MAX; self.triangles.len()];
            for &prim in &self.area_lights.prims {
                prim_entry[prim as usize] = entries.len() as u32;
                entries.push(LightRef::Triangle(prim));
                weights.push(weigh(self.area_lights.per_prim[prim as usize].0));
            }
        }
        let alias = AliasTable::new(&weights);
        let punctual_pmf = entries
            .iter()
            .enumerate()
            .filter(|(_, e)| matches!(e, LightRef::Punctual(_)))
            .map(|(k, _)| f64::from(alias.pmf(k)))
            .sum::<f64>() as f32;
        let by_importance = self.selection == LightSelection::Power
            && (2..=MAX_IMPORTANCE_LIGHTS).contains(&self.lights.len());
        self.light_table = LightTable {
            total: alias.total() as f32,
            alias,
            entries,
            environment,
            prim_entry,
            punctual_pmf,
            by_importance,
        };
    }

    /// The key light's selection weight.
    #[inline]
    fn key_weight(&self) -> f32 {
        let p = self.point_power();
        match self.selection {
            LightSelection::Power => p,
            LightSelection::Uniform => f32::from(p > 0.0),
        }
    }

    /// The probability that [`Scene::sample_light`] picks table entry `entry`.
    #[inline]
    fn entry_probability(&self, entry: usize) -> f32 {
        let rest = self.light_table.total;
        let total = self.key_weight() + rest;
        if total <= 0.0 {
            return 0.0;
        }
        self.light_table.alias.pmf(entry) * (rest / total)
    }

    /// Axis-aligned bounds of all triangles.
    pub fn bounds(&self) -> (Vec3A, Vec3A) {
        self.bounds
    }

    /// Radius of the sphere around the bounds.
    pub fn radius(&self) -> f32 {
        0.5 * (self.bounds.1 - self.bounds.0).length()
    }

    /// Gives triangle `prim` another BSDF (for the `path` integrator; `flat` and
    /// `direct` keep its reflectance).
    pub fn set_material(&mut self, prim: usize, material: Material) {
        let mut m = self.materials[self.material_of[prim] as usize].clone();
        m.kind = crate::materials::surface::MaterialKind::Fixed(material);
        self.material_of[prim] = self.materials.len() as u32;
        self.materials.push(m);
    }

    /// Radiance `Le` emitted by triangle `prim` from its front side (the side its
    /// normal points to) without textures; zero for a triangle that is not a light.
    #[inline]
    pub fn emission(&self, prim: u32) -> Vec3A {
        self.material(prim).emission
    }

    /// Radiance emitted by triangle `prim` at barycentrics `(b1, b2)`, textures
    /// applied (before the side test).
    #[inline]
    pub fn emission_at(&self, prim: u32, b1: f32, b2: f32) -> Vec3A {
        let m = self.material(prim);
        if m.emission_texture.is_none() {
            return m.emission;
        }
        let hit = Hit {
            t: 0.0,
            prim,
            b1,
            b2,
        };
        m.emitted(&self.attributes(&hit), &self.textures)
    }

    /// Makes triangle `prim` an area light emitting radiance `le` from its front
    /// side (zero turns it off), and updates the light tables.
    pub fn set_emission(&mut self, prim: usize, le: Vec3A) -> Result<(), SceneError> {
        if !(le.is_finite() && le.min_element() >= 0.0) {
            return Err(SceneError::BadEmission {
                index: prim,
                value: le.into(),
            });
        }
        let mut m = self.materials[self.material_of[prim] as usize].clone();
        m.emission = le;
        self.material_of[prim] = self.materials.len() as u32;
        self.materials.push(m);
        self.area_lights = AreaLights::build(self);
        self.rebuild_light_table();
        Ok(())
    }

    /// Total emitted power of the key point light, averaged over the colour
    /// channels (`P`, since its intensity is `P/(4π)` in every direction).
    #[inline]
    pub fn point_power(&self) -> f32 {
        // In f64: three channels near f32::MAX must not overflow their sum.
        let p = (self.light.power.as_dvec3().element_sum() / 3.0) as f32;
        if p.is_finite() && p > 0.0 { p } else { 0.0 }
    }

    /// Whether anything emits light.
    pub fn has_lights(&self) -> bool {
        self.point_power() > 0.0 || !self.light_table.alias.is_empty()
    }

    /// Whether [`Scene::sample_light`] reads its sample values: only when there
    /// are lights besides the key light (area lights, the environment, the
    /// glTF lights) to choose among or to pick a point on. Without them it
    /// returns the key light whatever the values, and a path tracer need not
    /// draw them.
    #[inline]
    pub fn light_needs_samples(&self) -> bool {
        self.light_table.total > 0.0
    }

    /// Picks a light with `u_select` (by power: the key light `P`; other
    /// punctual lights [`Light::power`]; the environment `π r² ∫ L dω`; each
    /// emitting triangle `π·A·Le`, doubled for two-sided emitters; or uniformly,
    /// see [`Scene::set_light_selection`]), then a point or direction on it with
    /// `u` (uniform by area on a triangle, by the map's importance on the
    /// environment), to light the point `p`. `u_select.x` chooses, `u_select.y`
    /// settles the alias table's coin. `None` when the scene has no light or the
    /// chosen one sends nothing to `p`.
    ///
    /// Punctual lights other than the key light, as a group, are picked as
    /// often as their power says; which one of them, though, goes by what each
    /// sends to `p` ([`Scene::punctual_importance`]: intensity over distance
    /// squared, or irradiance, times the cosine to the shading normal,
    /// [`Facing`]), picked with `u.x`, which punctual lights do not otherwise
    /// use. A sun behind a wall is then not chosen for it, nor a spot whose
    /// cone misses `p`; the environment and the emitters keep the
    /// probabilities that multiple importance sampling weighs by.
    /// (Inlined: as a call its sample came back through memory, 1.7 % of the
    /// lab box's `path`.)
    #[inline(always)]
    pub fn sample_light(
        &self,
        p: Vec3A,
        facing: Facing,
        u_select: Vec2,
        u: Vec2,
    ) -> Option<LightSample> {
        // (`light_needs_samples` must say when `u_select` and `u` are read.)
        let key = self.key_weight();
        let rest = self.light_table.total;
        let total = key + rest;
        if total <= 0.0 {
            return None;
        }
        let p_key = key / total;
        if u_select.x < p_key || rest <= 0.0 {
            return Some(LightSample::Point {
                position: self.light.position,
                intensity: self.light.power * (1.0 / (4.0 * PI * p_key)),
            });
        }
        let x = ((u_select.x - p_key) / (1.0 - p_key)).min(1.0 - f32::EPSILON / 2.0);
        let table = &self.light_table;
        let entry = table.alias.sample(Vec2::new(x, u_select.y))?;
        let probability = table.alias.pmf(entry) * (rest / total);
        match table.entries[entry] {
            LightRef::Punctual(i) => {
                let (i, probability) = if table.by_importance {
                    let (j, share) = self.pick_punctual(p, facing, u.x)?;
                    (j, share * table.punctual_pmf * (rest / total))
                } else {
                    (i, probability)
                };
                let scale = 1.0 / probability;
                Some(match self.lights[i as usize].incident(p)? {
                    Incident::FromPoint {
                        position,
                        intensity,
                    } => LightSample::Point {
                        position,
                        intensity: intensity * scale,
                    },
                    Incident::FromDirection {
                        to_light,
                        irradiance,
                    } => LightSample::Directional {
                        to_light,
                        irradiance: irradiance * scale,
                        distance: self.escape_distance(p),
                    },
                })
            }
            LightRef::Environment => {
                let (to_light, radiance, pdf) = self.environment.sample(u)?;
                Some(LightSample::Environment {
                    to_light,
                    radiance,
                    pdf: pdf * probability,
                    distance: self.escape_distance(p),
                })
            }
            LightRef::Triangle(prim) => {
                let v = &self.triangles[prim as usize].v;
                let (b1, b2) = uniform_barycentrics(u);
                let position = (1.0 - b1 - b2) * v[0] + b1 * v[1] + b2 * v[2];
                let area = self.area_lights.per_prim[prim as usize].1;
                Some(LightSample::Area {
                    position,
                    normal: self.normals[prim as usize],
                    radiance: self.emission_at(prim, b1, b2),
                    two_sided: self.material(prim).emits_both_sides,
                    pdf_area: probability / area,
                })
            }
        }
    }

    /// What punctual light `light` sends to `p` for choosing among the
    /// punctual lights: the mean over the channels of the intensity (with a
    /// spot's falloff) over the distance squared, or of a directional light's
    /// irradiance, times the cosine to the normal `facing` gives (none for
    /// [`Facing::Any`]), at least a thousandth of the cosine-free value,
    /// so that a light is never left out unless it sends nothing at all (a
    /// spot's cone, a light at `p`). Zero means nothing arrives.
    #[inline]
    pub fn punctual_importance(light: &Light, p: Vec3A, facing: Facing) -> f32 {
        let mean = |v: Vec3A| (v.x + v.y + v.z) * (1.0 / 3.0);
        let (to_light, value) = match light.incident(p) {
            None => return 0.0,
            Some(Incident::FromPoint {
                position,
                intensity,
            }) => {
                let d = position - p;
                let r2 = d.length_squared();
                if r2.is_nan() || r2 <= 0.0 {
                    return 0.0;
                }
                (d * r2.sqrt().recip(), mean(intensity) / r2)
            }
            Some(Incident::FromDirection {
                to_light,
                irradiance,
            }) => (to_light, mean(irradiance)),
        };
        let cos = match facing {
            Facing::Side(n) => n.dot(to_light),
            Facing::Both(n) => n.dot(to_light).abs(),
            Facing::Any => 1.0,
        };
        let w = value * cos.max(1e-3);
        if w.is_finite() { w.max(0.0) } else { 0.0 }
    }

    /// One of the punctual lights (not the key light), chosen with `u` in
    /// proportion to [`Scene::punctual_importance`] at `p`, and its share of
    /// the choice; `None` when none sends anything to `p`.
    #[inline]
    fn pick_punctual(&self, p: Vec3A, facing: Facing, u: f32) -> Option<(u32, f32)> {
        let mut weights = [0.0f32; MAX_IMPORTANCE_LIGHTS];
        let mut total = 0.0f32;
        for (w, light) in weights.iter_mut().zip(&self.lights) {
            *w = Self::punctual_importance(light, p, facing);
            total += *w;
        }
        if !(total > 0.0 && total.is_finite()) {
            return None;
        }
        let target = u * total;
        let mut run = 0.0f32;
        let n = self.lights.len();
        let mut last = None;
        for (k, &w) in weights[..n].iter().enumerate() {
            if w <= 0.0 {
                continue;
            }
            last = Some(k);
            run += w;
            if target < run {
                return Some((k as u32, w / total));
            }
        }
        // Rounding left `target` at the end: the last light with weight.
        last.map(|k| (k as u32, weights[k] / total))
    }

    /// How far a shadow ray from `p` must go to leave the scene's bounds.
    #[inline]
    fn escape_distance(&self, p: Vec3A) -> f32 {
        2.0 * self.radius() + (p - self.bounds.0).length() + 1.0
    }

    /// The density per unit area with which [`Scene::sample_light`] picks a point
    /// on emitting triangle `prim`: its selection probability over its area.
    #[inline]
    pub fn light_pdf_area(&self, prim: u32) -> f32 {
        let Some(&entry) = self.light_table.prim_entry.get(prim as usize) else {
            return 0.0;
        };
        if entry == u32::MAX {
            return 0.0;
        }
        let area = self.area_lights.per_prim[prim as usize].1;
        self.entry_probability(entry as usize) / area
    }

    /// The hit point of a ray along `dir` with its error bound, for spawning rays
    /// off the surface. Its normal is the face normal, turned towards the ray's
    /// origin in a two-sided scene.
    #[inline]
    pub fn surface_point(&self, hit: &Hit, dir: Vec3A) -> SurfacePoint {
        let prim = hit.prim as usize;
        let mut n = self.normals[prim];
        if self.two_sided && n.dot(dir) > 0.0 {
            n = -n;
        }
        SurfacePoint::on_triangle(&self.triangles[prim].v, hit.b1, hit.b2, n)
    }

    /// [`Scene::surface_point`] of four hits (with their rays' directions) in
    /// the lanes of SSE registers: points, normals and error bounds, each as
    /// x, y and z lanes. The scalar code's operations in its order, so the
    /// same values bit for bit; the vertices are gathered once into lanes
    /// (one at a time, with the points turned into lanes afterwards, this was
    /// a tenth of a `direct` frame).
    #[inline(always)]
    pub fn surface_points4(&self, hits: [&Hit; 4], dirs: [Vec3A; 4]) -> [[Vec4; 3]; 3] {
        let prims = [
            hits[0].prim as usize,
            hits[1].prim as usize,
            hits[2].prim as usize,
            hits[3].prim as usize,
        ];
        let (t0, t1, t2, t3) = (
            &self.triangles[prims[0]].v,
            &self.triangles[prims[1]].v,
            &self.triangles[prims[2]].v,
            &self.triangles[prims[3]].v,
        );
        let lanes = |a: Vec3A, b: Vec3A, c: Vec3A, d: Vec3A| {
            [
                Vec4::new(a.x, b.x, c.x, d.x),
                Vec4::new(a.y, b.y, c.y, d.y),
                Vec4::new(a.z, b.z, c.z, d.z),
            ]
        };
        let v0 = lanes(t0[0], t1[0], t2[0], t3[0]);
        let v1 = lanes(t0[1], t1[1], t2[1], t3[1]);
        let v2 = lanes(t0[2], t1[2], t2[2], t3[2]);
        let b1 = Vec4::new(hits[0].b1, hits[1].b1, hits[2].b1, hits[3].b1);
        let b2 = Vec4::new(hits[0].b2, hits[1].b2, hits[2].b2, hits[3].b2);
        // `SurfacePoint::on_triangle`.
        let b0 = Vec4::ONE - b1 - b2;
        let (a, b, c) = (
            [b0 * v0[0], b0 * v0[1], b0 * v0[2]],
            [b1 * v1[0], b1 * v1[1], b1 * v1[2]],
            [b2 * v2[0], b2 * v2[1], b2 * v2[2]],
        );
        let p = [a[0] + b[0] + c[0], a[1] + b[1] + c[1], a[2] + b[2] + c[2]];
        let g = Vec4::splat(crate::geometry::ray::gamma(7));
        let bound = |i: usize| g * (a[i].abs() + b[i].abs() + c[i].abs());
        let error = [bound(0), bound(1), bound(2)];
        let mut n = lanes(
            self.normals[prims[0]],
            self.normals[prims[1]],
            self.normals[prims[2]],
            self.normals[prims[3]],
        );
        if self.two_sided {
            // `n.dot(dir) > 0`, in glam's order of the sums.
            let d = lanes(dirs[0], dirs[1], dirs[2], dirs[3]);
            let away = (n[0] * d[0] + n[1] * d[1] + n[2] * d[2]).cmpgt(Vec4::ZERO);
            n = [
                Vec4::select(away, -n[0], n[0]),
                Vec4::select(away, -n[1], n[1]),
                Vec4::select(away, -n[2], n[2]),
            ];
        }
        [p, n, error]
    }

    /// The base colour at a hit (textures and vertex colours applied), which
    /// `flat` shows and `direct` uses as ρ.
    #[inline]
    pub fn base_color(&self, hit: &Hit) -> Vec3A {
        let m = self.material(hit.prim);
        match m.kind {
            crate::materials::surface::MaterialKind::Fixed(_) => m.reflectance,
            _ => self.textured_base_color(hit),
        }
    }

    /// [`Scene::base_color`] of a glTF material (out of line: the lab's
    /// `direct` loop stays small).
    #[inline(never)]
    fn textured_base_color(&self, hit: &Hit) -> Vec3A {
        let m = self.material(hit.prim);
        Vec3A::from(
            m.base_color(&self.attributes(hit), &self.textures)
                .truncate(),
        )
    }

    /// Texture coordinates and colour at a hit (defaults for bare triangles).
    #[inline]
    pub fn attributes(&self, hit: &Hit) -> HitAttributes {
        match self.mesh_of(hit.prim) {
            Some((_, mesh, idx)) => attributes_of(mesh, idx, barycentrics(hit)),
            None => HitAttributes::default(),
        }
    }

    /// The instance, mesh and vertex indices of triangle `prim`, if it has
    /// vertex attributes.
    #[inline]
    fn mesh_of(&self, prim: u32) -> Option<(&Instance, &MeshData, [u32; 3])> {
        let inst = *self.instance_of.get(prim as usize)?;
        let inst = self.instances.get(inst as usize)?;
        let mesh = &self.meshes[inst.mesh as usize];
        let local = (prim - inst.first_triangle) as usize;
        Some((inst, mesh, mesh.indices[local]))
    }

    /// Everything shading needs at a hit: the point, its front geometric normal,
    /// the shading normal (interpolated vertex normals, then the material's
    /// normal map, turned to the geometric normal's side) and the attributes.
    /// (Inlined: as a call it wrote the whole record out and the path tracer
    /// read it back, 1 % of the lab box's `path`.)
    #[inline(always)]
    pub fn surface(&self, hit: &Hit) -> SurfaceHit {
        let prim = hit.prim as usize;
        let ng = self.normals[prim];
        let point = SurfacePoint::on_triangle(&self.triangles[prim].v, hit.b1, hit.b2, ng);
        let material = self.material_of[prim];
        let Some((inst, mesh, idx)) = self.mesh_of(hit.prim) else {
            return SurfaceHit {
                point,
                ng,
                ns: ng,
                attrs: HitAttributes::default(),
                material,
            };
        };
        let b = barycentrics(hit);
        let attrs = attributes_of(mesh, idx, b);
        let mut ns = ng;
        if !mesh.normals.is_empty() {
            let n = interpolate(b, idx.map(|i| mesh.normals[i as usize]));
            let n = (inst.normal_to_world * Vec3A::from(n)).normalize_or_zero();
            if n != Vec3A::ZERO && n.is_finite() {
                ns = if n.dot(ng) < 0.0 { -n } else { n };
            }
        }
        let m = &self.materials[material as usize];
        if let Some(mapped) = m.mapped_normal(&attrs, &self.textures) {
            let local = (hit.prim - inst.first_triangle) as usize;
            let tangent = match &mesh.tangents {
                Tangents::PerVertex(t) => Some(interpolate(b, idx.map(|i| t[i as usize]))),
                Tangents::PerCorner(t) => Some(interpolate(b, t[local])),
                Tangents::None => None,
            };
            if let Some(t) = tangent {
                let sign = if inst.mirrors { -t.w } else { t.w };
                let t = inst.to_world.matrix3 * Vec3A::from(t.truncate());
                // Gram–Schmidt against the shading normal.
                let t = (t - ns * ns.dot(t)).normalize_or_zero();
                if t != Vec3A::ZERO {
                    let bitangent = sign.signum() * ns.cross(t);
                    let n =
                        (mapped.x * t + mapped.y * bitangent + mapped.z * ns).normalize_or_zero();
                    if n != Vec3A::ZERO && n.is_finite() {
                        ns = n;
                    }
                }
            }
        }
        SurfaceHit {
            point,
            ng,
            ns,
            attrs,
            material,
        }
    }

    /// Bytes held by the scene's geometry, attributes and BVH (textures apart).
    pub fn geometry_bytes(&self) -> usize {
        use std::mem::size_of_val;
        size_of_val(self.triangles.as_slice())
            + size_of_val(self.normals.as_slice())
            + size_of_val(self.material_of.as_slice())
            + size_of_val(self.instance_of.as_slice())
            + self
                .meshes
                .iter()
                .map(MeshData::memory_bytes)
                .sum::<usize>()
            + self.bvh.memory_bytes()
    }

    /// Total power emitted by the emitting triangles (the estimate they are
    /// chosen by), W averaged over the colour channels.
    pub fn emitted_power(&self) -> f32 {
        self.area_lights.total
    }

    /// How many triangles emit light.
    pub fn emitter_count(&self) -> usize {
        self.area_lights.prims.len()
    }
}

/// The barycentric combination of three values.
#[inline]
fn interpolate<T>(b: [f32; 3], v: [T; 3]) -> T
where
    T: std::ops::Mul<f32, Output = T> + std::ops::Add<Output = T> + Copy,
{
    v[0] * b[0] + v[1] * b[1] + v[2] * b[2]
}

/// The weights of a hit's three vertices.
#[inline]
fn barycentrics(hit: &Hit) -> [f32; 3] {
    [1.0 - hit.b1 - hit.b2, hit.b1, hit.b2]
}

/// A mesh's texture coordinates and colour at barycentrics `b` of the
/// triangle with vertices `idx`.
#[inline]
fn attributes_of(mesh: &MeshData, idx: [u32; 3], b: [f32; 3]) -> HitAttributes {
    let mut attrs = HitAttributes::default();
    for (set, uvs) in mesh.uvs.iter().enumerate() {
        if !uvs.is_empty() {
            attrs.uv[set] = interpolate(b, idx.map(|i| uvs[i as usize]));
        }
    }
    if !mesh.colors.is_empty() {
        attrs.color = interpolate(b, idx.map(|i| mesh.colors[i as usize]));
    }
    attrs
}

/// Barycentrics `(b1, b2)` of a point distributed uniformly by area over a
/// triangle, from `u` in `[0, 1)²`.
#[inline]
fn uniform_barycentrics(u: Vec2) -> (f32, f32) {
    let su = u.x.sqrt();
    (1.0 - su, u.y * su)
}

/// A number in `[0, 1)` that decides whether a ray passes a blended surface:
/// a hash of the ray and the hit, so the same ray always gets the same answer
/// (images stay deterministic) while different samples' rays get independent
/// ones.
#[inline]
fn coverage_number(ray: &Ray, prim: u32, p: Vec3A) -> f32 {
    let mut h = 0x9e37_79b9_7f4a_7c15u64 ^ prim as u64;
    for x in [ray.origin, ray.dir, p].iter().flat_map(|v| v.to_array()) {
        h = (h ^ x.to_bits() as u64).wrapping_mul(0xff51_afd7_ed55_8ccd);
        h ^= h >> 33;
    }
    (h >> 40) as f32 * (1.0 / (1u64 << 24) as f32)
}

/// A light chosen by [`Scene::sample_light`], with its selection probability
/// already divided out.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LightSample {
    /// A point light (the key light, a point or spot light).
    Point {
        /// Where it is.
        position: Vec3A,
        /// Its intensity towards the point (W/sr) divided by the probability of
        /// choosing it.
        intensity: Vec3A,
    },
    /// A directional light.
    Directional {
        /// Unit direction towards the light.
        to_light: Vec3A,
        /// Irradiance on a surface facing it, divided by the probability of
        /// choosing it.
        irradiance: Vec3A,
        /// How far a shadow ray must go to leave the scene.
        distance: f32,
    },
    /// A direction of the environment.
    Environment {
        /// Unit direction towards the sky.
        to_light: Vec3A,
        /// The environment's radiance.
        radiance: Vec3A,
        /// Solid-angle density of the direction (selection included).
        pdf: f32,
        /// How far a shadow ray must go to leave the scene.
        distance: f32,
    },
    /// A point on an emitting triangle.
    Area {
        /// The point.
        position: Vec3A,
        /// The triangle's front normal.
        normal: Vec3A,
        /// Its emitted radiance `Le`.
        radiance: Vec3A,
        /// Whether light leaves both faces (else only the front).
        two_sided: bool,
        /// Probability density of this point per unit area (selection included).
        pdf_area: f32,
    },
}

/// How [`Scene::sample_light`] chooses among the lights.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum LightSelection {
    /// In proportion to each light's estimated power.
    #[default]
    Power,
    /// Every light (every emitting triangle) equally: for comparisons.
    Uniform,
}

/// A light other than the key light, as the light table names it.
#[derive(Clone, Copy, Debug, PartialEq)]
enum LightRef {
    /// Punctual light `i` of [`Scene::lights`].
    Punctual(u32),
    /// The environment.
    Environment,
    /// An emitting triangle.
    Triangle(u32),
}

/// What the surface being lit lets through, for choosing among punctual lights
/// ([`Scene::sample_light`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Facing {
    /// Nothing known: every direction counts alike.
    Any,
    /// A reflecting surface: light arrives from the side this unit shading
    /// normal points to (the side the path leaves by).
    Side(Vec3A),
    /// A surface that also transmits: light arrives from either side of this
    /// unit shading normal.
    Both(Vec3A),
}

/// The most punctual lights [`Scene::sample_light`] weighs by what they send
/// to the point being lit (the others are chosen by power alone: the weighing
/// is a loop over them at every vertex that picks one).
pub const MAX_IMPORTANCE_LIGHTS: usize = 32;

/// The lights other than the key light and an alias table that chooses among
/// them by weight.
#[derive(Clone, Debug, Default)]
struct LightTable {
    /// The table's probability of picking one of the punctual lights.
    punctual_pmf: f32,
    /// Whether the punctual light picked is chosen by importance at the point
    /// ([`Scene::pick_punctual`]).
    by_importance: bool,
    alias: AliasTable,
    /// Sum of the weights (the table's, as `f32`: read per sample).
    total: f32,
    entries: Vec<LightRef>,
    /// The environment's entry, if it is a light.
    environment: Option<u32>,
    /// Every triangle's entry (`u32::MAX` for non-emitters); empty when none
    /// emits.
    prim_entry: Vec<u32>,
}

/// Points per triangle at which a textured emitter's radiance is averaged to
/// estimate its power.
const EMISSION_ESTIMATE_POINTS: u32 = 16;

/// The emitting triangles and their power, for power-proportional selection.
#[derive(Clone, Debug, Default)]
struct AreaLights {
    /// Emitting triangles.
    prims: Vec<u32>,
    /// Sum of their powers.
    total: f32,
    /// Power and area of every triangle (zero power for non-emitters); empty
    /// when none emits.
    per_prim: Vec<(f32, f32)>,
}

impl AreaLights {
    fn build(scene: &Scene) -> Self {
        let emissive: Vec<bool> = scene
            .materials
            .iter()
            .map(SurfaceMaterial::is_emissive)
            .collect();
        if !emissive.iter().any(|&e| e) {
            return Self::default();
        }
        let per_prim: Vec<(f32, f32)> = (0..scene.triangles.len())
            .into_par_iter()
            .map(|i| {
                let m = scene.material_of[i] as usize;
                if !emissive[m] {
                    return (0.0, 0.0);
                }
                let area = scene.triangles[i].area();
                let le = mean_emission(scene, i as u32);
                let sides = if scene.materials[m].emits_both_sides {
                    2.0
                } else {
                    1.0
                };
                let power = PI * area * sides * le.element_sum() / 3.0;
                if power > 0.0 && power.is_finite() {
                    (power, area)
                } else {
                    (0.0, 0.0)
                }
            })
            .collect();
        let mut lights = Self::default();
        for (i, &(power, _)) in per_prim.iter().enumerate() {
            if power > 0.0 {
                lights.total += power;
                lights.prims.push(i as u32);
            }
        }
        if !lights.prims.is_empty() {
            lights.per_prim = per_prim;
        }
        lights
    }
}

/// The mean emitted radiance over triangle `prim`: exact for untextured
/// emission, else the average over a fixed set of points inside it.
fn mean_emission(scene: &Scene, prim: u32) -> Vec3A {
    let k = EMISSION_ESTIMATE_POINTS;
    if scene.material(prim).emission_texture.is_none() {
        return scene.material(prim).emission;
    }
    let mut sum = Vec3A::ZERO;
    for s in 0..k {
        // A stratified point of the triangle (the same warp as light sampling).
        let u = Vec2::new(
            (s as f32 + 0.5) / k as f32,
            ((s * 7 % k) as f32 + 0.5) / k as f32,
        );
        let (b1, b2) = uniform_barycentrics(u);
        sum += scene.emission_at(prim, b1, b2);
    }
    sum / k as f32
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Four surface points in lanes are the four one at a time, bit for bit,
    /// in one-sided and two-sided scenes.
    #[test]
    fn surface_points_in_lanes_are_surface_points() {
        let mut rng = crate::sampling::sampler::Rng::new(8, 1);
        for two_sided in [false, true] {
            let mut scene = crate::load::cornell::scene();
            scene.two_sided = two_sided;
            let n = scene.triangles().len();
            for _ in 0..5_000 {
                let hits: [Hit; 4] = std::array::from_fn(|_| Hit {
                    t: 1.0,
                    prim: (rng.next_f32() * n as f32) as u32 % n as u32,
                    b1: rng.next_f32() * 0.6,
                    b2: rng.next_f32() * 0.4,
                });
                let dirs: [Vec3A; 4] = std::array::from_fn(|_| {
                    Vec3A::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) - 0.5
                });
                let [p, nrm, error] =
                    scene.surface_points4([&hits[0], &hits[1], &hits[2], &hits[3]], dirs);
                for lane in 0..4 {
                    let one = scene.surface_point(&hits[lane], dirs[lane]);
                    let at = |v: &[Vec4; 3]| [v[0][lane], v[1][lane], v[2][lane]].map(f32::to_bits);
                    assert_eq!(at(&p), one.p.to_array().map(f32::to_bits));
                    assert_eq!(at(&nrm), one.n.to_array().map(f32::to_bits));
                    assert_eq!(at(&error), one.error.to_array().map(f32::to_bits));
                }
            }
        }
    }

    fn light() -> PointLight {
        PointLight {
            position: Vec3A::ZERO,
            power: Vec3A::ONE,
        }
    }

    #[test]
    fn bad_input_is_refused_with_the_triangle_named() {
        let ok = Triangle::new(Vec3A::ZERO, Vec3A::X, Vec3A::Y);
        let nan = Triangle::new(Vec3A::ZERO, Vec3A::new(f32::NAN, 0.0, 0.0), Vec3A::Y);
        let inf = Triangle::new(Vec3A::splat(f32::INFINITY), Vec3A::X, Vec3A::Y);
        let grey = Vec3A::splat(0.5);
        let err = |tris: Vec<Triangle>, rho: Vec<Vec3A>| {
            Scene::new(tris, rho, light(), Vec3A::ZERO).unwrap_err()
        };
        assert_eq!(
            err(vec![ok, nan], vec![grey; 2]),
            SceneError::NonFiniteVertex { index: 1 }
        );
        assert_eq!(
            err(vec![inf], vec![grey]),
            SceneError::NonFiniteVertex { index: 0 }
        );
        assert!(matches!(
            err(vec![ok], vec![Vec3A::new(0.5, 1.5, 0.5)]),
            SceneError::BadReflectance { index: 0, .. }
        ));
        assert!(matches!(
            err(vec![ok], vec![Vec3A::splat(f32::NAN)]),
            SceneError::BadReflectance { index: 0, .. }
        ));
        assert_eq!(
            err(vec![ok, ok], vec![grey]),
            SceneError::LengthMismatch {
                triangles: 2,
                reflectances: 1
            }
        );
        assert_eq!(
            SceneError::NonFiniteVertex { index: 3 }.to_string(),
            "triangle 3 has a non-finite vertex"
        );
    }

    #[test]
    fn empty_and_degenerate_scenes_render_black() {
        let p = Vec3A::new(0.0, 0.0, 1.0);
        for tris in [vec![], vec![Triangle::new(p, p, p); 3]] {
            let n = tris.len();
            let scene = Scene::new(tris, vec![Vec3A::ONE; n], light(), Vec3A::ONE).unwrap();
            let cam = crate::camera::Camera::lab(Vec3A::new(0.0, 0.0, -3.0), 0.0, 0.0, 16, 16);
            let settings = crate::render::RenderSettings::default();
            let out = crate::render::render(&scene, &cam, &settings, &|_| {});
            assert!(out.film.pixels.iter().all(|p| *p == Vec3A::ZERO));
        }
    }
}
