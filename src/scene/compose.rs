//! Putting scenes together: placing a loaded model's parts in the world and
//! appending one model's parts to another's, as scene files do.

use glam::{Affine3A, Mat3A, Vec3A};

use super::analytic::{AnalyticShape, SceneShape};
use super::mesh::Instance;
use super::parts::{NO_INSTANCE, SceneParts};
use crate::geometry::cylinder::Cylinder;
use crate::geometry::disk::Disk;
use crate::geometry::placement::Placement;
use crate::geometry::sdf_voxel::SdfVoxel;
use crate::lights::Light;
use crate::materials::surface::{pattern_images_mut, texture_refs_mut};

impl SceneParts {
    /// Moves everything by `to_world`: triangles, their front normals,
    /// instances, analytic shapes, lights and cameras. A mirroring transform
    /// keeps each front normal on the side it was (as glTF's node transforms
    /// do).
    pub fn transform(&mut self, to_world: Affine3A) {
        let linear = to_world.matrix3;
        let scale = similarity(linear);
        if scale.is_none() {
            // An ellipsoid is not a sphere: as triangles.
            self.spheres_to_meshes();
        }
        // A medium's coefficients are per unit length; a placement that
        // is not a similarity leaves them as they are (documented).
        if let Some(s) = scale {
            self.media.transform(to_world, s);
        }
        self.shapes
            .retain_mut(|s| transform_shape(&mut s.shape, to_world));
        let normal_matrix = linear.inverse().transpose();
        for t in &mut self.triangles {
            for v in &mut t.v {
                *v = to_world.transform_point3a(*v);
            }
        }
        for n in &mut self.normals {
            *n = (normal_matrix * *n).normalize_or_zero();
        }
        for inst in &mut self.instances {
            *inst = Instance::new(inst.mesh, inst.first_triangle, to_world * inst.to_world);
        }
        let direction = |d: Vec3A| (linear * d).normalize_or_zero();
        for light in &mut self.lights {
            match light {
                Light::Point { position, .. } => *position = to_world.transform_point3a(*position),
                Light::Spot {
                    position,
                    direction: axis,
                    ..
                } => {
                    *position = to_world.transform_point3a(*position);
                    *axis = direction(*axis);
                }
                Light::Beam(b) => {
                    b.position = to_world.transform_point3a(b.position);
                    b.axis = direction(b.axis);
                    b.to_local *= linear.inverse();
                    if let crate::lights::BeamShape::Projector { normal, .. } = &mut b.shape {
                        *normal = linear * *normal;
                    }
                }
                Light::Directional {
                    direction: travel, ..
                } => *travel = direction(*travel),
            }
        }
        self.light.position = to_world.transform_point3a(self.light.position);
        for camera in &mut self.cameras {
            camera.position = to_world.transform_point3a(camera.position);
            // The rotation part only: a camera is not scaled.
            let r = linear * camera.rotation;
            let right = r.x_axis.normalize_or_zero();
            let forward = r.z_axis.normalize_or_zero();
            let down = forward.cross(right).normalize_or_zero();
            if right != Vec3A::ZERO && forward != Vec3A::ZERO && down != Vec3A::ZERO {
                camera.rotation = Mat3A::from_cols(right, down, forward);
            }
        }
    }

    /// Appends `other`'s triangles, meshes, instances, materials, images,
    /// lights and cameras after this one's, renumbering `other`'s references.
    /// The key light and the ambient term stay this one's; the result is
    /// two-sided if either is.
    pub fn append(&mut self, other: SceneParts) {
        let triangle_offset = self.triangles.len() as u32;
        let material_offset = self.materials.len() as u32;
        let mesh_offset = self.meshes.len() as u32;
        let instance_offset = self.instances.len() as u32;
        let grid_offset = self.sdf_grids.len() as u32;
        let image_offset = self.textures.append(other.textures);
        // An empty list means "all bare"; it must grow once either side has
        // instances.
        let had_instances = !self.instance_of.is_empty();
        if !had_instances && !other.instance_of.is_empty() {
            self.instance_of = vec![NO_INSTANCE; self.triangles.len()];
        }
        if had_instances || !other.instance_of.is_empty() {
            if other.instance_of.is_empty() {
                self.instance_of
                    .extend(std::iter::repeat_n(NO_INSTANCE, other.triangles.len()));
            } else {
                self.instance_of.extend(other.instance_of.iter().map(|&i| {
                    if i == NO_INSTANCE {
                        NO_INSTANCE
                    } else {
                        i + instance_offset
                    }
                }));
            }
        }
        self.triangles.extend(other.triangles);
        self.normals.extend(other.normals);
        self.material_of
            .extend(other.material_of.iter().map(|&m| m + material_offset));
        self.meshes.extend(other.meshes.into_iter().map(|mut mesh| {
            mesh.material += material_offset;
            mesh
        }));
        self.instances
            .extend(other.instances.into_iter().map(|inst| Instance {
                mesh: inst.mesh + mesh_offset,
                first_triangle: inst.first_triangle + triangle_offset,
                ..inst
            }));
        self.media
            .append(other.media, self.materials.len(), other.materials.len());
        self.materials
            .extend(other.materials.into_iter().map(|mut m| {
                for t in texture_refs_mut(&mut m) {
                    t.image += image_offset;
                }
                for image in pattern_images_mut(&mut m) {
                    *image += image_offset;
                }
                m
            }));
        self.lights.extend(other.lights);
        self.cameras.extend(other.cameras);
        self.two_sided |= other.two_sided;
        self.shapes.extend(other.shapes.into_iter().map(|mut s| {
            s.material += material_offset;
            if let AnalyticShape::SdfVoxel(v) = &mut s.shape {
                v.grid += grid_offset;
            }
            s
        }));
        self.sdf_grids.extend(other.sdf_grids);
    }

