//! Rendering the keys and the sky image, and compressing them into a file
//! (Bahnsen et al. §3.1 "Tips and tricks", §3.2).
//!
//! A key is the reference path tracer's indirect image (light reflected ≥ 2 times) of the
//! sun alone at the key's time: the paper subtracted direct-only renders from GI renders,
//! and the `indirect` image of
//! [`ReferenceRenderer::images`](illume_reference::ReferenceRenderer::images) is that
//! difference without the noise of a subtraction. The precompute works on a private copy
//! of the scene:
//! - dynamic instances are masked out (like the paper's teapot, they neither block nor
//!   bleed indirect light);
//! - the sky is off for keys, and the sun off for the one sky image;
//! - a key whose sun is at or below the horizon is exactly black, flagged dark, not
//!   rendered and kept out of the PCA;
//! - every key uses the same samples per texel (common random numbers,
//!   [`key_seed`]), and is denoised ([`illume_render::denoise`]) unless `denoise = "none"`: any
//!   machine renders the same key.

use crate::PrecomputedError;
use crate::domain::{Layout, Part};
use crate::file::{AtlasInfo, Header, KeyInfo, PcFile, Section, SectionFormat, scene_fingerprint};
use crate::pca::{self, Components, Precision};
use crate::schedule::KeyTime;
use crate::settings::{Colour, PrecomputedSettings};
use illume_core::image::RgbImage;
use illume_core::sampling::mix64;
use illume_scene::sun::SunSettings;
use illume_scene::{LightKind, Scene};
use illume_transport::World;

/// One rendered (or dark) key.
#[derive(Clone, Debug)]
pub struct Key {
    /// When.
    pub time: KeyTime,
    /// Sun at or below the horizon: black, not rendered.
    pub dark: bool,
    /// The indirect image (all zero when dark).
    pub image: RgbImage,
}

/// The scene's sun table, or an error naming the scene.
pub fn sun_of(scene: &Scene) -> Result<SunSettings, PrecomputedError> {
    scene
        .sun
        .as_ref()
        .map(|s| s.settings.clone())
        .ok_or_else(|| PrecomputedError::NoSun(scene.source.clone()))
}

/// The precompute's private scene: dynamic instances masked out.
pub fn static_scene(scene: &Scene) -> Scene {
    let mut s = scene.clone();
    for inst in s.instances.iter_mut().filter(|i| i.dynamic) {
        inst.mask = 0;
    }
    s
}

/// Samples' seed of the key at `hours`: one seed for every key with `common_samples`
/// (common random numbers: texel p's sample s follows the same path in every key, only
/// the sun differs), else one from (seed, time).
pub fn key_seed(settings: &PrecomputedSettings, hours: f64) -> u64 {
    if settings.common_samples {
        mix64(settings.seed ^ 0x6b65_7973)
    } else {
        mix64(settings.seed ^ mix64(hours.to_bits()))
    }
}

/// Renders the key at clock time `time.hours` (sun only, sky off, dynamic masked) in
/// the domain `settings` ask for, for images of `size` pixels ([`Layout::new`]).
pub fn render_key(
    world: &World,
    settings: &PrecomputedSettings,
    time: KeyTime,
    size: (u32, u32),
) -> Result<Key, PrecomputedError> {
    let layout = Layout::new(world, settings, size)?;
    render_key_in(world, settings, time, &layout)
}

/// As [`render_key`], in a layout made once for many keys.
pub fn render_key_in(
    world: &World,
    settings: &PrecomputedSettings,
    time: KeyTime,
    layout: &Layout,
) -> Result<Key, PrecomputedError> {
    let sun = sun_of(&world.scene)?;
    let state = illume_scene::sun::evaluate(&sun, sun.scene_time(time.hours))?;
    let size = layout.image_size();
    if state.position.elevation_deg <= 0.0 {
        return Ok(Key {
            time,
            dark: true,
            image: RgbImage::filled(size.0, size.1, illume_core::Rgb::ZERO),
        });
    }
    let mut scene = static_scene(&world.scene);
    if let Some(path) = scene.sun.as_mut() {
        path.sky_base = None;
    }
    scene.sky = None;
    scene.set_time(sun.scene_time(time.hours));
    let image = layout.render(
        &world.with_scene(scene),
        settings.spp,
        key_seed(settings, time.hours),
        true,
        settings.denoise,
    );
    Ok(Key {
        time,
        dark: false,
        image,
    })
}

