//! The image buffer, its display transform (exposure, tone mapping, 8-bit sRGB)
//! and atomic PNG/EXR output.

pub mod tonemap;

pub use tonemap::ToneMap;

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use glam::Vec3A;
use image::ImageEncoder;
use rayon::prelude::*;
use thiserror::Error;

/// A `width × height` image of linear RGB values, row-major from the top-left.
#[derive(Clone, Debug, PartialEq)]
pub struct Film {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Pixel values, `width * height` of them.
    pub pixels: Vec<Vec3A>,
}

impl Film {
    /// A black image.
    pub fn new(width: u32, height: u32) -> Self {
        Self {
            width,
            height,
            pixels: vec![Vec3A::ZERO; width as usize * height as usize],
        }
    }

    /// The pixel at column `x`, row `y`.
    pub fn get(&self, x: u32, y: u32) -> Vec3A {
        self.pixels[(y * self.width + x) as usize]
    }

    /// Multiplies every pixel by `s`.
    pub fn scale(&mut self, s: f32) {
        if s != 1.0 {
            self.pixels.par_iter_mut().for_each(|p| *p *= s);
        }
    }

    /// Turns a sum of `samples` samples per pixel into their mean. Components that
    /// overflowed (see [`Film::clamp_to_finite`]) come out finite.
    pub fn average(&mut self, samples: u32) {
        self.scale(1.0 / samples.max(1) as f32);
        self.clamp_to_finite();
    }

    /// Replaces components that are not finite with the nearest finite value (±inf
    /// to ±`f32::MAX`, NaN to 0), so that none is ever written: every sample is
    /// finite (non-finite ones are dropped), but an absurdly bright pixel's sum can
    /// still overflow f32. Returns how many components were replaced.
    pub fn clamp_to_finite(&mut self) -> usize {
        self.pixels
            .par_iter_mut()
            .map(|p| {
                let bad = (!p.is_finite_mask()).bitmask().count_ones() as usize;
                if bad > 0 {
                    *p = Vec3A::select(p.is_nan_mask(), Vec3A::ZERO, *p)
                        .clamp(Vec3A::splat(f32::MIN), Vec3A::splat(f32::MAX));
                }
                bad
            })
            .sum()
    }

    /// Every pixel through `display` as 8-bit sRGB RGB bytes.
    pub fn to_srgb8(&self, display: Display) -> Vec<u8> {
        let mut out = vec![0u8; self.pixels.len() * 3];
        out.par_chunks_mut(3 * 4096)
            .zip(self.pixels.par_chunks(4096))
            .for_each(|(bytes, pixels)| {
                for (b, p) in bytes.chunks_exact_mut(3).zip(pixels) {
                    b.copy_from_slice(&display.srgb8(*p));
                }
            });
        out
    }
}

/// How linear values become a PNG's (or the viewer's) 8-bit sRGB: multiplied
/// by `scale` (the exposure), tone mapped, sRGB-encoded.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Display {
    /// Factor applied first (`2^exposure`, and π for the lab's `path` images).
    pub scale: f32,
    /// Tone mapping operator.
    pub tonemap: ToneMap,
}

impl Display {
    /// Values scaled by `scale` and clamped: the lab's scenes.
    pub fn clamped(scale: f32) -> Self {
        Self {
            scale,
            tonemap: ToneMap::Clamp,
        }
    }

    /// The 8-bit sRGB code of linear colour `c`.
    #[inline]
    pub fn srgb8(&self, c: Vec3A) -> [u8; 3] {
        let p = c * self.scale;
        let p = match self.tonemap {
            ToneMap::Clamp => p,
            t => t.apply(if p.is_finite() { p } else { Vec3A::ZERO }),
        };
        [srgb8(p.x), srgb8(p.y), srgb8(p.z)]
    }
}

