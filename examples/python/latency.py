"""Latency after an edit: how fast three interactive techniques follow a moved object.

Moves the sphere of the built-in Cornell box, then steps photon_stream, selective and
radiance_cache for N frames each, measures every frame's HDR-FLIP against a reference
still of the moved scene, and plots the three curves into a PNG.

    python examples/python/latency.py --frames 30 --width 160 --height 120 -o latency.png

(CI runs it at a tiny size: --frames 3 --width 16 --height 12 --spp 4.)
"""

import argparse
import time

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

import illume  # noqa: E402

TECHNIQUES = ("photon_stream", "selective", "radiance_cache")


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--scene", default="builtin:cornell-spot")
    p.add_argument("--instance", default="sphere", help="the instance to move")
    p.add_argument("--offset", type=float, nargs=3, default=(0.8, 0.0, 0.0),
                   help="how far to move it [m]")
    p.add_argument("--frames", type=int, default=30, help="frames after the edit")
    p.add_argument("--warmup", type=int, default=5, help="frames before the edit")
    p.add_argument("--width", type=int, default=160)
    p.add_argument("--height", type=int, default=120)
    p.add_argument("--spp", type=int, default=256, help="the reference still's samples")
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("-o", "--output", default="latency.png")
    a = p.parse_args()

    scene = illume.Scene(a.scene)
    old = next(i for i in scene.instances() if i["name"] == a.instance)["translation"]
    new = tuple(o + d for o, d in zip(old, a.offset))
    edit = illume.Edit.move_instance(a.instance, translation=new)
    moved = scene.copy()
    moved.apply(edit)
    t0 = time.perf_counter()
    reference = illume.render(moved, "reference", spp=a.spp, width=a.width,
                              height=a.height, seed=a.seed)
    print(f"reference: {a.spp} spp in {time.perf_counter() - t0:.1f} s")

    fig, ax = plt.subplots(figsize=(6, 4))
    for technique in TECHNIQUES:
        engine = illume.Engine(scene, technique, width=a.width, height=a.height, seed=a.seed)
        engine.precompute()
        for _ in range(a.warmup):
            engine.step()
        engine.apply(edit)
        errors, ms = [], []
        for _ in range(a.frames):
            t = time.perf_counter()
            image, _ = engine.step()
            ms.append(1e3 * (time.perf_counter() - t))
            errors.append(illume.compare(reference, image, ["hdr-flip"])["hdr-flip"])
        ms.sort()
        print(f"{technique}: HDR-FLIP {errors[0]:.4f} → {errors[-1]:.4f} over "
              f"{a.frames} frames, median {ms[len(ms) // 2]:.1f} ms/frame")
        ax.plot(range(1, a.frames + 1), errors, marker=".", label=technique)
    ax.set_xlabel("frames after the edit")
    ax.set_ylabel("HDR-FLIP vs reference")
    ax.set_title(f"{a.scene}: {a.instance} moved by {tuple(a.offset)} m "
                 f"({a.width}×{a.height})")
    ax.set_ylim(bottom=0)
    ax.legend()
    fig.tight_layout()
    fig.savefig(a.output, dpi=120)
    print(f"wrote {a.output}")


if __name__ == "__main__":
    main()
