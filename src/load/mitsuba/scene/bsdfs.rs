//! Mitsuba's BSDFs and textures as raylab materials. What has an exact
//! twin here is translated; what has none yet is refused with a clear line
//! (docs/mitsuba-scenes.md lists both).

use std::collections::HashMap;
use std::path::PathBuf;
use std::sync::Arc;

use glam::{Affine2, Mat2, Mat4, Vec3A, Vec4};

use super::super::error::MitsubaError;
use super::super::tree::{Object, Tag};
use super::color::Role;
use super::props::{ColorProp, Props};
use crate::materials::MicrofacetKind;
use crate::materials::mitsuba::{
    Conductor, Plastic, Principled, PrincipledThin, RoughConductor, RoughDielectric, RoughPlastic,
    SmoothDielectric, ThinDielectric,
};
use crate::materials::mitsuba::{Param, PrincipledParam};
use crate::materials::surface::{
    AlphaMode, MaterialKind, Perturb, PerturbMap, SurfaceMaterial, TexturedBsdf,
};
use crate::materials::{Blend, Material};
use crate::memory::Ledger;
use crate::textures::{ColorSpace, Image, Pattern, TextureStore, Wrap, mitsuba_luminance};

/// Mitsuba's named indices of refraction (`include/mitsuba/render/ior.h`:
/// Hecht's values at about 589 nm).
const IOR_TABLE: [(&str, f32); 23] = [
    ("vacuum", 1.0),
    ("helium", 1.000036),
    ("hydrogen", 1.000132),
    ("air", 1.000277),
    ("carbon dioxide", 1.00045),
    ("water", 1.3330),
    ("acetone", 1.36),
    ("ethanol", 1.361),
    ("carbon tetrachloride", 1.461),
    ("glycerol", 1.4729),
    ("benzene", 1.501),
    ("silicone oil", 1.52045),
    ("bromine", 1.661),
    ("water ice", 1.31),
    ("fused quartz", 1.458),
    ("pyrex", 1.470),
    ("acrylic glass", 1.49),
    ("polypropylene", 1.49),
    ("bk7", 1.5046),
    ("sodium chloride", 1.544),
    ("amber", 1.55),
    ("pet", 1.5750),
    ("diamond", 2.419),
];

/// An index of refraction given as a float or one of Mitsuba's names.
pub(super) fn ior(p: &Props, name: &str, default: f32) -> Result<f32, MitsubaError> {
    if let Ok(Some(v)) = p.float_opt(name) {
        return Ok(v);
    }
    match p.string_opt(name)? {
        None => Ok(default),
        Some(s) => {
            let lower = s.to_ascii_lowercase();
            IOR_TABLE
                .iter()
                .find(|(n, _)| *n == lower)
                .map(|(_, v)| *v)
                .ok_or_else(|| {
                    p.error(format!(
                        "unknown index of refraction '{}' for '{name}' (Mitsuba's names: {})",
                        crate::guard::quote(s),
                        IOR_TABLE.map(|(n, _)| n).join(", ")
                    ))
                })
        }
    }
}

/// A microfacet `distribution` (Mitsuba's default: Beckmann).
fn distribution(p: &Props) -> Result<MicrofacetKind, MitsubaError> {
    Ok(
        match p.choice("distribution", "beckmann", &["beckmann", "ggx"])? {
            "ggx" => MicrofacetKind::Ggx,
            _ => MicrofacetKind::Beckmann,
        },
    )
}

