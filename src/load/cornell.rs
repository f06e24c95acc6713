//! The lab's Cornell box (the course's `TestModel`), exactly: 30 triangles in a
//! box filling `[-1, 1]³` with y pointing down and no front wall.

use glam::Vec3A;

use crate::geometry::triangle::Triangle;
use crate::materials::Material;
use crate::materials::surface::SurfaceMaterial;
use crate::scene::{PointLight, Scene, SceneParts};

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
/// Camera and light travel per key press in the lab box (2 units wide); other
/// scenes scale it with their size (see [`crate::controls::ViewState::step`]).
pub const LAB_STEP: f32 = 0.1;

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

/// The parts of the box that `--material` can name, with their triangles.
pub const PART_NAMES: [(&str, std::ops::Range<usize>); 7] = [
    ("floor", parts::FLOOR),
    ("ceiling", parts::CEILING),
    ("back", parts::BACK_WALL),
    ("left", parts::LEFT_WALL),
    ("right", parts::RIGHT_WALL),
    ("short", parts::SHORT_BLOCK),
    ("tall", parts::TALL_BLOCK),
];

/// The triangles of the part called `name` (see [`PART_NAMES`]).
pub fn part(name: &str) -> Option<std::ops::Range<usize>> {
    PART_NAMES
        .iter()
        .find(|(n, _)| *n == name)
        .map(|(_, r)| r.clone())
}

/// A material for a part of the box, by name: `diffuse` (the part's own
/// reflectance), `mirror`, `glass[:IOR]` (1.5 unless given), and the
/// conductors `gold`, `copper`, `silver`, `aluminium` and `conductor` (a perfect
/// one, Fresnel 1), each with an optional GGX width `:ALPHA` in `[0, 1]` (0, the
/// default, is polished: a delta lobe).
// (A command-line choice, read once: a `Material` as large as a Mitsuba
// blend is no cost here.)
#[allow(clippy::large_enum_variant)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum MaterialChoice {
    /// Lambertian with the part's reflectance.
    Diffuse,
    /// Anything else.
    Other(Material),
}

impl MaterialChoice {
    /// The names `parse` accepts.
    pub const NAMES: &str = "diffuse, mirror, glass[:IOR], gold, copper, silver, aluminium, conductor (metals take :ALPHA)";

    /// Reads a material name with its optional parameter.
    pub fn parse(spec: &str) -> Result<Self, String> {
        let (name, param) = match spec.split_once(':') {
            Some((n, p)) => (n, Some(p)),
            None => (spec, None),
        };
        let number = |lo: f32, hi: f32, what: &str| -> Result<Option<f32>, String> {
            param
                .map(|p| match p.trim().parse::<f32>() {
                    Ok(v) if v >= lo && v <= hi => Ok(v),
                    _ => Err(format!(
                        "{name}: expected {what} from {lo} to {hi}, got '{p}'"
                    )),
                })
                .transpose()
        };
        let metal = |make: fn(f32) -> Material| -> Result<Self, String> {
            Ok(Self::Other(make(
                number(0.0, 1.0, "a GGX width")?.unwrap_or(0.0),
            )))
        };
        let no_param = |m: Self| match param {
            Some(p) => Err(format!("{name} takes no parameter, got '{p}'")),
            None => Ok(m),
        };
        match name {
            "diffuse" => no_param(Self::Diffuse),
            "mirror" => no_param(Self::Other(Material::Mirror {
                reflectance: Vec3A::ONE,
            })),
            "glass" => Ok(Self::Other(Material::Dielectric {
                ior: number(1.0, 4.0, "an index of refraction")?.unwrap_or(1.5),
            })),
            "gold" => metal(Material::gold),
            "copper" => metal(Material::copper),
            "silver" => metal(Material::silver),
            "aluminium" | "aluminum" => metal(Material::aluminium),
            "conductor" => metal(Material::perfect_conductor),
            _ => Err(format!(
                "unknown material '{name}' (expected {})",
                Self::NAMES
            )),
        }
    }

    /// Gives the part's triangles this material (`path` only; `flat` and `direct`
    /// keep the lab's reflectances).
    pub fn apply(self, scene: &mut Scene, part: std::ops::Range<usize>) {
        for prim in part {
            let m = match self {
                Self::Diffuse => Material::Diffuse {
                    reflectance: scene.reflectance(prim as u32),
                },
                Self::Other(m) => m,
            };
            scene.set_material(prim, m);
        }
    }
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

/// The parts of `cornell` (or of `cornell-area` when `area`) in the lab's own
/// frame (y down), for composing with other models: the box, its point light
/// (the key light; off for `cornell-area`), its ambient term, and for
/// `cornell-area` the emitting ceiling patch.
pub fn parts(area: bool) -> SceneParts {
    let (mut tris, mut rho) = triangles();
    if area {
        push_area_light(&mut tris, &mut rho);
    }
    let light = PointLight {
        position: LIGHT_POSITION,
        power: Vec3A::splat(if area { 0.0 } else { LIGHT_POWER }),
    };
    let ambient = Vec3A::splat(if area { 0.0 } else { AMBIENT });
    let mut parts = SceneParts::lab(tris, rho, light, ambient).expect("the built-in box is valid");
    if area {
        let mut patch = SurfaceMaterial::diffuse(Vec3A::ZERO);
        patch.emission = AREA_LIGHT_RADIANCE;
        parts.materials.push(patch);
        for prim in parts::AREA_LIGHT {
            parts.material_of[prim] = parts.materials.len() as u32 - 1;
        }
    }
    parts
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
    fn materials_and_parts_by_name() {
        assert_eq!(part("tall"), Some(parts::TALL_BLOCK));
        assert_eq!(part("wall"), None);
        let all: usize = PART_NAMES.iter().map(|(_, r)| r.len()).sum();
        assert_eq!(all, 30, "the parts cover the box once");
        assert_eq!(
            MaterialChoice::parse("glass"),
            Ok(MaterialChoice::Other(Material::Dielectric { ior: 1.5 }))
        );
        assert_eq!(
            MaterialChoice::parse("glass:1.33"),
            Ok(MaterialChoice::Other(Material::Dielectric { ior: 1.33 }))
        );
        assert_eq!(
            MaterialChoice::parse("gold:0.2"),
            Ok(MaterialChoice::Other(Material::gold(0.2)))
        );
        assert_eq!(
            MaterialChoice::parse("conductor"),
            Ok(MaterialChoice::Other(Material::perfect_conductor(0.0)))
        );
        for bad in [
            "plastic",
            "gold:2",
            "gold:x",
            "mirror:1",
            "glass:nan",
            "",
            "diffuse:0.5",
        ] {
            assert!(MaterialChoice::parse(bad).is_err(), "{bad}");
        }
        let mut scene = scene();
        MaterialChoice::parse("mirror")
            .unwrap()
            .apply(&mut scene, part("tall").unwrap());
        use crate::materials::surface::MaterialKind;
        assert!(matches!(scene.material(25).kind, MaterialKind::Fixed(m) if m.is_specular()));
        assert_eq!(
            scene.material(0).kind,
            MaterialKind::Fixed(Material::Diffuse {
                reflectance: colors::GREEN
            })
        );
    }

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
