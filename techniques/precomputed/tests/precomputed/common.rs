//! Fixtures shared by the modules of this test binary: `builtin:sun-room` at the tests'
//! image size, its reference light, and 8×8 block means.

use illume_core::Rgb;
use illume_core::image::RgbImage;
use illume_reference::{ReferenceRenderer, ReferenceSettings};
use illume_scene::Scene;
use illume_transport::World;

/// The image size of every test here [pixels].
pub const SIZE: (u32, u32) = (32, 24);

/// `builtin:sun-room`.
pub fn world() -> World {
    World::new(illume_scene::builtin::load("sun-room").unwrap())
}

/// What the technique's indirect image holds for `scene` (seen in `world`'s BVHs): the
/// reference's indirect light (`spp` samples, `seeds.0`) plus the direct light of the
/// sky alone (the renderer skips it; `seeds.1`).
pub fn reference_with_sky_direct(
    world: &World,
    scene: Scene,
    spp: u32,
    seeds: (u64, u64),
) -> RgbImage {
    let r = render(world, scene.clone(), spp, seeds.0);
    r.images()
        .indirect
        .add(&sky_direct(world, scene, spp, seeds.1))
}

/// The reference's direct light of `scene`'s sky alone (`spp` samples, `seed`): what a
/// precomputed frame hands the renderer as its direct share.
pub fn sky_direct(world: &World, scene: Scene, spp: u32, seed: u64) -> RgbImage {
    let mut sky_only = scene;
    let sun_light = sky_only.sun.take().unwrap().light;
    sky_only.lights[sun_light.index()].kind = illume_scene::LightKind::Directional {
        irradiance: Rgb::ZERO,
    };
    render(world, sky_only, spp, seed).images().direct
}

/// The reference path tracer after `spp` samples of `scene` (seen in `world`'s BVHs).
fn render(world: &World, scene: Scene, spp: u32, seed: u64) -> ReferenceRenderer {
    let mut r = ReferenceRenderer::new(
        ReferenceSettings {
            spp,
            seed,
            ..Default::default()
        },
        SIZE.0,
        SIZE.1,
    );
    r.add_samples(&world.with_scene(scene), spp);
    r
}

/// Mean of each 8×8 block of a [`SIZE`] image (channel average), row by row.
pub fn blocks(img: &[Rgb]) -> Vec<f32> {
    let (w, h) = (SIZE.0 as usize, SIZE.1 as usize);
    let mut out = Vec::new();
    for by in 0..h / 8 {
        for bx in 0..w / 8 {
            let mut s = 0.0;
            for y in 0..8 {
                for x in 0..8 {
                    let p = img[(by * 8 + y) * w + bx * 8 + x];
                    s += (p.x + p.y + p.z) / 3.0;
                }
            }
            out.push(s / 64.0);
        }
    }
    out
}
