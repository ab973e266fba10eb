//! The converged-reference cache: one EXR per distinct scene state, named by a hash of
//! everything the image depends on, so a second run (or another scenario with the same
//! scene, state and settings) reuses it instead of path tracing again.
//!
//! The key text holds the illume version, the scene's identity (built-in name, or file
//! path, size and modification time), the scene *state* the frame shows — every
//! instance's, light's and the camera's world transform, every light's emission and
//! every material — and the reference settings (size, spp, seed, roulette depth). The
//! state is what the frame time and the scripted edits applied so far produce, so two
//! frames of a static scene share one reference, and a changed setting changes the key.
//! The key text is stored beside the image (`HASH.key.txt`) for inspection.
//!
//! Beside each image rendered since the halves were kept, `HASH.half.exr` holds the mean
//! of its first ⌊spp/2⌋ samples. The second half's mean follows from the two (2·full −
//! half for an even spp), and the two halves are independent (every sample has its own
//! random stream), so their difference measures the reference's own noise: the floor
//! under every error measured against it ([`HalfImages`]).

use crate::error::BenchError;
use illume_core::image::RgbImage;
use illume_reference::ReferenceSettings;
use illume_scene::Scene;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// What a converged reference image depends on, as text and its 64-bit hash.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct CacheKey {
    /// The canonical description (one `name value` line per item).
    pub text: String,
    /// FNV-1a 64 of `text`.
    pub hash: u64,
}

impl CacheKey {
    /// The key of the converged reference of `scene` in its current state, rendered with
    /// `settings` at `width × height` pixels; `scene_identity` names the scene's content
    /// (see [`Scenario::scene_identity`](crate::Scenario::scene_identity)).
    pub fn new(
        scene_identity: &str,
        scene: &Scene,
        settings: &ReferenceSettings,
        (width, height): (u32, u32),
    ) -> Self {
        let mut text = String::new();
        let _ = writeln!(text, "illume {}", env!("CARGO_PKG_VERSION"));
        let _ = writeln!(text, "scene {scene_identity}");
        let s = settings;
        let _ = writeln!(
            text,
            "reference width {} height {} spp {} seed {} rr_start_depth {} max_depth {}",
            width, height, s.spp, s.seed, s.rr_start_depth, s.max_depth
        );
        // Debug output of f32 is the shortest round-trip form: exact.
        for inst in &scene.instances {
            let _ = writeln!(
                text,
                "instance {:?} mask {} {:?}",
                inst.name, inst.mask, inst.world_from_object
            );
        }
        for light in &scene.lights {
            let _ = writeln!(
                text,
                "light {:?} {:?} {:?}",
                light.name, light.kind, light.world_from_light
            );
        }
        // The sky: its kind and integral (an environment map's pixels are in the
        // scene's identity, its file).
        match &scene.sky {
            Some(illume_scene::Sky::Uniform { radiance }) => {
                let _ = writeln!(text, "sky uniform {radiance:?}");
            }
            Some(sky) => {
                let _ = writeln!(text, "sky map {:?}", sky.integral());
            }
            None => {}
        }
        let _ = writeln!(
            text,
            "camera yfov_rad {:?} {:?}",
            scene.camera.yfov_rad, scene.camera.world_from_camera
        );
        for m in &scene.materials {
            let _ = writeln!(text, "material {m:?}");
        }
        let hash = fnv1a64(text.as_bytes());
        Self { text, hash }
    }

    /// The hash as 16 hex digits (the cache file's stem).
    pub fn hex(&self) -> String {
        format!("{:016x}", self.hash)
    }
}

/// FNV-1a, 64 bits: stable across runs, platforms and Rust versions (unlike
/// `std::hash`'s default hasher).
pub fn fnv1a64(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325, |h, &b| {
        (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3)
    })
}

/// A folder of converged references, `HASH.exr` (32-bit float, lossless) with
/// `HASH.key.txt` beside it; counts hits and renders.
#[derive(Clone, Debug)]
pub struct ReferenceCache {
    dir: PathBuf,
    /// Images read from the cache.
    pub hits: usize,
    /// Images rendered (and stored).
    pub renders: usize,
}

impl ReferenceCache {
    /// A cache in `dir` (created when the first image is stored).
    pub fn new(dir: impl Into<PathBuf>) -> Self {
        Self {
            dir: dir.into(),
            hits: 0,
            renders: 0,
        }
    }

    /// The cache folder.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// Where the image of `key` is (or would be) stored.
    pub fn path(&self, key: &CacheKey) -> PathBuf {
        self.dir.join(format!("{}.exr", key.hex()))
    }

    /// True when the image of `key` is stored and its key text matches (a hash
    /// collision or a foreign file is treated as a miss).
    pub fn contains(&self, key: &CacheKey) -> bool {
        let key_file = self.dir.join(format!("{}.key.txt", key.hex()));
        self.path(key).is_file()
            && std::fs::read_to_string(key_file).is_ok_and(|text| text == key.text)
    }

    /// Where the first half's image of `key` is (or would be) stored.
    pub fn half_path(&self, key: &CacheKey) -> PathBuf {
        self.dir.join(format!("{}.half.exr", key.hex()))
    }

