//! The `.illumepc` file: precomputed keys (a shard's raw key images, `kind = "partial"`)
//! or their PCA (`kind = "pca"`), versioned and checksummed.
//!
//! # Layout (all integers little-endian)
//!
//! | bytes | content |
//! | --- | --- |
//! | 8 | magic `ILLUMEPC` |
//! | 4 | format version, u32 ([`VERSION`]) |
//! | 4 | header length H, u32 |
//! | H | the header: UTF-8 TOML ([`Header`]) |
//! | 8 | FNV-1a 64 of the header bytes, u64 |
//! | … | the sections, back to back, in the header's order: `values` numbers each, f32 (4 bytes) or IEEE half f16 (2 bytes) |
//!
//! The header lists every section (name, format, number of values, FNV-1a 64 of its bytes
//! as 16 hex digits), the settings, the sun, the domain and sizes, the keys with their
//! dark flags, the eigenvalues, the exposure and the static-scene fingerprint
//! ([`scene_fingerprint`]). A reader checks, in this order: magic, version, header
//! checksum, header, total length, each section's checksum; each failure is its own
//! [`FileError`] naming the file. Files are written to a temporary sibling and renamed.
//!
//! New sections extend the format without a new version: a reader looks sections up by
//! name, so a file without one that came later (`sky.direct`, the sky's direct light,
//! [`crate::precompute::SKY_DIRECT`]) still loads, its feature off (warned).

use illume_scene::Scene;
use serde::{Deserialize, Serialize};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// The 8 bytes every `.illumepc` file starts with.
pub const MAGIC: &[u8; 8] = b"ILLUMEPC";
/// The format version this build reads and writes.
pub const VERSION: u32 = 1;
/// Largest file read \[bytes\] (an 8K atlas of 288 keys is ~40 GB raw; PCA files are small).
pub const MAX_FILE_BYTES: u64 = 64 << 30;
/// Most keys a file (and a precompute) may hold: a key a second over a whole day. Every
/// key is rendered and kept in memory (a PCA needs all of them), so more is never a
/// schedule but a typing error; the same rule as `animate`'s and `bench`'s frame caps.
pub const MAX_KEYS: usize = 86_400;
/// Largest key image side \[texels\] a header may state (an 8K atlas is 8192 wide;
/// a cube file's height is 6 faces).
pub const MAX_KEY_SIDE: u32 = 1 << 16;

/// Bytes a precompute or a merge holds for `keys` key images of `width × height`
/// texels: each key as linear RGB (12 bytes a texel) and the PCA's copy of it in its
/// channel groups (as much again).
pub fn keys_bytes(keys: usize, width: u32, height: u32) -> u64 {
    (keys as u64)
        .saturating_mul(u64::from(width) * u64::from(height))
        .saturating_mul(24)
}

/// The most keys `settings` can make: the uniform schedule's count, or for the adaptive
/// one a key every `step_min` with both ends.
pub fn most_keys(settings: &crate::PrecomputedSettings) -> usize {
    let s = settings;
    match s.schedule {
        crate::settings::ScheduleKind::Uniform => {
            crate::schedule::uniform(s.from_h, s.to_h, s.step_min).len()
        }
        crate::settings::ScheduleKind::Adaptive => {
            let n = ((s.to_h - s.from_h) * 60.0 / s.step_min).ceil() + 1.0;
            n.clamp(1.0, MAX_KEYS as f64 + 1.0) as usize
        }
    }
}

/// `Ok` when [`keys_bytes`] fits in the memory this process may still allocate
/// ([`illume_render::available_memory_bytes`]); else a message with both sizes and why.
/// Every key is held in memory for the PCA, so a run that cannot hold them would abort
/// at its last key (after hours of rendering): checked before any key is rendered or
/// read, the same rule as `render`'s image size and `animate`'s frames.
pub fn check_keys_memory(keys: usize, width: u32, height: u32) -> Result<(), String> {
    let need = keys_bytes(keys, width, height);
    match illume_render::available_memory_bytes() {
        Some(available) if need > available => Err(format!(
            "{keys} keys of {width}×{height} texels need about {} MiB (every key is held in \
             memory for the PCA, as linear RGB and again in its PCA groups), more than the \
             {} MiB available: use fewer keys (a larger step_min, a shorter from_h–to_h) or \
             a smaller image, or merge the shards on a machine with more memory",
            need >> 20,
            available >> 20
        )),
        _ => Ok(()),
    }
}

