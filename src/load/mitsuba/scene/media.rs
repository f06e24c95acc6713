//! Mitsuba's participating media (3.7.1's definitions): `homogeneous`
//! (`sigma_t`, `albedo`, `scale`, a `phase`), the phase functions
//! `isotropic` and `hg`, and which integrators render them (`volpath`,
//! `volpathmis`; Mitsuba's `path` ignores media).

use std::sync::Arc;

use glam::{Affine3A, Mat4, Vec3A};

use super::super::error::MitsubaError;
use super::super::tree::{Object, SceneTree, Tag};
use super::color::Role;
use super::props::{ColorProp, Props};
use crate::media::{Field, FieldValues, Grid, Heterogeneous, Medium, Phase, phase::MAX_G};
use crate::memory::Ledger;

/// A `<medium>` as raylab's [`Medium`]; files are found through `tree`
/// and checked against `ledger`.
pub(super) fn medium(
    o: &Object,
    tree: &SceneTree,
    ledger: &Ledger,
) -> Result<Medium, MitsubaError> {
    let p = Props::new(o);
    match o.plugin.as_str() {
        "homogeneous" => {
            let scale = p.float("scale", 1.0)?;
            if !(scale.is_finite() && scale >= 0.0) {
                return Err(p.error_at("scale", "must be finite and >= 0"));
            }
            let sigma_t = p.constant_color("sigma_t", Role::Unbounded, Vec3A::ONE)?;
            if !(sigma_t.is_finite() && sigma_t.min_element() >= 0.0) {
                return Err(p.error_at("sigma_t", "must be finite and >= 0"));
            }
            let albedo = p.constant_color("albedo", Role::Reflectance, Vec3A::splat(0.75))?;
            if !(albedo.is_finite() && albedo.min_element() >= 0.0 && albedo.max_element() <= 1.0) {
                return Err(p.error_at("albedo", "must lie in [0, 1]"));
            }
            let sample_emitters = p.boolean("sample_emitters", true)?;
            // (Spectral MIS is always on: the same expected image.)
            p.ignore(&["has_spectral_extinction"]);
            let phase = phase_of(&p)?;
            p.finish()?;
            let mut m = Medium::homogeneous(sigma_t * scale, albedo, phase);
            if let Medium::Homogeneous(h) = &mut m {
                h.sample_emitters = sample_emitters;
            }
            Ok(m)
        }
        "heterogeneous" => {
            let scale = p.float("scale", 1.0)?;
            if !(scale.is_finite() && scale >= 0.0) {
                return Err(p.error_at("scale", "must be finite and >= 0"));
            }
            let sigma_t = field(&p, "sigma_t", Role::Unbounded, 1.0, tree, ledger)?;
            let albedo = field(&p, "albedo", Role::Reflectance, 0.75, tree, ledger)?;
            if albedo.max() > 1.0 {
                return Err(p.error_at("albedo", "must lie in [0, 1]"));
            }
            let sample_emitters = p.boolean("sample_emitters", true)?;
            // (Spectral MIS is always on: the same expected image.)
            p.ignore(&["has_spectral_extinction"]);
            let phase = phase_of(&p)?;
            p.finish()?;
            Ok(Medium::Heterogeneous(Box::new(Heterogeneous {
                sigma_t,
                albedo,
                scale,
                phase,
                sample_emitters,
                emission: None,
            })))
        }
        other => Err(p.error(format!(
            "the medium '{}' is not supported (homogeneous is)",
            crate::guard::quote(other)
        ))),
    }
}

/// A medium's phase function (isotropic unless it holds one).
fn phase_of(p: &Props) -> Result<Phase, MitsubaError> {
    match p.children_of(Tag::Phase).as_slice() {
        [] => Ok(Phase::Isotropic),
        [one] => phase(one),
        _ => Err(p.error("a medium holds at most one phase function")),
    }
}

