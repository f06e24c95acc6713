"""raylab, a fast CPU ray tracer, in Python: scenes in, numpy images out.

    import raylab
    scene = raylab.load("model.glb")                 # also .gltf, .obj, .toml, "cornell", "cornell-area"
    img = raylab.render(scene, spp=64, width=640)    # numpy float32 (H, W, 3), linear radiance
    raylab.save(img, "out.png")                      # the command line's tone mapping and display

Every option of ``raylab render`` is a keyword argument of :func:`render`
with the same name (``--max-depth`` is ``max_depth``) and default, checked as
the command line checks it; ``help(raylab.render)`` lists them all. Images
show themselves in Jupyter. See docs/python.md in the repository.
"""

from __future__ import annotations

import inspect
import os
import sys
import textwrap

import numpy as np

from . import _raylab
from ._raylab import Camera, LoadError, RenderError, Scene

__version__ = _raylab.__version__

__all__ = [
    "Camera",
    "Image",
    "LoadError",
    "Render",
    "RenderError",
    "RenderInterrupted",
    "Scene",
    "load",
    "options",
    "read_exr",
    "render",
    "save",
]

#: How an image is shown when no render says: scale 1, exposure 0, clamped.
_PLAIN = (1.0, 0.0, "clamp")

#: The AOVs raylab renders (``aovs=[...]``).
AOVS = ("albedo", "normal", "depth", "position", "variance", "half", "samples")


class Image(np.ndarray):
    """A rendered image: a float32 ``(H, W, 3)`` array of linear radiance.

    It is a numpy array in every way; it also remembers how the command line
    shows it (``display``: the scene kind's factor, the exposure in stops and
    the tone mapping), which Jupyter uses (``_repr_png_``) and
    :func:`save` uses for PNG files, and how the render went (``info``: spp,
    seed, integrator, seconds, rays, ...).
    """

    display: tuple
    info: dict

    def __new__(cls, array, display=None, info=None):
        obj = np.asarray(array, dtype=np.float32).view(cls)
        obj.display = tuple(display) if display is not None else _PLAIN
        obj.info = dict(info or {})
        return obj

    def __array_finalize__(self, obj):
        self.display = getattr(obj, "display", _PLAIN)
        self.info = getattr(obj, "info", {})

    def __array_wrap__(self, array, context=None, return_scalar=False):
        # Reductions to one number give a number, not a 0-d Image.
        if array.ndim == 0:
            return array.view(np.ndarray)[()]
        return super().__array_wrap__(array, context)

    def __reduce__(self):
        rebuild, args, state = super().__reduce__()
        return rebuild, args, (state, self.display, self.info)

    def __setstate__(self, state):
        base, self.display, self.info = state
        super().__setstate__(base)

    def to_srgb8(self, exposure=None, tonemap=None):
        """The 8-bit sRGB ``(H, W, 3)`` uint8 array of the PNG ``raylab
        render`` writes of this image (for ``matplotlib.pyplot.imshow``);
        ``exposure`` and ``tonemap`` replace the render's, as in
        :func:`save`."""
        factor, exp, tm = self.display
        exp = exp if exposure is None else float(exposure)
        tm = tm if tonemap is None else str(tonemap)
        data = np.ascontiguousarray(self, dtype=np.float32)
        if data.ndim != 3 or data.shape[2] != 3:
            raise ValueError(f"an image is (H, W, 3), not {data.shape}")
        h, w = data.shape[:2]
        out = _raylab.srgb8(data.tobytes(), w, h, factor, exp, tm)
        return np.frombuffer(out, dtype=np.uint8).reshape(h, w, 3)

    def _repr_png_(self):
        """The PNG ``raylab render`` would write of this image."""
        if self.ndim != 3 or self.shape[2] != 3 or self.size == 0:
            return None
        return _png(self, self.display)


