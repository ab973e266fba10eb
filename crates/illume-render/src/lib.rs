//! illume's CPU renderer: one frame is G-buffer → direct light with shadows (plus
//! emission) → the technique's indirect light → an HDR image.
//!
//! Direct light is the renderer's job for every technique, as in all four papers: each
//! analytic light (point, spot, directional) is evaluated exactly, its visibility decided
//! by one shadow ray or by a shadow map ([`shadow_map`]), chosen per
//! light and frame by cost ([`RenderSettings::shadows`], [`shadow_choice`]); emissive triangles (area lights)
//! are sampled [`RenderSettings::area_light_samples`] times per pixel, chosen by power,
//! each sample with a shadow ray. The G-buffer samples each pixel once at its centre,
//! by rasterization or by rays ([`RenderSettings::primary_visibility`]).
//!
//! ```no_run
//! use illume_render::{Renderer, RenderSettings};
//! use illume_transport::World;
//! # fn technique() -> Box<dyn illume_transport::Technique> { unimplemented!() }
//! let world = World::new(illume_scene::builtin::load("cornell-spot").unwrap());
//! let mut technique = technique();
//! let frame = Renderer::new(RenderSettings::default()).render(&world, technique.as_mut(), 0);
//! println!("mean radiance {:?}", frame.full.mean());
//! ```

use illume_core::image::RgbImage;
use illume_core::sampling::{Pcg32, mix64};
use illume_core::{INV_PI, Progress, Rgb, Silent, Vec2};
use illume_transport::{GBuffer, GBufferPixel, Technique, TextureFilter, World};
use rayon::prelude::*;
use std::sync::{Arc, Mutex};
use std::time::Instant;

pub mod denoise;
pub mod shadow_choice;
pub mod shadow_map;
pub mod taa;

pub use shadow_choice::{LightShadowChoice, ShadowChooser, ShadowStats};
pub use shadow_map::{LightMapPlan, ShadowMapError, ShadowMapSettings, ShadowMaps};

/// Renderer settings.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct RenderSettings {
    /// Image width \[pixels\]. Default 640.
    pub width: u32,
    /// Image height \[pixels\]. Default 480.
    pub height: u32,
    /// Shadow-ray samples per pixel for area lights (emissive triangles). Higher: less
    /// noise in area-light direct light, at a cost linear in the count. Analytic lights
    /// always take exactly one shadow ray. Default 16.
    pub area_light_samples: u32,
    /// Seed of the renderer's random numbers (area-light samples). Default 0.
    pub seed: u64,
    /// How the G-buffer finds each pixel's primary hit. `raster` (default): the CPU
    /// visibility-buffer rasterizer, then one exact triangle test per pixel — the same
    /// hits as `rays` wherever both pick the same triangle (all but < 0.1 % of pixels, at
    /// triangle edges), ≈ 1.4× cheaper per frame at 800×600 (`BENCHMARKS.md`: the rasterizer
    /// itself is 40× cheaper than the rays; building each pixel's surface costs the same). `rays`: one BVH ray
    /// per pixel centre — the reference; pick it to rule the rasterizer out when
    /// debugging, or for scenes whose geometry comes within 0.1 mm of the camera plane
    /// (the rasterizer's near plane). Both sample pixel centres only.
    pub primary_visibility: PrimaryVisibility,
    /// How the rasterized G-buffer (`primary_visibility = "raster"`) reads base-colour
    /// textures and normal maps. `trilinear` (default): mip-mapped by each pixel's
    /// footprint — where a pixel covers many texels it sees their mean (no moiré, no
    /// shimmering under a moving camera, and a G-buffer of 0.86× the CPU time on Sponza,
    /// whose bilinear lookups of minified textures miss the cache; `BENCHMARKS.md`),
    /// elsewhere the bilinear lookup itself. `bilinear`: one lookup at the pixel centre's texture
    /// coordinates, the same values as `primary_visibility = "rays"` (which always reads
    /// textures this way) — pick it to compare G-buffers texel for texel. The reference
    /// technique shades from the same G-buffer, so both see the same filtered texture;
    /// a path tracer that supersamples each pixel averages the point lookups over the
    /// pixel, which mip-mapping approximates with a footprint of about one pixel.
    pub texture_filter: TextureFilter,
    /// How analytic lights (point, spot, directional) find their shadows; area lights
    /// always use rays. `rays`: one BVH shadow ray per pixel and light — exact, the
    /// reference path tracer's tests compare against it. `maps`: a depth map per light
    /// (six for a point light or a spot wider than 60°) rasterized from all the scene's
    /// triangles whenever the light or any object moved (kept otherwise), then a
    /// filtered lookup per pixel — equal to rays except in a band about one texel
    /// footprint wide along shadow edges, creases and contacts (see `shadow_maps`).
    ///
    /// `auto` (default): `rays` for techniques that are not interactive (the reference);
    /// for interactive ones ([`Technique::interactive`]: `photon_stream`, `selective`,
    /// `precomputed`) each light chooses, every frame, whichever is expected to cost less
    /// ([`shadow_choice`] has the model; [`Frame::shadows`] counts the outcome). Units:
    /// CPU time, measured on the scene at hand. Maps pay for re-rendering whenever the
    /// light or any object moved (per triangle and face, more where triangles cover many
    /// texels), then one lookup per lit pixel; rays pay one ray per lit pixel (probed
    /// every frame on a few hundred rays). Trade-off: a rendering that serves many frames
    /// is cheap per frame, so a still light keeps its map (a kept map costs lookups only,
    /// a fraction of the time of rays); a light that moves every frame over a large scene
    /// uses rays (the Cornell dragon with a moving point light); a light that stops
    /// moving returns to maps once one rendering pays off over as many frames as it has
    /// been still; a new light is expected to stay still for 300 frames. The measured
    /// costs are in `BENCHMARKS.md` ("Direct light — shadow maps against shadow rays").
    /// Force `maps` or `rays` to rule the choice out: it depends on measured times, so
    /// two runs may shade a light's shadow edges differently, within the maps' tolerance
    /// of rays.
    pub shadows: ShadowMode,
    /// Resolution, bias and filtering of the shadow maps (`[render.shadow_maps]`), used
    /// wherever maps are (`shadows = "maps"`, or chosen by `auto`). Out-of-range values are rejected by
    /// [`RenderSettings::validate`]; a renderer given them anyway falls back to rays.
    pub shadow_maps: ShadowMapSettings,
    /// Temporal anti-aliasing of interactive techniques' frames ([`taa`]): while the
    /// camera moves, each frame samples its pixels at the next sub-pixel offset of the R₂
    /// sequence, and the image shown (`Frame::full`; `direct` and `indirect` stay the
    /// frame's own) blends it into the reprojected, neighbourhood-clamped history of the
    /// frames before. Edges converge towards the box filter the reference shows; the cost
    /// is the blend's pass (measured in BENCHMARKS.md, "temporal anti-aliasing") and a
    /// little softening of texture detail under motion. A still camera keeps its last
    /// offset (a new one would rebuild the whole G-buffer every frame). Not applied to
    /// split frames, to explicit [`Renderer::jitter`]s, nor to the reference. Default
    /// false: frames at pixel centres, bit for bit as before.
    pub temporal_aa: bool,
    /// The new frame's weight in temporal anti-aliasing's blend, in (0, 1]: smaller is
    /// smoother (≈ 2/α − 1 frames averaged) but softer under motion and slower where the
    /// clamp does not act. Default 0.1 (Karis 2014).
    pub temporal_aa_blend: f32,
}