    /// Places signed distance grid `grid` (an index into `sdf_grids`) by
    /// `to_world` (any affine map: the unit cube the grid spans to the
    /// world) with material `material`: one analytic shape per cell the
    /// surface may cross. `smooth` selects Mitsuba's `smooth` shading
    /// normals (else `analytic`). Returns how many cells were placed; an
    /// error line when the grid does not exist, the map is singular, or no
    /// cell holds surface (Mitsuba's "SDFGrid should at least have one
    /// non-empty voxel").
    pub fn place_sdf_grid(
        &mut self,
        grid: u32,
        to_world: Affine3A,
        material: u32,
        smooth: bool,
    ) -> Result<usize, String> {
        let g = self
            .sdf_grids
            .get(grid as usize)
            .ok_or_else(|| format!("no signed distance grid {grid}"))?;
        let placement = Placement::from_affine(to_world)
            .ok_or("its to_world is singular or not finite (it squashes the grid flat)")?;
        let cells = g.resolution().map(|n| n - 1);
        let before = self.shapes.len();
        for cell in g.surface_cells() {
            self.shapes.push(SceneShape {
                shape: AnalyticShape::SdfVoxel(SdfVoxel {
                    placement,
                    corners: g.corners(cell),
                    cell,
                    cells,
                    grid,
                    smooth,
                }),
                flip: false,
                material,
            });
        }
        match self.shapes.len() - before {
            0 => Err("the grid has no cell the surface crosses (no sign change)".into()),
            n => Ok(n),
        }
    }

    /// Replaces the analytic spheres by meshes (Mitsuba's parametrisation,
    /// [`SPHERE_SEGMENTS`] around), for transforms that would make them
    /// ellipsoids. (Disks and cylinders stay: an affine map keeps them
    /// what they are.)
    pub fn spheres_to_meshes(&mut self) {
        for s in std::mem::take(&mut self.shapes) {
            let AnalyticShape::Sphere(sphere) = s.shape else {
                self.shapes.push(s);
                continue;
            };
            let mut mesh = super::mesh::unit_sphere_mesh(SPHERE_SEGMENTS, s.flip);
            mesh.material = s.material;
            let to_world = Affine3A::from_mat3_translation(
                (sphere.frame * sphere.radius).into(),
                sphere.center.into(),
            );
            self.place_mesh(mesh, to_world);
        }
    }

    /// Adds `mesh` and places it by `to_world` ([`SceneParts::place_instance`]).
    pub fn place_mesh(&mut self, mesh: super::mesh::MeshData, to_world: Affine3A) {
        let index = self.meshes.len() as u32;
        let material = mesh.material;
        self.meshes.push(mesh);
        self.place_instance(index, to_world, material);
    }

    /// Places mesh `mesh` (an index into `meshes`) by `to_world` with
    /// material `material`: its world triangles (front normals by their
    /// winding) and an instance.
    pub fn place_instance(&mut self, mesh: u32, to_world: Affine3A, material: u32) {
        self.place_instance_turned(mesh, to_world, material, false);
    }

    /// [`SceneParts::place_instance`], the front normals turned against the
    /// winding where `turned` (a Mitsuba mesh whose own normals a mirroring
    /// placement carries to the other side).
    pub fn place_instance_turned(
        &mut self,
        mesh: u32,
        to_world: Affine3A,
        material: u32,
        turned: bool,
    ) {
        let sign = if turned { -1.0 } else { 1.0 };
        let first = self.triangles.len() as u32;
        if self.instance_of.is_empty() && first > 0 {
            self.instance_of = vec![NO_INSTANCE; first as usize];
        }
        let instance = self.instances.len() as u32;
        let data = &self.meshes[mesh as usize];
        for tri in &data.indices {
            let v = tri.map(|i| to_world.transform_point3a(data.positions[i as usize].into()));
            let n = sign * (v[1] - v[0]).cross(v[2] - v[0]).normalize_or_zero();
            self.triangles
                .push(crate::geometry::triangle::Triangle::new(v[0], v[1], v[2]));
            self.normals.push(n);
            self.material_of.push(material);
            self.instance_of.push(instance);
        }
        self.instances.push(Instance::new(mesh, first, to_world));
    }
}

