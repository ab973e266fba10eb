//! `illume view` in a real window: an X server (Xvfb in CI, started by `.ci/run`), Mesa's
//! software Vulkan, xdotool for input and ImageMagick's `import` for screenshots of the
//! X server. Without them these tests fail, naming what is missing; they never skip.
#![cfg(feature = "view")]

use illume_core::image::{RgbImage, read_ldr};
use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::mpsc::{Receiver, channel};
use std::sync::{Mutex, MutexGuard};
use std::time::{Duration, Instant, SystemTime, UNIX_EPOCH};

/// One window at a time: the tests share one X server and its keyboard focus.
static DISPLAY_LOCK: Mutex<()> = Mutex::new(());

fn exe() -> &'static str {
    env!("CARGO_BIN_EXE_illume")
}

/// The display lock, after checking that a display and the tools are there.
fn display() -> MutexGuard<'static, ()> {
    let guard = DISPLAY_LOCK.lock().unwrap_or_else(|e| e.into_inner());
    let display = std::env::var("DISPLAY").unwrap_or_default();
    assert!(
        !display.is_empty(),
        "DISPLAY is not set: the viewer tests need an X server (.ci/run starts `Xvfb :99`; \
         locally: `Xvfb :99 -screen 0 1280x1024x24 & export DISPLAY=:99`)"
    );
    for tool in ["xdotool", "import"] {
        let found = Command::new("sh")
            .args(["-c", &format!("command -v {tool}")])
            .output()
            .is_ok_and(|o| o.status.success());
        assert!(
            found,
            "{tool} is missing: run scripts/ci/install-viewer-deps.sh (xdotool, imagemagick)"
        );
    }
    guard
}

fn out_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("illume-view-test-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn now_ms() -> f64 {
    SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .unwrap()
        .as_secs_f64()
        * 1e3
}

/// A running viewer with its stderr lines on a channel.
struct Viewer {
    child: Child,
    lines: Receiver<String>,
    log: Vec<String>,
}

impl Viewer {
    fn start(args: &[&str]) -> Self {
        let mut child = Command::new(exe())
            .arg("view")
            .args(args)
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .expect("illume view starts");
        let stderr = child.stderr.take().unwrap();
        let (tx, rx) = channel();
        std::thread::spawn(move || {
            for line in BufReader::new(stderr).lines().map_while(Result::ok) {
                if tx.send(line).is_err() {
                    break;
                }
            }
        });
        Self {
            child,
            lines: rx,
            log: Vec::new(),
        }
    }

    /// Waits (at most `timeout`) for a line satisfying `f`; returns it.
    fn wait_for(&mut self, timeout: Duration, what: &str, f: impl Fn(&str) -> bool) -> String {
        let end = Instant::now() + timeout;
        loop {
            let left = end.saturating_duration_since(Instant::now());
            match self.lines.recv_timeout(left) {
                Ok(line) => {
                    self.log.push(line.clone());
                    if f(&line) {
                        return line;
                    }
                }
                Err(_) => {
                    let _ = self.child.kill();
                    panic!(
                        "timed out waiting for {what}; the viewer said:\n{}",
                        self.log.join("\n")
                    );
                }
            }
        }
    }

    /// Waits for a shown frame whose reference has all its samples.
    fn wait_converged(&mut self, after_commands: u64) -> String {
        self.wait_for(Duration::from_secs(60), "a converged frame", |l| {
            field(l, "commands").is_some_and(|c| c >= after_commands as f64)
                && l.contains(" spp=")
                && spp(l).is_some_and(|(s, t)| s >= t)
        })
    }

    /// A viewer on `args` at [`SIZE`], its window's id once it has shown a first frame.
    fn open_small(args: &[&str]) -> (Self, String) {
        let mut viewer = Self::start(&[args, &SIZE].concat());
        let id = viewer.window();
        viewer.wait_for(Duration::from_secs(60), "a first frame", |l| {
            l.contains("render_ms=")
        });
        (viewer, id)
    }

