//! Three merged shards equal the unsharded file, bit for bit; shards that disagree are
//! refused with an error naming the file.

use illume_precomputed::file::PcFile;
use illume_precomputed::precompute::{SKY_DIRECT, precompute};
use illume_precomputed::settings::{PrecomputedSettings, ScheduleKind};
use illume_precomputed::shard::{Shard, merge, merge_level, precompute_level, precompute_shard};
use illume_transport::World;
use std::path::{Path, PathBuf};

const SIZE: (u32, u32) = (16, 12);

fn settings() -> PrecomputedSettings {
    PrecomputedSettings {
        schedule: ScheduleKind::Uniform,
        // 3:00–6:00 every 20 min: night keys (dark) and sunrise keys.
        from_h: 3.0,
        to_h: 6.0,
        step_min: 20.0,
        spp: 8,
        components: 4,
        ..Default::default()
    }
}

#[test]
fn three_merged_shards_equal_the_unsharded_file() {
    let world = World::new(illume_scene::builtin::load("sun-room").unwrap());
    let s = settings();
    let whole = precompute(&world, &s, SIZE, &mut illume_core::Silent).unwrap();
    assert!(whole.header.keys.iter().any(|k| k.dark) && whole.header.keys.iter().any(|k| !k.dark));
    let parts: Vec<(PathBuf, PcFile)> = (0..3)
        .map(|k| {
            let shard = Shard { index: k, count: 3 };
            let part = precompute_shard(&world, &s, SIZE, shard, &mut illume_core::Silent).unwrap();
            // Through bytes, as between machines.
            let path = PathBuf::from(format!("part{k}.illumepc"));
            (
                path.clone(),
                PcFile::from_bytes(&path, &part.to_bytes()).unwrap(),
            )
        })
        .collect();
    // Any order.
    let reordered = vec![parts[2].clone(), parts[0].clone(), parts[1].clone()];
    let merged = merge(&reordered).unwrap();
    assert!(
        merged.to_bytes() == whole.to_bytes(),
        "merged shards differ from the unsharded file"
    );
    assert!(
        merged.section(SKY_DIRECT).is_some(),
        "the sky's direct light survives the merge"
    );
    // Shards of an older build (no sky.direct in shard 0) merge into a file without it,
    // which the run time reads with its sky light all indirect.
    let mut old_zero = parts[0].clone();
    old_zero.1.sections.retain(|s| s.name != SKY_DIRECT);
    let old = merge(&[old_zero, parts[1].clone(), parts[2].clone()]).unwrap();
    let mut expected = whole.clone();
    expected.sections.retain(|s| s.name != SKY_DIRECT);
    assert!(
        old.to_bytes() == expected.to_bytes(),
        "old shards merge into the file without sky.direct"
    );

    // A missing shard, a duplicate, another seed.
    let e = merge(&parts[..2]).unwrap_err().to_string();
    assert!(e.contains("shard 2/3 is missing"), "{e}");
    let e = merge(&[parts[0].clone(), parts[0].clone(), parts[1].clone()])
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("part0.illumepc") && e.contains("also given"),
        "{e}"
    );
    let other = PrecomputedSettings {
        seed: 7,
        ..s.clone()
    };
    let odd = precompute_shard(
        &world,
        &other,
        SIZE,
        Shard { index: 2, count: 3 },
        &mut illume_core::Silent,
    )
    .unwrap();
    let e = merge(&[
        parts[0].clone(),
        parts[1].clone(),
        (PathBuf::from("odd.illumepc"), odd),
    ])
    .unwrap_err()
    .to_string();
    assert!(e.contains("odd.illumepc") && e.contains("settings"), "{e}");
}

#[test]
fn shard_spec_parses() {
    assert_eq!(
        "1/3".parse::<Shard>().unwrap(),
        Shard { index: 1, count: 3 }
    );
    assert!("3/3".parse::<Shard>().is_err());
    assert!("x".parse::<Shard>().is_err());
}

