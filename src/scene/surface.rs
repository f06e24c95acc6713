//! What a scene holds at a hit: the point with its error bound (one at a
//! time or four in lanes), the base colour, the texture coordinates and
//! colour, and everything shading needs ([`SurfaceHit`]: normals, normal
//! maps, tangents).

use glam::{Vec2, Vec3A, Vec4, Vec4Swizzles};

use super::analytic::AnalyticShape;
use super::mesh::{Instance, MeshData, Tangents};
use super::model::Scene;
use crate::geometry::ray::{Hit, SurfacePoint};
use crate::geometry::sdf_voxel::SdfVoxel;
use crate::materials::Frame;
use crate::materials::surface::{HitAttributes, MaterialKind, PerturbMap, TexturedBsdf};
use crate::textures::{TextureStore, mitsuba_luminance};

/// What a hit looks like: its point, normals and interpolated attributes.
#[derive(Clone, Copy, Debug)]
pub struct SurfaceHit {
    /// The hit point with its error bound; its normal is `ng`.
    pub point: SurfacePoint,
    /// Unit front geometric normal.
    pub ng: Vec3A,
    /// Unit shading normal (interpolated, normal-mapped), on `ng`'s side
    /// (a Mitsuba material's normal or bump map may tilt it past `ng`).
    pub ns: Vec3A,
    /// Unit interpolated normal (before any normal or bump map), on `ng`'s
    /// side; `ng` without vertex normals.
    pub ni: Vec3A,
    /// Unit normal of a clear coat (`KHR_materials_clearcoat`), on `ng`'s
    /// side: interpolated, then the coat's own normal map if it has one (the
    /// base's normal map does not apply); `ns` for a material without a coat.
    pub nc: Vec3A,
    /// The mesh's unit tangent and bitangent (`TANGENT` or MikkTSpace,
    /// orthogonalized against the interpolated normal) where the material
    /// is anisotropic (`KHR_materials_anisotropy`), for
    /// [`crate::materials::PbrBsdf::orient_anisotropy`]; zero elsewhere and
    /// without tangents. For a Mitsuba material whose frame matters (an
    /// anisotropic BSDF, a normal or bump map): Mitsuba's shading frame's
    /// `s` and `t` about `ni` (`s` is `∂p/∂u` made orthogonal to `ni`).
    pub tangent: Vec3A,
    /// See `tangent`.
    pub bitangent: Vec3A,
    /// Texture coordinates and colour.
    pub attrs: HitAttributes,
    /// Index of the material.
    pub material: u32,
}

