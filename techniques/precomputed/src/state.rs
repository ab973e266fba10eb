//! The technique at run time (Bahnsen et al. §3.1, Eq. 2, §4.2): [`Precomputed`] and its
//! `impl Technique`. Everything is loaded at construction (the paper pre-loads,
//! [`crate::load`]); each frame interpolates the k temporal coefficients and the mean
//! between the two keys around the clock time, reconstructs every pixel in O(k), clamps
//! at 0 and adds the sky image (its direct and indirect light) scaled by s(t)
//! ([`crate::reconstruct`]), reading the file's texels per domain ([`crate::lookup`]).
//! Scene changes are in [`crate::update`].

use crate::PrecomputedError;
use crate::lookup::Lookup;
use crate::reconstruct::Group;
use crate::settings::PrecomputedSettings;
use illume_core::image::RgbImage;
use illume_core::{Counters, Rgb};
use illume_scene::SceneChange;
use illume_scene::sun::SunSettings;
use illume_transport::{Budget, ChangeResponse, GBuffer, Technique, World};
use std::path::PathBuf;

pub use crate::load::attach_file_sun;

/// The loaded `precomputed` technique.
pub struct Precomputed {
    pub(crate) settings: PrecomputedSettings,
    pub(crate) file: PathBuf,
    pub(crate) sun: SunSettings,
    pub(crate) times: Vec<f64>,
    pub(crate) k: usize,
    pub(crate) groups: Vec<Group>,
    pub(crate) joint: bool,
    pub(crate) sky: Vec<Rgb>,
    /// The sky image's direct share (light reflected once), per texel; None for a file
    /// written before it was stored.
    pub(crate) sky_direct: Option<Vec<Rgb>>,
    /// The direct share of the last [`Technique::indirect`] image, until the renderer
    /// takes it ([`Technique::direct_share`]).
    pub(crate) share: Option<RgbImage>,
    /// Whether the renderer asks for the share ([`Technique::want_direct_share`]): the
    /// share's lookup is skipped when not (frames shown whole).
    pub(crate) share_wanted: bool,
    /// The key image's size (screen: the image's; cube: face × 6·face; atlas: lightmap
    /// and probe rows).
    pub(crate) width: u32,
    pub(crate) height: u32,
    pub(crate) lookup: Lookup,
    /// Reconstructed texels of `atlas` and the (hours, sky scale) they are for.
    pub(crate) cache: Option<((f64, f32), crate::lookup::AtlasTexels)>,
    /// `cube`: the texels reconstructed this frame (runs the pixels read).
    pub(crate) runs: Vec<Rgb>,
    /// Linear interpolation: the key pair (N, N+1) around the last frame's time and their
    /// reconstructed images (sun only, clamped at 0).
    pub(crate) pair: Option<(usize, usize, Vec<Rgb>, Vec<Rgb>)>,
    pub(crate) load_s: f64,
    pub(crate) last_ms: f64,
    pub(crate) stale: u64,
    /// No file yet: [`Technique::precompute`] makes one in memory.
    pub(crate) pending: bool,
}

impl Precomputed {
    /// The technique for the engine: loads `settings.data` if set, else precomputes in
    /// memory at [`Technique::precompute`] (for tests and tiny scenes).
    pub fn new(
        world: &World,
        settings: PrecomputedSettings,
        width: u32,
        height: u32,
    ) -> Result<Self, PrecomputedError> {
        settings.validate()?;
        if !settings.data.is_empty() {
            let path = PathBuf::from(&settings.data);
            return Self::load(world, settings, &path, width, height);
        }
        crate::precompute::sun_of(&world.scene)?;
        Ok(Self {
            file: PathBuf::from("(precomputed in memory)"),
            sun: crate::precompute::sun_of(&world.scene)?,
            settings,
            times: Vec::new(),
            k: 0,
            groups: Vec::new(),
            joint: false,
            sky: Vec::new(),
            sky_direct: None,
            share: None,
            share_wanted: false,
            width,
            height,
            lookup: Lookup::Screen,
            cache: None,
            runs: Vec::new(),
            pair: None,
            load_s: 0.0,
            last_ms: 0.0,
            stale: 0,
            pending: true,
        })
    }

    /// Seconds the load took (reported as `load_s`).
    pub fn load_seconds(&self) -> f64 {
        self.load_s
    }
}

impl Technique for Precomputed {
    fn name(&self) -> &'static str {
        crate::NAME
    }

    /// See [`crate::update`].
    fn scene_changed(&mut self, world: &World, changes: &[SceneChange]) -> ChangeResponse {
        self.on_changes(world, changes)
    }

    fn precompute(
        &mut self,
        world: &World,
        progress: &mut dyn illume_core::Progress,
    ) -> Result<(), illume_transport::TechniqueError> {
        if !self.pending {
            return Ok(());
        }
        let start = std::time::Instant::now();
        let size = (self.width, self.height);
        let file = crate::precompute::precompute(world, &self.settings, size, progress)?;
        let path = self.file.clone();
        *self = Self::from_file(
            world,
            self.settings.clone(),
            &path,
            file,
            size.0,
            size.1,
            start,
        )?;
        Ok(())
    }

    fn advance(&mut self, _world: &World, _budget: &Budget) {}

    fn indirect(&mut self, world: &World, gbuffer: &GBuffer) -> RgbImage {
        self.share = None;
        if self.pending || self.times.is_empty() {
            let n = gbuffer.width as usize * gbuffer.height as usize;
            return RgbImage::from_vec(gbuffer.width, gbuffer.height, vec![Rgb::ZERO; n])
                .expect("one value per pixel");
        }
        let start = std::time::Instant::now();
        let hours = self.sun.clock_hours(world.scene.time);
        let elevation = illume_scene::sun::solar_position(&self.sun, hours)
            .map(|p| p.elevation_deg)
            .unwrap_or(-90.0);
        let sky_scale = illume_scene::sun::sky_scale(elevation);
        let (out, share) = self.pixels(hours, sky_scale, gbuffer);
        self.share = share.and_then(|s| RgbImage::from_vec(gbuffer.width, gbuffer.height, s));
        self.last_ms = start.elapsed().as_secs_f64() * 1e3;
        RgbImage::from_vec(gbuffer.width, gbuffer.height, out).expect("one value per pixel")
    }

    fn stats(&self) -> Counters {
        let mut c = Counters::new();
        c.set("keys", self.times.len() as f64);
        c.set("components", self.k as f64);
        c.set("load_s", self.load_s);
        c.set("indirect_ms", self.last_ms);
        c.set("stale", self.stale as f64);
        c
    }

    fn reset(&mut self) {}

    /// Always: the indirect light is reconstructed from the file as a function of the
    /// scene time and the G-buffer alone, and nothing accumulates between frames.
    fn settled(&self) -> bool {
        true
    }

    /// Shadow maps for the sun, as in the paper's demo.
    fn interactive(&self) -> bool {
        true
    }

    /// The precomputed sky image holds the sky's direct light too (Eq. 2's s(t)·L_sky).
    fn supplies_sky_light(&self) -> bool {
        true
    }

    /// The sky's direct light in the last image (the file's `sky.direct` image at the
    /// frame's sky scale, through the domain's lookup): a split frame then holds the
    /// sky's light reflected once in its direct image, as the reference's does. None for
    /// a file written before that image was stored (warned at load), at night and before
    /// the precompute.
    fn direct_share(&mut self) -> Option<RgbImage> {
        self.share.take()
    }

    fn want_direct_share(&mut self, wanted: bool) {
        self.share_wanted = wanted;
    }
}
