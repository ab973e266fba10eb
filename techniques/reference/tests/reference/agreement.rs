//! The reference against itself through the engine (`illume_agreement`): another seed of
//! the same estimator on `builtin:cornell-spot`, with and without a sky.

use illume_agreement::{Agreement, Lighting, assert_agrees};

/// Another seed of the same estimator, 512 spp: only noise separates the two.
fn agreement() -> Agreement {
    Agreement {
        technique: illume_reference::NAME.into(),
        preset: None,
        sets: vec![
            "reference.spp_per_frame=256".into(),
            "reference.seed=77".into(),
        ],
        frames: 2,
        max_energy_error: 0.02,
        max_block_error: 0.06,
        why: "another seed of the same estimator, 512 spp: only noise separates the two. \
              The reference's own block noise at 512 spp is ≈ 0.02 (two independent halves, \
              photon_stream's tests/photon_stream/reference.rs), its energy noise well below 1 %"
            .into(),
    }
}

#[test]
fn another_seed_agrees_with_the_reference_with_and_without_a_sky() {
    assert_agrees(&agreement(), &Lighting::ALL, env!("CARGO_TARGET_TMPDIR"));
}
