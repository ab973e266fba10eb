//! Display of the element solution (§6): indirect radiance per G-buffer pixel.
//!
//! L = ρ(x)/π · E(x), E interpolated from the display vertices of the pixel's element
//! ([`Elements::irradiance`]), ρ the pixel's own albedo (textures at full resolution).

use crate::elements::{Display, Elements};
use illume_core::image::RgbImage;
use illume_core::{INV_PI, Rgb};
use illume_transport::{GBuffer, World};
use rayon::prelude::*;

/// Indirect radiance of every pixel of `gbuffer` from `display`.
pub fn shade(world: &World, gbuffer: &GBuffer, elements: &Elements, display: &Display) -> RgbImage {
    let (w, h) = (gbuffer.width, gbuffer.height);
    let mut img = RgbImage::filled(w, h, Rgb::ZERO);
    let scene = &world.scene;
    img.pixels_mut()
        .par_chunks_mut(w.max(1) as usize)
        .zip(gbuffer.pixels.par_chunks(w.max(1) as usize))
        .for_each(|(row, px)| {
            for (out, p) in row.iter_mut().zip(px) {
                *out = match p {
                    Some(p) if p.hit.reflects && p.hit.albedo != Rgb::ZERO => {
                        let inst = p.hit.instance.index();
                        let mesh = scene.instances[inst].mesh.index();
                        let e = elements.irradiance(
                            display,
                            inst,
                            mesh,
                            p.hit.triangle as usize,
                            p.hit.barycentrics,
                            p.hit.front_face,
                        );
                        p.hit.albedo * INV_PI * e
                    }
                    _ => Rgb::ZERO,
                };
            }
        });
    img
}
