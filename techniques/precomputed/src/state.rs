//! Run time (Bahnsen et al. §3.1, Eq. 2, §4.2): everything is loaded at construction (the
//! paper pre-loads); each frame interpolates the k temporal coefficients and the mean
//! between the two keys around the clock time, reconstructs every pixel in O(k), clamps at
//! 0 and adds the sky image (its direct and indirect light) scaled by s(t).
//!
//! Per domain ([`crate::domain`]): `screen` pixels are the file's pixels; `cube` pixels
//! look up the face texel along the direction from the camera to their surface; `atlas`
//! pixels of static surfaces read their lightmap texel (bilinear, within their chart),
//! pixels of dynamic objects the probe grid, both times the pixel's albedo. `atlas`
//! reconstructs its whole (small) domain image when the clock time changes and keeps it
//! while it stays; `cube` (about 9× the image's pixels) reconstructs only the four texels
//! each pixel reads.

use crate::PrecomputedError;
use crate::atlas::Atlas;
use crate::file::{FileError, PcFile};
use crate::schedule::bracket;
use crate::settings::{Interpolation, PrecomputedSettings};
use illume_core::image::RgbImage;
use illume_core::{Counters, Rgb};
use illume_scene::SceneChange;
use illume_scene::sun::SunSettings;
use illume_transport::{Budget, ChangeResponse, GBuffer, Technique, World};
use rayon::prelude::*;
use std::path::{Path, PathBuf};

/// One PCA group (a channel, or all three joint) ready to reconstruct.
#[derive(Clone, Debug)]
struct Group {
    /// Mean per key (all keys; dark keys 0).
    mean: Vec<f32>,
    /// k × keys coefficients.
    temporal: Vec<f32>,
    /// k × rows projected images.
    images: Vec<f32>,
    /// Values per image.
    rows: usize,
}

/// Gives `scene` the `[sun]` of the file `settings.data` when it has none of its own (a
/// scene file such as Sponza's carries no sun: the precompute attached one, and the run
/// time needs the same sun for the direct light). Returns whether it attached one.
pub fn attach_file_sun(
    scene: &mut illume_scene::Scene,
    settings: &PrecomputedSettings,
) -> Result<bool, PrecomputedError> {
    if scene.sun.is_some() || settings.data.is_empty() {
        return Ok(false);
    }
    let path = PathBuf::from(&settings.data);
    let header = PcFile::read_header(&path)?;
    let sun: SunSettings = header
        .sun
        .clone()
        .try_into()
        .map_err(|e: toml::de::Error| {
            PrecomputedError::File(FileError::Mismatch {
                path: path.clone(),
                what: "[sun] table".into(),
                expected: "a valid [sun]".into(),
                found: e.to_string(),
            })
        })?;
    scene.attach_sun(sun)?;
    Ok(true)
}

/// `cube`: texels are reconstructed in runs of this many (those some pixel reads).
const RUN: usize = 64;

/// How the file's texels reach the pixels.
enum Lookup {
    /// One texel per pixel.
    Screen,
    /// Six faces of `face` pixels around `position`.
    Cube {
        face: u32,
        position: illume_core::Vec3,
    },
    /// The lightmap and probes; probe validity flags.
    Atlas { atlas: Box<Atlas>, valid: Vec<f32> },
}

/// The loaded `precomputed` technique.
pub struct Precomputed {
    settings: PrecomputedSettings,
    file: PathBuf,
    sun: SunSettings,
    times: Vec<f64>,
    k: usize,
    groups: Vec<Group>,
    joint: bool,
    sky: Vec<Rgb>,
    /// The key image's size (screen: the image's; cube: face × 6·face; atlas: lightmap
    /// and probe rows).
    width: u32,
    height: u32,
    lookup: Lookup,
    /// Reconstructed texels of `atlas` and the (hours, sky scale) they are for.
    cache: Option<((f64, f32), Vec<Rgb>)>,
    /// `cube`: the texels reconstructed this frame (runs the pixels read).
    runs: Vec<Rgb>,
    /// Linear interpolation: the key pair (N, N+1) around the last frame's time and their
    /// reconstructed images (sun only, clamped at 0).
    pair: Option<(usize, usize, Vec<Rgb>, Vec<Rgb>)>,
    load_s: f64,
    last_ms: f64,
    stale: u64,
    /// No file yet: [`Technique::precompute`] makes one in memory.
    pending: bool,
}

