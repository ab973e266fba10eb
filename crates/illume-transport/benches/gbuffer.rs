//! G-buffer and direct-light cost per frame: `cargo bench -p illume-transport --bench gbuffer`.

use criterion::{Criterion, criterion_group, criterion_main};
use illume_core::Vec2;
use illume_transport::{GBuffer, World};

fn gbuffer(c: &mut Criterion) {
    let world = World::new(illume_scene::builtin::load("cornell-spot").expect("builtin"));
    let mut g = c.benchmark_group("gbuffer");
    g.sample_size(20);
    for (w, h) in [(640u32, 480u32), (800, 600)] {
        g.bench_function(format!("cornell-spot {w}x{h}"), |b| {
            b.iter(|| GBuffer::render(&world, w, h, Vec2::splat(0.5)))
        });
    }
    g.finish();
}

/// Criterion's generated entry points (private, so they need no docs).
mod entry {
    use super::*;
    criterion_group!(benches, gbuffer);
}
criterion_main!(entry::benches);
