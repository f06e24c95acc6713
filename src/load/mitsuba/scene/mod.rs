//! A Mitsuba 3 scene tree ([`SceneTree`]) turned into raylab's scene parts,
//! camera, environment and render settings ([`MitsubaScene`]), following
//! each plugin's definition in Mitsuba 3's source and documentation. What
//! raylab reads, approximates and refuses is listed in
//! `docs/mitsuba-scenes.md`; a property nothing reads is an error, as in
//! Mitsuba.
//!
//! `color.rs` turns spectra into RGB (over the CIE tables of `cie.rs`),
//! `props.rs` reads properties by type, `shapes.rs` makes meshes,
//! `bsdfs.rs` materials and textures; this file walks the scene: sensor,
//! film, sampler and integrator into settings and a camera, shapes (with
//! shape groups and instances sharing their meshes) and emitters.

mod bsdfs;
mod color;
mod conductors;
mod media;
mod props;
mod shapes;

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use glam::{Affine3A, Mat3A, Mat4, Vec3, Vec3A};

use super::error::MitsubaError;
use super::tree::{Object, SceneTree, Tag};
use crate::camera::{Aperture, DepthOfField, FilmWindow, Focus, Lens, SceneCamera};
use crate::integrators::Integrator;
use crate::integrators::path::{DirectSamples, HideEmitters, PathOptions};
use crate::lights::environment::{EnvMap, Environment};
use crate::lights::{BeamShape, Light};
use crate::load::shot::settings::ShotSettings;
use crate::materials::surface::SurfaceMaterial;
use crate::memory::Ledger;
use crate::sampling::filter::PixelFilter;
use crate::scene::mesh::MeshData;
use crate::scene::{MediumInterface, SceneParts};
use crate::textures::{ColorSpace, Pattern, TextureRef};
use bsdfs::Materials;
use color::Role;
use props::{ColorProp, Props};
use shapes::Member;

/// A Mitsuba scene as raylab's parts.
#[derive(Debug)]
pub struct MitsubaScene {
    /// Geometry, materials, textures and punctual lights (one-sided).
    pub parts: SceneParts,
    /// The `constant` or `envmap` emitter (black without one).
    pub environment: Environment,
    /// The first sensor.
    pub camera: Option<SceneCamera>,
    /// The film's size, the sampler's count and the integrator.
    pub settings: ShotSettings,
    /// What was approximated or ignored.
    pub warnings: Vec<String>,
    /// The objects read, by kind and plugin ([`SceneTree::summary`]).
    pub summary: String,
}

/// The 3 × 3 part and translation of a transform.
fn affine(m: Mat4) -> Affine3A {
    Affine3A::from_mat4(m)
}

/// Reads the scene at `path` (with `defines` as `mitsuba -D`) into raylab's
/// parts, charging textures to `ledger`.
pub fn load_mitsuba(
    path: &Path,
    defines: &[(String, String)],
    ledger: &Ledger,
) -> Result<MitsubaScene, MitsubaError> {
    let tree = super::xml::read_file(path, defines)?;
    build(&tree, ledger)
}

/// A shape's mesh before it is placed.
struct Placed {
    mesh: u32,
    to_world: Mat4,
    material: u32,
    /// Whether the mesh's normals are its own (see `Builder::place`).
    own_normals: bool,
}

struct Builder<'t, 'l> {
    tree: &'t SceneTree,
    materials: Materials<'l>,
    parts: SceneParts,
    /// Material table index by (BSDF object, emitter object) pointers and
    /// the media on the shape's two sides.
    material_of: HashMap<(usize, usize, MediumInterface), u32>,
    /// Medium index by the medium object's pointer.
    media_of: HashMap<usize, u32>,
    /// Members of shape groups, by the group object's pointer.
    groups: HashMap<usize, Vec<Member>>,
    /// The mesh attribute each material reads (its shapes' colours).
    attribute_of: HashMap<u32, Option<String>>,
    approximated: Vec<String>,
}

impl Builder<'_, '_> {
    /// The index of a `<medium>` (read once, however often referenced).
    fn medium(&mut self, o: &Arc<Object>) -> Result<u32, MitsubaError> {
        let key = Arc::as_ptr(o) as usize;
        if let Some(&m) = self.media_of.get(&key) {
            return Ok(m);
        }
        let medium = media::medium(o, self.tree, self.materials.ledger())?;
        let index = self.parts.media.media.len() as u32;
        self.parts.media.media.push(medium);
        self.media_of.insert(key, index);
        Ok(index)
    }

    /// The media a shape bounds: its `interior` and `exterior`.
    fn interface(&mut self, p: &Props) -> Result<MediumInterface, MitsubaError> {
        let mut side = |name: &str| -> Result<Option<u32>, MitsubaError> {
            match p.child_opt(name) {
                None => Ok(None),
                Some(o) if o.tag == Tag::Medium => self.medium(&o).map(Some),
                Some(o) => {
                    Err(p.error(format!("its {name} must be a medium, not {}", o.describe())))
                }
            }
        };
        Ok(MediumInterface {
            interior: side("interior")?,
            exterior: side("exterior")?,
        })
    }