    /// Waits (at most `timeout`) until no frame is shown for `quiet`; returns the last
    /// frame line seen before the quiet.
    fn wait_quiet(&mut self, quiet: Duration, timeout: Duration, what: &str) -> String {
        let end = Instant::now() + timeout;
        let mut last_frame = String::new();
        loop {
            match self.lines.recv_timeout(quiet) {
                Ok(line) => {
                    self.log.push(line.clone());
                    if line.contains("render_ms=") {
                        last_frame = line;
                    }
                }
                Err(_) => return last_frame,
            }
            if Instant::now() > end {
                let _ = self.child.kill();
                let frames = self.log.iter().filter(|l| l.contains("render_ms=")).count();
                panic!(
                    "{what}: frames still shown after {timeout:?} ({frames} in all); the last \
                     lines:\n{}",
                    self.log[self.log.len().saturating_sub(5)..].join("\n")
                );
            }
        }
    }

    /// CPU seconds (user + system) the viewer's process has used so far.
    fn cpu_s(&self) -> f64 {
        let stat = std::fs::read_to_string(format!("/proc/{}/stat", self.child.id()))
            .expect("the viewer's /proc stat");
        // Fields after the command name (in parentheses): utime and stime are the 12th
        // and 13th, in clock ticks (100 a second on Linux).
        let rest = &stat[stat.rfind(')').expect("(comm)") + 2..];
        let f: Vec<f64> = rest
            .split_whitespace()
            .skip(11)
            .take(2)
            .map(|v| v.parse().unwrap())
            .collect();
        (f[0] + f[1]) / 100.0
    }

    fn window(&mut self) -> String {
        // The window exists once the adapter line is printed.
        self.wait_for(Duration::from_secs(30), "the adapter line", |l| {
            l.contains("adapter")
        });
        let end = Instant::now() + Duration::from_secs(10);
        loop {
            // This viewer's window: a window of the test before may not be gone yet.
            let pid = self.child.id().to_string();
            let out = Command::new("xdotool")
                .args(["search", "--pid", &pid, "--name", "illume view"])
                .output()
                .unwrap();
            let id = String::from_utf8_lossy(&out.stdout)
                .lines()
                .next()
                .map(str::to_owned);
            if let Some(id) = id {
                return id;
            }
            assert!(
                Instant::now() < end,
                "no window named 'illume view' of process {}",
                self.child.id()
            );
            std::thread::sleep(Duration::from_millis(100));
        }
    }

    fn finish(mut self) -> Vec<String> {
        let _ = self.child.kill();
        let _ = self.child.wait();
        self.log.extend(self.lines.try_iter());
        self.log
    }
}

/// `name=value` of a log line, as a number.
fn field(line: &str, name: &str) -> Option<f64> {
    line.split_whitespace()
        .find_map(|w| w.strip_prefix(&format!("{name}=")))
        .and_then(|v| v.parse().ok())
}

/// The renderer's number of the frame a `frame N …` line shows.
fn frame_index(line: &str) -> u64 {
    line.split_whitespace()
        .nth(3)
        .and_then(|v| v.parse().ok())
        .unwrap_or_else(|| panic!("no frame number in {line:?}"))
}

/// `spp=S/T` of a frame line.
fn spp(line: &str) -> Option<(u32, u32)> {
    let v = line
        .split_whitespace()
        .find_map(|w| w.strip_prefix("spp="))?;
    let (s, t) = v.split_once('/')?;
    Some((s.parse().ok()?, t.parse().ok()?))
}

fn xdotool(args: &[&str]) {
    let st = Command::new("xdotool").args(args).status().unwrap();
    assert!(st.success(), "xdotool {args:?} failed");
}

/// Gives the window the keyboard focus (xdotool's synthetic `--window` events are
/// ignored by winit; real key events go to the focused window).
fn focus(id: &str) {
    xdotool(&["windowfocus", "--sync", id]);
}

/// Window position on the root window (no window manager: the client area's origin).
fn window_origin(id: &str) -> (u32, u32) {
    let out = Command::new("xdotool")
        .args(["getwindowgeometry", "--shell", id])
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    let get = |k: &str| {
        text.lines()
            .find_map(|l| l.strip_prefix(&format!("{k}=")))
            .and_then(|v| v.parse().ok())
            .unwrap_or(0)
    };
    (get("X"), get("Y"))
}

