//! The work budget (`Budget::work`, records per frame): a frame computes at most that
//! many records, coarse placement first; the pixels no record reaches take their
//! neighbours' light; the backlog clears over the next frames; replacements past the
//! budget wait a frame.

use crate::common::{H, W, cornell, on_threads};
use illume_core::image::RgbImage;
use illume_radiance_cache::{RadianceCache, RadianceCacheSettings, TemporalMode};
use illume_scene::Timeline;
use illume_transport::{Budget, Pacing, Technique, TechniqueSettings, World};

fn cache(world: &World, temporal: TemporalMode) -> RadianceCache {
    let timeline = Timeline::single(world.scene.clone(), 0.0, W, H);
    let settings = RadianceCacheSettings {
        theta_strata: 16,
        phi_strata: 16,
        temporal,
        ..RadianceCacheSettings::default()
    };
    RadianceCache::new(world, &timeline, settings).unwrap()
}

fn budget(work: u64) -> Budget {
    Budget {
        work: Some(work),
        time_ms: None,
    }
}

fn stat(rc: &RadianceCache, name: &str) -> f64 {
    rc.stats()
        .get(name)
        .unwrap_or_else(|| panic!("no counter {name}"))
}

/// Pixels non-black in `a` and black in `b`.
fn lost(a: &RgbImage, b: &RgbImage) -> usize {
    a.pixels()
        .iter()
        .zip(b.pixels())
        .filter(|(x, y)| x.max_element() > 0.0 && y.max_element() <= 0.0)
        .count()
}

#[test]
fn a_work_budget_caps_the_records_of_a_frame_and_fills_the_pixels_left_without() {
    let (world, g) = cornell();
    let mut free = cache(&world, TemporalMode::PerFrame);
    free.advance(&world, &Budget::default());
    let full = free.indirect(&world, &g);
    let needed = free.records_created();
    assert_eq!(stat(&free, "records_skipped"), 0.0);
    assert_eq!(stat(&free, "pixels_filled"), 0.0);

    let cap = needed / 4;
    let mut capped = cache(&world, TemporalMode::PerFrame);
    capped.advance(&world, &budget(cap));
    let img = capped.indirect(&world, &g);
    assert_eq!(capped.records_created(), cap, "{needed} needed");
    assert!(stat(&capped, "records_skipped") > 0.0);
    let filled = stat(&capped, "pixels_filled");
    let unfilled = stat(&capped, "pixels_unfilled");
    eprintln!(
        "{needed} records needed, {cap} made: {filled} pixels filled, {unfilled} unfilled; mean {} against {}",
        img.mean(),
        full.mean()
    );
    assert!(filled > 0.0);
    // The fill reaches (almost) every pixel that has light without a budget.
    let black = lost(&full, &img);
    assert!(
        black as f64 <= 0.01 * (W * H) as f64,
        "{black} pixels black"
    );
    // A coarser cache of the same light: the image's mean within 10 %.
    let (m, f) = (img.mean().element_sum(), full.mean().element_sum());
    assert!((m / f - 1.0).abs() < 0.1, "mean {m} against {f}");
    // Without the fill the skipped pixels would be black.
    assert!(filled >= black as f64);
}

#[test]
fn the_backlog_clears_over_the_following_frames_of_a_still_scene() {
    let (world, g) = cornell();
    let mut free = cache(&world, TemporalMode::Reuse);
    let full = free.indirect(&world, &g);
    let needed = free.records_created();
    let cap = needed / 3;
    let mut rc = cache(&world, TemporalMode::Reuse);
    rc.advance(&world, &budget(cap));
    let mut frames = 0;
    let mut last = rc.indirect(&world, &g);
    while stat(&rc, "records_skipped") > 0.0 {
        frames += 1;
        assert!(frames < 10, "the backlog does not clear");
        rc.advance(&world, &budget(cap));
        last = rc.indirect(&world, &g);
        assert!(stat(&rc, "records_created") <= cap as f64);
    }
    // Three budgets cover what one unbudgeted frame computes, give or take the
    // coarse records that now cover what fine ones would have.
    assert!(frames <= 5, "{frames} frames");
    assert_eq!(stat(&rc, "pixels_filled"), 0.0);
    let total = rc.records_created();
    assert!(
        total as f64 >= 0.7 * needed as f64 && total as f64 <= 1.3 * needed as f64,
        "{total} records against {needed}"
    );
    let (m, f) = (last.mean().element_sum(), full.mean().element_sum());
    assert!((m / f - 1.0).abs() < 0.05, "mean {m} against {f}");
    assert_eq!(lost(&full, &last), 0);
}