    /// The material of a shape's BSDF (default: Mitsuba's diffuse 0.5),
    /// area emitter and the media it bounds.
    fn material(
        &mut self,
        bsdf: Option<&Arc<Object>>,
        emitter: Option<&Arc<Object>>,
        interface: MediumInterface,
    ) -> Result<u32, MitsubaError> {
        let key = (
            bsdf.map_or(0, |b| Arc::as_ptr(b) as usize),
            emitter.map_or(0, |e| Arc::as_ptr(e) as usize),
            interface,
        );
        if let Some(&m) = self.material_of.get(&key) {
            return Ok(m);
        }
        let tree = self.tree;
        let resolve = move |name: &str| tree.resolve(name);
        self.materials.attribute = None;
        let mut m = match bsdf {
            Some(b) => self.materials.material(b, &resolve)?,
            None => {
                // Mitsuba's default: diffuse, 0.5 grey, or black for a shape
                // that emits (`Shape::Shape` in Mitsuba 3.7.1).
                let rho = Vec3A::splat(if emitter.is_some() { 0.0 } else { 0.5 });
                let mut m = SurfaceMaterial::diffuse(rho);
                m.kind = crate::materials::surface::MaterialKind::Textured(Box::new(
                    crate::materials::surface::TexturedBsdf::new(
                        crate::materials::Material::Diffuse { reflectance: rho },
                    ),
                ));
                m
            }
        };
        if let Some(e) = emitter {
            let p = Props::new(e);
            if e.plugin != "area" {
                return Err(p.error("only 'area' emitters can be attached to a shape"));
            }
            match p.color_opt("radiance", Role::Emission)? {
                None => m.emission = Vec3A::ONE,
                Some(ColorProp::Value(c)) => m.emission = c,
                Some(ColorProp::Texture(t)) => {
                    // An sRGB image (Mitsuba's `bitmap` as radiance), bilinear.
                    let pattern = self.materials.pattern(&t, &resolve)?;
                    let tex = match pattern {
                        Pattern::Image {
                            image,
                            wrap,
                            nearest: false,
                            space: ColorSpace::Srgb,
                            to_uv,
                        } if to_uv == glam::Affine2::IDENTITY => TextureRef {
                            wrap_s: wrap,
                            wrap_t: wrap,
                            ..TextureRef::new(image)
                        },
                        _ => {
                            return Err(Props::new(&t).error(
                                "an area light's radiance texture must be a bilinear sRGB bitmap without to_uv (others are not supported yet)",
                            ));
                        }
                    };
                    m.emission = Vec3A::ONE;
                    m.emission_texture = Some(tex);
                }
            }
            m.emits_both_sides = false;
            p.finish()?;
        }
        let index = self.parts.materials.len() as u32;
        self.parts.materials.push(m);
        if interface.is_transition() {
            let interfaces = &mut self.parts.media.interfaces;
            interfaces.resize(index as usize + 1, MediumInterface::default());
            interfaces[index as usize] = interface;
        }
        self.material_of.insert(key, index);
        self.attribute_of
            .insert(index, self.materials.attribute.take());
        Ok(index)
    }

    /// A shape object's mesh in its own space, and its `to_world`.
    fn mesh(
        &mut self,
        shape: &Object,
        p: &Props,
        attribute: Option<&str>,
    ) -> Result<(MeshData, Mat4, bool), MitsubaError> {
        let no_attributes = |p: &Props| {
            match attribute {
            Some(a) => Err(p.error(format!(
                "its material reads the mesh attribute '{}', which only ply and serialized meshes carry",
                crate::guard::quote(a)
            ))),
            None => Ok(()),
        }
        };
        if !matches!(shape.plugin.as_str(), "ply" | "serialized") {
            no_attributes(p)?;
        }
        let to_world = p.transform("to_world")?;
        let resolve = |p: &Props, name: &str| -> Result<PathBuf, MitsubaError> {
            self.tree
                .resolve(name)
                .ok_or_else(|| p.error(format!("cannot find '{}'", crate::guard::quote(name))))
        };
        // Whether the mesh's normals are its own (a file's, or a built-in
        // shape's), which Mitsuba carries to the world by the inverse
        // transpose, rather than made from the placed triangles (see
        // `place`).
        let mut own_normals = true;
        let mut mesh = match shape.plugin.as_str() {
            "obj" => {
                let file = p
                    .string_opt("filename")?
                    .ok_or_else(|| p.error("needs a 'filename'"))?;
                let file = resolve(p, file)?;
                let flip_uv = p.boolean("flip_tex_coords", true)?;
                let face_normals = p.boolean("face_normals", false)?;
                let (mesh, file_normals) = shapes::obj_mesh(&file, flip_uv, face_normals)?;
                own_normals = file_normals;
                mesh
            }
            "ply" => {
                let file = p
                    .string_opt("filename")?
                    .ok_or_else(|| p.error("needs a 'filename'"))?;
                let file = resolve(p, file)?;
                let flip_uv = p.boolean("flip_tex_coords", false)?;
                let face_normals = p.boolean("face_normals", false)?;
                let m = super::ply::read_ply(&file, flip_uv, self.materials.ledger())?;
                own_normals = m.normals.is_some();
                shapes::from_mitsuba_mesh(m, face_normals, attribute).map_err(|e| p.error(e))?
            }
            "serialized" => {
                let file = p
                    .string_opt("filename")?
                    .ok_or_else(|| p.error("needs a 'filename'"))?;
                let file = resolve(p, file)?;
                let index = p.integer("shape_index", 0)?;
                let face_normals = p.boolean("face_normals", false)?;
                let m = super::serialized::read_serialized(&file, index, self.materials.ledger())?;
                own_normals = m.normals.is_some();
                shapes::from_mitsuba_mesh(m, face_normals, attribute).map_err(|e| p.error(e))?
            }
            "rectangle" => shapes::rectangle(),
            "cube" => shapes::cube(),
            // (Made into triangles only where they cannot stay analytic: see
            // `shape`.)
            "sphere" | "disk" | "cylinder" => MeshData::default(),
            other => {
                return Err(p.error(format!(
                    "the shape '{}' is not supported yet (see docs/mitsuba-scenes.md)",
                    crate::guard::quote(other)
                )));
            }
        };
        // The analytic shapes' own placement parameters.
        let mut to_world = to_world;
        match shape.plugin.as_str() {
            "sphere" => {
                let c = p.vector_opt("center")?.unwrap_or(Vec3::ZERO);
                let r = p.float("radius", 1.0)?;
                to_world = to_world * Mat4::from_translation(c) * Mat4::from_scale(Vec3::splat(r));
            }
            "cylinder" => {
                let p0 = p.vector_opt("p0")?.unwrap_or(Vec3::ZERO);
                let p1 = p.vector_opt("p1")?.unwrap_or(Vec3::Z);
                let r = p.float("radius", 1.0)?;
                let axis = p1 - p0;
                let len = axis.length();
                if len <= 0.0 {
                    return Err(p.error("p0 and p1 are the same point"));
                }
                // Mitsuba's frame about the axis (which fixes where u = 0).
                let z = axis / len;
                let (x, y) = crate::geometry::placement::coordinate_system(z.as_dvec3());
                let (x, y) = (x.as_vec3(), y.as_vec3());
                let frame = Mat4::from_cols(
                    (x * r).extend(0.0),
                    (y * r).extend(0.0),
                    (z * len).extend(0.0),
                    p0.extend(1.0),
                );
                to_world *= frame;
            }
            _ => {}
        }
        if p.boolean("flip_normals", false)? {
            shapes::flip(&mut mesh);
        }
        let own_normals = own_normals && !mesh.normals.is_empty();
        Ok((mesh, to_world, own_normals))
    }

