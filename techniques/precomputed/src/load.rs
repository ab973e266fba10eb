//! Loading (§4.2: the paper pre-loads everything): the `.illumepc` file checked against
//! the scene, the camera and the image size its domain allows, and read into the PCA
//! groups the run time reconstructs from ([`crate::reconstruct`]).

use crate::PrecomputedError;
use crate::atlas::Atlas;
use crate::file::{FileError, PcFile};
use crate::lookup::Lookup;
use crate::precompute::SKY_DIRECT;
use crate::reconstruct::Group;
use crate::settings::PrecomputedSettings;
use crate::state::Precomputed;
use illume_core::Rgb;
use illume_scene::sun::SunSettings;
use illume_transport::World;
use std::path::{Path, PathBuf};

/// Gives `scene` the `[sun]` of the file `settings.data` when it has none of its own (a
/// scene file such as Sponza's carries no sun: the precompute attached one, and the run
/// time needs the same sun for the direct light). Returns whether it attached one.
pub fn attach_file_sun(
    scene: &mut illume_scene::Scene,
    settings: &PrecomputedSettings,
) -> Result<bool, PrecomputedError> {
    if scene.sun.is_some() || settings.data.is_empty() {
        return Ok(false);
    }
    let path = PathBuf::from(&settings.data);
    let header = PcFile::read_header(&path)?;
    let sun: SunSettings = header
        .sun
        .clone()
        .try_into()
        .map_err(|e: toml::de::Error| {
            PrecomputedError::File(FileError::Mismatch {
                path: path.clone(),
                what: "[sun] table".into(),
                expected: "a valid [sun]".into(),
                found: e.to_string(),
            })
        })?;
    scene.attach_sun(sun)?;
    Ok(true)
}

impl Precomputed {
    /// Loads `path` for `world`: checks the file, the static scene, and per domain:
    /// `screen` the camera and the image size `width × height`; `cube` the camera's
    /// position (it may turn, and any image size samples the faces); `atlas` that the
    /// scene gives the file's lightmap layout (any camera and size).
    pub fn load(
        world: &World,
        settings: PrecomputedSettings,
        path: &Path,
        width: u32,
        height: u32,
    ) -> Result<Self, PrecomputedError> {
        let start = std::time::Instant::now();
        let file = PcFile::read(path)?;
        Self::from_file(world, settings, path, file, width, height, start)
    }

    /// As [`Precomputed::load`], from a file already in memory (`path` only for errors).
    pub fn from_file(
        world: &World,
        settings: PrecomputedSettings,
        path: &Path,
        file: PcFile,
        width: u32,
        height: u32,
        start: std::time::Instant,
    ) -> Result<Self, PrecomputedError> {
        settings.validate()?;
        let h = &file.header;
        let mismatch =
            |what: &str, expected: String, found: String| mismatch(path, what, expected, found);
        if h.kind != "pca" {
            return Err(mismatch("file kind", "pca".into(), h.kind.clone()));
        }
        file.check_scene(path, &world.scene)?;
        let lookup = lookup_for(world, &file, path, width, height)?;
        let (width, height) = (h.width, h.height);
        let sun: SunSettings = h.sun.clone().try_into().map_err(|e: toml::de::Error| {
            mismatch("[sun] table", "a valid [sun]".into(), e.to_string())
        })?;
        // The renderer's direct light follows the scene's sun: it must be the keys'.
        if let Some(path) = &world.scene.sun
            && path.settings != sun
        {
            return Err(mismatch(
                "[sun] (the scene's sun must be the one the keys were rendered with)",
                format!("{:?}", path.settings),
                format!("{sun:?}"),
            ));
        }
        let joint = h.colour == "joint";
        let names: &[&str] = if joint { &["rgb"] } else { &["r", "g", "b"] };
        let pixels = width as usize * height as usize;
        let rows = if joint { 3 * pixels } else { pixels };
        let k = h.components as usize;
        let groups = read_groups(&file, path, names, rows)?;
        let sky = sky_section(&file, path, "sky", pixels)?
            .ok_or_else(|| mismatch("section sky", "present".into(), "missing".into()))?;
        let sky_direct = sky_section(&file, path, SKY_DIRECT, pixels)?;
        // The direct share is part of the sky's light (both come from the same samples):
        // more than the whole would leave the split frame's indirect image negative.
        if let Some(direct) = &sky_direct
            && let Some(i) = direct
                .iter()
                .zip(&sky)
                .position(|(d, a)| (*d - *a * (1.0 + 1e-5)).max_element() > 1e-12)
        {
            return Err(PrecomputedError::File(FileError::Invalid {
                path: path.to_path_buf(),
                field: format!("section {SKY_DIRECT} texel {i}"),
                value: format!("{:?}", direct[i]),
                reason: format!(
                    "the sky's direct share exceeds the sky's whole light there ({:?})",
                    sky[i]
                ),
            }));
        }
        if sky_direct.is_none() && sky.iter().any(|p| p.max_element() > 0.0) {
            log::warn!("{}", old_sky_warning(path));
        }
        Ok(Self {
            settings,
            file: path.to_path_buf(),
            sun,
            times: h.keys.iter().map(|k| k.hours).collect(),
            k,
            groups,
            joint,
            sky,
            sky_direct,
            share: None,
            share_wanted: false,
            width,
            height,
            lookup,
            cache: None,
            runs: Vec::new(),
            pair: None,
            load_s: start.elapsed().as_secs_f64(),
            last_ms: 0.0,
            stale: 0,
            pending: false,
        })
    }
}

