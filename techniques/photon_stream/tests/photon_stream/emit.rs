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
    let emitter = Emitter::new(
        &w,
        ps.vsls(),
        1.0 / ps.snapshot().quantum_w,
        ps.settings().photon_path(),
        7,
    );
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

/// Flux per VSL slot (ρ·Φ summed over channels, in quanta) of photons `0..n` of `seed`.
fn slot_flux(w: &World, ps: &PhotonStream, filtered: bool, seed: u64, n: u64) -> Vec<f64> {
    let mut path = ps.settings().photon_path();
    path.filtered_textures = filtered;
    let emitter = Emitter::new(w, ps.vsls(), 1.0 / ps.snapshot().quantum_w, path, seed);
    let mut flux = vec![0.0; 2 * ps.vsls().len()];
    for imp in emitter.trace_parallel(w, 0, n).impacts {
        flux[imp.slot as usize] += imp.quanta.channel_sum() as f64;
    }
    flux
}

/// Relative L1 distance Σ|a − b| / Σ|a|.
fn distance(a: &[f64], b: &[f64]) -> f64 {
    let d: f64 = a.iter().zip(b).map(|(x, y)| (x - y).abs()).sum();
    d / a.iter().map(|x| x.abs()).sum::<f64>()
}

#[test]
fn filtered_photon_textures_change_vsl_powers_less_than_photon_noise() {
    // Sponza: 11 MB of base-colour textures, every surface textured. Photons reading
    // the 128-texel copies must give the VSLs the same flux as full-resolution albedo:
    // the difference from the same photons with exact albedo must be smaller than the
    // difference between two independent photon sets, and the total within 0.5 %.
    let path = illume_scene::shared_scenes_dir().join("dabrovic_sponza/sponza.obj");
    let scene =
        illume_scene::load_scene(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let world = World::new(illume_scene::builtin::spot_from_above(scene)).shared();
    let ps = PhotonStream::new(&world, PhotonStreamSettings::deterministic()).unwrap();
    let w = world.read().unwrap();
    let n = 300_000;
    let exact = slot_flux(&w, &ps, false, 1, n);
    let filtered = slot_flux(&w, &ps, true, 1, n);
    let other_photons = slot_flux(&w, &ps, false, 2, n);
    let (by_filter, by_noise) = (
        distance(&exact, &filtered),
        distance(&exact, &other_photons),
    );
    let total = |v: &[f64]| v.iter().sum::<f64>();
    let total_change = total(&filtered) / total(&exact) - 1.0;
    println!("filter {by_filter:.4}, noise {by_noise:.4}, total {total_change:+.4}");
    assert!(
        by_filter < by_noise,
        "filtering moved VSL powers by {by_filter:.4}, photon noise by {by_noise:.4}"
    );
    assert!(
        total_change.abs() < 0.005,
        "total flux changed by {total_change:+.4}"
    );
    assert!(by_filter > 0.0, "the filtered textures were not used");
}
