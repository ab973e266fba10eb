//! HDR images, tone mapping and file I/O.
//!
//! Pixel values of linear images are radiance [W/(m²·sr)] per Rec.709 channel. OpenEXR
//! (32-bit float, via the `exr` crate) is the HDR format; PNG (8-bit sRGB, via `image`)
//! is for viewing, written through exposure and a tone curve.

use crate::math::{Rgb, Vec3};
use std::path::{Path, PathBuf};

/// Errors reading or writing images; each names the file.
#[derive(Debug, thiserror::Error)]
pub enum ImageError {
    /// The file could not be read or decoded.
    #[error("{path}: cannot read image: {message}")]
    Read {
        /// The file.
        path: PathBuf,
        /// What went wrong.
        message: String,
    },
    /// The file could not be encoded or written.
    #[error("{path}: cannot write image: {message}")]
    Write {
        /// The file.
        path: PathBuf,
        /// What went wrong.
        message: String,
    },
    /// The extension is not one illume reads or writes.
    #[error("{path}: unsupported image format (expected .exr or .png)")]
    UnsupportedFormat {
        /// The file.
        path: PathBuf,
    },
}

/// A width × height grid of pixels, row-major, row 0 at the top.
#[derive(Clone, Debug, PartialEq)]
pub struct Image<T> {
    width: u32,
    height: u32,
    data: Vec<T>,
}

/// Linear RGB image.
pub type RgbImage = Image<Rgb>;

impl<T: Clone> Image<T> {
    /// An image filled with `value`.
    pub fn filled(width: u32, height: u32, value: T) -> Self {
        Self {
            width,
            height,
            data: vec![value; width as usize * height as usize],
        }
    }
}

impl<T> Image<T> {
    /// An image from row-major pixels; `None` when the length does not match.
    pub fn from_vec(width: u32, height: u32, data: Vec<T>) -> Option<Self> {
        (data.len() == width as usize * height as usize).then_some(Self {
            width,
            height,
            data,
        })
    }

    /// The row-major pixels, without a copy (the inverse of [`Image::from_vec`]).
    pub fn into_pixels(self) -> Vec<T> {
        self.data
    }

    /// Width in pixels.
    pub fn width(&self) -> u32 {
        self.width
    }

    /// Height in pixels.
    pub fn height(&self) -> u32 {
        self.height
    }

    /// Row-major pixels.
    pub fn pixels(&self) -> &[T] {
        &self.data
    }

    /// Row-major pixels, mutable.
    pub fn pixels_mut(&mut self) -> &mut [T] {
        &mut self.data
    }

    /// Pixel at column `x`, row `y`.
    #[inline]
    pub fn get(&self, x: u32, y: u32) -> &T {
        &self.data[y as usize * self.width as usize + x as usize]
    }

    /// Mutable pixel at column `x`, row `y`.
    #[inline]
    pub fn get_mut(&mut self, x: u32, y: u32) -> &mut T {
        &mut self.data[y as usize * self.width as usize + x as usize]
    }

    /// Same pixels mapped through `f`.
    pub fn map<U>(&self, f: impl Fn(&T) -> U) -> Image<U> {
        Image {
            width: self.width,
            height: self.height,
            data: self.data.iter().map(f).collect(),
        }
    }
}

impl RgbImage {
    /// A black image.
    pub fn black(width: u32, height: u32) -> Self {
        Self::filled(width, height, Rgb::ZERO)
    }

    /// The first pixel (in row order) with a NaN or infinite channel: its x, y and value.
    pub fn first_non_finite(&self) -> Option<(u32, u32, Rgb)> {
        let w = self.width.max(1) as usize;
        self.pixels()
            .iter()
            .position(|p| !p.is_finite())
            .map(|i| ((i % w) as u32, (i / w) as u32, self.pixels()[i]))
    }

    /// Per-channel mean over all pixels (f64 accumulation).
    pub fn mean(&self) -> Rgb {
        let mut s = [0.0f64; 3];
        for p in &self.data {
            s[0] += p.x as f64;
            s[1] += p.y as f64;
            s[2] += p.z as f64;
        }
        let n = self.data.len().max(1) as f64;
        Rgb::new((s[0] / n) as f32, (s[1] / n) as f32, (s[2] / n) as f32)
    }

    /// The image shrunk by `k` in each direction, each pixel the mean of its k×k block
    /// (a box filter: a still rendered at k times the size and shrunk has its edges
    /// anti-aliased as a path tracer's box-filtered pixels are). Panics unless `k` ≥ 1
    /// divides both sides (a programming error, not input).
    pub fn box_downsample(&self, k: u32) -> RgbImage {
        assert!(
            k >= 1 && self.width.is_multiple_of(k) && self.height.is_multiple_of(k),
            "{k} must divide {}×{}",
            self.width,
            self.height
        );
        let (w, h) = (self.width / k, self.height / k);
        let inv = 1.0 / (k * k) as f32;
        let data = (0..h)
            .flat_map(|y| (0..w).map(move |x| (x, y)))
            .map(|(x, y)| {
                let mut sum = Rgb::ZERO;
                for dy in 0..k {
                    let row = ((y * k + dy) * self.width + x * k) as usize;
                    for p in &self.data[row..row + k as usize] {
                        sum += *p;
                    }
                }
                sum * inv
            })
            .collect();
        Image {
            width: w,
            height: h,
            data,
        }
    }

