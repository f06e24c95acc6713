//! Where a scene's participating media are: [`SceneMedia`], the media and,
//! per material, the [`MediumInterface`] its surfaces separate (Mitsuba's
//! shape `interior` and `exterior`, pbrt's `MediumInterface`), and the
//! medium the camera sits in.

use glam::Vec3A;

use crate::media::{Homogeneous, Medium};

/// The media on the two sides of a surface: `interior` behind its front
/// geometric normal, `exterior` in front of it; `None` is vacuum.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct MediumInterface {
    /// The medium behind the surface (inside a closed shape).
    pub interior: Option<u32>,
    /// The medium in front of it.
    pub exterior: Option<u32>,
}

impl MediumInterface {
    /// Whether crossing (or leaving) the surface changes the medium a ray
    /// is in: whether either side names one (Mitsuba's
    /// `is_medium_transition`). A surface that names none leaves the ray
    /// in whatever medium it was in.
    #[inline]
    pub fn is_transition(&self) -> bool {
        self.interior.is_some() || self.exterior.is_some()
    }

    /// The medium a ray leaving the surface along `dir` travels in, given
    /// the surface's front normal `ng` (Mitsuba's `target_medium`).
    #[inline]
    pub fn target(&self, ng: Vec3A, dir: Vec3A) -> Option<u32> {
        if ng.dot(dir) > 0.0 {
            self.exterior
        } else {
            self.interior
        }
    }
}

/// A scene's participating media and where they are bound.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SceneMedia {
    /// The media.
    pub media: Vec<Medium>,
    /// Per material of the scene: the media its surfaces separate. Empty
    /// when no surface bounds a medium.
    pub interfaces: Vec<MediumInterface>,
    /// The medium camera rays start in (`None`: vacuum).
    pub camera: Option<u32>,
}

impl SceneMedia {
    /// Whether the scene has any medium at all (else the volumetric path
    /// tracer is not needed).
    #[inline]
    pub fn is_empty(&self) -> bool {
        self.media.is_empty()
    }

    /// The homogeneous medium camera rays start in, with its index: the
    /// fog the viewer thickens ([`crate::Scene::fog`]). `None`
    /// for vacuum, a heterogeneous medium or a random-walk (subsurface) one.
    pub fn camera_homogeneous(&self) -> Option<(usize, &Homogeneous)> {
        let m = self.camera? as usize;
        match self.media.get(m)? {
            Medium::Homogeneous(h) if !h.random_walk => Some((m, h)),
            _ => None,
        }
    }

    /// The interface of material `material` (none if no material has one).
    #[inline]
    pub fn interface(&self, material: u32) -> MediumInterface {
        self.interfaces
            .get(material as usize)
            .copied()
            .unwrap_or_default()
    }

    /// Why the media cannot be rendered with `materials` materials, if
    /// they cannot: a bad medium, an interface list of another length, or
    /// an index past the media.
    pub fn check(&self, materials: usize) -> Result<(), String> {
        for (i, m) in self.media.iter().enumerate() {
            m.check().map_err(|e| format!("medium {i}: {e}"))?;
        }
        if !self.interfaces.is_empty() && self.interfaces.len() != materials {
            return Err(format!(
                "{} materials but {} medium interfaces",
                materials,
                self.interfaces.len()
            ));
        }
        let n = self.media.len();
        let bad = |m: Option<u32>| m.is_some_and(|m| m as usize >= n);
        if let Some(i) = self
            .interfaces
            .iter()
            .position(|f| bad(f.interior) || bad(f.exterior))
        {
            return Err(format!("material {i} names a medium of {n}"));
        }
        if bad(self.camera) {
            return Err(format!("the camera's medium is not one of {n}"));
        }
        Ok(())
    }

    /// Appends `other`'s media after this scene's `materials` materials
    /// (`other`'s materials follow them), keeping its references.
    pub fn append(&mut self, other: SceneMedia, materials: usize, other_materials: usize) {
        if other.interfaces.is_empty() && other.media.is_empty() {
            return;
        }
        let offset = self.media.len() as u32;
        if self.interfaces.is_empty() {
            self.interfaces = vec![MediumInterface::default(); materials];
        }
        if other.interfaces.is_empty() {
            self.interfaces.extend(std::iter::repeat_n(
                MediumInterface::default(),
                other_materials,
            ));
        } else {
            self.interfaces
                .extend(other.interfaces.iter().map(|f| MediumInterface {
                    interior: f.interior.map(|m| m + offset),
                    exterior: f.exterior.map(|m| m + offset),
                }));
        }
        self.camera = self.camera.or(other.camera.map(|m| m + offset));
        self.media.extend(other.media);
    }

    /// Adds `fog` as the medium everywhere no other is: the camera's (unless
    /// it is in one) and each side of a boundary that names none.
    pub fn add_fog(&mut self, fog: Medium) {
        let index = self.media.len() as u32;
        self.media.push(fog);
        self.camera = self.camera.or(Some(index));
        for f in &mut self.interfaces {
            f.interior = f.interior.or(Some(index));
            f.exterior = f.exterior.or(Some(index));
        }
    }

    /// Moves the media with the scene they are in, placed by `to_world`
    /// whose scale is `s` (a similarity's).
    pub fn transform(&mut self, to_world: glam::Affine3A, s: f32) {
        for m in &mut self.media {
            m.transform(to_world, s);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::media::Phase;

    /// The fog is the camera's homogeneous medium: not vacuum, not a
    /// subsurface (random-walk) medium, not a medium the camera is outside.
    #[test]
    fn the_camera_fog_is_its_homogeneous_scattering_medium() {
        let fog = Medium::homogeneous(Vec3A::splat(0.5), Vec3A::splat(0.8), Phase::Isotropic);
        let skin = Medium::subsurface(Vec3A::splat(2.0), Vec3A::splat(0.7), 0.0);
        let mut media = SceneMedia {
            media: vec![skin, fog],
            interfaces: Vec::new(),
            camera: None,
        };
        assert!(media.camera_homogeneous().is_none(), "vacuum");
        media.camera = Some(1);
        let (m, h) = media.camera_homogeneous().expect("fog");
        assert_eq!(m, 1);
        assert_eq!(h.sigma_t, Vec3A::splat(0.5));
        media.camera = Some(0);
        assert!(
            media.camera_homogeneous().is_none(),
            "a random walk is no fog"
        );
        media.camera = Some(7);
        assert!(
            media.camera_homogeneous().is_none(),
            "an index past the media"
        );
    }
}