    /// The stored image of `key` and its first half (None when the image was stored
    /// without one), or `render()`'s result, stored for next time. A stored image that
    /// is not `size` (width, height) is an error naming its file.
    pub fn get_or_render(
        &mut self,
        key: &CacheKey,
        size: (u32, u32),
        render: impl FnOnce() -> (RgbImage, Option<RgbImage>),
    ) -> Result<(RgbImage, Option<RgbImage>), BenchError> {
        let path = self.path(key);
        let half_path = self.half_path(key);
        if self.contains(key) {
            self.hits += 1;
            let image = read_sized(&path, size)?;
            let half = if half_path.is_file() {
                Some(read_sized(&half_path, size)?)
            } else {
                None
            };
            return Ok((image, half));
        }
        let (image, half) = render();
        std::fs::create_dir_all(&self.dir).map_err(|e| BenchError::io(&self.dir, e))?;
        // Images first, key last: a key file present means complete images. A half left
        // by an earlier, interrupted render is removed so it cannot pair with this image.
        image.write(&path, &Default::default())?;
        match &half {
            Some(h) => h.write(&half_path, &Default::default())?,
            None if half_path.exists() => {
                std::fs::remove_file(&half_path).map_err(|e| BenchError::io(&half_path, e))?
            }
            None => {}
        }
        let key_file = self.dir.join(format!("{}.key.txt", key.hex()));
        illume_core::atomic::write_file(&key_file, &key.text)
            .map_err(|e| BenchError::io(&key_file, e))?;
        self.renders += 1;
        Ok((image, half))
    }
}

/// The cached image at `path`, which must be `size` (width, height) pixels.
fn read_sized(path: &Path, size: (u32, u32)) -> Result<RgbImage, BenchError> {
    let image = RgbImage::read(path)?;
    if (image.width(), image.height()) != size {
        return Err(illume_core::image::ImageError::Read {
            path: path.to_owned(),
            message: format!(
                "the cached reference is {}×{}, the scenario's frames are {}×{}: a damaged or foreign cache file (remove it, or the cache folder, to render it again)",
                image.width(),
                image.height(),
                size.0,
                size.1
            ),
        }
        .into());
    }
    Ok(image)
}

/// A converged reference's two independent halves: the mean of its first ⌊spp/2⌋
/// samples and the mean of the rest, (spp·full − ⌊spp/2⌋·first) / (spp − ⌊spp/2⌋)
/// (2·full − first for an even spp; exact up to float rounding, since the full image is
/// the samples' mean).
#[derive(Clone, Debug)]
pub struct HalfImages {
    /// The first half's mean.
    pub first: RgbImage,
    /// The second half's mean.
    pub second: RgbImage,
}

impl HalfImages {
    /// The halves of `full`, the mean of `spp` samples whose first ⌊spp/2⌋ have the mean
    /// `first`; None when their sizes differ or `spp` < 2.
    pub fn new(full: &RgbImage, first: RgbImage, spp: u32) -> Option<Self> {
        if (first.width(), first.height()) != (full.width(), full.height()) || spp < 2 {
            return None;
        }
        let (n, h) = (spp as f32, (spp / 2) as f32);
        let second = RgbImage::from_vec(
            full.width(),
            full.height(),
            full.pixels()
                .iter()
                .zip(first.pixels())
                .map(|(f, a)| (n * *f - h * *a) / (n - h))
                .collect(),
        )?;
        Some(Self { first, second })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn second_half_is_the_mean_of_the_other_samples_for_odd_and_even_spp() {
        use illume_core::Vec3;
        let image = |v: f32| RgbImage::filled(2, 1, Vec3::new(v, 2.0 * v, 0.0));
        // Samples 1, 2, 3: the first half is sample 1, the second the mean of 2 and 3.
        let h = HalfImages::new(&image(2.0), image(1.0), 3).unwrap();
        assert_eq!(h.second.pixels(), image(2.5).pixels());
        // Samples 1, 2, 3, 5: halves 1.5 and 4.
        let h = HalfImages::new(&image(2.75), image(1.5), 4).unwrap();
        assert_eq!(h.second.pixels(), image(4.0).pixels());
        assert!(HalfImages::new(&image(1.0), image(1.0), 1).is_none());
        assert!(HalfImages::new(&image(1.0), RgbImage::filled(1, 1, Vec3::ZERO), 4).is_none());
    }

    #[test]
    fn fnv1a64_matches_published_vectors() {
        assert_eq!(fnv1a64(b""), 0xcbf2_9ce4_8422_2325);
        assert_eq!(fnv1a64(b"a"), 0xaf63_dc4c_8601_ec8c);
        assert_eq!(fnv1a64(b"foobar"), 0x8594_4171_f739_67e8);
    }

    #[test]
    fn key_follows_state_and_settings_not_identity_of_objects() {
        let scene = illume_scene::builtin::load("cornell-spot").unwrap();
        let settings = ReferenceSettings::default();
        let a = CacheKey::new("builtin:cornell-spot", &scene, &settings, (64, 48));
        assert_eq!(
            a,
            CacheKey::new("builtin:cornell-spot", &scene.clone(), &settings, (64, 48))
        );
        let more_spp = ReferenceSettings {
            spp: settings.spp + 1,
            ..settings.clone()
        };
        assert_ne!(
            a.hash,
            CacheKey::new("builtin:cornell-spot", &scene, &more_spp, (64, 48)).hash
        );
        let mut moved = scene.clone();
        moved.set_time(1.0); // the default animation moves the sphere and the light
        assert_ne!(
            a.hash,
            CacheKey::new("builtin:cornell-spot", &moved, &settings, (64, 48)).hash
        );
        assert_ne!(
            a.hash,
            CacheKey::new("other", &scene, &settings, (64, 48)).hash
        );
    }
}
