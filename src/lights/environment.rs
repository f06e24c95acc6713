//! The environment: radiance arriving from infinitely far away in every
//! direction, either constant or an equirectangular (latitude–longitude) map.
//! Rays that leave the scene see it; the path tracer samples it as a light.
//!
//! The mapping is `scene-conventions.md`'s: direction `d` (unit, away from the
//! scene, +y up) maps to `u = 0.5 + atan2(d.x, −d.z)/(2π)`, `v = acos(d.y)/π`,
//! with `(0, 0)` the image's top-left corner, so the centre column is seen
//! looking along −z and `u = 0.75` is +x. Lookups are bilinear between texel
//! centres, wrapping in `u` and clamping in `v`.
//!
//! Maps are importance sampled: a piecewise-constant distribution over the
//! texels ([`Distribution2D`]) in proportion to the luminance of each texel's
//! mean (bilinear) radiance times `sin θ`, the area its texel covers on the
//! sphere. A direction's density per solid angle is then
//! `p(u, v) / (2π² sin θ)`. Using each texel's *mean* bilinear radiance (not
//! its own value) keeps the density positive wherever the looked-up radiance
//! is, and makes the power estimate exact.

use std::f32::consts::PI;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use glam::{Mat3A, Vec2, Vec3A};
use rayon::prelude::*;
use thiserror::Error;

use super::rgbe::{self, RgbImage};
use crate::memory::{ENVIRONMENT_BYTES_PER_TEXEL, Ledger, Needs};
use crate::sampling::distribution::Distribution2D;

/// The widest or tallest environment map read.
pub const MAX_SIDE: usize = 32768;
/// The most texels an environment map may have (2^27: 1.5 GiB as RGB floats).
pub const MAX_TEXELS: usize = 1 << 27;
/// Largest radiance a texel (or a constant sky) keeps, W·sr⁻¹·m⁻²: 10¹³ times
/// the sun's disc (about 2·10⁷), so no real map reaches it, while a corrupt one
/// (RGBE exponents reach 2¹¹⁹) would make estimates overflow f32 (found by
/// fuzzing). Brighter channels are clamped to it.
pub const MAX_RADIANCE: f32 = 1e20;
/// Largest `strength` the environment takes (larger ones are clamped): with
/// [`MAX_RADIANCE`], radiance over a sample's pdf stays far inside f32.
pub const MAX_STRENGTH: f32 = 1e6;

/// A radiance channel as the environment keeps it: non-finite or negative
/// values become zero, values above [`MAX_RADIANCE`] that ceiling.
#[inline]
fn kept(x: f32) -> f32 {
    if x.is_finite() && x > 0.0 {
        x.min(MAX_RADIANCE)
    } else {
        0.0
    }
}

/// Why an environment map could not be read.
#[derive(Debug, Error)]
pub enum EnvError {
    /// The file could not be read.
    #[error("{}: {cause}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// What the system said.
        cause: std::io::Error,
    },
    /// The file is not a readable image or breaks a limit.
    #[error("{}: {message}", path.display())]
    Format {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        message: String,
    },
    /// The extension is neither `.hdr` nor `.exr`.
    #[error("{}: environment maps are Radiance .hdr or OpenEXR .exr files", path.display())]
    UnknownFormat {
        /// The file.
        path: PathBuf,
    },
    /// The map would need more memory than the budget allows.
    #[error(transparent)]
    Memory(#[from] crate::memory::MemoryError),
}

/// How the path tracer picks directions of the environment for next-event
/// estimation.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum EnvSampling {
    /// In proportion to the map's radiance (constant environments: uniform).
    #[default]
    Importance,
    /// Uniformly over the sphere (for comparisons).
    Uniform,
}

/// An equirectangular radiance map with its sampling distribution.
#[derive(Clone, Debug)]
pub struct EnvMap {
    width: usize,
    height: usize,
    texels: Vec<[f32; 3]>,
    distribution: Distribution2D,
    /// `∫ L dω` over the sphere of the channels' mean (in every lane).
    radiance_integral: Vec3A,
    /// Rows placed from pole to pole (row `j` at `v = j/(H − 1)`) instead of
    /// at texel centres: Mitsuba 3's `envmap` lookup (see
    /// [`EnvMap::with_pole_rows`]).
    pole_rows: bool,
}

/// Rec. 709 luminance.
#[inline]
fn luminance(c: Vec3A) -> f32 {
    0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z
}

