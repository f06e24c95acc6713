//! One cell of a placed signed distance grid ([`SdfVoxel`]): the
//! primitive an `sdfgrid` becomes in the scene's hierarchy of analytic
//! shapes, one per cell the surface may cross (as Mitsuba makes one
//! primitive per occupied voxel). It carries its eight corner values and
//! the grid's placement, so its ray test needs nothing else: the ray goes
//! to object space and then to the cell's units in double precision (the
//! same arithmetic for every cell of the grid, so neighbours agree on their
//! shared faces), and [`first_crossing`] finds the exact root.
//!
//! A hit's two coordinates (the `(u, v)` an analytic shape's hit carries)
//! encode the point in the cell, since an `sdfgrid` has no texture
//! coordinates of its own (Mitsuba gives `(0, 0)`): the axis `a` along
//! which the interpolant changes fastest at the hit, and the point's two
//! other cell coordinates, as `(2a + q[a+1], q[a+2])`. The point is rebuilt
//! from them on the surface itself: along axis `a` the interpolant is
//! linear, so its zero there is one division, well conditioned because
//! that axis's derivative is the largest.

use glam::{DVec3, Vec2, Vec3A};

use super::placement::Placement;
use super::ray::{Ray, SurfacePoint, gamma};
use super::sdfgrid::{first_crossing, trilinear, trilinear_gradient};

/// A cell of a signed distance grid placed in the world.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SdfVoxel {
    /// The grid's object space (the unit cube) to the world.
    pub placement: Placement,
    /// The cell's corner values, indexed `x + 2y + 4z`.
    pub corners: [f32; 8],
    /// The cell's lower corner, in samples.
    pub cell: [u32; 3],
    /// The grid's cells along each axis (samples − 1).
    pub cells: [u32; 3],
    /// Which grid of the scene the cell belongs to (for smooth normals).
    pub grid: u32,
    /// Whether shading uses Mitsuba's `smooth` normals (else `analytic`).
    pub smooth: bool,
}

impl SdfVoxel {
    /// The grid's cells per object unit along each axis.
    #[inline]
    fn scale(&self) -> DVec3 {
        DVec3::new(
            f64::from(self.cells[0]),
            f64::from(self.cells[1]),
            f64::from(self.cells[2]),
        )
    }

    /// The cell's lower corner, in cell units.
    #[inline]
    fn lower(&self) -> DVec3 {
        DVec3::new(
            f64::from(self.cell[0]),
            f64::from(self.cell[1]),
            f64::from(self.cell[2]),
        )
    }

    /// `ray` in the cell's units: origin and direction (`t` unchanged).
    #[inline]
    fn ray_to_cell(&self, ray: &Ray) -> (DVec3, DVec3) {
        let (o, d) = self.placement.ray_to_object(ray);
        let scale = self.scale();
        (o * scale - self.lower(), d * scale)
    }

    /// The ray parameter of the ray's first crossing of the surface in the
    /// cell, in `(0, t_max]`.
    #[inline]
    pub fn intersect(&self, ray: &Ray, t_max: f32) -> Option<f32> {
        let (o, d) = self.ray_to_cell(ray);
        let t = first_crossing(&self.corners, o, d, f64::from(t_max))? as f32;
        (t > 0.0 && t <= t_max).then_some(t)
    }

    /// The hit's coordinates (see the module) of the point at `t` along
    /// `ray`.
    #[inline]
    pub fn hit_code(&self, ray: &Ray, t: f32) -> Vec2 {
        let (o, d) = self.ray_to_cell(ray);
        let q = (o + d * f64::from(t)).clamp(DVec3::ZERO, DVec3::ONE);
        encode(&self.corners, q)
    }

    /// The point in cell units that the coordinates `code` name, on the
    /// surface.
    #[inline]
    pub fn cell_point(&self, code: Vec2) -> DVec3 {
        decode(&self.corners, code)
    }

    /// The object-space point (in the grid's unit cube) of `code`.
    #[inline]
    pub fn object_point(&self, code: Vec2) -> DVec3 {
        (self.lower() + self.cell_point(code)) / self.scale()
    }

