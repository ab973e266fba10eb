//! Fixtures shared by the modules of this test binary.

use std::process::Command;

/// The variable naming the one test a child process of this binary runs.
const ALONE: &str = "ILLUME_TEST_ALONE";

/// Whether the caller, the test at `path` (`module::test_name`), should run its body here.
///
/// A test that measures the whole process (resident memory) or exits it (a watchdog)
/// cannot share it with the other tests of this binary, which run in parallel threads.
/// Called first in such a test: in the test harness's own process it runs this binary
/// again with only `path` selected, in a process of its own, fails if that run fails (or
/// selects no test), and returns `false`; in that child process it returns `true`.
pub fn in_own_process(path: &str) -> bool {
    if std::env::var(ALONE).is_ok_and(|p| p == path) {
        return true;
    }
    let exe = std::env::current_exe().expect("the test binary's path");
    let out = Command::new(exe)
        .args([path, "--exact", "--nocapture", "--test-threads=1"])
        .env(ALONE, path)
        .output()
        .expect("the test binary runs again");
    let (stdout, stderr) = (
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr),
    );
    eprint!("{stderr}");
    assert!(
        out.status.success() && stdout.contains("1 passed"),
        "{path} in its own process: {}\n{stdout}",
        out.status
    );
    false
}

/// 60 VSLs placed on `scene` with the settings the cell tests share (Cornell box: every
/// object gets several), cells `oriented_cells` or nearest.
pub fn sixty_vsls(
    scene: &illume_scene::Scene,
    oriented_cells: bool,
) -> illume_photon_stream::placement::VslSet {
    illume_photon_stream::placement::VslSet::place(
        scene,
        &illume_photon_stream::placement::PlacementSettings {
            vsl_count: 60,
            oversampling: 0.1,
            triangle_scale: 0.8,
            seed: 5,
            oriented_cells,
        },
    )
}
