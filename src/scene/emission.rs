//! Light leaving the lights, for integrators that start paths at them
//! (`bdpt`'s light subpaths and its connections to a light): which light
//! sends a path ([`Scene::pick_emitter`], by power, independent of any point
//! being lit), the point it leaves from ([`Scene::emitter_point`]) and the
//! densities of both ([`Scene::emitter_pmf`]), and whether a scene has only
//! lights that can be started from ([`Scene::emission_unsupported`]), and
//! the disk light from infinity leaves by ([`Scene::infinite_disk`]).
//!
//! The choice is the light table's power-proportional one (its alias table
//! and the key light's weight), the same whatever [`LightSelection`] says
//! except `Uniform`, which chooses every light equally here too: a light
//! tree chooses by what a light sends to a point, and a light subpath has
//! no point yet.

use std::f32::consts::PI;

use glam::{Vec2, Vec3A};

use super::analytic::AnalyticShape;
use super::light_table::{LightRef, LightSelection};
use super::model::Scene;
use crate::geometry::ray::SurfacePoint;
use crate::lights::Light;

/// A light a path can start from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Emitter {
    /// The key point light ([`Scene::light`]).
    Key,
    /// Punctual light `i` of [`Scene::lights`] (a point, spot or beam).
    Punctual(u32),
    /// Emitting primitive `prim` (a triangle, disk or cylinder).
    Shape(u32),
    /// The environment ([`Scene::environment`]).
    Environment,
}

/// A point on an emitting shape, uniform by area.
#[derive(Clone, Copy, Debug)]
pub struct EmitterPoint {
    /// The point with its error bound, and the shape's unit front normal
    /// there.
    pub point: SurfacePoint,
    /// Coordinates for [`Scene::emission_at`] (barycentrics of a triangle,
    /// a shape's `uv`).
    pub uv: Vec2,
    /// The shape's area.
    pub area: f32,
}

impl Scene {
    /// The key light's weight and the table's, as the choice of
    /// [`Scene::pick_emitter`] reads them.
    #[inline]
    fn emitter_weights(&self) -> (f32, f32) {
        let key = self.point_power();
        let key = match self.selection {
            LightSelection::Uniform => f32::from(key > 0.0),
            _ => key,
        };
        (key, self.light_table.total)
    }

    /// A light chosen with `u` in proportion to its power, and the
    /// probability it was chosen with; `None` when nothing emits.
    pub fn pick_emitter(&self, u: Vec2) -> Option<(Emitter, f32)> {
        let (key, rest) = self.emitter_weights();
        let total = key + rest;
        if !total.gt(&0.0) {
            return None;
        }
        let p_key = key / total;
        if u.x < p_key || rest <= 0.0 {
            return Some((Emitter::Key, p_key));
        }
        let x = ((u.x - p_key) / (1.0 - p_key)).min(1.0 - f32::EPSILON / 2.0);
        let table = &self.light_table;
        let entry = table.alias.sample(Vec2::new(x, u.y))?;
        let pmf = table.alias.pmf(entry) * (rest / total);
        match table.entries[entry] {
            LightRef::Punctual(i) => Some((Emitter::Punctual(i), pmf)),
            LightRef::Triangle(prim) => Some((Emitter::Shape(prim), pmf)),
            LightRef::Environment => Some((Emitter::Environment, pmf)),
        }
    }

    /// The probability with which [`Scene::pick_emitter`] chooses `emitter`.
    pub fn emitter_pmf(&self, emitter: Emitter) -> f32 {
        let (key, rest) = self.emitter_weights();
        let total = key + rest;
        if !total.gt(&0.0) {
            return 0.0;
        }
        let table = &self.light_table;
        let entry = match emitter {
            Emitter::Key => return key / total,
            Emitter::Punctual(i) => table
                .entries
                .iter()
                .position(|e| *e == LightRef::Punctual(i)),
            Emitter::Shape(prim) => table
                .prim_entry
                .get(prim as usize)
                .filter(|&&e| e != u32::MAX)
                .map(|&e| e as usize),
            Emitter::Environment => table.environment.map(|e| e as usize),
        };
        entry.map_or(0.0, |e| table.alias.pmf(e) * (rest / total))
    }

    /// The density per unit area with which a light subpath starts at a
    /// point of emitting primitive `prim` ([`Scene::pick_emitter`], then
    /// [`Scene::emitter_point`]); 0 for a primitive that does not emit.
    pub fn emitter_origin_pdf(&self, prim: u32) -> f32 {
        let area = self
            .area_lights
            .per_prim
            .get(prim as usize)
            .map_or(0.0, |a| a.1);
        if !area.gt(&0.0) {
            return 0.0;
        }
        self.emitter_pmf(Emitter::Shape(prim)) / area
    }