/// How the file's texels reach the pixels, after checking per domain what the file
/// allows: `screen` the camera and the image size `width × height`; `cube` the camera's
/// position; `atlas` that the scene gives the file's lightmap layout.
fn lookup_for(
    world: &World,
    file: &PcFile,
    path: &Path,
    width: u32,
    height: u32,
) -> Result<Lookup, PrecomputedError> {
    let h = &file.header;
    let mismatch =
        |what: &str, expected: String, found: String| mismatch(path, what, expected, found);
    let camera = &world.scene.camera;
    let mut cam: Vec<f32> = camera.world_from_camera.to_cols_array().to_vec();
    cam.push(camera.yfov_rad);
    Ok(match h.domain.as_str() {
        "screen" => {
            if (h.width, h.height) != (width, height) {
                return Err(mismatch(
                    "image size (a screen file holds one image of its size)",
                    format!("{width}×{height}"),
                    format!("{}×{}", h.width, h.height),
                ));
            }
            if cam != h.camera {
                return Err(mismatch(
                    "camera (a screen file needs its fixed camera)",
                    format!("{cam:?}"),
                    format!("{:?}", h.camera),
                ));
            }
            Lookup::Screen
        }
        "cube" => {
            let position = camera.world_from_camera.translation;
            let stored = h.camera.get(9..12).unwrap_or(&[]);
            let tolerance = 1e-4 * (1.0 + position.abs().max_element());
            let same =
                stored.len() == 3 && (0..3).all(|i| (stored[i] - position[i]).abs() <= tolerance);
            if !same || h.height != 6 * h.width {
                return Err(mismatch(
                    "camera position (a cube file lets the camera turn, not move)",
                    format!("{:?}", position.to_array()),
                    format!("{stored:?}"),
                ));
            }
            Lookup::Cube {
                face: h.width,
                position: position.into(),
            }
        }
        "atlas" => {
            let info = h
                .atlas
                .as_ref()
                .ok_or_else(|| mismatch("[atlas] table", "present".into(), "missing".into()))?;
            let atlas = Atlas::build(&world.scene, info.density, info.probe_spacing)?;
            let checksum = format!("{:016x}", atlas.checksum());
            if checksum != info.layout_checksum
                || [atlas.width, atlas.height] != info.lightmap
                || atlas.image_size() != (h.width, h.height)
            {
                return Err(mismatch(
                    "atlas layout (the scene's lightmap coordinates; made by another version?)",
                    format!("{}×{} {checksum}", atlas.width, atlas.height),
                    format!(
                        "{}×{} {}",
                        info.lightmap[0], info.lightmap[1], info.layout_checksum
                    ),
                ));
            }
            let static_world = world.with_scene(crate::precompute::static_scene(&world.scene));
            let valid = crate::domain::probe_flags(&static_world, &atlas);
            Lookup::Atlas {
                atlas: Box::new(atlas),
                valid,
            }
        }
        other => {
            return Err(mismatch(
                "domain",
                "screen, cube or atlas".into(),
                other.into(),
            ));
        }
    })
}

