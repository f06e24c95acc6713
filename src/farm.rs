//! Render farms: one render split into parts that run anywhere (Slurm array
//! tasks, Kubernetes indexed jobs, processes on one machine) and merged into
//! exactly the image one process makes.
//!
//! Every sample of every pixel depends only on (seed, pixel, sample), and a
//! render's sums are exact ([`crate::fixed`]), so a part is just a subset of
//! the (pixel, sample) grid: the rows of one [`Split`] (`--tile K/N`) and/or a
//! range of sample indices (`--samples A..B`). A part is written as an EXR
//! ([`write_part`]) whose `R`, `G`, `B` are its own average (to look at) and
//! whose `sum.*` channels hold its exact sums, as the four little-endian
//! 32-bit words of each `i128` (`sum.R.0` the lowest), with one text attribute,
//! `raylab.part`, saying what it is a part of. [`merge`] checks that parts
//! belong to one render and cover it exactly once, and adds their sums.

use std::io::BufWriter;
use std::ops::Range;
use std::path::{Path, PathBuf};

use thiserror::Error;

use crate::aov::AovSet;
use crate::checkpoint::Key;
use crate::film::{Display, MetaValue, OutputError, ToneMap};
use crate::fixed::Fixed3;
use crate::render::{Accumulator, Split, TILE_ROWS, Tally};

/// The attribute that marks a part and says what it is of.
pub const PART_ATTRIBUTE: &str = "raylab.part";

/// What a part is a part of: the same for every part of a render.
#[derive(Clone, Debug, PartialEq)]
pub struct Render {
    /// Build, scene and settings (size, camera, integrator, seed, AOVs).
    pub key: Key,
    /// The whole render's samples per pixel.
    pub spp: u32,
    /// The seed (also in the key; kept for the output's metadata).
    pub seed: u64,
    /// The integrator's name (for the output's metadata).
    pub integrator: String,
    /// How the merged image becomes a PNG's pixels.
    pub display: Display,
    /// The animation frame, if the render is one.
    pub frame: Option<u32>,
    /// The AOVs the image shows as layers (`--aov`): the gathered ones may
    /// be more (the denoiser's guides).
    pub layers: AovSet,
    /// Whether the render was asked to be denoised (`--denoise`): its parts
    /// carry the guides, and `raylab merge --denoise` denoises the merged image.
    pub denoise: bool,
}

/// One part: what it is of, and its sums (which say which rows and samples).
#[derive(Clone, Debug)]
pub struct Part {
    /// The render it is a part of.
    pub render: Render,
    /// Its sums: the rows of `acc.split()`, samples `acc.first_sample()..`
    /// `+ acc.spp()`.
    pub acc: Accumulator,
}

/// Why a part could not be read, or parts not merged.
#[derive(Debug, Error)]
pub enum FarmError {
    /// A file is not a usable part.
    #[error("{}: {message}", path.display())]
    Part {
        /// The file.
        path: PathBuf,
        /// What is wrong with it.
        message: String,
    },
    /// The parts do not make one render exactly once.
    #[error("{0}")]
    Set(String),
}

fn part_err(path: &Path, message: impl Into<String>) -> FarmError {
    FarmError::Part {
        path: path.to_owned(),
        message: message.into(),
    }
}

/// The metadata `raylab render` writes into an image: `raylab.spp`, which EXR
/// tools show as a number, and `raylab.render`, the settings as text
/// (`denoised=1` at the end for a denoised image). A merge writes the same,
/// so that its EXR is the single render's byte for byte.
pub fn image_metadata(
    spp: u32,
    requested: Option<u32>,
    seed: u64,
    integrator: &str,
    interrupted: bool,
    denoised: bool,
) -> [(String, MetaValue); 2] {
    let requested = requested.map_or_else(String::new, |r| format!(" spp_requested={r}"));
    let denoised = if denoised { " denoised=1" } else { "" };
    [
        ("raylab.spp".to_string(), MetaValue::Int(spp as i32)),
        (
            "raylab.render".to_string(),
            MetaValue::Text(format!(
                "spp={spp}{requested} seed={seed} integrator={integrator} interrupted={}{denoised}",
                u8::from(interrupted)
            )),
        ),
    ]
}