/// How analytic lights' shadows are found (see [`RenderSettings::shadows`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ShadowMode {
    /// Per light and frame by cost for interactive techniques ([`ShadowChooser`]),
    /// `Rays` otherwise.
    #[default]
    Auto,
    /// One shadow ray per pixel and light (exact).
    Rays,
    /// Shadow maps rebuilt each frame ([`ShadowMaps`]).
    Maps,
}

/// Visibility of analytic lights for [`direct_light_with`] and [`direct_at_with`].
#[derive(Clone, Copy, Debug)]
pub enum Shadows<'a> {
    /// Shadow rays through the world's tracer.
    Rays,
    /// Lookups in maps built for the same world ([`ShadowMaps::rebuild`]); lights the
    /// last [`ShadowMaps::render_planned`] left without maps cast rays.
    Maps(&'a ShadowMaps),
    /// No shadows from analytic lights (area lights still cast rays): wrong wherever
    /// something occludes, for measuring what shadows cost and for debugging.
    Off,
}

/// How primary hits are found (see [`RenderSettings::primary_visibility`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PrimaryVisibility {
    /// Rasterize a visibility buffer ([`GBuffer::rasterize`]).
    #[default]
    Raster,
    /// Cast one BVH ray per pixel ([`GBuffer::render`]).
    Rays,
}

impl Default for RenderSettings {
    fn default() -> Self {
        Self {
            width: 640,
            height: 480,
            area_light_samples: 16,
            seed: 0,
            primary_visibility: PrimaryVisibility::Raster,
            texture_filter: TextureFilter::Trilinear,
            shadows: ShadowMode::Auto,
            shadow_maps: ShadowMapSettings::default(),
            temporal_aa: false,
            temporal_aa_blend: 0.1,
        }
    }
}