/// What can be wrong with a `.illumepc` file. Every variant names the file.
#[derive(Debug, thiserror::Error)]
pub enum FileError {
    /// It could not be read or written.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The system's error.
        source: std::io::Error,
    },
    /// It does not start with `ILLUMEPC`.
    #[error("{path}: not an .illumepc file (the first 8 bytes are not ILLUMEPC)")]
    Magic {
        /// The file.
        path: PathBuf,
    },
    /// It was written by another format version.
    #[error(
        "{path}: .illumepc format version {found}; this build reads version {expected} (precompute it again)"
    )]
    Version {
        /// The file.
        path: PathBuf,
        /// Its version.
        found: u32,
        /// Ours.
        expected: u32,
    },
    /// It ends early.
    #[error("{path}: truncated: {needed} bytes needed for {what}, the file has {got}")]
    Truncated {
        /// The file.
        path: PathBuf,
        /// What was being read.
        what: String,
        /// Bytes needed up to the end of it.
        needed: u64,
        /// Bytes in the file.
        got: u64,
    },
    /// A checksum does not match (a flipped byte).
    #[error(
        "{path}: checksum of {what} does not match (expected {expected:016x}, found {found:016x}): the file is corrupt"
    )]
    Checksum {
        /// The file.
        path: PathBuf,
        /// The header or a section name.
        what: String,
        /// Stored checksum.
        expected: u64,
        /// Checksum of the bytes read.
        found: u64,
    },
    /// The header is not valid TOML of the expected shape.
    #[error("{path}: header: {message}")]
    Header {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        message: String,
    },
    /// Bytes after the last section.
    #[error("{path}: {extra} bytes after the last section")]
    Trailing {
        /// The file.
        path: PathBuf,
        /// How many.
        extra: u64,
    },
    /// It was precomputed for another scene (or the static scene changed since).
    #[error(
        "{path}: precomputed for another scene: the file's static-scene fingerprint is {found} ({found_source}), the scene's is {expected} ({expected_source})"
    )]
    OtherScene {
        /// The file.
        path: PathBuf,
        /// The scene's fingerprint.
        expected: String,
        /// Where the scene came from.
        expected_source: String,
        /// The file's fingerprint.
        found: String,
        /// The source named in the file.
        found_source: String,
    },
    /// A header field or a section value is out of range (checked on every read, before
    /// anything indexes with it).
    #[error("{path}: {field} = {value}: {reason}")]
    Invalid {
        /// The file.
        path: PathBuf,
        /// The header field or section (and index) that is wrong.
        field: String,
        /// Its value, as read.
        value: String,
        /// What it must be.
        reason: String,
    },
    /// The output path holds something that is not an `.illumepc` file: illume
    /// overwrites only its own files.
    #[error(
        "{path}: exists and is not an .illumepc file (it does not start with ILLUMEPC); illume overwrites only its own files: choose another --output or move it away"
    )]
    NotOurs {
        /// The file.
        path: PathBuf,
    },
    /// The file's camera or image size differs from the run's (screen and cube domains).
    #[error("{path}: {what} differs: the file has {found}, this run has {expected}")]
    Mismatch {
        /// The file.
        path: PathBuf,
        /// What differs.
        what: String,
        /// The run's value.
        expected: String,
        /// The file's value.
        found: String,
    },
}

/// How a section's numbers are stored.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum SectionFormat {
    /// 4-byte IEEE single.
    F32,
    /// 2-byte IEEE half (values rounded to nearest; 11 significant bits).
    F16,
}

impl SectionFormat {
    /// Bytes per stored number.
    pub fn bytes(self) -> u64 {
        match self {
            SectionFormat::F32 => 4,
            SectionFormat::F16 => 2,
        }
    }
}

/// One section as listed in the header.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SectionInfo {
    /// Name (`mean.r`, `temporal.r`, `images.r`, `key.12`, `sky`, `sky.direct`, …).
    pub name: String,
    /// Storage.
    pub format: SectionFormat,
    /// Number of values.
    pub values: u64,
    /// FNV-1a 64 of the stored bytes, 16 hex digits.
    pub fnv1a64: String,
}