/// Name of the `word`-th 32-bit word of sum channel `channel`.
fn sum_channel(channel: &str, word: usize) -> String {
    format!("sum.{channel}.{word}")
}

/// The names of an AOV record's values in a part.
fn aov_channel(value: usize) -> String {
    format!("aov{value:02}")
}

/// Writes `part` to `path` (an EXR), atomically.
pub fn write_part(path: &Path, part: &Part) -> Result<(), OutputError> {
    use exr::prelude::*;
    let acc = &part.acc;
    let r = &part.render;
    let (w, h) = (acc.width() as usize, acc.height() as usize);
    let film = acc.rendered().film;
    let plane = |c: usize| film.pixels.iter().map(|p| p[c]).collect::<Vec<f32>>();
    let mut channels: Vec<AnyChannel<FlatSamples>> = ["R", "G", "B"]
        .into_iter()
        .enumerate()
        .map(|(c, name)| AnyChannel::new(name, FlatSamples::F32(plane(c))))
        .collect();
    let words = |values: &mut dyn Iterator<Item = i128>, word: usize| -> Vec<u32> {
        values.map(|v| (v >> (32 * word)) as u32).collect()
    };
    for (c, name) in ["R", "G", "B"].into_iter().enumerate() {
        for word in 0..4 {
            let values = words(&mut acc.image_sums().iter().map(|p| p[c]), word);
            channels.push(AnyChannel::new(
                sum_channel(name, word).as_str(),
                FlatSamples::U32(values),
            ));
        }
    }
    let stride = Accumulator::aov_stride(acc.aov_set());
    for v in 0..stride {
        for word in 0..4 {
            let values = words(
                &mut acc.aov_sums().iter().skip(v).step_by(stride).copied(),
                word,
            );
            channels.push(AnyChannel::new(
                sum_channel(&aov_channel(v), word).as_str(),
                FlatSamples::U32(values),
            ));
        }
    }
    let tally = acc.tally();
    let aovs = if acc.aov_set().is_empty() {
        "-".to_string()
    } else {
        acc.aov_set().to_string()
    };
    let layers = if r.layers.is_empty() {
        "-".to_string()
    } else {
        r.layers.to_string()
    };
    let text = format!(
        "raylab-part 1 width={w} height={h} tile={} samples={}..{} spp={} seed={} integrator={} \
         aovs={aovs} build={:016x} scene={:016x} settings={:016x} rays={} dropped={} \
         scale={:08x} tonemap={} frame={} layers={layers} denoise={}",
        acc.split(),
        acc.first_sample(),
        acc.first_sample() + acc.spp(),
        r.spp,
        r.seed,
        r.integrator,
        r.key.build,
        r.key.scene,
        r.key.settings,
        tally.rays,
        tally.dropped,
        r.display.scale.to_bits(),
        r.display.tonemap,
        r.frame.map_or_else(|| "-".to_string(), |f| f.to_string()),
        u8::from(r.denoise),
    );
    let mut image = Image::from_channels((w, h), AnyChannels::sort(channels.into()));
    image.attributes.other.insert(
        Text::from("raylab.spp"),
        AttributeValue::I32(acc.spp() as i32),
    );
    image.layer_data.attributes.other.insert(
        Text::from(PART_ATTRIBUTE),
        AttributeValue::Text(Text::from(text.as_str())),
    );
    // ZIP: the rows of other tiles are zeros, which it all but removes.
    image.layer_data.encoding.compression = Compression::ZIP16;
    crate::film::write_atomic_with(path, |file| {
        image
            .write()
            .non_parallel()
            .to_buffered(BufWriter::new(file))
            .map_err(|e| match e {
                exr::error::Error::Io(e) => e,
                e => std::io::Error::other(e.to_string()),
            })
    })
}

/// The `key=value` fields of a part's attribute.
struct Fields<'a>(Vec<(&'a str, &'a str)>);

