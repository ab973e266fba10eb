//! scratch: CPU time of G-buffer builds (not committed)
use illume_transport::{GBuffer, World};
fn main() {
    let args: Vec<String> = std::env::args().collect();
    let scene = &args[1];
    let iters: u32 = args[2].parse().unwrap();
    let world = if scene.contains('/') {
        World::new(illume_scene::load_scene(std::path::Path::new(scene)).unwrap())
    } else {
        World::new(illume_scene::builtin::load(scene).unwrap())
    };
    let mut g = GBuffer::rasterize(&world, 800, 600);
    let only_vis = std::env::var("VIS").is_ok();
    let mut v = illume_transport::VisibilityBuffer::render(&world.scene, 800, 600);
    for _ in 0..iters {
        if only_vis {
            v.render_into(&world.scene);
        } else {
            g.rasterize_into(&world, 800, 600);
        }
    }
    println!("{}", g.pixels.iter().filter(|p| p.is_some()).count());
}
#[allow(dead_code)]
fn vis_only() {}