/// One key as listed in the header.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct KeyInfo {
    /// Local clock time \[hours\].
    pub hours: f64,
    /// Adaptive level that added it (0 for uniform keys).
    pub level: u32,
    /// Sun below the horizon: exactly black, not rendered, not in the PCA.
    pub dark: bool,
}

/// The `atlas` domain's layout, as listed in the header: the run time rebuilds the
/// layout from the scene and checks it against `layout_checksum`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AtlasInfo {
    /// Lightmap width and height \[texels\] (the key image holds the probes' values in
    /// the rows after them).
    pub lightmap: [u32; 2],
    /// Texels per metre.
    pub density: f32,
    /// Probe spacing \[m\].
    pub probe_spacing: f32,
    /// Probes along x, y, z.
    pub probe_dims: [u32; 3],
    /// [`crate::atlas::Atlas::checksum`], 16 hex digits.
    pub layout_checksum: String,
}

/// The TOML header.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Header {
    /// `partial` (a shard's raw keys) or `pca` (the merged, compressed file).
    pub kind: String,
    /// The scene's source (`builtin:sun-room`, a path), for messages.
    pub scene_source: String,
    /// Static-scene fingerprint ([`scene_fingerprint`]), 16 hex digits.
    pub scene_fingerprint: String,
    /// The technique settings used (the `[precomputed]` table).
    pub settings: toml::Table,
    /// The `[sun]` table.
    pub sun: toml::Table,
    /// `screen`, `cube` or `atlas`.
    pub domain: String,
    /// Width of one key image (screen: pixels; cube: face side; atlas: texels).
    pub width: u32,
    /// Height of one key image.
    pub height: u32,
    /// Values per texel (3: RGB).
    pub channels: u32,
    /// The camera the keys were rendered from (screen and cube): `world_from_camera` as
    /// 12 numbers (column-major 3×4) and the vertical field of view \[rad\].
    pub camera: Vec<f32>,
    /// Exposure at which key images are compared with the Yee metric (`to_srgb8`).
    pub exposure: f32,
    /// Shard `[K, N]` of a partial file (`[0, 1]`: unsharded).
    pub shard: [u32; 2],
    /// The `atlas` layout (absent for other domains).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub atlas: Option<AtlasInfo>,
    /// The keys, sorted by time.
    pub keys: Vec<KeyInfo>,
    /// PCA: kept components k.
    pub components: u32,
    /// PCA: `per-channel` or `joint`.
    pub colour: String,
    /// PCA: all eigenvalues, largest first, per channel group.
    pub eigenvalues: Vec<Vec<f64>>,
    /// The sections that follow the header, in order.
    pub sections: Vec<SectionInfo>,
}

/// A section's name and numbers, in memory.
#[derive(Clone, Debug, PartialEq)]
pub struct Section {
    /// Its name.
    pub name: String,
    /// Storage on disk.
    pub format: SectionFormat,
    /// Its numbers (f16 sections hold the rounded values).
    pub values: Vec<f32>,
}

/// A whole file in memory.
#[derive(Clone, Debug, PartialEq)]
pub struct PcFile {
    /// The header (its `sections` list is rebuilt on write).
    pub header: Header,
    /// The sections.
    pub sections: Vec<Section>,
}

/// The error of `bytes` (read from `path`) ending before `needed` bytes, in `what`.
fn truncated(path: &Path, bytes: &[u8], what: &str, needed: u64) -> FileError {
    FileError::Truncated {
        path: path.to_path_buf(),
        what: what.to_string(),
        needed,
        got: bytes.len() as u64,
    }
}

/// FNV-1a 64 (as `illume-bench`'s cache keys).
pub fn fnv1a64(bytes: impl IntoIterator<Item = impl std::borrow::Borrow<u8>>) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for b in bytes {
        h ^= *b.borrow() as u64;
        h = h.wrapping_mul(0x0100_0000_01b3);
    }
    h
}

