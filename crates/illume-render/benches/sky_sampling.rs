//! Environment-map importance sampling against uniform sphere sampling at equal sample
//! counts: `cargo bench -p illume-render --bench sky_sampling`.
//!
//! The irradiance of an upward-facing point, E = ∫ L cosθ dω over the upper hemisphere,
//! under an environment that is dim everywhere (0.05) but for a small bright "sun"
//! (2 × 2 texels of a 256 × 128 map, 5000× brighter; ≈ 0.002 sr). Each strategy estimates E
//! with N samples, 2000 times (20 000 for one sample); the table gives the relative mean squared error against
//! quadrature, and the ratio. `importance` is `LightSet::sample_sky` (texel luminance ×
//! sinθ), `uniform` draws directions uniformly over the sphere (pdf 1/4π).

use illume_core::sampling::{Pcg32, SampleStream, uniform_sphere};
use illume_core::{Rgb, Vec3};
use illume_scene::{EnvMap, Scene, Sky};
use illume_transport::LightSet;
use std::sync::Arc;

fn main() {
    let (w, h) = (256u32, 128u32);
    let mut texels = vec![Rgb::splat(0.05); (w * h) as usize];
    for (i, j) in [(180, 30), (181, 30), (180, 31), (181, 31)] {
        texels[(j * w + i) as usize] = Rgb::splat(250.0);
    }
    let map = EnvMap {
        name: "sun".into(),
        width: w,
        height: h,
        texels: texels.into(),
        scale: 1.0,
        rotation_deg: 0.0,
        sampling: Default::default(),
    };
    let scene = Scene {
        sky: Some(Sky::Equirect(Arc::new(map.clone()))),
        ..Default::default()
    };
    let lights = LightSet::new(&scene);
    let n = Vec3::Y;
    // Quadrature of E (uniform in θ, φ; fine enough to resolve the sun's texels).
    let (nt, np) = (2048, 8192);
    let mut exact = 0f64;
    for a in 0..nt {
        let theta = (a as f64 + 0.5) / nt as f64 * std::f64::consts::FRAC_PI_2;
        for b in 0..np {
            let phi = (b as f64 + 0.5) / np as f64 * 2.0 * std::f64::consts::PI;
            let d = Vec3::new(
                (theta.sin() * phi.cos()) as f32,
                theta.cos() as f32,
                (theta.sin() * phi.sin()) as f32,
            );
            exact += map.lookup(map.uv(d)).x as f64 * theta.cos() * theta.sin();
        }
    }
    exact *= std::f64::consts::FRAC_PI_2 / nt as f64 * 2.0 * std::f64::consts::PI / np as f64;
    println!("E (quadrature) = {exact:.5} W/m²");
    println!("| samples | relMSE importance | relMSE uniform | uniform / importance |");
    println!("|---:|---:|---:|---:|");
    let trials = 2000;
    for spp in [1u32, 4, 16, 64] {
        let mut rng = Pcg32::new(1, u64::from(spp));
        let trials = if spp == 1 { 20 * trials } else { trials };
        let (mut err_is, mut err_uni) = (0f64, 0f64);
        for _ in 0..trials {
            let (mut e_is, mut e_uni) = (0f64, 0f64);
            for _ in 0..spp {
                if let Some(s) = lights.sample_sky(n, &mut rng) {
                    e_is += (s.weight.x * n.dot(s.wi).max(0.0)) as f64;
                }
                let d = uniform_sphere(rng.next_2d());
                let cos = n.dot(d).max(0.0) as f64;
                e_uni += map.lookup(map.uv(d)).x as f64 * cos * 4.0 * std::f64::consts::PI;
            }
            err_is += (e_is / spp as f64 - exact).powi(2);
            err_uni += (e_uni / spp as f64 - exact).powi(2);
        }
        let (rel_is, rel_uni) = (
            err_is / trials as f64 / (exact * exact),
            err_uni / trials as f64 / (exact * exact),
        );
        println!(
            "| {spp} | {rel_is:.4} | {rel_uni:.4} | {:.1} |",
            rel_uni / rel_is
        );
    }
}