impl Precomputed {
    /// The technique for the engine: loads `settings.data` if set, else precomputes in
    /// memory at [`Technique::precompute`] (for tests and tiny scenes).
    pub fn new(
        world: &World,
        settings: PrecomputedSettings,
        width: u32,
        height: u32,
    ) -> Result<Self, PrecomputedError> {
        settings.validate()?;
        if !settings.data.is_empty() {
            let path = PathBuf::from(&settings.data);
            return Self::load(world, settings, &path, width, height);
        }
        crate::precompute::sun_of(&world.scene)?;
        Ok(Self {
            file: PathBuf::from("(precomputed in memory)"),
            sun: crate::precompute::sun_of(&world.scene)?,
            settings,
            times: Vec::new(),
            k: 0,
            groups: Vec::new(),
            joint: false,
            sky: Vec::new(),
            width,
            height,
            lookup: Lookup::Screen,
            cache: None,
            runs: Vec::new(),
            pair: None,
            load_s: 0.0,
            last_ms: 0.0,
            stale: 0,
            pending: true,
        })
    }

    /// Loads `path` for `world`: checks the file, the static scene, and per domain:
    /// `screen` the camera and the image size `width × height`; `cube` the camera's
    /// position (it may turn, and any image size samples the faces); `atlas` that the
    /// scene gives the file's lightmap layout (any camera and size).
    pub fn load(
        world: &World,
        settings: PrecomputedSettings,
        path: &Path,
        width: u32,
        height: u32,
    ) -> Result<Self, PrecomputedError> {
        let start = std::time::Instant::now();
        let file = PcFile::read(path)?;
        Self::from_file(world, settings, path, file, width, height, start)
    }

