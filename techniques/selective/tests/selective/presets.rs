//! `--preset paper` is the paper (issue 35): every setting documented as beyond the paper
//! holds the paper's behaviour in it.

use illume_selective::SelectiveSettings;

/// The settings by which this implementation departs from the paper, and whether `s`
/// holds the paper's behaviour. A setting documented as "beyond the paper" that is
/// missing here fails `the_paper_preset_switches_every_deviation_off`.
fn paper_values(s: &SelectiveSettings) -> Vec<(&'static str, bool)> {
    vec![
        ("min_photons_per_element", s.min_photons_per_element == 0),
        ("min_impacts_per_element", s.min_impacts_per_element == 0),
        ("gather_impacts", s.gather_impacts == 0),
        ("gather_rings", s.gather_impacts == 0), // used only by the gather
        ("temporal_alpha", s.temporal_alpha == 1.0),
        ("temporal_sigmas", s.temporal_alpha == 1.0), // used only by the filter
        ("element_max_side", s.element_max_side == 0.0),
        ("max_photons", s.max_photons == 0),
        ("filtered_textures", !s.filtered_textures),
        ("restart_fraction", s.restart_fraction == 1.0),
        ("directional_albedo", !s.directional_albedo),
        ("emission_map", !s.emission_map),
    ]
}

#[test]
fn the_paper_preset_switches_every_deviation_off() {
    let paper = illume_agreement::assert_paper_preset(paper_values);
    // The paper's numbers (§7) are the default's.
    let default = SelectiveSettings::default();
    assert_eq!(
        (paper.pilots_per_group, paper.ratio, paper.element_count),
        (
            default.pilots_per_group,
            default.ratio,
            default.element_count
        )
    );
}
