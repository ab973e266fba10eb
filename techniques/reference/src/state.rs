//! The reference as a [`Technique`]: indirect light at G-buffer points by path tracing,
//! accumulated over frames; any scene change or a new G-buffer restarts the average.

use crate::settings::ReferenceSettings;
use crate::update;
use illume_core::image::RgbImage;
use illume_core::sampling::{Pcg32, mix64};
use illume_core::{Counters, Rgb, Vec3};
use illume_scene::SceneChange;
use illume_transport::path::{PathRadiance, continue_path};
use illume_transport::{Budget, ChangeResponse, GBuffer, Technique, World};
use rayon::prelude::*;

/// Path-traced indirect light for the renderer (technique name `reference`).
pub struct ReferenceTechnique {
    settings: ReferenceSettings,
    sum: Vec<[f64; 3]>,
    samples: u32,
    pending: u32,
    signature: Option<u64>,
    paths_traced: u64,
}

impl ReferenceTechnique {
    /// A technique with `settings` (its `spp_per_frame` is the default budget).
    pub fn new(settings: ReferenceSettings) -> Result<Self, crate::ReferenceError> {
        settings.validate()?;
        let pending = settings.spp_per_frame;
        Ok(Self {
            settings,
            sum: Vec::new(),
            samples: 0,
            pending,
            signature: None,
            paths_traced: 0,
        })
    }
}

/// A cheap fingerprint of a G-buffer (positions and instances) to tell when accumulation
/// must restart.
fn signature(g: &GBuffer) -> u64 {
    let mut h = mix64(g.width as u64) ^ mix64(g.height as u64 + 1);
    for (i, p) in g.pixels.iter().enumerate().step_by(7) {
        if let Some(p) = p {
            let v = p.hit.position.to_array().map(f32::to_bits);
            h = mix64(
                h ^ (i as u64)
                    ^ ((v[0] as u64) << 32 | v[1] as u64)
                    ^ v[2] as u64
                    ^ ((p.hit.instance.0 as u64) << 40),
            );
        }
    }
    h
}

impl Technique for ReferenceTechnique {
    fn name(&self) -> &'static str {
        crate::NAME
    }

    fn scene_changed(&mut self, _world: &World, changes: &[SceneChange]) -> ChangeResponse {
        if update::restarts_accumulation(changes) {
            self.reset();
        }
        ChangeResponse::Updated
    }

    /// Adds `budget.work` samples per pixel at the next [`Technique::indirect`]
    /// (default [`ReferenceSettings::spp_per_frame`]); `budget.time_ms` is ignored.
    fn advance(&mut self, _world: &World, budget: &Budget) {
        self.pending = budget.work.map_or(self.settings.spp_per_frame, |n| {
            n.clamp(1, u32::MAX as u64) as u32
        });
    }

    fn indirect(&mut self, world: &World, gbuffer: &GBuffer) -> RgbImage {
        let sig = signature(gbuffer);
        if self.signature != Some(sig) || self.sum.len() != gbuffer.pixels.len() {
            self.sum = vec![[0.0; 3]; gbuffer.pixels.len()];
            self.samples = 0;
            self.signature = Some(sig);
        }
        let first = self.samples;
        let spp = self.pending.max(1);
        let settings = &self.settings;
        let path = settings.path();
        self.sum
            .par_iter_mut()
            .zip(&gbuffer.pixels)
            .enumerate()
            .with_min_len(16)
            .for_each(|(i, (acc, px))| {
                let Some(px) = px else { return };
                for s in first..first + spp {
                    let mut rng = Pcg32::new(
                        mix64(
                            settings
                                .seed
                                .wrapping_add(0x5bd1e995)
                                .wrapping_add(s as u64),
                        ),
                        i as u64,
                    );
                    let mut out = PathRadiance::default();
                    continue_path(world, px.hit, px.to_camera, &mut rng, &path, &mut out);
                    for (a, v) in acc.iter_mut().zip(out.indirect.to_array()) {
                        *a += f64::from(v);
                    }
                }
            });
        self.samples += spp;
        self.paths_traced +=
            spp as u64 * gbuffer.pixels.iter().filter(|p| p.is_some()).count() as u64;
        let inv = 1.0 / self.samples as f64;
        let px = self
            .sum
            .iter()
            .map(|s| {
                Vec3::new(
                    (s[0] * inv) as f32,
                    (s[1] * inv) as f32,
                    (s[2] * inv) as f32,
                )
            })
            .collect::<Vec<Rgb>>();
        RgbImage::from_vec(gbuffer.width, gbuffer.height, px).expect("one value per pixel")
    }

    fn stats(&self) -> Counters {
        let mut c = Counters::new();
        c.set("spp", self.samples as f64);
        c.set("paths_traced", self.paths_traced as f64);
        c
    }

    fn reset(&mut self) {
        self.sum.clear();
        self.samples = 0;
        self.signature = None;
    }
}