/// Short adaptive days on `sun-room` that split (Yee at exposure 64 sees the keys'
/// differences only from about 32 spp and, with the paper's criterion, ~100 pixels up):
/// the paper's criterion over 9:00–17:00 down to 2 h, `verify_midpoint` over 7:00–19:00
/// down to 3 h at a smaller size. Returns the settings and the image size.
fn adaptive_case(verify_midpoint: bool) -> (PrecomputedSettings, (u32, u32)) {
    let s = PrecomputedSettings {
        schedule: ScheduleKind::Adaptive,
        spp: 32,
        components: 3,
        exposure: 64.0,
        verify_midpoint,
        ..Default::default()
    };
    if verify_midpoint {
        let s = PrecomputedSettings {
            from_h: 7.0,
            to_h: 19.0,
            step_min: 90.0,
            ..s
        };
        (s, (64, 48))
    } else {
        let s = PrecomputedSettings {
            from_h: 9.0,
            to_h: 17.0,
            step_min: 60.0,
            ..s
        };
        (s, (96, 72))
    }
}

/// Through bytes, as between machines.
fn carried(path: &str, file: &PcFile) -> (PathBuf, PcFile) {
    let path = PathBuf::from(path);
    let file = PcFile::from_bytes(&path, &file.to_bytes()).unwrap();
    (path, file)
}

/// Runs the adaptive schedule level by level in `n` shards, merging after each level, as
/// `scripts/slurm/submit_precompute_adaptive.sh` does; returns the final file and the
/// `levels` file of each level before the last.
fn sharded_adaptive(
    world: &World,
    s: &PrecomputedSettings,
    size: (u32, u32),
    n: u32,
) -> (PcFile, Vec<PcFile>) {
    let mut previous: Option<(PathBuf, PcFile)> = None;
    let mut levels = Vec::new();
    for level in 0..10 {
        let prev = previous.as_ref().map(|(p, f)| (p.as_path(), f));
        let mut parts: Vec<(PathBuf, PcFile)> = (0..n)
            .map(|k| {
                let shard = Shard { index: k, count: n };
                let part =
                    precompute_level(world, s, size, level, prev, shard, &mut illume_core::Silent)
                        .unwrap();
                carried(&format!("l{level}_{k}.illumepc"), &part)
            })
            .collect();
        parts.reverse(); // any order
        let merged = merge_level(&parts, prev).unwrap();
        let (path, merged) = carried(&format!("levels{level}.illumepc"), &merged);
        if merged.header.kind == "pca" {
            return (merged, levels);
        }
        assert_eq!(merged.header.kind, "levels");
        levels.push(merged.clone());
        previous = Some((path, merged));
    }
    panic!("the adaptive schedule did not end within 10 levels");
}

#[test]
fn adaptive_levels_in_shards_equal_the_unsharded_file() {
    let world = World::new(illume_scene::builtin::load("sun-room").unwrap());
    for verify_midpoint in [false, true] {
        let (s, size) = adaptive_case(verify_midpoint);
        let whole = precompute(&world, &s, size, &mut illume_core::Silent).unwrap();
        let top = whole.header.keys.iter().map(|k| k.level).max().unwrap();
        eprintln!(
            "verify_midpoint {verify_midpoint}: {} keys, levels 0–{top}",
            whole.header.keys.len()
        );
        assert!(top >= 1, "the test day must split at least once");
        let (merged, levels) = sharded_adaptive(&world, &s, size, 3);
        assert_eq!(
            levels.len() as u32,
            top,
            "one levels file per level that added keys"
        );
        assert!(
            merged.to_bytes() == whole.to_bytes(),
            "verify_midpoint {verify_midpoint}: sharded levels differ from the unsharded file"
        );
        assert!(
            merged.section(SKY_DIRECT).is_some()
                && levels.iter().all(|l| l.section(SKY_DIRECT).is_some()),
            "the sky's direct light is carried through every levels file"
        );
    }
}