/// Moves an analytic shape by `to_world` (a sphere only by a similarity);
/// `false` when the result is degenerate (a disk or cylinder squashed flat:
/// it is dropped, as its triangles would be).
fn transform_shape(shape: &mut AnalyticShape, to_world: Affine3A) -> bool {
    let linear = to_world.matrix3;
    match shape {
        AnalyticShape::Sphere(s) => {
            let Some(scale) = similarity(linear) else {
                return false;
            };
            s.center = to_world.transform_point3a(s.center);
            s.radius *= scale;
            s.frame = linear * (1.0 / scale) * s.frame;
        }
        AnalyticShape::Disk(d) => match d.placement.then(to_world) {
            Some(p) => *d = Disk::new(p),
            None => return false,
        },
        AnalyticShape::Cylinder(c) => match c.placement.then(to_world) {
            Some(p) => *c = Cylinder::new(p),
            None => return false,
        },
        AnalyticShape::SdfVoxel(v) => match v.placement.then(to_world) {
            Some(p) => v.placement = p,
            None => return false,
        },
    }
    true
}

/// Segments around a sphere made into triangles (256: within 2e-4 of its area).
pub const SPHERE_SEGMENTS: u32 = 256;

/// The scale of `m` if it is a rotation (or a mirror) times a uniform scale,
/// to a relative 1e-5.
pub fn similarity(m: Mat3A) -> Option<f32> {
    let cols = [m.x_axis, m.y_axis, m.z_axis];
    let s = cols[0].length();
    if !(s > 0.0 && s.is_finite()) {
        return None;
    }
    let tol = 1e-5 * s * s;
    let same = cols
        .iter()
        .all(|c| (c.length_squared() - s * s).abs() <= tol * 2.0);
    let orthogonal = cols[0].dot(cols[1]).abs() <= tol
        && cols[0].dot(cols[2]).abs() <= tol
        && cols[1].dot(cols[2]).abs() <= tol;
    (same && orthogonal).then_some(s)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::triangle::Triangle;
    use crate::materials::surface::SurfaceMaterial;
    use crate::scene::{MeshData, Scene};

    fn quad(material: u32) -> SceneParts {
        let (a, b, c, d) = (Vec3A::ZERO, Vec3A::X, Vec3A::new(1.0, 1.0, 0.0), Vec3A::Y);
        SceneParts {
            triangles: vec![Triangle::new(a, b, c), Triangle::new(a, c, d)],
            normals: vec![Vec3A::Z; 2],
            material_of: vec![material; 2],
            materials: vec![SurfaceMaterial::diffuse(Vec3A::splat(0.5)); material as usize + 1],
            ..SceneParts::default()
        }
    }

    #[test]
    fn appended_parts_keep_their_references() {
        let mut meshed = quad(0);
        meshed.meshes.push(MeshData {
            positions: vec![
                glam::Vec3::ZERO,
                glam::Vec3::X,
                glam::Vec3::ONE,
                glam::Vec3::Y,
            ],
            indices: vec![[0, 1, 2], [0, 2, 3]],
            ..MeshData::default()
        });
        meshed
            .instances
            .push(Instance::new(0, 0, Affine3A::IDENTITY));
        meshed.instance_of = vec![0, 0];
        meshed.lights.push(Light::Point {
            position: Vec3A::ZERO,
            intensity: Vec3A::ONE,
        });
        let mut empty = SceneParts::default();
        empty.append(meshed.clone());
        assert_eq!(empty.instance_of, [0, 0]);
        let mut all = quad(1);
        all.append(meshed.clone());
        meshed.transform(Affine3A::from_translation(glam::Vec3::new(0.0, 0.0, 5.0)));
        all.append(meshed);
        assert_eq!(all.triangles.len(), 6);
        assert_eq!(all.material_of, [1, 1, 2, 2, 3, 3]);
        assert_eq!(all.instance_of, [NO_INSTANCE, NO_INSTANCE, 0, 0, 1, 1]);
        assert_eq!(all.instances[1].first_triangle, 4);
        assert_eq!(all.instances[1].mesh, 1);
        assert_eq!(all.instances[1].to_world.translation.z, 5.0);
        assert_eq!(all.triangles[5].v[1], Vec3A::new(1.0, 1.0, 5.0));
        assert!(matches!(all.lights[1], Light::Point { position, .. } if position.z == 5.0));
        // What from_parts checks holds.
        Scene::from_parts(all).unwrap();
    }

    #[test]
    fn transforms_move_normals_as_normals() {
        let mut parts = quad(0);
        // Stretch x by 4 and turn 90° about y: +z normals become +x.
        let m = Affine3A::from_rotation_y(std::f32::consts::FRAC_PI_2)
            * Affine3A::from_scale(glam::Vec3::new(4.0, 1.0, 1.0));
        parts.transform(m);
        for n in &parts.normals {
            assert!((*n - Vec3A::X).length() < 1e-6, "{n}");
        }
        let t = &parts.triangles[0];
        assert!(
            (t.v[1] - Vec3A::new(0.0, 0.0, -4.0)).length() < 1e-5,
            "{}",
            t.v[1]
        );
    }
}