    /// Adds a shape (and what it holds) to the scene; shape groups are
    /// remembered, instances placed.
    fn shape(
        &mut self,
        shape: &Arc<Object>,
        within: Option<&mut Vec<Member>>,
    ) -> Result<(), MitsubaError> {
        let p = Props::new(shape);
        match shape.plugin.as_str() {
            "shapegroup" => {
                if self.groups.contains_key(&(Arc::as_ptr(shape) as usize)) {
                    // Built already, for an instance that came first.
                    return Ok(());
                }
                let mut members = Vec::new();
                for s in p.children_of(Tag::Shape) {
                    self.shape(&s, Some(&mut members))?;
                }
                p.finish()?;
                self.groups.insert(Arc::as_ptr(shape) as usize, members);
                return Ok(());
            }
            "instance" => {
                let to_world = p.transform("to_world")?;
                let groups = p.children_of(Tag::Shape);
                let [group] = groups.as_slice() else {
                    return Err(p.error("needs exactly one shapegroup"));
                };
                if group.plugin != "shapegroup" {
                    return Err(p.error("instances place a shapegroup"));
                }
                if !self.groups.contains_key(&(Arc::as_ptr(group) as usize)) {
                    self.shape(group, None)?;
                }
                p.finish()?;
                let members = self.groups[&(Arc::as_ptr(group) as usize)].clone();
                for member in members {
                    match member {
                        Member::Mesh(mesh, m, material, own_normals) => self.place(Placed {
                            mesh,
                            to_world: to_world * m,
                            material,
                            own_normals,
                        }),
                        Member::Sdf(grid, m, material, smooth) => self
                            .parts
                            .place_sdf_grid(grid, affine(to_world * m), material, smooth)
                            .map(|_| ())
                            .map_err(|e| p.error(format!("its sdfgrid: {e}")))?,
                        Member::Analytic(plugin, m, material, flip) => {
                            self.analytic(plugin, to_world * m, material, flip)
                        }
                    }
                }
                return Ok(());
            }
            _ => {}
        }
        let bsdfs = p.children_of(Tag::Bsdf);
        let emitters = p.children_of(Tag::Emitter);
        if bsdfs.len() > 1 || emitters.len() > 1 {
            return Err(p.error("a shape holds at most one BSDF and one emitter"));
        }
        if shape.plugin == "sdfgrid" && !emitters.is_empty() {
            return Err(p.error(
                "an sdfgrid cannot be an area emitter (as in Mitsuba, which has no way to sample its surface)",
            ));
        }
        let interface = self.interface(&p)?;
        let material = self.material(bsdfs.first(), emitters.first(), interface)?;
        if shape.plugin == "sdfgrid" {
            return self.sdfgrid(&p, material, within);
        }
        let attribute = self.attribute_of.get(&material).cloned().flatten();
        let (mut mesh, to_world, own_normals) = self.mesh(shape, &p, attribute.as_deref())?;
        shapes::finish(&p)?;
        mesh.material = material;
        let analytic = match shape.plugin.as_str() {
            "sphere" => Some("sphere"),
            "disk" => Some("disk"),
            "cylinder" => Some("cylinder"),
            _ => None,
        };
        if let Some(plugin) = analytic {
            // An analytic shape, placed now or by each instance of its
            // shape group (whose placements may not suit it: see
            // `Builder::analytic`).
            let flip = p.boolean("flip_normals", false)?;
            match within {
                Some(members) => members.push(Member::Analytic(plugin, to_world, material, flip)),
                None => self.analytic(plugin, to_world, material, flip),
            }
            return Ok(());
        }
        let mesh_index = self.parts.meshes.len() as u32;
        self.parts.meshes.push(mesh);
        match within {
            Some(members) => {
                members.push(Member::Mesh(mesh_index, to_world, material, own_normals))
            }
            None => self.place(Placed {
                mesh: mesh_index,
                to_world,
                material,
                own_normals,
            }),
        }
        Ok(())
    }