impl<'a> Fields<'a> {
    fn get(&self, name: &str) -> Result<&'a str, String> {
        self.0
            .iter()
            .find(|(k, _)| *k == name)
            .map(|(_, v)| *v)
            .ok_or_else(|| format!("its {PART_ATTRIBUTE} attribute has no {name}"))
    }
    fn num<T: std::str::FromStr>(&self, name: &str) -> Result<T, String> {
        let v = self.get(name)?;
        v.parse()
            .map_err(|_| format!("its {PART_ATTRIBUTE} attribute has {name}={v}"))
    }
    fn hex(&self, name: &str) -> Result<u64, String> {
        let v = self.get(name)?;
        u64::from_str_radix(v, 16)
            .map_err(|_| format!("its {PART_ATTRIBUTE} attribute has {name}={v}"))
    }
    fn pair(&self, name: &str, sep: &str) -> Result<(u32, u32), String> {
        let v = self.get(name)?;
        v.split_once(sep)
            .and_then(|(a, b)| Some((a.parse().ok()?, b.parse().ok()?)))
            .ok_or_else(|| format!("its {PART_ATTRIBUTE} attribute has {name}={v}"))
    }
}

/// Reads a part that [`write_part`] wrote, checking that it is whole and
/// consistent: its sums outside its rows zero, its samples within the render's.
pub fn read_part(path: &Path) -> Result<Part, FarmError> {
    read_part_within(path, &crate::memory::MemoryBudget::UNLIMITED)
}

/// The memory reading a part of `width × height` pixels with AOV records of
/// `stride` values takes while it is added up: the merged sums, the part's
/// sums, and its channels as the EXR reader holds them.
pub fn merge_bytes(width: u32, height: u32, stride: usize) -> u64 {
    let pixels = u64::from(width) * u64::from(height);
    let sums = 48 + 16 * stride as u64;
    // R, G, B as f32, then four u32 words per sum value.
    let channels = 12 + 16 * (3 + stride as u64);
    pixels * (2 * sums + channels)
}

