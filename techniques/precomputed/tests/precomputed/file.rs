//! The `.illumepc` file: round trip, and each kind of bad file gives its own error that
//! names the file.

use illume_precomputed::file::{
    FileError, Header, KeyInfo, PcFile, Section, SectionFormat, VERSION, scene_fingerprint,
};
use std::path::Path;

fn sample(scene: &illume_scene::Scene) -> PcFile {
    let (_, fingerprint) = scene_fingerprint(scene);
    PcFile {
        header: Header {
            kind: "pca".into(),
            scene_source: scene.source.clone(),
            scene_fingerprint: fingerprint,
            settings: toml::toml! { components = 10 },
            sun: toml::toml! { latitude_deg = 55.49 },
            domain: "screen".into(),
            width: 4,
            height: 2,
            channels: 3,
            camera: vec![
                1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 1.0, 2.0, 0.7,
            ],
            exposure: 1.0,
            shard: [0, 1],
            atlas: None,
            keys: vec![
                KeyInfo {
                    hours: 0.0,
                    level: 0,
                    dark: true,
                },
                KeyInfo {
                    hours: 12.0,
                    level: 0,
                    dark: false,
                },
            ],
            components: 1,
            colour: "per-channel".into(),
            eigenvalues: vec![vec![2.5, 0.0]],
            sections: vec![],
        },
        sections: vec![
            Section {
                name: "mean.r".into(),
                format: SectionFormat::F32,
                values: vec![0.25, -1.5e-7],
            },
            Section {
                name: "images.r".into(),
                format: SectionFormat::F16,
                values: (0..8).map(|i| i as f32 * 0.5).collect(),
            },
        ],
    }
}

fn scene() -> illume_scene::Scene {
    illume_scene::builtin::load("cornell-spot").unwrap()
}