    /// A `sphere`, `disk` or `cylinder` placed by `to_world`, with
    /// `material` and `flip_normals` `flip`: analytic where the placement
    /// suits it (a sphere's a similarity), else Mitsuba's unit shape
    /// tessellated (the load says so).
    fn analytic(&mut self, plugin: &'static str, to_world: Mat4, material: u32, flip: bool) {
        if let Some(s) = shapes::analytic(plugin, affine(to_world), flip) {
            self.parts
                .shapes
                .push(crate::scene::SceneShape { material, ..s });
            return;
        }
        self.approximated.push(plugin.to_string());
        let mut mesh = shapes::tessellated(plugin);
        mesh.material = material;
        if flip {
            shapes::flip(&mut mesh);
        }
        let mesh_index = self.parts.meshes.len() as u32;
        self.parts.meshes.push(mesh);
        self.place(Placed {
            mesh: mesh_index,
            to_world,
            material,
            own_normals: true,
        });
    }

    /// An `sdfgrid` (Mitsuba's signed distance grid: the zero set of the
    /// trilinear interpolation of a `.vol` file's samples over the unit
    /// cube) with material `material`: exact cells among the analytic
    /// shapes, placed now or, in a shape group, by each instance.
    fn sdfgrid(
        &mut self,
        p: &Props,
        material: u32,
        within: Option<&mut Vec<Member>>,
    ) -> Result<(), MitsubaError> {
        let (path, smooth, to_world) = shapes::sdfgrid_props(p, self.tree)?;
        let grid = super::vol::read_sdf_vol(&path, self.materials.ledger())?;
        let index = self.parts.sdf_grids.len() as u32;
        self.parts.sdf_grids.push(grid);
        match within {
            Some(members) => members.push(Member::Sdf(index, to_world, material, smooth)),
            None => {
                self.parts
                    .place_sdf_grid(index, affine(to_world), material, smooth)
                    .map_err(|e| p.error(e))?;
            }
        }
        Ok(())
    }

    /// World triangles and an instance of a mesh. Its front (the side a
    /// one-sided BSDF shows and an area light emits to) is, as in Mitsuba,
    /// the side its shading normals point to: normals of its own are
    /// carried to the world by the inverse transpose, so under a placement
    /// that mirrors (negative determinant) they point against the placed
    /// triangles' winding, and the front turns with them; normals Mitsuba
    /// makes (a mesh without them) come from the placed triangles and keep
    /// their winding's side, as do face normals.
    fn place(&mut self, placed: Placed) {
        let to_world = affine(placed.to_world);
        let by_normals = placed.own_normals && to_world.matrix3.determinant() < 0.0;
        self.parts
            .place_instance_turned(placed.mesh, to_world, placed.material, by_normals);
    }
}

/// Mitsuba's sensor frame as raylab's camera rotation: Mitsuba looks along
/// local +z with +y up and the image's left at local +x.
fn camera_frame(m: Mat4) -> (Vec3A, Mat3A, f32, f32) {
    let x = m.x_axis.truncate();
    let y = m.y_axis.truncate();
    let z = m.z_axis.truncate();
    let right = Vec3A::from(-x).normalize_or_zero();
    let down = Vec3A::from(-y).normalize_or_zero();
    let forward = Vec3A::from(z).normalize_or_zero();
    (
        Vec3A::from(m.w_axis.truncate()),
        Mat3A::from_cols(right, down, forward),
        x.length(),
        y.length(),
    )
}

/// A reconstruction filter.
fn rfilter(rf: &Object) -> Result<PixelFilter, MitsubaError> {
    let p = Props::new(rf);
    let filter = match rf.plugin.as_str() {
        "box" => PixelFilter::Box,
        "gaussian" => {
            let s = p.float("stddev", 0.5)?;
            if !(s > 0.0 && s <= 16.0) {
                return Err(p.error("stddev must be in (0, 16]"));
            }
            PixelFilter::gaussian(s)
        }
        "tent" => {
            let r = p.float("radius", 1.0)?;
            if !(r > 0.0 && r <= 64.0) {
                return Err(p.error("radius must be in (0, 64]"));
            }
            PixelFilter::tent(r)
        }
        other => {
            return Err(p.error(format!(
                "the '{}' filter is not supported (box, gaussian and tent are)",
                crate::guard::quote(other)
            )));
        }
    };
    p.finish()?;
    Ok(filter)
}

/// A spot or projector placed by `to_world`.
fn beam_light(
    p: &Props,
    to_world: Mat4,
    intensity: Vec3A,
    shape: BeamShape,
    texture: Option<crate::textures::Pattern>,
) -> Result<Light, MitsubaError> {
    let linear = glam::Mat3A::from_mat4(to_world);
    if linear.determinant().abs() < 1e-12 {
        return Err(p.error("to_world is singular"));
    }
    Ok(Light::Beam(crate::lights::Beam {
        position: Vec3A::from(to_world.w_axis.truncate()),
        to_local: linear.inverse(),
        axis: (linear * Vec3A::Z).normalize(),
        intensity,
        shape,
        texture,
    }))
}

