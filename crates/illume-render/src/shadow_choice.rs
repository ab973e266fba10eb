//! `shadows = "auto"`: each analytic light, each frame, gets its shadows from shadow maps
//! or from shadow rays, whichever a measured cost model expects to be cheaper.
//!
//! Per light, with `lit` the pixels the light reaches (in range, inside its cone, facing
//! it; counted on [`SAMPLED_PIXELS`] pixels spread over the G-buffer):
//!
//! * **maps** whose view and geometry did not change since they were rendered are always
//!   kept: they cost `lit × lookup_ns`, and lookups cost 0.1–0.4× the time of rays in
//!   every scene measured (`BENCHMARKS.md`). Stale maps cost their rendering, spread over
//!   the frames they are expected to serve — 1 for a light (or scene) that moved since
//!   the last frame, `k + 1` for one that has been still for `k` frames,
//!   [`NEW_LIGHT_STILL_FRAMES`] for a light seen for the first time — plus the lookups;
//! * **rays** cost `lit × ray_ns`.
//!
//! A light's `lookup_ns` includes the rays of the points it grazes, which its maps leave
//! to rays ([`ShadowMapSettings::ray_below_cos`]).
//!
//! Every cost is measured on the scene at hand, per light, and carried from frame to
//! frame as a running average. `ray_ns` (whenever the light's maps are stale) and
//! `lookup_ns` (whenever they were just rendered) by timing [`PROBE_RAYS`] shadow rays or
//! lookups from lit pixels: runs of neighbouring pixels spread over the image, each
//! timing [`PROBE_BATCH`] pixels after as many neighbours warmed the caches (as in the
//! shading pass), the fastest run counting (preemption by other processes only adds
//! time); the pass's rays cost [`RAY_PROBE_SCALE`] times the probe's. The rendering by
//! the CPU time its last one took on the renderer's threads. Before a measurement
//! exists, priors stand in: a lookup costs [`LOOKUP_PER_RAY_PRIOR`] of a ray, a ray
//! [`RAY_NS_PRIOR`], a rendering `faces × (triangles × RASTER_TRIANGLE_NS + face texels ×
//! RASTER_TEXEL_NS)` scaled by how far measured renderings of other lights were off this
//! prediction (the rasterizer's cost per triangle depends on how many texels each
//! covers: 40–600 ns). Costs are nanoseconds of CPU time: the passes are parallel alike,
//! so the thread count cancels out, and CPU time does not grow with the load of other
//! processes on the machine.
//!
//! The outcome: a light that moves every frame with a cube map over a large scene gets
//! rays (six rasterizations of every triangle cost more than one ray per lit pixel); a
//! still light keeps its map (lookups only); a light that stops moving goes back to maps
//! once the one rendering pays off over as many frames as it has been still.

use crate::shadow_map::{LightMapPlan, ShadowMapError, ShadowMapSettings, ShadowMaps};
use illume_core::Vec2;
use illume_transport::{GBuffer, GBufferPixel, LightSample, SurfaceHit, World};
use std::time::Instant;

/// Cost of one shadow-map lookup before one is measured, as a fraction of the light's
/// shadow ray (the probes measure 0.2–0.7 on the Cornell dragon, cornell-spot and
/// Sponza; `BENCHMARKS.md`).
pub const LOOKUP_PER_RAY_PRIOR: f64 = 0.5;

/// Cost of one shadow ray before one is measured \[ns of one core\].
pub const RAY_NS_PRIOR: f64 = 100.0;

/// The shading pass's shadow rays cost this many times the probe's: the pass's rays
/// miss caches that the probe's warm-up filled (cornell-spot and Sponza in
/// `benches/direct.rs`, per lit pixel against the probes: 1.35–2.2; `BENCHMARKS.md`).
pub const RAY_PROBE_SCALE: f64 = 1.5;

/// Rasterizing one triangle into one depth map, before any rendering is measured \[ns of
/// one core\]: vertex transform, setup, binning and its share of fill.
pub const RASTER_TRIANGLE_NS: f64 = 50.0;