/// The canonical text of the static scene (built like `illume-bench`'s `CacheKey`: one
/// line per item, f32 in Debug form, which round-trips exactly) and its FNV-1a 64 as 16
/// hex digits. Covers static instances (name, mesh, transform), every mesh's vertices and
/// indices (as a hash), materials and the sky; not dynamic instances, lights or camera.
pub fn scene_fingerprint(scene: &Scene) -> (String, String) {
    let mut text = String::new();
    let _ = writeln!(text, "illumepc {VERSION}");
    for inst in scene.instances.iter().filter(|i| !i.dynamic) {
        let _ = writeln!(
            text,
            "instance {:?} mesh {} mask {} {:?}",
            inst.name,
            inst.mesh.index(),
            inst.mask,
            inst.world_from_object
        );
    }
    for (i, mesh) in scene.meshes.iter().enumerate() {
        let mut bytes = Vec::with_capacity(mesh.positions.len() * 12 + mesh.indices.len() * 12);
        for p in &mesh.positions {
            for c in p.to_array() {
                bytes.extend_from_slice(&c.to_le_bytes());
            }
        }
        for t in &mesh.indices {
            for v in t {
                bytes.extend_from_slice(&v.to_le_bytes());
            }
        }
        for m in &mesh.triangle_materials {
            bytes.extend_from_slice(&m.0.to_le_bytes());
        }
        let _ = writeln!(text, "mesh {i} {:?} {:016x}", mesh.name, fnv1a64(&bytes));
    }
    for m in &scene.materials {
        let _ = writeln!(text, "material {m:?}");
    }
    // The sky at scale 1: a sun path scales the scene's sky with the time of day.
    let sky = scene.sun.as_ref().map_or(&scene.sky, |sun| &sun.sky_base);
    match sky {
        // An environment map by its texels' hash: its Debug text would print every texel
        // (a string of about 1 GB for an 8192 × 4096 map).
        Some(illume_scene::Sky::Equirect(map)) => {
            let bytes = map
                .texels
                .iter()
                .flat_map(|t| t.to_array())
                .flat_map(f32::to_le_bytes);
            let _ = writeln!(
                text,
                "sky map {:?} {}x{} scale {:?} rotation {:?} texels {:016x}",
                map.name,
                map.width,
                map.height,
                map.scale,
                map.rotation_deg,
                fnv1a64(bytes)
            );
        }
        _ => {
            let _ = writeln!(text, "sky {sky:?}");
        }
    }
    let hash = format!("{:016x}", fnv1a64(text.as_bytes()));
    (text, hash)
}

fn encode(section: &Section) -> Vec<u8> {
    match section.format {
        SectionFormat::F32 => section
            .values
            .iter()
            .flat_map(|v| v.to_le_bytes())
            .collect(),
        SectionFormat::F16 => section
            .values
            .iter()
            .flat_map(|v| half::f16::from_f32(*v).to_le_bytes())
            .collect(),
    }
}

/// [`check_overwritable`], then the output's folder created if need be (as `render -o`
/// creates its own): both before hours of rendering.
pub fn prepare_output(path: &Path) -> Result<(), FileError> {
    check_overwritable(path)?;
    if let Some(parent) = path.parent()
        && !parent.as_os_str().is_empty()
    {
        std::fs::create_dir_all(parent).map_err(|source| FileError::Io {
            path: parent.to_path_buf(),
            source,
        })?;
    }
    Ok(())
}

/// Whether `path` may be written: it does not exist, or it is a regular file that starts
/// with [`MAGIC`] (an earlier `.illumepc` file). Anything else — a user's file, a folder,
/// a link — is refused, untouched. Call it before the work that makes the file, too.
pub fn check_overwritable(path: &Path) -> Result<(), FileError> {
    use std::io::Read;
    let meta = match std::fs::symlink_metadata(path) {
        Ok(m) => m,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(()),
        Err(source) => {
            return Err(FileError::Io {
                path: path.to_path_buf(),
                source,
            });
        }
    };
    let mut magic = Vec::new();
    if meta.is_file()
        && let Ok(file) = std::fs::File::open(path)
    {
        let _ = file.take(8).read_to_end(&mut magic);
    }
    if magic == MAGIC {
        return Ok(());
    }
    Err(FileError::NotOurs {
        path: path.to_path_buf(),
    })
}