#[test]
fn replacements_past_the_budget_wait_a_frame_and_their_records_stay_in_use() {
    let (world, g) = cornell();
    let timeline = Timeline::single(world.scene.clone(), 0.0, W, H);
    let settings = RadianceCacheSettings {
        theta_strata: 16,
        phi_strata: 16,
        temporal: TemporalMode::Reuse,
        max_age_frames: 2,
        // Replacement wherever a record was used (no surface test).
        replace_only_on_surface: false,
        ..RadianceCacheSettings::default()
    };
    let mut rc = RadianceCache::new(&world, &timeline, settings).unwrap();
    let first = rc.indirect(&world, &g);
    let alive = rc.records_alive();
    rc.indirect(&world, &g);
    // Frame 2: every record expires; only `cap` are replaced, the rest wait.
    let cap = (alive / 4) as u64;
    rc.advance(&world, &budget(cap));
    let img = rc.indirect(&world, &g);
    let (replaced, deferred) = (stat(&rc, "records_replaced"), stat(&rc, "records_deferred"));
    eprintln!("{alive} alive: {replaced} replaced, {deferred} deferred");
    assert_eq!(replaced, cap as f64);
    assert!(deferred > 0.0);
    assert_eq!(
        replaced + deferred + stat(&rc, "records_deleted"),
        alive as f64
    );
    assert_eq!(stat(&rc, "records_reused"), deferred);
    assert_eq!(
        rc.records_alive() as f64,
        replaced + deferred + stat(&rc, "records_created"),
        "deferred records stay"
    );
    assert_eq!(lost(&first, &img), 0);
    // The next frames work the backlog off.
    rc.advance(&world, &budget(cap));
    rc.indirect(&world, &g);
    assert!(stat(&rc, "records_replaced") <= cap as f64);
    assert!(stat(&rc, "records_deferred") < deferred);
}

#[test]
fn the_budget_comes_from_work_per_frame_and_records_per_frame_max() {
    let mut s = RadianceCacheSettings::default();
    assert_eq!(s.default_budget().work, None);
    s.pace(Pacing::FixedWork {
        work_per_frame: Some(120),
    });
    assert_eq!(s.records_per_frame_max, 120);
    assert_eq!(s.default_budget().work, Some(120));
    s.pace(Pacing::FixedWork {
        work_per_frame: None,
    });
    assert_eq!(s.default_budget().work, Some(120));
    // The setting caps a frame that never saw `advance`.
    let (world, g) = cornell();
    let timeline = Timeline::single(world.scene.clone(), 0.0, W, H);
    let settings = RadianceCacheSettings {
        theta_strata: 16,
        phi_strata: 16,
        temporal: TemporalMode::PerFrame,
        records_per_frame_max: 30,
        ..RadianceCacheSettings::default()
    };
    let mut rc = RadianceCache::new(&world, &timeline, settings).unwrap();
    rc.indirect(&world, &g);
    assert_eq!(rc.records_created(), 30);
}

#[test]
fn a_budgeted_frame_does_not_depend_on_the_thread_count() {
    let (world, g) = cornell();
    let run = |threads: usize| {
        on_threads(threads, || {
            let mut rc = cache(&world, TemporalMode::PerFrame);
            rc.advance(&world, &budget(40));
            let img = rc.indirect(&world, &g);
            let records: Vec<_> = rc.records().map(|r| r.position).collect();
            (img, records)
        })
    };
    let (a, ra) = run(1);
    let (b, rb) = run(2);
    assert_eq!(ra, rb);
    assert_eq!(a.pixels(), b.pixels());
}

#[test]
fn a_time_budget_becomes_a_record_cap_from_the_measured_cost_of_a_record() {
    let (world, g) = cornell();
    let mut rc = cache(&world, TemporalMode::PerFrame);
    // Frame 0: no cost measured yet, so the time limit cannot cap it.
    let tiny = Budget {
        work: None,
        time_ms: Some(1e-9),
    };
    rc.advance(&world, &tiny);
    rc.indirect(&world, &g);
    let needed = rc.records_created();
    let gather_ms = stat(&rc, "gather_ms");
    assert_eq!(stat(&rc, "records_skipped"), 0.0);
    assert!(gather_ms > 0.0);
    // Frame 1: a quarter of frame 0's gather time buys a quarter of its records.
    rc.advance(
        &world,
        &Budget {
            work: None,
            time_ms: Some(gather_ms / 4.0),
        },
    );
    rc.indirect(&world, &g);
    let made = stat(&rc, "records_created") as u64;
    eprintln!("{needed} records in {gather_ms:.2} ms, then {made} under a quarter of it");
    assert!(
        made + 1 >= needed / 4 && made <= needed / 4,
        "{made} records made, {needed} needed"
    );
    assert!(stat(&rc, "records_skipped") > 0.0);
    // With a work cap too, the smaller of the two holds.
    rc.advance(
        &world,
        &Budget {
            work: Some(3),
            time_ms: Some(1e9),
        },
    );
    rc.indirect(&world, &g);
    assert_eq!(stat(&rc, "records_created"), 3.0);
    // A limit below one record's cost still makes one record a frame.
    rc.advance(&world, &tiny);
    rc.indirect(&world, &g);
    assert_eq!(stat(&rc, "records_created"), 1.0);
}
