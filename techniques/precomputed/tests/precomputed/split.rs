//! A split still (`illume render --split`) with precomputed: the sky's light reflected
//! once sits in the direct image, as the reference path tracer splits light (issue 36
//! goal 5), through the file's `sky.direct` section and
//! [`Technique::direct_share`](illume_transport::Technique::direct_share); a file
//! without that section (written before it) still renders, its sky light all indirect,
//! with a warning naming it.
//!
//! The case: `builtin:sun-room` at 06:30 on its 21 June, the sun up (the sky scale is
//! s ≈ 0.14) but north of east, so that none of its light enters the south window: only
//! the sky lights the room, and every pixel's direct light is the sky's.

use crate::common::SIZE;
use illume_core::image::RgbImage;
use illume_engine::{Config, TechniqueKind, render_still};
use illume_precomputed::file::PcFile;
use illume_precomputed::precompute::{SKY_DIRECT, precompute};
use illume_precomputed::settings::{PrecomputedSettings, ScheduleKind};
use illume_scene::Scene;
use std::path::{Path, PathBuf};
use std::sync::Mutex;

/// The clock time of the case.
const HOURS: f64 = 6.5;

/// Warnings logged by this process (the precomputed technique warns through `log`).
static WARNINGS: Mutex<Vec<String>> = Mutex::new(Vec::new());

struct Capture;

impl log::Log for Capture {
    fn enabled(&self, m: &log::Metadata) -> bool {
        m.level() <= log::Level::Warn
    }
    fn log(&self, r: &log::Record) {
        if self.enabled(r.metadata()) {
            let mut w = WARNINGS.lock().unwrap_or_else(|e| e.into_inner());
            w.push(r.args().to_string());
        }
    }
    fn flush(&self) {}
}

static CAPTURE: Capture = Capture;

/// Keys 06:00–07:00 every 30 min (the sun's own light never enters: black keys).
fn settings() -> PrecomputedSettings {
    PrecomputedSettings {
        schedule: ScheduleKind::Uniform,
        from_h: 6.0,
        to_h: 7.0,
        step_min: 30.0,
        spp: 256,
        components: 3,
        ..Default::default()
    }
}

/// `builtin:sun-room` at [`HOURS`], its dynamic box masked (precomputed light ignores
/// it; the reference must too, for a like comparison).
fn scene() -> Scene {
    let mut scene = illume_scene::builtin::load("sun-room").unwrap();
    for i in scene.instances.iter_mut().filter(|i| i.dynamic) {
        i.mask = 0;
    }
    let sun = scene.sun.as_ref().unwrap().settings.clone();
    scene.set_time(sun.scene_time(HOURS));
    scene
}

/// A still at [`SIZE`]: (full, direct, indirect).
fn still(config: Config) -> (RgbImage, RgbImage, RgbImage) {
    let mut config = config;
    config.render.width = SIZE.0;
    config.render.height = SIZE.1;
    // Shadow rays: `auto` picks maps or rays from measured times, frame by frame.
    config.render.shadows = illume_render::ShadowMode::Rays;
    let s = render_still(scene(), &config, &mut illume_core::Silent).unwrap();
    (s.full, s.direct, s.indirect)
}

/// precomputed's still with the file at `path`.
fn precomputed_still(path: &Path) -> (RgbImage, RgbImage, RgbImage) {
    let config = Config {
        technique: TechniqueKind::Precomputed,
        ..Default::default()
    };
    let data = format!("precomputed.data={:?}", path.to_str().unwrap());
    still(config.with_set(&data).unwrap())
}

/// The reference's still at `spp` samples, seed `seed`.
fn reference_still(spp: u32, seed: u64) -> (RgbImage, RgbImage, RgbImage) {
    let config = Config {
        technique: TechniqueKind::Reference,
        ..Default::default()
    };
    let config = config
        .with_set(&format!("reference.spp={spp}"))
        .unwrap()
        .with_set(&format!("reference.seed={seed}"))
        .unwrap();
    still(config)
}

/// Mean over pixels and channels.
fn mean(img: &RgbImage) -> f64 {
    let s: f64 = img
        .pixels()
        .iter()
        .map(|p| (p.x + p.y + p.z) as f64 / 3.0)
        .sum();
    s / img.pixels().len() as f64
}