impl EnvMap {
    /// A map from an RGB image (row 0 at the top, `+y`). Channels above
    /// [`MAX_RADIANCE`] are clamped to it; non-finite or negative
    /// values become zero. Builds the sampling tables, rows in parallel.
    pub fn from_image(image: RgbImage) -> Self {
        let RgbImage {
            width,
            height,
            mut pixels,
        } = image;
        pixels.par_iter_mut().for_each(|p| {
            *p = p.map(kept);
        });
        let mut map = Self {
            width,
            height,
            texels: pixels,
            distribution: Distribution2D::default(),
            radiance_integral: Vec3A::ZERO,
            pole_rows: false,
        };
        if width == 0 || height == 0 {
            return map;
        }
        // Each texel's mean radiance under bilinear filtering is a separable
        // filter of the texels: itself 3/4, each neighbour 1/8, along u
        // (wrapping) and then along v (clamping). Luminance is linear, so the
        // luminance of the mean is the filtered luminance. Rows in parallel.
        let mut luminance_rows = vec![0.0f32; width * height];
        let row_sums: Vec<f64> = luminance_rows
            .par_chunks_mut(width)
            .zip(map.texels.par_chunks(width))
            .map(|(out, row)| {
                let lum = |i: usize| luminance(Vec3A::from(row[i]));
                let mut sum = 0.0f64;
                for i in 0..width {
                    let (left, right) = ((i + width - 1) % width, (i + 1) % width);
                    out[i] = 0.75 * lum(i) + 0.125 * (lum(left) + lum(right));
                    sum += (row[i][0] + row[i][1] + row[i][2]) as f64 / 3.0;
                }
                sum
            })
            .collect();
        let sin_theta = |j: usize| (PI * (j as f32 + 0.5) / height as f32).sin();
        let at = |i: usize, j: isize| {
            luminance_rows[j.clamp(0, height as isize - 1) as usize * width + i]
        };
        map.distribution = Distribution2D::new(width, height, |i, j| {
            let j = j as isize;
            (0.75 * at(i, j) + 0.125 * (at(i, j - 1) + at(i, j + 1))) * sin_theta(j as usize)
        });
        // ∫ L dω (channel mean): each texel covers (2π/W)·(π/H)·sin θ, and the
        // u filter keeps a row's sum, so only the v filter mixes rows' sums.
        let texel_solid_angle = 2.0 * std::f64::consts::PI.powi(2) / (width * height) as f64;
        let row_sum = |j: isize| row_sums[j.clamp(0, height as isize - 1) as usize];
        let integral: f64 = (0..height as isize)
            .map(|j| {
                let filtered = 0.75 * row_sum(j) + 0.125 * (row_sum(j - 1) + row_sum(j + 1));
                filtered * sin_theta(j as usize) as f64 * texel_solid_angle
            })
            .sum();
        map.radiance_integral = Vec3A::splat(integral as f32);
        map
    }

    /// The same map looked up as Mitsuba 3's `envmap` does (the version its
    /// render tests' references were made with): columns at texel centres
    /// as here, but row `j` at `v = j/(H − 1)`, the first row at the `+y`
    /// pole and the last at the `−y` pole. Only the lookup changes; the
    /// sampling tables stay those of the texel-centred map, which keeps the
    /// estimates unbiased (the density of the directions they give is
    /// exact) at a little more variance.
    pub fn with_pole_rows(mut self) -> Self {
        self.pole_rows = true;
        self
    }

    /// Reads a Radiance `.hdr` or OpenEXR `.exr` file (by extension).
    pub fn load(path: &Path) -> Result<Self, EnvError> {
        Self::load_with(path, &Ledger::unlimited())
    }

    /// [`load`](Self::load), charging the map and its sampling tables to
    /// `ledger` from the file's header, before the texels are allocated.
    pub fn load_with(path: &Path, ledger: &Ledger) -> Result<Self, EnvError> {
        Ok(Self::from_image(read_image(path, ledger)?))
    }

    /// Width in texels.
    pub fn width(&self) -> usize {
        self.width
    }

    /// Height in texels.
    pub fn height(&self) -> usize {
        self.height
    }

    /// Texel `(i, j)` (column, row from the top).
    pub fn texel(&self, i: usize, j: usize) -> Vec3A {
        Vec3A::from(self.texels[j * self.width + i])
    }

    /// Bytes held by the texels and the sampling tables.
    pub fn memory_bytes(&self) -> usize {
        std::mem::size_of_val(self.texels.as_slice()) + self.distribution.memory_bytes()
    }