/// Mitsuba's horizontal field of view in degrees from `fov` and
/// `fov_axis` (or a `focal_length`, a diagonal field of a 36 × 24 mm film)
/// for an image of width over height `aspect` (its `parse_fov`).
fn x_fov(p: &Props, aspect: f32) -> Result<f32, MitsubaError> {
    if p.has("fov") && p.has("focal_length") {
        return Err(p.error("give either 'fov' or 'focal_length', not both"));
    }
    let axis = p.choice(
        "fov_axis",
        "x",
        &["x", "y", "diagonal", "smaller", "larger"],
    )?;
    let (fov, axis) = match p.float_opt("fov")? {
        Some(f) => (f64::from(f), axis),
        None => {
            let fl = p.string("focal_length", "50mm")?;
            let mm: f64 = fl
                .trim_end_matches("mm")
                .parse()
                .map_err(|_| p.error("focal_length must be like '50mm'"))?;
            let d = (36.0f64 * 36.0 + 24.0 * 24.0).sqrt();
            ((2.0 * (d / (2.0 * mm)).atan()).to_degrees(), "diagonal")
        }
    };
    let aspect = f64::from(aspect);
    let axis = match axis {
        "smaller" if aspect > 1.0 => "y",
        "smaller" => "x",
        "larger" if aspect > 1.0 => "x",
        "larger" => "y",
        a => a,
    };
    let half = (fov.to_radians() * 0.5).tan();
    let x = match axis {
        "x" => fov,
        "y" => (2.0 * (half * aspect).atan()).to_degrees(),
        _ => {
            let width = 2.0 * half / (1.0 + 1.0 / (aspect * aspect)).sqrt();
            (2.0 * (width * 0.5).atan()).to_degrees()
        }
    };
    if !(x > 0.0 && x < 180.0) {
        return Err(p.error("the horizontal field of view must be between 0 and 180 degrees"));
    }
    Ok(x as f32)
}

/// The sensor's camera and the film's settings.
fn sensor(sensor: &Object, settings: &mut ShotSettings) -> Result<SceneCamera, MitsubaError> {
    let p = Props::new(sensor);
    let to_world = p.transform("to_world")?;
    let (mut width, mut height) = (768u32, 576u32);
    let mut window = None;
    if let Some(film) = p.children_of(Tag::Film).first() {
        let f = Props::new(film);
        if film.plugin != "hdrfilm" {
            return Err(f.error("only 'hdrfilm' is supported"));
        }
        let w = f.integer("width", 768)?;
        let h = f.integer("height", 576)?;
        if !(1..=65536).contains(&w) || !(1..=65536).contains(&h) {
            return Err(f.error("width and height must be 1 to 65536"));
        }
        (width, height) = (w as u32, h as u32);
        window = film_window(&f, [width, height])?;
        let filters = f.children_of(Tag::Rfilter);
        settings.filter = Some(match filters.first() {
            // Mitsuba's default.
            None => PixelFilter::gaussian(0.5),
            Some(rf) => rfilter(rf)?,
        });
        f.ignore(&[
            "pixel_format",
            "component_format",
            "file_format",
            "sample_border",
            "compensate",
            "banner",
            "high_quality_edges",
        ]);
        f.finish()?;
    }
    settings.width = Some(width);
    settings.height = Some(height);
    if let Some(sampler) = p.children_of(Tag::Sampler).first() {
        let s = Props::new(sampler);
        let n = s.integer("sample_count", 4)?;
        if !(1..=i64::from(u32::MAX)).contains(&n) {
            return Err(s.error("sample_count must be positive"));
        }
        settings.spp = Some(n as u32);
        s.ignore(&["seed", "jitter", "scramble_seed"]);
        s.finish()?;
    }
    let aspect = width as f32 / height as f32;
    let (position, rotation, sx, sy) = camera_frame(to_world);
    let mut depth_of_field = DepthOfField::default();
    let lens = match sensor.plugin.as_str() {
        "perspective" | "thinlens" => {
            if sensor.plugin == "thinlens" {
                depth_of_field = thin_lens(&p, to_world)?;
            }
            // tan of half the vertical field of view.
            let tan_y = (x_fov(&p, aspect)?.to_radians() * 0.5).tan() / aspect;
            Lens::Perspective {
                focal_scale: 0.5 / tan_y,
            }
        }
        "orthographic" => Lens::Orthographic {
            half_height: sy / aspect,
        },
        other => {
            return Err(p.error(format!(
                "the sensor '{}' is not supported yet",
                crate::guard::quote(other)
            )));
        }
    };
    let _ = sx;
    clip_planes(&p)?;
    // (A pinhole's `focus_distance` is read by Mitsuba and has no effect.)
    p.ignore(&["focus_distance", "shutter_open", "shutter_close", "srf"]);
    p.finish()?;
    Ok(SceneCamera {
        name: sensor.id.clone().unwrap_or_default(),
        position,
        rotation,
        lens,
        aspect_ratio: Some(aspect),
        depth_of_field,
        window,
    })
}