    /// The world point of `code` with its error bound and the unit normal
    /// of the interpolant's gradient (Mitsuba's `analytic` normal: the
    /// outside, where the distance is positive).
    #[inline]
    pub fn point_at(&self, code: Vec2) -> SurfacePoint {
        let q = self.cell_point(code);
        let local = (self.lower() + q) / self.scale();
        // The point is on the surface to f64 rounding; the slack covers the
        // rounding of the division into object units.
        let (p, error) = self.placement.point(local, gamma(1));
        let g = trilinear_gradient(&self.corners, q) * self.scale();
        SurfacePoint {
            p,
            error,
            n: self.placement.normal(g.as_vec3a()),
        }
    }

    /// The world normal of an object-space normal `n`.
    #[inline]
    pub fn normal(&self, n: DVec3) -> Vec3A {
        self.placement.normal(n.as_vec3a())
    }

    /// Axis-aligned world bounds of the cell, widened by the rounding of
    /// its corners.
    pub fn bounds(&self) -> (Vec3A, Vec3A) {
        let (mut lo, mut hi) = (Vec3A::splat(f32::INFINITY), Vec3A::splat(f32::NEG_INFINITY));
        for i in 0..8usize {
            let corner = DVec3::new((i & 1) as f64, ((i >> 1) & 1) as f64, (i >> 2) as f64);
            let (p, error) = self
                .placement
                .point((self.lower() + corner) / self.scale(), gamma(2));
            lo = lo.min(p - error);
            hi = hi.max(p + error);
        }
        (lo, hi)
    }

    /// Whether the placement and the corner values are finite.
    pub fn is_finite(&self) -> bool {
        let (lo, hi) = self.bounds();
        lo.is_finite()
            && hi.is_finite()
            && self.corners.iter().all(|c| c.is_finite())
            && self.cells.iter().all(|&n| n > 0)
            && (0..3).all(|a| self.cell[a] < self.cells[a])
    }
}

/// The coordinates of the point `q` (cell units) in the cell of corner
/// values `c`: `(2a + q[b], q[c])` with `a` the axis of the gradient's
/// largest component and `b`, `c` the axes after it.
fn encode(c: &[f32; 8], q: DVec3) -> Vec2 {
    let g = trilinear_gradient(c, q).abs();
    let a = if g.x >= g.y && g.x >= g.z {
        0
    } else if g.y >= g.z {
        1
    } else {
        2
    };
    let (b, cc) = ((a + 1) % 3, (a + 2) % 3);
    Vec2::new((2 * a) as f32 + q[b] as f32, q[cc] as f32)
}