/// The PCA groups `names` (`rgb` joint, or `r`, `g`, `b`) of `file`, each image
/// `rows` values, their section lengths checked.
fn read_groups(
    file: &PcFile,
    path: &Path,
    names: &[&str],
    rows: usize,
) -> Result<Vec<Group>, PrecomputedError> {
    let h = &file.header;
    let mismatch =
        |what: &str, expected: String, found: String| mismatch(path, what, expected, found);
    let keys = h.keys.len();
    let k = h.components as usize;
    let mut groups = Vec::new();
    for name in names {
        let get = |what: &str, len: usize| -> Result<Vec<f32>, PrecomputedError> {
            let section = file.section(&format!("{what}.{name}")).ok_or_else(|| {
                mismatch(
                    &format!("section {what}.{name}"),
                    "present".into(),
                    "missing".into(),
                )
            })?;
            if section.values.len() != len {
                return Err(mismatch(
                    &format!("length of section {what}.{name}"),
                    len.to_string(),
                    section.values.len().to_string(),
                ));
            }
            Ok(section.values.clone())
        };
        let bright = h.keys.iter().any(|k| !k.dark);
        groups.push(Group {
            mean: get("mean", keys)?,
            temporal: get("temporal", k * keys)?,
            images: get("images", if bright { k * rows } else { 0 })?,
            rows,
        });
    }
    Ok(groups)
}

/// The warning for a file whose sky light has no direct share (section [`SKY_DIRECT`],
/// stored since the split): a split frame (`illume render --split`) then holds all of
/// it in its indirect image.
pub fn old_sky_warning(path: &Path) -> String {
    format!(
        "precomputed: {} has no section {SKY_DIRECT} (written before the sky's direct light \
         was stored): its sky light is all in the indirect image (render --split puts it in \
         _indirect, none in _direct); precompute the file again to split it as the reference does",
        path.display()
    )
}

/// Section `name` of `file` as `pixels` sky radiances (None when the file has no such
/// section): its length checked, every value finite (the reader's check) and ≥ 0.
fn sky_section(
    file: &PcFile,
    path: &Path,
    name: &str,
    pixels: usize,
) -> Result<Option<Vec<Rgb>>, PrecomputedError> {
    let Some(section) = file.section(name) else {
        return Ok(None);
    };
    let values = &section.values;
    if values.len() != 3 * pixels {
        return Err(mismatch(
            path,
            &format!("length of section {name}"),
            (3 * pixels).to_string(),
            values.len().to_string(),
        ));
    }
    // The sky image is radiance: a negative value would light the scene negatively.
    if let Some(i) = values.iter().position(|v| *v < 0.0) {
        return Err(PrecomputedError::File(FileError::Invalid {
            path: path.to_path_buf(),
            field: format!("section {name} value {i}"),
            value: values[i].to_string(),
            reason: "sky radiance must be ≥ 0".into(),
        }));
    }
    Ok(Some(
        values
            .chunks_exact(3)
            .map(|c| Rgb::new(c[0], c[1], c[2]))
            .collect(),
    ))
}

/// The error for a file that does not match what the run time needs.
fn mismatch(path: &Path, what: &str, expected: String, found: String) -> PrecomputedError {
    PrecomputedError::File(FileError::Mismatch {
        path: path.to_path_buf(),
        what: what.into(),
        expected,
        found,
    })
}
