//! A day on `builtin:sun-room` (issue 12's measurements, in kind with Bahnsen et al. §3.2,
//! §4): adaptive vs uniform keys (count, keys per hour, time per key), the PCA (time,
//! variance captured at k = 5, 10, 20, compression), file size and load time, error at
//! times between keys against the reference (Yee pixels, HDR-FLIP) for k = 10 and 20,
//! linear and cubic, and the run-time cost at 800×600 (reconstruction alone and a whole
//! engine frame).
//!
//! `cargo bench -p illume-precomputed --bench day` (env: `DAY_W`, `DAY_H`, `DAY_SPP`;
//! `DAY_ONLY_RUNTIME=1` for the 800×600 run time alone, `DAY_DOMAINS=screen,cube,atlas`).

use illume_core::image::RgbImage;
use illume_engine::{Config, Engine, TechniqueKind};
use illume_precomputed::Precomputed;
use illume_precomputed::domain::Layout;
use illume_precomputed::file::PcFile;
use illume_precomputed::precompute::{
    Key, base_header, compress, precompute, render_key, render_sky,
};
use illume_precomputed::schedule::KeyTime;
use illume_precomputed::settings::{Domain, Interpolation, PrecomputedSettings, ScheduleKind};
use illume_reference::{ReferenceRenderer, ReferenceSettings};
use illume_transport::World;
use std::time::Instant;

fn env(name: &str, default: u32) -> u32 {
    std::env::var(name)
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}

struct Count(u64);
impl illume_core::Progress for Count {
    fn begin(&mut self, _: &str, _: u64) {}
    fn set(&mut self, done: u64) {
        self.0 = self.0.max(done);
    }
    fn end(&mut self) {}
    fn message(&mut self, _: &str) {}
}

