//! The scene itself: [`Scene`], built from its parts (checked, with the BVH
//! and the light tables), its query seam ([`Scene::intersect`],
//! [`Scene::occluded`] and their four- and eight-ray forms, which make
//! alpha-masked surfaces holes) and what it holds. The lookups at a hit are
//! in `surface.rs`, the choice of lights in `light_sampling.rs`.

use glam::Vec3A;
use rayon::prelude::*;

use super::analytic::{AnalyticShape, AnalyticShapes, SceneShape};
use super::light_table::{AreaLights, LightNumbers, LightSelection, LightTable};
use super::media::SceneMedia;
use super::mesh::{Instance, MeshData, Tangents};
use super::parts::{PointLight, SceneError, SceneParts};
use crate::camera::SceneCamera;
use crate::geometry::bvh::Bvh;
use crate::geometry::ray::{Hit, Ray, SurfacePoint};
use crate::geometry::triangle::Triangle;
use crate::lights::Light;
use crate::lights::environment::Environment;
use crate::materials::Material;
use crate::materials::surface::{AlphaMode, SurfaceMaterial};
use crate::textures::TextureStore;

/// Alpha-masked layers a ray passes through at most before the next surface
/// counts as solid (a bound, so a pathological file cannot hang a render).
pub const MAX_ALPHA_LAYERS: usize = 256;