#[test]
fn round_trip() {
    let dir = std::env::temp_dir().join(format!("illumepc-rt-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("a.illumepc");
    let file = sample(&scene());
    file.write(&path).unwrap();
    let back = PcFile::read(&path).unwrap();
    assert_eq!(back.header.keys, file.header.keys);
    assert_eq!(back.header.sections.len(), 2);
    assert_eq!(back.sections, file.sections); // f16 values here are exact in half
    // Writing again gives the same bytes.
    assert_eq!(back.to_bytes(), file.to_bytes());
    back.check_scene(&path, &scene()).unwrap();
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn each_bad_file_has_its_own_error() {
    let path = Path::new("bad.illumepc");
    let bytes = sample(&scene()).to_bytes();
    let named = |e: &FileError| assert!(e.to_string().contains("bad.illumepc"), "{e}");

    // A flipped byte in the last section, and one in the header.
    let mut flipped = bytes.clone();
    *flipped.last_mut().unwrap() ^= 0x10;
    let e = PcFile::from_bytes(path, &flipped).unwrap_err();
    named(&e);
    assert!(
        matches!(&e, FileError::Checksum { what, .. } if what == "section images.r"),
        "{e}"
    );
    let mut flipped = bytes.clone();
    flipped[30] ^= 0x01;
    let e = PcFile::from_bytes(path, &flipped).unwrap_err();
    assert!(
        matches!(&e, FileError::Checksum { what, .. } if what == "the header"),
        "{e}"
    );

    // Another version.
    let mut other = bytes.clone();
    other[8..12].copy_from_slice(&(VERSION + 1).to_le_bytes());
    let e = PcFile::from_bytes(path, &other).unwrap_err();
    named(&e);
    assert!(matches!(e, FileError::Version { found, .. } if found == VERSION + 1));

    // Truncated: inside a section, inside the header, inside the magic.
    for cut in [bytes.len() - 1, 40, 5] {
        let e = PcFile::from_bytes(path, &bytes[..cut]).unwrap_err();
        named(&e);
        assert!(
            matches!(e, FileError::Truncated { .. }),
            "cut at {cut}: {e}"
        );
    }
    // Not ours at all, and bytes after the end.
    let e = PcFile::from_bytes(path, b"P6\n4 4\n255\n........").unwrap_err();
    assert!(matches!(e, FileError::Magic { .. }), "{e}");
    let mut longer = bytes.clone();
    longer.push(0);
    let e = PcFile::from_bytes(path, &longer).unwrap_err();
    assert!(matches!(e, FileError::Trailing { extra: 1, .. }), "{e}");

    // Another scene.
    let file = PcFile::from_bytes(path, &bytes).unwrap();
    let other_scene = illume_scene::builtin::load("cube-in-box").unwrap();
    let e = file.check_scene(path, &other_scene).unwrap_err();
    named(&e);
    assert!(matches!(e, FileError::OtherScene { .. }), "{e}");
    // A moved static instance is another scene too; a moved dynamic one is not.
    let mut moved = scene();
    let i = moved.instances.iter().position(|i| !i.dynamic).unwrap();
    moved.instances[i].world_from_object.translation.x += 0.01;
    assert!(file.check_scene(path, &moved).is_err());
}

/// Issue 38: a header whose checksum is right but whose fields are wrong (a NaN key time
/// panicked the run time in `schedule::bracket`; duplicate and unsorted times, NaN data,
/// impossible counts were accepted) is refused on read, naming the file, the field and
/// the value. Each case is generated from the valid sample and written with a fresh
/// checksum, so only the new checks can catch it.
#[test]
fn header_fields_and_values_are_checked_on_read() {
    let path = Path::new("bad.illumepc");
    type Edit = fn(&mut PcFile);
    let cases: &[(&str, Edit, &[&str])] = &[
        (
            "nan key time",
            |f| f.header.keys[1].hours = f64::NAN,
            &["keys[1].hours", "NaN"],
        ),
        (
            "inf key time",
            |f| f.header.keys[0].hours = f64::NEG_INFINITY,
            &["keys[0].hours", "-inf"],
        ),
        (
            "duplicate key time",
            |f| f.header.keys[1].hours = 0.0,
            &["keys[1].hours", "strictly increasing"],
        ),
        (
            "unsorted key times",
            |f| f.header.keys[0].hours = 13.0,
            &["keys[1].hours", "12"],
        ),
        ("no keys", |f| f.header.keys.clear(), &["keys", "none"]),
        (
            "more components than keys",
            |f| f.header.components = 2,
            &["components", "2"],
        ),
        ("width 0", |f| f.header.width = 0, &["width", "0"]),
        (
            "height 2^31",
            |f| f.header.height = 1 << 31,
            &["height", "2147483648"],
        ),
        ("channels 4", |f| f.header.channels = 4, &["channels", "4"]),
        (
            "camera short",
            |f| f.header.camera.truncate(3),
            &["camera", "13 finite"],
        ),
        (
            "camera nan",
            |f| f.header.camera[12] = f32::NAN,
            &["camera", "NaN"],
        ),
        (
            "exposure 0",
            |f| f.header.exposure = 0.0,
            &["exposure", "0"],
        ),
        (
            "exposure inf",
            |f| f.header.exposure = f32::INFINITY,
            &["exposure", "inf"],
        ),
        (
            "shard 2 of 2",
            |f| f.header.shard = [2, 2],
            &["shard", "[2, 2]"],
        ),
        (
            "shard of 0",
            |f| f.header.shard = [0, 0],
            &["shard", "[0, 0]"],
        ),
        // What a header makes a merge or the run time allocate is bounded on read.
        (
            "shard count 4e9",
            |f| f.header.shard = [0, 4_000_000_000],
            &["shard", "4000000000", "86400"],
        ),
        (
            "screen wider than a render",
            |f| f.header.width = 65_536,
            &["width/height", "65536×2", "16384"],
        ),
        (
            "cube not six faces",
            |f| f.header.domain = "cube".into(),
            &["width/height", "4×2", "6 × width"],
        ),
        (
            "unknown kind",
            |f| f.header.kind = "full".into(),
            &["kind", "full"],
        ),
        (
            "unknown domain",
            |f| f.header.domain = "sphere".into(),
            &["domain", "sphere"],
        ),
        (
            "nan eigenvalue",
            |f| f.header.eigenvalues[0][1] = f64::NAN,
            &["eigenvalues[0][1]", "NaN"],
        ),
        (
            "nan value",
            |f| f.sections[0].values[1] = f32::NAN,
            &["section mean.r value 1", "NaN"],
        ),
        (
            "inf value",
            |f| f.sections[0].values[0] = f32::INFINITY,
            &["section mean.r value 0", "inf"],
        ),
        (
            "f16 overflow",
            |f| f.sections[1].values[7] = 1e6,
            &["section images.r value 7", "inf"],
        ),
        (
            "too many keys",
            |f| {
                f.header.keys = (0..illume_precomputed::file::MAX_KEYS + 1)
                    .map(|i| KeyInfo {
                        hours: i as f64,
                        level: 0,
                        dark: true,
                    })
                    .collect();
                f.header.components = 0;
            },
            &["keys", "86401 keys", "86400"],
        ),
    ];
    for (name, edit, words) in cases {
        let mut file = sample(&scene());
        edit(&mut file);
        let bytes = file.to_bytes();
        let e = PcFile::from_bytes(path, &bytes).expect_err(name);
        let message = e.to_string();
        assert!(matches!(e, FileError::Invalid { .. }), "{name}: {message}");
        for word in ["bad.illumepc"].iter().chain(words.iter()) {
            assert!(message.contains(word), "{name}: {message:?} lacks {word:?}");
        }
        // The header alone (what `attach_file_sun` reads) is checked too.
        let dir = std::env::temp_dir().join(format!("illumepc-bad-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let on_disk = dir.join("h.illumepc");
        std::fs::write(&on_disk, &bytes).unwrap();
        let header = PcFile::read_header(&on_disk);
        let sections_only = matches!(*name, "nan value" | "inf value" | "f16 overflow");
        assert_eq!(
            header.is_err(),
            !sections_only,
            "{name}: read_header {header:?}"
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }
    // The sample itself is fine.
    PcFile::from_bytes(path, &sample(&scene()).to_bytes()).unwrap();
}

/// An environment map enters the fingerprint by its texels' hash, not their text (which
/// was about 1 GB for an 8192 × 4096 map): one texel changed changes the fingerprint,
/// and the text stays short however large the map.
#[test]
fn an_environment_maps_texels_enter_the_fingerprint_as_a_hash() {
    let with_map = |width: u32, height: u32, changed: bool| {
        let mut texels = vec![illume_core::Rgb::new(0.2, 0.3, 0.4); (width * height) as usize];
        if changed {
            texels[7].y = 0.31;
        }
        let mut s = scene();
        s.sky = Some(illume_scene::Sky::Equirect(std::sync::Arc::new(
            illume_scene::EnvMap {
                name: "sky.exr".into(),
                width,
                height,
                texels: texels.into(),
                scale: 1.0,
                rotation_deg: 0.0,
                sampling: Default::default(),
            },
        )));
        scene_fingerprint(&s)
    };
    let (small_text, small) = with_map(8, 4, false);
    let (_, changed) = with_map(8, 4, true);
    let (large_text, _) = with_map(1024, 512, false);
    assert_ne!(small, changed, "one texel changed");
    assert_eq!(small, with_map(8, 4, false).1, "the same map");
    assert!(
        large_text.len() < small_text.len() + 16,
        "{} bytes of text for 1024 × 512 texels against {} for 8 × 4",
        large_text.len(),
        small_text.len()
    );
}

/// A `pca` file of `lit` lit keys (and 3 dark ones) of `texels` texels, `k` components
/// per channel, with the sky's two images: the sections `precompute` writes.
fn pca_file(lit: usize, texels: usize, k: usize) -> PcFile {
    let mut file = sample(&scene());
    file.header.width = texels as u32;
    file.header.height = 1;
    file.header.components = k as u32;
    file.header.keys = (0..lit + 3)
        .map(|i| KeyInfo {
            hours: i as f64 * 0.1,
            level: 0,
            dark: i < 3,
        })
        .collect();
    let t_all = lit + 3;
    let section = |name: String, format, n: usize| Section {
        name,
        format,
        values: vec![0.5; n],
    };
    file.sections = ["r", "g", "b"]
        .iter()
        .flat_map(|c| {
            [
                section(format!("mean.{c}"), SectionFormat::F32, t_all),
                section(format!("temporal.{c}"), SectionFormat::F32, k * t_all),
                section(format!("images.{c}"), SectionFormat::F16, k * texels),
            ]
        })
        .chain([
            section("sky".into(), SectionFormat::F32, 3 * texels),
            section("sky.direct".into(), SectionFormat::F32, 3 * texels),
        ])
        .collect();
    file
}

#[test]
fn compression_counts_the_keys_values_as_the_paper_and_every_byte_beside() {
    // The paper's case (§4.1): 180 keys of 480 000 pixels, k = 10: 94.4 % of the values
    // (the paper rounds to 94.5 %), whatever the sky's images.
    let (lit, texels, k) = (180usize, 480_000usize, 10usize);
    let c = pca_file(lit, texels, k).compression().expect("a pca file");
    let t_all = (lit + 3) as f64;
    let (n, kf, tl) = (texels as f64, k as f64, lit as f64);
    let keys = 3.0 * (t_all + kf * t_all + kf * n);
    assert_eq!(c.raw_values, 3.0 * tl * n);
    assert_eq!(c.key_values, keys);
    let paper = c.of_key_values();
    assert!((paper - (1.0 - keys / (3.0 * tl * n))).abs() < 1e-12);
    assert!((0.9443..0.9445).contains(&paper), "{paper}");
    // Bytes: f16 images, f32 coefficients, means and the sky's two f32 images, against
    // the lit keys in f32.
    let bytes = 3.0 * (4.0 * t_all + 4.0 * kf * t_all + 2.0 * kf * n) + 2.0 * 4.0 * 3.0 * n;
    assert_eq!(c.stored_bytes, bytes);
    assert!((c.of_bytes() - (1.0 - bytes / (4.0 * 3.0 * tl * n))).abs() < 1e-12);
    // The sky's images weigh in bytes, not in the keys' values.
    let mut no_sky = pca_file(lit, texels, k);
    no_sky.sections.retain(|s| !s.name.starts_with("sky"));
    let d = no_sky.compression().expect("a pca file");
    assert_eq!(d.key_values, c.key_values);
    assert!(d.of_bytes() > c.of_bytes());
    // No lit key, or a partial file: nothing to compare with.
    let mut dark = pca_file(0, 4, 1);
    assert!(dark.compression().is_none());
    dark = pca_file(5, 4, 1);
    dark.header.kind = "partial".into();
    assert!(dark.compression().is_none());
}
