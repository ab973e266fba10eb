//! Sharding the precompute over machines (`--shard K/N`) and merging the shards
//! (`illume precompute merge`).
//!
//! Keys are seeded from (seed, time), the adaptive decisions are pure functions of the
//! images and the PCA sums its blocks in a fixed order, so every way of sharding below
//! gives the unsharded file bit for bit.
//!
//! # Uniform schedule
//! Shard K of N renders the keys whose index (in the schedule's order) is K mod N into a
//! `partial` file: the header lists every key of the schedule with its dark flag, the
//! sections hold this shard's raw key images (`key.INDEX`, f32 RGB) and, in shard 0, the
//! sky image. [`merge`] checks that the N shards agree and runs the PCA.
//!
//! # Adaptive schedule, level by level (`--level L`)
//! Level L's keys depend on the images of the levels before, so the schedule runs as one
//! round of shards and one merge per level ([`precompute_level`], [`merge_level`]):
//!
//! 1. level 0: shard K renders its share of the three first keys ([`adaptive_start`];
//!    shard 0 also the sky); the merge of the N shards writes a `levels` file;
//! 2. level L ≥ 1: every shard reads the `levels` file of levels < L (`--previous`),
//!    finds the middles level L renders ([`level_middles`]: with the paper's criterion
//!    each shard runs the same Yee tests on the interpolated middles, with
//!    `verify_midpoint` all tested middles are rendered) and renders middle j if
//!    j mod N = K. The merge (given the same `--previous`) gathers them, keeps the middles
//!    [`keeps_middle`] accepts and writes the `levels` file of levels ≤ L;
//! 3. the merge that finds the next level empty (no interval left to split) runs the PCA
//!    and writes the final `pca` file instead.
//!
//! A `levels` file is a `partial` file of all keys so far (raw f32 images of the non-dark
//! keys, `key.INDEX`, and the sky), `kind = "levels"`, shard `0/1`. It is as large as the
//! raw keys (800×600 f32 RGB: 5.8 MB a key). Its last level always added keys: a level
//! that adds none ends the schedule.

use crate::PrecomputedError;
use crate::file::{FileError, PcFile, Section, SectionFormat};
use crate::file::{Header, KeyInfo};
use crate::precompute::{
    Key, SKY_DIRECT, Sky, base_header, compress, daylight_floor, differs_visibly, lerp, render_key,
    render_sky, sun_of, with_sky_progress,
};
use crate::schedule::{Criterion, KeyTime, Middle, adaptive_start, keeps_middle, level_middles};
use crate::settings::{PrecomputedSettings, ScheduleKind};
use illume_core::Rgb;
use illume_core::image::RgbImage;
use illume_scene::sun::SunSettings;
use illume_transport::World;
use std::path::{Path, PathBuf};

pub use illume_core::Shard;

/// Renders shard `shard` of the uniform schedule into a `partial` file.
pub fn precompute_shard(
    world: &World,
    settings: &PrecomputedSettings,
    size: (u32, u32),
    shard: Shard,
    progress: &mut dyn illume_core::Progress,
) -> Result<PcFile, PrecomputedError> {
    settings.validate()?;
    if settings.schedule != ScheduleKind::Uniform {
        return Err(PrecomputedError::InvalidSetting {
            field: "schedule",
            reason: "the adaptive schedule shards level by level: give the level (--level L, \
                     precompute_level), 0 first, then each level with the merged file of the \
                     levels before"
                .into(),
        });
    }
    let sun = sun_of(&world.scene)?;
    let times = crate::schedule::uniform(settings.from_h, settings.to_h, settings.step_min);
    let mut header = base_header(world, settings, size)?;
    header.kind = "partial".into();
    header.shard = [shard.index, shard.count];
    let mut sections = Vec::new();
    let mine: Vec<usize> = (0..times.len()).filter(|&i| shard.owns(i)).collect();
    progress.begin("precomputed keys (shard)", mine.len() as u64);
    for (done, &i) in mine.iter().enumerate() {
        let key = render_key(world, settings, times[i], size)?;
        if !key.dark {
            sections.push(Section {
                name: format!("key.{i}"),
                format: SectionFormat::F32,
                values: key
                    .image
                    .pixels()
                    .iter()
                    .flat_map(|p| p.to_array())
                    .collect(),
            });
        }
        progress.set(done as u64 + 1);
    }
    progress.end();
    header.keys = times
        .iter()
        .map(|t| crate::file::KeyInfo {
            hours: t.hours,
            level: t.level,
            dark: is_dark(&sun, t.hours),
        })
        .collect();
    if shard.index == 0 {
        let sky = with_sky_progress(progress, || render_sky(world, settings, size))?;
        sections.extend(sky.sections());
    }
    Ok(PcFile { header, sections })
}

