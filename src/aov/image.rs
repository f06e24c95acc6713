//! The averaged AOVs of a render ([`AovImage`]), one [`AovLayer`] per AOV,
//! and their EXR channels.

use super::set::Aov;
use crate::film::Channel;

/// One AOV of a whole image.
#[derive(Clone, Debug, PartialEq)]
pub struct AovLayer {
    /// Which AOV.
    pub aov: Aov,
    /// Its values, row-major from the top-left, the channels of a pixel together
    /// (`aov.channels().len()` per pixel, as OIDN takes them).
    pub values: Vec<f32>,
}

/// The averaged AOVs of a render, in the order they were asked for.
#[derive(Clone, Debug, PartialEq)]
pub struct AovImage {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// One layer per AOV.
    pub layers: Vec<AovLayer>,
    /// Per pixel, the share of its samples whose camera ray hit a surface
    /// (the others saw the environment, or nothing).
    pub coverage: Vec<f32>,
    /// Samples per pixel averaged.
    pub samples: u32,
}

impl AovImage {
    /// The layer of `aov`, if it was gathered.
    pub fn layer(&self, aov: Aov) -> Option<&AovLayer> {
        self.layers.iter().find(|l| l.aov == aov)
    }

    /// The channels of `aov` at pixel `(x, y)`, if it was gathered.
    pub fn get(&self, aov: Aov, x: u32, y: u32) -> Option<&[f32]> {
        let k = aov.channels().len();
        let i = (y as usize * self.width as usize + x as usize) * k;
        self.layer(aov)?.values.get(i..i + k)
    }

    /// Every channel as an EXR channel named `layer.channel` (one plane each),
    /// each layer freed as soon as its planes are made (a large image's AOVs
    /// need not be held twice).
    pub fn into_channels(self) -> Vec<Channel> {
        let mut channels = Vec::new();
        for layer in self.layers {
            let k = layer.aov.channels().len();
            for (c, name) in layer.aov.channel_names().enumerate() {
                let values = layer.values.iter().skip(c).step_by(k).copied().collect();
                channels.push(Channel { name, values });
            }
        }
        channels
    }
}