fn render(args: &[&str], out: &Path) {
    let st = Command::new(exe())
        .arg("render")
        .args(args)
        .arg("-o")
        .arg(out)
        .stderr(Stdio::null())
        .status()
        .unwrap();
    assert!(st.success(), "illume render {args:?} failed");
}

/// Largest and mean difference \[8-bit levels\] between the PNG at `a` and the
/// `w × h` block of `b` at (`x0`, `y0`).
fn diff_levels(a: &Path, b: &image::RgbImage, x0: u32, y0: u32) -> (f64, f64) {
    let a = image::open(a).unwrap().to_rgb8();
    let (mut max, mut sum) = (0.0f64, 0.0f64);
    for (x, y, p) in a.enumerate_pixels() {
        let q = b.get_pixel(x0 + x, y0 + y);
        for c in 0..3 {
            let d = (p[c] as f64 - q[c] as f64).abs();
            max = max.max(d);
            sum += d;
        }
    }
    (max, sum / (3 * a.width() * a.height()) as f64)
}

const SIZE: [&str; 4] = ["--width", "160", "--height", "120"];

#[test]
fn screenshot_equals_render_and_the_window_shows_it() {
    let _display = display();
    let dir = out_dir("screenshot");
    let rendered = dir.join("render.png");
    let mut args = vec![
        "builtin:cornell-spot",
        "--technique",
        "reference",
        "--spp",
        "64",
    ];
    args.extend(SIZE);
    render(&args, &rendered);
    let shot = dir.join("view.png");
    let mut viewer = Viewer::start(
        &[
            args.as_slice(),
            &[
                "--screenshot",
                shot.to_str().unwrap(),
                "--exit-after-frames",
                "3",
                "--linger-ms",
                "3000",
            ],
        ]
        .concat(),
    );
    let id = viewer.window();
    viewer.wait_for(Duration::from_secs(60), "the screenshot", |l| {
        l.contains("wrote") && l.contains("view.png")
    });
    // The window shows the frame: a screenshot of the X server, cropped to the viewport.
    std::thread::sleep(Duration::from_millis(300));
    let root = dir.join("root.png");
    let st = Command::new("import")
        .args(["-window", "root"])
        .arg(&root)
        .status()
        .unwrap();
    assert!(st.success(), "import -window root failed");
    let status = viewer.child.wait().unwrap();
    assert!(status.success(), "illume view exited with {status}");

    // Same view, same settings: the same image within noise (same samples: identical).
    let a = read_ldr(&rendered).unwrap();
    let b = read_ldr(&shot).unwrap();
    let rmse = illume_metrics::rmse(&a, &b).unwrap();
    assert!(rmse < 1e-3, "view screenshot vs render: RMSE {rmse}");
    assert!(a.mean().length() > 0.01, "the render is black");
    let exr = illume_core::image::read_exr(&shot.with_extension("exr")).unwrap();
    assert_eq!((exr.width(), exr.height()), (160, 120));

    let (x, y) = window_origin(&id);
    let root_img = image::open(&root).unwrap().to_rgb8();
    let (max, mean) = diff_levels(&shot, &root_img, x, y);
    assert!(
        mean < 0.5 && max <= 2.0,
        "the window's viewport differs from the screenshot: mean {mean:.2}, max {max} levels (window at {x},{y})"
    );
}

