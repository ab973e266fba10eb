//! Shared by the targets: the input is written to a file with the extension the reader
//! dispatches on (the loaders read paths), one file per process, reused; builtin scenes
//! are loaded once per process; a scene's sky is checked and sampled as a render would.

use std::path::PathBuf;

/// Writes `data` to this process's scratch file named `input.EXT` and returns its path.
#[allow(dead_code, reason = "not every target reads a file")]
pub fn scratch_file(ext: &str, data: &[u8]) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("illume-fuzz-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("the scratch folder can be made");
    let path = dir.join(format!("input.{ext}"));
    std::fs::write(&path, data).expect("the scratch file can be written");
    path
}

/// The builtin scene `name` (`builtin:NAME`), loaded once per process.
#[allow(dead_code, reason = "not every target loads a scene")]
pub fn builtin(name: &str) -> &'static illume_scene::Scene {
    use std::collections::HashMap;
    use std::sync::{Mutex, OnceLock};
    static SCENES: OnceLock<Mutex<HashMap<String, &'static illume_scene::Scene>>> = OnceLock::new();
    let mut scenes = SCENES
        .get_or_init(Default::default)
        .lock()
        .unwrap_or_else(|e| e.into_inner());
    scenes.entry(name.to_owned()).or_insert_with(|| {
        let scene =
            illume_scene::load_scene(std::path::Path::new(name)).expect("the builtin scene loads");
        Box::leak(Box::new(scene))
    })
}

/// Sets `scene` to clock time `hours` (its sun, if any), checks it as the loader does
/// and, when it is valid, builds its lights and samples and evaluates the sky in a few
/// directions: what a render does first with a sky.
#[allow(dead_code, reason = "not every target has a sky")]
pub fn check_and_sample(scene: &mut illume_scene::Scene, hours: f64) {
    use illume_core::Vec3;
    use illume_core::sampling::Pcg32;
    let time = scene
        .sun
        .as_ref()
        .map_or(0.0, |s| s.settings.scene_time(hours));
    let _ = scene.set_time(time);
    if scene.validate().is_err() {
        return;
    }
    let lights = illume_transport::LightSet::new(scene);
    let _ = lights.sky_power();
    let mut rng = Pcg32::new(1, 2);
    for normal in [Vec3::Y, Vec3::NEG_Y, Vec3::X, Vec3::new(0.0, 0.6, 0.8)] {
        for _ in 0..4 {
            if let Some(sample) = lights.sample_sky(normal, &mut rng) {
                let _ = lights.sky_pdf(normal, sample.wi);
                let _ = lights.sky_radiance(sample.wi);
            }
        }
        let _ = lights.sky_radiance(normal);
    }
}