impl Header {
    /// Checks every field a reader indexes or computes with (issue 38): the kind and
    /// domain are known, sizes within [`MAX_KEY_SIDE`] and of the domain's shape (a
    /// screen image within the render size limit, six square cube faces, an atlas within
    /// its texel limit, the atlas layout's numbers finite and > 0), three channels, the camera 13
    /// finite numbers, the exposure finite and > 0, the shard `K < N ≤` [`MAX_KEYS`], the keys at most
    /// [`MAX_KEYS`], their times finite and strictly increasing, the components at most
    /// the keys in the PCA, the eigenvalues finite. `path` is only named in errors.
    pub fn check(&self, path: &Path) -> Result<(), FileError> {
        let invalid = |field: &str, value: String, reason: &str| FileError::Invalid {
            path: path.to_path_buf(),
            field: field.into(),
            value,
            reason: reason.into(),
        };
        if !["partial", "pca", "levels"].contains(&self.kind.as_str()) {
            return Err(invalid(
                "kind",
                format!("{:?}", illume_scene::excerpt(&self.kind)),
                "must be partial, pca or levels",
            ));
        }
        if !["screen", "cube", "atlas"].contains(&self.domain.as_str()) {
            return Err(invalid(
                "domain",
                format!("{:?}", illume_scene::excerpt(&self.domain)),
                "must be screen, cube or atlas",
            ));
        }
        for (field, v) in [("width", self.width), ("height", self.height)] {
            if v == 0 || v > MAX_KEY_SIDE {
                return Err(invalid(
                    field,
                    v.to_string(),
                    &format!("must be 1–{MAX_KEY_SIDE} texels"),
                ));
            }
        }
        // The shapes a precompute writes, so that nothing sized by the header (a dark
        // key's black image, the atlas) is larger than a run could have made it.
        let (w, h) = (u64::from(self.width), u64::from(self.height));
        let shape = match self.domain.as_str() {
            "screen" => (self.width <= illume_render::MAX_IMAGE_SIDE
                && self.height <= illume_render::MAX_IMAGE_SIDE)
                .then_some(())
                .ok_or(format!(
                    "a screen key is an image of at most {0}×{0} pixels",
                    illume_render::MAX_IMAGE_SIDE
                )),
            "cube" => (h == 6 * w)
                .then_some(())
                .ok_or("a cube key is six square faces: height = 6 × width".to_owned()),
            _ => (w * h <= crate::atlas::MAX_TEXELS + w)
                .then_some(())
                .ok_or(format!(
                    "an atlas key holds at most {} texels",
                    crate::atlas::MAX_TEXELS
                )),
        };
        if let Err(reason) = shape {
            return Err(invalid(
                "width/height",
                format!("{}×{} ({})", self.width, self.height, self.domain),
                &reason,
            ));
        }
        if let Some(atlas) = &self.atlas {
            for (field, v) in [
                ("atlas.density", atlas.density),
                ("atlas.probe_spacing", atlas.probe_spacing),
            ] {
                if !(v.is_finite() && v > 0.0) {
                    return Err(invalid(field, v.to_string(), "must be finite and > 0"));
                }
            }
            let [lw, lh] = atlas.lightmap;
            if lw != self.width || lh == 0 || lh > self.height {
                return Err(invalid(
                    "atlas.lightmap",
                    format!("[{lw}, {lh}]"),
                    &format!(
                        "must be as wide as the key image and at most as high ({}×{})",
                        self.width, self.height
                    ),
                ));
            }
        }
        if self.channels != 3 {
            return Err(invalid(
                "channels",
                self.channels.to_string(),
                "must be 3 (RGB)",
            ));
        }
        if self.camera.len() != 13 || self.camera.iter().any(|v| !v.is_finite()) {
            return Err(invalid(
                "camera",
                format!("{:?}", &self.camera[..self.camera.len().min(13)]),
                "must be 13 finite numbers (a 3×4 matrix and the field of view)",
            ));
        }
        if !(self.exposure.is_finite() && self.exposure > 0.0) {
            return Err(invalid(
                "exposure",
                self.exposure.to_string(),
                "must be finite and > 0",
            ));
        }
        let [k, n] = self.shard;
        if n == 0 || k >= n || n as usize > MAX_KEYS {
            return Err(invalid(
                "shard",
                format!("[{k}, {n}]"),
                &format!("must be [K, N] with K < N ≤ {MAX_KEYS} (at most a shard per key)"),
            ));
        }
        if self.keys.len() > MAX_KEYS {
            return Err(invalid(
                "keys",
                format!("{} keys", self.keys.len()),
                &format!("at most {MAX_KEYS} (a key a second for a day)"),
            ));
        }
        if self.kind != "partial" && self.keys.is_empty() {
            return Err(invalid("keys", "none".into(), "a merged file needs a key"));
        }
        for (i, key) in self.keys.iter().enumerate() {
            let after_previous = i == 0 || key.hours > self.keys[i - 1].hours;
            if !key.hours.is_finite() || !after_previous {
                return Err(invalid(
                    &format!("keys[{i}].hours"),
                    key.hours.to_string(),
                    "key times must be finite and strictly increasing",
                ));
            }
        }
        let bright = self.keys.iter().filter(|k| !k.dark).count();
        if self.components as usize > bright {
            return Err(invalid(
                "components",
                self.components.to_string(),
                &format!("more than the {bright} keys in the PCA"),
            ));
        }
        for (g, values) in self.eigenvalues.iter().enumerate() {
            if let Some(i) = values.iter().position(|v| !v.is_finite()) {
                return Err(invalid(
                    &format!("eigenvalues[{g}][{i}]"),
                    values[i].to_string(),
                    "must be finite",
                ));
            }
        }
        Ok(())
    }
}