    /// Pixel-wise sum; panics if sizes differ (a programming error, not input).
    pub fn add(&self, other: &RgbImage) -> RgbImage {
        assert_eq!(
            (self.width, self.height),
            (other.width, other.height),
            "image sizes differ"
        );
        let data = self
            .data
            .iter()
            .zip(&other.data)
            .map(|(a, b)| *a + *b)
            .collect();
        Image {
            width: self.width,
            height: self.height,
            data,
        }
    }

    /// Reads an `.exr` or Radiance `.hdr` (linear) or `.png`/`.jpg` (sRGB-decoded to
    /// linear) image: a regular file (not a pipe or device) of at most
    /// [`MAX_IMAGE_FILE_BYTES`], decoding to at most [`MAX_DECODED_IMAGE_BYTES`] (a header
    /// claiming more is refused before anything is allocated).
    pub fn read(path: &Path) -> Result<Self, ImageError> {
        crate::files::check_regular(path, MAX_IMAGE_FILE_BYTES).map_err(|e| ImageError::Read {
            path: path.to_owned(),
            message: e.to_string(),
        })?;
        match extension(path).as_deref() {
            Some("exr") => read_exr(path),
            Some("hdr") => read_hdr(path),
            Some("png") | Some("jpg") | Some("jpeg") => read_ldr(path),
            _ => Err(ImageError::UnsupportedFormat {
                path: path.to_owned(),
            }),
        }
    }

    /// Writes linear `.exr`, or tone-mapped sRGB `.png` with `tone`.
    pub fn write(&self, path: &Path, tone: &ToneMap) -> Result<(), ImageError> {
        match extension(path).as_deref() {
            Some("exr") => write_exr(self, path),
            Some("png") => write_png(self, path, tone),
            _ => Err(ImageError::UnsupportedFormat {
                path: path.to_owned(),
            }),
        }
    }
}

fn extension(path: &Path) -> Option<String> {
    path.extension()
        .and_then(|e| e.to_str())
        .map(|e| e.to_ascii_lowercase())
}

/// How linear radiance becomes display values for 8-bit output.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ToneMap {
    /// Exposure in stops (EV): pixel values are multiplied by `2^exposure_ev` first.
    /// Default 0.
    pub exposure_ev: f32,
    /// The tone curve applied after exposure. Default [`ToneCurve::Aces`].
    pub curve: ToneCurve,
}

impl Default for ToneMap {
    fn default() -> Self {
        Self {
            exposure_ev: 0.0,
            curve: ToneCurve::Aces,
        }
    }
}

/// Tone curves for display output.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ToneCurve {
    /// Clamp to [0, 1]: exact for values already in range (comparisons, tests).
    Clamp,
    /// Reinhard `x/(1+x)` per channel.
    Reinhard,
    /// Narkowicz's fit of the ACES filmic curve.
    Aces,
}

impl ToneMap {
    /// Display-linear value in [0, 1] of a linear radiance value.
    #[inline]
    pub fn apply(&self, c: Rgb) -> Rgb {
        self.prepared().apply(c)
    }

    /// The same map with `2^exposure_ev` computed once, for applying it to many pixels.
    #[inline]
    pub fn prepared(&self) -> PreparedToneMap {
        PreparedToneMap {
            scale: 2f32.powf(self.exposure_ev),
            curve: self.curve,
        }
    }
}

/// A [`ToneMap`] with its exposure factor computed ([`ToneMap::prepared`]): the same
/// values, one `powf` per image instead of one per pixel.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PreparedToneMap {
    /// `2^exposure_ev`.
    scale: f32,
    curve: ToneCurve,
}

impl PreparedToneMap {
    /// Display-linear value in [0, 1] of a linear radiance value ([`ToneMap::apply`]).
    #[inline]
    pub fn apply(&self, c: Rgb) -> Rgb {
        let x = (c * self.scale).max(Vec3::ZERO);
        let y = match self.curve {
            ToneCurve::Clamp => x,
            ToneCurve::Reinhard => x / (Vec3::ONE + x),
            ToneCurve::Aces => {
                let (a, b, c, d, e) = (2.51, 0.03, 2.43, 0.59, 0.14);
                (x * (x * a + b)) / (x * (x * c + d) + e)
            }
        };
        y.clamp(Vec3::ZERO, Vec3::ONE)
    }
}

/// The middle grey automatic exposure maps the scene's log-average luminance to
/// (Reinhard et al. 2002, "Photographic tone reproduction", the key value a = 0.18).
pub const AUTO_EXPOSURE_KEY: f32 = 0.18;

