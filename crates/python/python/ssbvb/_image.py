"""The image type ``Renderer.render`` returns: a numpy array that Jupyter shows."""

import numpy as np


class Image(np.ndarray):
    """An ``(H, W, 4)`` ``uint8`` RGBA image, row 0 at the top: a numpy array
    (``np.asarray(image)`` gives the plain array, no copy) that shows itself inline in
    Jupyter (``_repr_png_``)."""

    def _repr_png_(self) -> bytes:
        from ._ssbvb import png_bytes

        return png_bytes(np.ascontiguousarray(self, dtype=np.uint8))

    def save(self, path) -> None:
        """Writes the image as a PNG (to a temporary file in the same folder, then
        renamed, so a reader never sees half a file)."""
        import os
        import tempfile

        data = self._repr_png_()
        folder = os.path.dirname(os.path.abspath(path))
        fd, tmp = tempfile.mkstemp(dir=folder, suffix=".png.tmp")
        try:
            with os.fdopen(fd, "wb") as f:
                f.write(data)
            # mkstemp makes the file private; give it the mode a new file gets here.
            mask = os.umask(0)
            os.umask(mask)
            os.chmod(tmp, 0o666 & ~mask)
            os.replace(tmp, path)
        except BaseException:
            if os.path.exists(tmp):
                os.unlink(tmp)
            raise