    /// As [`Precomputed::load`], from a file already in memory (`path` only for errors).
    pub fn from_file(
        world: &World,
        settings: PrecomputedSettings,
        path: &Path,
        file: PcFile,
        width: u32,
        height: u32,
        start: std::time::Instant,
    ) -> Result<Self, PrecomputedError> {
        settings.validate()?;
        let h = &file.header;
        let mismatch = |what: &str, expected: String, found: String| {
            PrecomputedError::File(FileError::Mismatch {
                path: path.to_path_buf(),
                what: what.into(),
                expected,
                found,
            })
        };
        if h.kind != "pca" {
            return Err(mismatch("file kind", "pca".into(), h.kind.clone()));
        }
        file.check_scene(path, &world.scene)?;
        let camera = &world.scene.camera;
        let mut cam: Vec<f32> = camera.world_from_camera.to_cols_array().to_vec();
        cam.push(camera.yfov_rad);
        let lookup = match h.domain.as_str() {
            "screen" => {
                if (h.width, h.height) != (width, height) {
                    return Err(mismatch(
                        "image size (a screen file holds one image of its size)",
                        format!("{width}×{height}"),
                        format!("{}×{}", h.width, h.height),
                    ));
                }
                if cam != h.camera {
                    return Err(mismatch(
                        "camera (a screen file needs its fixed camera)",
                        format!("{cam:?}"),
                        format!("{:?}", h.camera),
                    ));
                }
                Lookup::Screen
            }
            "cube" => {
                let position = camera.world_from_camera.translation;
                let stored = h.camera.get(9..12).unwrap_or(&[]);
                let tolerance = 1e-4 * (1.0 + position.abs().max_element());
                let same = stored.len() == 3
                    && (0..3).all(|i| (stored[i] - position[i]).abs() <= tolerance);
                if !same || h.height != 6 * h.width {
                    return Err(mismatch(
                        "camera position (a cube file lets the camera turn, not move)",
                        format!("{:?}", position.to_array()),
                        format!("{stored:?}"),
                    ));
                }
                Lookup::Cube {
                    face: h.width,
                    position: position.into(),
                }
            }
            "atlas" => {
                let info = h
                    .atlas
                    .as_ref()
                    .ok_or_else(|| mismatch("[atlas] table", "present".into(), "missing".into()))?;
                let atlas = Atlas::build(&world.scene, info.density, info.probe_spacing)?;
                let checksum = format!("{:016x}", atlas.checksum());
                if checksum != info.layout_checksum
                    || [atlas.width, atlas.height] != info.lightmap
                    || atlas.image_size() != (h.width, h.height)
                {
                    return Err(mismatch(
                        "atlas layout (the scene's lightmap coordinates; made by another version?)",
                        format!("{}×{} {checksum}", atlas.width, atlas.height),
                        format!(
                            "{}×{} {}",
                            info.lightmap[0], info.lightmap[1], info.layout_checksum
                        ),
                    ));
                }
                let static_world = world.with_scene(crate::precompute::static_scene(&world.scene));
                let valid = crate::domain::probe_flags(&static_world, &atlas);
                Lookup::Atlas {
                    atlas: Box::new(atlas),
                    valid,
                }
            }
            other => {
                return Err(mismatch(
                    "domain",
                    "screen, cube or atlas".into(),
                    other.into(),
                ));
            }
        };
        let (width, height) = (h.width, h.height);
        let sun: SunSettings = h.sun.clone().try_into().map_err(|e: toml::de::Error| {
            mismatch("[sun] table", "a valid [sun]".into(), e.to_string())
        })?;
        // The renderer's direct light follows the scene's sun: it must be the keys'.
        if let Some(path) = &world.scene.sun
            && path.settings != sun
        {
            return Err(mismatch(
                "[sun] (the scene's sun must be the one the keys were rendered with)",
                format!("{:?}", path.settings),
                format!("{sun:?}"),
            ));
        }
        let joint = h.colour == "joint";
        let names: &[&str] = if joint { &["rgb"] } else { &["r", "g", "b"] };
        let pixels = width as usize * height as usize;
        let rows = if joint { 3 * pixels } else { pixels };
        let keys = h.keys.len();
        let k = h.components as usize;
        let mut groups = Vec::new();
        for name in names {
            let get = |what: &str, len: usize| -> Result<Vec<f32>, PrecomputedError> {
                let section = file.section(&format!("{what}.{name}")).ok_or_else(|| {
                    mismatch(
                        &format!("section {what}.{name}"),
                        "present".into(),
                        "missing".into(),
                    )
                })?;
                if section.values.len() != len {
                    return Err(mismatch(
                        &format!("length of section {what}.{name}"),
                        len.to_string(),
                        section.values.len().to_string(),
                    ));
                }
                Ok(section.values.clone())
            };
            let bright = h.keys.iter().any(|k| !k.dark);
            groups.push(Group {
                mean: get("mean", keys)?,
                temporal: get("temporal", k * keys)?,
                images: get("images", if bright { k * rows } else { 0 })?,
                rows,
            });
        }
        let sky_values = file
            .section("sky")
            .map(|s| s.values.clone())
            .unwrap_or_default();
        if sky_values.len() != 3 * pixels {
            return Err(mismatch(
                "length of section sky",
                (3 * pixels).to_string(),
                sky_values.len().to_string(),
            ));
        }
        let sky = sky_values
            .chunks_exact(3)
            .map(|c| Rgb::new(c[0], c[1], c[2]))
            .collect();
        Ok(Self {
            settings,
            file: path.to_path_buf(),
            sun,
            times: h.keys.iter().map(|k| k.hours).collect(),
            k,
            groups,
            joint,
            sky,
            width,
            height,
            lookup,
            cache: None,
            runs: Vec::new(),
            pair: None,
            load_s: start.elapsed().as_secs_f64(),
            last_ms: 0.0,
            stale: 0,
            pending: false,
        })
    }

    /// Seconds the load took (reported as `load_s`).
    pub fn load_seconds(&self) -> f64 {
        self.load_s
    }

    /// Weights of the keys around clock time `hours`: (key index, weight) pairs.
    fn weights(&self, hours: f64) -> Vec<(usize, f32)> {
        let (n, m, alpha) = bracket(&self.times, hours);
        match self.settings.interpolation {
            Interpolation::Linear => vec![(n, 1.0 - alpha), (m, alpha)],
            Interpolation::Cubic => {
                // Catmull–Rom in the key index (uniform parameter), ends repeated.
                let last = self.times.len() - 1;
                let p0 = n.saturating_sub(1);
                let p3 = (m + 1).min(last);
                let t = alpha;
                let (t2, t3) = (t * t, t * t * t);
                vec![
                    (p0, 0.5 * (-t3 + 2.0 * t2 - t)),
                    (n, 0.5 * (3.0 * t3 - 5.0 * t2 + 2.0)),
                    (m, 0.5 * (-3.0 * t3 + 4.0 * t2 + t)),
                    (p3, 0.5 * (t3 - t2)),
                ]
            }
        }
    }