impl Scene {
    /// The hit point of a ray along `dir` with its error bound, for spawning rays
    /// off the surface. Its normal is the face normal, turned towards the ray's
    /// origin in a two-sided scene.
    #[inline]
    pub fn surface_point(&self, hit: &Hit, dir: Vec3A) -> SurfacePoint {
        let prim = hit.prim as usize;
        if prim >= self.triangles.len() {
            return self.analytic_point(hit, dir);
        }
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
        if !self.shapes.is_empty() {
            return self.surface_points4_one_by_one(hits, dirs);
        }
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

    /// [`Scene::surface_points4`] in a scene with analytic shapes: point by
    /// point.
    #[cold]
    #[inline(never)]
    fn surface_points4_one_by_one(&self, hits: [&Hit; 4], dirs: [Vec3A; 4]) -> [[Vec4; 3]; 3] {
        let points: [SurfacePoint; 4] =
            std::array::from_fn(|i| self.surface_point(hits[i], dirs[i]));
        let lanes = |v: [Vec3A; 4]| {
            [
                Vec4::new(v[0].x, v[1].x, v[2].x, v[3].x),
                Vec4::new(v[0].y, v[1].y, v[2].y, v[3].y),
                Vec4::new(v[0].z, v[1].z, v[2].z, v[3].z),
            ]
        };
        [
            lanes(points.map(|p| p.p)),
            lanes(points.map(|p| p.n)),
            lanes(points.map(|p| p.error)),
        ]
    }

    /// [`Scene::surface_point`] of an analytic shape's hit: its front normal
    /// turned towards the ray in a two-sided scene.
    #[cold]
    #[inline(never)]
    fn analytic_point(&self, hit: &Hit, dir: Vec3A) -> SurfacePoint {
        let Some(s) = self.shape_of(hit.prim) else {
            return SurfacePoint {
                p: Vec3A::ZERO,
                error: Vec3A::ZERO,
                n: Vec3A::Z,
            };
        };
        let mut point = s.front_point(Vec2::new(hit.b1, hit.b2));
        if self.two_sided && point.n.dot(dir) > 0.0 {
            point.n = -point.n;
        }
        point
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
            None if hit.prim as usize >= self.triangles.len() => match self.shape_of(hit.prim) {
                Some(s) if matches!(s.shape, AnalyticShape::SdfVoxel(_)) => {
                    HitAttributes::default()
                }
                _ => analytic_attributes(hit),
            },
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
        if prim >= self.triangles.len() {
            return self.analytic_surface(hit);
        }
        let ng = self.normals[prim];
        let point = SurfacePoint::on_triangle(&self.triangles[prim].v, hit.b1, hit.b2, ng);
        let material = self.material_of[prim];
        let Some((inst, mesh, idx)) = self.mesh_of(hit.prim) else {
            return SurfaceHit {
                point,
                ng,
                ns: ng,
                ni: ng,
                nc: ng,
                tangent: Vec3A::ZERO,
                bitangent: Vec3A::ZERO,
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
        let interpolated = ns;
        let m = &self.materials[material as usize];
        if let MaterialKind::Textured(t) = &m.kind
            && t.needs_frame()
        {
            let uvs = (!mesh.uvs[0].is_empty()).then(|| idx.map(|i| mesh.uvs[0][i as usize]));
            let (dp_du, dp_dv) = triangle_derivatives(&self.triangles[prim].v, uvs, ng);
            let (n, s, tb) =
                mitsuba_frame(t, dp_du, dp_dv, ng, interpolated, &attrs, &self.textures);
            return SurfaceHit {
                point,
                ng,
                ns: n,
                ni: interpolated,
                nc: n,
                tangent: s,
                bitangent: tb,
                attrs,
                material,
            };
        }
        if let Some(mapped) = m.mapped_normal(&attrs, &self.textures)
            && let Some(n) = tangent_to_world(inst, mesh, idx, hit, b, interpolated, mapped)
        {
            ns = n;
        }
        let mut nc = ns;
        if m.has_coat() {
            nc = interpolated;
            if let Some(mapped) = m.mapped_coat_normal(&attrs, &self.textures)
                && let Some(n) = tangent_to_world(inst, mesh, idx, hit, b, interpolated, mapped)
            {
                nc = n;
            }
        }
        let (mut tangent, mut bitangent) = (Vec3A::ZERO, Vec3A::ZERO);
        if m.has_anisotropy()
            && let Some((t, b)) = tangent_frame(inst, mesh, idx, hit, b, interpolated)
        {
            (tangent, bitangent) = (t, b);
        }
        SurfaceHit {
            point,
            ng,
            ns,
            ni: interpolated,
            nc,
            tangent,
            bitangent,
            attrs,
            material,
        }
    }
}

impl Scene {
    /// [`Scene::surface`] of an analytic shape's hit: the point and normal
    /// from its coordinates `(u, v)`, which are also its texture
    /// coordinates, and Mitsuba's frame from the shape's `∂p/∂u`.
    #[cold]
    #[inline(never)]
    fn analytic_surface(&self, hit: &Hit) -> SurfaceHit {
        let uv = Vec2::new(hit.b1, hit.b2);
        let material = self
            .material_of
            .get(hit.prim as usize)
            .copied()
            .unwrap_or(0);
        let Some(shape) = self.shape_of(hit.prim) else {
            let point = SurfacePoint {
                p: Vec3A::ZERO,
                error: Vec3A::ZERO,
                n: Vec3A::Z,
            };
            return SurfaceHit {
                point,
                ng: Vec3A::Z,
                ns: Vec3A::Z,
                ni: Vec3A::Z,
                nc: Vec3A::Z,
                tangent: Vec3A::ZERO,
                bitangent: Vec3A::ZERO,
                attrs: HitAttributes::default(),
                material,
            };
        };
        let point = shape.front_point(uv);
        let ng = point.n;
        let (attrs, ni) = match &shape.shape {
            // A grid cell: no texture coordinates (Mitsuba's are (0, 0)), and
            // Mitsuba's smooth normal where asked for.
            AnalyticShape::SdfVoxel(v) => (HitAttributes::default(), self.sdf_normal(v, uv, ng)),
            _ => (analytic_attributes(hit), ng),
        };
        let (mut ns, mut tangent, mut bitangent) = (ni, Vec3A::ZERO, Vec3A::ZERO);
        if let Some(m) = self.materials.get(material as usize)
            && let MaterialKind::Textured(t) = &m.kind
            && t.needs_frame()
        {
            let (dp_du, dp_dv) = shape.shape.derivatives(uv);
            (ns, tangent, bitangent) =
                mitsuba_frame(t, dp_du, dp_dv, ng, ni, &attrs, &self.textures);
        }
        SurfaceHit {
            point,
            ng,
            ns,
            ni,
            nc: ns,
            tangent,
            bitangent,
            attrs,
            material,
        }
    }
}

impl Scene {
    /// The interpolated normal of a grid cell's hit with coordinates `code`
    /// and geometric normal `ng`: Mitsuba's `smooth` normal (see
    /// [`SdfGrid::smooth_normal`](crate::geometry::sdfgrid::SdfGrid::smooth_normal))
    /// where the cell asks for it, else `ng` (`analytic`).
    fn sdf_normal(&self, v: &SdfVoxel, code: Vec2, ng: Vec3A) -> Vec3A {
        if !v.smooth {
            return ng;
        }
        let Some(grid) = self.shapes.grid(v.grid) else {
            return ng;
        };
        let n = v.normal(grid.smooth_normal(v.object_point(code)));
        if n.is_finite() && n != Vec3A::ZERO {
            n
        } else {
            ng
        }
    }
}

/// An analytic shape's hit's attributes: its coordinates `(u, v)` as
/// texture coordinates (both sets), white.
#[inline]
fn analytic_attributes(hit: &Hit) -> HitAttributes {
    let uv = Vec2::new(hit.b1, hit.b2);
    HitAttributes {
        uv: [uv, uv],
        ..HitAttributes::default()
    }
}

/// `∂p/∂u` and `∂p/∂v` of the triangle of world vertices `v` with texture
/// coordinates `uvs` (if the mesh has them), or Mitsuba's
/// `coordinate_system` of the face normal `ng` where they are missing or
/// degenerate.
#[inline]
fn triangle_derivatives(v: &[Vec3A; 3], uvs: Option<[Vec2; 3]>, ng: Vec3A) -> (Vec3A, Vec3A) {
    let (e1, e2) = (v[1] - v[0], v[2] - v[0]);
    let fallback = Frame::from_normal(ng);
    let (mut dp_du, mut dp_dv) = (fallback.t, fallback.b);
    if let Some(uv) = uvs {
        let (d0, d1) = (uv[1] - uv[0], uv[2] - uv[0]);
        let det = d0.x * d1.y - d0.y * d1.x;
        if det != 0.0 {
            let inv = 1.0 / det;
            dp_du = (d1.y * e1 - d0.y * e2) * inv;
            dp_dv = (d0.x * e2 - d1.x * e1) * inv;
        }
    }
    (dp_du, dp_dv)
}

/// Mitsuba's shading frame at a hit of a Mitsuba material (`t`) with
/// surface derivatives `dp_du`, `dp_dv`, front geometric normal `ng` and
/// interpolated normal `ni`: its `s` is `∂p/∂u` made orthogonal to `ni`,
/// `t = ni × s`; its normal is `ni`, or what the material's normal or bump
/// map makes of it (Mitsuba 3.7.1's `normalmap` and `bumpmap` before their
/// view-dependent flip, which the integrator makes). Returns the normal,
/// `s` and `t`.
#[inline(never)]
fn mitsuba_frame(
    t: &TexturedBsdf,
    dp_du: Vec3A,
    dp_dv: Vec3A,
    ng: Vec3A,
    ni: Vec3A,
    attrs: &HitAttributes,
    textures: &TextureStore,
) -> (Vec3A, Vec3A, Vec3A) {
    let s = (dp_du - ni * ni.dot(dp_du)).normalize_or_zero();
    let s = if s != Vec3A::ZERO && s.is_finite() {
        s
    } else {
        Frame::from_normal(ni).t
    };
    let tb = ni.cross(s);
    let n = match t.perturb.as_ref().map(|p| &p.map) {
        None => ni,
        Some(PerturbMap::NormalMap(p)) => {
            let c = p.eval(attrs.uv[0], attrs.color, textures);
            let m = Vec3A::from(c.xyz()) * 2.0 - Vec3A::ONE;
            (m.x * s + m.y * tb + m.z * ni).normalize_or_zero()
        }
        Some(PerturbMap::BumpMap { height, scale }) => {
            let (gu, gv) = height.gradient(attrs.uv[0], textures);
            let (gu, gv) = (
                scale * mitsuba_luminance(gu.xyz()),
                scale * mitsuba_luminance(gv.xyz()),
            );
            let du = dp_du + ni * (gu - ni.dot(dp_du));
            let dv = dp_dv + ni * (gv - ni.dot(dp_dv));
            let n = du.cross(dv).normalize_or_zero();
            if n.dot(ng) < 0.0 { -n } else { n }
        }
    };
    let n = if n != Vec3A::ZERO && n.is_finite() {
        n
    } else {
        ni
    };
    (n, s, tb)
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

/// A normal map's tangent-space normal `mapped` at hit `hit` (barycentrics
/// `b`) of `mesh`'s triangle `idx`, in world space about the interpolated
/// normal `n`; `None` without tangents or where the result is degenerate.
#[inline]
fn tangent_to_world(
    inst: &Instance,
    mesh: &MeshData,
    idx: [u32; 3],
    hit: &Hit,
    b: [f32; 3],
    n: Vec3A,
    mapped: Vec3A,
) -> Option<Vec3A> {
    let (t, bitangent) = tangent_frame(inst, mesh, idx, hit, b, n)?;
    let mapped = (mapped.x * t + mapped.y * bitangent + mapped.z * n).normalize_or_zero();
    (mapped != Vec3A::ZERO && mapped.is_finite()).then_some(mapped)
}

/// The unit tangent and bitangent in world space at hit `hit` (barycentrics
/// `b`) of `mesh`'s triangle `idx`, about the interpolated normal `n`: the
/// tangent orthogonalized against `n`, the bitangent `w (n × t)` (glTF's
/// `TANGENT.w`, negated by a mirroring instance); `None` without tangents
/// or where the tangent is degenerate.
#[inline]
fn tangent_frame(
    inst: &Instance,
    mesh: &MeshData,
    idx: [u32; 3],
    hit: &Hit,
    b: [f32; 3],
    n: Vec3A,
) -> Option<(Vec3A, Vec3A)> {
    let local = (hit.prim - inst.first_triangle) as usize;
    let tangent = match &mesh.tangents {
        Tangents::PerVertex(t) => interpolate(b, idx.map(|i| t[i as usize])),
        Tangents::PerCorner(t) => interpolate(b, t[local]),
        Tangents::None => return None,
    };
    let sign = if inst.mirrors { -tangent.w } else { tangent.w };
    let t = inst.to_world.matrix3 * Vec3A::from(tangent.truncate());
    // Gram–Schmidt against the interpolated normal.
    let t = (t - n * n.dot(t)).normalize_or_zero();
    if t == Vec3A::ZERO {
        return None;
    }
    Some((t, sign.signum() * n.cross(t)))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// [`mitsuba_frame`] of a triangle's derivatives.
    fn mitsuba_frame_of(
        t: &TexturedBsdf,
        v: &[Vec3A; 3],
        uvs: Option<[Vec2; 3]>,
        ng: Vec3A,
        ni: Vec3A,
        attrs: &HitAttributes,
        textures: &TextureStore,
    ) -> (Vec3A, Vec3A, Vec3A) {
        let (du, dv) = triangle_derivatives(v, uvs, ng);
        mitsuba_frame(t, du, dv, ng, ni, attrs, textures)
    }

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

    /// A Mitsuba material with `perturb` (and a diffuse BSDF).
    fn textured(perturb: Option<PerturbMap>) -> TexturedBsdf {
        let mut t = TexturedBsdf::new(crate::materials::Material::Diffuse {
            reflectance: Vec3A::splat(0.5),
        });
        t.perturb = perturb.map(|map| crate::materials::surface::Perturb {
            map,
            flip_invalid: true,
            shadowing: true,
        });
        t
    }

    /// Mitsuba's frame on a triangle with texture coordinates: `s` along
    /// `∂p/∂u` (here `(2, 0, 0)` per unit of u, with `∂p/∂v = (0, 3, 0)`),
    /// made orthogonal to a tilted interpolated normal; a flat normal map
    /// leaves the normal alone; without texture coordinates `s` is the
    /// first axis of `coordinate_system(ng)`.
    #[test]
    fn mitsuba_frame_follows_dp_du() {
        use crate::textures::Pattern;
        let v = [
            Vec3A::ZERO,
            Vec3A::new(2.0, 0.0, 0.0),
            Vec3A::new(0.0, 3.0, 0.0),
        ];
        let uvs = Some([Vec2::ZERO, Vec2::X, Vec2::Y]);
        let ng = Vec3A::Z;
        let ni = Vec3A::new(0.3, 0.0, 1.0).normalize();
        let store = TextureStore::new();
        let attrs = HitAttributes::default();
        let flat = textured(Some(PerturbMap::NormalMap(Pattern::Constant(Vec4::new(
            0.5, 0.5, 1.0, 1.0,
        )))));
        let (n, s, t) = mitsuba_frame_of(&flat, &v, uvs, ng, ni, &attrs, &store);
        assert!((n - ni).length() < 1e-6, "{n}");
        // (2, 0, 0) − ni (ni · (2, 0, 0)), normalized.
        let expect = (Vec3A::X - ni * ni.x).normalize();
        assert!((s - expect).length() < 1e-6, "{s} vs {expect}");
        assert!((t - ni.cross(expect)).length() < 1e-6);
        // A normal map's (1, 0.5, 0.5) is the frame's +s: tilted 90°.
        let sideways = textured(Some(PerturbMap::NormalMap(Pattern::Constant(Vec4::new(
            1.0, 0.5, 0.5, 1.0,
        )))));
        let (n, ..) = mitsuba_frame_of(&sideways, &v, uvs, ng, ni, &attrs, &store);
        assert!((n - expect).length() < 1e-6, "{n}");
        // Without texture coordinates: Duff et al.'s first axis of ng.
        let (_, s, _) = mitsuba_frame_of(&textured(None), &v, None, ng, ng, &attrs, &store);
        assert!((s - Frame::from_normal(ng).t).length() < 1e-6, "{s}");
    }

    /// A bump map's normal is the analytic one of the displaced surface: a
    /// height rising linearly along u (a 2 × 1 image from 0 to 1 between its
    /// texel centres: ∂h/∂u = 2) scaled by 0.25 on the triangle of
    /// `∂p/∂u = (2, 0, 0)`, `∂p/∂v = (0, 3, 0)` gives
    /// `(2, 0, 0.5) × (0, 3, 0) ∝ (−1.5, 0, 6)`.
    #[test]
    fn bump_map_normal_is_the_displaced_surfaces() {
        use crate::textures::{ColorSpace, Image, Pattern, Wrap};
        use glam::Affine2;
        let mut store = TextureStore::new();
        let id = store.push(Image::from_u8(2, 1, 1, vec![0, 255]));
        let height = Pattern::Image {
            image: id,
            wrap: Wrap::ClampToEdge,
            nearest: false,
            space: ColorSpace::Linear,
            to_uv: Affine2::IDENTITY,
        };
        let bump = textured(Some(PerturbMap::BumpMap {
            height,
            scale: 0.25,
        }));
        let v = [
            Vec3A::ZERO,
            Vec3A::new(2.0, 0.0, 0.0),
            Vec3A::new(0.0, 3.0, 0.0),
        ];
        let uvs = Some([Vec2::ZERO, Vec2::X, Vec2::Y]);
        let mut attrs = HitAttributes::default();
        attrs.uv[0] = Vec2::new(0.5, 0.5);
        let (n, ..) = mitsuba_frame_of(&bump, &v, uvs, Vec3A::Z, Vec3A::Z, &attrs, &store);
        let expect = Vec3A::new(-1.5, 0.0, 6.0).normalize();
        assert!((n - expect).length() < 1e-5, "{n} vs {expect}");
    }
}
