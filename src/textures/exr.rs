//! OpenEXR images as textures ([`Image::decode_exr`]): linear floats, as
//! Mitsuba 3's `bitmap` reads an `.exr` (its RGB channels, or a single
//! luminance channel `Y`; alpha and other channels are not read).

use std::io::Cursor;

use super::error::{MAX_SIDE, MAX_TEXELS, TextureError};
use super::texel::Image;

impl Image {
    /// Decodes the first valid layer of an OpenEXR file (`bytes`, named
    /// `name` in errors) at its largest resolution into linear 32-bit
    /// texels: three channels from `R`, `G`, `B` (all three needed), else
    /// one from `Y`. Half, float and integer samples are read as `f32`.
    /// The decoded size is charged to `ledger` (for `scene`) before the
    /// texels are read.
    pub fn decode_exr(
        bytes: &[u8],
        name: &str,
        ledger: &crate::memory::Ledger,
        scene: &str,
    ) -> Result<Image, TextureError> {
        let fail = |why: String| TextureError::Exr {
            name: name.to_string(),
            why,
        };
        crate::guard::catch("exr", || decode(bytes, name, ledger, scene, &fail))
            .unwrap_or_else(|m| Err(fail(m)))
    }
}

/// [`Image::decode_exr`] without the guard against the decoder's panics.
fn decode(
    bytes: &[u8],
    name: &str,
    ledger: &crate::memory::Ledger,
    scene: &str,
    fail: &dyn Fn(String) -> TextureError,
) -> Result<Image, TextureError> {
    use exr::prelude::{ReadChannels, ReadLayers};
    let meta = exr::meta::MetaData::read_from_buffered(Cursor::new(bytes), false)
        .map_err(|e| fail(e.to_string()))?;
    let header = meta
        .headers
        .first()
        .ok_or_else(|| fail("the file has no layer".into()))?;
    let size = header.layer_size;
    let (width, height) = (size.width(), size.height());
    if width == 0 || height == 0 {
        return Err(TextureError::Empty {
            name: name.to_string(),
        });
    }
    if width > MAX_SIDE as usize
        || height > MAX_SIDE as usize
        || (width as u64).saturating_mul(height as u64) > MAX_TEXELS
    {
        return Err(TextureError::TooLarge {
            name: name.to_string(),
            width: width.min(u32::MAX as usize) as u32,
            height: height.min(u32::MAX as usize) as u32,
        });
    }
    let has = |c: &str| header.channels.list.iter().any(|ch| ch.name.eq(c));
    let names: &[&str] = if has("R") && has("G") && has("B") {
        &["R", "G", "B"]
    } else if has("Y") {
        &["Y"]
    } else {
        return Err(fail(
            "no R, G, B channels and no Y channel (Mitsuba's bitmap reads RGB or luminance)".into(),
        ));
    };
    ledger.charge(
        scene,
        crate::memory::Needs {
            textures: (width * height * names.len() * 4) as u64,
            ..Default::default()
        },
    )?;
    let image = exr::prelude::read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .first_valid_layer()
        .all_attributes()
        .from_buffered(Cursor::new(bytes))
        .map_err(|e| fail(e.to_string()))?;
    let layer = &image.layer_data;
    let (w, h) = (layer.size.width(), layer.size.height());
    let channels: Vec<Vec<f32>> = names
        .iter()
        .map(|n| {
            let ch = layer
                .channel_data
                .list
                .iter()
                .find(|ch| ch.name.eq(n))
                .ok_or_else(|| fail(format!("no channel {n} in the first layer")))?;
            let values: Vec<f32> = ch.sample_data.values_as_f32().collect();
            if values.len() != w * h {
                return Err(fail(format!("channel {n} is subsampled (not read)")));
            }
            Ok(values)
        })
        .collect::<Result<_, TextureError>>()?;
    let mut texels = Vec::with_capacity(w * h * channels.len());
    for i in 0..w * h {
        texels.extend(channels.iter().map(|c| c[i]));
    }
    Ok(Image::from_f32(
        w as u32,
        h as u32,
        channels.len() as u8,
        texels,
    ))
}