/// Clearing, filling and converting one depth-map texel, before any rendering is
/// measured \[ns of one core\].
pub const RASTER_TEXEL_NS: f64 = 5.0;

/// Frames a light seen for the first time is expected to stay still (10 s at 30 fps):
/// its first frame's rendering is charged 1/this of its cost (most lights never move).
pub const NEW_LIGHT_STILL_FRAMES: u32 = 300;

/// Shadow rays (or lookups) the probe times per light and frame.
pub const PROBE_RAYS: usize = 256;

/// Rays (or lookups) per timed batch of the probe.
pub const PROBE_BATCH: usize = 32;

/// G-buffer pixels sampled per light and frame to count the lit ones.
pub const SAMPLED_PIXELS: usize = 2048;

/// What one frame's shadows used (analytic lights; area lights always use rays).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ShadowStats {
    /// Analytic lights whose shadows came from maps.
    pub lights_with_maps: u32,
    /// Analytic lights whose shadows came from rays.
    pub lights_with_rays: u32,
    /// Depth maps rendered this frame (a cube map counts six; kept maps count nothing).
    pub maps_rendered: u32,
}

/// One light's estimate in one frame \[ns of one core\].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightShadowChoice {
    /// What the shadow maps found for the light.
    pub plan: LightMapPlan,
    /// Estimated pixels the light reaches.
    pub lit_pixels: f64,
    /// Cost of one shadow ray used for the estimate.
    pub ray_ns: f64,
    /// Cost of one lookup used for the estimate.
    pub lookup_ns: f64,
    /// Cost of rendering all the light's maps used for the estimate.
    pub render_ns: f64,
    /// Estimated cost of its maps this frame (rendering share + lookups).
    pub maps_ns: f64,
    /// Estimated cost of its rays this frame.
    pub rays_ns: f64,
    /// The choice.
    pub maps: bool,
}

/// What was measured for one analytic light \[ns of one core\].
#[derive(Clone, Copy, Debug, Default)]
struct Measured {
    ray_ns: Option<f64>,
    lookup_ns: Option<f64>,
}

/// The state behind `shadows = "auto"`: the costs measured per light, carried from frame
/// to frame.
#[derive(Clone, Debug)]
pub struct ShadowChooser {
    /// Per analytic light.
    measured: Vec<Measured>,
    /// Measured ÷ predicted rendering time (running average).
    raster_scale: f64,
    /// The last frame's choices.
    choices: Vec<LightShadowChoice>,
}

impl Default for ShadowChooser {
    fn default() -> Self {
        Self {
            measured: Vec::new(),
            raster_scale: 1.0,
            choices: Vec::new(),
        }
    }
}

/// Rendering cost of a light's maps predicted from the priors \[ns of one core\].
fn predicted_render_ns(plan: &LightMapPlan, triangles: f64) -> f64 {
    f64::from(plan.faces) * triangles * RASTER_TRIANGLE_NS + plan.texels as f64 * RASTER_TEXEL_NS
}

/// A running average of `old` and the new measurement `new`.
fn average(old: Option<f64>, new: Option<f64>) -> Option<f64> {
    match (old, new) {
        (Some(a), Some(b)) => Some(0.5 * (a + b)),
        (a, b) => b.or(a),
    }
}