/// [`read_part`], first checking that reading and merging it fits `budget`
/// (from the header, before any pixel is read).
pub fn read_part_within(
    path: &Path,
    budget: &crate::memory::MemoryBudget,
) -> Result<Part, FarmError> {
    use exr::prelude::*;
    let meta = crate::guard::catch("exr", || exr::meta::MetaData::read_from_file(path, false))
        .map_err(|m| part_err(path, m))?
        .map_err(|e| match e {
            exr::error::Error::Io(e) => part_err(path, format!("cannot read it: {e}")),
            e => part_err(path, format!("not an OpenEXR file: {e}")),
        })?;
    let header = meta
        .headers
        .first()
        .ok_or_else(|| part_err(path, "an EXR without an image"))?;
    let text = match header.own_attributes.other.get(&Text::from(PART_ATTRIBUTE)) {
        Some(AttributeValue::Text(t)) => t.to_string(),
        _ => {
            return Err(part_err(
                path,
                "not a part of a render (no raylab.part attribute: made by `raylab render --tile/--samples`?)",
            ));
        }
    };
    let mut words = text.split(' ');
    if words.next() != Some("raylab-part") || words.next() != Some("1") {
        return Err(part_err(
            path,
            "a part in a format this raylab does not read",
        ));
    }
    let fields = Fields(words.filter_map(|w| w.split_once('=')).collect());
    let parsed = (|| -> std::result::Result<_, String> {
        let width: u32 = fields.num("width")?;
        let height: u32 = fields.num("height")?;
        let (index, count) = fields.pair("tile", "/")?;
        let (a, b) = fields.pair("samples", "..")?;
        let spp: u32 = fields.num("spp")?;
        let aovs: AovSet = match fields.get("aovs")? {
            "-" => AovSet::NONE,
            s => s.parse()?,
        };
        let tonemap: ToneMap = fields.get("tonemap")?.parse()?;
        let frame = match fields.get("frame")? {
            "-" => None,
            _ => Some(fields.num("frame")?),
        };
        // (Parts written before the denoiser have neither: every AOV is a
        // layer, and they were not denoised.)
        let layers: AovSet = match fields.get("layers") {
            Err(_) => aovs,
            Ok("-") => AovSet::NONE,
            Ok(s) => s.parse()?,
        };
        if !aovs.includes(layers) {
            return Err(format!(
                "layers={layers} that it has not gathered (aovs={aovs})"
            ));
        }
        let denoise = match fields.get("denoise") {
            Err(_) | Ok("0") => false,
            Ok("1") => true,
            Ok(v) => return Err(format!("its {PART_ATTRIBUTE} attribute has denoise={v}")),
        };
        let render = Render {
            key: Key {
                build: fields.hex("build")?,
                scene: fields.hex("scene")?,
                settings: fields.hex("settings")?,
            },
            spp,
            seed: fields.num("seed")?,
            integrator: fields.get("integrator")?.to_string(),
            display: Display {
                scale: f32::from_bits(fields.hex("scale")? as u32),
                tonemap,
            },
            frame,
            layers,
            denoise,
        };
        let tally = Tally {
            rays: fields.num("rays")?,
            dropped: fields.num("dropped")?,
        };
        if width == 0
            || height == 0
            || width > crate::limits::MAX_SIDE
            || height > crate::limits::MAX_SIDE
            || u64::from(width) * u64::from(height) > crate::limits::MAX_PIXELS
        {
            return Err(format!("an image of {width}×{height} pixels"));
        }
        let split = Split::new(index, count, height)?;
        if a >= b || b > spp || spp > crate::limits::MAX_SPP {
            return Err(format!("samples {a}..{b} of a render of {spp} spp"));
        }
        Ok((width, height, split, a..b, aovs, render, tally))
    })();
    let (width, height, split, samples, aovs, render, tally) =
        parsed.map_err(|m| part_err(path, m))?;
    let needs = crate::memory::Needs {
        film: merge_bytes(width, height, Accumulator::aov_stride(aovs)),
        ..Default::default()
    };
    budget
        .check(&path.display().to_string(), &needs)
        .map_err(|e| FarmError::Set(e.to_string()))?;
    let size = header.layer_size;
    if (size.width(), size.height()) != (width as usize, height as usize) {
        return Err(part_err(
            path,
            format!(
                "its pixels are {}×{}, its attribute says {width}×{height}",
                size.width(),
                size.height()
            ),
        ));
    }
    let image = crate::guard::catch("exr", || crate::film::read_exr_layer(path))
        .map_err(|m| part_err(path, m))?
        .map_err(|e| part_err(path, format!("cannot read its pixels: {e}")))?;
    let channels = &image.layer_data.channel_data.list;
    let pixels = width as usize * height as usize;
    let plane = |name: &str| -> std::result::Result<&[u32], FarmError> {
        match channels.iter().find(|c| c.name.to_string() == name) {
            Some(c) => match &c.sample_data {
                FlatSamples::U32(v) if v.len() == pixels => Ok(v),
                _ => Err(part_err(
                    path,
                    format!("its channel {name} is not 32-bit words"),
                )),
            },
            None => Err(part_err(path, format!("it has no channel {name}"))),
        }
    };
    let read_sums =
        |name: &str, out: &mut dyn FnMut(usize, i128)| -> std::result::Result<(), FarmError> {
            let planes = [0, 1, 2, 3].map(|w| plane(&sum_channel(name, w)));
            let planes: Vec<&[u32]> = planes.into_iter().collect::<std::result::Result<_, _>>()?;
            let word = |i: usize, w: usize| u128::from(planes[w][i]) << (32 * w);
            (0..pixels).for_each(|i| out(i, (0..4).fold(0, |v, w| v | word(i, w)) as i128));
            Ok(())
        };
    let mut sums: Vec<Fixed3> = vec![[0; 3]; pixels];
    for (c, name) in ["R", "G", "B"].into_iter().enumerate() {
        read_sums(name, &mut |i, v| sums[i][c] = v)?;
    }
    let stride = Accumulator::aov_stride(aovs);
    let mut aov_sums = vec![0i128; pixels * stride];
    for v in 0..stride {
        read_sums(&aov_channel(v), &mut |i, x| aov_sums[i * stride + v] = x)?;
    }
    // Nothing outside its rows and the tiles beside them (into which a
    // splatting filter reaches, at most `MAX_SPLAT_BORDER` ≤ `TILE_ROWS`
    // rows), and nothing a sum of its samples cannot be.
    const _: () = assert!(crate::sampling::filter::MAX_SPLAT_BORDER <= TILE_ROWS);
    let limit = crate::fixed::fixed(crate::fixed::MAX_SAMPLE) * (samples.len() as i128);
    let width_px = width as usize;
    for (row, chunk) in sums.chunks(width_px).enumerate() {
        let tile = (row / TILE_ROWS) as u32;
        let inside = split.has_tile(tile)
            || tile > 0 && split.has_tile(tile - 1)
            || split.has_tile(tile + 1) && tile + 1 < Split::row_tiles(height);
        let bad = chunk
            .iter()
            .flatten()
            .any(|&v| if inside { v.abs() > limit } else { v != 0 });
        if bad {
            return Err(part_err(
                path,
                format!("damaged: the sums of row {row} are not those of tile {split}"),
            ));
        }
    }
    if aov_sums.iter().any(|v| v.abs() > limit) {
        return Err(part_err(path, "damaged: AOV sums out of range"));
    }
    let acc = Accumulator::from_parts(
        width,
        height,
        aovs,
        samples.len() as u32,
        tally,
        sums,
        aov_sums,
    )
    .map_err(|e| part_err(path, format!("damaged: {e}")))?
    .into_part(split, samples.start);
    Ok(Part { render, acc })
}