/// The sky's images at sky scale 1, in the layout of the keys.
#[derive(Clone, Debug, PartialEq)]
pub struct Sky {
    /// All the sky's reflected light, direct and indirect (section `sky`).
    pub all: RgbImage,
    /// Its direct share, light reflected once (section [`SKY_DIRECT`]); None for files
    /// written before it was stored: their sky light is all indirect in a split frame.
    pub direct: Option<RgbImage>,
}

/// The name of the sky's direct share's section.
pub const SKY_DIRECT: &str = "sky.direct";

impl From<RgbImage> for Sky {
    /// A sky image without its direct share (as in files written before it was stored).
    fn from(all: RgbImage) -> Self {
        Self { all, direct: None }
    }
}

impl Sky {
    /// Its file sections: `sky`, then [`SKY_DIRECT`] when there is one.
    pub fn sections(&self) -> Vec<Section> {
        let section = |name: &str, image: &RgbImage| Section {
            name: name.into(),
            format: SectionFormat::F32,
            values: image.pixels().iter().flat_map(|p| p.to_array()).collect(),
        };
        let mut out = vec![section("sky", &self.all)];
        out.extend(self.direct.as_ref().map(|d| section(SKY_DIRECT, d)));
        out
    }
}

/// Renders the sky's whole light (direct and indirect, Bahnsen et al. §2 "the skylight
/// … precomputed … which we scale") at sky scale 1, sun off, dynamic instances masked,
/// emission off (the renderer adds emission): at run time it is multiplied by s(t) and
/// the renderer skips its own sky term ([`illume_transport::Technique::supplies_sky_light`]).
/// Its direct share (light reflected once) comes from the same paths, at no extra
/// tracing: at run time the renderer files it under a frame's direct light
/// ([`illume_transport::Technique::direct_share`]), as the reference splits light.
pub fn render_sky(
    world: &World,
    settings: &PrecomputedSettings,
    size: (u32, u32),
) -> Result<Sky, PrecomputedError> {
    render_sky_in(world, settings, &Layout::new(world, settings, size)?)
}

/// As [`render_sky`], in a layout made once.
pub fn render_sky_in(
    world: &World,
    settings: &PrecomputedSettings,
    layout: &Layout,
) -> Result<Sky, PrecomputedError> {
    let size = layout.image_size();
    let mut scene = static_scene(&world.scene);
    let path = scene
        .sun
        .take()
        .ok_or_else(|| PrecomputedError::NoSun(scene.source.clone()))?;
    scene.sky = path.sky_base.clone();
    if let Some(light) = scene.lights.get_mut(path.light.index()) {
        light.kind = LightKind::Directional {
            irradiance: illume_core::Rgb::ZERO,
        };
    }
    for m in scene.materials.iter_mut() {
        m.emission = illume_core::Rgb::ZERO;
        m.emissive_texture = None;
    }
    if scene.sky.is_none() {
        let black = RgbImage::filled(size.0, size.1, illume_core::Rgb::ZERO);
        return Ok(Sky {
            all: black.clone(),
            direct: Some(black),
        });
    }
    let mut images = layout.render_parts(
        &world.with_scene(scene),
        settings.spp,
        mix64(settings.seed ^ 0x0073_6b79),
        &[Part::All, Part::Direct],
        crate::settings::Denoise::None,
    );
    let direct = images.pop();
    let all = images.pop().expect("two parts");
    Ok(Sky { all, direct })
}

