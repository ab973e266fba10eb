//! A still's long work reaches the caller's progress (`illume render`'s bars and log
//! lines): radiance_cache makes its records inside its one frame, where the G-buffer
//! says, so the frame itself reports them, pass by pass, without changing a pixel.

use illume_core::Progress;
use illume_engine::{Config, Engine, TechniqueKind, render_still};
use illume_radiance_cache::RadianceCacheSettings;

/// One reported phase: its name, its total and every count reported, and whether it
/// ended.
struct Phase {
    what: String,
    total: u64,
    done: Vec<u64>,
    ended: bool,
}

/// Keeps every report, checking the calling order of [`Progress`].
#[derive(Default)]
struct Recorded {
    phases: Vec<Phase>,
}

impl Recorded {
    /// The phase in progress; reports outside a phase fail the test.
    fn open(&mut self) -> &mut Phase {
        let p = self.phases.last_mut().expect("a report before any begin");
        assert!(!p.ended, "a report after {:?} ended", p.what);
        p
    }
}

impl Progress for Recorded {
    fn begin(&mut self, what: &str, total: u64) {
        if let Some(p) = self.phases.last() {
            assert!(p.ended, "{what:?} began inside {:?}", p.what);
        }
        self.phases.push(Phase {
            what: what.to_owned(),
            total,
            done: Vec::new(),
            ended: false,
        });
    }
    fn set(&mut self, done: u64) {
        self.open().done.push(done);
    }
    fn end(&mut self) {
        self.open().ended = true;
    }
    fn message(&mut self, _text: &str) {}
}

/// `render`'s preset (per-frame), small: 96×72 with 8×8 rays a record.
fn config() -> Config {
    let mut c = Config {
        technique: TechniqueKind::RadianceCache,
        ..Default::default()
    };
    c.render.width = 96;
    c.render.height = 72;
    c.radiance_cache = RadianceCacheSettings {
        theta_strata: 8,
        phi_strata: 8,
        ..RadianceCacheSettings::still()
    };
    c
}

#[test]
fn a_radiance_cache_still_reports_its_records_pass_by_pass_with_the_same_image() {
    let scene = illume_scene::builtin::load("cornell-spot").unwrap();
    let t = scene.time;
    let mut progress = Recorded::default();
    let still = render_still(scene.clone(), &config(), &mut progress).unwrap();

    // The same frame, nothing reported.
    let mut engine = Engine::new(scene, &config()).unwrap();
    engine.set_split(true);
    let out = engine.step(t).unwrap();
    assert!(
        still.indirect.pixels() == out.frame.indirect.pixels(),
        "reporting progress changed the image"
    );

    let records: Vec<&Phase> = progress
        .phases
        .iter()
        .filter(|p| p.what.starts_with("radiance_cache records"))
        .collect();
    let created = out.stats.get("radiance_cache.records_created").unwrap();
    let reported: u64 = records.iter().map(|p| p.total).sum();
    assert!(created > 100.0, "{created} records: too few to test with");
    assert_eq!(reported as f64, created, "records reported against made");
    // The coarsest grid (32 px) cannot cover a 96×72 image alone.
    assert!(records.len() >= 2, "{} passes reported", records.len());
    for p in &records {
        assert!(p.ended, "{:?} never ended", p.what);
        assert!(
            p.done.windows(2).all(|w| w[0] < w[1]),
            "{:?}: counts {:?} not increasing",
            p.what,
            p.done
        );
        assert_eq!(p.done.last(), Some(&p.total), "{:?} stopped short", p.what);
    }
}
