"""The Python package against analytic answers and the command line (issue 37).

The CLI comparisons run the `illume` binary named by ILLUME_BIN (.ci/run sets it to the
one its tests built); without it they fail, never skip. Images are tiny: the whole file
runs in seconds.
"""

import os
import signal
import subprocess
import threading
import time
import _thread

import numpy as np
import pytest

import illume


def cli(*args, check=True):
    """Runs `illume ARGS`; returns the completed process."""
    binary = os.environ.get("ILLUME_BIN")
    assert binary and os.path.exists(binary), (
        "set ILLUME_BIN to the illume binary (cargo build -p illume)"
    )
    p = subprocess.run([binary, *args], capture_output=True, text=True, timeout=300)
    if check:
        assert p.returncode == 0, p.stderr
    return p


def cli_error(*args):
    """The message `illume ARGS` fails with (its `error: ` line, without the prefix)."""
    p = cli(*args, check=False)
    assert p.returncode != 0, f"illume {args} succeeded"
    lines = [l for l in p.stderr.splitlines() if l.startswith("error: ")]
    assert lines, p.stderr
    return lines[-1][len("error: "):]


# --- the furnace -------------------------------------------------------------------

def test_furnace_converges_to_its_analytic_radiance():
    """Inside the closed furnace (albedo 0.5, emission 1) every pixel sees
    L = Le / (1 − ρ) = 2; the path tracer's error falls as samples grow and the mean
    lands within 1 % of 2."""
    errors = []
    for spp in (2, 32):
        img = illume.render("builtin:furnace", "reference", spp=spp, width=16, height=12, seed=1)
        assert img.shape == (12, 16, 3) and img.dtype == np.float32
        errors.append(float(np.sqrt(np.mean((img - 2.0) ** 2))))
    assert errors[1] < errors[0] * 0.5, errors
    assert abs(float(img.mean()) - 2.0) < 0.02, img.mean()


def test_furnace_through_the_engine_settles_on_the_analytic_radiance():
    """Frames of the reference technique stepped by an Engine accumulate toward 2."""
    engine = illume.Engine("builtin:furnace", "reference", width=8, height=6, seed=3)
    for _ in range(8):
        img, counters = engine.step()
    assert counters["reference.spp"] >= 8, counters
    assert abs(float(img.mean()) - 2.0) < 0.05, img.mean()


# --- the same frame as the command line ----------------------------------------------

def test_reference_still_equals_the_cli_bit_for_bit(tmp_path):
    out = tmp_path / "cli.exr"
    cli("render", "builtin:cornell-spot", "--technique", "reference", "--spp", "4",
        "--width", "20", "--height", "15", "--seed", "7", "-o", str(out))
    ours = illume.render("builtin:cornell-spot", "reference", spp=4, width=20, height=15, seed=7)
    theirs = illume.read_image(out)
    assert ours.dtype == theirs.dtype == np.float32
    assert np.array_equal(ours, theirs), np.abs(ours - theirs).max()


def test_technique_still_with_settings_equals_the_cli(tmp_path):
    """photon_stream through the same --set as the CLI: same image within 1e-6 relative
    (its still is deterministic; the bound is for float sums across threads)."""
    out = tmp_path / "cli.exr"
    cli("render", "builtin:cornell-spot", "--technique", "photon_stream", "--set",
        "photon_stream.vsl_count=40", "--width", "16", "--height", "12", "--seed", "5",
        "-o", str(out))
    ours = illume.render("builtin:cornell-spot", "photon_stream", width=16, height=12,
                         seed=5, vsl_count=40)
    theirs = illume.read_image(out)
    scale = float(np.abs(theirs).max())
    assert scale > 0
    assert float(np.abs(ours - theirs).max()) <= 1e-6 * scale


# --- edits ---------------------------------------------------------------------------

def screen_disc(scene, centre, radius, width, height):
    """Pixels (as a boolean mask) within the projected disc of a sphere."""
    cam = scene.camera()
    camera_from_world = np.linalg.inv(cam["transform"])
    p = camera_from_world @ np.array([*centre, 1.0])
    depth = -p[2]
    f = (height / 2) / np.tan(np.radians(cam["yfov_deg"]) / 2)
    cx, cy = width / 2 + f * p[0] / depth, height / 2 - f * p[1] / depth
    r = f * radius / depth + 1.5
    ys, xs = np.mgrid[0:height, 0:width] + 0.5
    return (xs - cx) ** 2 + (ys - cy) ** 2 <= r * r


