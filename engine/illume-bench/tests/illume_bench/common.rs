//! Fixtures shared by the modules of this test binary.

use std::path::PathBuf;

/// A folder for one test, `illume-bench-NAME-PID` in the system's temporary folder,
/// emptied (the test creates what it needs in it).
pub fn temp_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("illume-bench-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    d
}

/// Run options writing under `root`: the report in `root/report`, the cache in
/// `root/cache`, no notes.
pub fn options_in(root: &std::path::Path, save_frames: bool) -> illume_bench::RunOptions {
    illume_bench::RunOptions {
        output_dir: root.join("report"),
        cache_dir: root.join("cache"),
        save_frames,
        notes: Vec::new(),
    }
}