#[test]
fn keys_switch_technique_and_reference_converges_to_render() {
    let _display = display();
    let dir = out_dir("keys");
    let rendered = dir.join("reference.png");
    let mut args = vec![
        "builtin:cornell-spot",
        "--technique",
        "reference",
        "--spp",
        "16",
    ];
    args.extend(SIZE);
    render(&args, &rendered);
    let mut view_args = vec![
        "builtin:cornell-spot",
        "--technique",
        "photon_stream",
        "--spp",
        "16",
        "--log-input",
        "--output",
    ];
    view_args.push(dir.to_str().unwrap());
    view_args.extend(SIZE);
    let mut viewer = Viewer::start(&view_args);
    let id = viewer.window();
    let first = viewer.wait_for(Duration::from_secs(60), "a photon_stream frame", |l| {
        l.contains("technique=photon_stream")
    });
    assert!(first.contains("spp=none"), "{first}");
    focus(&id);
    // R: reference mode; it converges to the render of the reference.
    xdotool(&["key", "r"]);
    viewer.wait_for(Duration::from_secs(10), "R handled", |l| {
        l.contains("key R")
    });
    viewer.wait_converged(1);
    xdotool(&["key", "p"]);
    viewer.wait_for(Duration::from_secs(10), "the screenshot", |l| {
        l.contains("wrote") && l.contains("screenshot_001.png")
    });
    let a = read_ldr(&rendered).unwrap();
    let b = read_ldr(&dir.join("screenshot_001.png")).unwrap();
    let rmse = illume_metrics::rmse(&a, &b).unwrap();
    assert!(
        rmse < 1e-3,
        "reference mode vs render --technique reference: RMSE {rmse}"
    );
    // R again: back to the technique, whose image differs from the reference.
    xdotool(&["key", "r"]);
    viewer.wait_for(Duration::from_secs(30), "the technique again", |l| {
        l.contains("technique=photon_stream") && l.contains("spp=none")
    });
    // T: the next technique.
    xdotool(&["key", "t"]);
    let next = viewer.wait_for(Duration::from_secs(60), "another technique", |l| {
        l.contains("technique=") && !l.contains("technique=photon_stream")
    });
    assert!(next.contains("technique=selective"), "{next}");
    viewer.finish();
}

#[test]
fn the_window_handles_input_while_a_frame_takes_seconds() {
    let _display = display();
    let mut args = vec![
        "builtin:cornell-spot",
        "--technique",
        "reference",
        "--set",
        "reference.spp_per_frame=128",
        "--spp",
        "100000",
        "--log-input",
        "--width",
        "200",
        "--height",
        "150",
    ];
    args.extend(["--exposure", "0"]);
    let mut viewer = Viewer::start(&args);
    let id = viewer.window();
    let first = viewer.wait_for(Duration::from_secs(120), "a first frame", |l| {
        l.contains("render_ms=")
    });
    let frame_ms = field(&first, "render_ms").unwrap();
    assert!(
        frame_ms >= 1000.0,
        "a frame should take ≥ 1 s here: {first}"
    );
    // The viewer logs a frame when it takes it, then draws it: the first draw of an image
    // (the frame texture's creation, lavapipe's first run of the display pipeline) is a
    // one-time cost — a first key waited 61–118 ms behind it in two CI runs — and not
    // the steady state measured here; let it pass (frames take ≥ 1 s, so the next one
    // is still rendering).
    std::thread::sleep(Duration::from_millis(800));
    focus(&id);
    // One key first, not timed: the sleep above did not always cover that one-time cost
    // (the first timed key waited 70 ms once more in a clean-clone CI run, the four after
    // it 1–9 ms), and a focus change may cost the first key too. A viewer that waited for
    // frames to handle input would fail every key below by seconds.
    xdotool(&["key", "equal"]);
    viewer.wait_for(
        Duration::from_secs(5),
        "the untimed first key handled",
        |l| l.contains("input key") && l.contains("handled_unix_ms="),
    );
    std::thread::sleep(Duration::from_millis(150));
    // Latency: from the key's sending to the viewer's log line. xdotool sends the key
    // at the end of its run, after starting up and connecting to the X server; that cost
    // is measured before each key with a no-op run (`getmouselocation`) and taken off.
    let mut latencies = Vec::new();
    let mut raw = Vec::new();
    for _ in 0..5 {
        let t = now_ms();
        xdotool(&["getmouselocation"]);
        let startup = now_ms() - t;
        let sent = now_ms() + startup;
        xdotool(&["key", "equal"]);
        let line = viewer.wait_for(Duration::from_secs(5), "the key handled", |l| {
            l.contains("input key") && l.contains("handled_unix_ms=")
        });
        let handled = field(&line, "handled_unix_ms").unwrap();
        latencies.push(handled - sent);
        raw.push(handled - (sent - startup));
        std::thread::sleep(Duration::from_millis(150));
    }
    let log = viewer.finish();
    let frames = log.iter().filter(|l| l.contains("render_ms=")).count();
    eprintln!(
        "input latencies {latencies:?} ms (with xdotool's start-up: {raw:?}) while frames take {frame_ms:.0} ms; {frames} frames shown"
    );
    // The property tested is that input does not wait for frames: a viewer that did
    // would answer after up to a whole frame (≥ 1 s). A quarter of a frame tells the two
    // apart on a loaded machine too; the responsiveness itself (printed above) belongs to
    // a benchmark, not a test bound (issue 38: a 50 ms bound failed under load).
    let mut sorted = latencies.clone();
    sorted.sort_by(f64::total_cmp);
    let median = sorted[sorted.len() / 2];
    assert!(
        median < 0.25 * frame_ms,
        "input handled after a median {median:.1} ms, frames take {frame_ms:.0} ms (all: {latencies:?})"
    );
}

