//! The lab's Cornell box (the course's `TestModel`), exactly: 30 triangles in a
//! box filling `[-1, 1]³` with y pointing down and no front wall.

use glam::Vec3A;

use crate::scene::{PointLight, Scene};
use crate::triangle::Triangle;

/// Side of the box in the lab's model units before normalisation.
const L: f32 = 555.0;

/// Reflectances of the lab's surfaces.
pub mod colors {
    use glam::Vec3A;
    /// Floor.
    pub const GREEN: Vec3A = Vec3A::new(0.15, 0.75, 0.15);
    /// Left wall.
    pub const PURPLE: Vec3A = Vec3A::new(0.75, 0.15, 0.75);
    /// Right wall.
    pub const YELLOW: Vec3A = Vec3A::new(0.75, 0.75, 0.15);
    /// Ceiling.
    pub const CYAN: Vec3A = Vec3A::new(0.15, 0.75, 0.75);
    /// Back wall.
    pub const WHITE: Vec3A = Vec3A::new(0.75, 0.75, 0.75);
    /// Short block.
    pub const RED: Vec3A = Vec3A::new(0.75, 0.15, 0.15);
    /// Tall block.
    pub const BLUE: Vec3A = Vec3A::new(0.15, 0.15, 0.75);
}

/// The lab's default light position.
pub const LIGHT_POSITION: Vec3A = Vec3A::new(0.0, -0.5, -0.7);
/// The lab's light power per channel.
pub const LIGHT_POWER: f32 = 14.0;
/// The lab's ambient term.
pub const AMBIENT: f32 = 0.5;
/// The lab's camera position.
pub const CAMERA_POSITION: Vec3A = Vec3A::new(0.0, 0.0, -3.0);

/// Corners of `cornell-area`'s ceiling light, just below the ceiling, in the
/// order that makes its lab normal point down into the box (+y).
pub const AREA_LIGHT_CORNERS: [Vec3A; 4] = [
    Vec3A::new(-0.24, -0.999, -0.19),
    Vec3A::new(0.24, -0.999, -0.19),
    Vec3A::new(0.24, -0.999, 0.19),
    Vec3A::new(-0.24, -0.999, 0.19),
];
/// Radiance of `cornell-area`'s ceiling light.
pub const AREA_LIGHT_RADIANCE: Vec3A = Vec3A::new(17.0, 12.0, 4.0);

/// Triangle index ranges of the named parts, in scene order.
pub mod parts {
    use std::ops::Range;
    /// The floor.
    pub const FLOOR: Range<usize> = 0..2;
    /// The left wall (purple, at x = −1).
    pub const LEFT_WALL: Range<usize> = 2..4;
    /// The right wall (yellow, at x = +1).
    pub const RIGHT_WALL: Range<usize> = 4..6;
    /// The ceiling.
    pub const CEILING: Range<usize> = 6..8;
    /// The back wall.
    pub const BACK_WALL: Range<usize> = 8..10;
    /// `cornell-area`'s ceiling light (after the box's 30 triangles).
    pub const AREA_LIGHT: Range<usize> = 30..32;
    /// The room: floor, walls, ceiling.
    pub const ROOM: Range<usize> = 0..10;
    /// The short (red) block.
    pub const SHORT_BLOCK: Range<usize> = 10..20;
    /// The tall (blue) block.
    pub const TALL_BLOCK: Range<usize> = 20..30;
}

/// The box's triangles and their reflectances, in the lab's order.
pub fn triangles() -> (Vec<Triangle>, Vec<Vec3A>) {
    let v = |x: f32, y: f32, z: f32| Vec3A::new(x, y, z);
    let mut tris = Vec::with_capacity(30);
    let mut rho = Vec::with_capacity(30);
    let mut push = |a: Vec3A, b: Vec3A, c: Vec3A, color: Vec3A| {
        tris.push(Triangle::new(normalise(a), normalise(b), normalise(c)));
        rho.push(color);
    };

    let (a, b, c, d) = (v(L, 0., 0.), v(0., 0., 0.), v(L, 0., L), v(0., 0., L));
    let (e, f, g, h) = (v(L, L, 0.), v(0., L, 0.), v(L, L, L), v(0., L, L));
    push(c, b, a, colors::GREEN);
    push(c, d, b, colors::GREEN);
    push(a, e, c, colors::PURPLE);
    push(c, e, g, colors::PURPLE);
    push(f, b, d, colors::YELLOW);
    push(h, f, d, colors::YELLOW);
    push(e, f, g, colors::CYAN);
    push(f, h, g, colors::CYAN);
    push(g, d, c, colors::WHITE);
    push(g, h, d, colors::WHITE);

    let blocks = [
        (
            [(290., 114.), (130., 65.), (240., 272.), (82., 225.)],
            165.0,
            colors::RED,
        ),
        (
            [(423., 247.), (265., 296.), (472., 406.), (314., 456.)],
            330.0,
            colors::BLUE,
        ),
    ];
    for (base, height, color) in blocks {
        let [a, b, c, d] = base.map(|(x, z)| v(x, 0.0, z));
        let [e, f, g, h] = base.map(|(x, z)| v(x, height, z));
        for (p, q, r) in [
            (e, b, a),
            (e, f, b),
            (f, d, b),
            (f, h, d),
            (h, c, d),
            (h, g, c),
            (g, e, c),
            (e, a, c),
            (g, f, e),
            (g, h, f),
        ] {
            push(p, q, r, color);
        }
    }
    (tris, rho)
}

