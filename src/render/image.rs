//! Render output: a linear RGBA float image with optional AOVs, written as sRGB PNG or linear
//! OpenEXR (atomically), and the image comparisons the golden tests use.
use std::io::Cursor;
use std::path::Path;

use crate::error::{Error, Result};
use crate::io::atomic::write_bytes_atomically;

/// An extra per-pixel output (arbitrary output variable) carried into EXR files.
#[derive(Clone, Debug, PartialEq)]
pub struct Aov {
    /// Channel names, e.g. `["Z"]` or `["tangent.X", "tangent.Y", "tangent.Z"]`.
    pub channels: Vec<String>,
    /// Interleaved values, `channels.len()` per pixel, rows top to bottom.
    pub data: Vec<f32>,
}

/// A linear-light RGBA image, rows top to bottom.
#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    pub width: u32,
    pub height: u32,
    pub rgba: Vec<[f32; 4]>,
    pub aovs: Vec<Aov>,
}

/// The file types `coif render` writes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ImageFormat {
    Png,
    Exr,
}

impl ImageFormat {
    pub fn from_path(path: &Path) -> Result<ImageFormat> {
        match path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase).as_deref() {
            Some("png") => Ok(ImageFormat::Png),
            Some("exr") => Ok(ImageFormat::Exr),
            _ => Err(Error::Usage(format!(
                "{}: unknown image extension; coif render writes .png (sRGB) or .exr (linear)",
                path.display()
            ))),
        }
    }
}

/// The sRGB transfer function of a linear value in [0, 1].
pub fn linear_to_srgb(x: f32) -> f32 {
    let x = x.clamp(0.0, 1.0);
    if x <= 0.003_130_8 {
        12.92 * x
    } else {
        1.055 * x.powf(1.0 / 2.4) - 0.055
    }
}

impl Image {
    /// 8-bit sRGB RGB bytes (values above 1 clip).
    pub fn to_srgb8(&self) -> Vec<u8> {
        self.rgba
            .iter()
            .flat_map(|p| [p[0], p[1], p[2]])
            .map(|v| (linear_to_srgb(v) * 255.0 + 0.5) as u8)
            .collect()
    }

    pub fn encode_png(&self) -> Result<Vec<u8>> {
        encode_srgb8_png(self.width, self.height, &self.to_srgb8())
    }

    pub fn encode_exr(&self) -> Result<Vec<u8>> {
        use exr::prelude::*;
        let pixels = self.rgba.len();
        let mut channels: Vec<AnyChannel<FlatSamples>> = ["R", "G", "B", "A"]
            .iter()
            .enumerate()
            .map(|(c, name)| {
                AnyChannel::new(*name, FlatSamples::F32(self.rgba.iter().map(|p| p[c]).collect()))
            })
            .collect();
        for aov in &self.aovs {
            let n = aov.channels.len();
            for (c, name) in aov.channels.iter().enumerate() {
                let values: Vec<f32> = (0..pixels).map(|i| aov.data[i * n + c]).collect();
                channels.push(AnyChannel::new(name.as_str(), FlatSamples::F32(values)));
            }
        }
        let layer = Layer::new(
            (self.width as usize, self.height as usize),
            LayerAttributes::default(),
            Encoding::FAST_LOSSLESS,
            AnyChannels::sort(channels.into()),
        );
        let mut bytes = Vec::new();
        exr::prelude::Image::from_layer(layer)
            .write()
            .to_buffered(Cursor::new(&mut bytes))
            .map_err(|e| crate::Error::External(format!("EXR encoder: {e}")))?;
        Ok(bytes)
    }

    /// Writes the image as PNG or EXR by extension, atomically.
    pub fn write(&self, path: &Path) -> Result<()> {
        let bytes = match ImageFormat::from_path(path)? {
            ImageFormat::Png => self.encode_png()?,
            ImageFormat::Exr => self.encode_exr()?,
        };
        write_bytes_atomically(path, &bytes)
    }
}

/// An 8-bit RGB image read back from a PNG (golden references).
#[derive(Clone, Debug, PartialEq)]
pub struct Rgb8 {
    pub width: u32,
    pub height: u32,
    pub data: Vec<u8>,
}

impl Rgb8 {
    /// Writes the bytes as an 8-bit sRGB PNG, atomically.
    pub fn write_png(&self, path: &Path) -> Result<()> {
        write_bytes_atomically(path, &encode_srgb8_png(self.width, self.height, &self.data)?)
    }
}

/// An 8-bit sRGB RGB image as PNG bytes.
fn encode_srgb8_png(width: u32, height: u32, rgb: &[u8]) -> Result<Vec<u8>> {
    let mut bytes = Vec::new();
    {
        let mut encoder = png::Encoder::new(&mut bytes, width, height);
        encoder.set_color(png::ColorType::Rgb);
        encoder.set_depth(png::BitDepth::Eight);
        encoder.set_source_srgb(png::SrgbRenderingIntent::Perceptual);
        let mut writer = encoder.write_header().map_err(|e| Error::External(format!("PNG encoder: {e}")))?;
        writer.write_image_data(rgb).map_err(|e| Error::External(format!("PNG encoder: {e}")))?;
    }
    Ok(bytes)
}