fn main() {
    if let Ok(file) = std::env::var("DAY_FILE") {
        return file_runtime(&file);
    }
    let (w, h, spp) = (env("DAY_W", 160), env("DAY_H", 120), env("DAY_SPP", 32));
    let size = (w, h);
    let world = World::new(illume_scene::builtin::load("sun-room").unwrap());
    let sun = world.scene.sun.as_ref().unwrap().settings.clone();
    println!("# precomputed: a day on builtin:sun-room, {w}×{h}, {spp} spp per key");
    let base = PrecomputedSettings {
        spp,
        components: 20,
        exposure: 64.0,
        ..Default::default()
    };
    let dir = std::env::temp_dir().join(format!("illumepc-bench-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();

    let runtime_only = std::env::var_os("DAY_ONLY_RUNTIME").is_some();
    let mut files = Vec::new();
    let schedules: &[ScheduleKind] = if runtime_only {
        &[]
    } else {
        &[ScheduleKind::Adaptive, ScheduleKind::Uniform]
    };
    for &schedule in schedules {
        let s = PrecomputedSettings {
            schedule,
            ..base.clone()
        };
        let start = Instant::now();
        let mut count = Count(0);
        let file = precompute(&world, &s, size, &mut count).unwrap();
        let total = start.elapsed().as_secs_f64();
        let keys = &file.header.keys;
        let lit = keys.iter().filter(|k| !k.dark).count();
        let mut per_hour = [0usize; 24];
        for k in keys.iter().filter(|k| !k.dark) {
            per_hour[(k.hours.floor() as usize).min(23)] += 1;
        }
        let path = dir.join(format!("{schedule:?}.illumepc"));
        file.write(&path).unwrap();
        let bytes = std::fs::metadata(&path).unwrap().len();
        let t = Instant::now();
        let loaded = PcFile::read(&path).unwrap();
        let technique = Precomputed::from_file(&world, s.clone(), &path, loaded, w, h, t).unwrap();
        let load_s = technique.load_seconds();
        let eig = &file.header.eigenvalues[1];
        let var = |k| 100.0 * illume_precomputed::pca::variance_captured(eig, k);
        let p = (w * h) as f64;
        let t_keys = lit as f64;
        let ratio = |k: f64| 100.0 * (1.0 - (k * (p + t_keys) + t_keys) / (p * t_keys));
        println!(
            "{schedule:?}: {} keys ({} dark, {lit} rendered), {:.1} s total, {:.2} s per rendered key (incl. sky image and PCA)",
            keys.len(),
            keys.len() - lit,
            total,
            total / lit.max(1) as f64
        );
        println!("  keys per hour (lit): {per_hour:?}");
        println!(
            "  variance (green) k=5 {:.2} %, k=10 {:.2} %, k=20 {:.2} %; compression at k=10 {:.1} %, k=20 {:.1} %",
            var(5),
            var(10),
            var(20),
            ratio(10.0),
            ratio(20.0)
        );
        println!(
            "  file {:.2} MB (k = 20), load {:.4} s",
            bytes as f64 / 1e6,
            load_s
        );
        let curve: Vec<String> = (1..=eig.len().min(20))
            .map(|k| format!("{:.3}", var(k)))
            .collect();
        println!("  variance curve k=1..: {}", curve.join(" "));
        files.push((schedule, s, file));
    }

    if !runtime_only {
        measure_pca_and_error(&world, &sun, &files, size, spp);
    }
    runtime(&world, &sun, &dir);
    std::fs::remove_dir_all(&dir).ok();
}

/// PCA time on the uniform keys and error between keys against the reference.
fn measure_pca_and_error(
    world: &World,
    sun: &illume_scene::sun::SunSettings,
    files: &[(ScheduleKind, PrecomputedSettings, PcFile)],
    size: (u32, u32),
    spp: u32,
) {
    let (w, h) = size;
    let world = world.clone_world();
    let sun = sun.clone();
    // PCA time alone at this size on the uniform keys.
    let (_, s_uniform, uniform_file) = &files[1];
    let keys: Vec<Key> = uniform_file
        .header
        .keys
        .iter()
        .filter(|k| !k.dark)
        .map(|k| {
            render_key(
                &world,
                s_uniform,
                KeyTime {
                    hours: k.hours,
                    level: k.level,
                },
                size,
            )
            .unwrap()
        })
        .collect();
    let sky = render_sky(&world, s_uniform, size).unwrap();
    for k in [10, 20] {
        let s = PrecomputedSettings {
            components: k,
            ..s_uniform.clone()
        };
        let start = Instant::now();
        let _ = compress(base_header(&world, &s, size).unwrap(), &s, &keys, &sky).unwrap();
        println!(
            "PCA of {} keys × {} texels × 3 channels, k = {k}: {:.3} s",
            keys.len(),
            w * h,
            start.elapsed().as_secs_f64()
        );
    }

    // Error between keys, against the reference indirect image at that time.
    let times = [7.37, 9.61, 12.23, 15.87, 18.42];
    println!(
        "error vs reference indirect at {times:?} h (mean Yee failing pixels, mean HDR-FLIP):"
    );
    let references: Vec<RgbImage> = times
        .iter()
        .map(|&hours| {
            let mut scene = world.scene.clone();
            for i in scene.instances.iter_mut().filter(|i| i.dynamic) {
                i.mask = 0;
            }
            scene.set_time(sun.scene_time(hours));
            let rw = world.with_scene(scene);
            let mut r = ReferenceRenderer::new(
                ReferenceSettings {
                    spp: 4 * spp,
                    seed: 1234,
                    ..Default::default()
                },
                w,
                h,
            );
            r.add_samples(&rw, 4 * spp);
            // The technique supplies the sky's direct light too: add the sky's alone.
            let mut sky_only = rw.scene.clone();
            let light = sky_only.sun.take().unwrap().light;
            sky_only.lights[light.index()].kind = illume_scene::LightKind::Directional {
                irradiance: illume_core::Rgb::ZERO,
            };
            let mut rs = ReferenceRenderer::new(
                ReferenceSettings {
                    spp: 4 * spp,
                    seed: 4321,
                    ..Default::default()
                },
                w,
                h,
            );
            rs.add_samples(&world.with_scene(sky_only), 4 * spp);
            r.images().indirect.add(&rs.images().direct)
        })
        .collect();
    for (schedule, s, file) in files {
        for k in [10usize, 20] {
            for interpolation in [Interpolation::Linear, Interpolation::Cubic] {
                let s = PrecomputedSettings {
                    interpolation,
                    ..s.clone()
                };
                // Truncate the k = 20 file to k components.
                let mut f = file.clone();
                let keys = f.header.keys.len();
                let kk = k.min(f.header.components as usize);
                for sec in f.sections.iter_mut() {
                    if sec.name.starts_with("temporal.") {
                        sec.values.truncate(kk * keys);
                    } else if sec.name.starts_with("images.") {
                        sec.values.truncate(kk * (w * h) as usize);
                    }
                }
                f.header.components = kk as u32;
                let t = Instant::now();
                let tech = Precomputed::from_file(
                    &world,
                    s.clone(),
                    std::path::Path::new("bench"),
                    f,
                    w,
                    h,
                    t,
                )
                .unwrap();
                let (mut yee, mut flip) = (0.0, 0.0);
                for (&hours, reference) in times.iter().zip(&references) {
                    let e = illume_scene::sun::solar_position(&sun, hours)
                        .unwrap()
                        .elevation_deg;
                    let mut img = RgbImage::from_vec(w, h, tech.reconstruct(hours, 0.0)).unwrap();
                    // The reference includes the sky's indirect light: add ours.
                    let with_sky = tech.reconstruct(hours, illume_scene::sun::sky_scale(e));
                    img = RgbImage::from_vec(w, h, with_sky).unwrap_or(img);
                    let y = illume_metrics::yee_diff(
                        w,
                        h,
                        &illume_precomputed::precompute::to_srgb8(reference, s.exposure),
                        &illume_precomputed::precompute::to_srgb8(&img, s.exposure),
                        &Default::default(),
                    )
                    .unwrap();
                    yee += y.failed_pixels as f64;
                    flip += illume_metrics::hdr_flip(reference, &img, &Default::default())
                        .unwrap()
                        .map
                        .mean();
                }
                let n = times.len() as f64;
                println!(
                    "  {schedule:?} k={k} {interpolation:?}: Yee {:.0} px of {} ({:.2} %), HDR-FLIP {:.4}",
                    yee / n,
                    w * h,
                    100.0 * yee / n / (w * h) as f64,
                    flip / n
                );
            }
        }
    }
}

/// Run time at 800×600.
fn runtime(world: &World, sun: &illume_scene::sun::SunSettings, dir: &std::path::Path) {
    let world = world.clone_world();
    // Run time at 800×600 per domain: a synthetic file of the right size (run time does
    // not depend on the content), then whole engine frames with the sun moving, the
    // camera still (and for `atlas` turning too). Medians of the renderer's timings.
    let (fw, fh) = (800u32, 600u32);
    let only = std::env::var("DAY_DOMAINS").unwrap_or_else(|_| "screen,cube,atlas".into());
    for domain in [Domain::Screen, Domain::Cube, Domain::Atlas] {
        let name = format!("{domain:?}").to_lowercase();
        if !only.split(',').any(|d| d == name) {
            continue;
        }
        let s = PrecomputedSettings {
            schedule: ScheduleKind::Uniform,
            components: 10,
            domain,
            ..Default::default()
        };
        let start = Instant::now();
        let layout = Layout::new(&world, &s, (fw, fh)).unwrap();
        let layout_s = start.elapsed().as_secs_f64();
        let (iw, ih) = layout.image_size();
        let synthetic: Vec<Key> = (0..12)
            .map(|i| Key {
                time: KeyTime {
                    hours: 8.0 + i as f64,
                    level: 0,
                },
                dark: false,
                image: RgbImage::from_vec(
                    iw,
                    ih,
                    (0..iw * ih)
                        .map(|p| {
                            illume_core::Rgb::splat(
                                ((p * 7 + i * 13) % 101) as f32 * 1e-3 + i as f32 * 1e-3,
                            )
                        })
                        .collect(),
                )
                .unwrap(),
            })
            .collect();
        let sky = RgbImage::filled(iw, ih, illume_core::Rgb::splat(0.01));
        let start = Instant::now();
        let big = compress(
            base_header(&world, &s, (fw, fh)).unwrap(),
            &s,
            &synthetic,
            &sky.into(),
        )
        .unwrap();
        let pca_s = start.elapsed().as_secs_f64();
        let path = dir.join(format!("{name}.illumepc"));
        big.write(&path).unwrap();
        let tech = Precomputed::load(&world, s.clone(), &path, fw, fh).unwrap();
        println!(
            "{name}: key image {iw}×{ih} ({} texels{}), layout {layout_s:.3} s, PCA of 12 keys {pca_s:.2} s, file {:.1} MB, load {:.3} s",
            iw as u64 * ih as u64,
            match &layout {
                Layout::Atlas(a) => format!(
                    "; lightmap {}×{}, {} probes",
                    a.width,
                    a.height,
                    a.probes.count()
                ),
                _ => String::new(),
            },
            std::fs::metadata(&path).unwrap().len() as f64 / 1e6,
            tech.load_seconds()
        );
        drop(tech);
        let mut config = Config {
            technique: TechniqueKind::Precomputed,
            ..Default::default()
        };
        config.render.width = fw;
        config.render.height = fh;
        if let Ok(mode) = std::env::var("DAY_SHADOWS") {
            config.render.shadows = match mode.as_str() {
                "maps" => illume_render::ShadowMode::Maps,
                "rays" => illume_render::ShadowMode::Rays,
                _ => illume_render::ShadowMode::Auto,
            };
        }
        config.precomputed = PrecomputedSettings {
            data: path.display().to_string(),
            ..s
        };
        let turning: &[bool] = if domain == Domain::Atlas {
            &[false, true]
        } else {
            &[false]
        };
        frames(&world.scene, &config, sun, turning);
    }
}

/// Engine frames at 800×600 (`config`), the sun moving from 10:00, the camera still or
/// turning 2° a frame: median frame time and the renderer's breakdown.
fn frames(
    scene: &illume_scene::Scene,
    config: &Config,
    sun: &illume_scene::sun::SunSettings,
    cameras: &[bool],
) {
    for &turning in cameras {
        let mut engine = Engine::new(scene.clone(), config).unwrap();
        let _ = engine.step(sun.scene_time(10.0)).unwrap();
        let camera = scene.camera.world_from_camera;
        let frames = 15;
        let mut t: [Vec<f64>; 5] = Default::default();
        for f in 0..frames {
            if turning {
                let turn = illume_core::Affine3A::from_rotation_y((f as f32 * 2.0).to_radians());
                engine
                    .apply_edit(&illume_scene::Edit::SetCameraTransform {
                        world_from_camera: camera * turn,
                    })
                    .unwrap();
            }
            let start = Instant::now();
            let out = engine.step(sun.scene_time(10.0 + f as f64 * 0.05)).unwrap();
            let ft = out.frame.timings;
            if f == 0 {
                println!(
                    "  shadows: {} light(s) with maps, {} with rays",
                    out.frame.shadows.lights_with_maps, out.frame.shadows.lights_with_rays
                );
            }
            t[0].push(start.elapsed().as_secs_f64() * 1e3);
            t[1].push(ft.gbuffer_ms);
            t[2].push(ft.shadow_maps_ms);
            t[3].push(ft.direct_ms);
            t[4].push(ft.indirect_ms);
        }
        let med = |v: &mut Vec<f64>| {
            v.sort_by(f64::total_cmp);
            v[v.len() / 2]
        };
        let [a, b, c, d, e] = &mut t;
        let (frame, g, sm, direct, indirect) = (med(a), med(b), med(c), med(d), med(e));
        println!(
            "  800×600 frames, camera {}: {frame:.1} ms ({:.1} fps): G-buffer {g:.1}, direct {direct:.1} (shadow maps {sm:.1}), indirect {indirect:.1} ms ({:.0} % of the frame)",
            if turning { "turning" } else { "still" },
            1e3 / frame,
            100.0 * indirect / frame
        );
    }
}

/// A file made by `illume precompute` on a scene file, at 800×600: `DAY_FILE` (the
/// file), `DAY_SCENE` (the scene it was made for), `DAY_SKY=R,G,B` (the `--sky` it was
/// made with), `DAY_LOOK=EX,EY,EZ,TX,TY,TZ` (a camera; atlas files take any).
fn file_runtime(file: &str) {
    let scene_path = std::env::var("DAY_SCENE").expect("DAY_SCENE: the scene of DAY_FILE");
    let numbers = |name: &str| -> Option<Vec<f32>> {
        std::env::var(name).ok().map(|v| {
            v.split(',')
                .map(|x| x.trim().parse().expect(name))
                .collect()
        })
    };
    let mut scene = illume_scene::load_scene(std::path::Path::new(&scene_path)).unwrap();
    if let Some(l) = numbers("DAY_LOOK") {
        illume_scene::builtin::look_from(
            &mut scene,
            illume_core::Vec3::new(l[0], l[1], l[2]),
            illume_core::Vec3::new(l[3], l[4], l[5]),
        )
        .unwrap();
    }
    if let Some(c) = numbers("DAY_SKY") {
        scene.sky = Some(illume_scene::Sky::Uniform {
            radiance: illume_core::Rgb::new(c[0], c[1], c[2]),
        });
    }
    let header = PcFile::read_header(std::path::Path::new(file)).unwrap();
    let sun: illume_scene::sun::SunSettings = header.sun.clone().try_into().unwrap();
    println!(
        "# precomputed: {file} ({} domain, {}×{} key image, {} keys) on {scene_path}",
        header.domain,
        header.width,
        header.height,
        header.keys.len()
    );
    let mut config = Config {
        technique: TechniqueKind::Precomputed,
        ..Default::default()
    };
    config.render.width = 800;
    config.render.height = 600;
    config.precomputed.data = file.to_owned();
    let start = Instant::now();
    drop(Engine::new(scene.clone(), &config).unwrap());
    println!(
        "  engine with the file loaded in {:.2} s",
        start.elapsed().as_secs_f64()
    );
    frames(&scene, &config, &sun, &[false, true]);
}

/// A second world on the same meshes (the bench's helpers take `&World`).
trait CloneWorld {
    fn clone_world(&self) -> World;
}

impl CloneWorld for World {
    fn clone_world(&self) -> World {
        self.with_scene(self.scene.clone())
    }
}