/// Relative mean squared error of `image` against `reference`, as
/// `assets/refs/README.md` defines it: the mean over pixels and channels of
/// `(c − r)² / (r² + ε)` with `ε = 0.01 · mean(r)²`.
pub fn rel_mse(image: &Film, reference: &Film) -> f64 {
    assert_eq!(
        (image.width, image.height),
        (reference.width, reference.height),
        "images of different sizes"
    );
    let n = reference.pixels.len() as f64 * 3.0;
    let mean = reference
        .pixels
        .iter()
        .map(|p| p.as_dvec3().element_sum())
        .sum::<f64>()
        / n;
    let eps = 0.01 * mean * mean;
    image
        .pixels
        .iter()
        .zip(&reference.pixels)
        .map(|(c, r)| {
            let (c, r) = (c.as_dvec3(), r.as_dvec3());
            ((c - r) * (c - r) / (r * r + eps)).element_sum()
        })
        .sum::<f64>()
        / n
}

/// The sRGB transfer function of a linear value in `[0, 1]`.
pub fn srgb_encode(x: f32) -> f32 {
    if x <= 0.003_130_8 {
        12.92 * x
    } else {
        1.055 * x.powf(1.0 / 2.4) - 0.055
    }
}

/// Linear value of an sRGB-encoded value in `[0, 1]`.
fn srgb_decode(y: f64) -> f64 {
    if y <= 0.040_45 {
        y / 12.92
    } else {
        ((y + 0.055) / 1.055).powf(2.4)
    }
}

/// `round(255 · srgb_encode(clamp(x, 0, 1)))`, by binary search over the linear
/// values where the code changes (exact, and much cheaper than `powf`). NaN maps to 0.
#[inline]
pub fn srgb8(x: f32) -> u8 {
    static THRESHOLDS: OnceLock<[f32; 255]> = OnceLock::new();
    let t = THRESHOLDS
        .get_or_init(|| std::array::from_fn(|i| srgb_decode((i as f64 + 0.5) / 255.0) as f32));
    t.partition_point(|&edge| edge <= x) as u8
}

/// Why an image could not be written.
#[derive(Debug, Error)]
pub enum OutputError {
    /// The file name does not end in `.png` or `.exr`.
    #[error("{path}: unsupported output format (use .png or .exr)")]
    UnsupportedFormat {
        /// The requested path.
        path: PathBuf,
    },
    /// Creating, writing or renaming failed.
    #[error("cannot write {path}")]
    Io {
        /// The requested path.
        path: PathBuf,
        /// The underlying error.
        source: std::io::Error,
    },
    /// Extra channels (AOVs) were asked for in a format that has none.
    #[error("{path}: AOVs need an .exr output (a PNG holds only the image)")]
    ChannelsNeedExr {
        /// The requested path.
        path: PathBuf,
    },
    /// The encoder failed.
    #[error("cannot encode {path}: {message}")]
    Encode {
        /// The requested path.
        path: PathBuf,
        /// The encoder's message.
        message: String,
    },
}

/// Output formats, chosen by file extension.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    /// 8-bit sRGB PNG of the values clamped to `[0, 1]`.
    Png,
    /// Linear float32 RGB OpenEXR, values unchanged.
    Exr,
}

impl Format {
    /// The format for `path`'s extension (case-insensitive).
    pub fn from_path(path: &Path) -> Result<Self, OutputError> {
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase);
        match ext.as_deref() {
            Some("png") => Ok(Format::Png),
            Some("exr") => Ok(Format::Exr),
            _ => Err(OutputError::UnsupportedFormat {
                path: path.to_owned(),
            }),
        }
    }
}

/// Writes `film` to `path` atomically: to a temporary file in the same folder,
/// flushed to disk, then renamed over `path`. On failure `path` is untouched and
/// the temporary file removed.
pub fn write_image(film: &Film, path: &Path) -> Result<(), OutputError> {
    write_image_with(film, path, Display::clamped(1.0))
}

/// [`write_image`] with PNG values passed through `display` (exposure and tone
/// mapping); EXR always holds the values unchanged.
pub fn write_image_with(film: &Film, path: &Path, display: Display) -> Result<(), OutputError> {
    write_image_layers(film, Vec::new(), path, display)
}

/// One named channel of an EXR image: `width * height` values, row-major from
/// the top-left like a [`Film`].
#[derive(Clone, Debug, PartialEq)]
pub struct Channel {
    /// Its name, `layer.channel` for a layer's (e.g. `albedo.R`).
    pub name: String,
    /// Its values.
    pub values: Vec<f32>,
}