/// Why [`RenderSettings`] were refused.
#[derive(Debug, thiserror::Error)]
pub enum RenderSettingsError {
    /// A shadow-map setting is out of range.
    #[error(transparent)]
    ShadowMaps(#[from] ShadowMapError),
    /// `area_light_samples` is 0 (area lights would light nothing).
    #[error("area_light_samples = 0: must be at least 1")]
    NoAreaLightSamples,
    /// `temporal_aa_blend` is outside (0, 1].
    #[error("temporal_aa_blend = {0}: must be in (0, 1] (the new frame's weight)")]
    TemporalAaBlend(f32),
}

impl RenderSettings {
    /// Checks the settings whose ranges matter (area-light samples, the shadow maps';
    /// the image size is [`check_image_size`]'s).
    pub fn validate(&self) -> Result<(), RenderSettingsError> {
        if self.area_light_samples == 0 {
            return Err(RenderSettingsError::NoAreaLightSamples);
        }
        if !(self.temporal_aa_blend > 0.0 && self.temporal_aa_blend <= 1.0) {
            return Err(RenderSettingsError::TemporalAaBlend(self.temporal_aa_blend));
        }
        Ok(self.shadow_maps.validate()?)
    }
}

/// Largest image side \[pixels\]: the rasterizer's fixed-point edge functions are exact
/// up to 2¹⁴ pixels a side (`illume_transport::raster::GUARD_BAND`).
pub const MAX_IMAGE_SIDE: u32 = 1 << 14;

/// Memory a frame needs per pixel \[bytes\]: the G-buffer (≈ 100) and the direct,
/// indirect and full images with the technique's working images, rounded up.
pub const FRAME_BYTES_PER_PIXEL: u64 = 256;

/// Checks a `width × height` image before anything is allocated: each side in
/// 1..=[`MAX_IMAGE_SIDE`], and a frame's memory ([`FRAME_BYTES_PER_PIXEL`] per pixel)
/// within [`available_memory_bytes`] (unchecked where that is unknown). The message
/// names the limit.
pub fn check_image_size(width: u32, height: u32) -> Result<(), String> {
    if width == 0 || height == 0 {
        return Err(format!(
            "image size must be at least 1×1, got {width}×{height}"
        ));
    }
    if width > MAX_IMAGE_SIDE || height > MAX_IMAGE_SIDE {
        return Err(format!(
            "image size {width}×{height}: each side must be at most {MAX_IMAGE_SIDE} pixels"
        ));
    }
    let need = u64::from(width) * u64::from(height) * FRAME_BYTES_PER_PIXEL;
    if let Some(available) = available_memory_bytes()
        && need > available
    {
        return Err(format!(
            "image size {width}×{height} needs about {} MiB per frame, more than the {} MiB available",
            need >> 20,
            available >> 20
        ));
    }
    Ok(())
}

/// The memory this process may still allocate \[bytes\], where the system reports it:
/// `MemAvailable` of `/proc/meminfo`, or less when the process runs under an
/// address-space limit (`ulimit -v`, `prlimit --as`: the limit minus the address space
/// already in use, `VmSize` of `/proc/self/status`) — an allocation beyond that limit
/// would abort the process rather than fail cleanly.
pub fn available_memory_bytes() -> Option<u64> {
    let field = |file: &str, key: &str, column: usize| -> Option<String> {
        let text = std::fs::read_to_string(file).ok()?;
        let line = text.lines().find(|l| l.starts_with(key))?;
        line[key.len()..]
            .split_whitespace()
            .nth(column)
            .map(str::to_owned)
    };
    let system = field("/proc/meminfo", "MemAvailable:", 0)
        .and_then(|kib| kib.parse::<u64>().ok())
        .map(|kib| kib * 1024);
    // "Max address space   <soft> <hard> bytes"; the soft limit is the one enforced.
    let process = field("/proc/self/limits", "Max address space", 0)
        .and_then(|limit| limit.parse::<u64>().ok())
        .map(|limit| {
            let used = field("/proc/self/status", "VmSize:", 0)
                .and_then(|kib| kib.parse::<u64>().ok())
                .map_or(0, |kib| kib * 1024);
            limit.saturating_sub(used)
        });
    match (system, process) {
        (Some(a), Some(b)) => Some(a.min(b)),
        (a, b) => a.or(b),
    }
}

/// Wall-clock time of a frame's stages \[ms\].
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FrameTimings {
    /// Primary visibility (the G-buffer).
    pub gbuffer_ms: f64,
    /// Direct light and emission, shadow maps included.
    pub direct_ms: f64,
    /// Of `direct_ms`, rendering the shadow maps (0 with shadow rays).
    pub shadow_maps_ms: f64,
    /// The technique's indirect light.
    pub indirect_ms: f64,
    /// The whole frame.
    pub total_ms: f64,
}

/// A rendered frame: `full = direct + indirect`, all linear radiance.
pub struct Frame {
    /// Emission seen directly plus direct light (one bounce): the renderer's, and the
    /// technique's [`Technique::direct_share`] when it hands one over.
    pub direct: RgbImage,
    /// The technique's indirect light (two or more bounces): its image less its direct
    /// share.
    pub indirect: RgbImage,
    /// The sum.
    pub full: RgbImage,
    /// The primary hits the frame was shaded from. Shared with the renderer: once the
    /// caller drops the frame, the next frame rasterizes into the same allocation.
    pub gbuffer: Arc<GBuffer>,
    /// Stage timings.
    pub timings: FrameTimings,
    /// How many analytic lights took their shadows from maps and how many from rays.
    pub shadows: ShadowStats,
}

/// The CPU renderer.
#[derive(Debug, Default)]
pub struct Renderer {
    /// Its settings.
    pub settings: RenderSettings,
    /// The last frame's G-buffer, reused when no frame holds it any more (a G-buffer is
    /// ~100 bytes per pixel: reallocating 48 MB at 800×600 costs page faults every frame).
    previous: Mutex<Option<Arc<GBuffer>>>,
    /// The shadow maps, re-rendered each frame into the same allocations, and the
    /// per-light choice of `shadows = "auto"`.
    shadow_maps: Mutex<(ShadowMaps, ShadowChooser)>,
    /// Temporal anti-aliasing's history ([`RenderSettings::temporal_aa`]).
    taa: Mutex<taa::TemporalAa>,
    /// Frames split as the reference splits light: the technique's
    /// [`Technique::direct_share`] is asked for and moved into the direct image. False
    /// (the default): a technique's image is all indirect, and it may skip its share's
    /// work ([`Technique::want_direct_share`]); `full` is the same either way.
    pub split: bool,
    /// Where in each pixel the next frames sample, in `[0, 1)²` (0.5, 0.5 = the
    /// centre; `None`: the centre). Both primary visibilities follow it (the rasterizer
    /// by a shifted projection, [`GBuffer::rasterize_into_at`]); the mean of frames over
    /// well-spread offsets is the box filter a supersampled image gives (the window's
    /// still refinement).
    pub jitter: Option<Vec2>,
}

impl Renderer {
    /// A renderer with `settings`.
    pub fn new(settings: RenderSettings) -> Self {
        Self {
            settings,
            previous: Mutex::new(None),
            shadow_maps: Mutex::new((ShadowMaps::default(), ShadowChooser::default())),
            taa: Mutex::new(taa::TemporalAa::default()),
            split: false,
            jitter: None,
        }
    }