/// Automatic exposure in stops for `img` (Reinhard et al. 2002's key-value rule): the
/// exposure that maps a log-average luminance L̄ to [`AUTO_EXPOSURE_KEY`], i.e.
/// log₂(0.18 / L̄), taken so that it does not depend on the image's noise (issue 38:
/// the per-pixel log-average over pixels above 0 gave a bunny +7.3 EV from one
/// technique and +1.1 EV from another at the same mean radiance, and drifted with the
/// sample count):
///
/// - **Metering zones, not pixels.** Luminance is averaged over square blocks of
///   [`exposure_block`] pixels (about 16 across the image, as a camera's metering
///   zones) before the logarithm. The log of a noisy value is biased low
///   (E ln Y < ln E Y); a zone's mean keeps the image's mean radiance and holds many
///   pixels' samples.
/// - **Dark zones weigh little, by a smooth weight.** A zone of mean m counts with
///   weight m / (m + c), c = [`AUTO_EXPOSURE_SOFTNESS`] × the image's mean: nearly 1
///   for lit zones, nearly 0 for a black background, a shadow a path tracer leaves at
///   0, or a technique's 10⁻⁶ of numerical residue. Smooth, so no zone jumps in or out
///   of the average when noise moves it across a threshold.
///
/// Measured on the Stanford bunny under `--spot-from-above` at 96×72, 160×120 and
/// 320×240 (the reference at 4, 64 and 256 samples a pixel, photon_stream): every
/// exposure within 0.14 EV of the others (docs/benchmarks/renderer.md). A small object on black is exposed for the
/// zones it covers, so a little brighter than for itself.
///
/// Non-finite and negative pixels count as black. None when nothing has light.
/// Clamped to ±32 stops.
pub fn auto_exposure_ev(img: &RgbImage) -> Option<f32> {
    let b = exposure_block(img.width(), img.height());
    let (bw, bh) = (img.width().div_ceil(b), img.height().div_ceil(b));
    let mut zones = vec![(0.0f64, 0u32); (bw * bh) as usize];
    let mut total = 0.0f64;
    for y in 0..img.height() {
        for x in 0..img.width() {
            let l = crate::luminance(*img.get(x, y));
            let l = if l.is_finite() && l > 0.0 {
                l as f64
            } else {
                0.0
            };
            let zone = &mut zones[((y / b) * bw + x / b) as usize];
            zone.0 += l;
            zone.1 += 1;
            total += l;
        }
    }
    let mean = total / (img.width() as f64 * img.height() as f64);
    if !(mean > 0.0 && mean.is_finite()) {
        return None;
    }
    let c = AUTO_EXPOSURE_SOFTNESS as f64 * mean;
    let (mut sum, mut weight) = (0.0f64, 0.0f64);
    for &(s, n) in &zones {
        let m = s / n as f64;
        if m > 0.0 {
            let w = m / (m + c);
            sum += w * m.ln();
            weight += w;
        }
    }
    let log_average = (sum / weight).exp();
    Some(((AUTO_EXPOSURE_KEY as f64 / log_average).log2() as f32).clamp(-32.0, 32.0))
}

/// [`auto_exposure_ev`]'s zones of mean m weigh m / (m + c) with c this fraction of the
/// image's mean luminance: a zone at a tenth of the mean counts half. Chosen on the
/// bunny case measured there (0.03: zones straddle the knee and the exposure moves by
/// up to 0.23 EV with the sample count; 0.3: the image darkens by half a stop more).
pub const AUTO_EXPOSURE_SOFTNESS: f32 = 0.1;

/// The side in pixels of [`auto_exposure_ev`]'s metering zones for a `width` × `height`
/// image: 16 zones across the longer side (1 pixel up to 16 × 16, 50 pixels at
/// 800 × 600).
pub fn exposure_block(width: u32, height: u32) -> u32 {
    width.max(height).div_ceil(16).max(1)
}

/// The 8-bit sRGB code of a display-linear value: `round(255 · srgb_encode(x))` clamped
/// to 0–255 (NaN and values ≤ 0 give 0, values ≥ 1 give 255), read from tables: the
/// code at the start of `x`'s 1/4096-wide bucket, then stepped up past the thresholds
/// (the smallest value reaching each code) that lie inside the bucket — at most one, as
/// the curve rises by under one code per bucket. Exact because the formula is
/// non-decreasing in `x` (a test checks the tables against the formula). 8-bit output
/// (PNG, the viewer's display) goes through here instead of three `powf` per pixel.
#[inline]
pub fn srgb8(x: f32) -> u8 {
    if x.is_nan() || x <= 0.0 {
        return 0;
    }
    if x >= 1.0 {
        return 255;
    }
    let tables = srgb8_tables();
    let mut code = tables.bucket_start[(x * SRGB8_BUCKETS as f32) as usize] as usize;
    while code < 255 && tables.thresholds[code] <= x {
        code += 1;
    }
    code as u8
}

/// Buckets of [0, 1) in [`srgb8`]'s first table.
const SRGB8_BUCKETS: usize = 4096;

/// [`srgb8`]'s tables.
struct Srgb8Tables {
    /// Entry `b − 1`: the smallest non-negative `f32` whose code is at least `b`
    /// (b = 1…255).
    thresholds: [f32; 255],
    /// The code of each bucket's first value, `i / SRGB8_BUCKETS`.
    bucket_start: [u8; SRGB8_BUCKETS],
}