def test_moving_an_instance_changes_the_image_where_it_moved():
    """Engine.apply moves the sphere of cornell-spot; the frame changes most where the
    sphere was and now is, far more than on the far walls."""
    w, h = 48, 36
    engine = illume.Engine("builtin:cornell-spot", "reference", width=w, height=h, seed=2,
                           settings={"spp_per_frame": 4})
    before, _ = engine.step()
    scene = engine.scene
    old = next(i for i in scene.instances() if i["name"] == "sphere")["translation"]
    new = (old[0] + 0.8, old[1], old[2])
    changes = engine.apply(illume.Edit.move_instance("sphere", translation=new))
    assert changes == ["instance %d moved" % next(
        i["index"] for i in scene.instances() if i["name"] == "sphere")]
    after, _ = engine.step()
    diff = np.abs(after - before).sum(axis=2)
    moved = screen_disc(scene, old, 0.3, w, h) | screen_disc(scene, new, 0.3, w, h)
    assert moved.any() and (~moved).any()
    top = np.zeros_like(moved)
    top[: h // 4] = True  # ceiling and the top of the back wall
    assert diff[moved].mean() > 10 * diff[top & ~moved].mean(), (
        diff[moved].mean(), diff[top & ~moved].mean())
    # The engine's scene has the sphere where it was put.
    now = next(i for i in engine.scene.instances() if i["name"] == "sphere")["translation"]
    assert np.allclose(now, new)


def test_scene_edits_reach_a_still():
    """Recolouring the sphere on a Scene changes the still; light intensity scales it."""
    scene = illume.Scene("builtin:cornell-spot")
    base = illume.render(scene, "reference", spp=2, width=16, height=12, seed=1)
    brighter = scene.copy()
    light = brighter.lights()[0]["name"]
    brighter.apply(illume.Edit.set_light_intensity(light, 2 * np.array(brighter.lights()[0]["intensity"]).max()))
    lit = illume.render(brighter, "reference", spp=2, width=16, height=12, seed=1)
    assert lit.mean() > 1.5 * base.mean()


# --- bad input -----------------------------------------------------------------------

@pytest.mark.parametrize("setting, cli_set", [
    ({"nope": 1}, "reference.nope=1"),
    ({"spp": 0}, "reference.spp=0"),
    ({"render.widht": 3}, "render.widht=3"),
])
def test_bad_settings_raise_value_error_with_the_cli_message(setting, cli_set):
    message = cli_error("render", "builtin:furnace", "--technique", "reference",
                        "--set", cli_set, "-o", "/tmp/unused.png")
    with pytest.raises(ValueError) as e:
        illume.render("builtin:furnace", "reference", width=4, height=4, settings=setting)
    assert str(e.value) == message


def test_a_nan_setting_names_its_key():
    message = cli_error("render", "builtin:furnace", "--technique", "photon_stream",
                        "--set", "photon_stream.triangle_scale=nan", "-o", "/tmp/unused.png")
    with pytest.raises(ValueError) as e:
        illume.Engine("builtin:furnace", "photon_stream",
                      settings={"triangle_scale": float("nan")})
    assert str(e.value) == message
    assert "triangle_scale" in message


def test_unknown_technique_and_scene_raise_value_error():
    with pytest.raises(ValueError, match="unknown technique 'nope'"):
        illume.Engine("builtin:furnace", "nope")
    with pytest.raises(ValueError, match="builtin:nope"):
        illume.Scene("builtin:nope")
    with pytest.raises(ValueError, match="no-such-file.gltf"):
        illume.render("no-such-file.gltf")


def test_an_edit_of_a_missing_instance_raises_value_error_naming_it():
    engine = illume.Engine("builtin:cornell-spot", "reference", width=8, height=6)
    with pytest.raises(ValueError, match='no instance named "teapot" \\(have: .*sphere'):
        engine.apply(illume.Edit.move_instance("teapot", translation=(0, 0, 0)))
    with pytest.raises(ValueError, match="sets nothing"):
        illume.Edit.move_instance("sphere")
    with pytest.raises(ValueError, match="not finite"):
        illume.Edit.look_from((0, float("nan"), 0), (0, 0, 0))


def test_arrays_of_the_wrong_shape_or_dtype_raise_value_error_naming_the_argument():
    good = np.ones((4, 5, 3), np.float32)
    with pytest.raises(ValueError, match="^test: shape \\(4, 5\\)"):
        illume.compare(good, np.ones((4, 5)))
    with pytest.raises(ValueError, match="^reference: dtype int64"):
        illume.compare(np.ones((4, 5, 3), np.int64), good)
    with pytest.raises(ValueError, match="size"):
        illume.compare(good, np.ones((5, 4, 3), np.float32))
    with pytest.raises(ValueError, match="unknown metric|nope"):
        illume.compare(good, good, ["nope"])
    with pytest.raises(ValueError, match="^image: shape"):
        illume.write_image("/tmp/x.exr", np.ones((2, 2, 4), np.float32))


def test_a_panic_is_a_runtime_error():
    with pytest.raises(RuntimeError, match="internal error in illume"):
        illume._illume.panic_for_test()


# --- images and metrics --------------------------------------------------------------

def test_exr_round_trips_and_compare_matches_the_cli(tmp_path):
    rng = np.random.default_rng(0)
    a = rng.random((6, 7, 3), dtype=np.float32) * 3
    b = a + rng.normal(0, 0.1, a.shape).astype(np.float32)
    illume.write_image(tmp_path / "a.exr", a)
    illume.write_image(tmp_path / "b.exr", b)
    assert np.array_equal(illume.read_image(tmp_path / "a.exr"), a)
    ours = illume.compare(a, b, ["rmse", "hdr-flip"])
    assert abs(ours["rmse"] - float(np.sqrt(np.mean((a - b) ** 2)))) < 1e-6
    out = cli("compare", str(tmp_path / "a.exr"), str(tmp_path / "b.exr"),
              "--metric", "rmse,hdr-flip").stdout
    for line in out.splitlines()[:2]:
        name, value = line.split()
        assert abs(ours[name] - float(value)) < 1e-6, (name, value, ours)
    illume.write_image(tmp_path / "a.png", a)
    png = illume.read_image(tmp_path / "a.png")
    assert png.shape == a.shape and 0 <= png.min() and png.max() <= 1


# --- threads, Ctrl-C, progress -------------------------------------------------------

def test_other_threads_run_while_a_render_is_in_progress():
    """The main thread keeps ticking while another renders: the longest gap between its
    ticks is a small part of the render's time (a render holding the GIL would stop it
    for the whole render)."""
    done = threading.Event()
    span = {}

    def work():
        t0 = time.perf_counter()
        # 1024 spp: ≈ 1 s on the slow days of a 2-core CI machine, above the 0.3 s the
        # test needs on a fast one (256 spp took 0.28 s on a quiet day and failed it).
        illume.render("builtin:cornell-spot", "reference", spp=1024, width=48, height=36)
        span["render"] = time.perf_counter() - t0
        done.set()

    worker = threading.Thread(target=work)
    ticks = []
    worker.start()
    while not done.is_set():
        ticks.append(time.perf_counter())
        time.sleep(0.001)
    worker.join()
    assert span["render"] > 0.3, span
    assert len(ticks) > 50, (len(ticks), span)  # a render holding the GIL: 0 or 1 tick
    gap = max(np.diff(ticks))
    assert gap < span["render"] / 4, (gap, span)


def test_ctrl_c_stops_a_long_render():
    """KeyboardInterrupt (what Ctrl-C raises) stops a render at the next progress report
    (the reference reports every 1/32 of its samples), long before it would finish.

    The interrupt is sent from another thread 50 ms after the first report, so it lands
    while the engine works whatever the machine's speed (a timer started before the call
    fired after a 16 384-sample render had already finished on a quiet CI machine).

    Python's own SIGINT handler is installed for the test: a process started in the
    background by a non-interactive shell inherits SIGINT ignored, and then Python installs
    no handler and `interrupt_main` does nothing (the render ran to its end)."""
    spp = 1 << 16
    seen = []
    timers = []
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)

    def progress(what, done, total):
        seen.append(done)
        if not timers:
            timers.append(threading.Timer(0.05, _thread.interrupt_main))
            timers[0].start()

    try:
        with pytest.raises(KeyboardInterrupt):
            illume.render("builtin:cornell-spot", "reference", spp=spp, width=16, height=12,
                          progress=progress)
    finally:
        for t in timers:
            t.cancel()
        signal.signal(signal.SIGINT, previous)
    assert seen and seen[-1] < spp // 2, seen