/// Mean absolute luminance difference of two linear images over pixels `[x0, x1) × [y0, y1)`.
fn region_change(a: &RgbImage, b: &RgbImage, (x0, x1, y0, y1): (u32, u32, u32, u32)) -> f64 {
    let mut sum = 0.0;
    for y in y0..y1 {
        for x in x0..x1 {
            sum += (illume_core::luminance(*a.get(x, y)) - illume_core::luminance(*b.get(x, y)))
                .abs() as f64;
        }
    }
    sum / ((x1 - x0) * (y1 - y0)) as f64
}

#[test]
fn keys_move_the_clicked_object_and_only_its_light_changes() {
    let _display = display();
    let dir = out_dir("edit");
    // Noise of the reference at these samples: two seeds of the unchanged scene (far
    // apart: seed s + 1 shares all but one sample sequence with seed s).
    let mut args = vec![
        "builtin:cornell-spot",
        "--technique",
        "reference",
        "--spp",
        "64",
    ];
    args.extend(SIZE);
    render(
        &[args.as_slice(), &["--seed", "1"]].concat(),
        &dir.join("seed1.exr"),
    );
    render(
        &[args.as_slice(), &["--seed", "100000"]].concat(),
        &dir.join("seed2.exr"),
    );
    let mut view_args = args.clone();
    view_args.extend(["--log-input", "--output", dir.to_str().unwrap()]);
    let mut viewer = Viewer::start(&view_args);
    let id = viewer.window();
    viewer.wait_converged(0);
    focus(&id);
    xdotool(&["key", "p"]);
    viewer.wait_for(Duration::from_secs(10), "screenshot 1", |l| {
        l.contains("screenshot_001.png")
    });
    // Click the sphere (it sits at about (50, 85) of the 160×120 image), then → → →.
    xdotool(&["mousemove", "--window", &id, "50", "85", "click", "1"]);
    viewer.wait_for(Duration::from_secs(10), "the click", |l| {
        l.contains("input click")
    });
    for _ in 0..3 {
        xdotool(&["key", "Right"]);
        viewer.wait_for(Duration::from_secs(10), "→", |l| {
            l.contains("key ArrowRight")
        });
    }
    // The reference restarts, then converges on the moved scene.
    viewer.wait_for(Duration::from_secs(30), "a restarted reference", |l| {
        spp(l).is_some_and(|(s, t)| s < t)
    });
    viewer.wait_converged(0);
    xdotool(&["key", "p"]);
    viewer.wait_for(Duration::from_secs(10), "screenshot 2", |l| {
        l.contains("screenshot_002.png")
    });
    let log = viewer.finish();
    assert!(
        !log.iter().any(|l| l.contains("nothing selected")),
        "the click did not select the sphere:\n{}",
        log.join("\n")
    );
    let read = |name: &str| illume_core::image::read_exr(&dir.join(name)).unwrap();
    let (before, after) = (read("screenshot_001.exr"), read("screenshot_002.exr"));
    let noise = region_change(&read("seed1.exr"), &read("seed2.exr"), (0, 160, 0, 45));
    let sphere_was = region_change(&before, &after, (38, 62, 72, 100));
    let right_of_it = region_change(&before, &after, (62, 100, 72, 112));
    let far = region_change(&before, &after, (0, 160, 0, 45));
    eprintln!(
        "luminance change: sphere's old place {sphere_was:.4}, right of it {right_of_it:.4}, upper image {far:.4}; noise {noise:.4}"
    );
    assert!(
        sphere_was > 20.0 * noise.max(far),
        "the sphere did not move away"
    );
    assert!(
        right_of_it > 5.0 * far,
        "nothing changed where the sphere went"
    );
    assert!(
        far <= noise,
        "the upper image changed beyond noise: {far} vs noise {noise}"
    );
}