/// `round(255 · srgb_encode(x))` clamped to 0–255, computed directly (the reference
/// [`srgb8`]'s table is built from).
fn srgb8_formula(x: f32) -> u8 {
    (srgb_encode(x) * 255.0 + 0.5).clamp(0.0, 255.0) as u8
}

/// [`srgb8`]'s tables, built on first use: each threshold by bisection over the bit
/// patterns of [0, 1] (ordered like the values), each bucket's first code by the formula.
fn srgb8_tables() -> &'static Srgb8Tables {
    static TABLES: std::sync::OnceLock<Box<Srgb8Tables>> = std::sync::OnceLock::new();
    TABLES.get_or_init(|| {
        let mut thresholds = [0.0; 255];
        for (i, t) in thresholds.iter_mut().enumerate() {
            let code = i as u8 + 1;
            // Invariant: formula(lo) < code <= formula(hi).
            let (mut lo, mut hi) = (0u32, 1f32.to_bits());
            while hi - lo > 1 {
                let mid = lo + (hi - lo) / 2;
                if srgb8_formula(f32::from_bits(mid)) >= code {
                    hi = mid;
                } else {
                    lo = mid;
                }
            }
            *t = f32::from_bits(hi);
        }
        let mut bucket_start = [0; SRGB8_BUCKETS];
        for (i, b) in bucket_start.iter_mut().enumerate() {
            *b = srgb8_formula(i as f32 / SRGB8_BUCKETS as f32);
        }
        Box::new(Srgb8Tables {
            thresholds,
            bucket_start,
        })
    })
}

/// sRGB transfer (encode) of a display-linear value in [0, 1].
#[inline]
pub fn srgb_encode(x: f32) -> f32 {
    if x <= 0.0031308 {
        12.92 * x
    } else {
        1.055 * x.powf(1.0 / 2.4) - 0.055
    }
}

/// sRGB transfer (decode) to display-linear.
#[inline]
pub fn srgb_decode(x: f32) -> f32 {
    if x <= 0.04045 {
        x / 12.92
    } else {
        ((x + 0.055) / 1.055).powf(2.4)
    }
}

/// Writes a linear image as 32-bit float RGB OpenEXR: ZIP compression (16 scan lines a
/// block), increasing line order. The `exr` crate's default encoding (RLE, unspecified
/// line order) crashes tinyexr-based readers (e.g. NVIDIA's FLIP tool); this encoding is
/// read by every common OpenEXR reader.
pub fn write_exr(img: &RgbImage, path: &Path) -> Result<(), ImageError> {
    use exr::prelude::*;
    let w = img.width as usize;
    let encoding = Encoding {
        compression: Compression::ZIP16,
        blocks: Blocks::ScanLines,
        line_order: LineOrder::Increasing,
    };
    let channels = SpecificChannels::rgb(|pos: Vec2<usize>| {
        let p = img.data[pos.y() * w + pos.x()];
        (p.x, p.y, p.z)
    });
    let layer = Layer::new(
        (w, img.height as usize),
        LayerAttributes::default(),
        encoding,
        channels,
    );
    write_atomically(path, |tmp| {
        Image::from_layer(layer)
            .write()
            .to_file(tmp)
            .map_err(|e| e.to_string())
    })
}

/// Writes `path` through `write` into a temporary file in the same folder, renamed over
/// `path` only once complete: a failed write leaves the previous file intact and no
/// partial file behind.
pub fn write_atomically(
    path: &Path,
    write: impl FnOnce(&Path) -> Result<(), String>,
) -> Result<(), ImageError> {
    crate::atomic::write_with(path, write).map_err(|e| ImageError::Write {
        path: path.to_owned(),
        message: match e {
            crate::atomic::AtomicWriteError::Write(m) => m,
            crate::atomic::AtomicWriteError::Rename(e) => e.to_string(),
        },
    })
}

/// Reads a Radiance RGBE (`.hdr`) file as linear RGB.
pub fn read_hdr(path: &Path) -> Result<RgbImage, ImageError> {
    let read_error = |message: String| ImageError::Read {
        path: path.to_owned(),
        message,
    };
    let open = || {
        image::ImageReader::open(path)
            .map_err(|e| read_error(e.to_string()))?
            .with_guessed_format()
            .map_err(|e| read_error(e.to_string()))
    };
    // The name says Radiance HDR: content of another format (a PNG named .hdr) is
    // refused as a .png name is, not decoded as what it happens to be.
    let format = open()?.format();
    if format != Some(image::ImageFormat::Hdr) {
        return Err(read_error(match format {
            Some(f) => {
                format!("not a Radiance HDR file: its content is {f:?} (the name ends in .hdr)")
            }
            None => "not a Radiance HDR file (no #?RADIANCE or #?RGBE header)".into(),
        }));
    }
    if let Some((w, h)) = open().ok().and_then(|r| r.into_dimensions().ok()) {
        check_decoded_size(w, h).map_err(read_error)?;
    }
    let img = open()?
        .decode()
        .map_err(|e| match e {
            // "Memory limit exceeded" alone names no size: the header's claim does.
            image::ImageError::Limits(_) => {
                match open().ok().and_then(|r| r.into_dimensions().ok()) {
                    Some((w, h)) => read_error(format!(
                        "its header claims {w}×{h} pixels, more than the {} MiB illume decodes",
                        image::Limits::default().max_alloc.unwrap_or(0) >> 20
                    )),
                    None => read_error(e.to_string()),
                }
            }
            e => read_error(e.to_string()),
        })?
        .to_rgb32f();
    let (w, h) = img.dimensions();
    let texels = img
        .pixels()
        .map(|p| Rgb::new(p.0[0], p.0[1], p.0[2]))
        .collect();
    Image::from_vec(w, h, texels).ok_or_else(|| read_error("inconsistent size".into()))
}