/// Textures of scalar parameters met while reading a BSDF: the
/// parameter's name and the texture object.
type ScalarTextures = Vec<(&'static str, Arc<Object>)>;

/// A scalar parameter that Mitsuba lets be a texture (its `eval_1`): a
/// float, or a grey colour; `default` if not given. A texture is kept in
/// `textures` for the caller (which varies the parameter by it), and
/// `default` stands for it here.
fn scalar(
    p: &Props,
    name: &'static str,
    default: f32,
    textures: &mut ScalarTextures,
) -> Result<f32, MitsubaError> {
    match p.color_opt(name, Role::Unbounded)? {
        None => Ok(default),
        Some(ColorProp::Value(c)) if c.x == c.y && c.y == c.z => Ok(c.x),
        Some(ColorProp::Value(_)) => Err(p.error(format!(
            "'{name}' is a scalar: give a <float> (raylab does not take a coloured one)"
        ))),
        Some(ColorProp::Texture(t)) => {
            textures.push((name, t));
            Ok(default)
        }
    }
}

/// Mitsuba's `principled`, all constants but `base_color` (whose texture
/// the caller keeps as the reflectance).
fn principled(
    p: &Props,
    base_color: Vec3A,
    t: &mut ScalarTextures,
) -> Result<Principled, MitsubaError> {
    let mut m = Principled {
        base_color,
        roughness: scalar(p, "roughness", 0.5, t)?,
        anisotropic: scalar(p, "anisotropic", 0.0, t)?,
        metallic: scalar(p, "metallic", 0.0, t)?,
        spec_trans: scalar(p, "spec_trans", 0.0, t)?,
        spec_tint: scalar(p, "spec_tint", 0.0, t)?,
        sheen: scalar(p, "sheen", 0.0, t)?,
        sheen_tint: scalar(p, "sheen_tint", 0.0, t)?,
        flatness: scalar(p, "flatness", 0.0, t)?,
        clearcoat: scalar(p, "clearcoat", 0.0, t)?,
        clearcoat_gloss: scalar(p, "clearcoat_gloss", 0.0, t)?,
        main_specular_sampling_rate: p.float("main_specular_sampling_rate", 1.0)?,
        clearcoat_sampling_rate: p.float("clearcoat_sampling_rate", 1.0)?,
        diffuse_reflectance_sampling_rate: p.float("diffuse_reflectance_sampling_rate", 1.0)?,
        ..Principled::default()
    };
    // Mitsuba keeps the index away from 1 (no refraction) when the
    // transmission lobe is on: `spec_trans` given and not the float 0 (a
    // texture turns it on whatever its values).
    let transmits = m.spec_trans != 0.0 || t.iter().any(|(n, _)| *n == "spec_trans");
    if p.has("eta") && p.has("specular") {
        return Err(p.error("give either eta or specular, not both"));
    }
    m.eta = if p.has("eta") {
        let eta = p.float("eta", 1.5)?;
        if transmits && eta == 1.0 { 1.001 } else { eta }
    } else {
        let specular = p.float("specular", 0.5)?;
        let specular = if transmits && specular == 0.0 {
            1e-3
        } else {
            specular
        };
        Principled::eta_of_specular(specular)
    };
    if !(m.eta.is_finite() && m.eta > 0.0) {
        return Err(p.error("the index of refraction (eta, or from specular) must be positive"));
    }
    Ok(m)
}

/// Mitsuba's `principledthin`, all constants but `base_color`.
fn principled_thin(
    p: &Props,
    base_color: Vec3A,
    t: &mut ScalarTextures,
) -> Result<PrincipledThin, MitsubaError> {
    let m = PrincipledThin {
        base_color,
        roughness: scalar(p, "roughness", 0.5, t)?,
        anisotropic: scalar(p, "anisotropic", 0.0, t)?,
        spec_trans: scalar(p, "spec_trans", 0.0, t)?,
        eta: scalar(p, "eta", 1.5, t)?,
        spec_tint: scalar(p, "spec_tint", 0.0, t)?,
        sheen: scalar(p, "sheen", 0.0, t)?,
        sheen_tint: scalar(p, "sheen_tint", 0.0, t)?,
        flatness: scalar(p, "flatness", 0.0, t)?,
        diff_trans: scalar(p, "diff_trans", 0.0, t)?,
        specular_reflectance_sampling_rate: p.float("specular_reflectance_sampling_rate", 1.0)?,
        specular_transmittance_sampling_rate: p
            .float("specular_transmittance_sampling_rate", 1.0)?,
        diffuse_reflectance_sampling_rate: p.float("diffuse_reflectance_sampling_rate", 1.0)?,
        diffuse_transmittance_sampling_rate: p.float("diffuse_transmittance_sampling_rate", 1.0)?,
        ..PrincipledThin::default()
    };
    if !(m.eta.is_finite() && m.eta > 0.0) {
        return Err(p.error("eta must be positive"));
    }
    Ok(m)
}

/// A conductor's complex index: `eta` and `k`, or a `material` preset
/// (Mitsuba's default `none`: a perfect mirror, η = 0, k = 1).
fn conductor_ior(p: &Props) -> Result<(Vec3A, Vec3A), MitsubaError> {
    let given = p.has("eta") || p.has("k");
    let material = p.string_opt("material")?;
    if given && material.is_some() {
        return Err(p.error("give either a material or eta and k"));
    }
    if given {
        let eta = p.constant_color("eta", Role::Unbounded, Vec3A::ZERO)?;
        let k = p.constant_color("k", Role::Unbounded, Vec3A::ONE)?;
        return Ok((eta, k));
    }
    match material.unwrap_or("none") {
        "none" => Ok((Vec3A::ZERO, Vec3A::ONE)),
        name => super::conductors::preset(name)
            .map(|(eta, k)| (Vec3A::from(eta), Vec3A::from(k)))
            .ok_or_else(|| {
                p.error(format!(
                    "unknown conductor '{}' (Mitsuba's names: {})",
                    crate::guard::quote(name),
                    super::conductors::names().join(", ")
                ))
            }),
    }
}

/// Mitsuba's `to_uv` (a 4 × 4 transform) as the 2-D affine map its
/// textures apply: the x and y rows and columns and the translation.
fn to_uv(m: Mat4) -> Affine2 {
    Affine2 {
        matrix2: Mat2::from_cols(
            m.x_axis.truncate().truncate(),
            m.y_axis.truncate().truncate(),
        ),
        translation: m.w_axis.truncate().truncate(),
    }
}

/// Whether `path` names an OpenEXR file (by its extension, as Mitsuba
/// picks the format).
fn is_exr(path: &std::path::Path) -> bool {
    path.extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("exr"))
}

/// Constant microfacet widths `(alpha_u, alpha_v)` and the textures that
/// vary them.
type Widths = ((f32, f32), Vec<(Param, Pattern)>);

/// Builds materials and their textures, each object once.
pub(super) struct Materials<'l> {
    /// The images the patterns read.
    pub textures: TextureStore,
    images: HashMap<(PathBuf, bool), u32>,
    ledger: &'l Ledger,
    scene: String,
    /// What was approximated.
    pub warnings: Vec<String>,
    /// The mesh attribute (`vertex_…` or `face_…`) the last material built
    /// reads, if any: its shapes hold it as their colours.
    pub attribute: Option<String>,
}

impl<'l> Materials<'l> {
    /// No materials yet.
    pub fn new(ledger: &'l Ledger, scene: String) -> Self {
        Self {
            textures: TextureStore::new(),
            images: HashMap::new(),
            ledger,
            scene,
            warnings: Vec::new(),
            attribute: None,
        }
    }

