//! Choosing a light for next-event estimation, and the densities multiple
//! importance sampling weighs by: the key light, the other punctual lights,
//! the environment and the emitting triangles of a [`Scene`], picked by what
//! each can send to the point being lit (a light tree, the default), by
//! power, or uniformly.

use crate::textures::TextureStore;
use std::f32::consts::PI;

use glam::{Vec2, Vec3A};
use rayon::prelude::*;

use super::analytic::{AnalyticShape, SceneShape};
use super::light_table::{
    AreaLights, KEY_LIGHT, LightNumbers, LightRef, LightSelection, LightTable, PositionalLight,
};
use super::light_tree::{self, Facing, Fraction, LightBounds, LightTree, TreeLight};
use super::model::Scene;
use crate::geometry::ray::Hit;
use crate::lights::environment::SkyRadiance;
use crate::lights::{Incident, Light};
use crate::materials::surface::SurfaceMaterial;
use crate::sampling::distribution::AliasTable;

impl Scene {
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

    /// How the light tree's choice gets its number ([`LightNumbers`]); the
    /// same expected image either way.
    pub fn set_light_numbers(&mut self, numbers: LightNumbers) {
        self.numbers = numbers;
    }

    /// How the light tree's choice gets its number.
    pub fn light_numbers(&self) -> LightNumbers {
        self.numbers
    }

    /// Radiance arriving from the environment along `dir` (unit, away from the
    /// scene).
    #[inline]
    pub fn environment_radiance(&self, dir: Vec3A) -> Vec3A {
        self.environment.radiance(dir)
    }

    /// The solid-angle density with which [`Scene::sample_light`], lighting
    /// a surface at `from` that `facing` describes, picks direction `dir` of
    /// the environment (selection included).
    #[inline]
    pub fn environment_pdf(&self, dir: Vec3A, from: Vec3A, facing: Facing) -> f32 {
        let Some(entry) = self.light_table.environment else {
            return 0.0;
        };
        let choice = if self.uses_tree() {
            {
                let weights = self.top_level(from, facing);
                weights.share(weights.environment)
            }
        } else {
            self.entry_probability(entry as usize)
        };
        choice * self.environment.pdf(dir)
    }

    /// Whether lights are chosen by the light tree: the default, when there
    /// is anything to choose besides the key light, unless the only other
    /// lights are the triangles of one flat emitter (`cornell-area`'s ceiling
    /// patch). There the tree's choice differs from power's only by the
    /// triangles' distances, and weighing them at every vertex cost 29 % more
    /// instructions on `cornell-area` for no measurable gain. (Decided when
    /// the light table is built.)
    #[inline]
    fn uses_tree(&self) -> bool {
        self.light_table.tree_active
    }

    /// Whether the light chosen, and the densities MIS weighs by, depend on
    /// the point being lit and its side ([`Facing`]): the light tree is in use.
    #[inline]
    pub(crate) fn light_choice_depends_on_point(&self) -> bool {
        self.uses_tree()
    }