/// Largest image file [`RgbImage::read`] reads \[bytes\].
pub const MAX_IMAGE_FILE_BYTES: u64 = 4 << 30;

/// Most memory an image read by [`RgbImage::read`] may decode to \[bytes\]: 1 GiB, e.g.
/// 16384 × 5461 linear RGB pixels (the `image` crate's own limit for PNG, JPEG and HDR
/// is 512 MiB).
pub const MAX_DECODED_IMAGE_BYTES: u64 = 1 << 30;

/// The largest block (tile or group of scan lines, as the file's header describes it)
/// [`read_exr`] lets the decoder reserve \[bytes\]: 256 MiB, far above any real block
/// (a 16 384-pixel-wide image in 256-line DWAB blocks with 16 float channels is 256 MiB).
pub const MAX_EXR_BLOCK_BYTES: u64 = 256 << 20;

/// The fewest bytes of an OpenEXR file that one block of pixel data takes: its 8-byte
/// offset-table entry, then its 4-byte position (scan line, or tile coordinates: more)
/// and 4-byte data size (OpenEXR file layout, "Chunk layout").
const MIN_EXR_BLOCK_FILE_BYTES: u64 = 16;

/// Reads the first RGB(A) layer of an OpenEXR file as linear RGB. The header's size is
/// checked against [`MAX_DECODED_IMAGE_BYTES`] before the pixels are allocated.
pub fn read_exr(path: &Path) -> Result<RgbImage, ImageError> {
    let read_error = |message: String| ImageError::Read {
        path: path.to_owned(),
        message,
    };
    // The exr crate says "reference to missing bytes" for an empty or cut file: say what
    // it means, with the file's size.
    let explain = |e: exr::error::Error| {
        let size = std::fs::metadata(path).map_or(0, |m| m.len());
        let text = e.to_string();
        if size == 0 {
            read_error("empty file (0 bytes): not an OpenEXR image".into())
        } else if text.contains("missing bytes") {
            read_error(format!(
                "truncated: the file ends ({size} bytes) before its header or pixel data is complete"
            ))
        } else {
            read_error(text)
        }
    };
    let meta = exr::meta::MetaData::read_from_file(path, false).map_err(explain)?;
    for header in &meta.headers {
        let (w, h) = (header.layer_size.width(), header.layer_size.height());
        if w == 0 || h == 0 {
            return Err(read_error(format!(
                "its header claims {w}×{h} pixels: an empty image"
            )));
        }
        let bytes = (w as u64)
            .saturating_mul(h as u64)
            .saturating_mul(std::mem::size_of::<Rgb>() as u64);
        if bytes > MAX_DECODED_IMAGE_BYTES || w > u32::MAX as usize || h > u32::MAX as usize {
            return Err(read_error(format!(
                "its header claims {w}×{h} pixels, more than the {} MiB illume decodes",
                MAX_DECODED_IMAGE_BYTES >> 20
            )));
        }
        // The exr crate reserves a whole block (a tile, or the compression's group of
        // scan lines over the full width, not clamped to the layer's height) for each
        // chunk it reads: a 1-pixel-high, very wide layer passes the check above but asks
        // for blocks of gigabytes (found by fuzzing: 816 bytes reserved 1.85 GB).
        let pixels_per_block = match header.blocks {
            exr::meta::BlockDescription::Tiles(t) => {
                (t.tile_size.x() as u64).saturating_mul(t.tile_size.y() as u64)
            }
            exr::meta::BlockDescription::ScanLines => {
                (header.compression.scan_lines_per_block() as u64).saturating_mul(w as u64)
            }
        };
        let block_bytes = pixels_per_block.saturating_mul(header.channels.bytes_per_pixel as u64);
        if block_bytes > MAX_EXR_BLOCK_BYTES {
            return Err(read_error(format!(
                "its header claims blocks of {} MiB, more than the {} MiB illume reads at once",
                block_bytes >> 20,
                MAX_EXR_BLOCK_BYTES >> 20
            )));
        }
    }
    // Every block of pixel data takes at least 16 bytes of the file (its offset-table
    // entry, its position and its size), whatever its compression: a file too short for
    // the blocks its header claims is refused here, before the image is allocated (found
    // by fuzzing: 1 063 bytes claiming 1 281 rows of a 1 GB image took 1 GB and 2 s to
    // be refused by the decoder).
    let blocks: u64 = meta.headers.iter().map(|h| h.chunk_count as u64).sum();
    let size = std::fs::metadata(path).map_or(0, |m| m.len());
    if blocks.saturating_mul(MIN_EXR_BLOCK_FILE_BYTES) > size {
        return Err(read_error(format!(
            "truncated: its header claims {blocks} blocks of pixel data, which take at least {} bytes, but the file has {size}",
            blocks.saturating_mul(MIN_EXR_BLOCK_FILE_BYTES)
        )));
    }
    check_exr_block_positions(path).map_err(explain)?;
    // The pixels, allocated here where a refused allocation (a process under a memory
    // limit: `ulimit -v`, a batch job's cgroup) is an error naming the file, rather than
    // an abort inside the decoder; handed to the decoder's first call below (it makes one
    // image, the first layer with RGB channels: each layer was checked above).
    let mut storage: Vec<Rgb> = Vec::new();
    let largest = meta
        .headers
        .iter()
        .map(|h| h.layer_size.width() * h.layer_size.height())
        .max()
        .unwrap_or(0);
    storage.try_reserve_exact(largest).map_err(|_| {
        read_error(format!(
            "cannot allocate {} MiB for its pixels (a memory limit?)",
            (largest as u64 * std::mem::size_of::<Rgb>() as u64) >> 20
        ))
    })?;
    let storage = std::cell::RefCell::new(Some(storage));
    let img = exr::prelude::read_first_rgba_layer_from_file(
        path,
        move |res, _| {
            let (w, h) = (res.width() as u32, res.height() as u32);
            match storage.borrow_mut().take() {
                Some(mut data) => {
                    data.resize(res.width() * res.height(), Rgb::ZERO);
                    Image::from_vec(w, h, data).unwrap_or_else(|| Image::black(w, h))
                }
                None => Image::<Rgb>::black(w, h),
            }
        },
        |img, pos, (r, g, b, _a): (f32, f32, f32, f32)| {
            *img.get_mut(pos.x() as u32, pos.y() as u32) = Rgb::new(r, g, b);
        },
    )
    .map_err(explain)?;
    Ok(img.layer_data.channel_data.pixels)
}