    /// The last frame's per-light estimates and choices of `shadows = "auto"` (empty
    /// unless the last frame chose by cost).
    pub fn shadow_choices(&self) -> Vec<LightShadowChoice> {
        let state = self.shadow_maps.lock().unwrap_or_else(|e| e.into_inner());
        state.1.choices().to_vec()
    }

    /// The previous G-buffer's allocation if the caller has dropped its frame.
    fn recycled_gbuffer(&self) -> Option<GBuffer> {
        let previous = self
            .previous
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .take()?;
        Arc::try_unwrap(previous).ok()
    }

    /// Renders one frame of `world` with `technique`'s indirect light. `frame_index`
    /// decorrelates the random numbers of successive frames.
    pub fn render(&self, world: &World, technique: &mut dyn Technique, frame_index: u64) -> Frame {
        self.render_with_progress(world, technique, frame_index, &mut Silent)
    }

    /// [`Renderer::render`], the technique's long work in the frame reported to
    /// `progress` ([`Technique::indirect_with_progress`]): a still's one frame.
    pub fn render_with_progress(
        &self,
        world: &World,
        technique: &mut dyn Technique,
        frame_index: u64,
        progress: &mut dyn Progress,
    ) -> Frame {
        let t0 = Instant::now();
        let s = &self.settings;
        let mut taa = self.taa.lock().unwrap_or_else(|e| e.into_inner());
        let temporal_aa =
            s.temporal_aa && self.jitter.is_none() && !self.split && technique.interactive();
        if !temporal_aa {
            taa.reset();
        }
        let offset = match self.jitter {
            Some(offset) => offset,
            None if temporal_aa => taa.next_offset(&world.scene.camera),
            None => Vec2::splat(0.5),
        };
        let gbuffer = Arc::new(match s.primary_visibility {
            PrimaryVisibility::Raster => {
                let mut g = self.recycled_gbuffer().unwrap_or_else(GBuffer::empty);
                g.rasterize_into_at(world, s.width, s.height, s.texture_filter, offset);
                g
            }
            PrimaryVisibility::Rays => GBuffer::render(world, s.width, s.height, offset),
        });
        *self.previous.lock().unwrap_or_else(|e| e.into_inner()) = Some(Arc::clone(&gbuffer));
        let t1 = Instant::now();
        let mut state = self.shadow_maps.lock().unwrap_or_else(|e| e.into_inner());
        let (maps, chooser) = &mut *state;
        let analytic = world.lights.analytic_range().len() as u32;
        let all_rays = ShadowStats {
            lights_with_rays: analytic,
            ..ShadowStats::default()
        };
        // Settings that `RenderSettings::validate` rejects fall back to exact rays.
        let stats = match s.shadows {
            ShadowMode::Auto if technique.interactive() => chooser
                .choose(world, &gbuffer, maps, &s.shadow_maps)
                .unwrap_or(all_rays),
            ShadowMode::Maps => match maps.rebuild(world, &s.shadow_maps) {
                Ok(()) => {
                    let with_maps = world
                        .lights
                        .analytic_range()
                        .filter(|&i| maps.uses_maps(i))
                        .count() as u32;
                    ShadowStats {
                        lights_with_maps: with_maps,
                        lights_with_rays: analytic - with_maps,
                        maps_rendered: maps.rendered_last_build() as u32,
                    }
                }
                Err(_) => all_rays,
            },
            ShadowMode::Auto | ShadowMode::Rays => all_rays,
        };
        let shadows = if stats.lights_with_maps > 0 {
            Shadows::Maps(&*maps)
        } else {
            Shadows::Rays
        };
        let t_maps = Instant::now();
        let direct = direct_light_sky(
            world,
            &gbuffer,
            shadows,
            s.area_light_samples,
            mix64(s.seed ^ frame_index.wrapping_mul(0x9e37)),
            !technique.supplies_sky_light(),
        );
        drop(state);
        let t2 = Instant::now();
        technique.want_direct_share(self.split);
        let mut indirect = technique.indirect_with_progress(world, &gbuffer, progress);
        let mut direct = direct;
        let share = if self.split {
            technique.direct_share()
        } else {
            None
        };
        let t3 = Instant::now();
        let full = match share {
            Some(share) => add_moving_share(&mut direct, &mut indirect, &share),
            None => add_par(&direct, &indirect),
        };
        let full = if temporal_aa {
            taa.resolve(&gbuffer, &full, s, &world.scene)
        } else {
            full
        };
        drop(taa);
        let ms = |a: Instant, b: Instant| (b - a).as_secs_f64() * 1e3;
        let timings = FrameTimings {
            gbuffer_ms: ms(t0, t1),
            direct_ms: ms(t1, t2),
            shadow_maps_ms: ms(t1, t_maps),
            indirect_ms: ms(t2, t3),
            total_ms: ms(t0, Instant::now()),
        };
        Frame {
            direct,
            indirect,
            full,
            gbuffer,
            timings,
            shadows: stats,
        }
    }
}

/// Emission plus direct light with shadows at every G-buffer pixel, shadow rays for
/// every light.
pub fn direct_light(
    world: &World,
    gbuffer: &GBuffer,
    area_light_samples: u32,
    seed: u64,
) -> RgbImage {
    direct_light_with(world, gbuffer, Shadows::Rays, area_light_samples, seed)
}

/// [`direct_light`] with analytic lights' visibility from `shadows`.
pub fn direct_light_with(
    world: &World,
    gbuffer: &GBuffer,
    shadows: Shadows<'_>,
    area_light_samples: u32,
    seed: u64,
) -> RgbImage {
    direct_light_sky(world, gbuffer, shadows, area_light_samples, seed, true)
}

/// `a + b` pixel by pixel, in parallel ([`RgbImage::add`] runs on one thread: at
/// 800×600 it and its first touch of the new image were a serial millisecond or two of
/// every frame, while the other core waited). Panics if the sizes differ.
fn add_par(a: &RgbImage, b: &RgbImage) -> RgbImage {
    assert_eq!(
        (a.width(), a.height()),
        (b.width(), b.height()),
        "image sizes differ"
    );
    let pixels = a
        .pixels()
        .par_iter()
        .zip(b.pixels().par_iter())
        .with_min_len(4096)
        .map(|(x, y)| *x + *y)
        .collect();
    RgbImage::from_vec(a.width(), a.height(), pixels).expect("one value per pixel")
}

/// `direct + indirect` (as [`add_par`]), and in the same pass `share` (a technique's
/// [`Technique::direct_share`]) moved from `indirect` to `direct`. A share of another
/// size than the images is left out (the split stays as the technique gave it).
fn add_moving_share(direct: &mut RgbImage, indirect: &mut RgbImage, share: &RgbImage) -> RgbImage {
    let size = (share.width(), share.height());
    if size != (direct.width(), direct.height()) || size != (indirect.width(), indirect.height()) {
        return add_par(direct, indirect);
    }
    let (width, height) = size;
    let pixels = direct
        .pixels_mut()
        .par_iter_mut()
        .zip(indirect.pixels_mut().par_iter_mut())
        .zip(share.pixels().par_iter())
        .with_min_len(4096)
        .map(|((d, i), s)| {
            let full = *d + *i;
            *d += *s;
            *i -= *s;
            full
        })
        .collect();
    RgbImage::from_vec(width, height, pixels).expect("one value per pixel")
}

/// [`direct_light_with`], with the sky's light at surface points only when `sky` (a
/// technique that supplies it, [`Technique::supplies_sky_light`], turns it off).
pub fn direct_light_sky(
    world: &World,
    gbuffer: &GBuffer,
    shadows: Shadows<'_>,
    area_light_samples: u32,
    seed: u64,
    sky: bool,
) -> RgbImage {
    // Jobs of a few rows: per-pixel work is ~20 ns, so finer splitting costs more in
    // scheduling than it gains in balance.
    // Pixels that see nothing see the sky (black without one).
    let camera = world.lights.sky().map(|_| {
        illume_transport::CameraRays::new(&world.scene.camera, gbuffer.width, gbuffer.height)
    });
    let pixels: Vec<Rgb> = gbuffer
        .pixels
        .par_iter()
        .enumerate()
        .with_min_len(1024)
        .map(|(i, px)| {
            illume_core::prefetch(&gbuffer.pixels, i + illume_core::PREFETCH_AHEAD);
            match px {
                Some(px) => {
                    let mut rng = Pcg32::new(seed, i as u64);
                    px.hit.emission
                        + direct_at_sky(world, px, shadows, area_light_samples, &mut rng, sky)
                }
                None => match &camera {
                    Some(c) => {
                        let (x, y) = (i as u32 % gbuffer.width, i as u32 / gbuffer.width);
                        world.lights.sky_radiance(c.ray(x, y, gbuffer.offset).dir)
                    }
                    None => Rgb::ZERO,
                },
            }
        })
        .collect();
    RgbImage::from_vec(gbuffer.width, gbuffer.height, pixels).expect("one value per pixel")
}

/// Reflected direct radiance towards the camera at one G-buffer pixel, shadow rays for
/// every light.
pub fn direct_at(
    world: &World,
    px: &GBufferPixel,
    area_light_samples: u32,
    rng: &mut Pcg32,
) -> Rgb {
    direct_at_with(world, px, Shadows::Rays, area_light_samples, rng)
}

/// [`direct_at`] with analytic lights' visibility from `shadows` (a fraction in [0, 1]
/// with maps). Surfaces whose shading normal faces away from a light, and points outside
/// a spot cone, get nothing from it before any visibility test; light from below the
/// facet that the shading normal faces takes [`World::shadow_ray`]'s terminator ray,
/// whatever `shadows` says.
pub fn direct_at_with(
    world: &World,
    px: &GBufferPixel,
    shadows: Shadows<'_>,
    area_light_samples: u32,
    rng: &mut Pcg32,
) -> Rgb {
    direct_at_sky(world, px, shadows, area_light_samples, rng, true)
}

/// [`direct_at_with`], the sky's term only when `sky`. Always inlined: called per pixel,
/// its colour came back through memory, and reading it back stalled on store-to-load
/// forwarding (13 % of the direct pass's samples; BENCHMARKS.md).
#[inline(always)]
fn direct_at_sky(
    world: &World,
    px: &GBufferPixel,
    shadows: Shadows<'_>,
    area_light_samples: u32,
    rng: &mut Pcg32,
    sky: bool,
) -> Rgb {
    let hit = &px.hit;
    if hit.is_black() {
        return Rgb::ZERO;
    }
    // Lambertian: one BRDF value for every light (exactly albedo/π); glossy: per light.
    let lambert = hit.is_lambertian();
    let f = hit.albedo * INV_PI;
    let n = hit.facing_normal();
    let ng = hit.facing_geometric_normal();
    let lights = &world.lights;
    let mut sum = Rgb::ZERO;
    // `analytic`: the analytic light the sample came from (a map may decide), or None.
    let shade = |s: illume_transport::LightSample, analytic: Option<usize>| -> Rgb {
        let cos = n.dot(s.wi);
        if cos <= 0.0 {
            return Rgb::ZERO;
        }
        let map_visibility = match (shadows, analytic) {
            // Light from below the facet (a shadow terminator): only the shared shadow
            // ray from the smooth surface decides (`World::shadow_ray`); a map cannot
            // tell the facet's own shadow from the object's.
            _ if ng.dot(s.wi) <= 0.0 => None,
            (Shadows::Maps(maps), Some(i)) => maps.visibility(i, hit, &s),
            (Shadows::Off, Some(_)) => Some(1.0),
            _ => None,
        };
        let visibility = match map_visibility {
            Some(v) => v,
            None if world.unoccluded(hit, &s) => 1.0,
            None => return Rgb::ZERO,
        };
        let f = if lambert {
            f
        } else {
            hit.eval_brdf(px.to_camera, s.wi)
        };
        f * s.weight * (cos * visibility)
    };
    for i in lights.analytic_range() {
        if let Some((s, _)) = lights.incident_from(i, hit.position, Vec2::ZERO) {
            sum += shade(s, Some(i));
        }
    }
    if lights.has_area_lights() && area_light_samples > 0 {
        let mut area = Rgb::ZERO;
        for _ in 0..area_light_samples {
            if let Some(s) = lights.sample_area_incident(hit.position, rng) {
                area += shade(s, None);
            }
        }
        sum += area / area_light_samples as f32;
    }
    // The sky: cosine-weighted samples about the normal with shadow rays to infinity
    // (as many as area-light samples, at least one).
    if sky && lights.sky().is_some() {
        let samples = area_light_samples.max(1);
        let mut sky = Rgb::ZERO;
        for _ in 0..samples {
            if let Some(s) = lights.sample_sky(n, rng) {
                sky += shade(s, None);
            }
        }
        sum += sky / samples as f32;
    }
    sum
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A constant indirect image of `value` of which `direct` (an image of `size`) is
    /// direct light.
    struct Shared {
        value: Rgb,
        direct: Option<Rgb>,
        size: (u32, u32),
    }

    /// A technique with no indirect light.
    fn black() -> Shared {
        Shared {
            value: Rgb::ZERO,
            direct: None,
            size: (0, 0),
        }
    }

    impl Technique for Shared {
        fn name(&self) -> &'static str {
            "shared"
        }
        fn scene_changed(
            &mut self,
            _: &World,
            _: &[illume_scene::SceneChange],
        ) -> illume_transport::ChangeResponse {
            illume_transport::ChangeResponse::Updated
        }
        fn advance(&mut self, _: &World, _: &illume_transport::Budget) {}
        fn indirect(&mut self, _: &World, g: &GBuffer) -> RgbImage {
            RgbImage::filled(g.width, g.height, self.value)
        }
        fn stats(&self) -> illume_core::Counters {
            illume_core::Counters::default()
        }
        fn reset(&mut self) {}
        fn direct_share(&mut self) -> Option<RgbImage> {
            self.direct
                .map(|d| RgbImage::filled(self.size.0, self.size.1, d))
        }
    }

