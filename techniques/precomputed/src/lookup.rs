//! Per domain, how the file's texels reach the pixels at run time ([`crate::domain`]
//! says where keys live): `screen` pixels are the file's pixels; `cube` pixels look up
//! the face texel along the direction from the camera to their surface; `atlas` pixels
//! of static surfaces read their lightmap texel (bilinear, within their chart), pixels
//! of dynamic objects the probe grid, both times the pixel's albedo. `atlas`
//! reconstructs its whole (small) domain image when the clock time changes and keeps it
//! while it stays; `cube` (about 9× the image's pixels) reconstructs only the runs of
//! texels the pixels read.

use crate::atlas::{Atlas, Texel};
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
    /// the sky is up, read in the same pass (one read of the G-buffer for both).
    pub(crate) fn pixels(
        &mut self,
        hours: f64,
        sky_scale: f32,
        gbuffer: &GBuffer,
    ) -> (Vec<Rgb>, Option<Vec<Rgb>>) {
        match &self.lookup {
            Lookup::Screen => self.screen_pixels(hours, sky_scale, gbuffer),
            Lookup::Cube { face, position } => {
                let (face, position) = (*face, *position);
                self.cube_pixels(face, position, hours, sky_scale, gbuffer)
            }
            Lookup::Atlas { .. } => self.atlas_pixels(hours, sky_scale, gbuffer),
        }
    }

    /// The sky's direct texels and the scale of this frame, when a share is handed over.
    fn direct_texels(&self, sky_scale: f32) -> Option<(&[Rgb], f32)> {
        if !self.share_wanted {
            return None;
        }
        let direct = self.sky_direct.as_deref()?;
        (sky_scale > 0.0).then_some((direct, sky_scale))
    }

    /// `screen`: the file's pixel under each pixel.
    fn screen_pixels(
        &mut self,
        hours: f64,
        sky_scale: f32,
        gbuffer: &GBuffer,
    ) -> (Vec<Rgb>, Option<Vec<Rgb>>) {
        let n = gbuffer.width as usize * gbuffer.height as usize;
        // Pixels that see nothing get nothing. A G-buffer of another size than
        // the file's was refused at load; keep black rather than a wrong image
        // if it happens anyway.
        if (gbuffer.width, gbuffer.height) != (self.width, self.height) {
            return (vec![Rgb::ZERO; n], None);
        }
        let values = self.values(hours, sky_scale);
        let seen = |i: usize, texels: &[Rgb]| {
            if gbuffer.pixels[i].is_some() {
                texels[i]
            } else {
                Rgb::ZERO
            }
        };
        read_both(n, &values, self.direct_texels(sky_scale), 4096, seen)
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
        let read = |i: usize, texels: &[Rgb]| {
            taps[i]
                .iter()
                .map(|&(t, w)| texels[t] * w)
                .fold(Rgb::ZERO, |a, b| a + b)
        };
        let out = read_both(
            taps.len(),
            &buffer,
            self.direct_texels(sky_scale),
            1024,
            read,
        );
        self.runs = buffer;
        out
    }

    /// `atlas`: the domain image reconstructed when the clock time changes (paired with
    /// the sky's direct share, scaled, when one is handed over: one lookup reads both),
    /// read per pixel from the lightmap and probes.
    fn atlas_pixels(
        &mut self,
        hours: f64,
        sky_scale: f32,
        gbuffer: &GBuffer,
    ) -> (Vec<Rgb>, Option<Vec<Rgb>>) {
        let key = (hours, sky_scale);
        // The cached texels carry the direct share exactly when it is wanted now.
        let with_share = self.direct_texels(sky_scale).is_some();
        if self.cache.as_ref().is_none_or(|(k, texels)| {
            *k != key || matches!(texels, AtlasTexels::WithShare(_)) != with_share
        }) {
            let values = self.values(hours, sky_scale);
            let texels = match self.direct_texels(sky_scale) {
                None => AtlasTexels::Light(values),
                Some((direct, scale)) => AtlasTexels::WithShare(
                    values
                        .par_iter()
                        .zip(direct)
                        .with_min_len(4096)
                        .map(|(v, d)| Both(*v, *d * scale))
                        .collect(),
                ),
            };
            self.cache = Some((key, texels));
        }
        let pixels = gbuffer.pixels.par_iter().with_min_len(256);
        match &self.cache.as_ref().expect("just filled").1 {
            AtlasTexels::Light(values) => (pixels.map(|px| self.shade(px, values)).collect(), None),
            AtlasTexels::WithShare(both) => {
                let (out, share): (Vec<Rgb>, Vec<Rgb>) = pixels
                    .map(|px| {
                        let Both(v, d) = self.shade(px, both);
                        (v, d)
                    })
                    .unzip();
                (out, Some(share))
            }
        }
    }

    /// `atlas`: a pixel's value from the lightmap and probes `values`.
    fn shade<T: Texel + Times>(
        &self,
        px: &Option<illume_transport::GBufferPixel>,
        values: &[T],
    ) -> T {
        let Some(px) = px else {
            return T::ZERO;
        };
        let hit = &px.hit;
        match &self.lookup {
            Lookup::Screen | Lookup::Cube { .. } => T::ZERO,
            Lookup::Atlas { atlas, valid } => {
                let back = !hit.front_face;
                let albedo = hit.albedo;
                let lit = match atlas.slot(hit.instance, hit.triangle, back) {
                    Some(slot) => atlas.lookup(values, slot, hit.barycentrics),
                    // The unlit back of a one-sided static surface.
                    None if atlas.maps(hit.instance) => return T::ZERO,
                    None => {
                        let probes = &values[atlas.lightmap_texels()..];
                        atlas.probe_lookup(probes, valid, hit.position, hit.facing_normal())
                    }
                };
                lit.times(albedo)
            }
        }
    }
}

