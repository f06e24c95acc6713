//! The `[camera]` section resolved: a look-at camera or a model's own, with
//! its thin lens checked ([`ShotCamera`]).

use std::path::Path;

use super::error::{ShotError, check, invalid};
use super::schema::CameraSection;
use crate::camera::{
    Aperture, DepthOfField, Focus, Lens, MAX_LENS_LENGTH, SceneCamera, lens_length_is_valid,
};

/// The camera a scene file asks for, resolved.
#[derive(Clone, Debug, PartialEq)]
pub enum ShotCamera {
    /// Nothing given: the first camera of the models' files, else the built-in
    /// box's camera if the first model is a box, else framing.
    Default,
    /// A camera placed by the file (or taken from a model's file).
    Placed(SceneCamera),
}

/// The `[camera]` section resolved.
pub(super) fn camera(
    path: &Path,
    c: &CameraSection,
    model_cameras: &[(String, std::ops::Range<usize>)],
    cameras: &[SceneCamera],
) -> Result<SceneCamera, ShotError> {
    if let Some(model) = &c.model {
        if c.position.is_some() || c.target.is_some() || c.up.is_some() || c.fov.is_some() {
            return Err(invalid(
                path,
                "[camera]: give model (and index) or position/target/up/fov, not both".into(),
            ));
        }
        let Some((_, range)) = model_cameras.iter().find(|(n, _)| n == model) else {
            let names: Vec<&str> = model_cameras.iter().map(|(n, _)| n.as_str()).collect();
            return Err(invalid(
                path,
                format!(
                    "[camera] model = '{model}': no such model (models: {})",
                    names.join(", ")
                ),
            ));
        };
        let index = c.index.unwrap_or(0);
        if index >= range.len() {
            return Err(invalid(
                path,
                format!(
                    "[camera] model '{model}' has {} camera(s); index {index} is out of range",
                    range.len()
                ),
            ));
        }
        return Ok(SceneCamera {
            depth_of_field: depth_of_field(path, c)?,
            // The scene file's [render] size is the film.
            window: None,
            ..cameras[range.start + index].clone()
        });
    }
    if c.index.is_some() {
        return Err(invalid(path, "[camera] index needs model".into()));
    }
    let (Some(position), Some(target)) = (c.position, c.target) else {
        return Err(invalid(
            path,
            "[camera]: give position and target (or model)".into(),
        ));
    };
    let up = c.up.unwrap_or([0.0, 1.0, 0.0]);
    for (key, v) in [("position", position), ("target", target), ("up", up)] {
        check(path, &format!("[camera] {key}"), &v, false)?;
    }
    let fov = c.fov.unwrap_or(40.0);
    if !(fov > 0.0 && fov < 180.0) {
        return Err(invalid(
            path,
            format!("[camera] fov = {fov}: expected degrees between 0 and 180"),
        ));
    }
    let rotation =
        crate::camera::look_at(position.into(), target.into(), up.into()).ok_or_else(|| {
            invalid(
                path,
                "[camera]: position equals target, or up is along the view".into(),
            )
        })?;
    Ok(SceneCamera {
        name: "[camera]".into(),
        position: position.into(),
        rotation,
        lens: Lens::from_yfov(fov.to_radians()),
        aspect_ratio: None,
        depth_of_field: depth_of_field(path, c)?,
        window: None,
    })
}

/// The `[camera]` section's thin lens, checked (a focus pixel is checked
/// against the image once its size is known).
fn depth_of_field(path: &Path, c: &CameraSection) -> Result<DepthOfField, ShotError> {
    let aperture = match (c.aperture, c.f_number) {
        (Some(_), Some(_)) => {
            return Err(invalid(
                path,
                "[camera]: give aperture or f_number, not both".into(),
            ));
        }
        (Some(r), None) if lens_length_is_valid(r, false) => Some(Aperture::Radius(r)),
        (None, Some(n)) if lens_length_is_valid(n, true) => Some(Aperture::FNumber(n)),
        (Some(r), None) => {
            return Err(invalid(
                path,
                format!("[camera] aperture = {r}: expected a radius from 0 to {MAX_LENS_LENGTH:e}"),
            ));
        }
        (None, Some(n)) => {
            return Err(invalid(
                path,
                format!(
                    "[camera] f_number = {n}: expected a number above 0, at most {MAX_LENS_LENGTH:e}"
                ),
            ));
        }
        (None, None) => None,
    };
    let focus = match (c.focus_distance, c.focus_pixel) {
        (Some(_), Some(_)) => {
            return Err(invalid(
                path,
                "[camera]: give focus_distance or focus_pixel, not both".into(),
            ));
        }
        (Some(d), None) if lens_length_is_valid(d, true) => Some(Focus::Distance(d)),
        (Some(d), None) => {
            return Err(invalid(
                path,
                format!(
                    "[camera] focus_distance = {d}: expected a distance above 0, at most {MAX_LENS_LENGTH:e}"
                ),
            ));
        }
        (None, Some(p)) => Some(Focus::Pixel(p)),
        (None, None) => None,
    };
    if let Some(n) = c.aperture_blades
        && !crate::camera::blades_are_valid(n)
    {
        return Err(invalid(
            path,
            format!(
                "[camera] aperture_blades = {n}: expected 0 (round) or 3 to {}",
                crate::camera::MAX_BLADES
            ),
        ));
    }
    Ok(DepthOfField {
        aperture,
        focus,
        blades: c.aperture_blades,
    })
}