class Render:
    """A render with AOVs: ``.image`` (an :class:`Image`) and one array per
    AOV asked for, as attributes and in ``.aovs``: ``albedo``, ``normal`` and
    ``position`` are ``(H, W, 3)``, ``depth``, ``variance`` and ``samples``
    ``(H, W)``, ``half`` ``(H, W, 4)`` (a half's mean colour and its count);
    ``.noisy`` is the image before denoising (with ``denoise=True``), else
    None. Shows its image in Jupyter."""

    def __init__(self, image, aovs=None, noisy=None):
        self.image = image
        self.aovs = dict(aovs or {})
        self.noisy = noisy
        for name, array in self.aovs.items():
            setattr(self, name, array)

    @property
    def info(self):
        """How the render went (the image's ``info``)."""
        return self.image.info

    def __getattr__(self, name):
        if name in AOVS:
            raise AttributeError(
                f"the {name} AOV was not rendered: ask for it with aovs=[..., {name!r}]"
            )
        raise AttributeError(name)

    def _repr_png_(self):
        return self.image._repr_png_()

    def __repr__(self):
        h, w = self.image.shape[:2]
        aovs = ", ".join(self.aovs) or "no AOVs"
        noisy = ", noisy" if self.noisy is not None else ""
        return f"<raylab.Render {w}x{h}: image, {aovs}{noisy}>"


class RenderInterrupted(KeyboardInterrupt):
    """Ctrl-C stopped a render after the samples in flight (whole samples
    per pixel are kept). ``.result`` is what :func:`render` would have
    returned, made of the samples taken (an :class:`Image`, a
    :class:`Render` with AOVs, or the list of files written with
    ``output=``); ``.image`` is its image. Being a ``KeyboardInterrupt``, it
    stops a script as Ctrl-C does unless caught::

        try:
            img = raylab.render(scene, spp=4096)
        except KeyboardInterrupt as stop:
            img = stop.image          # the image so far
    """

    def __init__(self, result):
        self.result = result
        spp = _info(result).get("spp")
        said = f" after {spp} spp" if spp is not None else ""
        super().__init__(f"render interrupted{said}: the image so far is in .result")

    @property
    def image(self):
        """The image so far (None when files were written)."""
        if isinstance(self.result, Render):
            return self.result.image
        if isinstance(self.result, Image):
            return self.result
        return None


def _info(result):
    if isinstance(result, (Image, Render)):
        return result.info
    return {}


def _png(image, display):
    data = np.ascontiguousarray(image, dtype=np.float32)
    h, w = data.shape[:2]
    factor, exposure, tonemap = display
    return _raylab.png(data.tobytes(), w, h, factor, exposure, tonemap)


def _plane(data, h, w, k):
    array = np.frombuffer(data, dtype=np.float32)
    return array.reshape(h, w) if k == 1 else array.reshape(h, w, k)


def _result(out):
    h, w = out["height"], out["width"]
    display, info = out["display"], out["info"]
    image = Image(_plane(out["image"], h, w, 3), display, info)
    aovs = {name: _plane(data, h, w, k) for name, data, k in out["aovs"]}
    if not aovs:
        return image
    noisy = out["noisy"]
    if noisy is not None:
        noisy = Image(_plane(noisy, h, w, 3), display, info)
    return Render(image, aovs, noisy)


class _TextBar:
    """A percentage on stderr, when tqdm is not installed."""

    def __init__(self):
        self.shown = None

    def __call__(self, done, total):
        percent = 100 * done // max(total, 1)
        if percent != self.shown:
            self.shown = percent
            sys.stderr.write(f"\rraylab: {percent:3d}%")
            sys.stderr.flush()

    def close(self):
        if self.shown is not None:
            sys.stderr.write("\n")


class _TqdmBar:
    def __init__(self, tqdm):
        self.tqdm = tqdm
        self.bar = None

    def __call__(self, done, total):
        if self.bar is None:
            self.bar = self.tqdm(total=total, desc="raylab", unit="row·sample", unit_scale=True)
        self.bar.total = total
        self.bar.update(done - self.bar.n)

    def close(self):
        if self.bar is not None:
            self.bar.close()


def _progress(progress):
    if progress is None or progress is False:
        return None
    if progress is True:
        try:
            from tqdm.auto import tqdm
        except ImportError:
            return _TextBar()
        return _TqdmBar(tqdm)
    if callable(progress):
        return progress
    raise TypeError(f"progress takes True, False or a callable, not {progress!r}")


def render(scene="cornell", /, **options):
    # The docstring is made from the command line's options below.
    bar = _progress(options.pop("progress", None))
    try:
        out = _raylab.render(scene, options, bar)
    finally:
        if hasattr(bar, "close"):
            bar.close()
    if "files" in out:
        result = out["files"]
    else:
        result = _result(out)
    if out["interrupted"]:
        raise RenderInterrupted(result)
    return result