/// The `atlas` domain's texels for the frame's clock time: the light alone, or paired
/// with the sky's direct share.
pub(crate) enum AtlasTexels {
    /// The light (sun's indirect and the sky's whole light).
    Light(Vec<Rgb>),
    /// The light and, beside it, the sky's direct share (both at the frame's sky scale).
    WithShare(Vec<Both>),
}

/// Two texel values read with one set of lookup weights: the light and its direct share.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Both(Rgb, Rgb);

impl std::ops::Add for Both {
    type Output = Self;
    fn add(self, o: Self) -> Self {
        Both(self.0 + o.0, self.1 + o.1)
    }
}

impl std::ops::AddAssign for Both {
    fn add_assign(&mut self, o: Self) {
        *self = *self + o;
    }
}

impl std::ops::Mul<f32> for Both {
    type Output = Self;
    fn mul(self, w: f32) -> Self {
        Both(self.0 * w, self.1 * w)
    }
}

impl Texel for Both {
    const ZERO: Self = Both(Rgb::ZERO, Rgb::ZERO);
}

/// A lookup's result times a pixel's albedo, channel by channel.
trait Times {
    fn times(self, albedo: Rgb) -> Self;
}

impl Times for Rgb {
    fn times(self, albedo: Rgb) -> Self {
        self * albedo
    }
}

impl Times for Both {
    fn times(self, albedo: Rgb) -> Self {
        Both(self.0 * albedo, self.1 * albedo)
    }
}

/// `read(i, texels)` for each pixel i < `n` from `values`, and, when `direct` is given
/// (the sky's direct texels and the frame's sky scale), from them too, scaled, in the
/// same pass (pixels in jobs of at least `min_len`).
fn read_both<F>(
    n: usize,
    values: &[Rgb],
    direct: Option<(&[Rgb], f32)>,
    min_len: usize,
    read: F,
) -> (Vec<Rgb>, Option<Vec<Rgb>>)
where
    F: Fn(usize, &[Rgb]) -> Rgb + Sync,
{
    let pixels = (0..n).into_par_iter().with_min_len(min_len);
    match direct {
        None => (pixels.map(|i| read(i, values)).collect(), None),
        Some((direct, scale)) => {
            let (out, share): (Vec<Rgb>, Vec<Rgb>) = pixels
                .map(|i| (read(i, values), read(i, direct) * scale))
                .unzip();
            (out, Some(share))
        }
    }
}