/// A file that cannot serve as what it was given for (`message` says why).
pub(crate) fn unusable(path: &Path, message: String) -> PrecomputedError {
    PrecomputedError::File(FileError::Header {
        path: path.to_path_buf(),
        message,
    })
}

fn disagree(path: &std::path::Path, message: String) -> PrecomputedError {
    PrecomputedError::File(FileError::Header {
        path: path.to_path_buf(),
        message: format!("shards disagree: {message}"),
    })
}

fn image(values: &[f32], size: (u32, u32)) -> Option<RgbImage> {
    let px: Vec<Rgb> = values
        .chunks_exact(3)
        .map(|c| Rgb::new(c[0], c[1], c[2]))
        .collect();
    RgbImage::from_vec(size.0, size.1, px)
}

/// Whether the sun is at or below the horizon at clock time `hours` (a dark key).
fn is_dark(sun: &SunSettings, hours: f64) -> bool {
    illume_scene::sun::solar_position(sun, hours)
        .map(|p| p.elevation_deg <= 0.0)
        .unwrap_or(true)
}

/// The header with the fields that differ between shards, levels and the final file
/// cleared: what all files of one precompute share.
fn shared_part(h: &Header) -> Header {
    Header {
        kind: String::new(),
        shard: [0, 0],
        keys: Vec::new(),
        components: 0,
        eigenvalues: Vec::new(),
        sections: Vec::new(),
        ..h.clone()
    }
}

/// `None` when `a` and `b` (called `names`) belong to one precompute (scene, settings,
/// sun, size, camera… agree); otherwise what differs, e.g. `settings (spp: 8 in A, 16 in
/// B)`.
fn difference(a: &Header, b: &Header, names: (&str, &str)) -> Option<String> {
    let (a, b) = (shared_part(a), shared_part(b));
    if a == b {
        return None;
    }
    if a.settings != b.settings {
        let mut fields: Vec<&String> = a.settings.keys().chain(b.settings.keys()).collect();
        fields.sort();
        fields.dedup();
        let shown: Vec<String> = fields
            .into_iter()
            .filter(|n| a.settings.get(*n) != b.settings.get(*n))
            .map(|n| {
                let show = |t: &toml::Table| t.get(n).map_or("unset".into(), |v| v.to_string());
                format!(
                    "{n}: {} in {}, {} in {}",
                    show(&a.settings),
                    names.0,
                    show(&b.settings),
                    names.1
                )
            })
            .collect();
        return Some(format!("settings ({})", shown.join("; ")));
    }
    let named = [
        ("scene", a.scene_fingerprint != b.scene_fingerprint),
        ("sun", a.sun != b.sun),
        ("image size", (a.width, a.height) != (b.width, b.height)),
        ("camera", a.camera != b.camera),
        ("domain", a.domain != b.domain),
        ("exposure", a.exposure != b.exposure),
    ];
    Some(
        named
            .iter()
            .find(|(_, differs)| *differs)
            .map_or("header", |(name, _)| name)
            .to_string(),
    )
}