impl PcFile {
    /// The file's bytes (the header's section list rebuilt from `sections`).
    pub fn to_bytes(&self) -> Vec<u8> {
        let encoded: Vec<Vec<u8>> = self.sections.iter().map(encode).collect();
        let mut header = self.header.clone();
        header.sections = self
            .sections
            .iter()
            .zip(&encoded)
            .map(|(s, bytes)| SectionInfo {
                name: s.name.clone(),
                format: s.format,
                values: s.values.len() as u64,
                fnv1a64: format!("{:016x}", fnv1a64(bytes)),
            })
            .collect();
        // A header always serialises (plain data, finite or not: TOML has nan/inf).
        let text = toml::to_string(&header).unwrap_or_default();
        let mut out =
            Vec::with_capacity(24 + text.len() + encoded.iter().map(Vec::len).sum::<usize>());
        out.extend_from_slice(MAGIC);
        out.extend_from_slice(&VERSION.to_le_bytes());
        out.extend_from_slice(&(text.len() as u32).to_le_bytes());
        out.extend_from_slice(text.as_bytes());
        out.extend_from_slice(&fnv1a64(text.as_bytes()).to_le_bytes());
        for bytes in encoded {
            out.extend_from_slice(&bytes);
        }
        out
    }

    /// Writes the file (temporary sibling, then rename), over an earlier file only when
    /// that is an `.illumepc` file ([`check_overwritable`]).
    pub fn write(&self, path: &Path) -> Result<(), FileError> {
        check_overwritable(path)?;
        illume_core::atomic::write_file(path, self.to_bytes()).map_err(|source| FileError::Io {
            path: path.to_path_buf(),
            source,
        })
    }

    /// Reads and checks a file.
    pub fn read(path: &Path) -> Result<Self, FileError> {
        let bytes = illume_core::files::read_regular(path, MAX_FILE_BYTES).map_err(|source| {
            FileError::Io {
                path: path.to_path_buf(),
                source,
            }
        })?;
        Self::from_bytes(path, &bytes)
    }

    /// Reads and checks only the header of the file at `path` (its magic, version and
    /// header checksum), not its sections: what a caller needs to know about a file
    /// before loading it (its `[sun]`, domain, sizes).
    pub fn read_header(path: &Path) -> Result<Header, FileError> {
        use std::io::Read;
        let io = |source| FileError::Io {
            path: path.to_path_buf(),
            source,
        };
        let mut file = std::fs::File::open(path).map_err(io)?;
        let mut prefix = Vec::new();
        (&mut file).take(16).read_to_end(&mut prefix).map_err(io)?;
        if prefix.len() == 16 && &prefix[..8] == MAGIC {
            let len = u32::from_le_bytes([prefix[12], prefix[13], prefix[14], prefix[15]]);
            // A header longer than the whole-file limit is a corrupt length: read what
            // is there and let the parser report the truncation.
            let want = (len as u64 + 8).min(MAX_FILE_BYTES);
            file.take(want).read_to_end(&mut prefix).map_err(io)?;
        }
        Self::parse_header(path, &prefix).map(|(header, _)| header)
    }

