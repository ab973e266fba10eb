//! Shared by the targets: the input is written to a file with the extension the reader
//! dispatches on (the loaders read paths), one file per process, reused.

use std::path::PathBuf;

/// Writes `data` to this process's scratch file named `input.EXT` and returns its path.
pub fn scratch_file(ext: &str, data: &[u8]) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("illume-fuzz-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("the scratch folder can be made");
    let path = dir.join(format!("input.{ext}"));
    std::fs::write(&path, data).expect("the scratch file can be written");
    path
}