    #[test]
    fn a_direct_share_moves_from_indirect_to_direct_and_full_stays() {
        let world = World::new(illume_scene::builtin::load("cornell-spot").expect("builtin"));
        let settings = RenderSettings {
            width: 16,
            height: 12,
            ..Default::default()
        };
        let mut renderer = Renderer::new(settings);
        renderer.split = true;
        let mut none = Shared {
            value: Rgb::splat(0.25),
            direct: None,
            size: (16, 12),
        };
        let base = renderer.render(&world, &mut none, 0);
        assert!(
            base.indirect
                .pixels()
                .iter()
                .all(|p| *p == Rgb::splat(0.25))
        );
        let share = Rgb::new(0.125, 0.0625, 0.25);
        let mut shared = Shared {
            value: Rgb::splat(0.25),
            direct: Some(share),
            size: (16, 12),
        };
        let split = renderer.render(&world, &mut shared, 0);
        assert_eq!(split.full, base.full, "full unchanged");
        for i in 0..base.full.pixels().len() {
            assert_eq!(split.direct.pixels()[i], base.direct.pixels()[i] + share);
            assert_eq!(split.indirect.pixels()[i], Rgb::splat(0.25) - share);
        }
        // A share of another size is left out, not a panic.
        let mut odd = Shared {
            value: Rgb::splat(0.25),
            direct: Some(share),
            size: (3, 2),
        };
        let kept = renderer.render(&world, &mut odd, 0);
        assert_eq!(kept.direct, base.direct);
        assert_eq!(kept.indirect, base.indirect);
        // Frames not split (the default: animations, the window) leave the share where
        // the technique put it.
        renderer.split = false;
        let whole = renderer.render(&world, &mut shared, 0);
        assert_eq!(whole.full, base.full);
        assert_eq!(whole.direct, base.direct);
        assert_eq!(whole.indirect, base.indirect);
    }