/// The point (cell units) that [`encode`] gave `code`: its two coordinates
/// as given, the third the zero of the interpolant along its axis (linear
/// there), clamped into the cell.
fn decode(c: &[f32; 8], code: Vec2) -> DVec3 {
    let a = ((code.x * 0.5).floor().clamp(0.0, 2.0)) as usize;
    let (b, cc) = ((a + 1) % 3, (a + 2) % 3);
    let mut q = DVec3::ZERO;
    q[b] = (f64::from(code.x) - (2 * a) as f64).clamp(0.0, 1.0);
    q[cc] = f64::from(code.y).clamp(0.0, 1.0);
    q[a] = 0.0;
    let f0 = trilinear(c, q);
    q[a] = 1.0;
    let f1 = trilinear(c, q);
    q[a] = if f0 != f1 {
        (f0 / (f0 - f1)).clamp(0.0, 1.0)
    } else {
        0.5
    };
    q
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::sdfgrid::SdfGrid;
    use crate::sampling::sampler::Rng;
    use glam::{Mat3A, Vec3};

    /// A grid of `n³` samples of a sphere's signed distance (centre 0.5,
    /// radius `r`, in object units).
    fn sphere_grid(n: u32, r: f64) -> SdfGrid {
        let mut v = Vec::new();
        for z in 0..n {
            for y in 0..n {
                for x in 0..n {
                    let p = DVec3::new(f64::from(x), f64::from(y), f64::from(z)) / f64::from(n - 1);
                    v.push(((p - DVec3::splat(0.5)).length() - r) as f32);
                }
            }
        }
        SdfGrid::new([n; 3], v).unwrap()
    }

    fn voxels(grid: &SdfGrid, placement: Placement) -> Vec<SdfVoxel> {
        let res = grid.resolution();
        grid.surface_cells()
            .map(|cell| SdfVoxel {
                placement,
                corners: grid.corners(cell),
                cell,
                cells: res.map(|n| n - 1),
                grid: 0,
                smooth: false,
            })
            .collect()
    }

    fn closest(voxels: &[SdfVoxel], ray: &Ray) -> Option<(f32, usize)> {
        voxels
            .iter()
            .enumerate()
            .filter_map(|(k, v)| v.intersect(ray, f32::INFINITY).map(|t| (t, k)))
            .min_by(|a, b| a.0.total_cmp(&b.0))
    }

    /// A grid of a sphere's distances (40³, radius 0.3, placed by a
    /// rotation, an uneven scale and a translation) is hit within the
    /// interpolation's error of the true sphere: trilinear interpolation of
    /// the distance to a sphere of radius R with cells of size h is off by
    /// at most about h²/(2R) (the distance's curvature 1/R over half a
    /// cell), here 1.1e-3 object units; the rebuilt points lie on the
    /// interpolated surface and the normals are the sphere's to the same
    /// order (h/R).
    #[test]
    fn a_sphere_grid_is_hit_on_the_sphere() {
        let (n, radius) = (40u32, 0.3);
        let grid = sphere_grid(n, radius);
        let linear = Mat3A::from_rotation_z(0.4)
            * Mat3A::from_rotation_x(-0.7)
            * Mat3A::from_diagonal(Vec3::new(2.0, 3.0, 1.5));
        let placement = Placement::new(linear, Vec3A::new(1.0, -2.0, 0.5)).unwrap();
        let cells = voxels(&grid, placement);
        assert!(cells.len() > 1000, "{}", cells.len());
        let h = 1.0 / f64::from(n - 1);
        let bound = h * h / (2.0 * radius) + 1e-6;
        let centre = placement.point(DVec3::splat(0.5), 0.0).0;
        let mut rng = Rng::new(21, 2);
        let mut hits = 0;
        for _ in 0..400 {
            let mut r = || rng.next_f32() * 2.0 - 1.0;
            let target = centre + Vec3A::new(r(), r(), r()) * 0.6;
            let origin = centre + Vec3A::new(r(), r(), r()).normalize_or(Vec3A::X) * 8.0;
            let ray = Ray::new(origin, (target - origin).normalize());
            let Some((t, k)) = closest(&cells, &ray) else {
                continue;
            };
            hits += 1;
            let v = &cells[k];
            let local = placement.point_to_object(ray.at(t));
            let off = (local - DVec3::splat(0.5)).length() - radius;
            assert!(off.abs() < bound + 1e-5, "hit {off} off the sphere");
            // The rebuilt point: on the interpolated surface, near the hit.
            let code = v.hit_code(&ray, t);
            let q = v.cell_point(code);
            assert!(trilinear(&v.corners, q).abs() < 1e-6, "{q}");
            let sp = v.point_at(code);
            assert!(
                (sp.p - ray.at(t)).length() < 1e-4,
                "{} vs {}",
                sp.p,
                ray.at(t)
            );
            // The analytic normal: the sphere's (mapped by the inverse
            // transpose), to first order in h.
            let radial = placement.normal((local - DVec3::splat(0.5)).as_vec3a());
            assert!(sp.n.dot(radial) > 0.99, "{} vs {radial}", sp.n);
            let smooth = v.normal(grid.smooth_normal(v.object_point(code)));
            assert!(smooth.dot(radial) > 0.995, "{smooth} vs {radial}");
        }
        assert!(hits > 150, "{hits}");
        // Rays that pass the sphere by more than the bound miss every cell.
        for k in 0..50 {
            let y = 0.3 + bound + 0.01 + 0.001 * f64::from(k);
            let o = placement.point(DVec3::new(-1.0, 0.5 + y, 0.5), 0.0).0;
            let e = placement.point(DVec3::new(2.0, 0.5 + y, 0.5), 0.0).0;
            assert_eq!(closest(&cells, &Ray::new(o, (e - o).normalize())), None);
        }
    }

    /// The world normal of a hit is the direction of the world gradient of
    /// the placed interpolant, by central differences of the function of
    /// world points (through the placement's inverse), under an uneven,
    /// sheared placement.
    #[test]
    fn the_world_normal_is_the_placed_fields_gradient() {
        let mut rng = Rng::new(12, 4);
        let linear = Mat3A::from_cols(
            Vec3A::new(2.0, 0.3, 0.0),
            Vec3A::new(0.5, 1.2, -0.4),
            Vec3A::new(0.1, 0.0, 3.0),
        );
        let placement = Placement::new(linear, Vec3A::new(-1.0, 2.0, 0.5)).unwrap();
        let mut checked = 0;
        while checked < 300 {
            let corners: [f32; 8] = std::array::from_fn(|_| rng.next_f32() * 2.0 - 1.0);
            let v = SdfVoxel {
                placement,
                corners,
                cell: [3, 1, 2],
                cells: [7, 5, 9],
                grid: 0,
                smooth: false,
            };
            let mut r = || f64::from(rng.next_f32());
            let q = DVec3::new(r(), r(), r()) * 0.8 + 0.1;
            let local = (v.lower() + q) / v.scale();
            let world = placement.point(local, 0.0).0.as_dvec3();
            let field = |w: DVec3| {
                let o = placement.point_to_object(w.as_vec3a());
                trilinear(&corners, o * v.scale() - v.lower())
            };
            let h = 1e-3;
            let fd = DVec3::new(
                field(world + DVec3::X * h) - field(world - DVec3::X * h),
                field(world + DVec3::Y * h) - field(world - DVec3::Y * h),
                field(world + DVec3::Z * h) - field(world - DVec3::Z * h),
            ) / (2.0 * h);
            if fd.length() < 0.05 {
                continue;
            }
            let n = v.point_at(encode(&corners, q)).n.as_dvec3();
            // (The coordinates name the point on the surface nearest q
            // along one axis: compare where the gradient is taken.)
            let at = v.cell_point(encode(&corners, q));
            let g = trilinear_gradient(&corners, at) * v.scale();
            let want = placement.normal(g.as_vec3a()).as_dvec3();
            assert!((n - want).length() < 1e-6, "{n} vs {want}");
            let at_q = placement
                .normal((trilinear_gradient(&corners, q) * v.scale()).as_vec3a())
                .as_dvec3();
            assert!(
                (at_q - fd.normalize()).length() < 1e-3,
                "{at_q} vs {}",
                fd.normalize()
            );
            checked += 1;
        }
    }

    /// Coordinates name the point they were made from: the rebuilt point is
    /// on the surface and within the coordinates' rounding of the original.
    #[test]
    fn hit_coordinates_round_trip() {
        let mut rng = Rng::new(6, 1);
        let mut checked = 0;
        while checked < 2000 {
            let c: [f32; 8] = std::array::from_fn(|_| rng.next_f32() * 2.0 - 1.0);
            let mut r = || f64::from(rng.next_f32());
            let o = DVec3::new(r(), r(), r()) * 3.0 - 1.0;
            let d = DVec3::new(r(), r(), r()) - 0.5;
            let Some(t) = first_crossing(&c, o, d, f64::INFINITY) else {
                continue;
            };
            let q = (o + t * d).clamp(DVec3::ZERO, DVec3::ONE);
            let back = decode(&c, encode(&c, q));
            assert!((back - q).length() < 1e-5, "{q} vs {back}");
            assert!(trilinear(&c, back).abs() < 1e-12 || (back - q).length() < 1e-6);
            checked += 1;
        }
    }

    /// Rays spawned off hit points (offset by the error bound, either way)
    /// do not find the cell's surface again at once.
    #[test]
    fn spawned_rays_leave_the_surface() {
        let grid = sphere_grid(16, 0.35);
        let placement = Placement::new(
            Mat3A::from_diagonal(Vec3::splat(5.0)),
            Vec3A::new(3.0, 1.0, -2.0),
        )
        .unwrap();
        let cells = voxels(&grid, placement);
        let centre = placement.point(DVec3::splat(0.5), 0.0).0;
        let mut rng = Rng::new(9, 9);
        let mut tested = 0;
        for _ in 0..3000 {
            let mut r = || rng.next_f32() * 2.0 - 1.0;
            let origin = centre + Vec3A::new(r(), r(), r()).normalize_or(Vec3A::X) * 10.0;
            let target = centre + Vec3A::new(r(), r(), r());
            let ray = Ray::new(origin, (target - origin).normalize());
            let Some((t, k)) = closest(&cells, &ray) else {
                continue;
            };
            let sp = cells[k].point_at(cells[k].hit_code(&ray, t));
            // Out of the convex surface: nothing ahead at all.
            let out = (Vec3A::new(r(), r(), r()).normalize_or(Vec3A::X) + 1.5 * sp.n).normalize();
            let spawned = Ray::new(sp.offset_origin(out), out);
            assert_eq!(closest(&cells, &spawned), None, "{sp:?} {out}");
            tested += 1;
        }
        assert!(tested > 500, "{tested}");
    }
}
