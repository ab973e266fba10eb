//! radiance_cache's indirect light (`per_frame`) against the reference's through the
//! engine (`illume_agreement`) on `builtin:cornell-spot`, with and without a sky, within
//! the tolerance its registration states (`src/lib.rs`).

use illume_agreement::{Agreement, Lighting, assert_agrees};

#[test]
fn converged_light_agrees_with_the_reference_with_and_without_a_sky() {
    assert_agrees(
        &Agreement::registered::<illume_radiance_cache::Descriptor>(),
        &Lighting::ALL,
        env!("CARGO_TARGET_TMPDIR"),
    );
}