/// The film's crop window (`crop_offset_x`, `crop_offset_y`, `crop_width`,
/// `crop_height`, Mitsuba's `Film`: the whole film by default), checked to
/// lie within the film of `size`; `None` when it is the whole film.
fn film_window(f: &Props, size: [u32; 2]) -> Result<Option<FilmWindow>, MitsubaError> {
    let names = [
        ["crop_offset_x", "crop_width"],
        ["crop_offset_y", "crop_height"],
    ];
    let mut offset = [0u32; 2];
    let mut extent = size;
    for (k, [at, len]) in names.into_iter().enumerate() {
        let side = size[k];
        let o = f.integer(at, 0)?;
        if !(0..i64::from(side)).contains(&o) {
            return Err(f.error_at(
                at,
                format!(
                    "{o} is outside the film (0 to {} for its {side} pixels)",
                    side - 1
                ),
            ));
        }
        let n = f.integer(len, i64::from(side) - o)?;
        if !(1..=i64::from(side) - o).contains(&n) {
            return Err(f.error_at(
                len,
                format!(
                    "{n} does not fit the film: {at} {o} + {len} must be 1 to {side} pixels \
                     (the film's {})",
                    if k == 0 { "width" } else { "height" }
                ),
            ));
        }
        (offset[k], extent[k]) = (o as u32, n as u32);
    }
    Ok((offset != [0, 0] || extent != size).then_some(FilmWindow {
        film: size,
        offset,
        size: extent,
    }))
}

/// Checks a projective sensor's clip planes as Mitsuba does (`near_clip`
/// above 0 and below `far_clip`; 0.01 and 10⁴ by default). raylab's cameras
/// do not clip: they matter only for surfaces nearer than `near_clip` to the
/// camera or farther than `far_clip`.
fn clip_planes(p: &Props) -> Result<(f32, f32), MitsubaError> {
    let near = p.float("near_clip", 1e-2)?;
    let far = p.float("far_clip", 1e4)?;
    if near <= 0.0 {
        return Err(p.error_at("near_clip", "must be greater than zero"));
    }
    if near >= far {
        return Err(p.error_at("far_clip", "must be greater than near_clip"));
    }
    Ok((near, far))
}

/// Mitsuba's `thinlens`: a lens of `aperture_radius` (a uniform disk, its
/// points in the plane through the sensor's position across the view) that
/// focuses at `focus_distance` along the view axis (default `far_clip`, as
/// Mitsuba's `ProjectiveCamera`); raylab's [`crate::camera::ThinLens`] with
/// the same radius and focus. A radius of 0 is a pinhole (Mitsuba takes its
/// float epsilon then). Like Mitsuba, a `to_world` that scales is refused.
fn thin_lens(p: &Props, to_world: Mat4) -> Result<DepthOfField, MitsubaError> {
    // A length the lens takes: a radius (at least 0) or a distance (above 0).
    let length = |name: &str, value: f32, positive: bool| {
        if crate::camera::lens_length_is_valid(value, positive) {
            return Ok(value);
        }
        let least = if positive { "above 0" } else { "at least 0" };
        let most = crate::camera::MAX_LENS_LENGTH;
        Err(p.error_at(name, format!("must be {least} and at most {most:e}")))
    };
    let radius = p
        .float_opt("aperture_radius")?
        .ok_or_else(|| p.error("needs an 'aperture_radius'"))?;
    let radius = length("aperture_radius", radius, false)?;
    let far = p.float_opt("far_clip")?.unwrap_or(1e4);
    let focus = length("focus_distance", p.float("focus_distance", far)?, true)?;
    // Mitsuba's `has_scale`: the rows of the 3 × 3 part orthonormal to 1e-3.
    let m = Mat3A::from_mat4(to_world).transpose();
    let gram = m.transpose() * m;
    let scales = (gram - Mat3A::IDENTITY)
        .to_cols_array()
        .iter()
        .any(|e| e.abs() > 1e-3);
    if scales {
        return Err(p.error_at(
            "to_world",
            "scale factors in the camera-to-world transformation are not allowed (as in Mitsuba)",
        ));
    }
    Ok(DepthOfField {
        aperture: Some(Aperture::Radius(radius)),
        focus: Some(Focus::Distance(focus)),
        blades: None,
    })
}

/// `direct`'s sample counts: `emitter_samples` and `bsdf_samples`, each
/// `shading_samples` (1) unless given (not both ways, as in Mitsuba).
fn direct_samples(p: &Props) -> Result<DirectSamples, MitsubaError> {
    if p.has("shading_samples") && (p.has("emitter_samples") || p.has("bsdf_samples")) {
        return Err(p.error(
            "give either shading_samples or emitter_samples/bsdf_samples, not both (as in Mitsuba)",
        ));
    }
    let count = |name: &str, default: u32| -> Result<u32, MitsubaError> {
        let n = p.integer(name, i64::from(default))?;
        u32::try_from(n)
            .ok()
            .filter(|&n| n <= DirectSamples::MAX)
            .ok_or_else(|| {
                p.error_at(
                    name,
                    format!("must be from 0 to {} (it is {n})", DirectSamples::MAX),
                )
            })
    };
    let shading = count("shading_samples", 1)?;
    let (emitter, bsdf) = (
        count("emitter_samples", shading)?,
        count("bsdf_samples", shading)?,
    );
    DirectSamples::new(emitter, bsdf)
        .ok_or_else(|| p.error("needs at least one emitter or BSDF sample (as in Mitsuba)"))
}