impl ShadowChooser {
    /// Chooses maps or rays for every analytic light of `world` this frame, renders the
    /// maps of the lights that get them ([`ShadowMaps::plan`], then
    /// [`ShadowMaps::render_planned`]) and reports the counts. Call once per frame; then
    /// shade with `Shadows::Maps(maps)`: lights without maps cast rays.
    pub fn choose(
        &mut self,
        world: &World,
        gbuffer: &GBuffer,
        maps: &mut ShadowMaps,
        settings: &ShadowMapSettings,
    ) -> Result<ShadowStats, ShadowMapError> {
        let plans = maps.plan(world, settings)?.to_vec();
        if self.measured.len() != plans.len() {
            self.measured = vec![Measured::default(); plans.len()];
        }
        let triangles = world.scene.instanced_triangle_count() as f64;
        let previous = std::mem::take(&mut self.choices);
        let mut samples = Vec::with_capacity(plans.len());
        for (light, plan) in plans.iter().enumerate() {
            // A current map is kept whatever the costs (below): no sampling, no probe,
            // the last estimate of its lit pixels stands.
            let lit = if plan.current {
                LitSample {
                    pixels: previous.get(light).map_or(0.0, |c| c.lit_pixels),
                    batches: Vec::new(),
                }
            } else {
                lit_samples(world, gbuffer, light)
            };
            let m = &mut self.measured[light];
            if plan.faces > 0 && !plan.current {
                let probed = time_batches(&lit.batches, |(hit, s)| world.unoccluded(hit, s));
                m.ray_ns = average(m.ray_ns, probed.map(|ns| ns * RAY_PROBE_SCALE));
            }
            let render_ns = match maps.render_cost(light) {
                Some(ns) => ns,
                None => self.raster_scale * predicted_render_ns(plan, triangles),
            };
            let ray_ns = m.ray_ns.unwrap_or(RAY_NS_PRIOR);
            let mut choice = LightShadowChoice {
                plan: *plan,
                lit_pixels: lit.pixels,
                ray_ns,
                lookup_ns: m.lookup_ns.unwrap_or(LOOKUP_PER_RAY_PRIOR * ray_ns),
                render_ns,
                maps_ns: 0.0,
                rays_ns: 0.0,
                maps: false,
            };
            let frames = plan.still_frames.map_or(NEW_LIGHT_STILL_FRAMES, |k| k + 1);
            let render_share = if plan.current {
                0.0
            } else {
                render_ns / f64::from(frames.max(1))
            };
            choice.maps_ns = render_share + choice.lit_pixels * choice.lookup_ns;
            choice.rays_ns = choice.lit_pixels * choice.ray_ns;
            // No map can be made (faces = 0): rays. A current map is always kept: its
            // lookups cost 0.1–0.4× the time of rays in every scene measured
            // (`BENCHMARKS.md`), and the probes cannot tell them apart that finely.
            choice.maps = plan.faces > 0 && (plan.current || choice.maps_ns < choice.rays_ns);
            self.choices.push(choice);
            samples.push(lit.batches);
        }
        let use_maps: Vec<bool> = self.choices.iter().map(|c| c.maps).collect();
        maps.render_planned_timed(world, &use_maps, &pool_cpu_ns);
        let maps_ref = &*maps;
        for (light, (choice, lit)) in self.choices.iter().zip(&samples).enumerate() {
            if !choice.maps {
                continue;
            }
            let m = &mut self.measured[light];
            m.lookup_ns = average(
                m.lookup_ns,
                // Grazing points take rays even with maps: part of the maps' cost.
                time_batches(lit, |(hit, s)| {
                    maps_ref
                        .visibility(light, hit, s)
                        .unwrap_or_else(|| f32::from(u8::from(world.unoccluded(hit, s))))
                }),
            );
            // A rendering this frame calibrates the priors for lights not yet rendered.
            if !choice.plan.current
                && let Some(ns) = maps.render_cost(light)
            {
                let predicted = predicted_render_ns(&choice.plan, triangles);
                let ratio = (ns / predicted).clamp(0.05, 50.0);
                self.raster_scale = 0.5 * (self.raster_scale + ratio);
            }
        }
        let with_maps = use_maps.iter().filter(|&&m| m).count() as u32;
        Ok(ShadowStats {
            lights_with_maps: with_maps,
            lights_with_rays: plans.len() as u32 - with_maps,
            maps_rendered: maps.rendered_last_build() as u32,
        })
    }

    /// The last frame's per-light estimates and choices, in analytic-light order.
    pub fn choices(&self) -> &[LightShadowChoice] {
        &self.choices
    }

    /// Measured ÷ predicted rendering time of the lights rendered so far: the
    /// calibration of [`RASTER_TRIANGLE_NS`] and [`RASTER_TEXEL_NS`] on this scene (1
    /// before any rendering was timed).
    pub fn raster_scale(&self) -> f64 {
        self.raster_scale
    }
}