/// Checks that `parts` are the N shards (each once) of one precompute step: `partial`
/// files, the same N, the same header and keys. Returns N.
fn check_shards(parts: &[(PathBuf, PcFile)]) -> Result<u32, PrecomputedError> {
    let Some((first_path, first)) = parts.first() else {
        return Err(PrecomputedError::InvalidSetting {
            field: "merge",
            reason: "no shard files given".into(),
        });
    };
    let count = first.header.shard[1];
    let mut seen = vec![None::<&PathBuf>; count as usize];
    for (path, part) in parts {
        let h = &part.header;
        if h.kind != "partial" {
            return Err(disagree(
                path,
                format!("kind is {:?}, not \"partial\"", h.kind),
            ));
        }
        if h.shard[1] != count {
            return Err(disagree(
                path,
                format!(
                    "it is shard {}/{}, {} is shard {}/{count}",
                    h.shard[0],
                    h.shard[1],
                    first_path.display(),
                    first.header.shard[0]
                ),
            ));
        }
        let names = (path.display().to_string(), first_path.display().to_string());
        if let Some(field) = difference(h, &first.header, (&names.0, &names.1)) {
            return Err(disagree(
                path,
                format!("its {field} differs from {}'s", first_path.display()),
            ));
        }
        if h.keys != first.header.keys {
            return Err(disagree(
                path,
                format!("its keys differ from {}'s", first_path.display()),
            ));
        }
        let slot = &mut seen[h.shard[0] as usize];
        if let Some(other) = slot {
            return Err(disagree(
                path,
                format!("shard {} also given as {}", h.shard[0], other.display()),
            ));
        }
        *slot = Some(path);
    }
    if let Some(missing) = seen.iter().position(Option::is_none) {
        return Err(disagree(
            first_path,
            format!("shard {missing}/{count} is missing"),
        ));
    }
    Ok(count)
}

/// The settings stored in a header.
fn settings_of(path: &Path, header: &Header) -> Result<PrecomputedSettings, PrecomputedError> {
    header
        .settings
        .clone()
        .try_into()
        .map_err(|e: toml::de::Error| {
            PrecomputedError::File(FileError::Header {
                path: path.to_path_buf(),
                message: format!("settings: {e}"),
            })
        })
}

/// The shard (among `parts`) that holds shard index `k`.
fn shard_file(parts: &[(PathBuf, PcFile)], k: u32) -> &(PathBuf, PcFile) {
    parts
        .iter()
        .find(|(_, p)| p.header.shard[0] == k)
        .unwrap_or(&parts[0])
}

/// The sky images of a file (shard 0 of level 0, a `levels` file), or an error naming
/// it. Its direct share is carried when the file has one (shards of an older build have
/// none: the merged file then has none either).
pub(crate) fn sky_of(path: &Path, file: &PcFile) -> Result<Sky, PrecomputedError> {
    let size = (file.header.width, file.header.height);
    let all = file
        .section("sky")
        .and_then(|s| image(&s.values, size))
        .ok_or_else(|| unusable(path, "it has no sky image (shard 0 renders it)".into()))?;
    let direct = match file.section(SKY_DIRECT) {
        None => None,
        Some(s) => Some(image(&s.values, size).ok_or_else(|| {
            unusable(
                path,
                format!(
                    "its section {SKY_DIRECT} holds {} values, not the {} of a {}×{} image",
                    s.values.len(),
                    3 * size.0 as u64 * size.1 as u64,
                    size.0,
                    size.1
                ),
            )
        })?),
    };
    Ok(Sky { all, direct })
}

/// Key `i` of `file`'s header as an image: its `key.i` section, or black when it has none
/// (a dark key: not rendered). A non-dark key without a section is an error.
fn key_image(path: &Path, file: &PcFile, i: usize) -> Result<RgbImage, PrecomputedError> {
    let h = &file.header;
    let size = (h.width, h.height);
    let info = &h.keys[i];
    match file.section(&format!("key.{i}")) {
        Some(section) => image(&section.values, size)
            .ok_or_else(|| unusable(path, format!("key {i} has {} values", section.values.len()))),
        None if info.dark => Ok(RgbImage::filled(size.0, size.1, Rgb::ZERO)),
        None => Err(unusable(
            path,
            format!("key {i} ({} h) is missing", info.hours),
        )),
    }
}

/// Checks that `parts` are the N shards of one uniform precompute (or of adaptive level 0)
/// and runs the PCA over them (level 0: see [`merge_level`]).
pub fn merge(parts: &[(PathBuf, PcFile)]) -> Result<PcFile, PrecomputedError> {
    merge_level(parts, None)
}

/// Merges the N shards of one step: a uniform precompute (then `previous` must be
/// `None`) or adaptive level L with `previous` = the `levels` file of levels < L (`None`
/// for level 0). Returns the final `pca` file when the schedule is complete, else the
/// `levels` file of levels ≤ L (adaptive).
pub fn merge_level(
    parts: &[(PathBuf, PcFile)],
    previous: Option<(&Path, &PcFile)>,
) -> Result<PcFile, PrecomputedError> {
    let count = check_shards(parts)?;
    let (first_path, first) = &parts[0];
    let settings = settings_of(first_path, &first.header)?;
    match (settings.schedule, previous) {
        (ScheduleKind::Uniform, None) => merge_uniform(parts, count, &settings),
        (ScheduleKind::Uniform, Some((path, _))) => Err(disagree(
            path,
            "given as the previous levels, but the shards are of the uniform schedule \
             (it has no levels)"
                .into(),
        )),
        (ScheduleKind::Adaptive, previous) => merge_adaptive(parts, count, &settings, previous),
    }
}