/// A fresh folder for this test's files.
fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("illumepc-split-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

#[test]
fn split_puts_the_skys_direct_light_in_direct_as_the_reference_does() {
    let world = crate::common::world();
    let sun = world.scene.sun.as_ref().unwrap().settings.clone();
    let position = illume_scene::sun::solar_position(&sun, HOURS).unwrap();
    // The sun is up (the sky lights) and north of east (azimuth from north < 90°): its
    // light cannot pass the south window.
    assert!(position.elevation_deg > 3.0, "{position:?}");
    assert!(position.azimuth_deg < 80.0, "{position:?}");

    let file = precompute(&world, &settings(), SIZE, &mut illume_core::Silent).unwrap();
    assert!(
        file.section(SKY_DIRECT).is_some(),
        "a new file stores the sky's direct light"
    );
    let dir = scratch("new");
    let path = dir.join("day.illumepc");
    file.write(&path).unwrap();
    let (full, direct, indirect) = precomputed_still(&path);

    // (b) full = direct + indirect, pixel by pixel (to f32 rounding: the share moved from
    // one to the other after the sum was taken).
    for (i, ((f, d), n)) in full
        .pixels()
        .iter()
        .zip(direct.pixels())
        .zip(indirect.pixels())
        .enumerate()
    {
        let sum = *d + *n;
        assert!(
            (*f - sum).abs().max_element() <= 1e-6 * (1.0 + f.max_element()),
            "pixel {i}: full {f:?} ≠ direct {d:?} + indirect {n:?}"
        );
    }

    // (a) The means of direct and indirect against the reference's. Measured noise
    // (docs/benchmarks/precomputed.md, 2026-11-28): the reference at 1024 spp, seeds 1–4,
    // gave direct 0.0002418–0.0002419 and indirect 0.0002573 (16384 spp: 0.0002416,
    // 0.0002572); precomputed with its sky image at 256 spp, seeds 0–3, gave direct
    // 0.0002387–0.0002427 (−1.2 … +0.5 % of the 16384-spp mean) and indirect
    // 0.0002561–0.0002584 (−0.4 … +0.5 %). 5 % is four times the largest deviation;
    // today's code (no share) gives a direct mean of 0 — a 100 % miss.
    let (_, r_direct, r_indirect) = reference_still(1024, 1);
    let (md, mi) = (mean(&direct), mean(&indirect));
    let (rd, ri) = (mean(&r_direct), mean(&r_indirect));
    eprintln!(
        "direct mean: precomputed {md:.6}, reference {rd:.6}; indirect mean: precomputed \
         {mi:.6}, reference {ri:.6}"
    );
    assert!(
        rd > 1e-4 && ri > 1e-4,
        "the sky lights the room: {rd}, {ri}"
    );
    assert!(
        (md / rd - 1.0).abs() < 0.05,
        "direct means differ by more than 5 %: precomputed {md}, reference {rd}"
    );
    assert!(
        (mi / ri - 1.0).abs() < 0.05,
        "indirect means differ by more than 5 %: precomputed {mi}, reference {ri}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_file_without_the_skys_direct_light_renders_it_all_indirect_with_a_warning() {
    let _ = log::set_logger(&CAPTURE);
    log::set_max_level(log::LevelFilter::Warn);
    let world = crate::common::world();
    let s = PrecomputedSettings {
        spp: 16,
        ..settings()
    };
    let new = precompute(&world, &s, SIZE, &mut illume_core::Silent).unwrap();
    // The file as an older build wrote it: the same sections but sky.direct.
    let mut old = new.clone();
    old.sections.retain(|s| s.name != SKY_DIRECT);
    let dir = scratch("old");
    let (new_path, old_path) = (dir.join("new.illumepc"), dir.join("old.illumepc"));
    new.write(&new_path).unwrap();
    old.write(&old_path).unwrap();
    assert!(
        PcFile::read(&old_path)
            .unwrap()
            .section(SKY_DIRECT)
            .is_none()
    );

    let (new_full, new_direct, _) = precomputed_still(&new_path);
    let (old_full, old_direct, old_indirect) = precomputed_still(&old_path);
    // The same light in all, the sky's all indirect: direct has none of it (here, where
    // the sun does not enter, direct is black).
    assert_eq!(old_full, new_full, "full unchanged");
    assert!(mean(&new_direct) > 1e-4, "{}", mean(&new_direct));
    assert_eq!(
        mean(&old_direct),
        0.0,
        "an old file's sky light is all indirect"
    );
    assert_eq!(old_indirect, old_full);

    let name = old_path.display().to_string();
    let warnings = WARNINGS.lock().unwrap_or_else(|e| e.into_inner()).clone();
    let about_old: Vec<&String> = warnings.iter().filter(|w| w.contains(&name)).collect();
    assert!(
        !about_old.is_empty() && about_old[0].contains("_indirect"),
        "no warning naming {name}: {warnings:?}"
    );
    let new_name = new_path.display().to_string();
    assert!(
        !warnings.iter().any(|w| w.contains(&new_name)),
        "a new file is not warned about: {warnings:?}"
    );

    // A bad sky.direct is refused, naming the file, the section and the value.
    let load = |file: PcFile| {
        illume_precomputed::Precomputed::from_file(
            &world,
            s.clone(),
            &new_path,
            file,
            SIZE.0,
            SIZE.1,
            std::time::Instant::now(),
        )
        .err()
        .map(|e| e.to_string())
        .unwrap_or_default()
    };
    let mut negative = new.clone();
    let at = negative
        .sections
        .iter()
        .position(|s| s.name == SKY_DIRECT)
        .unwrap();
    negative.sections[at].values[7] = -1.0;
    let e = load(negative.clone());
    assert!(
        e.contains(&new_name) && e.contains("section sky.direct value 7") && e.contains("-1"),
        "{e}"
    );
    // A direct share above the sky's whole light would leave the indirect image negative.
    let mut above = new.clone();
    let sky_at = above.sections.iter().position(|s| s.name == "sky").unwrap();
    let i = above.sections[sky_at]
        .values
        .iter()
        .position(|v| *v > 0.0)
        .expect("a lit sky texel");
    above.sections[at].values[i] = 2.0 * above.sections[sky_at].values[i];
    let e = load(above);
    assert!(
        e.contains(&new_name)
            && e.contains(&format!("section sky.direct texel {}", i / 3))
            && e.contains("exceeds the sky's whole light"),
        "{e}"
    );
    negative.sections[at].values.pop();
    let e = load(negative);
    assert!(
        e.contains(&new_name) && e.contains("length of section sky.direct"),
        "{e}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}
