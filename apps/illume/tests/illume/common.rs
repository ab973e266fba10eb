//! Fixtures shared by the modules of this test binary.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// Runs the `illume` binary of this build with `args`.
pub fn illume(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_illume"))
        .args(args)
        .output()
        .expect("the illume binary runs")
}

/// A fresh empty folder for one test, `name` in the module's `group`.
pub fn scratch(group: &str, name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("illume-{group}-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Asserts that an `illume` run succeeded, showing its stderr when it did not.
pub fn ok(out: &Output) {
    assert!(
        out.status.success(),
        "illume failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// A path as the `&str` argument the binary takes (test paths are UTF-8).
pub fn path(p: &Path) -> &str {
    p.to_str().unwrap()
}