fn merge_uniform(
    parts: &[(PathBuf, PcFile)],
    count: u32,
    settings: &PrecomputedSettings,
) -> Result<PcFile, PrecomputedError> {
    let header = &parts[0].1.header;
    let size = (header.width, header.height);
    let mut keys = Vec::with_capacity(header.keys.len());
    for (i, info) in header.keys.iter().enumerate() {
        let time = KeyTime {
            hours: info.hours,
            level: info.level,
        };
        let image = if info.dark {
            RgbImage::filled(size.0, size.1, Rgb::ZERO)
        } else {
            let (path, owner) = shard_file(parts, (i % count as usize) as u32);
            key_image(path, owner, i)?
        };
        keys.push(Key {
            time,
            dark: info.dark,
            image,
        });
    }
    let (sky_path, sky_file) = shard_file(parts, 0);
    let sky = sky_of(sky_path, sky_file)?;
    compress(shared_part(header), settings, &keys, &sky)
}

/// The adaptive criterion of `settings`.
fn criterion(settings: &PrecomputedSettings) -> Criterion {
    if settings.verify_midpoint {
        Criterion::VerifyMidpoint
    } else {
        Criterion::Ends
    }
}

/// The keys of a `levels` file (checked against `like`, a header of the same
/// precompute, called `like_name` in errors) with their images, its sky and the level it
/// ends at.
#[expect(
    clippy::type_complexity,
    reason = "the three parts of a levels file, used together"
)]
fn read_levels(
    path: &Path,
    file: &PcFile,
    like: &Header,
    like_name: &str,
) -> Result<(Vec<(KeyTime, RgbImage)>, Sky, u32), PrecomputedError> {
    let h = &file.header;
    match h.kind.as_str() {
        "levels" => {}
        "pca" => {
            return Err(unusable(
                path,
                "given as the previous levels, but it is the final file (the adaptive \
                 schedule is complete): there is no next level"
                    .into(),
            ));
        }
        kind => {
            return Err(unusable(
                path,
                format!(
                    "given as the previous levels, but its kind is {kind:?}, not \"levels\" \
                     (merge the shards of the previous level first)"
                ),
            ));
        }
    }
    let name = path.display().to_string();
    if let Some(field) = difference(h, like, (&name, like_name)) {
        return Err(PrecomputedError::File(FileError::Header {
            path: path.to_path_buf(),
            message: format!(
                "given as the previous levels, but not of this precompute: its {field} differs"
            ),
        }));
    }
    let keys = (0..h.keys.len())
        .map(|i| {
            let info = &h.keys[i];
            let time = KeyTime {
                hours: info.hours,
                level: info.level,
            };
            Ok((time, key_image(path, file, i)?))
        })
        .collect::<Result<Vec<_>, PrecomputedError>>()?;
    let level = h.keys.iter().map(|k| k.level).max().unwrap_or(0);
    Ok((keys, sky_of(path, file)?, level))
}