/// Maps a lab model vertex into `[-1, 1]³` and flips x and y, as the lab does.
fn normalise(p: Vec3A) -> Vec3A {
    let q = p * (2.0 / L) - Vec3A::ONE;
    Vec3A::new(-q.x, -q.y, q.z)
}

/// The lab's scene: the box, the point light and the ambient term.
pub fn scene() -> Scene {
    let (tris, rho) = triangles();
    Scene::new(
        tris,
        rho,
        PointLight {
            position: LIGHT_POSITION,
            power: Vec3A::splat(LIGHT_POWER),
        },
        Vec3A::splat(AMBIENT),
    )
    .expect("the built-in box is valid")
}

/// `cornell-area`: the lab box with the point light replaced by the classic
/// ceiling patch ([`AREA_LIGHT_CORNERS`], triangles [`parts::AREA_LIGHT`]), which
/// emits [`AREA_LIGHT_RADIANCE`] from its lower side only and reflects nothing.
/// The point light is off (power 0); no ambient term.
pub fn area_scene() -> Scene {
    let (mut tris, mut rho) = triangles();
    push_area_light(&mut tris, &mut rho);
    let mut scene = Scene::new(
        tris,
        rho,
        PointLight {
            position: LIGHT_POSITION,
            power: Vec3A::ZERO,
        },
        Vec3A::ZERO,
    )
    .expect("the built-in box is valid");
    light_area_patch(&mut scene);
    scene
}

/// Appends the ceiling patch's two triangles (black) to a box's triangles.
pub fn push_area_light(tris: &mut Vec<Triangle>, rho: &mut Vec<Vec3A>) {
    let [a, b, c, d] = AREA_LIGHT_CORNERS;
    tris.extend([Triangle::new(a, b, c), Triangle::new(a, c, d)]);
    rho.extend([Vec3A::ZERO; 2]);
}

/// Makes the ceiling patch pushed by [`push_area_light`] emit.
pub fn light_area_patch(scene: &mut Scene) {
    for prim in parts::AREA_LIGHT {
        scene
            .set_emission(prim, AREA_LIGHT_RADIANCE)
            .expect("a valid radiance");
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_area_light_faces_down_and_covers_the_patch() {
        let scene = area_scene();
        assert_eq!(scene.triangles().len(), 32);
        let area: f32 = parts::AREA_LIGHT.map(|i| scene.triangles()[i].area()).sum();
        assert!((area - 0.48 * 0.38).abs() < 1e-6);
        for i in parts::AREA_LIGHT {
            assert!((scene.normal(i as u32) - Vec3A::Y).length() < 1e-6);
            assert_eq!(scene.emission(i as u32), AREA_LIGHT_RADIANCE);
            assert_eq!(scene.reflectance(i as u32), Vec3A::ZERO);
        }
        assert!(scene.has_lights());
        assert_eq!(scene.light.power, Vec3A::ZERO);
    }

    #[test]
    fn fills_the_unit_cube_with_outward_facing_surfaces_towards_the_camera() {
        let (tris, _) = triangles();
        assert_eq!(tris.len(), 30);
        // The named parts cover the room in order.
        assert_eq!(parts::FLOOR.start, parts::ROOM.start);
        assert_eq!(parts::BACK_WALL.end, parts::ROOM.end);
        assert!((tris[parts::CEILING.start].lab_normal() - Vec3A::Y).length() < 1e-6);
        assert!((tris[parts::RIGHT_WALL.start].lab_normal() + Vec3A::X).length() < 1e-6);
        let (mut lo, mut hi) = (Vec3A::splat(9.0), Vec3A::splat(-9.0));
        for t in &tris {
            lo = lo.min(t.min());
            hi = hi.max(t.max());
        }
        assert!((lo + Vec3A::ONE).abs().max_element() < 1e-6);
        assert!((hi - Vec3A::ONE).abs().max_element() < 1e-6);
        // Floor at y = +1 with its normal pointing up (-y, y points down).
        assert!((tris[0].v[0].y - 1.0).abs() < 1e-6);
        assert!((tris[0].lab_normal() - Vec3A::new(0.0, -1.0, 0.0)).length() < 1e-6);
        // Left wall (purple) at x = -1 faces +x, back wall at z = +1 faces -z.
        assert!((tris[2].lab_normal() - Vec3A::X).length() < 1e-6);
        assert!((tris[8].lab_normal() + Vec3A::Z).length() < 1e-6);
        // Every block face's normal points away from the block's centre.
        for range in [parts::SHORT_BLOCK, parts::TALL_BLOCK] {
            let centre = range
                .clone()
                .map(|i| (tris[i].v[0] + tris[i].v[1] + tris[i].v[2]) / 3.0)
                .sum::<Vec3A>()
                / 10.0;
            for i in range {
                let t = &tris[i];
                let mid = (t.v[0] + t.v[1] + t.v[2]) / 3.0;
                assert!(t.lab_normal().dot(mid - centre) > 0.0, "triangle {i}");
            }
        }
    }
}