    /// Asks for the two rows of texels that [`EnvMap::lookup`] at `uv` reads
    /// (a hint: it reads nothing the program sees).
    #[inline]
    pub fn prefetch(&self, uv: Vec2) {
        let (w, h) = (self.width, self.height);
        if w == 0 || h == 0 {
            return;
        }
        let x = ((uv.x * w as f32 - 0.5).max(0.0) as usize).min(w - 1);
        // (Truncation is `floor` wherever `row` does not clamp to 0.)
        let y = uv.y * h as f32 - 0.5;
        for j in [self.row(y), self.row(y + 1.0)] {
            crate::memory::prefetch(self.texels.as_ptr().wrapping_add(j * w + x));
        }
    }

    /// Row `k` of a lookup's taps, clamped to the map (`height > 0`).
    #[inline]
    fn row(&self, k: f32) -> usize {
        (k.max(0.0) as usize).min(self.height - 1)
    }

    /// Bilinear lookup at `(u, v)` (texel centres at `(i + 0.5)/W`), wrapping
    /// in `u`, clamping in `v`.
    #[inline]
    pub fn lookup(&self, uv: Vec2) -> Vec3A {
        let (w, h) = (self.width, self.height);
        if w == 0 || h == 0 {
            return Vec3A::ZERO;
        }
        let x = uv.x * w as f32 - 0.5;
        let y = match self.pole_rows {
            false => uv.y * h as f32 - 0.5,
            true => uv.y * (h - 1) as f32,
        };
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = (x - x0, y - y0);
        // (Inside the map no remainder, a 64-bit division, is needed.)
        let col = |k: f32| {
            let k = k as i64;
            if (0..w as i64).contains(&k) {
                k as usize
            } else {
                k.rem_euclid(w as i64) as usize
            }
        };
        let (i0, i1) = (col(x0), col(x0 + 1.0));
        let (j0, j1) = (self.row(y0), self.row(y0 + 1.0));
        let t = |i: usize, j: usize| Vec3A::from(self.texels[j * w + i]);
        let top = t(i0, j0) * (1.0 - fx) + t(i1, j0) * fx;
        let bottom = t(i0, j1) * (1.0 - fx) + t(i1, j1) * fx;
        top * (1.0 - fy) + bottom * fy
    }
}

/// Charges a `width × height` map to `ledger`.
fn charge(path: &Path, ledger: &Ledger, width: usize, height: usize) -> Result<(), EnvError> {
    let texels = (width as u64).saturating_mul(height as u64);
    ledger.charge(
        &path.display().to_string(),
        Needs {
            environment: texels.saturating_mul(ENVIRONMENT_BYTES_PER_TEXEL),
            ..Needs::default()
        },
    )?;
    Ok(())
}

/// Reads an environment image, checking its size (against the limits, the
/// bytes present and the budget) before allocating.
fn read_image(path: &Path, ledger: &Ledger) -> Result<RgbImage, EnvError> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    let format = |message: String| EnvError::Format {
        path: path.to_owned(),
        message,
    };
    match ext.as_deref() {
        Some("hdr") => {
            let bytes = std::fs::read(path).map_err(|cause| EnvError::Io {
                path: path.to_owned(),
                cause,
            })?;
            // Within the limits (else decoding says which is broken), the
            // map is charged before its texels are allocated.
            if let Ok(h) = rgbe::read_header(&bytes)
                && h.width <= MAX_SIDE
                && h.height <= MAX_SIDE
                && h.width.saturating_mul(h.height) <= MAX_TEXELS
            {
                charge(path, ledger, h.width, h.height)?;
            }
            rgbe::decode(&bytes, MAX_SIDE, MAX_TEXELS).map_err(format)
        }
        Some("exr") => {
            crate::guard::catch("exr", || read_exr(path, &|w, h| charge(path, ledger, w, h)))
                .unwrap_or_else(|m| Err(ExrError::Message(m)))
                .map_err(|e| match e {
                    ExrError::Env(e) => e,
                    ExrError::Message(m) => format(m),
                })
        }
        _ => Err(EnvError::UnknownFormat {
            path: path.to_owned(),
        }),
    }
}

/// Why [`read_exr`] failed: a message about the file, or the budget.
enum ExrError {
    Message(String),
    Env(EnvError),
}

impl From<String> for ExrError {
    fn from(m: String) -> Self {
        ExrError::Message(m)
    }
}