    #[test]
    fn gbuffer_allocation_is_reused_once_the_frame_is_dropped() {
        let mut world = World::new(illume_scene::builtin::load("cornell-spot").expect("builtin"));
        let settings = RenderSettings {
            width: 64,
            height: 48,
            ..Default::default()
        };
        let renderer = Renderer::new(settings.clone());
        let first = renderer.render(&world, &mut black(), 0);
        let address = first.gbuffer.pixels.as_ptr();
        // While the caller holds a frame, the next one gets its own G-buffer.
        let held = renderer.render(&world, &mut black(), 1);
        let held_address = held.gbuffer.pixels.as_ptr();
        assert_ne!(held_address, address);
        drop(first);
        drop(held);
        world.set_time(1.0); // the sphere and the light move
        let reused = renderer.render(&world, &mut black(), 2);
        assert_eq!(
            reused.gbuffer.pixels.as_ptr(),
            held_address,
            "the last frame's allocation is reused"
        );
        let fresh = Renderer::new(settings).render(&world, &mut black(), 2);
        assert_eq!(
            reused.full, fresh.full,
            "a recycled G-buffer renders exactly like a new one"
        );
    }

    #[test]
    fn raster_and_ray_gbuffers_light_alike() {
        let world = World::new(illume_scene::builtin::load("cornell-spot").expect("builtin"));
        let (w, h) = (200, 150);
        let raster = GBuffer::rasterize(&world, w, h);
        let rays = GBuffer::render(&world, w, h, Vec2::splat(0.5));
        let a = direct_light(&world, &raster, 4, 7);
        let b = direct_light(&world, &rays, 4, 7);
        let (mut same_surface, mut differ) = (0, 0);
        for (i, (r, t)) in raster.pixels.iter().zip(&rays.pixels).enumerate() {
            let agree = match (r, t) {
                (Some(r), Some(t)) => {
                    (r.hit.instance, r.hit.triangle) == (t.hit.instance, t.hit.triangle)
                }
                (None, None) => true,
                _ => false,
            };
            if agree {
                same_surface += 1;
                // Same surface up to f32 rounding of the hit point: the same light,
                // except where that rounding flips a shadow ray at a shadow edge.
                let (x, y) = (a.pixels()[i], b.pixels()[i]);
                if (x - y).abs().max_element() > 1e-4 * (1.0 + y.max_element()) {
                    differ += 1;
                }
            }
        }
        assert!(
            same_surface as f64 >= 0.999 * (w * h) as f64,
            "{same_surface}"
        );
        assert!(
            differ as f64 <= 1e-3 * (w * h) as f64,
            "{differ} pixels differ"
        );
    }

