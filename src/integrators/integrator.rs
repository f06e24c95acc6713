//! The light transport algorithms ([`Integrator`]): which there are, their
//! names on the command line, and `path`'s radiance with a fixed random
//! stream for the others' packet code ([`path_from`]).

use std::fmt;
use std::str::FromStr;

use glam::Vec3A;

use super::path::{self, PathOptions};
use crate::geometry::ray::{Hit, Ray};
use crate::sampling::sampler::Rng;
use crate::scene::Scene;

/// The light transport algorithm used for each camera ray.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Integrator {
    /// The reflectance ρ of the closest triangle; black on a miss (lab task 1).
    Flat,
    /// The lab's model (lab task 3): `ρ ∘ (D + N)` with the point light's
    /// `D = P·max(r̂·n̂, 0) / (4πr²)`, zero in shadow, and the ambient term `N`.
    #[default]
    Direct,
    /// Global illumination in physical units: an unbiased path tracer with
    /// next-event estimation and multiple importance sampling (see [`path`]).
    Path(PathOptions),
    /// Bidirectional path tracing (see [`crate::integrators::bdpt`]): the
    /// path tracer's options, its camera subpaths joined to light subpaths
    /// by every strategy. Its value for a lone ray (without a camera to
    /// splat to) is `path`'s.
    Bdpt(PathOptions),
    /// Vertex connection and merging (see [`crate::integrators::bdpt`]):
    /// `bdpt` whose camera vertices also merge with the light vertices of
    /// every pixel's light subpath near them. Consistent: converges to
    /// `bdpt`'s image as the merge radius shrinks.
    Vcm(PathOptions),
}

impl Integrator {
    /// All integrators with default options, in the viewer's key order.
    pub const ALL: [Integrator; 3] = [
        Integrator::Flat,
        Integrator::Direct,
        Integrator::Path(PathOptions {
            max_depth: u32::MAX,
            sampler: path::SamplerKind::DEFAULT,
            filter: crate::sampling::filter::PixelFilter::Box,
            reconstruction: crate::sampling::filter::Reconstruction::Sample,
            hide_emitters: path::HideEmitters::No,
            direct: path::DirectSamples::ONE_EACH,
        }),
    ];

    /// The `path` integrator with default options.
    pub fn path() -> Self {
        Integrator::Path(PathOptions::default())
    }

    /// The `bdpt` integrator with default options.
    pub fn bdpt() -> Self {
        Integrator::Bdpt(PathOptions::default())
    }

    /// The `vcm` integrator with default options.
    pub fn vcm() -> Self {
        Integrator::Vcm(PathOptions::default())
    }

    /// Whether the integrator joins camera and light subpaths (`bdpt`,
    /// `vcm`).
    pub fn is_bidirectional(self) -> bool {
        matches!(self, Integrator::Bdpt(_) | Integrator::Vcm(_))
    }

    /// The path tracer's options of `path`, `bdpt` and `vcm`.
    pub fn path_options(self) -> Option<PathOptions> {
        match self {
            Integrator::Path(o) | Integrator::Bdpt(o) | Integrator::Vcm(o) => Some(o),
            _ => None,
        }
    }

    /// This integrator with the path tracer's options `options` (for `path`
    /// and `bdpt`; the others have none).
    pub fn with_path_options(self, options: PathOptions) -> Self {
        match self {
            Integrator::Path(_) => Integrator::Path(options),
            Integrator::Bdpt(_) => Integrator::Bdpt(options),
            Integrator::Vcm(_) => Integrator::Vcm(options),
            other => other,
        }
    }

    /// The name used on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Integrator::Flat => "flat",
            Integrator::Direct => "direct",
            Integrator::Path(_) => "path",
            Integrator::Bdpt(_) => "bdpt",
            Integrator::Vcm(_) => "vcm",
        }
    }

    /// Whether the integrator computes radiance in physical units (`path`), as
    /// opposed to the lab's units (`flat`, `direct`).
    pub fn is_physical(self) -> bool {
        matches!(
            self,
            Integrator::Path(_) | Integrator::Bdpt(_) | Integrator::Vcm(_)
        )
    }
}

/// `path`'s radiance with the fixed stream of [`Integrator::radiance`]. Out of
/// line: inlined, the path tracer would make the lab integrators' functions too
/// large for the render loop to inline them.
#[inline(never)]
pub(super) fn path_from(
    scene: &Scene,
    ray: &Ray,
    hit: Option<Hit>,
    options: &PathOptions,
    rays: &mut u64,
) -> Vec3A {
    path::radiance_from(scene, ray, hit, options, &mut Rng::new(0, 0), rays)
}

impl fmt::Display for Integrator {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Integrator {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Integrator::ALL
            .into_iter()
            .chain([Integrator::bdpt(), Integrator::vcm()])
            .find(|i| i.name() == s)
            .ok_or_else(|| {
                format!("unknown integrator '{s}' (expected flat, direct, path, bdpt or vcm)")
            })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip() {
        for i in Integrator::ALL {
            assert_eq!(i.name().parse::<Integrator>(), Ok(i));
        }
        assert_eq!("path".parse::<Integrator>(), Ok(Integrator::path()));
        assert_eq!("bdpt".parse::<Integrator>(), Ok(Integrator::bdpt()));
        assert_eq!(Integrator::bdpt().name(), "bdpt");
        assert_eq!("vcm".parse::<Integrator>(), Ok(Integrator::vcm()));
        assert!("bogus".parse::<Integrator>().is_err());
    }
}