/// The merged render: the sums of all samples of every pixel, and what it is.
#[derive(Clone, Debug)]
pub struct Merged {
    /// What was rendered.
    pub render: Render,
    /// The whole image's sums (samples `0..render.spp`).
    pub acc: Accumulator,
}

/// Reads the parts at `paths` (one at a time: memory for two images' sums) and
/// adds them up, after checking that they are parts of one render (same
/// build, scene, settings, seed, size) that cover every row tile and sample
/// exactly once. The sums are exact, so the result is the single render's,
/// whatever the split. Errors name the file, or the rows and samples missing
/// or held twice.
pub fn merge(paths: &[PathBuf]) -> Result<Merged, FarmError> {
    merge_within(paths, &crate::memory::MemoryBudget::UNLIMITED)
}

/// [`merge`] within `budget` (see [`read_part_within`]).
pub fn merge_within(
    paths: &[PathBuf],
    budget: &crate::memory::MemoryBudget,
) -> Result<Merged, FarmError> {
    let Some(first_path) = paths.first() else {
        return Err(FarmError::Set("no parts to merge".into()));
    };
    let mut total: Option<(Render, Accumulator)> = None;
    // Per part: its split and samples, for the coverage check.
    let mut held: Vec<(Split, Range<u32>)> = Vec::with_capacity(paths.len());
    for (k, path) in paths.iter().enumerate() {
        if paths[..k].contains(path) {
            return Err(FarmError::Set(format!("{} is named twice", path.display())));
        }
        let part = read_part_within(path, budget)?;
        let acc = &part.acc;
        held.push((
            acc.split(),
            acc.first_sample()..acc.first_sample() + acc.spp(),
        ));
        match &mut total {
            None => {
                let mut sum =
                    Accumulator::part(acc.width(), acc.height(), acc.aov_set(), Split::WHOLE, 0);
                sum.add_sums(acc).map_err(|m| part_err(path, m))?;
                total = Some((part.render, sum));
            }
            Some((render, sum)) => {
                let what = if part.render.key.scene != render.key.scene {
                    Some("another scene".to_string())
                } else if (acc.width(), acc.height()) != (sum.width(), sum.height()) {
                    Some(format!(
                        "another image size ({}×{} against {}×{})",
                        acc.width(),
                        acc.height(),
                        sum.width(),
                        sum.height()
                    ))
                } else if part.render.seed != render.seed {
                    Some(format!(
                        "another seed ({} against {})",
                        part.render.seed, render.seed
                    ))
                } else if part.render.spp != render.spp {
                    Some(format!(
                        "a render of {} spp, not {}",
                        part.render.spp, render.spp
                    ))
                } else if part.render.frame != render.frame {
                    Some("another frame".to_string())
                } else if acc.aov_set() != sum.aov_set() {
                    Some("other AOVs".to_string())
                } else if part.render.key.settings != render.key.settings {
                    Some("other settings (camera, integrator or its options)".to_string())
                } else if part.render.key.build != render.key.build {
                    Some("another build of raylab".to_string())
                } else if part.render.display != render.display {
                    Some("another exposure or tone mapping".to_string())
                } else {
                    None
                };
                if let Some(what) = what {
                    return Err(part_err(
                        path,
                        format!(
                            "not a part of the same render as {}: {what}",
                            first_path.display()
                        ),
                    ));
                }
                sum.add_sums(acc).map_err(|m| part_err(path, m))?;
            }
        }
    }
    let (render, mut acc) = total.expect("at least one part");
    check_coverage(paths, &held, acc.height(), render.spp)?;
    acc.set_samples(Split::WHOLE, 0, render.spp);
    Ok(Merged { render, acc })
}

