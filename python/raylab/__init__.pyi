# Type hints of the raylab package (the functions' docstrings are in
# __init__.py; help(raylab.render) lists every option with its help text).
import os
from typing import Callable, Literal, Mapping, Optional, Sequence, Tuple, Union

import numpy as np

__version__: str

_Path = Union[str, "os.PathLike[str]"]
_Vec3 = Union[str, Sequence[float]]
_Pair = Union[str, Tuple[int, int], Sequence[int]]

AOVS: Tuple[str, ...]

class LoadError(Exception): ...
class RenderError(Exception): ...

class Camera:
    @property
    def position(self) -> Tuple[float, float, float]: ...
    @property
    def yaw(self) -> float: ...
    @property
    def pitch(self) -> float: ...
    @property
    def step(self) -> float: ...
    def moved(self, *, forward: int = 0, yaw: float = 0.0, pitch: float = 0.0) -> Camera: ...

class Scene:
    @property
    def name(self) -> str: ...
    @property
    def kind(self) -> str: ...
    @property
    def camera(self) -> Camera: ...
    @property
    def size(self) -> Tuple[int, int]: ...
    @property
    def options(self) -> dict: ...
    @property
    def bounds(self) -> Tuple[Tuple[float, float, float], Tuple[float, float, float]]: ...

class Image(np.ndarray):
    display: Tuple[float, float, str]
    info: dict
    def __new__(cls, array: object, display: Optional[Tuple[float, float, str]] = ..., info: Optional[dict] = ...) -> Image: ...
    def to_srgb8(self, exposure: Optional[float] = ..., tonemap: Optional[str] = ...) -> np.ndarray: ...
    def _repr_png_(self) -> Optional[bytes]: ...

class Render:
    image: Image
    aovs: dict
    noisy: Optional[Image]
    albedo: np.ndarray
    normal: np.ndarray
    depth: np.ndarray
    position: np.ndarray
    variance: np.ndarray
    half: np.ndarray
    samples: np.ndarray
    @property
    def info(self) -> dict: ...
    def __init__(self, image: Image, aovs: Optional[Mapping[str, np.ndarray]] = ..., noisy: Optional[Image] = ...) -> None: ...
    def _repr_png_(self) -> Optional[bytes]: ...

class RenderInterrupted(KeyboardInterrupt):
    result: Union[Image, Render, list]
    @property
    def image(self) -> Optional[Image]: ...

_Aov = Literal["albedo", "normal", "depth", "position", "variance", "half", "samples"]

def render(
    scene: Union[Scene, _Path] = "cornell",
    /,
    *,
    width: Optional[int] = None,
    height: Optional[int] = None,
    integrator: Optional[Literal["flat", "direct", "path"]] = None,
    camera: Union[None, int, Camera] = None,
    variant: Optional[str] = None,
    define: Union[None, str, Mapping[str, object], Sequence[str]] = None,
    default_light: Literal["auto", "on", "off"] = "auto",
    light_selection: Literal["tree", "power", "uniform"] = "tree",
    light_numbers: Optional[Literal["stratified", "independent"]] = None,
    tonemap: Optional[Literal["clamp", "aces", "khronos-pbr-neutral"]] = None,
    max_depth: Optional[int] = None,
    sampler: Literal["sobol", "independent"] = "sobol",
    filter: Optional[str] = None,
    reconstruction: Optional[Literal["sample", "splat"]] = None,
    material: Union[None, str, Mapping[str, str], Sequence[str]] = None,
    exposure: Optional[float] = None,
    camera_pos: Optional[_Vec3] = None,
    yaw: float = 0.0,
    pitch: float = 0.0,
    aperture: Optional[float] = None,
    f_number: Optional[float] = None,
    focus_distance: Optional[float] = None,
    focus_pixel: Optional[_Pair] = None,
    aperture_blades: Optional[int] = None,
    light_pos: Optional[_Vec3] = None,
    light_power: Optional[float] = None,
    env: Optional[_Path] = None,
    env_color: Optional[_Vec3] = None,
    env_strength: Optional[float] = None,
    env_rotate: Optional[float] = None,
    fog: Union[None, float, str, Sequence[float]] = None,
    add: Union[None, _Path, Sequence[_Path]] = None,
    transform: Union[None, str, Sequence[str]] = None,
    ambient: Optional[float] = None,
    max_memory: Union[None, str, int] = None,
    cache: Optional[_Path] = None,
    denoise: Optional[bool] = None,
    at: Optional[float] = None,
    animation: Union[None, int, str] = None,
    output: Optional[_Path] = None,
    aov: Union[None, str, Sequence[_Aov]] = None,
    spp: Optional[int] = None,
    time: Optional[float] = None,
    noise_threshold: Optional[float] = None,
    seed: Optional[int] = None,
    threads: Optional[int] = None,
    checkpoint: Optional[_Path] = None,
    checkpoint_every: float = 10.0,
    nan_check: bool = False,
    tile: Optional[_Pair] = None,
    samples: Optional[_Pair] = None,
    frames: Union[None, int, _Pair] = None,
    orbit: Optional[float] = None,
    fps: Optional[float] = None,
    quiet: bool = False,
    aovs: Union[None, str, Sequence[_Aov]] = None,
    progress: Union[None, bool, Callable[[int, int], object]] = None,
) -> Union[Image, Render, list]: ...

def load(scene: _Path, /, **options: object) -> Scene: ...
def save(image: Union[Image, Render, np.ndarray], path: _Path, *, exposure: Optional[float] = None, tonemap: Optional[str] = None) -> None: ...
def read_exr(path: _Path) -> Union[Image, Render]: ...
def options() -> list: ...