/// A value of a metadata attribute (see [`write_image_meta`]).
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum MetaValue {
    /// A whole number (an EXR `int`).
    Int(i32),
    /// Text (an EXR `string`; Latin-1 only, others are left out).
    Text(String),
}

/// [`write_image_with`] with `extra` channels (AOVs) beside the image's: one
/// single-part EXR whose `R`, `G`, `B` are the image (what [`read_exr`] and
/// every EXR reader take as the picture) and whose other channels are named
/// `layer.channel`, the layer convention that Nuke, Blender and OpenImageIO
/// read from single-part files (the EXR format stores channels sorted by
/// name). `extra` must be empty for PNG ([`OutputError::ChannelsNeedExr`]);
/// it is taken, not borrowed, since the EXR encoder needs its planes owned (a
/// copy of a large image's AOVs would double their memory).
pub fn write_image_layers(
    film: &Film,
    extra: Vec<Channel>,
    path: &Path,
    display: Display,
) -> Result<(), OutputError> {
    write_image_meta(film, extra, path, display, &[])
}

/// [`write_image_layers`] with `metadata`: attributes of the EXR header (e.g.
/// `raylab.spp`, which every EXR reader shows, `exrheader` among them), and
/// nothing for PNG (which keeps its pixels only). At most two, since the EXR
/// writer keeps attributes in hash maps, two of them, whose order is random:
/// with one attribute in each, the same image still gives the same bytes.
pub fn write_image_meta(
    film: &Film,
    extra: Vec<Channel>,
    path: &Path,
    display: Display,
    metadata: &[(String, MetaValue)],
) -> Result<(), OutputError> {
    let format = Format::from_path(path)?;
    if !extra.is_empty() && format != Format::Exr {
        return Err(OutputError::ChannelsNeedExr {
            path: path.to_owned(),
        });
    }
    if metadata.len() > 2 {
        return Err(OutputError::Encode {
            path: path.to_owned(),
            message: format!("{} metadata attributes, at most 2", metadata.len()),
        });
    }
    if let Some(c) = extra.iter().find(|c| c.values.len() != film.pixels.len()) {
        return Err(OutputError::Encode {
            path: path.to_owned(),
            message: format!(
                "channel {} has {} values for {} pixels",
                c.name,
                c.values.len(),
                film.pixels.len()
            ),
        });
    }
    write_atomic(path, |tmp| {
        write_format(film, extra, format, path, tmp, display, metadata)
    })
}

/// Writes `bytes` to `path` atomically (as [`write_image`] does).
pub fn write_bytes(bytes: &[u8], path: &Path) -> Result<(), OutputError> {
    write_atomic(path, |tmp| {
        std::fs::write(tmp, bytes).map_err(|source| OutputError::Io {
            path: path.to_owned(),
            source,
        })
    })
}

/// Creates the hidden temporary sibling of `path`, has `write` fill it, then
/// makes it `path` as [`write_image`] does.
pub(crate) fn write_atomic_with(
    path: &Path,
    write: impl FnOnce(File) -> std::io::Result<()>,
) -> Result<(), OutputError> {
    write_atomic(path, |tmp| {
        File::create(tmp)
            .and_then(write)
            .map_err(|source| OutputError::Io {
                path: path.to_owned(),
                source,
            })
    })
}

/// Runs `write` on a hidden temporary sibling of `path`, then makes it `path`.
fn write_atomic(
    path: &Path,
    write: impl FnOnce(&Path) -> Result<(), OutputError>,
) -> Result<(), OutputError> {
    let io_err = |source| OutputError::Io {
        path: path.to_owned(),
        source,
    };
    let tmp = temp_path(path);
    let result = write(&tmp).and_then(|()| {
        File::open(&tmp)
            .and_then(|f| f.sync_all())
            .and_then(|()| std::fs::rename(&tmp, path))
            .map_err(io_err)
    });
    if result.is_ok() {
        // Make the rename itself durable; not every file system lets a folder be
        // synced, and the file is complete either way.
        let folder = match path.parent() {
            Some(p) if !p.as_os_str().is_empty() => p,
            _ => Path::new("."),
        };
        let _ = File::open(folder).and_then(|d| d.sync_all());
    } else {
        let _ = std::fs::remove_file(&tmp);
    }
    result
}

