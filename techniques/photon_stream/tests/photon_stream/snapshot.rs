//! The VSL power snapshot is never torn (issue 14, thread safety). In a grey world (the
//! furnace: grey albedo, white emission) every photon carries equal red, green and blue,
//! so in any consistent pool state each VSL's power quanta are equal in the three
//! channels, and both sides' totals follow K. The simulation thread updates the pool
//! continuously (streaming mode, normal priority) while this test takes snapshots as fast
//! as it can; every snapshot must show R = G = B at every VSL and powers that are never
//! negative. (K, the photons in the pool, may decrease: the pool holds a number of
//! impacts, and one photon with many impacts can evict several.)

use illume_photon_stream::settings::StreamPriority;
use illume_photon_stream::{PhotonStream, PhotonStreamSettings};
use illume_transport::{Budget, Technique, World};
use std::time::{Duration, Instant};

#[test]
fn snapshots_under_concurrent_updates_are_never_torn() {
    let world = World::new(illume_scene::builtin::furnace(0.5, illume_core::Rgb::ONE)).shared();
    let mut ps = PhotonStream::new(
        &world,
        PhotonStreamSettings {
            vsl_count: 40,
            pool_size: 20_000,
            batch_photons: 64,
            stream_priority: StreamPriority::Normal,
            // Updates for the whole run, though the world stays still.
            rest_when_settled: false,
            ..PhotonStreamSettings::default()
        },
    )
    .unwrap();
    {
        let w = world.read().unwrap();
        ps.advance(&w, &Budget::default());
    }
    let start = Instant::now();
    let (mut snapshots, mut changed, mut last_k, mut last) = (0u64, 0u64, 0u64, None);
    while start.elapsed() < Duration::from_secs(3) {
        let s = ps.snapshot();
        last_k = s.photons;
        for (i, q) in s.quanta.iter().enumerate() {
            let [r, g, b] = q.0;
            assert!(
                r == g && g == b,
                "snapshot {snapshots}: VSL side {i} torn: {:?}",
                q.0
            );
            assert!(r >= 0, "snapshot {snapshots}: VSL side {i} negative: {r}");
        }
        if last.as_ref().is_some_and(|l| *l != s.quanta) {
            changed += 1;
        }
        last = Some(s.quanta);
        snapshots += 1;
        // Let the simulation thread take the pool's mutex between snapshots.
        std::thread::yield_now();
    }
    eprintln!(
        "{snapshots} snapshots, {changed} of them changed since the one before, K = {last_k}"
    );
    // The thread did update the pool between snapshots, many times.
    assert!(
        changed > 20,
        "only {changed} changes in {snapshots} snapshots"
    );
    assert!(last_k > 0);
}