    #[test]
    fn renderer_with_maps_shades_like_direct_light_with_fresh_maps() {
        let mut world = World::new(illume_scene::builtin::load("cornell-spot").expect("builtin"));
        let settings = RenderSettings {
            width: 64,
            height: 48,
            shadows: ShadowMode::Maps,
            ..Default::default()
        };
        let renderer = Renderer::new(settings.clone());
        drop(renderer.render(&world, &mut black(), 0));
        // The light and the sphere move: the renderer's maps must follow.
        world.set_time(1.0);
        let frame = renderer.render(&world, &mut black(), 1);
        let maps = ShadowMaps::build(&world, &settings.shadow_maps).expect("valid");
        let expected = direct_light_with(
            &world,
            &frame.gbuffer,
            Shadows::Maps(&maps),
            settings.area_light_samples,
            mix64(settings.seed ^ 1u64.wrapping_mul(0x9e37)),
        );
        assert_eq!(frame.direct, expected);
        assert!(frame.timings.shadow_maps_ms > 0.0);
        // Invalid map settings are reported, and the renderer falls back to exact rays.
        let bad = RenderSettings {
            shadow_maps: ShadowMapSettings {
                resolution: 0,
                ..Default::default()
            },
            ..settings.clone()
        };
        assert!(matches!(
            bad.validate(),
            Err(RenderSettingsError::ShadowMaps(
                ShadowMapError::OutOfRange {
                    field: "resolution",
                    ..
                }
            ))
        ));
        let no_samples = RenderSettings {
            area_light_samples: 0,
            ..settings.clone()
        };
        assert!(matches!(
            no_samples.validate(),
            Err(RenderSettingsError::NoAreaLightSamples)
        ));
        for blend in [0.0, -0.1, 1.5, f32::NAN] {
            let bad_blend = RenderSettings {
                temporal_aa_blend: blend,
                ..settings.clone()
            };
            let e = bad_blend.validate().expect_err("out of (0, 1]");
            assert!(e.to_string().contains("temporal_aa_blend"), "{e}");
        }
        let fallback = Renderer::new(bad).render(&world, &mut black(), 1);
        let rays = direct_light(
            &world,
            &fallback.gbuffer,
            16,
            mix64(1u64.wrapping_mul(0x9e37)),
        );
        assert_eq!(fallback.direct, rays);
    }

