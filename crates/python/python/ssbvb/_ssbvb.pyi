"""Type stubs of the extension module ``ssbvb._ssbvb`` (re-exported by ``ssbvb``)."""

from os import PathLike
from typing import Any, Dict, List, Optional, Sequence, Tuple, Union

import numpy as np
import numpy.typing as npt

from ._image import Image

_Vec3 = Tuple[float, float, float]
_Color = Sequence[Union[int, float]]

class Error(Exception):
    """An error of the ssbvb engine; the message is the engine's."""

class SsbvbWarning(UserWarning):
    """What ssbvb did instead of what was asked (a missing texture, an empty grid)."""

class Voxels:
    """Voxels ready to render, and where they lie (see the module docs' conventions)."""

    @staticmethod
    def from_dense(
        array: npt.ArrayLike,
        origin: _Vec3 = (0.0, 0.0, 0.0),
        voxel_size: float = 1.0,
        order: str = "xyz",
        color: Optional[_Color] = None,
        palette: Optional[npt.ArrayLike] = None,
    ) -> "Voxels": ...
    @staticmethod
    def from_sparse(
        coords: npt.ArrayLike,
        colors: Optional[npt.ArrayLike] = None,
        origin: _Vec3 = (0.0, 0.0, 0.0),
        voxel_size: float = 1.0,
        color: Optional[_Color] = None,
        palette: Optional[npt.ArrayLike] = None,
    ) -> "Voxels": ...
    @property
    def origin(self) -> _Vec3: ...
    @property
    def voxel_size(self) -> float: ...
    @property
    def level(self) -> int: ...
    @property
    def dense_origin(self) -> _Vec3: ...
    @property
    def warnings(self) -> List[str]: ...
    def __len__(self) -> int: ...
    def dense(self) -> npt.NDArray[np.uint8]: ...
    def sparse(
        self,
    ) -> Tuple[npt.NDArray[np.int32], npt.NDArray[np.uint8], npt.NDArray[np.float32]]: ...

class Camera:
    """A pinhole camera (Y up, no far plane)."""

    def __init__(
        self,
        eye: _Vec3,
        target: _Vec3 = (0.0, 0.0, 0.0),
        up: _Vec3 = (0.0, 1.0, 0.0),
        fov_y: float = 40.0,
        near: Optional[float] = None,
    ) -> None: ...
    @staticmethod
    def orbit(
        azimuth: float,
        elevation: float,
        distance: float,
        target: _Vec3 = (0.0, 0.0, 0.0),
        fov_y: float = 40.0,
    ) -> "Camera": ...
    @property
    def eye(self) -> _Vec3: ...
    @property
    def target(self) -> _Vec3: ...
    @property
    def up(self) -> _Vec3: ...
    @property
    def fov_y(self) -> float: ...
    @property
    def near(self) -> float: ...

class Renderer:
    """Renders voxels and scenes headless into numpy arrays."""

    def __init__(
        self,
        size: Tuple[int, int] = (640, 480),
        pipeline: Optional[str] = None,
        backend: Optional[str] = None,
        smooth: bool = True,
        gpu_budget_mib: Optional[int] = None,
    ) -> None: ...
    def add(
        self,
        x: Union[Voxels, str, PathLike],
        transform: Optional[npt.ArrayLike] = None,
        level: Optional[int] = None,
    ) -> None: ...
    def clear(self) -> None: ...
    def render(self, camera: Optional[Camera] = None) -> Image: ...
    def render_many(self, cameras: Sequence[Camera]) -> npt.NDArray[np.uint8]: ...
    def depth(self) -> npt.NDArray[np.float32]: ...
    def instance_ids(self) -> npt.NDArray[np.uint32]: ...
    def counters(self) -> Dict[str, Any]: ...
    @property
    def size(self) -> Tuple[int, int]: ...
    @property
    def info(self) -> Dict[str, Any]: ...
    def close(self) -> None: ...

def voxelize(path: Union[str, PathLike], level: Optional[int] = None) -> Voxels: ...
def png_bytes(image: npt.NDArray[np.uint8]) -> bytes: ...
def forms() -> List[str]: ...