fn merge_adaptive(
    parts: &[(PathBuf, PcFile)],
    count: u32,
    settings: &PrecomputedSettings,
    previous: Option<(&Path, &PcFile)>,
) -> Result<PcFile, PrecomputedError> {
    let (first_path, first) = &parts[0];
    let header = &first.header;
    let (mut keys, sky, level) = match previous {
        None => (Vec::new(), None, 0),
        Some((path, file)) => {
            let (keys, sky, last) =
                read_levels(path, file, header, &first_path.display().to_string())?;
            (keys, Some(sky), last + 1)
        }
    };
    // The shards' keys: the previous levels' (the same), then this level's middles.
    let before: Vec<KeyInfo> = header
        .keys
        .iter()
        .filter(|k| k.level < level)
        .cloned()
        .collect();
    let expected: Vec<KeyInfo> = match previous {
        Some((_, file)) => file.header.keys.clone(),
        None => Vec::new(),
    };
    if before != expected || header.keys.iter().any(|k| k.level > level) {
        let (what, path) = match previous {
            Some((p, _)) => (format!("level {level} after {}", p.display()), first_path),
            None => ("level 0 (no previous levels given)".into(), first_path),
        };
        return Err(disagree(
            path,
            format!("its keys are not those of {what}: shards of another level?"),
        ));
    }
    let sky = match sky {
        Some(sky) => sky,
        None => {
            let (sky_path, sky_file) = shard_file(parts, 0);
            sky_of(sky_path, sky_file)?
        }
    };
    let middles: Vec<usize> = (0..header.keys.len())
        .filter(|&i| header.keys[i].level == level)
        .collect();
    // A `levels` file is written only when the next level has middles to render, and
    // every shard finds the same ones: shards without any are of an earlier level.
    if middles.is_empty() {
        return Err(disagree(
            first_path,
            format!("it holds no key of level {level}: a shard of an earlier level?"),
        ));
    }
    let criterion = criterion(settings);
    let exposure = settings.exposure;
    let differs = |a: &RgbImage, b: &RgbImage| differs_visibly(a, b, exposure);
    let sun: SunSettings = sun_from(first_path, header)?;
    let forced = daylight_floor(&sun);
    let mut kept = Vec::new();
    for (j, &i) in middles.iter().enumerate() {
        let info = &header.keys[i];
        let (path, owner) = shard_file(parts, (j % count as usize) as u32);
        let image = key_image(path, owner, i)?;
        let time = KeyTime {
            hours: info.hours,
            level,
        };
        let keep = if level == 0 {
            true
        } else {
            // The interval this middle splits: its neighbours among the earlier keys.
            let after = keys.partition_point(|k| k.0.hours < info.hours);
            if after == 0 || after >= keys.len() {
                return Err(disagree(
                    path,
                    format!("key {i} ({} h) is outside the previous keys", info.hours),
                ));
            }
            let ends = (&keys[after - 1].1, &keys[after].1);
            let force = forced(keys[after - 1].0.hours, keys[after].0.hours);
            keeps_middle(criterion, force, ends, &image, differs, lerp)
        };
        if keep {
            kept.push((time, image));
        }
    }
    let added = !kept.is_empty();
    keys.extend(kept);
    keys.sort_by(|a, b| a.0.hours.total_cmp(&b.0.hours));
    let complete = !added
        || level_middles(
            &keys,
            level + 1,
            settings.step_min,
            criterion,
            &forced,
            differs,
            lerp,
        )
        .is_empty();
    let infos: Vec<KeyInfo> = keys
        .iter()
        .map(|(t, _)| KeyInfo {
            hours: t.hours,
            level: t.level,
            dark: is_dark(&sun, t.hours),
        })
        .collect();
    if complete {
        let keys: Vec<Key> = keys
            .into_iter()
            .zip(&infos)
            .map(|((time, image), info)| Key {
                time,
                dark: info.dark,
                image,
            })
            .collect();
        return compress(shared_part(header), settings, &keys, &sky);
    }
    Ok(levels_file(shared_part(header), &keys, infos, &sky))
}

/// The sun table of a header.
fn sun_from(path: &Path, header: &Header) -> Result<SunSettings, PrecomputedError> {
    header
        .sun
        .clone()
        .try_into()
        .map_err(|e: toml::de::Error| disagree(path, format!("sun: {e}")))
}

/// A `levels` file: `keys` (sorted) with their images (sections for the non-dark ones)
/// and the sky.
fn levels_file(
    base: Header,
    keys: &[(KeyTime, RgbImage)],
    infos: Vec<KeyInfo>,
    sky: &Sky,
) -> PcFile {
    let mut sections: Vec<Section> = keys
        .iter()
        .zip(&infos)
        .enumerate()
        .filter(|(_, (_, info))| !info.dark)
        .map(|(i, ((_, image), _))| key_section(i, image))
        .collect();
    sections.extend(sky.sections());
    PcFile {
        header: Header {
            kind: "levels".into(),
            shard: [0, 1],
            keys: infos,
            ..base
        },
        sections,
    }
}

fn key_section(i: usize, image: &RgbImage) -> Section {
    Section {
        name: format!("key.{i}"),
        format: SectionFormat::F32,
        values: image.pixels().iter().flat_map(|p| p.to_array()).collect(),
    }
}

