//! Settings: the paper's values as defaults, every invalid value named
//! `radiance_cache.FIELD`, presets valid, unknown keys refused.

use illume_radiance_cache::{RadianceCacheSettings, TemporalMode};

/// The settings by which this implementation departs from the paper, and whether `s`
/// holds the paper's value. A setting documented as "beyond the paper" that is missing
/// here fails `the_paper_preset_switches_every_deviation_off`.
fn paper_values(s: &RadianceCacheSettings) -> Vec<(&'static str, bool)> {
    vec![
        ("gradient_limit", !s.gradient_limit),
        ("replace_only_on_surface", !s.replace_only_on_surface),
        ("reuse_directions", !s.reuse_directions),
        ("expire_on_surprise", !s.expire_on_surprise),
        ("neighbour_aging", !s.neighbour_aging),
        // The paper's records hold one bounce (§4.3, §5); ours every bounce.
        ("max_depth", s.max_depth == 1),
        ("smooth_weights", !s.smooth_weights),
        ("min_sphere_fraction", s.min_sphere_fraction == 0.0),
        // Only in real time, where the paper has no rule (its frames are a timeline).
        ("max_age_frames", s.max_age_frames == 20),
    ]
}

#[test]
fn the_paper_preset_switches_every_deviation_off() {
    let paper = illume_agreement::assert_paper_preset(paper_values);
    // The paper's numbers are the default's; only the additions differ.
    let default = RadianceCacheSettings::default();
    assert_eq!(
        RadianceCacheSettings {
            gradient_limit: true,
            replace_only_on_surface: true,
            reuse_directions: true,
            expire_on_surprise: true,
            max_depth: 1024,
            smooth_weights: true,
            min_sphere_fraction: 0.04,
            ..paper
        },
        default
    );
}

#[test]
fn defaults_are_the_papers_values() {
    let s = RadianceCacheSettings::default();
    assert_eq!(s.temporal_accuracy, 0.05);
    assert_eq!(s.max_age_frames, 20);
    assert_eq!((s.theta_strata, s.phi_strata), (64, 64));
    assert_eq!(s.temporal, TemporalMode::Interpolated);
    s.validate().unwrap();
}

#[test]
fn invalid_settings_name_their_field() {
    type Edit = fn(&mut RadianceCacheSettings);
    let cases: Vec<(Edit, &str)> = vec![
        (|s| s.accuracy = 0.0, "accuracy"),
        (|s| s.accuracy = 1.5, "accuracy"),
        (|s| s.accuracy = f32::NAN, "accuracy"),
        (|s| s.r_min_fraction = 0.0, "r_min_fraction"),
        (|s| s.r_min_fraction = f32::NAN, "r_min_fraction"),
        (|s| s.r_min_fraction = 0.8, "r_min_fraction"),
        (|s| s.r_max_fraction = -1.0, "r_max_fraction"),
        (|s| s.r_max_fraction = f32::INFINITY, "r_max_fraction"),
        (|s| s.r_max_fraction = f32::NAN, "r_max_fraction"),
        (|s| s.min_sphere_fraction = -0.01, "min_sphere_fraction"),
        (|s| s.min_sphere_fraction = 0.6, "min_sphere_fraction"),
        (|s| s.min_sphere_fraction = f32::NAN, "min_sphere_fraction"),
        (|s| s.theta_strata = 1, "theta_strata"),
        (|s| s.theta_strata = 5000, "theta_strata"),
        (|s| s.phi_strata = 2, "phi_strata"),
        (|s| s.temporal_accuracy = 0.0, "temporal_accuracy"),
        (|s| s.temporal_accuracy = f32::NAN, "temporal_accuracy"),
        (|s| s.temporal_accuracy = 2.0, "temporal_accuracy"),
        (|s| s.max_age_frames = 0, "max_age_frames"),
        (|s| s.glossy_roughness_max = 1.5, "glossy_roughness_max"),
        (
            |s| s.glossy_roughness_max = f32::NAN,
            "glossy_roughness_max",
        ),
        (|s| s.hsh_order = 0, "hsh_order"),
        (|s| s.hsh_order = 17, "hsh_order"),
        (|s| s.traced_roughness_max = 1.5, "traced_roughness_max"),
        (|s| s.glossy_roughness_max = 0.4, "traced_roughness_max"),
        (
            |s| s.traced_roughness_max = f32::NAN,
            "traced_roughness_max",
        ),
        (|s| s.traced_roughness_max = -0.1, "traced_roughness_max"),
        (|s| s.hole_fill_max_passes = 0, "hole_fill_max_passes"),
        (|s| s.traced_rays = 0, "traced_rays"),
        (|s| s.max_depth = 0, "max_depth"),
    ];
    for (edit, field) in cases {
        let mut s = RadianceCacheSettings::default();
        edit(&mut s);
        let want = format!("radiance_cache.{field}:");
        let e = s.validate().expect_err(&want).to_string();
        assert!(e.starts_with(&want), "{e} should start with {want}");
    }
}