/// The integrator as raylab's `path` with its depth.
fn integrator(obj: &Object, settings: &mut ShotSettings) -> Result<(), MitsubaError> {
    let p = Props::new(obj);
    match obj.plugin.as_str() {
        "moment" => {
            for inner in p.children_of(Tag::Integrator) {
                integrator(&inner, settings)?;
            }
        }
        "path" | "ptracer" | "direct" => {
            let mut direct = DirectSamples::ONE_EACH;
            let depth = match obj.plugin.as_str() {
                "direct" => {
                    direct = direct_samples(&p)?;
                    2
                }
                _ => {
                    p.ignore(&["rr_depth", "samples_per_pass"]);
                    p.integer("max_depth", -1)?
                }
            };
            let hide_emitters = match (p.boolean("hide_emitters", false)?, obj.plugin.as_str()) {
                (false, _) => HideEmitters::No,
                // `direct` (rendered as a path of depth 2) by its own rule.
                (true, "direct") => HideEmitters::Direct,
                (true, "path") => HideEmitters::Path,
                // (Its hidden emitters stay opaque: not `path`'s rule.)
                (true, _) => {
                    return Err(p.error_at(
                        "hide_emitters",
                        "is not supported for ptracer yet (path and direct take it)",
                    ));
                }
            };
            let max_depth = match depth {
                -1 => u32::MAX,
                d if d >= 0 => u32::try_from(d).unwrap_or(u32::MAX),
                _ => return Err(p.error("max_depth must be -1 (unlimited) or at least 0")),
            };
            settings.max_depth = Some(max_depth);
            settings.integrator = Some(Integrator::Path(PathOptions {
                max_depth,
                hide_emitters,
                direct,
                ..PathOptions::default()
            }));
        }
        "volpath" | "volpathmis" => {
            // `path` made volumetric where the scene has media (`volpathmis`
            // samples chromatic media with spectral MIS, as raylab always
            // does; both converge to the same image).
            p.ignore(&["rr_depth"]);
            let max_depth = match p.integer("max_depth", -1)? {
                -1 => u32::MAX,
                d if d >= 0 => u32::try_from(d).unwrap_or(u32::MAX),
                _ => return Err(p.error("max_depth must be -1 (unlimited) or at least 0")),
            };
            let hide_emitters = if p.boolean("hide_emitters", false)? {
                HideEmitters::Path
            } else {
                HideEmitters::No
            };
            settings.max_depth = Some(max_depth);
            settings.integrator = Some(Integrator::Path(PathOptions {
                max_depth,
                hide_emitters,
                ..PathOptions::default()
            }));
        }
        other => {
            return Err(p.error(format!(
                "the integrator '{}' is not supported (path, direct, ptracer and moment are)",
                crate::guard::quote(other)
            )));
        }
    }
    p.finish()
}

