"""illume from Python: load a scene, edit it, step any technique, get NumPy frames.

The package is a thin layer over the engine the ``illume`` command line runs: the same
scene loader, settings checks (unknown keys and bad values raise ``ValueError`` with the
command line's message), still renderer, frame loop, image metrics and bench runner.

>>> import illume
>>> img = illume.render("builtin:furnace", "reference", spp=16, width=8, height=6)
>>> img.shape, img.dtype
((6, 8, 3), dtype('float32'))

Every call that renders releases the GIL, so other Python threads keep running; Ctrl-C
stops a still or a precompute; an internal error is a ``RuntimeError``, never a crash.
"""

from __future__ import annotations

import os
from typing import Any, Dict, Iterable, Optional, Union

import numpy as np

from . import _illume
from ._illume import Edit, Engine, Scene, __version__, bench, read_image, techniques

__all__ = [
    "Edit",
    "Engine",
    "Scene",
    "bench",
    "compare",
    "read_image",
    "render",
    "techniques",
    "write_image",
    "__version__",
]

METRICS = ("rmse", "relmse", "psnr", "ssim", "flip", "hdr-flip")
"""The metric names ``compare`` takes, as ``illume compare --metric`` does."""


def _image(name: str, array: Any) -> np.ndarray:
    """``array`` as a C-contiguous float32 (height, width, 3) array, or a ValueError
    naming the argument ``name`` and what is wrong with it."""
    a = np.asarray(array)
    if a.dtype.kind != "f":
        raise ValueError(
            f"{name}: dtype {a.dtype}, expected a float array of radiance "
            "(float32, shape (height, width, 3))"
        )
    if a.ndim != 3 or a.shape[2] != 3 or a.shape[0] == 0 or a.shape[1] == 0:
        raise ValueError(f"{name}: shape {a.shape}, expected (height, width, 3)")
    return np.ascontiguousarray(a, dtype=np.float32)


def render(
    scene: Union[str, os.PathLike, Scene],
    technique: str = "reference",
    spp: Optional[int] = None,
    width: int = 32,
    height: int = 24,
    *,
    seed: Optional[int] = None,
    preset: Optional[str] = None,
    settings: Optional[Dict[str, Any]] = None,
    split: bool = False,
    progress: Any = None,
    **technique_settings: Any,
) -> Any:
    """One still, as ``illume render SCENE --technique T --spp N --width W --height H
    --seed S --set ...`` makes it.

    ``scene`` is a ``Scene``, a file or ``"builtin:NAME"``. Keyword arguments beyond the
    named ones are the technique's settings (``vsl_count=50``); ``settings`` takes any
    table's keys too (``{"render.shadows": "rays"}``). The technique's ``still`` preset
    applies unless ``preset`` is given. ``spp`` is for techniques with a
    samples-per-pixel setting (ValueError otherwise). ``progress(what, done, total)`` is
    called as the render goes; Ctrl-C stops it with ``KeyboardInterrupt``.

    Returns the radiance as float32 (height, width, 3); with ``split=True`` a dict of
    ``full``, ``direct`` and ``indirect`` arrays.
    """
    merged: Dict[str, Any] = dict(technique_settings)
    merged.update(settings or {})
    return _illume.render(
        scene,
        technique,
        spp,
        width,
        height,
        seed=seed,
        preset=preset,
        settings=merged,
        split=split,
        progress=progress,
    )


def compare(
    reference: Any,
    test: Any,
    metrics: Union[None, str, Iterable[str]] = None,
) -> Dict[str, float]:
    """Image metrics of ``test`` against ``reference`` (float (height, width, 3)
    arrays of radiance), as ``illume compare`` computes them.

    ``metrics``: names from ``METRICS`` as a list or one comma-separated string
    (default: all). Returns ``{name: value}``. Arrays of another shape or a non-float
    dtype, or of different sizes, raise ValueError naming the argument.
    """
    if isinstance(metrics, str):
        metrics = [metrics]
    elif metrics is not None:
        metrics = list(metrics)
    return _illume.compare(_image("reference", reference), _image("test", test), metrics)


def write_image(
    path: Union[str, os.PathLike],
    image: Any,
    exposure: float = 0.0,
    exposure_mode: str = "auto",
) -> None:
    """Writes a float (height, width, 3) radiance array: ``.exr`` linear, ``.png``
    tone-mapped as ``illume render`` writes it (automatic exposure plus ``exposure``
    stops; ``exposure_mode="fixed"``: ``exposure`` alone). Written to a temporary file
    and renamed, so a failure leaves no partial file."""
    _illume.write_image(os.fspath(path), _image("image", image), exposure, exposure_mode)