fn write_format(
    film: &Film,
    extra: Vec<Channel>,
    format: Format,
    path: &Path,
    tmp: &Path,
    display: Display,
    metadata: &[(String, MetaValue)],
) -> Result<(), OutputError> {
    let io_err = |source| OutputError::Io {
        path: path.to_owned(),
        source,
    };
    let encode_err = |message: String| OutputError::Encode {
        path: path.to_owned(),
        message,
    };
    match format {
        Format::Png => {
            let mut out = BufWriter::new(File::create(tmp).map_err(io_err)?);
            image::codecs::png::PngEncoder::new(&mut out)
                .write_image(
                    &film.to_srgb8(display),
                    film.width,
                    film.height,
                    image::ExtendedColorType::Rgb8,
                )
                .map_err(|e| match e {
                    image::ImageError::IoError(e) => io_err(e),
                    e => encode_err(e.to_string()),
                })?;
            out.flush().map_err(io_err)
        }
        Format::Exr => {
            use exr::prelude::*;
            let size = (film.width as usize, film.height as usize);
            let plane = |c: usize| film.pixels.iter().map(|p| p[c]).collect::<Vec<f32>>();
            let channels = ["R", "G", "B"]
                .into_iter()
                .enumerate()
                .map(|(c, name)| AnyChannel::new(name, FlatSamples::F32(plane(c))))
                .chain(
                    extra
                        .into_iter()
                        .map(|c| AnyChannel::new(c.name.as_str(), FlatSamples::F32(c.values))),
                )
                .collect();
            let mut image = Image::from_channels(size, AnyChannels::sort(channels));
            for (k, (name, value)) in metadata.iter().enumerate() {
                let value = match value {
                    MetaValue::Int(v) => AttributeValue::I32(*v),
                    MetaValue::Text(t) => match Text::new_or_none(t) {
                        Some(t) => AttributeValue::Text(t),
                        None => continue,
                    },
                };
                if let Some(name) = Text::new_or_none(name) {
                    // One in each map (see above).
                    match k {
                        0 => image.attributes.other.insert(name, value),
                        _ => image.layer_data.attributes.other.insert(name, value),
                    };
                }
            }
            // Blocks written in order, not by a thread pool: the same image gives
            // the same bytes (pixels were identical before, the files not).
            image
                .write()
                .non_parallel()
                .to_file(tmp)
                .map_err(|e| match e {
                    exr::error::Error::Io(e) => io_err(e),
                    e => encode_err(e.to_string()),
                })
        }
    }
}

/// The hidden sibling of `path` that this process writes before renaming it
/// to `path` (`.NAME.PID.tmp`): a program that must abort mid-write may
/// remove it.
pub fn temp_path(path: &Path) -> PathBuf {
    let name = path
        .file_name()
        .map_or_else(|| "image".into(), |n| n.to_string_lossy().into_owned());
    path.with_file_name(format!(".{name}.{}.tmp", std::process::id()))
}

/// Reads a linear RGB(A) OpenEXR file (the first layer) into a film.
pub fn read_exr(path: &Path) -> Result<Film, OutputError> {
    use exr::prelude::*;
    let image = read_first_rgba_layer_from_file(
        path,
        |res, _| Film::new(res.width() as u32, res.height() as u32),
        |film: &mut Film, pos, (r, g, b, _a): (f32, f32, f32, f32)| {
            let w = film.width as usize;
            film.pixels[pos.y() * w + pos.x()] = Vec3A::new(r, g, b);
        },
    )
    .map_err(|e| OutputError::Encode {
        path: path.to_owned(),
        message: e.to_string(),
    })?;
    Ok(image.layer_data.channel_data.pixels)
}

/// Every channel of an EXR file's first part, by name.
#[derive(Clone, Debug, PartialEq)]
pub struct ExrChannels {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// The channels, in the file's (name) order, as `f32`.
    pub channels: Vec<Channel>,
}

impl ExrChannels {
    /// The values of the channel called `name` (e.g. `albedo.R`), if present.
    pub fn get(&self, name: &str) -> Option<&[f32]> {
        self.channels
            .iter()
            .find(|c| c.name == name)
            .map(|c| c.values.as_slice())
    }

