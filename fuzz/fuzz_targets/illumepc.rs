//! The `.illumepc` reader (`techniques/precomputed/src/file.rs`) on arbitrary bytes, and
//! what reads a file after it. Every input runs twice:
//!
//! 1. as it is (`PcFile::from_bytes`): magic, version, header checksum, header, sections;
//! 2. with its checksums made right (the header's and each section's, recomputed over the
//!    bytes the header lists), so that the header's fields and the section values reach
//!    the checks behind the checksums — a checksum only proves the bytes are the ones
//!    written. A file that then reads is handed to what `precompute merge` does with a
//!    single part (its memory check, then the merge), and to the run time: `Precomputed::from_file` for `builtin:sun-room`
//!    and a frame's indirect light at several clock times.
//!
//! Every input gives a value or an error, never a panic, an abort or a hang. Run it under
//! an address-space limit (`prlimit --as`, as the corpus runs illume), which the memory
//! checks read.
#![no_main]

use illume_precomputed::file::{Header, MAGIC, PcFile, SectionFormat, fnv1a64};
use illume_precomputed::{Precomputed, PrecomputedSettings};
use illume_transport::{GBuffer, Technique, World};
use std::path::Path;
use std::sync::OnceLock;

/// `builtin:sun-room` (a scene with a sun path), built once.
fn world() -> &'static World {
    static WORLD: OnceLock<World> = OnceLock::new();
    WORLD.get_or_init(|| {
        let scene = illume_scene::load_scene(Path::new("builtin:sun-room"))
            .expect("the builtin scene loads");
        World::new(scene)
    })
}

/// `data` with the header checksum and every section checksum recomputed (the header
/// re-serialised with the new section checksums), or `None` when it has no parsable
/// header.
fn with_checksums(data: &[u8]) -> Option<Vec<u8>> {
    if data.len() < 16 || &data[..8] != MAGIC {
        return None;
    }
    let len = u32::from_le_bytes(data[12..16].try_into().ok()?) as usize;
    let text_end = 16usize.checked_add(len)?;
    let text = std::str::from_utf8(data.get(16..text_end)?).ok()?;
    let mut header: Header = toml::from_str(text).ok()?;
    let body = data.get(text_end + 8..).unwrap_or(&[]);
    let mut at = 0usize;
    for section in &mut header.sections {
        let size = match section.format {
            SectionFormat::F32 => 4,
            SectionFormat::F16 => 2,
        };
        let end = usize::try_from(section.values)
            .ok()?
            .checked_mul(size)?
            .checked_add(at)?
            .min(body.len());
        section.fnv1a64 = format!("{:016x}", fnv1a64(&body[at.min(end)..end]));
        at = end;
    }
    let text = toml::to_string(&header).ok()?;
    let mut out = Vec::with_capacity(24 + text.len() + body.len());
    out.extend_from_slice(&data[..12]);
    out.extend_from_slice(&u32::try_from(text.len()).ok()?.to_le_bytes());
    out.extend_from_slice(text.as_bytes());
    out.extend_from_slice(&fnv1a64(text.as_bytes()).to_le_bytes());
    out.extend_from_slice(body);
    Some(out)
}

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    let path = Path::new("fuzz.illumepc");
    let _ = PcFile::from_bytes(path, data);
    let Some(fixed) = with_checksums(data) else {
        return;
    };
    let Ok(file) = PcFile::from_bytes(path, &fixed) else {
        return;
    };
    // `precompute merge` of one part (a partial file, or adaptive level 0), after the
    // memory check the command makes first.
    let h = &file.header;
    if illume_precomputed::file::check_keys_memory(h.keys.len(), h.width, h.height).is_ok() {
        let _ = illume_precomputed::shard::merge(&[(path.to_path_buf(), file.clone())]);
    }
    // The run time, for the scene the seeds were precomputed for.
    let world = world();
    let (width, height) = match file.header.domain.as_str() {
        "screen" => (file.header.width, file.header.height),
        _ => (8, 6),
    };
    if u64::from(width) * u64::from(height) > 64 * 64 {
        return;
    }
    let Ok(mut technique) = Precomputed::from_file(
        world,
        PrecomputedSettings::default(),
        path,
        file,
        width,
        height,
        std::time::Instant::now(),
    ) else {
        return;
    };
    let Some(sun) = world.scene.sun.as_ref().map(|s| s.settings.clone()) else {
        return;
    };
    for hours in [-1.0, 0.0, 5.25, 12.0, 17.9, 23.99, 24.0, 30.0] {
        let mut at = world.clone();
        let _ = at.set_time(sun.scene_time(hours));
        let gbuffer = GBuffer::rasterize(&at, width, height);
        let _ = technique.indirect(&at, &gbuffer);
    }
});