pub fn read_png(path: &Path) -> Result<Rgb8> {
    let file = std::fs::File::open(path).map_err(|e| Error::io(path, e))?;
    let mut decoder = png::Decoder::new(std::io::BufReader::new(file));
    decoder.set_transformations(png::Transformations::EXPAND | png::Transformations::STRIP_16);
    let mut reader = decoder.read_info().map_err(|e| Error::format(path, e.to_string()))?;
    let mut buffer = vec![0; reader.output_buffer_size().unwrap_or(0)];
    let info = reader.next_frame(&mut buffer).map_err(|e| Error::format(path, e.to_string()))?;
    let channels = info.color_type.samples();
    if channels < 3 {
        return Err(Error::format(path, "expected an RGB or RGBA PNG"));
    }
    let data = buffer[..info.buffer_size()].chunks(channels).flat_map(|p| [p[0], p[1], p[2]]).collect();
    Ok(Rgb8 { width: info.width, height: info.height, data })
}

/// Root-mean-square difference of two equally sized 8-bit images, in units of full scale (0–1).
pub fn rmse(a: &[u8], b: &[u8]) -> f64 {
    assert_eq!(a.len(), b.len(), "images differ in size");
    let sum: f64 = a.iter().zip(b).map(|(&x, &y)| (x as f64 - y as f64).powi(2)).sum();
    (sum / a.len().max(1) as f64).sqrt() / 255.0
}

/// RMSE of two equally sized 8-bit RGB images after averaging `factor`×`factor` blocks: sampling
/// noise averages out, differences in the picture (colour, lighting, shape) stay.
pub fn rmse_downsampled(a: &[u8], b: &[u8], width: u32, height: u32, factor: u32) -> f64 {
    assert_eq!(a.len(), b.len(), "images differ in size");
    assert_eq!(a.len(), (width * height * 3) as usize, "image size does not match {width}x{height}");
    let (w, h) = (width / factor, height / factor);
    let block = |img: &[u8], bx: u32, by: u32, c: usize| -> f64 {
        let mut sum = 0.0;
        for y in by * factor..(by + 1) * factor {
            for x in bx * factor..(bx + 1) * factor {
                sum += img[((y * width + x) * 3) as usize + c] as f64;
            }
        }
        sum / (factor * factor) as f64
    };
    let mut total = 0.0;
    for by in 0..h {
        for bx in 0..w {
            for c in 0..3 {
                total += (block(a, bx, by, c) - block(b, bx, by, c)).powi(2);
            }
        }
    }
    (total / (w * h * 3).max(1) as f64).sqrt() / 255.0
}

/// Root-mean-square difference of two linear images' RGB, for noise measurement.
pub fn rmse_linear(a: &[[f32; 4]], b: &[[f32; 4]]) -> f64 {
    assert_eq!(a.len(), b.len(), "images differ in size");
    let sum: f64 =
        a.iter().zip(b).flat_map(|(p, q)| (0..3).map(move |c| (p[c] as f64 - q[c] as f64).powi(2))).sum();
    (sum / (3 * a.len().max(1)) as f64).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn png_and_exr_round_trip() {
        let image = Image {
            width: 3,
            height: 2,
            rgba: vec![
                [0.0, 0.5, 1.0, 1.0],
                [0.2, 0.2, 0.2, 1.0],
                [1.5, 0.0, 0.0, 1.0],
                [0.0; 4],
                [0.04, 0.0, 0.0, 0.5],
                [1.0; 4],
            ],
            aovs: vec![Aov { channels: vec!["Z".into()], data: vec![1.0, 2.0, 3.0, 4.0, 5.0, 6.0] }],
        };
        let dir = tempfile::tempdir().unwrap();
        let png_path = dir.path().join("a.png");
        image.write(&png_path).unwrap();
        let back = read_png(&png_path).unwrap();
        assert_eq!((back.width, back.height), (3, 2));
        assert_eq!(&back.data[..6], &[0, 188, 255, 124, 124, 124]);

        let exr_path = dir.path().join("a.exr");
        image.write(&exr_path).unwrap();
        let read = exr::prelude::read_all_flat_layers_from_file(&exr_path).unwrap();
        let layer = &read.layer_data[0];
        let z = layer.channel_data.list.iter().find(|c| c.name == *"Z").unwrap();
        assert_eq!(z.sample_data.values_as_f32().collect::<Vec<_>>(), vec![1.0, 2.0, 3.0, 4.0, 5.0, 6.0]);
        let r = layer.channel_data.list.iter().find(|c| c.name == *"R").unwrap();
        assert_eq!(r.sample_data.values_as_f32().nth(2), Some(1.5), "EXR keeps linear values above 1");
    }

    #[test]
    fn unknown_extension_is_a_usage_error() {
        assert!(matches!(ImageFormat::from_path(Path::new("x.jpg")), Err(Error::Usage(_))));
    }
}
