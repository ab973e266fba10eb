//! Sharding the precompute over machines (`--shard K/N`) and merging the shards
//! (`illume precompute merge`).
//!
//! Shard K of N renders the keys whose index (in the schedule's order) is K mod N into a
//! `partial` file: the header lists every key of the schedule with its dark flag, the
//! sections hold this shard's raw key images (`key.INDEX`, f32 RGB) and, in shard 0, the
//! sky image. Keys are seeded from (seed, time) and the PCA sums its blocks in a fixed
//! order, so the merge of N shards equals the unsharded file bit for bit.
//!
//! Sharding covers the uniform schedule; the adaptive one runs level by level in one
//! process for now (each level's keys could shard the same way: not done yet).

use crate::PrecomputedError;
use crate::file::{FileError, PcFile, Section, SectionFormat};
use crate::precompute::{Key, base_header, compress, render_key, render_sky, sun_of};
use crate::schedule::KeyTime;
use crate::settings::{PrecomputedSettings, ScheduleKind};
use illume_core::Rgb;
use illume_core::image::RgbImage;
use illume_transport::World;
use std::path::PathBuf;

/// `K/N`: this is shard K (0-based) of N.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Shard {
    /// Which (0 ≤ index < count).
    pub index: u32,
    /// How many.
    pub count: u32,
}

impl std::str::FromStr for Shard {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, String> {
        let bad = || format!("--shard {s:?}: expected K/N with 0 ≤ K < N, e.g. 0/3");
        let (k, n) = s.split_once('/').ok_or_else(bad)?;
        let index: u32 = k.trim().parse().map_err(|_| bad())?;
        let count: u32 = n.trim().parse().map_err(|_| bad())?;
        if count == 0 || index >= count {
            return Err(bad());
        }
        Ok(Self { index, count })
    }
}

impl Shard {
    /// Whether item `i` belongs to this shard.
    pub fn owns(&self, i: usize) -> bool {
        i % self.count as usize == self.index as usize
    }
}

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
            reason: "--shard needs the uniform schedule for now (adaptive levels do not shard yet)"
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
        .map(|t| {
            let dark = illume_scene::sun::solar_position(&sun, t.hours)
                .map(|p| p.elevation_deg <= 0.0)
                .unwrap_or(true);
            crate::file::KeyInfo {
                hours: t.hours,
                level: t.level,
                dark,
            }
        })
        .collect();
    if shard.index == 0 {
        let sky = render_sky(world, settings, size)?;
        sections.push(Section {
            name: "sky".into(),
            format: SectionFormat::F32,
            values: sky.pixels().iter().flat_map(|p| p.to_array()).collect(),
        });
    }
    Ok(PcFile { header, sections })
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

/// Checks that `parts` are the N shards of one precompute and runs the PCA over them.
pub fn merge(parts: &[(PathBuf, PcFile)]) -> Result<PcFile, PrecomputedError> {
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
        let mut a = h.clone();
        let mut b = first.header.clone();
        a.shard = [0, 0];
        b.shard = [0, 0];
        a.sections.clear();
        b.sections.clear();
        if a != b {
            let field = [
                ("scene", a.scene_fingerprint != b.scene_fingerprint),
                ("settings", a.settings != b.settings),
                ("sun", a.sun != b.sun),
                ("image size", (a.width, a.height) != (b.width, b.height)),
                ("camera", a.camera != b.camera),
                ("keys", a.keys != b.keys),
            ]
            .iter()
            .find(|(_, differs)| *differs)
            .map_or("header", |(name, _)| name);
            return Err(disagree(
                path,
                format!("its {field} differs from {}'s", first_path.display()),
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
    let header = &first.header;
    let size = (header.width, header.height);
    let settings: PrecomputedSettings = header
        .settings
        .clone()
        .try_into()
        .map_err(|e: toml::de::Error| disagree(first_path, format!("settings: {e}")))?;
    let mut keys = Vec::with_capacity(header.keys.len());
    for (i, info) in header.keys.iter().enumerate() {
        let time = KeyTime {
            hours: info.hours,
            level: info.level,
        };
        if info.dark {
            keys.push(Key {
                time,
                dark: true,
                image: RgbImage::filled(size.0, size.1, Rgb::ZERO),
            });
            continue;
        }
        let owner = &parts[parts
            .iter()
            .position(|(_, p)| p.header.shard[0] as usize == i % count as usize)
            .unwrap_or(0)];
        let section = owner
            .1
            .section(&format!("key.{i}"))
            .ok_or_else(|| disagree(&owner.0, format!("key {i} ({} h) is missing", info.hours)))?;
        let image = image(&section.values, size).ok_or_else(|| {
            disagree(
                &owner.0,
                format!("key {i} has {} values", section.values.len()),
            )
        })?;
        keys.push(Key {
            time,
            dark: false,
            image,
        });
    }
    let sky_owner = &parts[parts
        .iter()
        .position(|(_, p)| p.header.shard[0] == 0)
        .unwrap_or(0)];
    let sky = sky_owner
        .1
        .section("sky")
        .and_then(|s| image(&s.values, size))
        .ok_or_else(|| disagree(&sky_owner.0, "shard 0 has no sky image".into()))?;
    let mut base = header.clone();
    base.sections.clear();
    compress(base, &settings, &keys, &sky)
}