    /// Each PCA group's mean and k coefficients at clock time `hours`, interpolated
    /// between the keys around it.
    fn blend(&self, hours: f64) -> Vec<(f32, Vec<f32>)> {
        let weights = self.weights(hours);
        let keys = self.times.len();
        let blend = |values: &[f32], offset: usize| -> f32 {
            weights.iter().map(|&(i, w)| w * values[offset + i]).sum()
        };
        self.groups
            .iter()
            .map(|g| {
                (
                    blend(&g.mean, 0),
                    (0..self.k).map(|c| blend(&g.temporal, c * keys)).collect(),
                )
            })
            .collect()
    }

    /// Channel `c` of texels `first..first + out.len()` before the clamp: the blended
    /// mean, then one multiply-add pass per component (vectorised for per-channel
    /// groups).
    fn accumulate(&self, c: usize, blended: &(f32, Vec<f32>), first: usize, out: &mut [f32]) {
        let group = &self.groups[if self.joint { 0 } else { c }];
        let (mean, coefficients) = blended;
        out.fill(*mean);
        for (i, coefficient) in coefficients.iter().enumerate() {
            let image = &group.images[i * group.rows..(i + 1) * group.rows];
            if self.joint {
                for (j, o) in out.iter_mut().enumerate() {
                    *o += image[3 * (first + j) + c] * coefficient;
                }
            } else {
                let src = &image[first..first + out.len()];
                for (o, x) in out.iter_mut().zip(src) {
                    *o += x * coefficient;
                }
            }
        }
    }

    /// [`Precomputed::reconstruct`] of the runs of [`RUN`] texels marked in `needed`,
    /// written into `out` (other texels left as they are).
    fn reconstruct_runs(&self, hours: f64, sky_scale: f32, needed: &[bool], out: &mut [Rgb]) {
        let blended = self.blend(hours);
        out.par_chunks_mut(RUN)
            .zip(needed)
            .enumerate()
            .filter(|(_, (_, n))| **n)
            .for_each(|(run, (out, _))| {
                let first = run * RUN;
                let mut planes = [[0f32; RUN]; 3];
                for (c, plane) in planes.iter_mut().enumerate() {
                    let g = if self.joint { 0 } else { c };
                    self.accumulate(c, &blended[g], first, &mut plane[..out.len()]);
                }
                for (j, o) in out.iter_mut().enumerate() {
                    *o = Rgb::new(
                        planes[0][j].max(0.0),
                        planes[1][j].max(0.0),
                        planes[2][j].max(0.0),
                    ) + self.sky[first + j] * sky_scale;
                }
            });
    }

    /// The sun's indirect light at clock time `hours` plus the sky's whole light (direct
    /// and indirect) at scale `sky_scale`, one value per texel of the file's key image
    /// (screen: its pixels).
    pub fn reconstruct(&self, hours: f64, sky_scale: f32) -> Vec<Rgb> {
        let per_group = self.blend(hours);
        let pixels = self.width as usize * self.height as usize;
        // Channel planes, filled in cache-sized chunks: per chunk, mean then one
        // multiply-add pass per component (vectorised), then clamp at 0.
        const CHUNK: usize = 4096;
        let mut planes = vec![vec![0f32; pixels]; 3];
        for (c, plane) in planes.iter_mut().enumerate() {
            let g = if self.joint { 0 } else { c };
            plane
                .par_chunks_mut(CHUNK)
                .enumerate()
                .for_each(|(chunk, out)| self.accumulate(c, &per_group[g], chunk * CHUNK, out));
        }
        (0..pixels)
            .into_par_iter()
            .with_min_len(CHUNK)
            .map(|p| {
                Rgb::new(
                    planes[0][p].max(0.0),
                    planes[1][p].max(0.0),
                    planes[2][p].max(0.0),
                ) + self.sky[p] * sky_scale
            })
            .collect()
    }
}