#[test]
fn adaptive_levels_refuse_wrong_inputs() {
    let world = World::new(illume_scene::builtin::load("sun-room").unwrap());
    let (s, size) = adaptive_case(true);
    let level0 = |s: &PrecomputedSettings, k: u32| {
        let shard = Shard { index: k, count: 2 };
        let part = precompute_level(&world, s, size, 0, None, shard, &mut illume_core::Silent);
        carried(&format!("l0_{k}.illumepc"), &part.unwrap())
    };
    let parts = vec![level0(&s, 0), level0(&s, 1)];
    let levels0 = merge_level(&parts, None).unwrap();
    assert_eq!(levels0.header.kind, "levels");
    let prev = carried("levels0.illumepc", &levels0);
    let prev_ref = Some((prev.0.as_path(), &prev.1));
    let silent = &mut illume_core::Silent;
    let one = Shard { index: 0, count: 1 };
    let err = |r: Result<PcFile, illume_precomputed::PrecomputedError>| r.unwrap_err().to_string();

    // A level with the uniform schedule.
    let e = err(precompute_level(
        &world,
        &settings(),
        SIZE,
        0,
        None,
        one,
        silent,
    ));
    assert!(e.contains("adaptive"), "{e}");
    // The uniform entry point with the adaptive schedule points to levels.
    let e = err(precompute_shard(&world, &s, size, one, silent));
    assert!(e.contains("--level"), "{e}");
    // Level 1 without the levels before; level 0 with them.
    let e = err(precompute_level(&world, &s, size, 1, None, one, silent));
    assert!(e.contains("needs the merged file of levels 0–0"), "{e}");
    let e = err(precompute_level(&world, &s, size, 0, prev_ref, one, silent));
    assert!(e.contains("takes no previous levels"), "{e}");
    // The wrong level for the file.
    let e = err(precompute_level(&world, &s, size, 2, prev_ref, one, silent));
    assert!(
        e.contains("levels0.illumepc") && e.contains("next level is 1"),
        "{e}"
    );
    // The final file as the previous levels.
    let fin = precompute(&world, &s, size, silent).unwrap();
    let e = err(precompute_level(
        &world,
        &s,
        size,
        1,
        Some((Path::new("day.illumepc"), &fin)),
        one,
        silent,
    ));
    assert!(
        e.contains("day.illumepc") && e.contains("final file"),
        "{e}"
    );
    // The levels of other settings, another image size.
    let other = PrecomputedSettings {
        spp: 4,
        ..s.clone()
    };
    let e = err(precompute_level(
        &world, &other, size, 1, prev_ref, one, silent,
    ));
    assert!(
        e.contains("levels0.illumepc") && e.contains("spp: 32 in levels0.illumepc, 4 in this run"),
        "{e}"
    );
    let e = err(precompute_level(
        &world,
        &s,
        (20, 16),
        1,
        prev_ref,
        one,
        silent,
    ));
    assert!(
        e.contains("levels0.illumepc") && e.contains("image size"),
        "{e}"
    );
    // Another scene.
    let repainted = World::new(
        illume_scene::builtin::load("sun-room")
            .map(|mut sc| {
                sc.materials[0].base_color = illume_core::Rgb::new(0.1, 0.2, 0.3);
                sc
            })
            .unwrap(),
    );
    let e = err(precompute_level(
        &repainted, &s, size, 1, prev_ref, one, silent,
    ));
    assert!(
        e.contains("levels0.illumepc") && e.contains("another scene"),
        "{e}"
    );
    // A shard given as the previous levels.
    let e = err(precompute_level(
        &world,
        &s,
        size,
        1,
        Some((parts[0].0.as_path(), &parts[0].1)),
        one,
        silent,
    ));
    assert!(
        e.contains("l0_0.illumepc") && e.contains("not \"levels\""),
        "{e}"
    );
    // Merging level-0 shards again on top of their own merge.
    let e = err(merge_level(&parts, prev_ref));
    assert!(e.contains("no key of level 1"), "{e}");
    // Level-1 shards merged without the levels before.
    let l1 = precompute_level(&world, &s, size, 1, prev_ref, one, silent).unwrap();
    let l1 = vec![carried("l1_0.illumepc", &l1)];
    if l1[0].1.header.keys.iter().any(|k| k.level == 1) {
        let e = err(merge_level(&l1, None));
        assert!(e.contains("l1_0.illumepc") && e.contains("level 0"), "{e}");
    }
}
