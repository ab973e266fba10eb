//! scratch (not committed): CPU time of VSL shading
use illume_photon_stream::shade::shade;
use illume_photon_stream::{PhotonStream, PhotonStreamSettings};
use illume_transport::{GBuffer, World};
fn main() {
    let args: Vec<String> = std::env::args().collect();
    let stride: u32 = args[1].parse().unwrap();
    let iters: u32 = args[2].parse().unwrap();
    let world = World::new(illume_scene::builtin::load("cornell-spot").unwrap()).shared();
    let mut ps = PhotonStream::new(&world, PhotonStreamSettings::deterministic()).unwrap();
    let w = world.read().unwrap();
    ps.warm_up(&w);
    let field = ps.field(&w);
    let g = GBuffer::rasterize(&w, 800, 600);
    let s = PhotonStreamSettings {
        shading_stride: stride,
        ..PhotonStreamSettings::deterministic()
    };
    let t = std::time::Instant::now();
    let mut e = 0;
    for k in 0..iters {
        let (_img, st) = shade(&w, &g, &field, &s, k as u64);
        e += st.evaluations;
    }
    println!(
        "{:.2} ms/frame wall, {} evals/frame",
        t.elapsed().as_secs_f64() * 1e3 / iters.max(1) as f64,
        e / iters.max(1) as u64
    );
}