/// Turns the tree into parts.
fn build(tree: &SceneTree, ledger: &Ledger) -> Result<MitsubaScene, MitsubaError> {
    let root = &tree.root;
    let scene_name = tree
        .files
        .first()
        .map(|f| f.display().to_string())
        .unwrap_or_default();
    let mut b = Builder {
        tree,
        materials: Materials::new(ledger, scene_name),
        parts: SceneParts::default(),
        material_of: HashMap::new(),
        media_of: HashMap::new(),
        groups: HashMap::new(),
        attribute_of: HashMap::new(),
        approximated: Vec::new(),
    };
    let mut settings = ShotSettings::default();
    let mut warnings = tree.warnings.clone();
    let mut camera = None;
    let mut environment = Environment::none();
    let rp = Props::new(root);
    for child in &root.children {
        let o = &child.object;
        match o.tag {
            Tag::Shape => b.shape(o, None)?,
            Tag::Bsdf | Tag::Texture => {} // used through references
            Tag::Sensor if camera.is_none() => camera = Some(sensor(o, &mut settings)?),
            Tag::Integrator => integrator(o, &mut settings)?,
            // An area light declared at the top (with an id) belongs to the
            // shapes that refer to it, which read it there.
            Tag::Emitter if o.plugin == "area" && o.id.is_some() => {}
            Tag::Emitter => {
                let p = Props::new(o);
                match o.plugin.as_str() {
                    "point" => {
                        let m = p.transform("to_world")?;
                        let pos = p
                            .vector_opt("position")?
                            .unwrap_or_else(|| m.w_axis.truncate());
                        let intensity =
                            p.constant_color("intensity", Role::Emission, Vec3A::ONE)?;
                        b.parts.lights.push(Light::Point {
                            position: pos.into(),
                            intensity,
                        });
                    }
                    "directional" => {
                        let m = p.transform("to_world")?;
                        let d = p
                            .vector_opt("direction")?
                            .unwrap_or_else(|| m.z_axis.truncate());
                        let irradiance =
                            p.constant_color("irradiance", Role::Emission, Vec3A::ONE)?;
                        let d = Vec3A::from(d).normalize_or_zero();
                        if d == Vec3A::ZERO {
                            return Err(p.error("direction is zero"));
                        }
                        b.parts.lights.push(Light::Directional {
                            direction: d,
                            irradiance,
                        });
                    }
                    "spot" => {
                        let m = p.transform("to_world")?;
                        let intensity =
                            p.constant_color("intensity", Role::Emission, Vec3A::ONE)?;
                        let cutoff = p.float("cutoff_angle", 20.0)?;
                        let beam = p.float("beam_width", cutoff * 0.75)?;
                        if !(cutoff > 0.0 && cutoff < 90.0 && beam >= 0.0 && beam < cutoff) {
                            return Err(p.error(
                                "needs 0 < cutoff_angle < 90 and 0 <= beam_width < cutoff_angle (degrees)",
                            ));
                        }
                        let texture = match p.child_opt("texture") {
                            None => None,
                            Some(t) => {
                                let resolve = |name: &str| tree.resolve(name);
                                Some(b.materials.pattern(&t, &resolve)?)
                            }
                        };
                        let shape = BeamShape::Spot {
                            cutoff: cutoff.to_radians(),
                            beam_width: beam.to_radians(),
                        };
                        b.parts
                            .lights
                            .push(beam_light(&p, m, intensity, shape, texture)?);
                    }
                    "projector" => {
                        let m = p.transform("to_world")?;
                        let scale = p.float("scale", 1.0)?;
                        let resolve = |name: &str| tree.resolve(name);
                        let (irradiance, texture, aspect) =
                            match p.color_opt("irradiance", Role::Emission)? {
                                None => (Vec3A::ONE, None, 1.0),
                                Some(ColorProp::Value(c)) => (c, None, 1.0),
                                Some(ColorProp::Texture(t)) => {
                                    let pattern = b.materials.pattern(&t, &resolve)?;
                                    let aspect = match pattern {
                                        crate::textures::Pattern::Image { image, .. } => {
                                            let i = b.materials.textures.get(image);
                                            i.width() as f32 / i.height() as f32
                                        }
                                        _ => 1.0,
                                    };
                                    (Vec3A::ONE, Some(pattern), aspect)
                                }
                            };
                        let x_fov = x_fov(&p, aspect)?;
                        let shape = BeamShape::Projector {
                            tan_half_fov: (x_fov.to_radians() * 0.5).tan(),
                            aspect,
                            normal: glam::Mat3A::from_mat4(m) * Vec3A::Z,
                        };
                        b.parts
                            .lights
                            .push(beam_light(&p, m, irradiance * scale, shape, texture)?);
                    }
                    "constant" => {
                        let radiance = p.constant_color("radiance", Role::Emission, Vec3A::ONE)?;
                        environment = Environment::constant(radiance);
                    }
                    "envmap" => {
                        let name = p
                            .string_opt("filename")?
                            .ok_or_else(|| p.error("needs a 'filename'"))?;
                        let file = tree.resolve(name).ok_or_else(|| {
                            p.error(format!("cannot find '{}'", crate::guard::quote(name)))
                        })?;
                        let scale = p.float("scale", 1.0)?;
                        let m = p.transform("to_world")?;
                        // Mitsuba's u is raylab's shifted by half a turn.
                        let map = EnvMap::load_with(&file, ledger)
                            .map_err(|e| p.error(e.to_string()))?
                            .with_pole_rows();
                        environment = Environment::map(map).with_strength(scale);
                        environment = if m == Mat4::IDENTITY {
                            environment.with_rotation(180.0)
                        } else {
                            // A rotation (Mitsuba looks up the inverse
                            // transform's direction), then the half turn.
                            let r = Mat3A::from_mat4(m);
                            let orthonormal = (r.transpose() * r - Mat3A::IDENTITY)
                                .to_cols_array()
                                .iter()
                                .all(|e| e.abs() < 1e-4)
                                && r.determinant() > 0.0;
                            if !orthonormal {
                                return Err(p.error(
                                    "an envmap's to_world must be a rotation (raylab does not take a scale or a mirror there)",
                                ));
                            }
                            environment
                                .with_frame(r * Mat3A::from_diagonal(Vec3::new(-1.0, 1.0, -1.0)))
                        };
                    }
                    other => {
                        return Err(p.error(format!(
                            "the emitter '{}' is not supported yet",
                            crate::guard::quote(other)
                        )));
                    }
                }
                p.finish()?;
            }
            // Media are read where shapes refer to them.
            Tag::Medium => {}
            Tag::Phase | Tag::Volume => {
                return Err(rp.error(format!("{} belongs inside a medium", o.describe())));
            }
            _ => {}
        }
    }
    warnings.append(&mut b.materials.warnings);
    if !b.approximated.is_empty() {
        let mut counts = std::collections::BTreeMap::new();
        for plugin in &b.approximated {
            *counts.entry(plugin.as_str()).or_insert(0usize) += 1;
        }
        let list: Vec<String> = counts.iter().map(|(p, n)| format!("{p} ×{n}")).collect();
        warnings.push(format!(
            "shapes approximated by triangles ({} segments around; spheres under uneven scales): {}",
            shapes::SEGMENTS,
            list.join(", ")
        ));
    }
    let mut parts = b.parts;
    if !parts.media.interfaces.is_empty() {
        parts
            .media
            .interfaces
            .resize(parts.materials.len(), MediumInterface::default());
    }
    // Mitsuba's integrators other than `volpath` and `volpathmis` ignore
    // media: surfaces that bound them are plain surfaces.
    let volumetric = root
        .children
        .iter()
        .any(|c| c.object.tag == Tag::Integrator && media::volumetric(&c.object));
    if !volumetric && !parts.media.is_empty() {
        warnings.push(
            "the scene's media are ignored: its integrator is not volpath or volpathmis (as in Mitsuba)".into(),
        );
        parts.media = Default::default();
    }
    parts.textures = b.materials.textures;
    parts.two_sided = false;
    Ok(MitsubaScene {
        parts,
        environment,
        camera,
        settings,
        warnings,
        summary: tree.summary(),
    })
}

/// A Mitsuba scene's render settings alone (film size, sample count,
/// integrator), without loading its meshes or textures.
pub fn read_settings(
    path: &Path,
    defines: &[(String, String)],
) -> Result<ShotSettings, MitsubaError> {
    let tree = super::xml::read_file(path, defines)?;
    let mut settings = ShotSettings::default();
    for o in tree.root.children_of(Tag::Sensor).take(1) {
        sensor(o, &mut settings)?;
    }
    for o in tree.root.children_of(Tag::Integrator) {
        integrator(o, &mut settings)?;
    }
    Ok(settings)
}