/// Reads every block of the OpenEXR file `path` as stored (not decompressed) and checks
/// that each lies inside the layer its header describes, so that a file whose blocks do
/// not belong to the image it claims is refused before that image is allocated (found by
/// fuzzing: 1.7 KB files claiming 1 GB images, refused by the decoder only at their first
/// block, after the allocation). Costs one more read of the file's compressed bytes.
fn check_exr_block_positions(path: &Path) -> exr::error::Result<()> {
    use exr::block::reader::ChunksReader as _;
    let file = std::io::BufReader::new(std::fs::File::open(path)?);
    let chunks = exr::block::read(file, false)?.all_chunks(false)?;
    let headers = chunks.meta_data().headers.clone();
    for chunk in chunks {
        let chunk = chunk?;
        let header = headers.get(chunk.layer_index).ok_or_else(|| {
            exr::error::Error::Invalid("block of a layer the header lacks".into())
        })?;
        let tile = header.get_block_data_indices(&chunk.compressed_block)?;
        header.get_absolute_block_pixel_coordinates(tile)?;
    }
    Ok(())
}

/// Writes tone-mapped, sRGB-encoded 8-bit PNG.
pub fn write_png(img: &RgbImage, path: &Path, tone: &ToneMap) -> Result<(), ImageError> {
    let bytes = to_srgb8(img, tone);
    write_atomically(path, |tmp| {
        image::save_buffer_with_format(
            tmp,
            &bytes,
            img.width,
            img.height,
            image::ColorType::Rgb8,
            image::ImageFormat::Png,
        )
        .map_err(|e| e.to_string())
    })
}

/// Tone-mapped sRGB 8-bit bytes (RGB, row-major): [`ToneMap::apply`], then [`srgb8`]
/// per channel.
pub fn to_srgb8(img: &RgbImage, tone: &ToneMap) -> Vec<u8> {
    let tone = tone.prepared();
    img.data
        .iter()
        .flat_map(|&p| {
            let d = tone.apply(p);
            [srgb8(d.x), srgb8(d.y), srgb8(d.z)]
        })
        .collect()
}

/// `Ok` when an image of `width × height` pixels fits in [`MAX_DECODED_IMAGE_BYTES`] as
/// linear RGB (12 bytes a pixel, what illume keeps of any image or texture); otherwise
/// the message, saying what the header claims, the size it would take and the limit.
/// Checked on the header before anything is decoded: the `image` crate's own limit
/// (512 MiB) is on the file's own pixel format, so an 8-bit grey PNG passes it with 4×
/// the pixels and takes 12× its decoded size once linear RGB.
pub fn check_decoded_size(width: u32, height: u32) -> Result<(), String> {
    let bytes = u64::from(width) * u64::from(height) * std::mem::size_of::<Rgb>() as u64;
    if bytes > MAX_DECODED_IMAGE_BYTES {
        return Err(format!(
            "its header claims {width}×{height} pixels, {} MiB as linear RGB, more than the {} MiB illume decodes for one image",
            bytes >> 20,
            MAX_DECODED_IMAGE_BYTES >> 20
        ));
    }
    Ok(())
}

