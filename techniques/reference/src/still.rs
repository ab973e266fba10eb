//! The reference's own route to a still (`illume render --technique reference`): the
//! whole image by path tracing, and the same denoised (`--denoise`).

use crate::{ReferenceRenderer, ReferenceSettings, SplitImages};
use illume_core::Progress;
use illume_scene::Scene;
use illume_transport::{StillImages, TechniqueError, World};

/// The whole image by path tracing ([`ReferenceRenderer`], `spp` samples per pixel,
/// progress per chunk of samples).
pub(crate) fn still(
    scene: Scene,
    settings: &ReferenceSettings,
    size: (u32, u32),
    progress: &mut dyn Progress,
) -> Result<StillImages, TechniqueError> {
    let (_, all) = path_traced(&World::new(scene), settings, size, false, progress);
    Ok(images(all))
}

/// [`still`] denoised (issue 36, goal 6: `illume render --technique reference
/// --denoise`): `settings.spp` samples in two halves (the first half's mean gives the
/// variance), then the direct and the indirect image each filtered by
/// [`illume_render::denoise::atrous`] under the camera's guide; `full` is their sum, so a
/// split still sums to it.
///
/// Never ground truth: the bench, the agreement harness and the tests take their
/// references from [`still`] (the filter blurs what noise hides: a reference that is
/// filtered cannot show a technique's blur). Only `render --denoise` reaches this.
pub(crate) fn denoised_still(
    scene: Scene,
    settings: &ReferenceSettings,
    (width, height): (u32, u32),
    progress: &mut dyn Progress,
) -> Result<StillImages, TechniqueError> {
    use illume_render::denoise::{Guide, atrous};
    let world = World::new(scene);
    let (half, all) = path_traced(&world, settings, (width, height), true, progress);
    let guide = Guide::camera(&world, width, height, 0);
    let direct = atrous(&all.direct, half.as_ref().map(|h| &h.direct), &guide);
    let indirect = atrous(&all.indirect, half.as_ref().map(|h| &h.indirect), &guide);
    Ok(StillImages {
        full: direct.add(&indirect),
        direct,
        indirect,
    })
}

/// `settings.spp` samples per pixel in chunks (the image does not depend on the
/// chunking; chunks keep the bar moving and the work parallel over pixels); with
/// `halves`, also the images after the first half of them (at least 2 samples).
fn path_traced(
    world: &World,
    settings: &ReferenceSettings,
    (width, height): (u32, u32),
    halves: bool,
    progress: &mut dyn Progress,
) -> (Option<SplitImages>, SplitImages) {
    let mut r = ReferenceRenderer::new(settings.clone(), width, height);
    let spp = settings.spp;
    progress.begin("path tracing", u64::from(spp));
    let chunk = (spp / 32).max(1);
    let mut run_to = |r: &mut ReferenceRenderer, to: u32| {
        while r.samples() < to {
            r.add_samples(world, chunk.min(to - r.samples()));
            progress.set(u64::from(r.samples()));
        }
    };
    let half = (halves && spp >= 2).then(|| {
        run_to(&mut r, spp / 2);
        r.images()
    });
    run_to(&mut r, spp);
    progress.end();
    (half, r.images())
}

fn images(i: SplitImages) -> StillImages {
    StillImages {
        full: i.full,
        direct: i.direct,
        indirect: i.indirect,
    }
}