impl Precomputed {
    /// Every texel's value at `hours` (what [`Precomputed::reconstruct`] gives, to
    /// rounding): with linear interpolation, Eq. 2 literally, `(1 − α)·L_N + α·L_{N+1} +
    /// s·L_sky` from the two key images reconstructed once per key interval (each
    /// clamped at 0), so a frame costs a blend instead of k multiply-adds per texel;
    /// with cubic interpolation a whole reconstruction.
    fn values(&mut self, hours: f64, sky_scale: f32) -> Vec<Rgb> {
        if self.settings.interpolation != Interpolation::Linear {
            return self.reconstruct(hours, sky_scale);
        }
        let (n, m, alpha) = bracket(&self.times, hours);
        if self.pair.as_ref().is_none_or(|p| (p.0, p.1) != (n, m)) {
            let a = self.reconstruct(self.times[n], 0.0);
            let b = self.reconstruct(self.times[m], 0.0);
            self.pair = Some((n, m, a, b));
        }
        let (_, _, a, b) = self.pair.as_ref().expect("just filled");
        a.par_iter()
            .zip(b)
            .zip(&self.sky)
            .with_min_len(4096)
            .map(|((a, b), sky)| *a * (1.0 - alpha) + *b * alpha + *sky * sky_scale)
            .collect()
    }

    /// `atlas`: each pixel's value from the reconstructed lightmap and probes.
    fn shade(&self, values: &[Rgb], gbuffer: &GBuffer) -> Vec<Rgb> {
        gbuffer
            .pixels
            .par_iter()
            .with_min_len(256)
            .map(|px| {
                let Some(px) = px else {
                    return Rgb::ZERO;
                };
                let hit = &px.hit;
                match &self.lookup {
                    Lookup::Screen | Lookup::Cube { .. } => Rgb::ZERO,
                    Lookup::Atlas { atlas, valid } => {
                        let back = !hit.front_face;
                        let albedo = hit.albedo;
                        match atlas.slot(hit.instance, hit.triangle, back) {
                            Some(slot) => atlas.lookup(values, slot, hit.barycentrics) * albedo,
                            // The unlit back of a one-sided static surface.
                            None if atlas.maps(hit.instance) => Rgb::ZERO,
                            None => {
                                let probes = &values[atlas.lightmap_texels()..];
                                atlas.probe_lookup(probes, valid, hit.position, hit.facing_normal())
                                    * albedo
                            }
                        }
                    }
                }
            })
            .collect()
    }
}