/// Reads an 8-bit image (PNG, JPEG) and decodes sRGB to linear; the header's size is
/// checked ([`check_decoded_size`]) before the pixels are decoded.
pub fn read_ldr(path: &Path) -> Result<RgbImage, ImageError> {
    let read_error = |message: String| ImageError::Read {
        path: path.to_owned(),
        message,
    };
    let claimed = image::ImageReader::open(path)
        .and_then(|r| r.with_guessed_format())
        .ok()
        .and_then(|r| r.into_dimensions().ok());
    if let Some((w, h)) = claimed {
        check_decoded_size(w, h).map_err(read_error)?;
    }
    let dynimg = image::open(path).map_err(|e| ImageError::Read {
        path: path.to_owned(),
        message: e.to_string(),
    })?;
    let rgb = dynimg.to_rgb8();
    let (w, h) = rgb.dimensions();
    let data = rgb
        .pixels()
        .map(|p| {
            Rgb::new(
                srgb_decode(p[0] as f32 / 255.0),
                srgb_decode(p[1] as f32 / 255.0),
                srgb_decode(p[2] as f32 / 255.0),
            )
        })
        .collect();
    Ok(Image {
        width: w,
        height: h,
        data,
    })
}

#[cfg(test)]
mod tests {

    #[test]
    fn box_downsample_averages_blocks_and_keeps_the_mean() {
        // 4×2 → 2×1 with k = 2: each output pixel the mean of its 2×2 block.
        let img = RgbImage::from_vec(
            4,
            2,
            [1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0]
                .map(Rgb::splat)
                .to_vec(),
        )
        .unwrap();
        let d = img.box_downsample(2);
        assert_eq!((d.width(), d.height()), (2, 1));
        assert_eq!(d.pixels(), &[Rgb::splat(3.5), Rgb::splat(5.5)]);
        assert_eq!(d.mean(), img.mean());
        // k = 1 is the image itself.
        assert_eq!(img.box_downsample(1), img);
    }

    #[test]
    fn auto_exposure_maps_the_log_average_to_middle_grey() {
        // Uniform radiance L: exposure log2(0.18 / L), whatever L.
        for l in [0.01f32, 1.0, 250.0] {
            let img = RgbImage::filled(4, 4, Rgb::splat(l));
            let ev = auto_exposure_ev(&img).unwrap();
            assert!((ev - (0.18 / l).log2()).abs() < 1e-3, "L = {l}: {ev}");
        }
        // Any image scaled by s: the exposure falls by log2(s) exactly (every weight
        // is relative to the image's own mean).
        let mut img = RgbImage::filled(40, 30, Rgb::ZERO);
        for (i, p) in img.pixels_mut().iter_mut().enumerate() {
            *p = Rgb::splat(match i % 5 {
                0 => 1.0,
                1 => 4.0,
                2 => 0.0,
                3 => f32::NAN,
                _ => 0.3 * (i % 7) as f32,
            });
        }
        let ev = auto_exposure_ev(&img).unwrap();
        let mut brighter = img.clone();
        brighter.pixels_mut().iter_mut().for_each(|p| *p *= 8.0);
        let ev8 = auto_exposure_ev(&brighter).unwrap();
        assert!((ev - ev8 - 3.0).abs() < 1e-3, "{ev} {ev8}");
        // Nothing lit: no exposure to choose.
        assert_eq!(auto_exposure_ev(&RgbImage::filled(2, 2, Rgb::ZERO)), None);
    }

    /// A lit object on black, as two renderers give it: one leaves the shadowed and
    /// background pixels at exactly 0, the other at 10⁻⁶ of residue, and each adds
    /// Monte Carlo noise of its own (4 or 256 samples' worth). The exposure is the same
    /// within 0.3 EV (issue 38: the per-pixel log-average gave +7.3 against +1.1 EV).
    #[test]
    fn auto_exposure_ignores_black_residue_and_noise() {
        let (w, h) = (160u32, 120u32);
        // The object: a disc of radiance falling from 2 to 0.5 across it, in a third of
        // the image; the rest black.
        let clean = |x: u32, y: u32| {
            let (dx, dy) = (x as f32 - 80.0, y as f32 - 60.0);
            if dx * dx + dy * dy < 45.0 * 45.0 {
                2.0 - 1.5 * (x as f32 / w as f32)
            } else {
                0.0
            }
        };
        let mut rng = crate::sampling::Pcg32::new(7, 1);
        let mut render = |spp: u32, residue: f32| {
            let mut img = RgbImage::filled(w, h, Rgb::ZERO);
            for y in 0..h {
                for x in 0..w {
                    let l = clean(x, y);
                    // The mean of `spp` samples each 0 or 4·l with probability 1/4.
                    let hits = (0..spp).filter(|_| rng.next_below(4) == 0).count();
                    let noisy = 4.0 * l * hits as f32 / spp as f32;
                    *img.get_mut(x, y) = Rgb::splat(if l > 0.0 { noisy } else { residue });
                }
            }
            auto_exposure_ev(&img).unwrap()
        };
        let evs = [
            render(4, 0.0),
            render(256, 0.0),
            render(4, 1e-6),
            render(256, 1e-6),
        ];
        let (lo, hi) = evs
            .iter()
            .fold((f32::MAX, f32::MIN), |(a, b), &e| (a.min(e), b.max(e)));
        assert!(hi - lo < 0.3, "{evs:?}");
    }