/// Renders shard `shard` of adaptive level `level` into a `partial` file. Level 0 (the
/// three first keys, and the sky in shard 0) takes no `previous`; level L ≥ 1 takes the
/// `levels` file of levels < L (path, for errors, and contents), which must come from
/// the same scene and settings. Every shard tests the same middles
/// ([`level_middles`]) and renders middle j if j mod N = K.
pub fn precompute_level(
    world: &World,
    settings: &PrecomputedSettings,
    size: (u32, u32),
    level: u32,
    previous: Option<(&Path, &PcFile)>,
    shard: Shard,
    progress: &mut dyn illume_core::Progress,
) -> Result<PcFile, PrecomputedError> {
    settings.validate()?;
    let bad = |reason: String| PrecomputedError::InvalidSetting {
        field: "level",
        reason,
    };
    if settings.schedule != ScheduleKind::Adaptive {
        return Err(bad(
            "levels belong to the adaptive schedule; the uniform one shards with --shard K/N \
             alone"
                .into(),
        ));
    }
    let sun = sun_of(&world.scene)?;
    let mut header = base_header(world, settings, size)?;
    if level == 0
        && shard.index == 0
        && let Some(warning) = crate::schedule::small_image_warning(header.width, header.height)
    {
        log::warn!("{warning}");
    }
    header.kind = "partial".into();
    header.shard = [shard.index, shard.count];
    let mut sections = Vec::new();
    let (before, middles): (Vec<(KeyTime, RgbImage)>, Vec<Middle>) = match (level, previous) {
        (0, None) => {
            let start = adaptive_start(settings.from_h, settings.to_h);
            let middles = start
                .iter()
                .map(|k| Middle {
                    hours: k.hours,
                    ends: (0, 0),
                })
                .collect();
            (Vec::new(), middles)
        }
        (0, Some((path, _))) => {
            return Err(bad(format!(
                "level 0 starts the schedule: it takes no previous levels ({} given)",
                path.display()
            )));
        }
        (_, None) => {
            return Err(bad(format!(
                "level {level} needs the merged file of levels 0–{} (--previous FILE)",
                level - 1
            )));
        }
        (_, Some((path, file))) => {
            file.check_scene(path, &world.scene)?;
            let (keys, _, last) = read_levels(path, file, &header, "this run")?;
            if last + 1 != level {
                return Err(bad(format!(
                    "{} holds levels 0–{last}: the next level is {}, not {level}",
                    path.display(),
                    last + 1
                )));
            }
            let exposure = settings.exposure;
            let middles = level_middles(
                &keys,
                level,
                settings.step_min,
                criterion(settings),
                daylight_floor(&sun),
                |a, b| differs_visibly(a, b, exposure),
                lerp,
            );
            (keys, middles)
        }
    };
    let mine: Vec<usize> = (0..middles.len()).filter(|&j| shard.owns(j)).collect();
    progress.begin(
        &format!("precomputed keys (level {level}, shard {shard})"),
        mine.len() as u64,
    );
    let mut images = Vec::with_capacity(mine.len());
    for (done, &j) in mine.iter().enumerate() {
        let time = KeyTime {
            hours: middles[j].hours,
            level,
        };
        images.push((j, render_key(world, settings, time, size)?));
        progress.set(done as u64 + 1);
    }
    progress.end();
    let mut times: Vec<KeyTime> = before.iter().map(|k| k.0).collect();
    times.extend(middles.iter().map(|m| KeyTime {
        hours: m.hours,
        level,
    }));
    times.sort_by(|a, b| a.hours.total_cmp(&b.hours));
    for (j, key) in images {
        let i = times.partition_point(|t| t.hours < middles[j].hours);
        if !key.dark {
            sections.push(key_section(i, &key.image));
        }
    }
    sections.sort_by_key(|s| {
        s.name
            .strip_prefix("key.")
            .and_then(|n| n.parse::<usize>().ok())
    });
    header.keys = times
        .iter()
        .map(|t| KeyInfo {
            hours: t.hours,
            level: t.level,
            dark: is_dark(&sun, t.hours),
        })
        .collect();
    if level == 0 && shard.index == 0 {
        let sky = with_sky_progress(progress, || render_sky(world, settings, size))?;
        sections.extend(sky.sections());
    }
    Ok(PcFile { header, sections })
}