/// Triangles, their materials and attributes, textures, lights and cameras,
/// with an acceleration structure.
#[derive(Clone, Debug)]
pub struct Scene {
    pub(super) triangles: Vec<Triangle>,
    pub(super) normals: Vec<Vec3A>,
    pub(super) material_of: Vec<u32>,
    pub(super) instance_of: Vec<u32>,
    pub(super) meshes: Vec<MeshData>,
    pub(super) instances: Vec<Instance>,
    pub(super) materials: Vec<SurfaceMaterial>,
    pub(super) textures: TextureStore,
    pub(super) lights: Vec<Light>,
    pub(super) area_lights: AreaLights,
    pub(super) has_alpha: bool,
    /// Whether any material is `KHR_materials_unlit` (the lab's integrators
    /// test their hits' materials only then).
    pub(super) has_unlit: bool,
    pub(super) environment: Environment,
    pub(super) selection: LightSelection,
    /// How the light tree's choice gets its number.
    pub(super) numbers: LightNumbers,
    /// The lights other than the key light, for choosing one.
    pub(super) light_table: LightTable,
    pub(super) bounds: (Vec3A, Vec3A),
    pub(super) bvh: Bvh,
    /// Analytic spheres, disks and cylinders: primitive `triangles.len() +
    /// k` is shape `k` (`material_of` holds their materials after the
    /// triangles').
    pub(super) shapes: AnalyticShapes,
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
    /// Participating media and the surfaces that bound them.
    pub(super) media: SceneMedia,
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
        // (Only when not the default, so that fingerprints made before there
        // was a choice stay the same.)
        if self.selection != LightSelection::default() {
            let _ = write!(f, "|light selection {:?}", self.selection);
        }
        if self.numbers != LightNumbers::default() {
            let _ = write!(f, "|light numbers {:?}", self.numbers);
        }
        if !self.shapes.is_empty() {
            let _ = write!(f, "|analytic shapes {:?}", self.shapes.in_order());
        }
        if !self.shapes.grids().is_empty() {
            let _ = write!(f, "|sdf grids {:?}", self.shapes.grids());
        }
        if self.media != SceneMedia::default() {
            let _ = write!(f, "|media {:?}", self.media);
        }
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
            let mut patterns = m.clone();
            let missing_pattern_image =
                crate::materials::surface::pattern_images_mut(&mut patterns)
                    .any(|i| *i as usize >= image_count);
            if missing_pattern_image
                || crate::materials::surface::texture_refs(m)
                    .any(|t| t.image as usize >= image_count)
            {
                return Err(SceneError::BadReference {
                    what: format!("material '{}' refers to a missing image", m.name),
                });
            }
        }
        for (k, s) in parts.shapes.iter().enumerate() {
            if !s.shape.is_finite() {
                return Err(SceneError::BadReference {
                    what: format!("analytic shape {k} is degenerate: {:?}", s.shape),
                });
            }
            if s.material as usize >= parts.materials.len() {
                return Err(SceneError::BadReference {
                    what: format!(
                        "analytic shape {k} has material {} of {}",
                        s.material,
                        parts.materials.len()
                    ),
                });
            }
            if let AnalyticShape::SdfVoxel(_) = &s.shape
                && parts.materials[s.material as usize].emission != Vec3A::ZERO
            {
                return Err(SceneError::BadReference {
                    what: format!(
                        "analytic shape {k} is a cell of a signed distance grid with an emitting material (an sdfgrid cannot be an area emitter, as in Mitsuba)"
                    ),
                });
            }
            if let AnalyticShape::SdfVoxel(v) = &s.shape
                && parts
                    .sdf_grids
                    .get(v.grid as usize)
                    .is_none_or(|g| g.resolution().map(|n| n - 1) != v.cells)
            {
                return Err(SceneError::BadReference {
                    what: format!(
                        "analytic shape {k} is a cell of signed distance grid {} of {} (or of another size)",
                        v.grid,
                        parts.sdf_grids.len()
                    ),
                });
            }
        }
        parts
            .media
            .check(parts.materials.len())
            .map_err(|what| SceneError::BadReference { what })?;
        let has_alpha = parts.materials.iter().any(|m| m.alpha != AlphaMode::Opaque);
        let has_unlit = parts.materials.iter().any(SurfaceMaterial::is_unlit);
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
        let bounds = parts
            .shapes
            .iter()
            .map(|s| s.shape.bounds())
            .fold((n > 0).then_some(bounds), |all, (a, b)| {
                Some(all.map_or((a, b), |(lo, hi)| (lo.min(a), hi.max(b))))
            })
            .unwrap_or((Vec3A::ZERO, Vec3A::ZERO));
        let bvh = Bvh::build(&parts.triangles);
        let shapes = AnalyticShapes::build(&parts.shapes, parts.sdf_grids);
        let mut material_of = parts.material_of;
        material_of.extend(parts.shapes.iter().map(|s| s.material));
        let mut scene = Self {
            triangles: parts.triangles,
            normals: parts.normals,
            material_of,
            instance_of: parts.instance_of,
            meshes: parts.meshes,
            instances: parts.instances,
            materials: parts.materials,
            textures: parts.textures,
            lights: Vec::new(),
            area_lights: AreaLights::default(),
            has_alpha,
            has_unlit,
            environment: Environment::none(),
            selection: LightSelection::Tree,
            numbers: LightNumbers::Independent,
            light_table: LightTable::default(),
            bounds,
            bvh,
            shapes,
            light: parts.light,
            ambient: parts.ambient,
            two_sided: parts.two_sided,
            cameras: parts.cameras,
            media: parts.media,
        };
        scene.area_lights = AreaLights::build(&scene);
        scene.set_lights(parts.lights);
        Ok(scene)
    }

    /// The closest hit along `ray` with `t` in `(0, t_max]`; alpha-masked holes
    /// are passed through.
    #[inline]
    pub fn intersect(&self, ray: &Ray, t_max: f32) -> Option<Hit> {
        let hit = self.intersect_solid(ray, t_max)?;
        if !self.has_alpha {
            return Some(hit);
        }
        self.through_holes(ray, t_max, hit)
    }

    /// The closest hit along `ray` in `(0, t_max]`, holes counted as solid:
    /// the triangles', or an analytic shape's when the scene has them.
    #[inline(always)]
    fn intersect_solid(&self, ray: &Ray, t_max: f32) -> Option<Hit> {
        if self.shapes.is_empty() {
            self.bvh.intersect(ray, t_max)
        } else {
            self.intersect_with_shapes(ray, t_max)
        }
    }

    /// [`Scene::intersect_solid`] in a scene with analytic shapes: the
    /// triangles' closest hit, then any shape nearer than it.
    #[inline(never)]
    fn intersect_with_shapes(&self, ray: &Ray, t_max: f32) -> Option<Hit> {
        let triangle = self.bvh.intersect(ray, t_max);
        let limit = triangle.map_or(t_max, |h| h.t);
        match self.shapes.intersect(ray, limit) {
            Some((t, k)) if triangle.is_none_or(|h| t < h.t) => {
                let uv = self.shapes.get(k).shape.uv_at(ray, t);
                Some(Hit {
                    t,
                    prim: self.triangles.len() as u32 + k,
                    b1: uv.x,
                    b2: uv.y,
                })
            }
            _ => triangle,
        }
    }

    /// Analytic shape `k` of primitive `prim`, if `prim` is one.
    #[inline]
    pub(super) fn shape_of(&self, prim: u32) -> Option<&SceneShape> {
        let k = (prim as usize).checked_sub(self.triangles.len())?;
        (k < self.shapes.len()).then(|| self.shapes.get(k as u32))
    }

    /// Whether the scene has analytic shapes (spheres, disks, cylinders).
    #[inline]
    pub fn has_analytic_shapes(&self) -> bool {
        !self.shapes.is_empty()
    }

    /// How many analytic shapes (spheres, disks, cylinders, and the cells of
    /// signed distance grids) the scene has.
    pub fn analytic_shape_count(&self) -> usize {
        self.shapes.len()
    }

    /// Whether anything blocks `ray` for `t` in `(0, t_max]` (holes do not).
    #[inline]
    pub fn occluded(&self, ray: &Ray, t_max: f32) -> bool {
        if self.has_alpha {
            return self.occluded_through_holes(ray, t_max);
        }
        self.bvh.occluded(ray, t_max)
            || (!self.shapes.is_empty() && self.shapes.occluded(ray, t_max))
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
        if self.has_alpha || !self.shapes.is_empty() {
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
        if self.has_alpha || !self.shapes.is_empty() {
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
        if self.has_alpha || !self.shapes.is_empty() {
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
        if self.has_alpha || !self.shapes.is_empty() {
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
            hit = self.intersect_solid(&current, t_max - travelled)?;
        }
        let p = self.hit_point(&hit);
        hit.t = (p.p - ray.origin).dot(ray.dir) * inv_len2;
        Some(hit)
    }

    /// The point of a hit, reconstructed from its barycentrics.
    #[inline]
    fn hit_point(&self, hit: &Hit) -> SurfacePoint {
        if let Some(s) = self.shape_of(hit.prim) {
            return s.shape.point_at(glam::Vec2::new(hit.b1, hit.b2));
        }
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
    /// convention; for glTF the counter-clockwise side after the transform);
    /// zero for an analytic shape (see [`Scene::surface`]).
    #[inline]
    pub fn normal(&self, prim: u32) -> Vec3A {
        self.normals
            .get(prim as usize)
            .copied()
            .unwrap_or(Vec3A::ZERO)
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

    /// Whether material `index` turns a one-sided BSDF's shading normal
    /// towards the viewer: a material with sides of its own (a Mitsuba
    /// material: [`SurfaceMaterial::two_sided`], Mitsuba's `twosided`) says
    /// so itself, whatever the scene; the others follow the scene
    /// ([`Scene::two_sided`]).
    #[inline]
    pub fn material_turns(&self, index: u32) -> bool {
        match self.materials.get(index as usize) {
            Some(m) if m.has_own_sides() => m.two_sided(),
            _ => self.two_sided,
        }
    }

    /// Whether any material is `KHR_materials_unlit`.
    #[inline]
    pub fn has_unlit(&self) -> bool {
        self.has_unlit
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

    /// The index of primitive `prim`'s material (in [`Scene::materials`]).
    #[inline(always)]
    pub(crate) fn material_index(&self, prim: u32) -> usize {
        self.material_of[prim as usize] as usize
    }

    /// Fills the scene's bounding box with fog (`--fog`): a medium of
    /// extinction `density` per scene unit and single-scattering albedo
    /// `albedo`, scattering isotropically, that ends at the box, so that
    /// the sky and the sun still light it from outside. Where a boundary
    /// names no medium the fog is, and the camera starts in it. Fails on a
    /// density or albedo out of range.
    pub fn add_fog(&mut self, density: f32, albedo: Vec3A) -> Result<(), String> {
        if !(density.is_finite() && density >= 0.0) {
            return Err(format!("fog density {density} (must be finite and >= 0)"));
        }
        self.add_fog_with(
            Vec3A::splat(density),
            albedo,
            crate::media::Phase::Isotropic,
        )
    }

    /// [`Scene::add_fog`] with an extinction per channel (`sigma_t`, per
    /// scene unit) and a phase function (a scene file's `[[medium]] type =
    /// "fog"`).
    pub fn add_fog_with(
        &mut self,
        sigma_t: Vec3A,
        albedo: Vec3A,
        phase: crate::media::Phase,
    ) -> Result<(), String> {
        if !(sigma_t.is_finite() && sigma_t.min_element() >= 0.0) {
            return Err(format!("fog density {sigma_t} (must be finite and >= 0)"));
        }
        if !(albedo.is_finite() && albedo.min_element() >= 0.0 && albedo.max_element() <= 1.0) {
            return Err(format!(
                "fog colour {albedo} (each channel is an albedo in [0, 1])"
            ));
        }
        let (lo, hi) = self.bounds;
        // A flat scene's box gets a little depth (a thousandth of its size).
        let size = (hi - lo).max(Vec3A::splat(1e-3 * (hi - lo).length().max(1e-3)));
        self.media.add_fog(crate::media::Medium::homogeneous_box(
            sigma_t,
            albedo,
            phase,
            lo,
            lo + size,
        ));
        Ok(())
    }

    /// Where the fog ([`Scene::add_fog_with`]) is among the media: the
    /// medium camera rays start in, if it is a bounded homogeneous one.
    fn fog_index(&self) -> Option<usize> {
        let (m, h) = self.media.camera_homogeneous()?;
        h.bounds.is_some().then_some(m)
    }

    /// The fog ([`Scene::add_fog_with`]), if the scene has one.
    pub fn fog(&self) -> Option<&crate::media::Homogeneous> {
        match &self.media.media[self.fog_index()?] {
            crate::media::Medium::Homogeneous(h) => Some(h),
            crate::media::Medium::Heterogeneous(_) => None,
        }
    }

    /// The fog, to change its coefficients (the viewer's fog keys).
    pub fn fog_mut(&mut self) -> Option<&mut crate::media::Homogeneous> {
        let i = self.fog_index()?;
        match &mut self.media.media[i] {
            crate::media::Medium::Homogeneous(h) => Some(h),
            crate::media::Medium::Heterogeneous(_) => None,
        }
    }

    /// The scene's participating media and the surfaces that bound them.
    #[inline]
    pub fn media(&self) -> &SceneMedia {
        &self.media
    }

    /// Whether the scene holds participating media (then `path` is
    /// volumetric: `crate::integrators::path::volume`).
    #[inline]
    pub fn has_media(&self) -> bool {
        !self.media.is_empty()
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

    /// The share of triangle `prim`'s emission at barycentrics `(b1, b2)`
    /// that a clear coat lets out along `towards` (any length): see
    /// [`SurfaceMaterial::coat_dimming`]; 1 without a coat.
    #[inline]
    pub fn coat_dimming(&self, prim: u32, b1: f32, b2: f32, towards: Vec3A) -> f32 {
        let m = self.material(prim);
        if !m.has_coat() {
            return 1.0;
        }
        let s = self.surface(&Hit {
            t: 0.0,
            prim,
            b1,
            b2,
        });
        m.coat_dimming(&s.attrs, &self.textures, s.nc, towards.normalize_or_zero())
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
            + self.shapes.len() * std::mem::size_of::<SceneShape>()
            + self
                .shapes
                .grids()
                .iter()
                .map(|g| g.memory_bytes())
                .sum::<usize>()
    }
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

#[cfg(test)]
mod tests {
    use super::*;

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
