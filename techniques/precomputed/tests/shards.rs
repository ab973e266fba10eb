//! Three merged shards equal the unsharded file, bit for bit; shards that disagree are
//! refused with an error naming the file.

use illume_precomputed::file::PcFile;
use illume_precomputed::precompute::precompute;
use illume_precomputed::settings::{PrecomputedSettings, ScheduleKind};
use illume_precomputed::shard::{Shard, merge, precompute_shard};
use illume_transport::World;
use std::path::PathBuf;

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
