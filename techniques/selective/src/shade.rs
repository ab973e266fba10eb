//! Display of the element solution (§6): indirect radiance per G-buffer pixel.
//!
//! L = A(x)/π · E(x), E interpolated from the display vertices of the pixel's element
//! ([`Elements::irradiance`]), A the pixel's directional albedo towards the camera
//! ([`GBufferPixel::display_albedo`](illume_transport::GBufferPixel::display_albedo):
//! its albedo ρ on a Lambertian surface, textures at full resolution; on a glossy one
//! what the BRDF reflects of light arriving uniformly — beyond the paper, which shows
//! ρ/π · E everywhere, as `directional_albedo = false` does; issue 34 goal 4).

use crate::elements::{Display, Elements};
use illume_core::image::RgbImage;
use illume_core::{INV_PI, Rgb};
use illume_transport::{GBuffer, World};
use rayon::prelude::*;

/// Indirect radiance of every pixel of `gbuffer` from `display`; `directional`: glossy
/// receivers by their directional albedo (`SelectiveSettings::directional_albedo`).
pub fn shade(
    world: &World,
    gbuffer: &GBuffer,
    elements: &Elements,
    display: &Display,
    directional: bool,
) -> RgbImage {
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
                        p.display_albedo(directional) * INV_PI * e
                    }
                    _ => Rgb::ZERO,
                };
            }
        });
    img
}