    /// Parses and checks the magic, version and header at the start of `bytes`; returns
    /// the header and the offset of the first section. `path` is only named in errors.
    fn parse_header(path: &Path, bytes: &[u8]) -> Result<(Header, usize), FileError> {
        let p = || path.to_path_buf();
        let truncated = |what: &str, needed: u64| truncated(path, bytes, what, needed);
        if bytes.len() < 8 {
            // Too short even for the magic: call it what it starts like.
            if MAGIC.starts_with(bytes) && !bytes.is_empty() {
                return Err(truncated("the magic", 8));
            }
            return Err(FileError::Magic { path: p() });
        }
        if &bytes[..8] != MAGIC {
            return Err(FileError::Magic { path: p() });
        }
        if bytes.len() < 16 {
            return Err(truncated("the version and header length", 16));
        }
        let u32_at =
            |o: usize| u32::from_le_bytes([bytes[o], bytes[o + 1], bytes[o + 2], bytes[o + 3]]);
        let version = u32_at(8);
        if version != VERSION {
            return Err(FileError::Version {
                path: p(),
                found: version,
                expected: VERSION,
            });
        }
        let header_len = u32_at(12) as usize;
        let header_end = 16 + header_len;
        if bytes.len() < header_end + 8 {
            return Err(truncated("the header", header_end as u64 + 8));
        }
        let header_bytes = &bytes[16..header_end];
        let mut sum = [0u8; 8];
        sum.copy_from_slice(&bytes[header_end..header_end + 8]);
        let (expected, found) = (u64::from_le_bytes(sum), fnv1a64(header_bytes));
        if expected != found {
            return Err(FileError::Checksum {
                path: p(),
                what: "the header".into(),
                expected,
                found,
            });
        }
        let text = std::str::from_utf8(header_bytes).map_err(|e| FileError::Header {
            path: p(),
            message: format!("not UTF-8: {e}"),
        })?;
        let header: Header = toml::from_str(text).map_err(|e| FileError::Header {
            path: p(),
            message: e.to_string(),
        })?;
        header.check(path)?;
        Ok((header, header_end + 8))
    }

    /// Parses and checks a file's bytes; `path` is only named in errors.
    pub fn from_bytes(path: &Path, bytes: &[u8]) -> Result<Self, FileError> {
        let p = || path.to_path_buf();
        let got = bytes.len() as u64;
        let truncated = |what: &str, needed: u64| truncated(path, bytes, what, needed);
        let (header, header_end) = Self::parse_header(path, bytes)?;
        let header_end = header_end - 8;
        let mut offset = header_end as u64 + 8;
        let mut sections = Vec::with_capacity(header.sections.len());
        for info in &header.sections {
            let size = info.format.bytes();
            let end = info
                .values
                .checked_mul(size)
                .and_then(|n| n.checked_add(offset))
                .ok_or_else(|| FileError::Header {
                    path: p(),
                    message: format!("section {} is too large", info.name),
                })?;
            if end > got {
                return Err(truncated(&format!("section {}", info.name), end));
            }
            let data = &bytes[offset as usize..end as usize];
            let expected =
                u64::from_str_radix(&info.fnv1a64, 16).map_err(|_| FileError::Header {
                    path: p(),
                    message: format!(
                        "section {}: checksum {:?} is not 16 hex digits",
                        info.name, info.fnv1a64
                    ),
                })?;
            let found = fnv1a64(data);
            if expected != found {
                return Err(FileError::Checksum {
                    path: p(),
                    what: format!("section {}", info.name),
                    expected,
                    found,
                });
            }
            let values: Vec<f32> = match info.format {
                SectionFormat::F32 => data
                    .chunks_exact(4)
                    .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
                    .collect(),
                SectionFormat::F16 => data
                    .chunks_exact(2)
                    .map(|c| half::f16::from_le_bytes([c[0], c[1]]).to_f32())
                    .collect(),
            };
            // A NaN or infinite value would render as 0 or poison every texel it
            // reaches: a checksum only proves the bytes are the ones written.
            if let Some(i) = values.iter().position(|v| !v.is_finite()) {
                return Err(FileError::Invalid {
                    path: p(),
                    field: format!("section {} value {i}", info.name),
                    value: values[i].to_string(),
                    reason: "every stored value must be finite".into(),
                });
            }
            sections.push(Section {
                name: info.name.clone(),
                format: info.format,
                values,
            });
            offset = end;
        }
        if offset < got {
            return Err(FileError::Trailing {
                path: p(),
                extra: got - offset,
            });
        }
        Ok(Self { header, sections })
    }

