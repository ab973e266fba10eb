//! A target built without a test harness (`test = false` in its `Cargo.toml`, which CI's
//! build time asks for where a harness would run nothing) must hold no test: a `#[test]`
//! added under its sources would otherwise never run, silently.

use std::path::{Path, PathBuf};

fn repo_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// Every `Cargo.toml` of the workspace's members (the root manifest's `members` list).
fn member_manifests(root: &Path) -> Vec<PathBuf> {
    let text = std::fs::read_to_string(root.join("Cargo.toml")).expect("the root manifest");
    let members = text
        .split("members = [")
        .nth(1)
        .and_then(|rest| rest.split(']').next())
        .expect("a members list");
    members
        .lines()
        .map(|line| line.split('#').next().unwrap_or("").trim())
        .filter_map(|line| line.strip_prefix('"')?.split('"').next())
        .map(|m| root.join(m).join("Cargo.toml"))
        .collect()
}

/// Every `.rs` file under `dir`.
fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).into_iter().flatten().flatten() {
        let path = entry.path();
        if path.is_dir() {
            rust_files(&path, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
}

#[test]
fn a_target_without_a_test_harness_holds_no_test() {
    let root = repo_root();
    let manifests = member_manifests(&root);
    assert!(manifests.len() >= 10, "members found: {manifests:?}");
    let mut checked = 0;
    let mut errors = Vec::new();
    for manifest in manifests {
        let text = std::fs::read_to_string(&manifest).expect("a member manifest");
        if !text
            .lines()
            .any(|l| l.trim().replace(' ', "") == "test=false")
        {
            continue;
        }
        checked += 1;
        let mut files = Vec::new();
        rust_files(&manifest.parent().unwrap().join("src"), &mut files);
        for file in files {
            let source = std::fs::read_to_string(&file).expect("a source file");
            if source.contains("#[test]") || source.contains("#[cfg(test)]") {
                errors.push(format!(
                    "{} holds a test, but {} builds no test harness (test = false)",
                    file.display(),
                    manifest.display()
                ));
            }
        }
    }
    assert!(checked >= 2, "only {checked} manifests with test = false");
    assert!(errors.is_empty(), "{}", errors.join("\n"));
}