/// Reads the first RGB(A) layer of an OpenEXR file (alpha ignored; a file
/// with only luminance `Y` is not read); `charge` is asked about the size
/// before the texels are allocated.
fn read_exr(
    path: &Path,
    charge: &dyn Fn(usize, usize) -> Result<(), EnvError>,
) -> Result<RgbImage, ExrError> {
    use exr::prelude::*;
    let meta = exr::meta::MetaData::read_from_file(path, false).map_err(|e| e.to_string())?;
    let header = meta
        .headers
        .first()
        .ok_or_else(|| "the file has no layer".to_string())?;
    let size = header.layer_size;
    if size.width() > MAX_SIDE
        || size.height() > MAX_SIDE
        || size.width().saturating_mul(size.height()) > MAX_TEXELS
    {
        return Err(ExrError::Message(format!(
            "the image is {}×{}; at most {MAX_SIDE} a side and {MAX_TEXELS} pixels are read",
            size.width(),
            size.height()
        )));
    }
    charge(size.width(), size.height()).map_err(ExrError::Env)?;
    let image = read()
        .no_deep_data()
        .largest_resolution_level()
        .rgba_channels(
            |res, _| RgbImage {
                width: res.width(),
                height: res.height(),
                pixels: vec![[0.0; 3]; res.width() * res.height()],
            },
            |img: &mut RgbImage, pos, (r, g, b, _a): (f32, f32, f32, f32)| {
                let w = img.width;
                img.pixels[pos.y() * w + pos.x()] = [r, g, b];
            },
        )
        .first_valid_layer()
        .all_attributes()
        .from_file(path)
        .map_err(|e| match e {
            exr::error::Error::NotSupported(what) if what.contains("channel") => {
                format!("no R, G, B channels ({what})")
            }
            e => e.to_string(),
        })?;
    Ok(image.layer_data.channel_data.pixels)
}

/// The map's `(u, v)` of a direction (unit, +y up, in the map's own frame).
#[inline]
pub fn direction_to_uv(d: Vec3A) -> Vec2 {
    let u = 0.5 + d.x.atan2(-d.z) * (0.5 / PI);
    let v = d.y.clamp(-1.0, 1.0).acos() * (1.0 / PI);
    Vec2::new(u - u.floor(), v)
}

/// The direction of a point `(u, v)` of the map, and `sin θ`.
#[inline]
pub fn uv_to_direction(uv: Vec2) -> (Vec3A, f32) {
    let phi = 2.0 * PI * (uv.x - 0.5);
    let theta = PI * uv.y;
    let (sin_t, cos_t) = theta.sin_cos();
    let (sin_p, cos_p) = phi.sin_cos();
    (
        Vec3A::new(sin_t * sin_p, cos_t, -sin_t * cos_p),
        sin_t.max(0.0),
    )
}

/// What surrounds the scene.
#[derive(Clone, Debug, Default)]
enum Source {
    /// Nothing (black).
    #[default]
    None,
    /// The same radiance from every direction.
    Constant(Vec3A),
    /// An equirectangular map (shared: scenes and their copies keep one).
    Map(Arc<EnvMap>),
}

/// The environment: a source (none, constant, map), a strength that scales
/// it, a rotation about +y, and how it is sampled.
#[derive(Clone, Debug, Default)]
pub struct Environment {
    source: Source,
    /// Multiplies the source's radiance.
    strength: f32,
    /// `(sin, cos)` of the rotation about +y (counter-clockwise seen from above).
    rotation: (f32, f32),
    /// Rotation in degrees, as given.
    rotation_degrees: f32,
    /// A general rotation from the map's frame to the world, which replaces
    /// the one about +y where it is given ([`Environment::with_frame`]).
    frame: Option<Mat3A>,
    sampling: EnvSampling,
}

impl Environment {
    /// Adds what decides the environment's radiance to `f`: the map's size
    /// and texels (or the constant), strength and rotation (see
    /// [`crate::Scene::fingerprint`]).
    pub fn fingerprint_into(&self, f: &mut crate::fingerprint::Fingerprint) {
        match &self.source {
            Source::None => f.update(b"no environment"),
            Source::Constant(c) => f.floats(c.to_array()),
            Source::Map(m) => {
                f.words32([m.width as u32, m.height as u32]);
                f.floats(m.texels.iter().flatten().copied());
                if m.pole_rows {
                    f.update(b"pole rows");
                }
            }
        }
        f.floats([self.strength, self.rotation_degrees]);
        if let Some(m) = &self.frame {
            f.floats(m.to_cols_array());
        }
        f.update(format!("{:?}", self.sampling).as_bytes());
    }

