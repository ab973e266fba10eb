//! Fixtures shared by the modules of this test binary.

use std::path::PathBuf;
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
