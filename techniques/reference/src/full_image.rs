//! Full-image path tracing: every pixel's radiance from the camera, accumulated
//! progressively and split into direct and indirect light (the ground-truth images).

use crate::settings::ReferenceSettings;
use illume_core::Vec3;
use illume_core::image::RgbImage;
use illume_core::sampling::{Pcg32, SampleStream, mix64};
use illume_transport::path::radiance;
use illume_transport::{CameraRays, World};
use rayon::prelude::*;

/// The reference's output images (linear radiance).
#[derive(Clone, Debug)]
pub struct SplitImages {
    /// direct + indirect.
    pub full: RgbImage,
    /// Emission seen directly plus light reflected once.
    pub direct: RgbImage,
    /// Light reflected two or more times.
    pub indirect: RgbImage,
}

/// Progressive full-image path tracing: each call to [`ReferenceRenderer::add_samples`]
/// adds samples per pixel; the running mean is always available.
pub struct ReferenceRenderer {
    settings: ReferenceSettings,
    width: u32,
    height: u32,
    direct_sum: Vec<[f64; 3]>,
    indirect_sum: Vec<[f64; 3]>,
    samples: u32,
}

impl ReferenceRenderer {
    /// An empty accumulator for a `width × height` image \[pixels\].
    pub fn new(settings: ReferenceSettings, width: u32, height: u32) -> Self {
        let n = width as usize * height as usize;
        Self {
            settings,
            width,
            height,
            direct_sum: vec![[0.0; 3]; n],
            indirect_sum: vec![[0.0; 3]; n],
            samples: 0,
        }
    }

    /// Samples per pixel so far.
    pub fn samples(&self) -> u32 {
        self.samples
    }

    /// The settings.
    pub fn settings(&self) -> &ReferenceSettings {
        &self.settings
    }

    /// Image size \[pixels\].
    pub fn size(&self) -> (u32, u32) {
        (self.width, self.height)
    }

    /// Adds `spp` samples per pixel (in parallel over pixels).
    pub fn add_samples(&mut self, world: &World, spp: u32) {
        let (w, h) = (self.width, self.height);
        let cam = CameraRays::new(&world.scene.camera, w, h);
        let settings = &self.settings;
        let path = settings.path();
        let first = self.samples;
        self.direct_sum
            .par_iter_mut()
            .zip(self.indirect_sum.par_iter_mut())
            .enumerate()
            .with_min_len(16)
            .for_each(|(i, (d, ind))| {
                let (x, y) = (i as u32 % w, i as u32 / w);
                for s in first..first + spp {
                    let mut rng = Pcg32::new(mix64(settings.seed.wrapping_add(s as u64)), i as u64);
                    let ray = cam.ray(x, y, rng.next_2d());
                    let r = radiance(world, &ray, &mut rng, &path);
                    let direct = r.emitted + r.direct;
                    for c in 0..3 {
                        d[c] += direct[c] as f64;
                        ind[c] += r.indirect[c] as f64;
                    }
                }
            });
        self.samples += spp;
    }

    /// The running means.
    pub fn images(&self) -> SplitImages {
        let (w, h) = (self.width, self.height);
        let inv = 1.0 / self.samples.max(1) as f64;
        let to_img = |sum: &[[f64; 3]]| {
            RgbImage::from_vec(
                w,
                h,
                sum.iter()
                    .map(|s| {
                        Vec3::new(
                            (s[0] * inv) as f32,
                            (s[1] * inv) as f32,
                            (s[2] * inv) as f32,
                        )
                    })
                    .collect(),
            )
            .expect("one value per pixel")
        };
        let direct = to_img(&self.direct_sum);
        let indirect = to_img(&self.indirect_sum);
        let full = direct.add(&indirect);
        SplitImages {
            full,
            direct,
            indirect,
        }
    }

    /// Forgets all samples.
    pub fn reset(&mut self) {
        self.direct_sum.iter_mut().for_each(|v| *v = [0.0; 3]);
        self.indirect_sum.iter_mut().for_each(|v| *v = [0.0; 3]);
        self.samples = 0;
    }
}