    /// The memory budget textures and meshes are charged to.
    pub fn ledger(&self) -> &'l Ledger {
        self.ledger
    }

    /// The image at `path` (decoded once).
    fn image(&mut self, path: PathBuf, t: &Props) -> Result<u32, MitsubaError> {
        if let Some(&id) = self.images.get(&(path.clone(), false)) {
            return Ok(id);
        }
        let bytes = std::fs::read(&path).map_err(|cause| MitsubaError::Io {
            path: path.clone(),
            cause,
        })?;
        if is_exr(&path) {
            // Linear floats, read as they are (Mitsuba's `raw` changes nothing).
            let image = Image::decode_exr(
                &bytes,
                &path.display().to_string(),
                self.ledger,
                &self.scene,
            )
            .map_err(|e| t.error(e.to_string()))?;
            let id = self.textures.push(image);
            self.images.insert((path, false), id);
            return Ok(id);
        }
        let store = TextureStore::decode_all_within(
            vec![(path.display().to_string(), bytes)],
            self.ledger,
            &self.scene,
        )
        .map_err(|e| t.error(format!("{}: {e}", path.display())))?;
        let id = self.textures.append(store);
        self.images.insert((path, false), id);
        Ok(id)
    }

    /// A texture object as a [`Pattern`].
    pub fn pattern(
        &mut self,
        tex: &Object,
        resolve: &dyn Fn(&str) -> Option<PathBuf>,
    ) -> Result<Pattern, MitsubaError> {
        let t = Props::new(tex);
        let pattern = match (tex.tag, tex.plugin.as_str()) {
            (Tag::Texture, "bitmap") => {
                let name = t
                    .string_opt("filename")?
                    .ok_or_else(|| t.error("needs a 'filename'"))?;
                let path = resolve(name).ok_or_else(|| {
                    t.error(format!("cannot find '{}'", crate::guard::quote(name)))
                })?;
                let nearest =
                    t.choice("filter_type", "bilinear", &["bilinear", "nearest"])? == "nearest";
                let wrap = match t.choice("wrap_mode", "repeat", &["repeat", "mirror", "clamp"])? {
                    "mirror" => Wrap::MirroredRepeat,
                    "clamp" => Wrap::ClampToEdge,
                    _ => Wrap::Repeat,
                };
                let raw = t.boolean("raw", false)?;
                let to_uv = to_uv(t.transform("to_uv")?);
                t.ignore(&["format", "accel"]);
                let image = self.image(path, &t)?;
                Pattern::Image {
                    image,
                    wrap,
                    nearest,
                    space: if raw {
                        ColorSpace::Linear
                    } else {
                        ColorSpace::Srgb
                    },
                    to_uv,
                }
            }
            (Tag::Texture, "mesh_attribute") => {
                let name = t
                    .string_opt("name")?
                    .ok_or_else(|| t.error("needs a 'name' (vertex_… or face_…)"))?;
                if !(name.starts_with("vertex_") || name.starts_with("face_")) {
                    return Err(t.error(format!(
                        "attribute '{}' must be named vertex_… or face_…",
                        crate::guard::quote(name)
                    )));
                }
                match &self.attribute {
                    Some(other) if other != name => {
                        return Err(t.error(format!(
                            "a material reads one mesh attribute; it reads '{}' and '{}'",
                            crate::guard::quote(other),
                            crate::guard::quote(name)
                        )));
                    }
                    _ => self.attribute = Some(name.to_string()),
                }
                t.ignore(&["scale"]);
                Pattern::MeshAttribute
            }
            (Tag::Texture, "checkerboard") => {
                let c0 = t.constant_color("color0", Role::Reflectance, Vec3A::splat(0.4))?;
                let c1 = t.constant_color("color1", Role::Reflectance, Vec3A::splat(0.2))?;
                Pattern::Checkerboard {
                    color0: c0.extend(1.0),
                    color1: c1.extend(1.0),
                    to_uv: to_uv(t.transform("to_uv")?),
                }
            }
            (Tag::Texture, "rawconstant") => {
                // A float or a 3-D vector (Mitsuba's default: 1).
                let v = match t.vector_opt("value")? {
                    Some(v) => v,
                    None => glam::Vec3::splat(t.float("value", 1.0)?),
                };
                Pattern::Constant(v.extend(1.0))
            }
            _ => {
                return Err(t.error(
                    "this texture is not supported yet (bitmap, checkerboard, mesh_attribute and rawconstant are)",
                ));
            }
        };
        t.finish()?;
        Ok(pattern)
    }

    /// The mean of a pattern's values (channels and texels), as Mitsuba's
    /// `Texture::mean` weighs plastic's lobes.
    fn mean(&self, pattern: &Pattern) -> f32 {
        match *pattern {
            Pattern::Image { image, space, .. } => {
                let m = self.textures.get(image).average(space);
                (m.x + m.y + m.z) / 3.0
            }
            Pattern::Checkerboard { color0, color1, .. } => {
                ((color0 + color1) * 0.5).truncate().element_sum() / 3.0
            }
            // (Mitsuba's mean of a mesh attribute is its values' mean; the
            // mesh is not known here: the middle of the range.)
            Pattern::MeshAttribute => 0.5,
            Pattern::Constant(c) => c.truncate().element_sum() / 3.0,
        }
    }

    /// A colour-or-texture property as a constant or a pattern.
    fn color(
        &mut self,
        p: &Props,
        name: &str,
        default: Vec3A,
        resolve: &dyn Fn(&str) -> Option<PathBuf>,
    ) -> Result<(Vec3A, Option<Pattern>), MitsubaError> {
        match p.color_opt(name, Role::Reflectance)? {
            None => Ok((default, None)),
            Some(ColorProp::Value(c)) => Ok((c, None)),
            Some(ColorProp::Texture(t)) => {
                let pattern = self.pattern(&t, resolve)?;
                // flat and direct show the texture's mean: take the centre's.
                Ok((Vec3A::splat(0.5), Some(pattern)))
            }
        }
    }

    /// `alpha`, or `alpha_u` and `alpha_v` (Mitsuba's default 0.1): the
    /// constant widths, and the textures that vary them (a textured width's
    /// constant is its texture's mean, for what shows a material's mean).
    fn alphas(
        &mut self,
        p: &Props,
        resolve: &dyn Fn(&str) -> Option<PathBuf>,
    ) -> Result<Widths, MitsubaError> {
        let mut params = Vec::new();
        let mut width = |name: &str, at: &[Param]| -> Result<Option<f32>, MitsubaError> {
            match p.color_opt(name, Role::Unbounded)? {
                None => Ok(None),
                Some(ColorProp::Value(c)) => match c.x.is_finite() && c.x >= 0.0 {
                    true => Ok(Some(c.x)),
                    false => Err(p.error(format!("'{name}' must be a non-negative number"))),
                },
                Some(ColorProp::Texture(t)) => {
                    let pattern = self.pattern(&t, resolve)?;
                    let mean = self.mean(&pattern);
                    params.extend(at.iter().map(|&a| (a, pattern)));
                    Ok(Some(mean))
                }
            }
        };
        if p.has("alpha") && (p.has("alpha_u") || p.has("alpha_v")) {
            return Err(p.error("give either alpha or alpha_u and alpha_v"));
        }
        if let Some(a) = width("alpha", &[Param::AlphaU, Param::AlphaV])? {
            return Ok(((a, a), params));
        }
        let u = width("alpha_u", &[Param::AlphaU])?;
        let v = width("alpha_v", &[Param::AlphaV])?;
        match (u, v) {
            (None, None) => Ok(((0.1, 0.1), params)),
            (Some(u), Some(v)) => Ok(((u, v), params)),
            _ => Err(p.error("alpha_u and alpha_v go together")),
        }
    }

    /// A `blendbsdf`'s `weight` (Mitsuba's default 0.5): the constant (a
    /// colour read as Mitsuba's `eval_1` reads it, its luminance), and the
    /// pattern of a texture, whose mean then stands for it.
    fn weight(
        &mut self,
        p: &Props,
        resolve: &dyn Fn(&str) -> Option<PathBuf>,
    ) -> Result<(f32, Option<Pattern>), MitsubaError> {
        match p.color_opt("weight", Role::Unbounded)? {
            None => Ok((0.5, None)),
            Some(ColorProp::Value(c)) => Ok((mitsuba_luminance(c.into()), None)),
            Some(ColorProp::Texture(t)) => {
                let pattern = self.pattern(&t, resolve)?;
                Ok((self.mean(&pattern), Some(pattern)))
            }
        }
    }

    /// One of a general `blendbsdf`'s two BSDFs: its textured BSDF (a
    /// Mitsuba BSDF a [`Blend`] can hold, with its own textures) and its
    /// reflectance for `flat` and `direct`.
    fn blend_part(
        &mut self,
        o: &Arc<Object>,
        resolve: &dyn Fn(&str) -> Option<PathBuf>,
    ) -> Result<(TexturedBsdf, Vec3A), MitsubaError> {
        let q = Props::new(o);
        if let "blendbsdf" | "twosided" | "mask" | "normalmap" | "bumpmap" | "null" =
            o.plugin.as_str()
        {
            return Err(q.error(format!(
                "raylab's blendbsdf blends two plain BSDFs (diffuse, conductor, dielectric, plastic, principled and their variants); a '{}' inside a blend is not supported yet",
                o.plugin
            )));
        }
        let m = self.material(o, resolve)?;
        match m.kind {
            MaterialKind::Textured(t) if t.bsdf.blend_part().is_some() => Ok((*t, m.reflectance)),
            _ => Err(q.error("this BSDF cannot be blended yet")),
        }
    }

    /// A `<bsdf>` as a material (no emission yet).
    pub fn material(
        &mut self,
        bsdf: &Arc<Object>,
        resolve: &dyn Fn(&str) -> Option<PathBuf>,
    ) -> Result<SurfaceMaterial, MitsubaError> {
        let p = Props::new(bsdf);
        let mut textured = TexturedBsdf::new(Material::Diffuse {
            reflectance: Vec3A::splat(0.5),
        });
        let rho;
        match bsdf.plugin.as_str() {
            "diffuse" => {
                let (c, pattern) = self.color(&p, "reflectance", Vec3A::splat(0.5), resolve)?;
                rho = c;
                textured.bsdf = Material::Diffuse { reflectance: c };
                textured.reflectance = pattern;
            }
            "blendbsdf" => {
                let inner = p.children_of(Tag::Bsdf);
                let [a, b] = inner.as_slice() else {
                    return Err(p.error("needs exactly two nested BSDFs"));
                };
                // Two constant Lambertian BSDFs blend into one, exactly.
                let lambertian =
                    |o: &Arc<Object>| o.plugin == "diffuse" && o.child("reflectance").is_none();
                if !(lambertian(a) && lambertian(b)) {
                    let (weight, pattern) = self.weight(&p, resolve)?;
                    let (t0, rho0) = self.blend_part(a, resolve)?;
                    let (t1, rho1) = self.blend_part(b, resolve)?;
                    let part = |t: &TexturedBsdf| t.bsdf.blend_part().expect("checked");
                    let blend = Blend::new(weight, part(&t0), part(&t1));
                    textured.bsdf = Material::MiBlend(blend);
                    rho = rho0 * (1.0 - blend.weight) + rho1 * blend.weight;
                    textured
                        .params
                        .extend(pattern.map(|pat| (Param::Weight, pat)));
                    let textured_part =
                        |t: &TexturedBsdf| t.reflectance.is_some() || !t.params.is_empty();
                    if textured_part(&t0) || textured_part(&t1) {
                        textured.parts = Some(Box::new([t0, t1]));
                    }
                } else {
                    let rho = |o: &Arc<Object>| -> Result<Vec3A, MitsubaError> {
                        let q = Props::new(o);
                        let c =
                            q.constant_color("reflectance", Role::Reflectance, Vec3A::splat(0.5))?;
                        q.finish()?;
                        Ok(c)
                    };
                    let (r0, r1) = (rho(a)?, rho(b)?);
                    let (w, pattern) = self.color(&p, "weight", Vec3A::splat(0.5), resolve)?;
                    let mixed = r0 * (1.0 - w.x) + r1 * w.x;
                    textured.bsdf = Material::Diffuse { reflectance: mixed };
                    if pattern.is_some() {
                        textured.reflectance = pattern;
                        textured.blend = Some([r0, r1]);
                    }
                    p.finish()?;
                    let mut m = SurfaceMaterial::fixed(mixed, textured.bsdf);
                    m.name = bsdf.id.clone().unwrap_or_default();
                    m.kind = MaterialKind::Textured(Box::new(textured));
                    return Ok(m);
                }
            }
            "twosided" => {
                let inner = p.children_of(Tag::Bsdf);
                let [one] = inner.as_slice() else {
                    return Err(p.error(
                        "raylab's twosided takes one BSDF (the same on both sides); different front and back BSDFs are not supported yet",
                    ));
                };
                let mut m = self.material(one, resolve)?;
                if let MaterialKind::Textured(t) = &mut m.kind {
                    t.two_sided = true;
                }
                p.finish()?;
                return Ok(m);
            }
            "normalmap" | "bumpmap" => {
                let inner = p.children_of(Tag::Bsdf);
                let [one] = inner.as_slice() else {
                    return Err(p.error("needs exactly one nested BSDF"));
                };
                let map = if bsdf.plugin == "normalmap" {
                    let t = p
                        .child_opt("normalmap")
                        .ok_or_else(|| p.error("needs a 'normalmap' texture"))?;
                    PerturbMap::NormalMap(self.pattern(&t, resolve)?)
                } else {
                    // Mitsuba takes the one nested texture, whatever its name.
                    let textures = p.children_of(Tag::Texture);
                    let [t] = textures.as_slice() else {
                        return Err(p.error("needs exactly one nested texture (the height)"));
                    };
                    PerturbMap::BumpMap {
                        height: self.pattern(t, resolve)?,
                        scale: p.float("scale", 1.0)?,
                    }
                };
                let perturb = Perturb {
                    map,
                    flip_invalid: p.boolean("flip_invalid_normals", true)?,
                    shadowing: p.boolean("use_shadowing_function", true)?,
                };
                let mut m = self.material(one, resolve)?;
                match &mut m.kind {
                    MaterialKind::Textured(t) if t.perturb.is_none() => t.perturb = Some(perturb),
                    _ => {
                        return Err(p.error(
                            "a normal or bump map of a normal- or bump-mapped BSDF is not supported yet",
                        ));
                    }
                }
                p.finish()?;
                return Ok(m);
            }
            "mask" => {
                let inner = p.children_of(Tag::Bsdf);
                let [one] = inner.as_slice() else {
                    return Err(p.error("needs exactly one nested BSDF"));
                };
                let mut m = self.material(one, resolve)?;
                let opacity = match p.color_opt("opacity", Role::Reflectance)? {
                    None => Pattern::Checkerboard {
                        color0: Vec4::splat(0.5),
                        color1: Vec4::splat(0.5),
                        to_uv: Affine2::IDENTITY,
                    },
                    Some(ColorProp::Value(c)) => Pattern::Checkerboard {
                        color0: c.extend(1.0),
                        color1: c.extend(1.0),
                        to_uv: Affine2::IDENTITY,
                    },
                    Some(ColorProp::Texture(t)) => self.pattern(&t, resolve)?,
                };
                if let MaterialKind::Textured(t) = &mut m.kind {
                    t.opacity = Some(opacity);
                } else {
                    return Err(p.error("the nested BSDF cannot be masked"));
                }
                m.alpha = AlphaMode::Blend;
                p.finish()?;
                return Ok(m);
            }
            "conductor" | "roughconductor" => {
                let specular =
                    p.constant_color("specular_reflectance", Role::Reflectance, Vec3A::ONE)?;
                let (eta, k) = conductor_ior(&p)?;
                textured.bsdf = if bsdf.plugin == "conductor" {
                    Material::MiConductor(Conductor::new(eta, k, specular))
                } else {
                    let kind = distribution(&p)?;
                    let ((au, av), params) = self.alphas(&p, resolve)?;
                    textured.params = params;
                    Material::MiRoughConductor(RoughConductor::new(kind, au, av, eta, k, specular))
                };
                p.ignore(&["sample_visible"]);
                rho = specular;
            }
            "dielectric" | "thindielectric" | "roughdielectric" => {
                let int = ior(&p, "int_ior", 1.5046)?;
                let ext = ior(&p, "ext_ior", 1.000277)?;
                if !(int > 0.0 && ext > 0.0) {
                    return Err(p.error("indices of refraction must be positive"));
                }
                let r = p.constant_color("specular_reflectance", Role::Reflectance, Vec3A::ONE)?;
                let t =
                    p.constant_color("specular_transmittance", Role::Reflectance, Vec3A::ONE)?;
                let eta = int / ext;
                textured.bsdf = match bsdf.plugin.as_str() {
                    "dielectric" => Material::MiDielectric(SmoothDielectric::new(eta, r, t)),
                    "thindielectric" => Material::MiThinDielectric(ThinDielectric::new(eta, r, t)),
                    _ => {
                        let kind = distribution(&p)?;
                        let ((au, av), params) = self.alphas(&p, resolve)?;
                        textured.params = params;
                        p.ignore(&["sample_visible"]);
                        Material::MiRoughDielectric(RoughDielectric::new(kind, au, av, eta, r, t))
                    }
                };
                rho = Vec3A::ONE;
            }
            "plastic" | "roughplastic" => {
                let int = ior(&p, "int_ior", 1.49)?;
                let ext = ior(&p, "ext_ior", 1.000277)?;
                if !(int > 0.0 && ext > 0.0) {
                    return Err(p.error("indices of refraction must be positive"));
                }
                let (diffuse, pattern) =
                    self.color(&p, "diffuse_reflectance", Vec3A::splat(0.5), resolve)?;
                let specular =
                    p.constant_color("specular_reflectance", Role::Reflectance, Vec3A::ONE)?;
                let nonlinear = p.boolean("nonlinear", false)?;
                let eta = int / ext;
                // Mitsuba weighs its lobes by the reflectances' means (a
                // texture's mean over its texels).
                let diffuse_mean = match &pattern {
                    Some(pat) => self.mean(pat),
                    None => (diffuse.x + diffuse.y + diffuse.z) / 3.0,
                };
                let weight = crate::materials::mitsuba::specular_sampling_weight(
                    diffuse_mean,
                    (specular.x + specular.y + specular.z) / 3.0,
                );
                textured.bsdf = if bsdf.plugin == "plastic" {
                    let mut m = Plastic::new(eta, diffuse, specular, nonlinear);
                    m.specular_sampling_weight = weight;
                    Material::MiPlastic(m)
                } else {
                    let kind = distribution(&p)?;
                    let alpha = p.float("alpha", 0.1)?;
                    if !(alpha.is_finite() && alpha >= 0.0) {
                        return Err(p.error("alpha must be a non-negative number"));
                    }
                    p.ignore(&["sample_visible"]);
                    let mut m = RoughPlastic::new(kind, alpha, eta, diffuse, specular, nonlinear);
                    m.specular_sampling_weight = weight;
                    Material::MiRoughPlastic(m)
                };
                textured.reflectance = pattern;
                rho = diffuse;
            }
            "principled" | "principledthin" => {
                let (base, pattern) = self.color(&p, "base_color", Vec3A::splat(0.5), resolve)?;
                let mut scalars = ScalarTextures::new();
                textured.bsdf = if bsdf.plugin == "principled" {
                    Material::MiPrincipled(principled(&p, base, &mut scalars)?)
                } else {
                    Material::MiPrincipledThin(principled_thin(&p, base, &mut scalars)?)
                };
                for (name, object) in scalars {
                    let param = PrincipledParam::ALL
                        .into_iter()
                        .find(|q| q.name() == name)
                        .ok_or_else(|| p.error(format!("'{name}' cannot be textured")))?;
                    let pattern = self.pattern(&object, resolve)?;
                    // The texture's mean stands for it where one value does.
                    let mean = self.mean(&pattern);
                    textured.bsdf.set_param(Param::Principled(param), mean);
                    textured.params.push((Param::Principled(param), pattern));
                }
                textured.reflectance = pattern;
                rho = base;
            }
            "null" => {
                textured.bsdf = Material::Dielectric { ior: 1.0 };
                rho = Vec3A::ZERO;
            }
            other => {
                return Err(p.error(format!(
                    "the BSDF '{}' is not supported yet (see docs/mitsuba-scenes.md)",
                    crate::guard::quote(other)
                )));
            }
        }
        p.finish()?;
        // Textured even where nothing varies: the kind carries the sides.
        let mut m = SurfaceMaterial::fixed(rho, textured.bsdf);
        m.name = bsdf.id.clone().unwrap_or_default();
        m.kind = MaterialKind::Textured(Box::new(textured));
        Ok(m)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::materials::mitsuba::PrincipledParam;

    /// The material of the `<bsdf>` in `body` (a scene's only child), or
    /// the one-line error.
    fn bsdf(body: &str) -> Result<Material, String> {
        super::blend_and_exr_tests::read(body).map(|(t, _)| t.bsdf)
    }

    #[test]
    fn principled_reads_every_parameter_with_mitsubas_defaults() {
        let Ok(Material::MiPrincipled(d)) = bsdf(r#"<bsdf type="principled"/>"#) else {
            panic!()
        };
        assert_eq!(d, Principled::default());
        assert!((d.eta - 1.5).abs() < 1e-6);
        let Ok(Material::MiPrincipled(m)) = bsdf(
            r#"<bsdf type="principled">
                <rgb name="base_color" value="0.8, 0.4, 0.2"/>
                <float name="roughness" value="0.3"/>
                <float name="anisotropic" value="0.5"/>
                <float name="metallic" value="0.2"/>
                <float name="spec_trans" value="0.4"/>
                <float name="eta" value="1.33"/>
                <float name="spec_tint" value="0.1"/>
                <float name="sheen" value="0.6"/>
                <float name="sheen_tint" value="0.7"/>
                <float name="flatness" value="0.8"/>
                <float name="clearcoat" value="0.9"/>
                <float name="clearcoat_gloss" value="0.35"/>
                <float name="main_specular_sampling_rate" value="0.5"/>
                <float name="clearcoat_sampling_rate" value="2"/>
                <float name="diffuse_reflectance_sampling_rate" value="0.7"/>
            </bsdf>"#,
        ) else {
            panic!()
        };
        let want = Principled {
            base_color: Vec3A::new(0.8, 0.4, 0.2),
            roughness: 0.3,
            anisotropic: 0.5,
            metallic: 0.2,
            spec_trans: 0.4,
            eta: 1.33,
            spec_tint: 0.1,
            sheen: 0.6,
            sheen_tint: 0.7,
            flatness: 0.8,
            clearcoat: 0.9,
            clearcoat_gloss: 0.35,
            main_specular_sampling_rate: 0.5,
            clearcoat_sampling_rate: 2.0,
            diffuse_reflectance_sampling_rate: 0.7,
            ..Principled::default()
        };
        assert_eq!(m, want);
        // specular sets eta; with transmission on, Mitsuba keeps the index
        // off 1 (specular 0 is 1e-3, eta 1 is 1.001).
        let eta = |body: &str| match bsdf(body) {
            Ok(Material::MiPrincipled(m)) => m.eta,
            other => panic!("{other:?}"),
        };
        let spec = r#"<bsdf type="principled"><float name="specular" value="0.7"/></bsdf>"#;
        assert_eq!(eta(spec), Principled::eta_of_specular(0.7));
        let zero = r#"<bsdf type="principled"><float name="specular" value="0"/></bsdf>"#;
        assert_eq!(eta(zero), 1.0);
        let zero_t = r#"<bsdf type="principled"><float name="specular" value="0"/><float name="spec_trans" value="0.5"/></bsdf>"#;
        assert_eq!(eta(zero_t), Principled::eta_of_specular(1e-3));
        let one_t = r#"<bsdf type="principled"><float name="eta" value="1"/><float name="spec_trans" value="0.5"/></bsdf>"#;
        assert_eq!(eta(one_t), 1.001);
    }

    #[test]
    fn principled_thin_reads_every_parameter_with_mitsubas_defaults() {
        let Ok(Material::MiPrincipledThin(d)) = bsdf(r#"<bsdf type="principledthin"/>"#) else {
            panic!()
        };
        assert_eq!(d, PrincipledThin::default());
        let Ok(Material::MiPrincipledThin(m)) = bsdf(
            r#"<bsdf type="principledthin">
                <rgb name="base_color" value="0.7, 0.1, 0.1"/>
                <float name="roughness" value="0.3"/>
                <float name="anisotropic" value="0.5"/>
                <float name="spec_trans" value="0.4"/>
                <float name="eta" value="1.33"/>
                <float name="spec_tint" value="0.1"/>
                <float name="sheen" value="0.6"/>
                <float name="sheen_tint" value="0.7"/>
                <float name="flatness" value="0.8"/>
                <float name="diff_trans" value="1.4"/>
                <float name="specular_reflectance_sampling_rate" value="0.5"/>
                <float name="specular_transmittance_sampling_rate" value="2"/>
                <float name="diffuse_reflectance_sampling_rate" value="0.7"/>
                <float name="diffuse_transmittance_sampling_rate" value="1.5"/>
            </bsdf>"#,
        ) else {
            panic!()
        };
        let mut want = PrincipledThin {
            base_color: Vec3A::new(0.7, 0.1, 0.1),
            specular_reflectance_sampling_rate: 0.5,
            specular_transmittance_sampling_rate: 2.0,
            diffuse_reflectance_sampling_rate: 0.7,
            diffuse_transmittance_sampling_rate: 1.5,
            ..PrincipledThin::default()
        };
        for (p, v) in [
            (PrincipledParam::Roughness, 0.3),
            (PrincipledParam::Anisotropic, 0.5),
            (PrincipledParam::SpecTrans, 0.4),
            (PrincipledParam::Eta, 1.33),
            (PrincipledParam::SpecTint, 0.1),
            (PrincipledParam::Sheen, 0.6),
            (PrincipledParam::SheenTint, 0.7),
            (PrincipledParam::Flatness, 0.8),
            (PrincipledParam::DiffTrans, 1.4),
        ] {
            assert!(want.set(p, v));
        }
        assert_eq!(m, want);
    }

    #[test]
    fn principled_refuses_what_it_cannot_take() {
        for (body, says) in [
            (
                r#"<bsdf type="principled"><float name="eta" value="1.5"/><float name="specular" value="0.5"/></bsdf>"#,
                "either eta or specular",
            ),
            (
                r#"<bsdf type="principled"><float name="diff_trans" value="1"/></bsdf>"#,
                "unused parameter 'diff_trans'",
            ),
            (
                r#"<bsdf type="principledthin"><float name="clearcoat" value="1"/></bsdf>"#,
                "unused parameter 'clearcoat'",
            ),
            (
                r#"<bsdf type="principled"><rgb name="roughness" value="0.1, 0.2, 0.3"/></bsdf>"#,
                "'roughness' is a scalar",
            ),
        ] {
            let e = bsdf(body).expect_err(body);
            assert!(e.contains(says), "{body}: {e}");
        }
        // A textured base colour is the reflectance a texture replaces.
        let m = bsdf(
            r#"<bsdf type="principled"><texture name="base_color" type="checkerboard"/></bsdf>"#,
        );
        assert!(matches!(m, Ok(Material::MiPrincipled(_))), "{m:?}");
        // Textured scalars vary per hit; the constant is the texture's mean,
        // and a textured spec_trans turns the transmission on (eta ≠ 1).
        let m = bsdf(
            r#"<bsdf type="principled"><float name="eta" value="1"/>
                <texture name="metallic" type="checkerboard"><float name="color0" value="0.2"/><float name="color1" value="0.6"/></texture>
                <texture name="spec_trans" type="checkerboard"/></bsdf>"#,
        );
        let Ok(Material::MiPrincipled(m)) = m else {
            panic!("{m:?}")
        };
        assert!((m.metallic - 0.4).abs() < 1e-6, "{}", m.metallic);
        assert_eq!(m.eta, 1.001);
        let m = bsdf(
            r#"<bsdf type="principledthin"><texture name="diff_trans" type="checkerboard"/></bsdf>"#,
        );
        assert!(matches!(m, Ok(Material::MiPrincipledThin(_))), "{m:?}");
    }
}

