//! Every technique is its folder, and every folder has the same shape
//! (`techniques/README.md`): one name everywhere, the same inner files, its own test
//! binary with its agreement with the reference, its docs page. Read from the tree, so a
//! technique added without part of the shape fails here by name.

use std::path::{Path, PathBuf};

/// The files every `techniques/NAME/` holds, `NAME` standing for the folder's name.
const FILES: &[&str] = &[
    "Cargo.toml",
    "src/lib.rs",
    "src/settings.rs",
    "src/state.rs",
    "src/update.rs",
    "src/error.rs",
    "tests/NAME/main.rs",
];

/// Techniques whose agreement with the reference is not the shared harness's
/// `builtin:cornell-spot` comparison, each with the reason and where it is instead.
const OWN_AGREEMENT: &[(&str, &str)] = &[
    (
        "precomputed",
        "needs a scene with a sun path and a precomputed day; its agreement test is \
         tests/precomputed/sun_room.rs on builtin:sun-room",
    ),
    (
        "ambient",
        "the test technique, exact only where bounced light is uniform: the engine's unit \
         test runs it through the engine in builtin:furnace against the analytic value",
    ),
];

fn repo_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// The technique folders: every directory under `techniques/`.
fn technique_folders(root: &Path) -> Vec<(String, PathBuf)> {
    let mut folders: Vec<(String, PathBuf)> = std::fs::read_dir(root.join("techniques"))
        .expect("techniques/ is readable")
        .map(|e| e.expect("a directory entry").path())
        .filter(|p| p.is_dir())
        .map(|p| {
            let name = p.file_name().unwrap().to_string_lossy().into_owned();
            (name, p)
        })
        .collect();
    folders.sort();
    folders
}

/// What is missing or misnamed in the folder of technique `name`, one line each.
fn shape_errors(root: &Path, name: &str, dir: &Path) -> Vec<String> {
    let mut errors = Vec::new();
    let read = |rel: &str| std::fs::read_to_string(dir.join(rel)).unwrap_or_default();
    for file in FILES {
        let rel = file.replace("NAME", name);
        if !dir.join(&rel).is_file() {
            errors.push(format!("techniques/{name}/{rel} is missing"));
        }
    }
    let package = format!("name = \"illume-{}\"", name.replace('_', "-"));
    if !read("Cargo.toml").lines().any(|l| l.trim() == package) {
        errors.push(format!(
            "techniques/{name}/Cargo.toml: the package is not `illume-{}`",
            name.replace('_', "-")
        ));
    }
    let constant = format!("pub const NAME: &str = \"{name}\";");
    if !read("src/lib.rs").lines().any(|l| l.trim() == constant) {
        errors.push(format!(
            "techniques/{name}/src/lib.rs does not declare `{constant}`"
        ));
    }
    let docs = root.join(format!("docs/techniques/{name}.md"));
    if !docs.is_file() {
        errors.push(format!("docs/techniques/{name}.md is missing"));
    }
    let tests = dir.join("tests").join(name);
    let calls_the_harness = std::fs::read_dir(&tests).is_ok_and(|entries| {
        entries.filter_map(Result::ok).any(|e| {
            std::fs::read_to_string(e.path()).is_ok_and(|s| s.contains("illume_agreement::"))
        })
    });
    if !calls_the_harness && !OWN_AGREEMENT.iter().any(|(n, _)| *n == name) {
        errors.push(format!(
            "techniques/{name}/tests/{name}/ never calls the agreement harness \
             (illume_agreement::assert_agrees with its tolerance and why)"
        ));
    }
    errors
}

#[test]
fn every_technique_folder_has_the_same_shape_and_one_name() {
    let root = repo_root();
    let folders = technique_folders(&root);
    assert!(
        folders.len() >= 5,
        "techniques/ holds {} folders",
        folders.len()
    );
    let errors: Vec<String> = folders
        .iter()
        .flat_map(|(name, dir)| shape_errors(&root, name, dir))
        .collect();
    assert!(errors.is_empty(), "{}", errors.join("\n"));
}

#[test]
fn the_shape_check_names_what_a_folder_lacks() {
    let root = repo_root();
    let dir = std::env::temp_dir().join(format!("illume-shape-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(dir.join("src")).unwrap();
    std::fs::write(
        dir.join("src/lib.rs"),
        "pub const NAME: &str = \"other\";\n",
    )
    .unwrap();
    let errors = shape_errors(&root, "made_up", &dir).join("\n");
    for expected in [
        "techniques/made_up/Cargo.toml is missing",
        "techniques/made_up/src/update.rs is missing",
        "techniques/made_up/tests/made_up/main.rs is missing",
        "does not declare `pub const NAME: &str = \"made_up\";`",
        "docs/techniques/made_up.md is missing",
        "never calls the agreement harness",
    ] {
        assert!(errors.contains(expected), "{expected:?} not in:\n{errors}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}
