//! The G-buffer: the primary hit of every pixel, which direct lighting and every
//! technique's indirect light shade.

use crate::camera::CameraRays;
use crate::surface::SurfaceHit;
use crate::world::World;
use illume_core::{Vec2, Vec3};
use rayon::prelude::*;

/// What a pixel sees.
#[derive(Clone, Copy, Debug)]
pub struct GBufferPixel {
    /// The primary hit (position, normals, albedo, instance, depth `t`).
    pub hit: SurfaceHit,
    /// Unit direction from the hit towards the camera.
    pub to_camera: Vec3,
}

/// Primary hits of a `width × height` image (row-major, row 0 at the top); `None` where
/// the pixel sees nothing.
#[derive(Clone, Debug)]
pub struct GBuffer {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// One entry per pixel.
    pub pixels: Vec<Option<GBufferPixel>>,
}

impl GBuffer {
    /// Traces one primary ray per pixel through `offset` within the pixel (0.5, 0.5 =
    /// centre), in parallel. This is the reference for primary visibility;
    /// [`GBuffer::rasterize`] gives the same hits far cheaper but only at the pixel centre
    /// (offset 0.5, 0.5), so sub-pixel jitter needs this path.
    pub fn render(world: &World, width: u32, height: u32, offset: Vec2) -> Self {
        let cam = CameraRays::new(&world.scene.camera, width, height);
        let pixels = (0..width * height)
            .into_par_iter()
            .with_min_len(64)
            .map(|i| {
                let ray = cam.ray(i % width, i / width, offset);
                world
                    .trace(&ray, illume_scene::MASK_DEFAULT)
                    .map(|hit| GBufferPixel {
                        hit,
                        to_camera: -ray.dir,
                    })
            })
            .collect();
        Self {
            width,
            height,
            pixels,
        }
    }

    /// The entry of pixel (x, y).
    pub fn get(&self, x: u32, y: u32) -> Option<&GBufferPixel> {
        self.pixels[(y * self.width + x) as usize].as_ref()
    }
}