/// The lit pixels of a G-buffer sample, for one light.
struct LitSample<'g> {
    /// Estimated lit pixels in the whole image.
    pixels: f64,
    /// Up to [`PROBE_RAYS`] / [`PROBE_BATCH`] runs of up to [`PROBE_BATCH`] consecutive
    /// lit pixels, spread over the image, with their light samples: neighbours, as the
    /// shading pass meets them (shadow rays and map lookups of neighbouring pixels share
    /// caches; scattered ones would cost several times more).
    batches: Vec<Vec<(&'g SurfaceHit, LightSample)>>,
}

/// The light sample of `light` at `px` if the light reaches it (in range and cone,
/// the surface facing it).
fn lit_by(world: &World, px: &Option<GBufferPixel>, light: usize) -> Option<LightSample> {
    let hit = &px.as_ref()?.hit;
    if hit.is_black() {
        return None;
    }
    let (s, _) = world
        .lights
        .incident_from(light, hit.position, Vec2::ZERO)?;
    let (normal, geometric) = (hit.facing_normal(), hit.facing_geometric_normal());
    (normal.dot(s.wi) > 0.0 && geometric.dot(s.wi) > 0.0).then_some(s)
}

/// Counts the pixels of `gbuffer` that analytic light `light` reaches among
/// [`SAMPLED_PIXELS`] pixels spread over the image, and collects the probe's runs.
fn lit_samples<'g>(world: &World, gbuffer: &'g GBuffer, light: usize) -> LitSample<'g> {
    let pixels = &gbuffer.pixels;
    let n = pixels.len();
    let stride = n.div_ceil(SAMPLED_PIXELS).max(1);
    let (mut lit, mut sampled) = (0usize, 0usize);
    for px in pixels.iter().skip(stride / 2).step_by(stride) {
        sampled += 1;
        lit += usize::from(lit_by(world, px, light).is_some());
    }
    let runs = PROBE_RAYS / PROBE_BATCH;
    let mut batches = Vec::with_capacity(runs);
    if lit > 0 {
        for run in 0..runs {
            // From the middle of each n/runs-pixel band, the next 2 × PROBE_BATCH lit
            // pixels (scanning at most 64 batches' worth): the first half warms the
            // caches, the second is timed.
            let start = (2 * run + 1) * n / (2 * runs);
            let batch: Vec<_> = pixels[start.min(n)..]
                .iter()
                .take(64 * PROBE_BATCH)
                .filter_map(|px| Some((&px.as_ref()?.hit, lit_by(world, px, light)?)))
                .take(2 * PROBE_BATCH)
                .collect();
            if batch.len() > 1 {
                batches.push(batch);
            }
        }
    }
    LitSample {
        pixels: lit as f64 * n as f64 / sampled.max(1) as f64,
        batches,
    }
}

/// Cost of `f` per sample \[ns\]: that of the fastest run, timed on the second half of
/// its samples once the first half (their neighbours) has brought the data they share
/// into the caches; `None` without samples.
fn time_batches<T, R>(batches: &[Vec<T>], f: impl Fn(&T) -> R) -> Option<f64> {
    let mut fastest: Option<f64> = None;
    for batch in batches.iter().filter(|b| b.len() > 1) {
        let (warm, timed) = batch.split_at(batch.len() / 2);
        for sample in warm {
            std::hint::black_box(f(sample));
        }
        let t = Instant::now();
        for sample in timed {
            std::hint::black_box(f(sample));
        }
        let ns = t.elapsed().as_secs_f64() * 1e9 / timed.len() as f64;
        fastest = Some(fastest.map_or(ns, |f: f64| f.min(ns)));
    }
    fastest
}

/// CPU time consumed so far by the threads of the current rayon pool \[ns\]: what the
/// map renderings cost, whatever share of the cores other processes take meanwhile
/// (wall-clock time would grow with their load; the probes, too short to be preempted,
/// do not).
fn pool_cpu_ns() -> f64 {
    rayon::broadcast(|_| illume_core::cpu_time::thread_cpu_ns())
        .iter()
        .sum()
}
