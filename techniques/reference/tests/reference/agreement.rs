//! The reference against itself through the engine (`illume_agreement`): another seed of
//! the same estimator on `builtin:cornell-spot`, with and without a sky, within the
//! tolerance its registration states (`src/lib.rs`).

use illume_agreement::{Agreement, Lighting, assert_agrees};

#[test]
fn another_seed_agrees_with_the_reference_with_and_without_a_sky() {
    assert_agrees(
        &Agreement::registered::<illume_reference::Descriptor>(),
        &Lighting::ALL,
        env!("CARGO_TARGET_TMPDIR"),
    );
}