/// The settings a sky image depends on besides the scene, its sky and the camera: the
/// layout's and the sampling's. The hours, the schedule, the PCA and the run-time
/// settings do not enter it (the sky is rendered with the sun off).
const SKY_SETTINGS: [&str; 6] = [
    "domain",
    "cube_face",
    "atlas_density",
    "probe_spacing",
    "spp",
    "seed",
];

/// The sky images stored in `file` (read from `path`), for a precompute of `world` with
/// `settings` in `layout` (`illume precompute --sky-from`). The sky image does not depend
/// on the hours, the schedule or the PCA, so a file of the same scene and sky, image
/// size, layout, samples and seed holds, bit for bit, the image this precompute would
/// spend about 1.3 keys' time rendering (Sponza's atlas at 512 spp). Anything of those
/// that differs is an error naming the file and each difference. Lights other than the
/// sun are not in the scene's fingerprint, so they are not checked (nor between shards).
pub fn sky_from_file(
    world: &World,
    settings: &PrecomputedSettings,
    layout: &Layout,
    path: &std::path::Path,
    file: &PcFile,
) -> Result<Sky, PrecomputedError> {
    let ours = base_header_in(world, settings, layout)?;
    let theirs = &file.header;
    let mut differs = Vec::new();
    if ours.scene_fingerprint != theirs.scene_fingerprint {
        differs.push("the scene or its sky".to_owned());
    }
    if (ours.width, ours.height) != (theirs.width, theirs.height) {
        differs.push(format!(
            "the image size ({}×{} here, {}×{} in the file)",
            ours.width, ours.height, theirs.width, theirs.height
        ));
    }
    // The screen and cube domains see from the camera; the atlas does not.
    if ours.domain != "atlas" && ours.camera != theirs.camera {
        differs.push("the camera".to_owned());
    }
    if ours.atlas != theirs.atlas && differs.is_empty() {
        differs.push("the atlas layout".to_owned());
    }
    for name in SKY_SETTINGS {
        let (a, b) = (ours.settings.get(name), theirs.settings.get(name));
        if a != b {
            let show = |v: Option<&toml::Value>| v.map_or("unset".into(), |v| v.to_string());
            differs.push(format!(
                "{name} ({} here, {} in the file)",
                show(a),
                show(b)
            ));
        }
    }
    if !differs.is_empty() {
        return Err(crate::shard::unusable(
            path,
            format!(
                "its sky image cannot serve this precompute: {} differ{}",
                differs.join(", "),
                if differs.len() == 1 { "s" } else { "" }
            ),
        ));
    }
    crate::shard::sky_of(path, file)
}

/// Runs `render` (the sky's images) as a phase of its own in `progress`: one image for
/// the whole day, but at the keys' samples it takes as long as two keys or so (Sponza's
/// atlas at 512 spp: ≈ 12 min), and without a phase the log said nothing until the keys
/// began.
pub(crate) fn with_sky_progress<T>(
    progress: &mut dyn illume_core::Progress,
    render: impl FnOnce() -> T,
) -> T {
    progress.begin("precomputed sky (once for the day)", 1);
    let out = render();
    progress.set(1);
    progress.end();
    out
}

/// The 8-bit sRGB encoding (clamped, no tone curve) of an image at `exposure` (for the Yee metric).
pub fn to_srgb8(image: &RgbImage, exposure: f32) -> Vec<u8> {
    illume_core::image::to_srgb8(
        image,
        &illume_core::image::ToneMap {
            exposure_ev: exposure.max(1e-30).log2(),
            curve: illume_core::image::ToneCurve::Clamp,
        },
    )
}

/// The header of a file for `world` with `settings` at `size`: everything but the keys
/// and the PCA results.
pub fn base_header(
    world: &World,
    settings: &PrecomputedSettings,
    size: (u32, u32),
) -> Result<Header, PrecomputedError> {
    base_header_in(world, settings, &Layout::new(world, settings, size)?)
}

