//! selective's converged indirect light against the reference's through the engine
//! (`illume_agreement`) on `builtin:cornell-spot`, with and without a sky.

use illume_agreement::{Agreement, Lighting, assert_agrees};

/// Every photon of a 1.15 M pool bucketed in mesh elements.
fn agreement() -> Agreement {
    Agreement {
        technique: illume_selective::NAME.into(),
        preset: None,
        sets: vec![
            "selective.mode=deterministic".into(),
            "selective.pilots_per_group=1000".into(),
        ],
        frames: 1,
        max_energy_error: 0.05,
        max_block_error: 0.15,
        why: "every photon of a 1.15 M pool (N_g = 72, N_p = 1000, R = 16) bucketed in \
              12 400 elements: unbiased up to element-scale blur (irradiance constant per \
              element, Gouraud-smoothed) and the element noise of ≈ 90 impacts per element. \
              Issue 10's bounds: energy ±5 %, block error ≤ 0.15"
            .into(),
    }
}

#[test]
fn converged_light_agrees_with_the_reference_with_and_without_a_sky() {
    assert_agrees(&agreement(), &Lighting::ALL, env!("CARGO_TARGET_TMPDIR"));
}