    /// The names of the channels.
    pub fn names(&self) -> Vec<&str> {
        self.channels.iter().map(|c| c.name.as_str()).collect()
    }
}

/// The `raylab.*`-style attributes of an EXR file's header that
/// [`write_image_meta`] writes (every `int` and `string` attribute that is not
/// one of the format's own), sorted by name.
pub fn read_exr_metadata(path: &Path) -> Result<Vec<(String, MetaValue)>, OutputError> {
    use exr::meta::attribute::AttributeValue;
    let meta =
        exr::meta::MetaData::read_from_file(path, false).map_err(|e| OutputError::Encode {
            path: path.to_owned(),
            message: e.to_string(),
        })?;
    let mut out = Vec::new();
    for header in meta.headers.iter().take(1) {
        for (name, value) in header
            .shared_attributes
            .other
            .iter()
            .chain(&header.own_attributes.other)
        {
            let value = match value {
                AttributeValue::I32(v) => MetaValue::Int(*v),
                AttributeValue::Text(t) => MetaValue::Text(t.to_string()),
                _ => continue,
            };
            out.push((name.to_string(), value));
        }
    }
    out.sort_by(|a, b| a.0.cmp(&b.0));
    Ok(out)
}

/// Every channel of an OpenEXR file's first valid layer, as stored (the
/// largest resolution level, no deep data, with the attributes).
pub(crate) fn read_exr_layer(
    path: &Path,
) -> exr::error::Result<
    exr::image::Image<exr::image::Layer<exr::image::AnyChannels<exr::image::FlatSamples>>>,
> {
    use exr::prelude::*;
    read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .first_valid_layer()
        .all_attributes()
        .from_file(path)
}