/// As [`base_header`], for a layout made once.
pub fn base_header_in(
    world: &World,
    settings: &PrecomputedSettings,
    layout: &Layout,
) -> Result<Header, PrecomputedError> {
    let size = layout.image_size();
    let sun = sun_of(&world.scene)?;
    let (_, fingerprint) = scene_fingerprint(&world.scene);
    let camera = &world.scene.camera;
    let mut cam: Vec<f32> = camera.world_from_camera.to_cols_array().to_vec();
    cam.push(camera.yfov_rad);
    let table = |v: &dyn erased::Ser| v.table();
    // The data path is where a file is read from, not how it was made.
    let mut settings_table = table(settings);
    settings_table.remove("data");
    Ok(Header {
        kind: "pca".into(),
        scene_source: world.scene.source.clone(),
        scene_fingerprint: fingerprint,
        settings: settings_table,
        sun: table(&sun),
        domain: layout.name().into(),
        atlas: match layout {
            Layout::Atlas(a) => Some(AtlasInfo {
                lightmap: [a.width, a.height],
                density: a.density,
                probe_spacing: a.probes.spacing,
                probe_dims: a.probes.dims,
                layout_checksum: format!("{:016x}", a.checksum()),
            }),
            _ => None,
        },
        width: size.0,
        height: size.1,
        channels: 3,
        camera: cam,
        exposure: settings.exposure,
        shard: [0, 1],
        keys: Vec::new(),
        components: 0,
        colour: match settings.colour {
            Colour::PerChannel => "per-channel".into(),
            Colour::Joint => "joint".into(),
        },
        eigenvalues: Vec::new(),
        sections: Vec::new(),
    })
}

/// Runs the PCA over the non-dark keys and assembles the file from `base`
/// ([`base_header`]). `keys` sorted by time.
pub fn compress(
    base: Header,
    settings: &PrecomputedSettings,
    keys: &[Key],
    sky: &Sky,
) -> Result<PcFile, PrecomputedError> {
    let bright: Vec<usize> = (0..keys.len()).filter(|&i| !keys[i].dark).collect();
    let channel =
        |key: &Key, c: usize| -> Vec<f32> { key.image.pixels().iter().map(|p| p[c]).collect() };
    let components = match settings.variance_target {
        Some(target) => Components::VarianceTarget {
            target,
            max: settings.components,
        },
        None => Components::Fixed(settings.components),
    };
    // Half floats where asked and where every value fits (|v| ≤ 65 504): a brighter
    // section stays f32 rather than turn into infinities.
    let image_format = |name: &str, values: &[f32]| {
        let fits = values.iter().all(|v| v.abs() <= f32::from(half::f16::MAX));
        match (settings.half_floats, fits) {
            (true, true) => SectionFormat::F16,
            (true, false) => {
                log::warn!("precomputed: section {name} exceeds half floats' range: kept as f32");
                SectionFormat::F32
            }
            _ => SectionFormat::F32,
        }
    };
    let mut sections = Vec::new();
    let mut eigenvalues = Vec::new();
    let mut k_kept = 0;
    // Fits of the channel groups: per channel (r, g, b) or one joint fit.
    let groups: Vec<(String, Vec<Vec<f32>>)> = match settings.colour {
        Colour::PerChannel => ["r", "g", "b"]
            .iter()
            .enumerate()
            .map(|(c, name)| {
                (
                    name.to_string(),
                    bright.iter().map(|&i| channel(&keys[i], c)).collect(),
                )
            })
            .collect(),
        Colour::Joint => vec![(
            "rgb".to_string(),
            bright
                .iter()
                .map(|&i| {
                    keys[i]
                        .image
                        .pixels()
                        .iter()
                        .flat_map(|p| p.to_array())
                        .collect()
                })
                .collect(),
        )],
    };
    for (name, data) in groups {
        let (mean, temporal_bright, images, k, eig) = if data.is_empty() {
            (Vec::new(), Vec::new(), Vec::new(), 0, Vec::new())
        } else {
            let refs: Vec<&[f32]> = data.iter().map(Vec::as_slice).collect();
            let basis = pca::fit(&refs, components, Precision::F32)?;
            let k = basis.components();
            (
                basis.mean,
                basis.temporal,
                basis.images,
                k,
                basis.eigenvalues,
            )
        };
        k_kept = k;
        // Spread over all keys: dark keys get mean 0 and coefficients 0 (exactly black).
        let t_all = keys.len();
        let mut mean_all = vec![0f32; t_all];
        let mut temporal_all = vec![0f32; k * t_all];
        for (j, &i) in bright.iter().enumerate() {
            mean_all[i] = mean[j];
            for c in 0..k {
                temporal_all[c * t_all + i] = temporal_bright[c * bright.len() + j];
            }
        }
        sections.push(Section {
            name: format!("mean.{name}"),
            format: SectionFormat::F32,
            values: mean_all,
        });
        sections.push(Section {
            name: format!("temporal.{name}"),
            format: SectionFormat::F32,
            values: temporal_all,
        });
        sections.push(Section {
            name: format!("images.{name}"),
            format: image_format(&format!("images.{name}"), &images),
            values: images,
        });
        eigenvalues.push(eig);
    }
    sections.extend(sky.sections().into_iter().map(|s| Section {
        format: image_format(&s.name, &s.values),
        ..s
    }));
    Ok(PcFile {
        header: Header {
            kind: "pca".into(),
            shard: [0, 1],
            keys: keys
                .iter()
                .map(|k| KeyInfo {
                    hours: k.time.hours,
                    level: k.time.level,
                    dark: k.dark,
                })
                .collect(),
            components: k_kept as u32,
            eigenvalues,
            sections: Vec::new(),
            ..base
        },
        sections,
    })
}

