//! Per domain, how the file's texels reach the pixels at run time ([`crate::domain`]
//! says where keys live): `screen` pixels are the file's pixels; `cube` pixels look up
//! the face texel along the direction from the camera to their surface; `atlas` pixels
//! of static surfaces read their lightmap texel (bilinear, within their chart), pixels
//! of dynamic objects the probe grid, both times the pixel's albedo. `atlas`
//! reconstructs its whole (small) domain image when the clock time changes and keeps it
//! while it stays; `cube` (about 9× the image's pixels) reconstructs only the runs of
//! texels the pixels read.

use crate::atlas::Atlas;
use crate::reconstruct::RUN;
use crate::state::Precomputed;
use illume_core::{Rgb, Vec3};
use illume_transport::GBuffer;
use rayon::prelude::*;

/// How the file's texels reach the pixels.
pub(crate) enum Lookup {
    /// One texel per pixel.
    Screen,
    /// Six faces of `face` pixels around `position`.
    Cube { face: u32, position: Vec3 },
    /// The lightmap and probes; probe validity flags.
    Atlas { atlas: Box<Atlas>, valid: Vec<f32> },
}

impl Precomputed {
    /// Each pixel's indirect light (and sky light) at clock time `hours`, the sky at
    /// scale `sky_scale`, through the domain's lookup; and the direct share of it (the
    /// sky's direct light, [`crate::precompute::Sky::direct`]) when the file has one and
    /// the sky is up.
    pub(crate) fn pixels(
        &mut self,
        hours: f64,
        sky_scale: f32,
        gbuffer: &GBuffer,
    ) -> (Vec<Rgb>, Option<Vec<Rgb>>) {
        match &self.lookup {
            Lookup::Screen => {
                let share = self.screen_share(sky_scale, gbuffer);
                (self.screen_pixels(hours, sky_scale, gbuffer), share)
            }
            Lookup::Cube { face, position } => {
                let (face, position) = (*face, *position);
                self.cube_pixels(face, position, hours, sky_scale, gbuffer)
            }
            Lookup::Atlas { .. } => {
                let share = self
                    .sky_direct
                    .as_ref()
                    .filter(|_| sky_scale > 0.0)
                    .map(|d| {
                        let mut share = self.shade(d, gbuffer);
                        share.par_iter_mut().for_each(|p| *p *= sky_scale);
                        share
                    });
                (self.atlas_pixels(hours, sky_scale, gbuffer), share)
            }
        }
    }

    /// `screen`: the sky's direct light at scale `sky_scale` under each pixel that sees
    /// something.
    fn screen_share(&self, sky_scale: f32, gbuffer: &GBuffer) -> Option<Vec<Rgb>> {
        let direct = self.sky_direct.as_ref().filter(|_| sky_scale > 0.0)?;
        ((gbuffer.width, gbuffer.height) == (self.width, self.height)).then(|| {
            direct
                .par_iter()
                .zip(&gbuffer.pixels)
                .with_min_len(4096)
                .map(|(d, px)| {
                    if px.is_some() {
                        *d * sky_scale
                    } else {
                        Rgb::ZERO
                    }
                })
                .collect()
        })
    }

    /// `screen`: the file's pixel under each pixel.
    fn screen_pixels(&mut self, hours: f64, sky_scale: f32, gbuffer: &GBuffer) -> Vec<Rgb> {
        let n = gbuffer.width as usize * gbuffer.height as usize;
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

    /// `cube`: each pixel's four face texels along the direction from the cube's
    /// `position` (faces of `face` pixels).
    fn cube_pixels(
        &mut self,
        face: u32,
        position: Vec3,
        hours: f64,
        sky_scale: f32,
        gbuffer: &GBuffer,
    ) -> (Vec<Rgb>, Option<Vec<Rgb>>) {
        // Only the runs of texels the pixels read: a cube holds ~9× the image's
        // pixels, a camera sees a fraction of it.
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
        let share = self
            .sky_direct
            .as_ref()
            .filter(|_| sky_scale > 0.0)
            .map(|d| {
                taps.par_iter()
                    .with_min_len(1024)
                    .map(|tap| {
                        tap.iter()
                            .map(|&(t, w)| d[t] * (w * sky_scale))
                            .fold(Rgb::ZERO, |a, b| a + b)
                    })
                    .collect()
            });
        (out, share)
    }

    /// `atlas`: the domain image reconstructed when the clock time changes, read per
    /// pixel from the lightmap and probes.
    fn atlas_pixels(&mut self, hours: f64, sky_scale: f32, gbuffer: &GBuffer) -> Vec<Rgb> {
        let key = (hours, sky_scale);
        if self.cache.as_ref().is_none_or(|(k, _)| *k != key) {
            let values = self.values(hours, sky_scale);
            self.cache = Some((key, values));
        }
        let values = &self.cache.as_ref().expect("just filled").1;
        self.shade(values, gbuffer)
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