    /// A point of emitting primitive `prim` uniformly by area with `u`;
    /// `None` for a primitive that cannot be sampled so (a signed distance
    /// cell: see [`Scene::emission_unsupported`]).
    pub fn emitter_point(&self, prim: u32, u: Vec2) -> Option<EmitterPoint> {
        let area = self.area_lights.per_prim.get(prim as usize)?.1;
        if (prim as usize) < self.triangles.len() {
            let v = &self.triangles[prim as usize].v;
            let su = u.x.sqrt();
            let (b1, b2) = (1.0 - su, u.y * su);
            return Some(EmitterPoint {
                point: SurfacePoint::on_triangle(v, b1, b2, self.normals[prim as usize]),
                uv: Vec2::new(b1, b2),
                area,
            });
        }
        let s = self.shape_of(prim)?;
        let uv = match &s.shape {
            AnalyticShape::Disk(d) => d.sample_uv(u),
            AnalyticShape::Cylinder(c) => c.sample_uv(u),
            AnalyticShape::Sphere(s) => s.sample_uv(u),
            AnalyticShape::SdfVoxel(_) => return None,
        };
        Some(EmitterPoint {
            point: s.front_point(uv),
            uv,
            area,
        })
    }

    /// Why light cannot be started from every light of this scene (for
    /// `bdpt`), or `None` when it can: emitting cells of a signed distance
    /// grid are not (yet) lights a path can leave.
    pub fn emission_unsupported(&self) -> Option<String> {
        let triangles = self.triangles.len();
        let grid = self.area_lights.prims.iter().any(|&p| {
            p as usize >= triangles
                && self
                    .shape_of(p)
                    .is_some_and(|s| matches!(s.shape, AnalyticShape::SdfVoxel(_)))
        });
        grid.then(|| "an emitting signed distance grid (sdfgrid)".into())
    }

    /// The light `emitter` as one at infinity: the environment, or a
    /// directional light ([`InfiniteEmitter`]); `None` for lights at a
    /// place.
    pub fn infinite_emitter(&self, emitter: Emitter) -> Option<InfiniteEmitter> {
        match emitter {
            Emitter::Environment => Some(InfiniteEmitter::Environment),
            Emitter::Punctual(i) => match self.lights.get(i as usize)? {
                Light::Directional {
                    direction,
                    irradiance,
                } => Some(InfiniteEmitter::Directional {
                    direction: *direction,
                    irradiance: *irradiance,
                }),
                _ => None,
            },
            Emitter::Key | Emitter::Shape(_) => None,
        }
    }

    /// The disk light from infinity leaves by (Veach's and pbrt's choice):
    /// the centre and radius of the sphere about the scene's bounds. A
    /// light subpath from the environment or a directional light starts
    /// uniformly on this disk, turned to face its direction, one radius out
    /// from the centre, so that its rays cover the whole scene.
    pub fn infinite_disk(&self) -> (Vec3A, f32) {
        let (lo, hi) = self.bounds();
        (0.5 * (lo + hi), self.radius().max(1e-3))
    }

    /// The density per solid angle with which a light subpath (or
    /// next-event estimation from [`Scene::pick_emitter`]) leaves from
    /// infinity along `-to_light`, the choice of the light included: the
    /// environment's own sampling density times its probability of being
    /// chosen (a directional light's delta counts as 0).
    pub fn infinite_origin_pdf(&self, to_light: Vec3A) -> f32 {
        if self.environment.is_black() {
            return 0.0;
        }
        self.emitter_pmf(Emitter::Environment) * self.environment.pdf(to_light)
    }

    /// A direction leaving point light `emitter` (the key light or a
    /// punctual one) drawn with `u`: uniform over the sphere, or over a
    /// spot's or beam's outer cone; with its solid-angle density and the
    /// intensity (W/sr) sent along it. `None` for a directional light.
    pub fn punctual_emission(&self, emitter: Emitter, u: Vec2) -> Option<PunctualEmission> {
        let (position, axis, cos_max) = match emitter {
            Emitter::Key => (self.light.position, Vec3A::Z, -1.0),
            Emitter::Punctual(i) => match &self.lights[i as usize] {
                Light::Point { position, .. } => (*position, Vec3A::Z, -1.0),
                Light::Spot {
                    position,
                    direction,
                    cos_outer,
                    ..
                } => (*position, *direction, *cos_outer),
                Light::Beam(b) => (b.position, b.axis, b.cones().1),
                Light::Directional { .. } => return None,
            },
            Emitter::Shape(_) | Emitter::Environment => return None,
        };
        let dir = uniform_cone(axis, cos_max, u);
        let pdf = cone_pdf(cos_max);
        let intensity = self.punctual_intensity(emitter, dir);
        Some(PunctualEmission {
            position,
            dir,
            pdf,
            intensity,
        })
    }