    /// No environment: escaping rays see black.
    pub fn none() -> Self {
        Self::from_source(Source::None)
    }

    /// The same radiance `radiance` from every direction (clamped to
    /// [`MAX_RADIANCE`]; non-finite or
    /// negative channels become zero).
    pub fn constant(radiance: Vec3A) -> Self {
        let clean = Vec3A::from(radiance.to_array().map(kept));
        if clean == Vec3A::ZERO {
            return Self::none();
        }
        Self::from_source(Source::Constant(clean))
    }

    /// An environment map.
    pub fn map(map: EnvMap) -> Self {
        Self::from_source(Source::Map(Arc::new(map)))
    }

    /// Reads a map from a Radiance `.hdr` or OpenEXR `.exr` file.
    pub fn load(path: &Path) -> Result<Self, EnvError> {
        Ok(Self::map(EnvMap::load(path)?))
    }

    /// [`load`](Self::load) within `ledger`'s budget (see
    /// [`EnvMap::load_with`]).
    pub fn load_with(path: &Path, ledger: &Ledger) -> Result<Self, EnvError> {
        Ok(Self::map(EnvMap::load_with(path, ledger)?))
    }

    fn from_source(source: Source) -> Self {
        Self {
            source,
            strength: 1.0,
            rotation: (0.0, 1.0),
            rotation_degrees: 0.0,
            frame: None,
            sampling: EnvSampling::Importance,
        }
    }

    /// The same environment scaled by `strength` (finite, ≥ 0, else 0; at most
    /// [`MAX_STRENGTH`]).
    pub fn with_strength(mut self, strength: f32) -> Self {
        self.strength = if strength.is_finite() && strength > 0.0 {
            strength.min(MAX_STRENGTH)
        } else {
            0.0
        };
        self
    }

    /// The same environment turned by `degrees` about +y (positive:
    /// counter-clockwise seen from above, so what was seen towards +x is then
    /// seen towards −z).
    pub fn with_rotation(mut self, degrees: f32) -> Self {
        let d = if degrees.is_finite() { degrees } else { 0.0 };
        let r = (d as f64).to_radians();
        self.rotation = (r.sin() as f32, r.cos() as f32);
        self.rotation_degrees = d;
        self
    }

    /// The same environment turned by the rotation `frame` (map directions
    /// to world ones; orthonormal, right-handed), instead of a rotation about
    /// +y: a Mitsuba `envmap`'s `to_world`.
    pub fn with_frame(mut self, frame: Mat3A) -> Self {
        self.frame = Some(frame);
        self
    }

    /// The same environment, sampled as `sampling` says.
    pub fn with_sampling(mut self, sampling: EnvSampling) -> Self {
        self.sampling = sampling;
        self
    }

    /// The strength.
    pub fn strength(&self) -> f32 {
        self.strength
    }

    /// The rotation about +y in degrees.
    pub fn rotation_degrees(&self) -> f32 {
        self.rotation_degrees
    }

    /// The map, if the environment is one.
    pub fn env_map(&self) -> Option<&EnvMap> {
        match &self.source {
            Source::Map(m) => Some(m),
            _ => None,
        }
    }

    /// Whether escaping rays see black (nothing to look up or sample).
    #[inline]
    pub fn is_black(&self) -> bool {
        self.strength == 0.0 || matches!(self.source, Source::None)
    }

    /// A world direction in the map's frame (undoing the rotation).
    #[inline]
    fn to_map(&self, d: Vec3A) -> Vec3A {
        if let Some(m) = &self.frame {
            return m.transpose() * d;
        }
        let (s, c) = self.rotation;
        Vec3A::new(c * d.x - s * d.z, d.y, s * d.x + c * d.z)
    }

    /// A map direction in the world (applying the rotation).
    #[inline]
    fn to_world(&self, d: Vec3A) -> Vec3A {
        if let Some(m) = &self.frame {
            return *m * d;
        }
        let (s, c) = self.rotation;
        Vec3A::new(c * d.x + s * d.z, d.y, -s * d.x + c * d.z)
    }