/// Checks that `held` (each part's split and samples) covers samples
/// `0..spp` of every row tile of an image `height` rows high exactly once.
fn check_coverage(
    paths: &[PathBuf],
    held: &[(Split, Range<u32>)],
    height: u32,
    spp: u32,
) -> Result<(), FarmError> {
    // Parts cut the same way are named by their tile; others by rows.
    let counts: Vec<u32> = held.iter().map(|(s, _)| s.count).collect();
    let same_count = counts.windows(2).all(|w| w[0] == w[1]);
    let place = |tile: u32| {
        let rows = tile * TILE_ROWS as u32..((tile + 1) * TILE_ROWS as u32).min(height);
        if same_count && counts[0] > 1 {
            format!(
                "tile {}/{} (rows {}..{} and others)",
                tile % counts[0],
                counts[0],
                rows.start,
                rows.end
            )
        } else if same_count {
            "the image".to_string()
        } else {
            format!("rows {}..{}", rows.start, rows.end)
        }
    };
    for tile in 0..Split::row_tiles(height) {
        let mut ranges: Vec<(Range<u32>, usize)> = held
            .iter()
            .enumerate()
            .filter(|(_, (s, _))| s.has_tile(tile))
            .map(|(i, (_, r))| (r.clone(), i))
            .collect();
        ranges.sort_by_key(|(r, _)| (r.start, r.end));
        let mut next = 0u32;
        let mut last: Option<usize> = None;
        for (r, i) in &ranges {
            if r.start > next {
                return Err(FarmError::Set(format!(
                    "incomplete: no part holds samples {next}..{} of {}",
                    r.start,
                    place(tile)
                )));
            }
            if r.start < next {
                let other = last.expect("a range before");
                return Err(FarmError::Set(format!(
                    "overlap: {} and {} both hold samples {}..{} of {}",
                    paths[other].display(),
                    paths[*i].display(),
                    r.start,
                    next.min(r.end),
                    place(tile)
                )));
            }
            next = r.end;
            last = Some(*i);
        }
        if next < spp {
            return Err(FarmError::Set(format!(
                "incomplete: no part holds samples {next}..{spp} of {}",
                place(tile)
            )));
        }
    }
    Ok(())
}

/// `pattern` with its frame-number field (`%d`, or `%0Nd` for N digits, as
/// ffmpeg and Blender write it) replaced by `frame`; `None` if it has none.
pub fn frame_path(pattern: &Path, frame: u32) -> Option<PathBuf> {
    let text = pattern.to_str()?;
    let at = text.find('%')?;
    let rest = &text[at + 1..];
    let digits: String = rest.chars().take_while(|c| c.is_ascii_digit()).collect();
    let after = rest[digits.len()..].strip_prefix('d')?;
    let width: usize = if digits.is_empty() {
        0
    } else {
        digits.parse().ok().filter(|w| *w <= 9)?
    };
    Some(PathBuf::from(format!(
        "{}{frame:0width$}{after}",
        &text[..at]
    )))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frame_patterns() {
        let p = |s: &str, f| frame_path(Path::new(s), f).map(|p| p.display().to_string());
        assert_eq!(p("out-%04d.png", 7).as_deref(), Some("out-0007.png"));
        assert_eq!(p("out-%d.png", 12).as_deref(), Some("out-12.png"));
        assert_eq!(p("a/%03d/x.exr", 5).as_deref(), Some("a/005/x.exr"));
        assert_eq!(p("out.png", 1), None);
        assert_eq!(p("out-%x.png", 1), None);
    }
}
