//! `--sky-from`: a file's sky images serve another precompute of the same scene, layout,
//! samples and seed, giving the file a fresh render would, bit for bit; a file that
//! differs in anything the sky depends on is refused, naming it and the difference.

use illume_precomputed::file::PcFile;
use illume_precomputed::precompute::{precompute, precompute_with_sky};
use illume_precomputed::settings::{Domain, PrecomputedSettings, ScheduleKind};
use illume_transport::World;
use std::path::{Path, PathBuf};

const SIZE: (u32, u32) = (16, 12);

fn settings(from_h: f64, to_h: f64) -> PrecomputedSettings {
    PrecomputedSettings {
        schedule: ScheduleKind::Uniform,
        domain: Domain::Screen,
        from_h,
        to_h,
        step_min: 60.0,
        spp: 4,
        components: 2,
        ..Default::default()
    }
}

#[test]
fn another_files_sky_gives_the_fresh_file_and_differences_are_named() {
    let world = World::new(illume_scene::builtin::load("sun-room").unwrap());
    let morning = precompute(&world, &settings(6.0, 9.0), SIZE, &mut illume_core::Silent).unwrap();
    // Through bytes, as from disk.
    let path = PathBuf::from("morning.illumepc");
    let morning = PcFile::from_bytes(&path, &morning.to_bytes()).unwrap();
    let sky = morning.section("sky").expect("a sky image");
    assert!(
        sky.values.iter().any(|&v| v > 0.0),
        "the sun-room's sky lights the room: the reused image is not trivially black"
    );
    let source = Some((path.as_path(), &morning));

    // Other hours, another schedule step and fewer components: the same file as rendered.
    let afternoon = PrecomputedSettings {
        step_min: 30.0,
        components: 3,
        ..settings(13.0, 16.0)
    };
    let fresh = precompute(&world, &afternoon, SIZE, &mut illume_core::Silent).unwrap();
    let reused =
        precompute_with_sky(&world, &afternoon, SIZE, source, &mut illume_core::Silent).unwrap();
    assert!(
        reused.to_bytes() == fresh.to_bytes(),
        "the reused sky's file differs from the rendered one"
    );

    let refused = |s: &PrecomputedSettings, size: (u32, u32), w: &World, from: (&Path, &PcFile)| {
        precompute_with_sky(w, s, size, Some(from), &mut illume_core::Silent)
            .unwrap_err()
            .to_string()
    };
    let source = (path.as_path(), &morning);
    let more_samples = PrecomputedSettings {
        spp: 8,
        ..afternoon.clone()
    };
    let e = refused(&more_samples, SIZE, &world, source);
    assert!(
        e.contains("morning.illumepc") && e.contains("spp (8 here, 4 in the file)"),
        "{e}"
    );
    let other_seed = PrecomputedSettings {
        seed: 9,
        ..afternoon.clone()
    };
    let e = refused(&other_seed, (20, 15), &world, source);
    assert!(
        e.contains("image size (20×15 here, 16×12 in the file)") && e.contains("seed ("),
        "{e}"
    );
    let mut other_scene = illume_scene::builtin::load("sun-room").unwrap();
    other_scene.sun.as_mut().unwrap().sky_base = Some(illume_scene::Sky::Uniform {
        radiance: illume_core::Rgb::new(1.0, 2.0, 3.0),
    });
    let e = refused(&afternoon, SIZE, &World::new(other_scene), source);
    assert!(e.contains("the scene or its sky"), "{e}");
    // A file without its sky image (not shard 0 of a sharded run).
    let mut skyless = morning.clone();
    skyless.sections.retain(|s| !s.name.starts_with("sky"));
    let e = refused(&afternoon, SIZE, &world, (path.as_path(), &skyless));
    assert!(e.contains("no sky image"), "{e}");
}