    #[test]
    fn shadows_default_to_auto_and_parse_from_toml_names() {
        assert_eq!(RenderSettings::default().shadows, ShadowMode::Auto);
        let s: RenderSettings = toml_like("maps");
        assert_eq!(s.shadows, ShadowMode::Maps);
    }

    /// Settings with `shadows` set through serde, as a config file would.
    fn toml_like(mode: &str) -> RenderSettings {
        let value = serde::de::value::StrDeserializer::<serde::de::value::Error>::new(mode);
        let shadows = <ShadowMode as serde::Deserialize>::deserialize(value).expect("known name");
        RenderSettings {
            shadows,
            ..Default::default()
        }
    }

    #[test]
    fn texture_filter_defaults_to_trilinear_and_parses_snake_case_names() {
        assert_eq!(
            RenderSettings::default().texture_filter,
            TextureFilter::Trilinear
        );
        for (name, filter) in [
            ("bilinear", TextureFilter::Bilinear),
            ("trilinear", TextureFilter::Trilinear),
        ] {
            let value = serde::de::value::StrDeserializer::<serde::de::value::Error>::new(name);
            assert_eq!(
                <TextureFilter as serde::Deserialize>::deserialize(value).expect("known name"),
                filter
            );
        }
    }

    #[test]
    fn primary_visibility_defaults_to_raster() {
        assert_eq!(
            RenderSettings::default().primary_visibility,
            PrimaryVisibility::Raster
        );
    }
}