    /// Builds the table that chooses among the lights other than the key light:
    /// punctual lights, the environment and the emitting triangles, weighted by
    /// power (or equally).
    pub(super) fn rebuild_light_table(&mut self) {
        let radius = self.radius().max(1e-3);
        let mut entries = Vec::new();
        let mut weights = Vec::new();
        let weigh = |power: f32| match self.selection {
            LightSelection::Tree | LightSelection::Power => power,
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
            prim_entry = vec![u32::MAX; self.triangles.len() + self.shapes.len()];
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
        let one_flat_emitter = self.lights.is_empty()
            && environment.is_none()
            && (1..=MAX_FLAT_EMITTER).contains(&self.area_lights.prims.len())
            && self.emitters_share_a_plane();
        let (tree, directional, env_importance) = if self.selection == LightSelection::Tree {
            self.build_tree(environment.is_some())
        } else {
            (LightTree::default(), Vec::new(), 0.0)
        };
        let alias_total = alias.total() as f32;
        let mean = |v: Vec3A| (v.as_dvec3().element_sum() / 3.0) as f32;
        let key = (self.point_power() > 0.0).then(|| PositionalLight {
            light: KEY_LIGHT,
            position: self.light.position,
            intensity: self.point_power() * (0.25 / PI),
        });
        let others = self.lights.iter().enumerate().filter_map(|(i, l)| {
            let (position, intensity) = match *l {
                Light::Point {
                    position,
                    intensity,
                }
                | Light::Spot {
                    position,
                    intensity,
                    ..
                } => (position, mean(intensity)),
                Light::Beam(ref b) => (b.position, mean(b.intensity)),
                Light::Directional { .. } => return None,
            };
            (intensity > 0.0 && intensity.is_finite() && l.power(radius) > 0.0).then_some(
                PositionalLight {
                    light: i as u32,
                    position,
                    intensity,
                },
            )
        });
        let positional = key.into_iter().chain(others).collect();
        self.light_table = LightTable {
            positional,
            total: alias_total,
            alias,
            entries,
            environment,
            prim_entry,
            punctual_pmf,
            by_importance,
            tree,
            directional,
            env_importance,
            tree_active: self.selection == LightSelection::Tree
                && alias_total > 0.0
                && !one_flat_emitter,
        };
    }

    /// Whether every emitting triangle has the same front normal and lies in
    /// the same plane (to a relative 1e-5).
    fn emitters_share_a_plane(&self) -> bool {
        let prims = &self.area_lights.prims;
        let Some(&first) = prims.first() else {
            return false;
        };
        if prims
            .iter()
            .any(|&prim| prim as usize >= self.triangles.len())
        {
            return false;
        }
        let n = self.normals[first as usize];
        let v = self.triangles[first as usize].v[0];
        let scale = 1e-5 * (1.0 + v.abs().max_element());
        prims.iter().all(|&prim| {
            let t = &self.triangles[prim as usize];
            (self.normals[prim as usize] - n).abs().max_element() <= 1e-5
                && t.v.iter().all(|&w| (w - v).dot(n).abs() <= scale)
        })
    }

    /// The light tree over the emitting triangles and the point and spot
    /// lights; the directional lights (chosen beside it); the environment's
    /// importance (`π` times its mean radiance: the irradiance it would give
    /// if it were uniform).
    fn build_tree(&self, environment: bool) -> (LightTree, Vec<u32>, f32) {
        let mean = |v: Vec3A| (v.as_dvec3().element_sum() / 3.0) as f32;
        let mut lights = Vec::new();
        let mut directional = Vec::new();
        for (i, l) in self.lights.iter().enumerate() {
            let bounds = match *l {
                Light::Point {
                    position,
                    intensity,
                } => LightBounds::point(position, mean(intensity)),
                Light::Spot {
                    position,
                    direction,
                    intensity,
                    cos_inner,
                    cos_outer,
                } => LightBounds::spot(position, direction, mean(intensity), cos_inner, cos_outer),
                Light::Beam(ref b) => {
                    let (cos_inner, cos_outer) = b.cones();
                    LightBounds::spot(b.position, b.axis, mean(b.intensity), cos_inner, cos_outer)
                }
                Light::Directional { irradiance, .. } => {
                    if mean(irradiance) > 0.0 {
                        directional.push(i as u32);
                    }
                    continue;
                }
            };
            lights.push((bounds, TreeLight::Punctual(i as u32)));
        }
        for &prim in &self.area_lights.prims {
            let power = self.area_lights.per_prim[prim as usize].0;
            let two_sided = self.material(prim).emits_both_sides;
            if let Some(s) = self.shape_of(prim) {
                lights.push((
                    analytic_bounds(s, power, two_sided),
                    TreeLight::Triangle(prim),
                ));
                continue;
            }
            // `power = π A Le` per side: the intensity along the normal is `A Le`.
            let phi = power / (PI * if two_sided { 2.0 } else { 1.0 });
            lights.push((
                LightBounds::triangle(
                    &self.triangles[prim as usize].v,
                    self.normals[prim as usize],
                    phi,
                    two_sided,
                ),
                TreeLight::Triangle(prim),
            ));
        }
        let env_importance = if environment {
            0.25 * self.environment.radiance_integral()
        } else {
            0.0
        };
        (
            LightTree::build(
                lights,
                self.triangles.len() + self.shapes.len(),
                self.lights.len(),
            ),
            directional,
            env_importance,
        )
    }

    /// What each kind of light the tree mode chooses among first can send to
    /// a surface at `p` (as `facing` says).
    #[inline]
    fn top_level(&self, p: Vec3A, facing: Facing) -> TopLevelWeights {
        let table = &self.light_table;
        let key = self.point_power() * (0.25 / PI);
        let key = if key > 0.0 {
            point_importance(self.light.position, key, p, facing)
        } else {
            0.0
        };
        let root = table.tree.root_importances(p, facing);
        let tree = light_tree::sum(root);
        let environment = table.env_importance;
        let mut total = key + tree + environment;
        for &i in &table.directional {
            total += directional_importance(&self.lights[i as usize], facing);
        }
        TopLevelWeights {
            key,
            tree,
            root,
            environment,
            total,
        }
    }

    /// [`Scene::sample_light`] by the light tree: the choice made with
    /// `u_select.x`, or, with [`LightNumbers::Stratified`], with `u.x`
    /// ([`select_number`]), whose leftover then places the point.
    #[inline]
    fn sample_light_by_tree(
        &self,
        p: Vec3A,
        facing: Facing,
        u_select: Vec2,
        u: Vec2,
    ) -> Option<LightSample> {
        match self.numbers {
            LightNumbers::Independent => self.sample_light_with(p, facing, u_select.x, u, false),
            LightNumbers::Stratified => {
                self.sample_light_with(p, facing, select_number(u.x, u_select.x), u, true)
            }
        }
    }

    /// [`Scene::sample_light_by_tree`] with the choosing number `select`;
    /// `reuse`: whether its leftover replaces `u.x` on the chosen light.
    #[inline(always)]
    fn sample_light_with<U: Fraction>(
        &self,
        p: Vec3A,
        facing: Facing,
        select: U,
        u: Vec2,
        reuse: bool,
    ) -> Option<LightSample> {
        let weights = self.top_level(p, facing);
        let total = weights.total;
        if !(total > 0.0 && total.is_finite()) {
            return None;
        }
        // The kinds in order: key light, tree, environment, directional
        // lights (whose weights are worked out only up to the one chosen).
        let directional = &self.light_table.directional;
        let kinds = [weights.key, weights.tree, weights.environment]
            .into_iter()
            .chain(
                directional
                    .iter()
                    .map(|&i| directional_importance(&self.lights[i as usize], facing)),
            );
        let (k, w, rest) = light_tree::choose(kinds, total, select)?;
        let kind = match k {
            0 => TopLevel::Key,
            1 => TopLevel::Tree,
            2 => TopLevel::Environment,
            _ => TopLevel::Directional(directional[k - 3]),
        };
        let probability = w / total;
        let on_light = |rest: U| {
            if reuse {
                Vec2::new(rest.to_unit_f32(), u.y)
            } else {
                u
            }
        };
        match kind {
            TopLevel::Key => Some(self.key_sample(probability)),
            TopLevel::Tree => {
                let (light, pmf, rest) =
                    self.light_table
                        .tree
                        .sample(weights.root, p, facing, rest)?;
                let probability = pmf * probability;
                match light {
                    TreeLight::Punctual(i) => self.punctual_sample(i, p, probability),
                    TreeLight::Triangle(prim) => {
                        self.triangle_sample(prim, on_light(rest), probability, p)
                    }
                }
            }
            TopLevel::Environment => self.environment_sample(p, on_light(rest), probability),
            TopLevel::Directional(i) => self.punctual_sample(i, p, probability),
        }
    }

    /// The key light's sample, chosen with `probability`.
    #[inline]
    fn key_sample(&self, probability: f32) -> LightSample {
        LightSample::Point {
            position: self.light.position,
            intensity: self.light.power * (1.0 / (4.0 * PI * probability)),
            light: KEY_LIGHT,
        }
    }

    /// A direction of the environment for `p`, by the map's importance with
    /// `u`, chosen with `probability`.
    #[inline]
    fn environment_sample(&self, p: Vec3A, u: Vec2, probability: f32) -> Option<LightSample> {
        let (to_light, radiance, pdf) = self.environment.sample_direction(u)?;
        Some(LightSample::Environment {
            to_light,
            radiance,
            pdf: pdf * probability,
            distance: self.escape_distance(p),
        })
    }

    /// Punctual light `i`'s sample for `p`, chosen with `probability`.
    #[inline]
    fn punctual_sample(&self, i: u32, p: Vec3A, probability: f32) -> Option<LightSample> {
        let scale = 1.0 / probability;
        Some(match self.lights[i as usize].incident(p, &self.textures)? {
            Incident::FromPoint {
                position,
                intensity,
            } => LightSample::Point {
                position,
                intensity: intensity * scale,
                light: i,
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

    /// A point on emitting triangle `prim`, uniform by area with `u`, chosen
    /// with `probability`, for the shading point `p` (towards which a clear
    /// coat dims it); for an analytic shape, [`Scene::shape_sample`].
    #[inline]
    fn triangle_sample(
        &self,
        prim: u32,
        u: Vec2,
        probability: f32,
        p: Vec3A,
    ) -> Option<LightSample> {
        if prim as usize >= self.triangles.len() {
            return self.shape_sample(prim, u, probability, p);
        }
        let v = &self.triangles[prim as usize].v;
        let (b1, b2) = uniform_barycentrics(u);
        let position = (1.0 - b1 - b2) * v[0] + b1 * v[1] + b2 * v[2];
        let area = self.area_lights.per_prim[prim as usize].1;
        Some(LightSample::Area {
            position,
            normal: self.normals[prim as usize],
            radiance: self.emission_at(prim, b1, b2)
                * self.coat_dimming(prim, b1, b2, p - position),
            two_sided: self.material(prim).emits_both_sides,
            pdf_area: probability / area,
        })
    }

    /// A point of emitting analytic shape `prim` for the shading point `p`,
    /// chosen with `probability`: a sphere's by the solid angle it subtends
    /// from `p`
    /// ([`Sphere::sample_from`](crate::geometry::sphere::Sphere::sample_from)),
    /// its density stated per unit area at the point (as the integrators
    /// read an area light's); a disk's or cylinder's uniformly by area.
    #[cold]
    #[inline(never)]
    fn shape_sample(&self, prim: u32, u: Vec2, probability: f32, p: Vec3A) -> Option<LightSample> {
        let s = self.shape_of(prim)?;
        let (uv, solid_angle_pdf) = match &s.shape {
            AnalyticShape::Sphere(sphere) => {
                let (uv, pdf) = sphere.sample_from(p, u)?;
                (uv, Some(pdf))
            }
            AnalyticShape::Disk(d) => (d.sample_uv(u), None),
            AnalyticShape::Cylinder(c) => (c.sample_uv(u), None),
            // (Never a light: `Scene::from_parts` refuses emitting cells.)
            AnalyticShape::SdfVoxel(_) => return None,
        };
        let point = s.front_point(uv);
        let normal = point.n;
        let d = point.p - p;
        let r2 = d.length_squared();
        let cos = normal.dot(d).abs() / r2.sqrt();
        if !(cos > 0.0 && r2 > 0.0) {
            return None;
        }
        let pdf_area = match solid_angle_pdf {
            Some(pdf) => probability * pdf * cos / r2,
            None => probability / self.area_lights.per_prim[prim as usize].1,
        };
        Some(LightSample::Area {
            position: point.p,
            normal,
            radiance: self.emission_at(prim, uv.x, uv.y)
                * self.coat_dimming(prim, uv.x, uv.y, p - point.p),
            two_sided: self.material(prim).emits_both_sides,
            pdf_area,
        })
    }

    /// The key light's selection weight.
    #[inline]
    fn key_weight(&self) -> f32 {
        let p = self.point_power();
        match self.selection {
            LightSelection::Tree | LightSelection::Power => p,
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

    /// The lights at a point that send light ([`PositionalLight`]): the
    /// key light, then the point lights, spots and beams in the order of
    /// [`Scene::lights`].
    #[inline]
    pub fn positional_lights(&self) -> &[PositionalLight] {
        &self.light_table.positional
    }

    /// Where positional light `light` ([`LightSample::Point::light`]) is and
    /// the intensity it sends towards `p` (W/sr); `None` when it sends none.
    #[inline]
    pub fn point_light_towards(&self, light: u32, p: Vec3A) -> Option<(Vec3A, Vec3A)> {
        if light == KEY_LIGHT {
            return Some((self.light.position, self.light.power * (0.25 / PI)));
        }
        match self
            .lights
            .get(light as usize)?
            .incident(p, &self.textures)?
        {
            Incident::FromPoint {
                position,
                intensity,
            } => Some((position, intensity)),
            Incident::FromDirection { .. } => None,
        }
    }

    /// The probability that [`Scene::sample_light`] picks positional light
    /// `light` ([`LightSample::Point::light`]) to light a point `p` in a
    /// medium ([`Facing::Any`]), whichever light selection is in use.
    pub fn point_light_pmf(&self, light: u32, p: Vec3A) -> f32 {
        let facing = Facing::Any;
        if self.uses_tree() {
            let weights = self.top_level(p, facing);
            if light == KEY_LIGHT {
                return weights.share(weights.key);
            }
            let pmf = self
                .light_table
                .tree
                .punctual_pmf(weights.root, light, p, facing);
            return pmf * weights.share(weights.tree);
        }
        let key = self.key_weight();
        let rest = self.light_table.total;
        let total = key + rest;
        if !(total > 0.0 && total.is_finite()) {
            return 0.0;
        }
        if light == KEY_LIGHT {
            return key / total;
        }
        let table = &self.light_table;
        if table.by_importance {
            let importance = |l: &Light| Self::punctual_importance(l, p, facing, &self.textures);
            let all: f32 = self.lights.iter().map(importance).sum();
            let Some(this) = self.lights.get(light as usize).map(importance) else {
                return 0.0;
            };
            if !(all > 0.0 && all.is_finite()) {
                return 0.0;
            }
            return this / all * table.punctual_pmf * (rest / total);
        }
        table
            .entries
            .iter()
            .position(|e| *e == LightRef::Punctual(light))
            .map_or(0.0, |entry| self.entry_probability(entry))
    }

    /// Picks a light with `u_select` (by power: the key light `P`; other
    /// punctual lights [`Light::power`]; the environment `π r² ∫ L dω`; each
    /// emitting triangle `π·A·Le`, doubled for two-sided emitters; or uniformly,
    /// see [`Scene::set_light_selection`]), then a point or direction on it with
    /// `u` (uniform by area on a triangle, by the map's importance on the
    /// environment), to light the point `p`. `u_select.x` chooses, `u_select.y`
    /// settles the alias table's coin. With the light tree
    /// ([`LightSelection::Tree`]) `u.x` chooses instead, `u_select.x` filling
    /// in below its last bit, and what is left of it after the choice places
    /// the point (so Sobol' points stay stratified over each light). `None`
    /// when the scene has no light or the chosen one sends nothing to `p`.
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
        if self.uses_tree() {
            return self.sample_light_by_tree(p, facing, u_select, u);
        }
        let key = self.key_weight();
        let rest = self.light_table.total;
        let total = key + rest;
        if total <= 0.0 {
            return None;
        }
        let p_key = key / total;
        if u_select.x < p_key || rest <= 0.0 {
            return Some(self.key_sample(p_key));
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
                self.punctual_sample(i, p, probability)
            }
            LightRef::Environment => self.environment_sample(p, u, probability),
            LightRef::Triangle(prim) => self.triangle_sample(prim, u, probability, p),
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
    pub fn punctual_importance(
        light: &Light,
        p: Vec3A,
        facing: Facing,
        textures: &TextureStore,
    ) -> f32 {
        let mean = |v: Vec3A| (v.x + v.y + v.z) * (1.0 / 3.0);
        let (to_light, value) = match light.incident(p, textures) {
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
        let w = value * facing.cosine(to_light).max(1e-3);
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
            *w = Self::punctual_importance(light, p, facing, &self.textures);
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

    /// The density per unit area with which [`Scene::sample_light`], lighting
    /// a surface at `from` that `facing` describes, picks a point on emitting
    /// triangle `prim`: its selection probability there over its area.
    #[inline]
    pub fn light_pdf_area(&self, prim: u32, from: Vec3A, facing: Facing) -> f32 {
        let Some(&entry) = self.light_table.prim_entry.get(prim as usize) else {
            return 0.0;
        };
        if entry == u32::MAX {
            return 0.0;
        }
        let area = self.area_lights.per_prim[prim as usize].1;
        if self.uses_tree() {
            let weights = self.top_level(from, facing);
            let pmf = self
                .light_table
                .tree
                .triangle_pmf(weights.root, prim, from, facing);
            return pmf * weights.share(weights.tree) / area;
        }
        self.entry_probability(entry as usize) / area
    }

    /// The solid-angle density with which [`Scene::sample_light`], lighting
    /// a surface at `from` that `facing` describes, picks the direction of
    /// `hit` (a ray's from `from`, with unit direction, meeting an emitter
    /// whose normal makes cosine `cos_out` with it): for a triangle its area
    /// density times `t²/|cos|` (so for a disk or cylinder too), for a
    /// sphere the density of its solid-angle sampling.
    #[inline]
    pub fn light_pdf_hit(&self, hit: &Hit, from: Vec3A, facing: Facing, cos_out: f32) -> f32 {
        if (hit.prim as usize) < self.triangles.len() {
            return self.light_pdf_area(hit.prim, from, facing) * hit.t * hit.t / cos_out.abs();
        }
        self.analytic_light_pdf(hit, from, facing, cos_out)
    }

    /// [`Scene::light_pdf_hit`] of an analytic shape.
    #[cold]
    #[inline(never)]
    fn analytic_light_pdf(&self, hit: &Hit, from: Vec3A, facing: Facing, cos_out: f32) -> f32 {
        let Some(s) = self.shape_of(hit.prim) else {
            return 0.0;
        };
        let AnalyticShape::Sphere(sphere) = &s.shape else {
            return self.light_pdf_area(hit.prim, from, facing) * hit.t * hit.t / cos_out.abs();
        };
        // The selection probability: the area density times the area.
        let choice = self.light_pdf_area(hit.prim, from, facing) * sphere.area();
        if choice <= 0.0 {
            return 0.0;
        }
        let q = sphere.point_at(Vec2::new(hit.b1, hit.b2)).p;
        choice * sphere.pdf_from(from, q, cos_out)
    }

    /// Total power emitted by the emitting triangles (the estimate they are
    /// chosen by), W averaged over the colour channels.
    pub fn emitted_power(&self) -> f32 {
        self.area_lights.total
    }

    /// How many triangles emit light (analytic shapes not counted).
    pub fn emitter_count(&self) -> usize {
        self.area_lights.prims.len() - self.emitting_shape_count()
    }

    /// How many analytic shapes (spheres, disks, cylinders) emit light.
    pub fn emitting_shape_count(&self) -> usize {
        let triangles = self.triangles.len();
        self.area_lights
            .prims
            .iter()
            .filter(|&&p| p as usize >= triangles)
            .count()
    }
}

/// The number that chooses a light in the tree's stratified sampling: the
/// light sample's own first number `u` (a multiple of 2⁻²⁴ in `[0, 1)`, as
/// the samplers make them) with `jitter` (another, independent one) filling
/// the cell of width 2⁻²⁴ below it, in double precision: uniform in
/// `[0, 1)`. Choosing with the number that then places the point on the
/// chosen light (the leftover of the choice, [`LightTree::sample`]) keeps
/// the sampler's two-dimensional stratification across the lights: with
/// several lights a Sobol' pattern's points spread over each light as over
/// one, where an independent choice would leave each light a random subset
/// of them.
#[inline]
fn select_number(u: f32, jitter: f32) -> f64 {
    (f64::from(u) + f64::from(jitter) * SELECT_CELL).min(<f64 as Fraction>::ONE_BELOW)
}

/// The spacing of the samplers' numbers, 2⁻²⁴.
const SELECT_CELL: f64 = 1.0 / (1u32 << 24) as f64;

/// The light tree's bounds of an emitting analytic shape of power `power`
/// (`π A Le`, per side): a sphere sends `πr²Le = power/4π` every way; a
/// disk `A Le` along its front normal (from the front, or both sides); a
/// cylinder at most its projected area `2rℓ` times `Le`, `power/π²`, in
/// directions all round (a bound, as the tree needs).
fn analytic_bounds(s: &SceneShape, power: f32, two_sided: bool) -> LightBounds {
    let (lo, hi) = s.shape.bounds();
    match &s.shape {
        AnalyticShape::Sphere(_) => LightBounds::sphere(lo, hi, power / (4.0 * PI)),
        AnalyticShape::Disk(d) => {
            let n = if s.flip { -d.normal() } else { d.normal() };
            let phi = power / (PI * if two_sided { 2.0 } else { 1.0 });
            LightBounds::flat(lo, hi, n, phi, two_sided)
        }
        AnalyticShape::Cylinder(_) => LightBounds::sphere(lo, hi, power / (PI * PI)),
        // (Never a light: `Scene::from_parts` refuses emitting cells.)
        AnalyticShape::SdfVoxel(_) => LightBounds::sphere(lo, hi, 0.0),
    }
}

/// Barycentrics `(b1, b2)` of a point distributed uniformly by area over a
/// triangle, from `u` in `[0, 1)²`.
#[inline]
fn uniform_barycentrics(u: Vec2) -> (f32, f32) {
    let su = u.x.sqrt();
    (1.0 - su, u.y * su)
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
        /// Which light: an index of [`Scene::lights`], or [`KEY_LIGHT`].
        light: u32,
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
        /// The environment's radiance, read by
        /// [`Environment::radiance_of`](crate::lights::environment::Environment::radiance_of)
        /// once it is needed.
        radiance: SkyRadiance,
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

/// The most punctual lights [`Scene::sample_light`] weighs by what they send
/// to the point being lit (the others are chosen by power alone: the weighing
/// is a loop over them at every vertex that picks one).
pub const MAX_IMPORTANCE_LIGHTS: usize = 32;

/// The most triangles a flat emitter chosen by power instead of the light
/// tree may have (see [`Scene::uses_tree`]: at most this many triangles of one
/// plane facing one way, and no other light but the key light).
const MAX_FLAT_EMITTER: usize = 4;

/// What [`LightSelection::Tree`] first chooses among.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum TopLevel {
    Key,
    Tree,
    Environment,
    /// Light `i` of [`Scene::lights`].
    Directional(u32),
}

/// The weights of [`TopLevel`]'s kinds at a point (the directional lights'
/// only in the total).
#[derive(Clone, Copy, Debug)]
struct TopLevelWeights {
    key: f32,
    tree: f32,
    /// The importances of the tree root's children (their sum is `tree`).
    root: glam::Vec4,
    environment: f32,
    total: f32,
}

impl TopLevelWeights {
    /// The probability of choosing a kind of weight `w` (one of these
    /// weights).
    #[inline]
    fn share(&self, w: f32) -> f32 {
        if self.total > 0.0 && self.total.is_finite() {
            w / self.total
        } else {
            0.0
        }
    }
}

/// What a point light of intensity `phi` at `position` sends to a surface at
/// `p` that `facing` describes: `phi cos θ / d²`, zero from below the
/// surface's horizon (the light tree's bound for a point, exact).
#[inline]
fn point_importance(position: Vec3A, phi: f32, p: Vec3A, facing: Facing) -> f32 {
    let to_p = p - position;
    let d2 = to_p.length_squared();
    let cos = match facing {
        Facing::Any => 1.0,
        _ => facing.cosine(-to_p) * d2.sqrt().recip(),
    };
    let w = phi / d2 * cos;
    if w.is_finite() && w > 0.0 { w } else { 0.0 }
}

/// What directional light `light` sends to a surface facing as `facing`
/// says: its irradiance (the mean over the channels) times the cosine, zero
/// from below the surface's horizon.
#[inline]
fn directional_importance(light: &Light, facing: Facing) -> f32 {
    let Light::Directional {
        direction,
        irradiance,
    } = *light
    else {
        return 0.0;
    };
    let e = (irradiance.x + irradiance.y + irradiance.z) * (1.0 / 3.0);
    let w = e * facing.cosine(-direction);
    if w.is_finite() { w.max(0.0) } else { 0.0 }
}

/// Points per triangle at which a textured emitter's radiance is averaged to
/// estimate its power.
const EMISSION_ESTIMATE_POINTS: u32 = 16;

impl AreaLights {
    pub(super) fn build(scene: &Scene) -> Self {
        let emissive: Vec<bool> = scene
            .materials
            .iter()
            .map(SurfaceMaterial::is_emissive)
            .collect();
        if !emissive.iter().any(|&e| e) {
            return Self::default();
        }
        let n_tri = scene.triangles.len();
        let per_prim: Vec<(f32, f32)> = (0..n_tri + scene.shapes.len())
            .into_par_iter()
            .map(|i| {
                let m = scene.material_of[i] as usize;
                if !emissive[m] {
                    return (0.0, 0.0);
                }
                let area = match scene.shape_of(i as u32) {
                    Some(s) => s.shape.area(),
                    None => scene.triangles[i].area(),
                };
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
