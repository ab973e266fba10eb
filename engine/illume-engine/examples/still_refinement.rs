//! The window's still refinement, measured: a technique's frame at pixel centres once it
//! has settled, and the mean of it and `FRAMES − 1` frames at jittered offsets (the R₂
//! sequence, as `illume view` adds them once the view rests).
//!
//! ```text
//! cargo run --release -p illume-engine --example still_refinement -- \
//!     SCENE WIDTH HEIGHT FRAMES OUT_DIR [TECHNIQUE]
//! ```
//!
//! writes `OUT_DIR/centre.exr` and `OUT_DIR/refined.exr` (linear radiance) and prints
//! the time per refinement frame; compare each with a reference by `illume compare`.

use illume_core::image::{RgbImage, write_exr};
use illume_core::sampling::r2_point;
use illume_engine::{Config, Engine, TechniqueKind};
use std::time::{Duration, Instant};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [scene, width, height, frames, out, rest @ ..] = args.as_slice() else {
        return Err("usage: still_refinement SCENE WIDTH HEIGHT FRAMES OUT_DIR [TECHNIQUE]".into());
    };
    let technique: TechniqueKind = match rest.first() {
        Some(t) => t.parse()?,
        None => TechniqueKind::PhotonStream,
    };
    let mut config = Config {
        technique,
        ..Default::default()
    };
    config.render.width = width.parse()?;
    config.render.height = height.parse()?;
    let frames: u32 = frames.parse()?;
    let out = std::path::Path::new(out);
    std::fs::create_dir_all(out)?;
    let scene = illume_scene::load_scene(std::path::Path::new(scene))?;
    let mut engine = Engine::new(scene, &config)?;
    // Frames at pixel centres until the technique settles (photon_stream's thread rests
    // on a pool the last frame shaded), as the window renders them.
    let start = Instant::now();
    let mut centre = engine.step_held()?.frame.full;
    while !engine.technique().settled() {
        if start.elapsed() > Duration::from_secs(600) {
            return Err(format!("{} did not settle in 600 s", technique.name()).into());
        }
        std::thread::sleep(Duration::from_millis(20));
        centre = engine.step_held()?.frame.full;
    }
    println!("settled after {:.1} s", start.elapsed().as_secs_f64());
    write_exr(&centre, &out.join("centre.exr"))?;
    let mut sum = centre.clone();
    let t0 = Instant::now();
    let mut stages = [0.0f64; 3];
    for i in 1..frames {
        engine.set_jitter(Some(r2_point(i)));
        let frame = engine.step_held()?.frame;
        let t = frame.timings;
        for (s, x) in stages
            .iter_mut()
            .zip([t.gbuffer_ms, t.direct_ms, t.indirect_ms])
        {
            *s += x / f64::from(frames - 1);
        }
        let f = frame.full;
        for (s, p) in sum.pixels_mut().iter_mut().zip(f.pixels()) {
            *s += *p;
        }
    }
    let per_frame = t0.elapsed().as_secs_f64() * 1e3 / f64::from(frames.max(2) - 1);
    let mean: RgbImage = sum.map(|&p| p / frames as f32);
    write_exr(&mean, &out.join("refined.exr"))?;
    println!(
        "{frames} frames averaged; {per_frame:.1} ms a refinement frame (G-buffer {:.1}, \
         direct {:.1}, indirect {:.1} ms on average); still settled: {}",
        stages[0],
        stages[1],
        stages[2],
        engine.technique().settled()
    );
    Ok(())
}