mod erased {
    /// Serialises plain settings to a TOML table (empty if they cannot be).
    pub trait Ser {
        fn table(&self) -> toml::Table;
    }
    impl<T: serde::Serialize> Ser for T {
        fn table(&self) -> toml::Table {
            toml::Table::try_from(self).unwrap_or_default()
        }
    }
}

/// Whether two key images differ visibly (Yee & Newman at the file's exposure, pdiff's
/// defaults): the adaptive schedule's test.
pub fn differs_visibly(a: &RgbImage, b: &RgbImage, exposure: f32) -> bool {
    let (w, h) = (a.width(), a.height());
    illume_metrics::yee_diff(
        w,
        h,
        &to_srgb8(a, exposure),
        &to_srgb8(b, exposure),
        &illume_metrics::YeeSettings::default(),
    )
    .is_ok_and(|r| r.visible)
}

/// The adaptive schedule's daylight floor for `sun`: whether the interval between clock
/// times `a` and `b` is longer than [`crate::schedule::MAX_DAYLIGHT_GAP_H`] with the sun
/// above the horizon at some minute inside it.
pub fn daylight_floor(sun: &SunSettings) -> impl Fn(f64, f64) -> bool + '_ {
    move |a, b| {
        if b - a <= crate::schedule::MAX_DAYLIGHT_GAP_H {
            return false;
        }
        let minutes = ((b - a) * 60.0).ceil().min(1e6) as u32;
        (0..=minutes).any(|m| {
            let hours = (a + m as f64 / 60.0).min(b);
            illume_scene::sun::solar_position(sun, hours).is_ok_and(|p| p.elevation_deg > 0.0)
        })
    }
}

/// `(1 − α)·a + α·b`, pixel by pixel (same sizes): the adaptive schedule's interpolation.
pub fn lerp(a: &RgbImage, b: &RgbImage, alpha: f32) -> RgbImage {
    let px = a
        .pixels()
        .iter()
        .zip(b.pixels())
        .map(|(x, y)| *x * (1.0 - alpha) + *y * alpha)
        .collect();
    RgbImage::from_vec(a.width(), a.height(), px).expect("same size")
}