impl Technique for Precomputed {
    fn name(&self) -> &'static str {
        crate::NAME
    }

    /// The sun's motion is on the file's timeline; a moved static instance, a changed
    /// material, or a camera that leaves what the domain allows (`screen`: any move;
    /// `cube`: a new position) makes the file stale (a warning and `stale` counted,
    /// never a rebuild).
    fn scene_changed(&mut self, world: &World, changes: &[SceneChange]) -> ChangeResponse {
        for c in changes {
            let stale = match c {
                SceneChange::InstanceMoved { instance, .. } => world
                    .scene
                    .instances
                    .get(instance.index())
                    .is_some_and(|i| !i.dynamic),
                SceneChange::MaterialChanged { .. } => true,
                // A screen file holds its camera's view, a cube file its position's.
                SceneChange::CameraMoved { from, to } => match self.lookup {
                    Lookup::Screen => !self.pending,
                    Lookup::Cube { .. } => from.translation != to.translation,
                    Lookup::Atlas { .. } => false,
                },
                _ => false,
            };
            if stale {
                self.stale += 1;
                log::warn!(
                    "precomputed: {} no longer matches the scene (a static instance moved, a material changed, or the camera left what a {} file allows): indirect light is stale",
                    self.file.display(),
                    match self.lookup {
                        Lookup::Screen => "screen",
                        Lookup::Cube { .. } => "cube",
                        Lookup::Atlas { .. } => "atlas",
                    }
                );
            }
        }
        ChangeResponse::Updated
    }

    fn precompute(
        &mut self,
        world: &World,
        progress: &mut dyn illume_core::Progress,
    ) -> Result<(), illume_transport::TechniqueError> {
        if !self.pending {
            return Ok(());
        }
        let start = std::time::Instant::now();
        let size = (self.width, self.height);
        let file = crate::precompute::precompute(world, &self.settings, size, progress)?;
        let path = self.file.clone();
        *self = Self::from_file(
            world,
            self.settings.clone(),
            &path,
            file,
            size.0,
            size.1,
            start,
        )?;
        Ok(())
    }

    fn advance(&mut self, _world: &World, _budget: &Budget) {}

    fn indirect(&mut self, world: &World, gbuffer: &GBuffer) -> RgbImage {
        if self.pending || self.times.is_empty() {
            let n = gbuffer.width as usize * gbuffer.height as usize;
            return RgbImage::from_vec(gbuffer.width, gbuffer.height, vec![Rgb::ZERO; n])
                .expect("one value per pixel");
        }
        let start = std::time::Instant::now();
        let hours = self.sun.clock_hours(world.scene.time);
        let elevation = illume_scene::sun::solar_position(&self.sun, hours)
            .map(|p| p.elevation_deg)
            .unwrap_or(-90.0);
        let sky_scale = illume_scene::sun::sky_scale(elevation);
        let n = gbuffer.width as usize * gbuffer.height as usize;
        let out = match &self.lookup {
            Lookup::Screen => {
                // Pixels that see nothing get nothing. A G-buffer of another size than
                // the file's was refused at load; keep black rather than a wrong image
                // if it happens anyway.
                if (gbuffer.width, gbuffer.height) == (self.width, self.height) {
                    self.values(hours, sky_scale)
                        .into_par_iter()
                        .zip(&gbuffer.pixels)
                        .map(|(v, px)| if px.is_some() { v } else { Rgb::ZERO })
                        .collect()
                } else {
                    vec![Rgb::ZERO; n]
                }
            }
            Lookup::Cube { face, position } => {
                // Only the runs of texels the pixels read: a cube holds ~9× the image's
                // pixels, a camera sees a fraction of it.
                let (face, position) = (*face, *position);
                let taps: Vec<[(usize, f32); 4]> = gbuffer
                    .pixels
                    .par_iter()
                    .with_min_len(1024)
                    .map(|px| match px {
                        Some(px) => crate::domain::cube_texels(face, px.hit.position - position),
                        None => [(0, 0.0); 4],
                    })
                    .collect();
                let texels = self.width as usize * self.height as usize;
                let mut needed = vec![false; texels.div_ceil(RUN)];
                for tap in &taps {
                    for &(t, w) in tap {
                        if w > 0.0 {
                            needed[t / RUN] = true;
                        }
                    }
                }
                let mut buffer = std::mem::take(&mut self.runs);
                buffer.resize(texels, Rgb::ZERO);
                self.reconstruct_runs(hours, sky_scale, &needed, &mut buffer);
                let out = taps
                    .par_iter()
                    .with_min_len(1024)
                    .map(|tap| {
                        tap.iter()
                            .map(|&(t, w)| buffer[t] * w)
                            .fold(Rgb::ZERO, |a, b| a + b)
                    })
                    .collect();
                self.runs = buffer;
                out
            }
            Lookup::Atlas { .. } => {
                let key = (hours, sky_scale);
                if self.cache.as_ref().is_none_or(|(k, _)| *k != key) {
                    let values = self.values(hours, sky_scale);
                    self.cache = Some((key, values));
                }
                let values = &self.cache.as_ref().expect("just filled").1;
                self.shade(values, gbuffer)
            }
        };
        self.last_ms = start.elapsed().as_secs_f64() * 1e3;
        RgbImage::from_vec(gbuffer.width, gbuffer.height, out).expect("one value per pixel")
    }

    fn stats(&self) -> Counters {
        let mut c = Counters::new();
        c.set("keys", self.times.len() as f64);
        c.set("components", self.k as f64);
        c.set("load_s", self.load_s);
        c.set("indirect_ms", self.last_ms);
        c.set("stale", self.stale as f64);
        c
    }

    fn reset(&mut self) {}

    /// Always: the indirect light is reconstructed from the file as a function of the
    /// scene time and the G-buffer alone, and nothing accumulates between frames.
    fn settled(&self) -> bool {
        true
    }

    /// Shadow maps for the sun, as in the paper's demo.
    fn interactive(&self) -> bool {
        true
    }

    /// The precomputed sky image holds the sky's direct light too (Eq. 2's s(t)·L_sky).
    fn supplies_sky_light(&self) -> bool {
        true
    }
}