    /// The solid-angle density with which [`Scene::punctual_emission`]
    /// draws `dir` from `emitter` (0 outside a cone).
    pub fn punctual_pdf(&self, emitter: Emitter, dir: Vec3A) -> f32 {
        let (axis, cos_max) = match emitter {
            Emitter::Key => return cone_pdf(-1.0),
            Emitter::Punctual(i) => match &self.lights[i as usize] {
                Light::Point { .. } => return cone_pdf(-1.0),
                Light::Spot {
                    direction,
                    cos_outer,
                    ..
                } => (*direction, *cos_outer),
                Light::Beam(b) => (b.axis, b.cones().1),
                Light::Directional { .. } => return 0.0,
            },
            Emitter::Shape(_) | Emitter::Environment => return 0.0,
        };
        if axis.dot(dir) >= cos_max {
            cone_pdf(cos_max)
        } else {
            0.0
        }
    }

    /// The intensity (W/sr) point light `emitter` sends along the unit
    /// direction `dir`.
    pub fn punctual_intensity(&self, emitter: Emitter, dir: Vec3A) -> Vec3A {
        let light = match emitter {
            Emitter::Key => return self.light.power * (0.25 / PI),
            Emitter::Punctual(i) => &self.lights[i as usize],
            Emitter::Shape(_) | Emitter::Environment => return Vec3A::ZERO,
        };
        let (position, _) = match light {
            Light::Point { position, .. } | Light::Spot { position, .. } => (*position, ()),
            Light::Beam(b) => (b.position, ()),
            Light::Directional { .. } => return Vec3A::ZERO,
        };
        match light.incident(position + dir, &self.textures) {
            Some(crate::lights::Incident::FromPoint { intensity, .. }) => intensity,
            _ => Vec3A::ZERO,
        }
    }
}

/// A light at infinity ([`Scene::infinite_emitter`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum InfiniteEmitter {
    /// The environment: radiance from every direction.
    Environment,
    /// A directional light.
    Directional {
        /// The unit direction its light travels in.
        direction: Vec3A,
        /// Its irradiance on a surface facing it, W/m².
        irradiance: Vec3A,
    },
}

/// A direction drawn from a point light ([`Scene::punctual_emission`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PunctualEmission {
    /// Where the light is.
    pub position: Vec3A,
    /// The unit direction.
    pub dir: Vec3A,
    /// Its solid-angle density.
    pub pdf: f32,
    /// The intensity along it, W/sr.
    pub intensity: Vec3A,
}

/// The density of a direction uniform in a cone of cosine `cos_max` (−1:
/// the whole sphere).
#[inline]
fn cone_pdf(cos_max: f32) -> f32 {
    1.0 / (2.0 * PI * (1.0 - cos_max))
}

/// A direction uniform in the cone about the unit `axis` whose half-angle
/// has cosine `cos_max`.
#[inline]
fn uniform_cone(axis: Vec3A, cos_max: f32, u: Vec2) -> Vec3A {
    let cos = 1.0 - u.x * (1.0 - cos_max);
    let sin = (1.0 - cos * cos).max(0.0).sqrt();
    let phi = 2.0 * PI * u.y;
    let frame = crate::materials::Frame::from_normal(axis);
    (frame.t * (sin * phi.cos()) + frame.b * (sin * phi.sin()) + axis * cos).normalize()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Directions in a cone stay in it, and its density integrates to one
    /// over it: the fraction of uniform sphere directions inside the cone
    /// times the sphere's 4π equals the cone's solid angle `1/pdf`.
    #[test]
    fn cones_are_sampled_uniformly() {
        let axis = Vec3A::new(0.3, -0.5, 0.8).normalize();
        let cos_max = 0.6f32;
        let mut rng = crate::sampling::sampler::Rng::new(3, 4);
        for _ in 0..2000 {
            let d = uniform_cone(
                axis,
                cos_max,
                glam::Vec2::new(rng.next_f32(), rng.next_f32()),
            );
            assert!(d.dot(axis) >= cos_max - 1e-5);
            assert!((d.length() - 1.0).abs() < 1e-5);
        }
        let solid_angle = 1.0 / cone_pdf(cos_max);
        assert!((solid_angle - 2.0 * PI * 0.4).abs() < 1e-5);
        // The mean cosine to the axis of a uniform cone is (1 + cos_max)/2.
        let n = 20000;
        let mean: f32 = (0..n)
            .map(|_| {
                uniform_cone(
                    axis,
                    cos_max,
                    glam::Vec2::new(rng.next_f32(), rng.next_f32()),
                )
                .dot(axis)
            })
            .sum::<f32>()
            / n as f32;
        assert!((mean - 0.8).abs() < 0.005, "{mean}");
    }
}
