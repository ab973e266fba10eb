"""Type stubs of the native module ``illume._illume`` (see the docstrings at run time)."""

import os
from typing import Any, Callable, Dict, List, Optional, Sequence, Tuple, Union

import numpy as np
import numpy.typing as npt

__version__: str

Vec3 = Tuple[float, float, float]
Image = npt.NDArray[np.float32]
Progress = Callable[[str, int, int], Any]
PathLike = Union[str, os.PathLike]

class Scene:
    """A scene file (.gltf, .glb, .obj, .ply) or ``builtin:NAME``, loaded with the
    options of ``illume render``."""

    def __init__(
        self,
        path: PathLike,
        *,
        units: str = "radiometric",
        strict: bool = False,
        spot_from_above: bool = False,
        animation: Optional[str] = None,
        time: float = 0.0,
        look_from: Optional[Sequence[float]] = None,
        look_at: Optional[Sequence[float]] = None,
        sky: Optional[Sequence[float]] = None,
        envmap: Optional[PathLike] = None,
        envmap_scale: float = 1.0,
        envmap_rotation: float = 0.0,
    ) -> None: ...
    @property
    def source(self) -> str:
        """Where the scene came from."""
    @property
    def time(self) -> float:
        """The scene time [s]."""
    @property
    def warnings(self) -> List[str]:
        """The loader's warnings."""
    def instances(self) -> List[Dict[str, Any]]:
        """Dicts with index, name, mesh, dynamic, translation, transform (4×4)."""
    def lights(self) -> List[Dict[str, Any]]:
        """Dicts with index, name, kind, intensity, position, direction, transform."""
    def materials(self) -> List[Dict[str, Any]]:
        """Dicts with index, name, base_color, emission, metallic, roughness, textured."""
    def camera(self) -> Dict[str, Any]:
        """A dict with name, yfov_deg, position, transform."""
    def apply(self, edit: Edit) -> List[str]:
        """Applies ``edit``; returns the changes. ValueError for an unknown item."""
    def copy(self) -> Scene:
        """An independent copy."""

class Edit:
    """A scene edit by name, resolved into the engine's Edit where it is applied."""

    @staticmethod
    def move_instance(
        name: str,
        translation: Optional[Sequence[float]] = None,
        rotation_deg: Optional[Sequence[float]] = None,
    ) -> Edit:
        """New world translation [m] and/or rotation (degrees about X, Y, Z)."""
    @staticmethod
    def move_light(
        name: str,
        translation: Optional[Sequence[float]] = None,
        rotation_deg: Optional[Sequence[float]] = None,
    ) -> Edit:
        """As move_instance, for a light."""
    @staticmethod
    def set_material(
        name: str,
        base_color: Optional[Sequence[float]] = None,
        emission: Optional[Sequence[float]] = None,
    ) -> Edit:
        """New diffuse albedo (linear RGB in [0, 1]) and/or emission [W/(m²·sr)]."""
    @staticmethod
    def set_light_intensity(name: str, intensity: Union[float, Sequence[float]]) -> Edit:
        """New intensity [W/sr] (irradiance [W/m²] for a directional light)."""
    @staticmethod
    def look_from(eye: Sequence[float], target: Sequence[float]) -> Edit:
        """Places the camera at ``eye`` looking at ``target`` (+Y up)."""
    @staticmethod
    def set_fov(degrees: float) -> Edit:
        """The camera's vertical field of view, within (0, 180) degrees."""

class Engine:
    """A scene, a technique and a renderer, stepped frame by frame."""

    def __init__(
        self,
        scene: Union[PathLike, Scene],
        technique: str = "photon_stream",
        *,
        settings: Optional[Dict[str, Any]] = None,
        preset: Optional[str] = None,
        width: int = 64,
        height: int = 48,
        seed: Optional[int] = None,
        work: Optional[int] = None,
        time_ms: Optional[float] = None,
    ) -> None: ...
    @property
    def technique(self) -> str:
        """The technique's name."""
    @property
    def size(self) -> Tuple[int, int]:
        """(width, height) [pixels]."""
    @property
    def scene(self) -> Scene:
        """The scene as the engine has it now (a copy)."""
    def precompute(self, progress: Optional[Progress] = None) -> float:
        """Runs the precompute now; returns its time [ms]."""
    def step(
        self, time: Optional[float] = None, *, split: bool = False
    ) -> Tuple[Any, Dict[str, Any]]:
        """One frame: (float32 (H, W, 3) radiance, or a dict with split=True; counters)."""
    def apply(self, edit: Edit) -> List[str]:
        """Applies ``edit`` as the engine's Edit; returns the changes."""
    def set_frame_index(self, index: int) -> None:
        """The index the next frame renders as."""

def render(
    scene: Union[PathLike, Scene],
    technique: str = "reference",
    spp: Optional[int] = None,
    width: int = 32,
    height: int = 24,
    *,
    seed: Optional[int] = None,
    preset: Optional[str] = None,
    settings: Optional[Dict[str, Any]] = None,
    split: bool = False,
    progress: Optional[Progress] = None,
) -> Any:
    """One still, as ``illume render`` makes it."""

def techniques() -> Dict[str, Dict[str, Any]]:
    """Every technique: summary, work unit and presets."""

def compare(
    reference: Image, test: Image, metrics: Optional[List[str]] = None
) -> Dict[str, float]:
    """Image metrics of ``test`` against ``reference``."""

def read_image(path: PathLike) -> Image:
    """Reads .exr/.hdr (linear) or .png/.jpg (sRGB decoded) as float32 (H, W, 3)."""

def write_image(
    path: PathLike, image: Image, exposure: float = 0.0, exposure_mode: str = "auto"
) -> None:
    """Writes .exr (linear) or .png (tone-mapped)."""

def bench(
    scenario: PathLike,
    *,
    cache: PathLike = "out/cache",
    output: Optional[PathLike] = None,
    progress: Optional[Progress] = None,
) -> Dict[str, Any]:
    """Runs a bench scenario; returns plain dicts and arrays."""

def panic_for_test() -> None:
    """Panics inside engine work: raises RuntimeError."""