#[cfg(test)]
mod blend_and_exr_tests {
    use super::*;
    use glam::Vec2;
    use std::path::Path;

    /// The material of the `<bsdf>` in `body`, files found in
    /// `tests/data/mitsuba/suite/textures`, with the texture store.
    pub(super) fn read(body: &str) -> Result<(TexturedBsdf, TextureStore), String> {
        let text = format!("<scene version=\"3.0.0\">{body}</scene>");
        let tree = crate::load::mitsuba::read_str(&text, Path::new("/virtual/scene.xml"), &[])
            .map_err(|e| e.to_string())?;
        let ledger = Ledger::unlimited();
        let mut materials = Materials::new(&ledger, "test".into());
        let object = tree.root.children[0].object.clone();
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/mitsuba/suite/textures");
        let resolve = move |name: &str| Some(dir.join(name)).filter(|p| p.exists());
        let m = materials
            .material(&object, &resolve)
            .map_err(|e| e.to_string())?;
        match m.kind {
            MaterialKind::Textured(t) => Ok((*t, materials.textures)),
            _ => Err("not a textured material".into()),
        }
    }

    #[test]
    fn blendbsdf_blends_any_two_bsdfs() {
        let (t, _) = read(
            r#"<bsdf type="blendbsdf"><float name="weight" value="0.25"/>
                <bsdf type="diffuse"><rgb name="reflectance" value="0.2, 0.4, 0.6"/></bsdf>
                <bsdf type="roughconductor"><float name="alpha" value="0.3"/></bsdf></bsdf>"#,
        )
        .unwrap();
        let Material::MiBlend(b) = t.bsdf else {
            panic!("{:?}", t.bsdf)
        };
        assert_eq!(b.weight, 0.25);
        assert_eq!(
            b.parts[0],
            crate::materials::BlendPart::Diffuse(Vec3A::new(0.2, 0.4, 0.6))
        );
        assert!(matches!(
            b.parts[1],
            crate::materials::BlendPart::RoughConductor(_)
        ));
        assert!(t.params.is_empty() && t.parts.is_none());
        // A textured weight is a parameter; textured parts keep their
        // textures (a checkerboard reflectance, a textured alpha).
        let (t, _) = read(
            r#"<bsdf type="blendbsdf">
                <texture name="weight" type="checkerboard"/>
                <bsdf type="diffuse"><texture name="reflectance" type="checkerboard"/></bsdf>
                <bsdf type="roughconductor"><texture name="alpha" type="checkerboard"/></bsdf></bsdf>"#,
        )
        .unwrap();
        assert_eq!(t.params.len(), 1);
        assert_eq!(t.params[0].0, Param::Weight);
        let parts = t.parts.expect("textured parts");
        assert!(parts[0].reflectance.is_some() && parts[1].params.len() == 2);
        // Two constant Lambertian BSDFs stay one exact Lambertian BSDF.
        let (t, _) =
            read(r#"<bsdf type="blendbsdf"><bsdf type="diffuse"/><bsdf type="diffuse"/></bsdf>"#)
                .unwrap();
        assert!(matches!(t.bsdf, Material::Diffuse { .. }), "{:?}", t.bsdf);
    }

    #[test]
    fn blendbsdf_refuses_what_it_cannot_hold_in_one_line() {
        for (body, says) in [
            (
                r#"<bsdf type="blendbsdf"><bsdf type="diffuse"/></bsdf>"#,
                "exactly two nested BSDFs",
            ),
            (
                r#"<bsdf type="blendbsdf"><bsdf type="diffuse"/><bsdf type="blendbsdf"><bsdf type="diffuse"/><bsdf type="conductor"/></bsdf></bsdf>"#,
                "a 'blendbsdf' inside a blend is not supported yet",
            ),
            (
                r#"<bsdf type="blendbsdf"><bsdf type="conductor"/><bsdf type="twosided"><bsdf type="diffuse"/></bsdf></bsdf>"#,
                "a 'twosided' inside a blend",
            ),
            (
                r#"<bsdf type="blendbsdf"><float name="weight" value="0.5"/><float name="wieght" value="0.5"/><bsdf type="conductor"/><bsdf type="diffuse"/></bsdf>"#,
                "wieght",
            ),
        ] {
            let e = read(body).map(|_| ()).expect_err(body);
            assert!(e.contains(says) && !e.contains('\n'), "{body}: {e}");
            assert!(e.contains("scene.xml:"), "{e}");
        }
    }

    #[test]
    fn exr_bitmaps_are_linear_floats_rgb_or_luminance() {
        // weight.exr: one float channel Y, texel (i, j) = 0.5 + 0.45
        // sin(2π i / 16) cos(2π j / 21); albedo.exr: RGB halves.
        let (t, store) = read(
            r#"<bsdf type="diffuse"><texture name="reflectance" type="bitmap">
                <string name="filename" value="weight.exr"/>
                <string name="filter_type" value="nearest"/></texture></bsdf>"#,
        )
        .unwrap();
        let p = t.reflectance.expect("a pattern");
        let image = store.get(p.image().unwrap());
        assert_eq!(
            (image.width(), image.height(), image.channels()),
            (32, 32, 1)
        );
        assert_eq!(image.bits_per_channel(), 32);
        let at = |i: f32, j: f32| Vec2::new((i + 0.5) / 32.0, (j + 0.5) / 32.0);
        let want = |i: f32, j: f32| {
            use std::f32::consts::TAU;
            0.5 + 0.45 * (i * TAU / 16.0).sin() * (j * TAU / 21.0).cos()
        };
        for (i, j) in [(0.0, 0.0), (4.0, 0.0), (3.0, 7.0)] {
            let v = p.eval(at(i, j), Vec4::ONE, &store);
            assert!((v.x - want(i, j)).abs() < 1e-6 && v.x == v.y && v.y == v.z);
            // As a number (eval_1), a grey value is itself.
            assert!((p.eval_1(at(i, j), Vec4::ONE, &store) - v.x).abs() < 1e-6);
        }
        // raw changes nothing; RGB channels are read as they are.
        let (t, store) = read(
            r#"<bsdf type="diffuse"><texture name="reflectance" type="bitmap">
                <string name="filename" value="albedo.exr"/><boolean name="raw" value="true"/>
                <string name="filter_type" value="nearest"/></texture></bsdf>"#,
        )
        .unwrap();
        let p = t.reflectance.unwrap();
        assert_eq!(store.get(p.image().unwrap()).channels(), 3);
        let v = p.eval(Vec2::new(0.5 / 16.0, 0.5 / 16.0), Vec4::ONE, &store);
        // Texel (0, 0): R 0.15, G 0.7, B 0.8, as halves.
        for (got, want) in [(v.x, 0.15f32), (v.y, 0.7), (v.z, 0.8)] {
            assert!((got - want).abs() < 1e-3, "{v}");
        }
    }

    #[test]
    fn a_bad_exr_is_one_line_naming_it() {
        let dir = std::env::temp_dir().join(format!("raylab-exr-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let bad = dir.join("bad.exr");
        std::fs::write(&bad, b"not an OpenEXR file at all").unwrap();
        let text = format!(
            r#"<scene version="3.0.0"><bsdf type="diffuse"><texture name="reflectance" type="bitmap"><string name="filename" value="{}"/></texture></bsdf></scene>"#,
            bad.display()
        );
        let tree =
            crate::load::mitsuba::read_str(&text, Path::new("/virtual/scene.xml"), &[]).unwrap();
        let ledger = Ledger::unlimited();
        let mut materials = Materials::new(&ledger, "test".into());
        let object = tree.root.children[0].object.clone();
        let resolve = |name: &str| Some(PathBuf::from(name));
        let e = materials
            .material(&object, &resolve)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("bad.exr") && e.contains("OpenEXR") && !e.contains('\n'),
            "{e}"
        );
        std::fs::remove_dir_all(&dir).ok();
    }
}
