//! A batch cut short (the frame loop wants the world) holds exactly the first photons of
//! the full batch: stopping early loses no impact and changes no path.

use illume_photon_stream::emit::Emitter;
use illume_photon_stream::{PhotonStream, PhotonStreamSettings};
use illume_transport::World;
use std::cell::Cell;

#[test]
fn a_batch_stopped_early_is_a_prefix_of_the_full_batch() {
    let world = World::new(illume_scene::builtin::load("cornell-spot").unwrap()).shared();
    let ps = PhotonStream::new(&world, PhotonStreamSettings::deterministic()).unwrap();
    let w = world.read().unwrap();
    let emitter = Emitter::new(&w, ps.vsls(), 1.0 / ps.snapshot().quantum_w, 32, 7);
    let full = emitter.trace(&w, 1000, 100);
    let calls = Cell::new(0u32);
    let cut = emitter.trace_until(&w, 1000, 100, || {
        calls.set(calls.get() + 1);
        calls.get() > 40
    });
    assert_eq!(full.photons(), 100);
    assert_eq!(cut.photons(), 40, "stops before photon 41");
    let (a, b): (Vec<_>, Vec<_>) = (full.paths().take(40).collect(), cut.paths().collect());
    assert_eq!(a, b, "the same 40 paths");
    assert!(cut.rays > 0 && cut.rays < full.rays);
    let never = emitter.trace_until(&w, 1000, 100, || false);
    assert_eq!(
        never.paths().collect::<Vec<_>>(),
        full.paths().collect::<Vec<_>>()
    );
}