/// The whole precompute in one process: the sky image, the keys (uniform or adaptive),
/// the PCA. `progress` counts keys (adaptive: one bar per level, counting that level's
/// keys).
pub fn precompute(
    world: &World,
    settings: &PrecomputedSettings,
    size: (u32, u32),
    progress: &mut dyn illume_core::Progress,
) -> Result<PcFile, PrecomputedError> {
    precompute_with_sky(world, settings, size, None, progress)
}

/// [`precompute`], with the sky images taken from another file (path and contents;
/// checked by [`sky_from_file`]) instead of rendered, when `sky_from` is given.
pub fn precompute_with_sky(
    world: &World,
    settings: &PrecomputedSettings,
    size: (u32, u32),
    sky_from: Option<(&std::path::Path, &PcFile)>,
    progress: &mut dyn illume_core::Progress,
) -> Result<PcFile, PrecomputedError> {
    settings.validate()?;
    sun_of(&world.scene)?;
    let layout = Layout::new(world, settings, size)?;
    let (w, h) = layout.image_size();
    crate::file::check_keys_memory(crate::file::most_keys(settings), w, h).map_err(|reason| {
        PrecomputedError::InvalidSetting {
            field: "step_min",
            reason,
        }
    })?;
    let sky = match sky_from {
        Some((path, file)) => sky_from_file(world, settings, &layout, path, file)?,
        None => with_sky_progress(progress, || render_sky_in(world, settings, &layout))?,
    };
    let keys = match settings.schedule {
        crate::settings::ScheduleKind::Uniform => {
            let times = crate::schedule::uniform(settings.from_h, settings.to_h, settings.step_min);
            progress.begin("precomputed keys", times.len() as u64);
            let mut keys = Vec::with_capacity(times.len());
            for (i, t) in times.into_iter().enumerate() {
                keys.push(render_key_in(world, settings, t, &layout)?);
                progress.set(i as u64 + 1);
            }
            progress.end();
            keys
        }
        crate::settings::ScheduleKind::Adaptive => {
            if let Some(warning) = crate::schedule::small_image_warning(w, h) {
                log::warn!("{warning}");
            }
            let criterion = if settings.verify_midpoint {
                crate::schedule::Criterion::VerifyMidpoint
            } else {
                crate::schedule::Criterion::Ends
            };
            let sun = sun_of(&world.scene)?;
            // Level by level: each level's bar counts the keys that level renders.
            let (mut done, mut level) = (0u64, 0u32);
            let exposure = settings.exposure;
            let keys = crate::schedule::adaptive(
                settings.from_h,
                settings.to_h,
                settings.step_min,
                criterion,
                daylight_floor(&sun),
                |times| {
                    progress.begin(
                        &format!(
                            "precomputed keys, adaptive level {level} ({done} rendered before)"
                        ),
                        times.len() as u64,
                    );
                    let mut out = Vec::with_capacity(times.len());
                    for (i, &hours) in times.iter().enumerate() {
                        let key =
                            render_key_in(world, settings, KeyTime { hours, level: 0 }, &layout)?;
                        out.push(key.image);
                        progress.set(i as u64 + 1);
                    }
                    progress.end();
                    done += times.len() as u64;
                    level += 1;
                    Ok::<_, PrecomputedError>(out)
                },
                |a, b| differs_visibly(a, b, exposure),
                lerp,
            )?;
            keys.into_iter()
                .map(|(time, image)| {
                    let dark = illume_scene::sun::solar_position(&sun, time.hours)
                        .map(|p| p.elevation_deg <= 0.0)
                        .unwrap_or(true);
                    Key { time, dark, image }
                })
                .collect()
        }
    };
    compress(
        base_header_in(world, settings, &layout)?,
        settings,
        &keys,
        &sky,
    )
}