def load(scene, /, **options):
    """Loads a scene once, to render it as often as you like.

    ``scene`` is ``"cornell"`` (the lab's box), ``"cornell-area"`` (the box
    under a ceiling light), a Wavefront ``.obj``, a glTF ``.gltf`` or
    ``.glb`` file or a ``.toml`` scene file (a path or a string). The
    keyword arguments are :func:`render`'s, and become the defaults of the
    scene's renders (a render's own keywords override them). Options that
    change what is loaded (``add``, ``transform``, ``material``, the light,
    the environment, ``camera=N`` of a glTF file, ``max_memory``, ``cache``)
    load the scene again when a render changes them; the others cost
    nothing. Raises :class:`LoadError` with the command line's message
    (naming the file) if the scene cannot be loaded. The GIL is released
    while it loads; a load cannot be stopped halfway, so Ctrl-C raises its
    ``KeyboardInterrupt`` once the load is done.

    The scene has ``.camera`` (a :class:`Camera` to move), ``.size``,
    ``.kind``, ``.bounds``, ``.name`` and ``.options``.
    """
    return _raylab.load(scene, options)


def save(image, path, *, exposure=None, tonemap=None):
    """Writes ``image`` to ``path`` as ``raylab render`` writes it.

    PNG (8-bit sRGB) goes through the command line's display: the scene
    kind's factor, the exposure and the tone mapping of the render that made
    the image (an :class:`Image` remembers them), the same bytes as the
    command line's PNG of the same render. ``exposure`` (stops) and
    ``tonemap`` (``"clamp"``, ``"aces"``, ``"khronos-pbr-neutral"``)
    replace the render's. EXR (linear float32) holds the values as they
    are, with a :class:`Render`'s AOVs (and ``noisy`` image) as layers and
    the render's metadata, as the command line writes them. A plain array
    of shape ``(H, W, 3)`` is shown clamped, unscaled.
    """
    layers, noisy = [], None
    if isinstance(image, Render):
        for name, array in image.aovs.items():
            array = np.ascontiguousarray(array, dtype=np.float32)
            layers.append((name, array.tobytes(), 1 if array.ndim == 2 else array.shape[2]))
        if image.noisy is not None:
            noisy = np.ascontiguousarray(image.noisy, dtype=np.float32).tobytes()
        image = image.image
    display = getattr(image, "display", _PLAIN)
    info = getattr(image, "info", {})
    data = np.ascontiguousarray(image, dtype=np.float32)
    if data.ndim != 3 or data.shape[2] != 3:
        raise ValueError(f"an image is (H, W, 3), not {data.shape}")
    h, w = data.shape[:2]
    factor, exp, tm = display
    if exposure is not None:
        exp = float(exposure)
    if tonemap is not None:
        tm = str(tonemap)
    metadata = None
    if "spp" in info:
        metadata = (
            info["spp"],
            info.get("spp_requested"),
            info.get("seed", 0),
            info.get("integrator", ""),
            info.get("ended") == "stopped",
            info.get("denoise_seconds") is not None,
        )
    _raylab.save(os.fspath(path), data.tobytes(), w, h, factor, exp, tm, layers, noisy, metadata)


def read_exr(path):
    """Reads an OpenEXR file: an :class:`Image` of its R, G, B channels, or
    a :class:`Render` when it holds layers (raylab's AOVs, ``noisy``), as
    ``raylab render --aov ...`` writes them."""
    width, height, channels = _raylab.read_exr(os.fspath(path))
    planes = {name: np.frombuffer(data, dtype=np.float32).reshape(height, width) for name, data in channels}

    def stack(names):
        return np.ascontiguousarray(np.stack([planes[n] for n in names], axis=-1))

    if not all(c in planes for c in "RGB"):
        raise LoadError(f"{path}: no R, G, B channels (has {', '.join(planes)})")
    image = Image(stack("RGB"))
    aovs = {}
    for name in AOVS:
        names = sorted((n for n in planes if n.startswith(name + ".")), key=_channel_order)
        if names:
            aovs[name] = planes[names[0]].copy() if len(names) == 1 else stack(names)
    noisy = Image(stack([f"noisy.{c}" for c in "RGB"])) if "noisy.R" in planes else None
    if not aovs and noisy is None:
        return image
    return Render(image, aovs, noisy)


