"""ssbvb: voxels rendered headless on the GPU (or Mesa's lavapipe) into numpy arrays.

Voxels come from a model file (``voxelize``), a dense grid (``Voxels.from_dense``) or
sparse coordinates (``Voxels.from_sparse``); a ``Renderer`` draws them, and scene files,
with the Screen Space Billboard Voxel Buffer pipeline the engine chooses for the adapter.

    >>> import numpy as np, ssbvb
    >>> ball = np.linalg.norm(np.indices((32, 32, 32)) - 15.5, axis=0) < 14
    >>> image = ssbvb.render(ssbvb.Voxels.from_dense(ball), size=(320, 240))
    >>> image.shape
    (240, 320, 4)

Conventions: cell ``(i, j, k)`` of a grid is the world box ``origin + voxel_size *
[i, i+1] x [j, j+1] x [k, k+1]`` with ``x`` right, ``y`` up and ``z`` towards the default
camera; ``array[i, j, k]`` is ``(x, y, z)`` unless ``order="zyx"``. Colours are sRGB
(``uint8``, or floats in [0, 1]), alpha linear. Images are ``(H, W, 4)`` ``uint8`` RGBA,
row 0 at the top.

Errors are ``TypeError``/``ValueError`` for unusable arguments, ``FileNotFoundError`` for a
missing file, else ``ssbvb.Error``; what the engine did instead of what was asked is a
``warnings.warn`` of ``ssbvb.SsbvbWarning``.
"""

import os
import sys
import tempfile
from os import PathLike
from typing import Optional, Tuple, Union


def _quiet_window_system_probe() -> None:
    """Mesa's Vulkan driver probes Wayland, which prints an error per device where
    XDG_RUNTIME_DIR is unset (headless machines, containers): point it at a private empty
    folder first, as the engine's programs do (``ssbvb_engine::platform``)."""
    if not sys.platform.startswith("linux"):
        return
    current = os.environ.get("XDG_RUNTIME_DIR")
    if current and os.path.isdir(current):
        return
    folder = os.path.join(tempfile.gettempdir(), f"ssbvb-xdg-runtime-{os.getuid()}")
    try:
        os.makedirs(folder, mode=0o700, exist_ok=True)
        os.chmod(folder, 0o700)
    except OSError:
        return
    os.environ["XDG_RUNTIME_DIR"] = folder


_quiet_window_system_probe()

from ._image import Image  # noqa: E402
from ._ssbvb import (  # noqa: E402
    Camera,
    Error,
    Renderer,
    SsbvbWarning,
    Voxels,
    forms,
    voxelize,
)

__all__ = [
    "Camera",
    "Error",
    "Image",
    "Renderer",
    "SsbvbWarning",
    "Voxels",
    "forms",
    "render",
    "voxelize",
]


# The renderer `render` keeps between calls (its device and compiled pipelines), for the
# last (size, pipeline, smooth) asked.
_kept = {}


def render(
    x: Union[Voxels, str, PathLike],
    level: Optional[int] = None,
    size: Tuple[int, int] = (640, 480),
    camera: Optional[Camera] = None,
    pipeline: Optional[str] = None,
    smooth: bool = True,
) -> Image:
    """Renders ``x`` in one call: ``Voxels``, a model file (at ``level``, default 8) or a
    scene file (``.ron``), into an ``(H, W, 4)`` ``uint8`` image.

    ``camera=None`` is a scene's camera, a model's default view, or a view framing the
    voxels. ``pipeline`` and ``smooth`` are ``Renderer``'s (``smooth=False``: the exact
    cubes, unsmoothed). One renderer is kept between calls with the same ``size``,
    ``pipeline`` and ``smooth``, so later calls reuse its device and compiled pipelines.
    """
    key = (tuple(size), pipeline, smooth)
    renderer = _kept.get(key)
    if renderer is None:
        renderer = Renderer(size=size, pipeline=pipeline, smooth=smooth)
        _kept.clear()
        _kept[key] = renderer
    renderer.clear()
    renderer.add(x, level=level)
    return renderer.render(camera)