    /// The section called `name`.
    pub fn section(&self, name: &str) -> Option<&Section> {
        self.sections.iter().find(|s| s.name == name)
    }

    /// How much smaller this file is than its lit keys stored raw ([`Compression`]);
    /// `None` for a file that is not `pca` or has no lit key.
    pub fn compression(&self) -> Option<Compression> {
        let h = &self.header;
        let lit = h.keys.iter().filter(|k| !k.dark).count() as f64;
        let raw_values = lit * f64::from(h.width) * f64::from(h.height) * f64::from(h.channels);
        if h.kind != "pca" || raw_values == 0.0 {
            return None;
        }
        let is_key_section = |s: &&Section| {
            ["mean.", "temporal.", "images."]
                .iter()
                .any(|p| s.name.starts_with(p))
        };
        Some(Compression {
            raw_bytes: raw_values * 4.0,
            stored_bytes: self
                .sections
                .iter()
                .map(|s| s.values.len() as f64 * s.format.bytes() as f64)
                .sum(),
            raw_values,
            key_values: self
                .sections
                .iter()
                .filter(is_key_section)
                .map(|s| s.values.len() as f64)
                .sum(),
        })
    }
}

/// A `pca` file's size against its lit keys stored raw (f32 values).
///
/// Two measures, both printed by `illume precompute info`:
/// - **bytes**: the whole file (every section, in its stored format, f16 or f32) against
///   the lit keys in f32 — what the disk and memory see;
/// - **key values** (the paper's measure, Bahnsen et al. §4.1: "ten eigenvectors with a
///   dimension of 180 and ten projected vectors with a dimension of 480 000" against the
///   180 images, 94.5 %): the numbers that restore the keys (the k component images, the
///   k × T coefficients and each key's mean) against the keys' numbers. The sky's images
///   are left out of this one, as the paper leaves out its skylight image (§3: "computed
///   separately", "precomputed once and scaled"), which is not part of the compressed
///   sequence; the bytes measure counts them.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Compression {
    /// The lit keys' values × 4 bytes.
    pub raw_bytes: f64,
    /// Every section's bytes as stored.
    pub stored_bytes: f64,
    /// Lit keys × texels × channels.
    pub raw_values: f64,
    /// Values of the `mean.*`, `temporal.*` and `images.*` sections.
    pub key_values: f64,
}

impl Compression {
    /// `1 − stored / raw` in bytes.
    pub fn of_bytes(&self) -> f64 {
        1.0 - self.stored_bytes / self.raw_bytes
    }

    /// `1 − key values / raw values` (the paper's measure).
    pub fn of_key_values(&self) -> f64 {
        1.0 - self.key_values / self.raw_values
    }
}

impl PcFile {
    /// Checks that the file was precomputed for `scene`'s static part.
    pub fn check_scene(&self, path: &Path, scene: &Scene) -> Result<(), FileError> {
        let (_, fingerprint) = scene_fingerprint(scene);
        if fingerprint == self.header.scene_fingerprint {
            return Ok(());
        }
        Err(FileError::OtherScene {
            path: path.to_path_buf(),
            expected: fingerprint,
            expected_source: scene.source.clone(),
            found: self.header.scene_fingerprint.clone(),
            found_source: self.header.scene_source.clone(),
        })
    }
}
