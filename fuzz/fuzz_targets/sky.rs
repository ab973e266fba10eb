//! Sky input on arbitrary text: the first line as a `--sky R,G,B` value
//! (`illume_core::parse_radiance`), the rest as a `[sun]` table (`SunSettings`, as a
//! scene, a bench scenario or a `.illumepc` header gives it). A sky that parses replaces
//! the sky of `builtin:cornell-spot` and of `builtin:sun-room` (where the sun scales it),
//! a sun that parses is attached to `builtin:cornell-spot` and evaluated over a day; each
//! scene is then checked (`Scene::validate`) and, when valid, its lights are built and
//! the sky sampled. Every input gives a value or an error, never a panic, an abort or a
//! hang.
#![no_main]

mod common;

use illume_scene::Sky;
use illume_scene::sun::SunSettings;

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let (first, rest) = text.split_once('\n').unwrap_or((text, ""));
    if let Ok(radiance) = illume_core::parse_radiance(first) {
        for name in ["builtin:cornell-spot", "builtin:sun-room"] {
            let mut scene = common::builtin(name).clone();
            scene.replace_sky(Sky::Uniform { radiance });
            for hours in [0.0, 6.0, 12.0] {
                common::check_and_sample(&mut scene, hours);
            }
        }
    }
    if let Ok(sun) = toml::from_str::<SunSettings>(rest) {
        for hours in [-25.0, 0.0, 6.5, 12.0, 23.99, 1e9] {
            let _ = illume_scene::sun::evaluate(&sun, sun.scene_time(hours));
        }
        let mut scene = common::builtin("builtin:cornell-spot").clone();
        if scene.attach_sun(sun).is_ok() {
            for hours in [0.0, 6.0, 12.0, 18.0] {
                common::check_and_sample(&mut scene, hours);
            }
        }
    }
});
