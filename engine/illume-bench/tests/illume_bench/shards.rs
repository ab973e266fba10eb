//! `illume bench --shard K/N`: three shards fill the reference cache with exactly the
//! images (bit for bit) the unsharded run renders, and the plain run after them renders
//! nothing.

use crate::common::temp_dir;
use illume_bench::{RunOptions, Scenario, Silent, references_shard, run};
use illume_core::Shard;
use std::path::Path;

/// 16×12 pixels, 5 frames, the light moving (5 distinct states) and one edit.
const TINY: &str = r#"
name = "tiny-shards"
scene = "builtin:cornell-spot"
animation = "move_light"
width = 16
height = 12
times_s = [0.0, 0.25, 0.5, 0.75, 1.0]
metrics = ["rmse"]

[reference]
spp = 8

[[technique]]
name = "reference"
work = 1

[[edit]]
at_s = 0.5
instance = "sphere"
translation = [0.2, 0.3, 0.0]
"#;

/// Every file of the cache folder, by name, with its bytes.
fn files(dir: &Path) -> Vec<(String, Vec<u8>)> {
    let mut v: Vec<_> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| {
            let p = e.unwrap().path();
            let name = p.file_name().unwrap().to_string_lossy().into_owned();
            (name, std::fs::read(&p).unwrap())
        })
        .collect();
    v.sort();
    v
}

#[test]
fn sharded_references_equal_the_unsharded_ones() {
    let root = temp_dir("shards");
    let scenario = Scenario::parse(TINY, &root.join("tiny.toml")).unwrap();
    let options = |cache: &str| RunOptions {
        output_dir: root.join(format!("report-{cache}")),
        cache_dir: root.join(cache),
        save_frames: false,
        notes: Vec::new(),
    };

    let whole = run(&scenario, &options("whole"), &mut Silent).unwrap();
    assert_eq!(whole.cache_renders, 5);

    let sharded = options("sharded");
    let mut mine = Vec::new();
    for k in 0..3 {
        let shard = Shard { index: k, count: 3 };
        let done = references_shard(&scenario, &sharded, shard, &mut Silent).unwrap();
        assert_eq!(done.distinct, 5);
        assert_eq!(done.cache_renders, done.mine);
        mine.push(done.mine);
    }
    assert_eq!(mine, vec![2, 2, 1], "distinct references j mod 3");
    assert!(!sharded.output_dir.exists(), "a shard writes no report");
    let (a, b) = (files(&root.join("whole")), files(&root.join("sharded")));
    assert_eq!(
        a.len(),
        15,
        "5 images, their 5 first halves and 5 key files"
    );
    let names = |v: &[(String, Vec<u8>)]| v.iter().map(|f| f.0.clone()).collect::<Vec<_>>();
    assert_eq!(names(&a), names(&b));
    for ((name, x), (_, y)) in a.iter().zip(&b) {
        assert!(
            x == y,
            "{name} differs between the sharded and unsharded caches"
        );
    }

    // A shard run again finds its images; the plain run after the shards renders none.
    let again = references_shard(
        &scenario,
        &sharded,
        Shard { index: 1, count: 3 },
        &mut Silent,
    )
    .unwrap();
    assert_eq!((again.cache_hits, again.cache_renders), (2, 0));
    let after = run(&scenario, &sharded, &mut Silent).unwrap();
    assert_eq!((after.cache_hits, after.cache_renders), (5, 0));
    let _ = std::fs::remove_dir_all(&root);
}