#[test]
fn real_time_pacing_refuses_the_modes_that_need_the_timeline() {
    use illume_transport::{Pacing, TechniqueSettings};
    for (mode, refused) in [
        (TemporalMode::PerFrame, false),
        (TemporalMode::Reuse, false),
        (TemporalMode::Extrapolated, true),
        (TemporalMode::Interpolated, true),
    ] {
        let mut s = RadianceCacheSettings {
            temporal: mode,
            ..RadianceCacheSettings::default()
        };
        s.pace(Pacing::RealTime);
        match s.validate() {
            Err(e) if refused => {
                let e = e.to_string();
                assert!(
                    e.starts_with("radiance_cache.temporal:") && e.contains("--realtime"),
                    "{e}"
                );
            }
            Ok(()) if !refused => {}
            other => panic!("{mode:?}: {other:?}"),
        }
        s.pace(Pacing::FixedWork {
            work_per_frame: None,
        });
        s.validate().unwrap();
    }
}

#[test]
fn presets_validate_and_the_first_is_default() {
    let presets = RadianceCacheSettings::presets();
    assert_eq!(presets[0].0, "default");
    assert_eq!(
        RadianceCacheSettings::preset("default"),
        Some(RadianceCacheSettings::default())
    );
    for (name, _) in presets {
        let s = RadianceCacheSettings::preset(name).unwrap();
        s.validate()
            .unwrap_or_else(|e| panic!("preset {name}: {e}"));
    }
    assert!(RadianceCacheSettings::preset("paper").is_some());
    assert!(RadianceCacheSettings::preset("fast").is_some());
    assert!(RadianceCacheSettings::preset("nope").is_none());
}

#[test]
fn toml_tables_read_known_keys_and_refuse_unknown_ones() {
    let s: RadianceCacheSettings =
        toml::from_str("accuracy = 0.1\ntemporal = \"extrapolated\"\nmax_age_frames = 8").unwrap();
    assert_eq!(s.accuracy, 0.1);
    assert_eq!(s.temporal, TemporalMode::Extrapolated);
    assert_eq!(s.max_age_frames, 8);
    assert_eq!(s.theta_strata, 64, "unset keys keep their defaults");
    for mode in ["per_frame", "reuse", "extrapolated", "interpolated"] {
        let s: RadianceCacheSettings = toml::from_str(&format!("temporal = \"{mode}\"")).unwrap();
        s.validate().unwrap();
    }
    let e = toml::from_str::<RadianceCacheSettings>("acuracy = 0.1")
        .unwrap_err()
        .to_string();
    assert!(e.contains("unknown field") && e.contains("acuracy"), "{e}");
    assert!(toml::from_str::<RadianceCacheSettings>("temporal = \"sometimes\"").is_err());
    // The whole struct survives a round trip.
    let text = toml::to_string(&RadianceCacheSettings::fast()).unwrap();
    let back: RadianceCacheSettings = toml::from_str(&text).unwrap();
    assert_eq!(back, RadianceCacheSettings::fast());
}

#[test]
fn record_settings_turn_fractions_into_metres() {
    let s = RadianceCacheSettings::default();
    let r = s.record_settings(4.0);
    assert_eq!(r.r_min_m, 0.04);
    assert_eq!(r.r_max_m, 2.0);
    assert_eq!((r.theta_strata, r.phi_strata), (64, 64));
    assert_eq!(r.path.rr_start_depth, s.rr_start_depth);
}