/// `x,y[,z]` numbers of a `name=` field of a log line.
fn numbers(line: &str, name: &str) -> Option<Vec<f64>> {
    line.split_whitespace()
        .find_map(|w| w.strip_prefix(&format!("{name}=")))
        .map(|v| v.split([',', ';']).filter_map(|x| x.parse().ok()).collect())
}

#[test]
fn dragging_the_gizmo_moves_the_selection_along_the_axis() {
    let _display = display();
    let (mut viewer, id) = Viewer::open_small(&[
        "builtin:cornell-spot",
        "--technique",
        "reference",
        "--spp",
        "2",
        "--log-input",
    ]);
    focus(&id);
    // Select the sphere (about (50, 85) of the 160×120 image); its gizmo appears.
    xdotool(&["mousemove", "--window", &id, "50", "85", "click", "1"]);
    // The frame with the selection is shown, then its gizmo drawn.
    let before = viewer.wait_for(Duration::from_secs(20), "a frame with the selection", |l| {
        l.contains("render_ms=") && !l.contains("pivot=none")
    });
    let gizmo = viewer.wait_for(Duration::from_secs(20), "the gizmo", |l| {
        l.contains("gizmo centre_px=")
    });
    let pivot0 = numbers(&before, "pivot").unwrap();
    let c = numbers(&gizmo, "centre_px").unwrap();
    let axes = numbers(&gizmo, "axes_px").unwrap();
    let length_m = field(&gizmo, "length_m").unwrap();
    // Grab the X handle at 3/4 of its length and drag 40 px along it, in steps.
    let h = (axes[0] - c[0], axes[1] - c[1]);
    let h_len = (h.0 * h.0 + h.1 * h.1).sqrt();
    assert!(h_len > 20.0, "X handle too short on screen: {gizmo}");
    let grab = (c[0] + 0.75 * h.0, c[1] + 0.75 * h.1);
    let drag_px = 40.0;
    let to = |f: f64| {
        let p = (
            grab.0 + f * drag_px * h.0 / h_len,
            grab.1 + f * drag_px * h.1 / h_len,
        );
        [format!("{:.0}", p.0), format!("{:.0}", p.1)]
    };
    let [x, y] = to(0.0);
    xdotool(&["mousemove", "--window", &id, &x, &y, "mousedown", "1"]);
    for i in 1..=8 {
        std::thread::sleep(Duration::from_millis(60));
        let [x, y] = to(i as f64 / 8.0);
        xdotool(&["mousemove", "--window", &id, &x, &y]);
    }
    std::thread::sleep(Duration::from_millis(100));
    xdotool(&["mouseup", "1"]);
    viewer.wait_for(Duration::from_secs(10), "the drag handled", |l| {
        l.contains("input gizmo Axis(0)")
    });
    // The pivot moves along +X by the dragged length (a handle length per handle length
    // dragged; the handle's screen length changes a little as the sphere moves).
    let expected = drag_px / h_len * length_m;
    let after = viewer.wait_for(
        Duration::from_secs(30),
        "a frame of the moved sphere",
        |l| {
            l.contains("render_ms=")
                && numbers(l, "pivot")
                    .is_some_and(|p| p.len() == 3 && p[0] - pivot0[0] > 0.6 * expected)
        },
    );
    std::thread::sleep(Duration::from_millis(500));
    let log = viewer.finish();
    let last = log
        .iter()
        .rev()
        .find(|l| l.contains("render_ms=") && l.contains("pivot="))
        .unwrap_or(&after);
    let pivot1 = numbers(last, "pivot").unwrap();
    let moved = [
        pivot1[0] - pivot0[0],
        pivot1[1] - pivot0[1],
        pivot1[2] - pivot0[2],
    ];
    eprintln!("gizmo drag: moved {moved:?} m, expected {expected:.4} m along X");
    assert!(
        (moved[0] - expected).abs() < 0.3 * expected,
        "moved {moved:?} m, expected {expected:.4} m along X"
    );
    assert!(
        moved[1].abs() < 1e-4 && moved[2].abs() < 1e-4,
        "the X handle moved the sphere off its axis: {moved:?}"
    );
    assert!(
        !log.iter().any(|l| l.contains("input wheel")),
        "no camera input expected"
    );
}