/// A heterogeneous medium's parameter `name`: a `<volume>` (`gridvolume`,
/// `constvolume`) or a constant, which is Mitsuba's `constvolume` over the
/// unit cube (its default `to_world`), as Mitsuba makes one of it.
fn field(
    p: &Props,
    name: &str,
    role: Role,
    default: f32,
    tree: &SceneTree,
    ledger: &Ledger,
) -> Result<Field, MitsubaError> {
    let child = p.child_opt(name);
    let Some(v) = child.filter(|c| c.tag == Tag::Volume) else {
        let value = match p.color_opt(name, role)? {
            None => Vec3A::splat(default),
            Some(ColorProp::Value(c)) => c,
            Some(ColorProp::Texture(t)) => {
                return Err(p.error_at(
                    name,
                    format!(
                        "{} is not a volume (gridvolume or constvolume)",
                        t.describe()
                    ),
                ));
            }
        };
        return Ok(Field::new(FieldValues::Constant(value), Affine3A::IDENTITY));
    };
    let q = Props::new(&v);
    let to_world = affine(q.transform("to_world")?)
        .ok_or_else(|| q.error_at("to_world", "must be an invertible affine map"))?;
    let field = match v.plugin.as_str() {
        "constvolume" => {
            let value = q.constant_color("value", role, Vec3A::ONE)?;
            Field::new(FieldValues::Constant(value), to_world)
        }
        "gridvolume" => {
            let file = q
                .string_opt("filename")?
                .ok_or_else(|| q.error("needs a 'filename' (a .vol file)"))?;
            let path = tree
                .resolve(file)
                .ok_or_else(|| q.error(format!("cannot find '{}'", crate::guard::quote(file))))?;
            if path
                .extension()
                .is_some_and(|e| e.eq_ignore_ascii_case("vdb"))
            {
                // raylab's extension: an OpenVDB file's float grid, placed by
                // its own transform and then `to_world`.
                let grid = q.string_opt("grid")?.map(str::to_owned);
                q.choice("filter_type", "trilinear", &["trilinear"])?;
                q.ignore(&["raw", "accel", "wrap_mode", "use_grid_bbox"]);
                let vdb = crate::load::vdb::read_vdb(&path, grid.as_deref(), ledger)
                    .map_err(|e| MitsubaError::mesh(&e.path, e.message))?;
                let field = Field::sparse(vdb.grid, to_world * vdb.index_to_world);
                q.finish()?;
                return Ok(field);
            }
            let vol = super::super::vol::read_vol(&path, ledger)?;
            let nearest =
                q.choice("filter_type", "trilinear", &["trilinear", "nearest"])? == "nearest";
            if q.choice("wrap_mode", "clamp", &["clamp", "repeat", "mirror"])? != "clamp" {
                return Err(q.error_at("wrap_mode", "only 'clamp' is supported yet"));
            }
            // (Raw or not matters only to Mitsuba's spectral variants.)
            q.ignore(&["raw", "accel"]);
            if q.has("max_value") {
                return Err(q.error_at(
                    "max_value",
                    "is not supported (raylab bounds the grid by its own largest value)",
                ));
            }
            let to_world = if q.boolean("use_grid_bbox", false)? {
                // The header's box, mapped to the unit cube first.
                let (lo, hi) = (
                    glam::Vec3::from(vol.bounds.0),
                    glam::Vec3::from(vol.bounds.1),
                );
                let size = hi - lo;
                if !(size.min_element() > 0.0 && size.is_finite() && lo.is_finite()) {
                    return Err(q.error_at("use_grid_bbox", "the file's bounding box is empty"));
                }
                to_world * Affine3A::from_scale_rotation_translation(size, glam::Quat::IDENTITY, lo)
            } else {
                to_world
            };
            let grid = Grid::new(vol.res, vol.channels, vol.values)
                .map_err(|e| MitsubaError::mesh(&path, e))?;
            Field::new(
                FieldValues::Grid {
                    grid: Arc::new(grid),
                    nearest,
                },
                to_world,
            )
        }
        other => {
            return Err(q.error(format!(
                "the volume '{}' is not supported (gridvolume and constvolume are)",
                crate::guard::quote(other)
            )));
        }
    };
    q.finish()?;
    Ok(field)
}

/// `m` as an affine map, if it is one and invertible.
fn affine(m: Mat4) -> Option<Affine3A> {
    // The same map the shapes get (`Affine3A::from_mat4`): its 3 × 3 part and translation.
    let a = Affine3A::from_mat4(m);
    (m.row(3) == glam::Vec4::W && a.matrix3.determinant().abs() > 0.0 && a.is_finite()).then_some(a)
}

/// A `<phase>`: `isotropic` or `hg` (`g`, default 0.8).
fn phase(o: &Object) -> Result<Phase, MitsubaError> {
    let p = Props::new(o);
    let phase = match o.plugin.as_str() {
        "isotropic" => Phase::Isotropic,
        "hg" => {
            let g = p.float("g", 0.8)?;
            if g.is_nan() || g.abs() > MAX_G {
                return Err(p.error_at("g", format!("must lie in [-{MAX_G}, {MAX_G}]")));
            }
            Phase::HenyeyGreenstein { g }
        }
        other => {
            return Err(p.error(format!(
                "the phase function '{}' is not supported (isotropic and hg are)",
                crate::guard::quote(other)
            )));
        }
    };
    p.finish()?;
    Ok(phase)
}

/// Whether the integrator (inside `moment` too) renders media: `volpath`
/// and `volpathmis` do; Mitsuba's other integrators ignore them.
pub(super) fn volumetric(integrator: &Object) -> bool {
    match integrator.plugin.as_str() {
        "volpath" | "volpathmis" => true,
        "moment" => integrator
            .children
            .iter()
            .any(|c| c.object.tag == Tag::Integrator && volumetric(&c.object)),
        _ => false,
    }
}