def _channel_order(name):
    suffix = name.rsplit(".", 1)[-1]
    return "RGBXYZ".find(suffix) if suffix in "RGBXYZ" else 99


def options():
    """Every keyword argument of :func:`render` that is an option of
    ``raylab render``: a list of (name, value name, default, help), in the
    command line's order."""
    return list(_raylab.options())


def _default(value, value_name):
    """The command line's default as a Python value."""
    if value is None:
        return False if value_name is None else None
    for kind in (int, float):
        try:
            return kind(value)
        except ValueError:
            pass
    return value


def _render_doc():
    head = """Renders a scene, as ``raylab render`` does, into numpy arrays.

``scene`` is a :class:`Scene` from :func:`load` (rendered without loading
it again) or what :func:`load` takes: ``"cornell"`` (the default),
``"cornell-area"``, an ``.obj``, ``.gltf``, ``.glb`` or ``.toml`` file.

Returns an :class:`Image`, a float32 ``(H, W, 3)`` numpy array of linear
radiance, bit for bit the values of the EXR ``raylab render`` writes of the
same scene and options; with ``aovs=[...]`` a :class:`Render` whose
``.image`` and AOV attributes (``.albedo``, ``.normal``, ``.depth``, ...)
are arrays. With ``output=FILE`` it writes files instead, exactly as the
command line (PNG or EXR, parts with ``tile``/``samples``, ``frames``,
checkpoints), and returns a list of what it wrote (one dict per file).

Every option of ``raylab render`` is a keyword argument with the same name
(``--max-depth`` is ``max_depth``) and the same default; ``None`` means the
default. Values are what the command line takes, as Python values or
strings: numbers, ``True``/``False``, paths, ``camera_pos=(0, 0, -2)``,
``tile=(0, 4)`` or ``"0/4"``, ``samples=(0, 64)``, ``aovs=["albedo",
"depth"]`` (``aov`` works too), ``material={"tall": "mirror"}``,
``add=[...]``. They are checked as the command line checks them: a wrong
keyword raises ``TypeError`` naming it, a bad value ``ValueError`` with the
command line's message. A scene file's ``[render]`` settings fill in what
the keywords leave out, as on the command line.

Also:
    camera : Camera or int
        A :class:`Camera` (``scene.camera.moved(yaw=10)``) to look through
        (its position, yaw and pitch); a number picks a glTF file's camera
        as ``--camera N`` does.
    progress : bool or callable
        ``True``: a tqdm bar (a percentage on stderr without tqdm); a
        callable is called as ``progress(done, total)`` about every 50 ms
        (row-samples, or milliseconds with ``time``).

The GIL is released while raylab renders (other Python threads run, and
renders in several threads run in parallel). Ctrl-C stops the render after
the samples in flight and raises :class:`RenderInterrupted` (a
``KeyboardInterrupt``) carrying the image so far in ``.result``. Errors are
exceptions with the command line's one-line messages: :class:`LoadError`
for a scene that cannot be loaded, ``ValueError`` for bad options,
:class:`RenderError` for a failed render (and for a panic inside raylab).
The lines ``raylab render`` prints (load summaries, warnings) go to
``sys.stderr`` unless ``quiet=True``.

Options (``raylab render``'s, in its order):
"""
    parts = [head]
    for name, value_name, default, help in _OPTIONS:
        kind = value_name or "bool"
        shown = f" = {default}" if default is not None else ""
        alias = " (or aovs)" if name == "aov" else ""
        parts.append(f"    {name}{alias} : {kind}{shown}\n")
        for paragraph in help.split("\n\n"):
            parts.append(textwrap.fill(" ".join(paragraph.split()), 76, initial_indent=" " * 8, subsequent_indent=" " * 8))
            parts.append("\n")
    return "".join(parts)


def _render_signature():
    P = inspect.Parameter
    params = [P("scene", P.POSITIONAL_ONLY, default="cornell")]
    for name, value_name, default, _ in _OPTIONS:
        params.append(P(name, P.KEYWORD_ONLY, default=_default(default, value_name)))
    params.append(P("aovs", P.KEYWORD_ONLY, default=None))
    params.append(P("progress", P.KEYWORD_ONLY, default=None))
    return inspect.Signature(params)


_OPTIONS = _raylab.options()
render.__doc__ = _render_doc()
render.__signature__ = _render_signature()