#[test]
fn a_settled_photon_stream_leaves_the_cores_idle_until_the_camera_moves() {
    let _display = display();
    let (mut viewer, id) = Viewer::open_small(&[
        "builtin:cornell-spot",
        "--technique",
        "photon_stream",
        "--log-input",
        "--refine",
        "4",
    ]);
    // The streaming thread rests once its pool has turned over; the viewer then adds
    // the still refinement's frames (jittered pixel centres, averaged) and stops
    // rendering (the scene's animation is paused, nothing moves).
    let quiet = Duration::from_millis(1500);
    let settled = viewer.wait_quiet(quiet, Duration::from_secs(60), "photon_stream settling");
    assert_eq!(
        field(&settled, "refined"),
        Some(4.0),
        "the last frame before the viewer idles averages the 4 refinement frames: {settled}"
    );
    let t0 = Instant::now();
    let cpu0 = viewer.cpu_s();
    std::thread::sleep(Duration::from_secs(2));
    let cpu = (viewer.cpu_s() - cpu0) / t0.elapsed().as_secs_f64();
    assert!(
        cpu < 0.1,
        "an idle viewer used {:.0} % of a core (frames stopped at: {settled})",
        cpu * 100.0
    );
    // A camera move (the wheel dollies) is rendered at once: the photons stay valid, so
    // the thread keeps resting and the frames stop again after it.
    focus(&id);
    xdotool(&["mousemove", "--window", &id, "80", "60", "click", "4"]);
    let before = field(&settled, "commands").unwrap_or(0.0);
    let moved = viewer.wait_for(
        Duration::from_secs(20),
        "a frame after the camera move",
        |l| l.contains("render_ms=") && field(l, "commands").is_some_and(|c| c > before),
    );
    let last = viewer.wait_quiet(quiet, Duration::from_secs(20), "after the camera move");
    // Frames follow commands only (the wheel may send a few camera steps): each command
    // starts the mean over, so at most a frame at pixel centres and the 3 refinement
    // frames after it for each command, and for the frame that finds the technique
    // settled.
    let frames = frame_index(&last).max(frame_index(&moved)) - frame_index(&settled);
    let commands = field(&last, "commands").unwrap_or(0.0) - before;
    assert!(
        frames >= 1 && frames as f64 <= 4.0 * (commands + 1.0),
        "{frames} frames for {commands} commands of a camera move (from {settled} to {last})"
    );
    assert_eq!(field(&last, "refined"), Some(4.0), "{last}");
    viewer.finish();
}

#[test]
fn technique_frames_keep_to_max_fps_while_the_animation_plays() {
    let _display = display();
    let (mut viewer, _id) = Viewer::open_small(&[
        "builtin:cornell-spot",
        "--technique",
        "photon_stream",
        "--play",
        "--max-fps",
        "30",
        "--log-input",
    ]);
    // The renderer numbers every frame it renders; the window logs the ones it shows.
    let is_frame = |l: &str| l.contains("render_ms=");
    let first = viewer.wait_for(Duration::from_secs(20), "a frame", is_frame);
    let t0 = field(&first, "shown_unix_ms").unwrap();
    std::thread::sleep(Duration::from_secs(3));
    // The newest frame line (the channel holds every line since `first`).
    let last = viewer
        .lines
        .try_iter()
        .filter(|l| is_frame(l))
        .last()
        .unwrap_or_else(|| panic!("no frame shown in 3 s of animation"));
    let seconds = (field(&last, "shown_unix_ms").unwrap() - t0) / 1e3;
    let rate = (frame_index(&last) - frame_index(&first)) as f64 / seconds;
    viewer.finish();
    eprintln!("{rate:.1} frames a second rendered over {seconds:.2} s");
    // Unpaced, this 160×120 animation renders a few hundred frames a second; the bound
    // tested is the cap (33 for 30 and the clock's rounding). The floor only says frames
    // kept coming: a loaded 2-core machine can slow them well below 30.
    assert!(
        (1.0..=33.0).contains(&rate),
        "{rate:.1} frames a second rendered with --max-fps 30 (over {seconds:.2} s)"
    );
}