    /// Radiance arriving from direction `dir` (unit, world space, pointing
    /// away from the scene).
    #[inline]
    pub fn radiance(&self, dir: Vec3A) -> Vec3A {
        match &self.source {
            Source::None => Vec3A::ZERO,
            Source::Constant(c) => *c * self.strength,
            Source::Map(m) => m.lookup(direction_to_uv(self.to_map(dir))) * self.strength,
        }
    }

    /// A direction chosen from `u` in `[0, 1)²`, with the radiance from it and
    /// its density per solid angle; `None` for a black environment or a
    /// direction of zero density.
    #[inline]
    pub fn sample(&self, u: Vec2) -> Option<(Vec3A, Vec3A, f32)> {
        let (dir, radiance, pdf) = self.sample_direction(u)?;
        Some((dir, self.radiance_of(radiance), pdf))
    }

    /// [`Environment::sample`] with the radiance left to read
    /// ([`Environment::radiance_of`]) and its texels asked for: the read is a
    /// cache miss (perf put 16 % of the helmet's time on the map's first texel
    /// load), which a shadow ray traced meanwhile hides, and which a shadow
    /// ray that finds the sky hidden saves.
    #[inline]
    pub fn sample_direction(&self, u: Vec2) -> Option<(Vec3A, SkyRadiance, f32)> {
        if self.is_black() {
            return None;
        }
        let map = match (&self.source, self.sampling) {
            (Source::Map(m), EnvSampling::Importance) => m,
            _ => {
                let dir = uniform_sphere(u);
                let radiance = SkyRadiance::Known(self.radiance(dir));
                return Some((dir, radiance, 1.0 / (4.0 * PI)));
            }
        };
        let (uv, pdf_uv) = map.distribution.sample(u)?;
        let (d, sin_theta) = uv_to_direction(uv);
        if sin_theta <= 0.0 || pdf_uv <= 0.0 {
            return None;
        }
        let pdf = pdf_uv / (2.0 * PI * PI * sin_theta);
        map.prefetch(uv);
        Some((self.to_world(d), SkyRadiance::MapAt(uv), pdf))
    }

    /// The radiance a [`Environment::sample_direction`] left to read.
    #[inline]
    pub fn radiance_of(&self, radiance: SkyRadiance) -> Vec3A {
        match (radiance, &self.source) {
            (SkyRadiance::Known(c), _) => c,
            (SkyRadiance::MapAt(uv), Source::Map(map)) => map.lookup(uv) * self.strength,
            (SkyRadiance::MapAt(_), _) => Vec3A::ZERO,
        }
    }

    /// The density per solid angle with which [`Environment::sample`] picks
    /// direction `dir` (world space).
    #[inline]
    pub fn pdf(&self, dir: Vec3A) -> f32 {
        if self.is_black() {
            return 0.0;
        }
        match (&self.source, self.sampling) {
            (Source::Map(m), EnvSampling::Importance) => {
                let d = self.to_map(dir);
                let sin_theta = (1.0 - d.y * d.y).max(0.0).sqrt();
                if sin_theta <= 0.0 {
                    return 0.0;
                }
                m.distribution.pdf(direction_to_uv(d)) / (2.0 * PI * PI * sin_theta)
            }
            _ => 1.0 / (4.0 * PI),
        }
    }

    /// `∫ L dω` over the sphere, averaged over the colour channels. The power
    /// the environment sends into a sphere of radius `r` is `π r²` times this
    /// (the scene's light choice weighs it so).
    pub fn radiance_integral(&self) -> f32 {
        let per_channel = match &self.source {
            Source::None => Vec3A::ZERO,
            Source::Constant(c) => *c * (4.0 * PI),
            Source::Map(m) => m.radiance_integral,
        };
        let mean = per_channel.element_sum() / 3.0 * self.strength;
        if mean.is_finite() && mean > 0.0 {
            mean
        } else {
            0.0
        }
    }
}

/// The radiance of a direction [`Environment::sample_direction`] chose:
/// known, or to be read from the map ([`Environment::radiance_of`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum SkyRadiance {
    /// The radiance itself.
    Known(Vec3A),
    /// The map's bilinear value at these coordinates, times the strength.
    MapAt(Vec2),
}

/// A direction uniformly on the unit sphere from `u` in `[0, 1)²`.
#[inline]
pub fn uniform_sphere(u: Vec2) -> Vec3A {
    let z = 1.0 - 2.0 * u.x;
    let s = (1.0 - z * z).max(0.0).sqrt();
    let (sin, cos) = (2.0 * PI * u.y).sin_cos();
    Vec3A::new(s * cos, s * sin, z)
}