def test_progress_is_reported_and_its_exception_stops_the_work():
    seen = []
    illume.render("builtin:furnace", "reference", spp=64, width=4, height=4,
                  progress=lambda what, done, total: seen.append((what, done, total)))
    assert seen[0] == ("path tracing", 0, 64) and seen[-1][1] == 64

    def stop(what, done, total):
        if done > 0:
            raise ZeroDivisionError("stop here")

    with pytest.raises(ZeroDivisionError, match="stop here"):
        illume.render("builtin:furnace", "reference", spp=64, width=4, height=4, progress=stop)


# --- bench ---------------------------------------------------------------------------

def test_a_bench_scenario_runs_into_dicts_and_arrays(tmp_path):
    scenario = tmp_path / "tiny.toml"
    scenario.write_text(
        'name = "tiny"\nscene = "builtin:cornell-spot"\nanimation = "move_light"\n'
        'width = 8\nheight = 6\ntimes_s = [0.0, 0.5]\nmetrics = ["rmse"]\n'
        '[reference]\nspp = 4\n[[technique]]\nname = "reference"\nwork = 1\n'
    )
    result = illume.bench(scenario, cache=tmp_path / "cache")
    assert result["name"] == "tiny"
    assert list(result["times_s"]) == [0.0, 0.5]
    series = result["series"]["reference"]
    assert series["technique"] == "reference"
    assert series["frames"]["rmse"].shape == (2,)
    assert np.all(np.isfinite(series["frames"]["rmse"]))
    assert result["cache_renders"] == 2
    # Two samples a pixel in each half of a 4-spp reference: their difference is noise.
    mean, worst = result["reference_noise"]["rmse"]
    assert 0.0 < mean <= worst