/// Reads every channel of an OpenEXR file's first part (the image and the AOVs
/// that [`write_image_layers`] writes, or any other file's), converted to `f32`.
pub fn read_exr_channels(path: &Path) -> Result<ExrChannels, OutputError> {
    let image = read_exr_layer(path).map_err(|e| OutputError::Encode {
        path: path.to_owned(),
        message: e.to_string(),
    })?;
    let size = image.layer_data.size;
    let channels = image
        .layer_data
        .channel_data
        .list
        .into_iter()
        .map(|c| Channel {
            name: c.name.to_string(),
            values: c.sample_data.values_as_f32().collect(),
        })
        .collect();
    Ok(ExrChannels {
        width: size.width() as u32,
        height: size.height() as u32,
        channels,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn overflowed_pixels_are_clamped_to_finite_values() {
        let mut film = Film::new(2, 1);
        film.pixels[0] = Vec3A::new(f32::INFINITY, 1.0, f32::NEG_INFINITY);
        film.pixels[1] = Vec3A::new(f32::NAN, 2.0, 3.0);
        assert_eq!(film.clamp_to_finite(), 3);
        assert_eq!(film.pixels[0], Vec3A::new(f32::MAX, 1.0, f32::MIN));
        assert_eq!(film.pixels[1], Vec3A::new(0.0, 2.0, 3.0));
        assert_eq!(film.clamp_to_finite(), 0);
    }

    #[test]
    fn srgb8_matches_the_transfer_function() {
        for i in 0..=10_000 {
            let x = i as f32 / 10_000.0;
            let want = (srgb_encode(x) * 255.0).round() as i32;
            let got = srgb8(x) as i32;
            // Exact except where f32 powf rounds across a code boundary.
            assert!((want - got).abs() <= 1, "{x}: {want} vs {got}");
        }
        assert_eq!(srgb8(-1.0), 0);
        assert_eq!(srgb8(f32::NAN), 0);
        assert_eq!(srgb8(0.0), 0);
        assert_eq!(srgb8(1.0), 255);
        assert_eq!(srgb8(7.0), 255);
        assert_eq!(srgb8(0.5), 188);
        assert_eq!(srgb8(0.75), 225);
    }

    #[test]
    fn png_and_exr_round_trip() {
        let dir = tempfile::tempdir().unwrap();
        let mut film = Film::new(3, 2);
        film.pixels[0] = Vec3A::new(0.25, 2.5, -1.0);
        film.pixels[5] = Vec3A::new(1.0, 0.5, 0.0);
        let exr = dir.path().join("a.EXR");
        write_image(&film, &exr).unwrap();
        assert_eq!(read_exr(&exr).unwrap(), film);
        let png = dir.path().join("a.png");
        write_image(&film, &png).unwrap();
        let img = image::open(&png).unwrap().to_rgb8();
        assert_eq!(img.dimensions(), (3, 2));
        assert_eq!(img.get_pixel(0, 0).0, [137, 255, 0]);
        assert_eq!(img.get_pixel(2, 1).0, [255, 188, 0]);
        // Nothing but the two outputs is left behind.
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 2);
    }

    #[test]
    fn extra_channels_round_trip_beside_the_image_and_need_exr() {
        let dir = tempfile::tempdir().unwrap();
        let mut film = Film::new(2, 2);
        film.pixels[1] = Vec3A::new(0.5, 1.5, 2.5);
        let extra = vec![
            Channel {
                name: "depth.Z".into(),
                values: vec![4.0, f32::INFINITY, 1.0, 2.0],
            },
            Channel {
                name: "albedo.R".into(),
                values: vec![0.75, 0.0, 0.5, 1.0],
            },
        ];
        let exr = dir.path().join("a.exr");
        write_image_layers(&film, extra.clone(), &exr, Display::clamped(1.0)).unwrap();
        // The image reads as before; every channel by name, sorted as EXR stores them.
        assert_eq!(read_exr(&exr).unwrap(), film);
        let all = read_exr_channels(&exr).unwrap();
        assert_eq!((all.width, all.height), (2, 2));
        assert_eq!(all.names(), ["B", "G", "R", "albedo.R", "depth.Z"]);
        assert_eq!(all.get("depth.Z"), Some(&extra[0].values[..]));
        assert_eq!(all.get("albedo.R"), Some(&extra[1].values[..]));
        assert_eq!(all.get("G").unwrap()[1], 1.5);
        assert_eq!(all.get("normal.X"), None);
        // PNG has no room for them; a channel of the wrong size is refused.
        let png = dir.path().join("a.png");
        let err = write_image_layers(&film, extra, &png, Display::clamped(1.0)).unwrap_err();
        assert!(matches!(err, OutputError::ChannelsNeedExr { .. }), "{err}");
        let short = vec![Channel {
            name: "x".into(),
            values: vec![1.0],
        }];
        assert!(write_image_layers(&film, short, &exr, Display::clamped(1.0)).is_err());
        assert_eq!(read_exr_channels(&exr).unwrap(), all, "the old file stays");
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
    }

    #[test]
    fn failed_write_keeps_the_old_file_and_leaves_no_temporary() {
        let dir = tempfile::tempdir().unwrap();
        let names = || {
            let mut n: Vec<String> = std::fs::read_dir(dir.path())
                .unwrap()
                .map(|e| e.unwrap().file_name().into_string().unwrap())
                .collect();
            n.sort();
            n
        };
        // Failure before anything is written: a folder squats on the temporary name.
        let path = dir.path().join("keep.png");
        std::fs::write(&path, b"old").unwrap();
        std::fs::create_dir(temp_path(&path)).unwrap();
        let err = write_image(&Film::new(2, 2), &path).unwrap_err();
        assert!(err.to_string().contains("keep.png"), "{err}");
        assert_eq!(std::fs::read(&path).unwrap(), b"old");
        std::fs::remove_dir(temp_path(&path)).unwrap();
        // Failure after the whole image is written: the rename onto a folder fails,
        // and the complete temporary file is removed again.
        let folder = dir.path().join("taken.exr");
        std::fs::create_dir(&folder).unwrap();
        std::fs::write(folder.join("inside"), b"x").unwrap();
        assert!(write_image(&Film::new(2, 2), &folder).is_err());
        assert_eq!(names(), ["keep.png", "taken.exr"]);
        assert_eq!(std::fs::read(folder.join("inside")).unwrap(), b"x");
        let bad = write_image(&Film::new(2, 2), &dir.path().join("x.jpg")).unwrap_err();
        assert!(matches!(bad, OutputError::UnsupportedFormat { .. }));
        assert_eq!(names(), ["keep.png", "taken.exr"]);
    }
}