    use super::*;

    /// Writes go through a temporary file renamed into place: success leaves only the
    /// file, a failure leaves what was there and no partial file.
    #[test]
    fn writes_are_atomic() {
        let dir = std::env::temp_dir().join(format!("illume-atomic-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        let img = RgbImage::filled(4, 3, Rgb::splat(0.5));
        let png = dir.join("a.png");
        write_png(&img, &png, &ToneMap::default()).unwrap();
        write_exr(&img, &dir.join("a.exr")).unwrap();
        let names = |d: &Path| {
            let mut v: Vec<String> = std::fs::read_dir(d)
                .unwrap()
                .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
                .collect();
            v.sort();
            v
        };
        assert_eq!(names(&dir), ["a.exr", "a.png"]);
        // The target is a non-empty folder: the rename fails, the folder stays, and no
        // temporary file is left.
        let blocked = dir.join("b.png");
        std::fs::create_dir_all(blocked.join("inside")).unwrap();
        assert!(write_png(&img, &blocked, &ToneMap::default()).is_err());
        assert!(blocked.join("inside").is_dir());
        assert_eq!(names(&dir), ["a.exr", "a.png", "b.png"]);
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn exr_round_trip_is_exact() {
        let dir = std::env::temp_dir().join(format!("illume-img-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let mut img = RgbImage::black(5, 3);
        for y in 0..3 {
            for x in 0..5 {
                *img.get_mut(x, y) = Rgb::new(x as f32 * 1.5, y as f32 * 100.0, 1e-3);
            }
        }
        let p = dir.join("a.exr");
        img.write(&p, &ToneMap::default()).unwrap();
        let back = RgbImage::read(&p).unwrap();
        assert_eq!(back, img);
    }

    #[test]
    fn png_round_trip_within_quantisation() {
        let dir = std::env::temp_dir().join(format!("illume-img-png-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let img = RgbImage::filled(4, 4, Rgb::new(0.5, 0.2, 0.9));
        let p = dir.join("a.png");
        img.write(
            &p,
            &ToneMap {
                exposure_ev: 0.0,
                curve: ToneCurve::Clamp,
            },
        )
        .unwrap();
        let back = RgbImage::read(&p).unwrap();
        for px in back.pixels() {
            assert!((*px - Rgb::new(0.5, 0.2, 0.9)).abs().max_element() < 0.01);
        }
    }

    #[test]
    fn srgb_transfer_round_trips() {
        for i in 0..=100 {
            let x = i as f32 / 100.0;
            assert!((srgb_decode(srgb_encode(x)) - x).abs() < 1e-5);
        }
    }

    /// The table-driven 8-bit code equals the formula: at every threshold and the value
    /// just below it, on a dense sweep of [0, 1] and on the special values.
    #[test]
    fn srgb8_by_table_equals_the_formula() {
        let table = &srgb8_tables().thresholds;
        for (i, &t) in table.iter().enumerate() {
            assert_eq!(srgb8(t), i as u8 + 1, "threshold {t}");
            assert_eq!(srgb8_formula(t), i as u8 + 1, "threshold {t}");
            let below = f32::from_bits(t.to_bits() - 1);
            assert_eq!(srgb8(below), srgb8_formula(below), "below {t}");
            assert_eq!(srgb8_formula(below), i as u8, "below {t}");
        }
        for k in 0..=1_000_000u32 {
            let x = k as f32 / 1e6;
            assert_eq!(srgb8(x), srgb8_formula(x), "{x}");
        }
        for x in [
            -1.0,
            -0.0,
            0.0,
            1e-30,
            0.0031308,
            1.0,
            1.5,
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::NAN,
        ] {
            assert_eq!(srgb8(x), srgb8_formula(x), "{x}");
        }
        // The formula is non-decreasing over every f32 of [0, 1] near each threshold
        // (the table's premise): 64 values either side.
        // Every bucket boundary and the value just below it.
        for i in 1..SRGB8_BUCKETS {
            let x = i as f32 / SRGB8_BUCKETS as f32;
            let below = f32::from_bits(x.to_bits() - 1);
            assert_eq!(srgb8(x), srgb8_formula(x), "{x}");
            assert_eq!(srgb8(below), srgb8_formula(below), "{below}");
        }
        for &t in table {
            let b = t.to_bits();
            let codes: Vec<u8> = (b.saturating_sub(64)..b + 64)
                .map(|u| srgb8_formula(f32::from_bits(u)))
                .collect();
            assert!(codes.windows(2).all(|w| w[0] <= w[1]), "around {t}");
        }
    }

    #[test]
    fn missing_file_error_names_it() {
        let e = RgbImage::read(Path::new("/nonexistent/x.exr")).unwrap_err();
        assert!(e.to_string().contains("/nonexistent/x.exr"));
    }
}
