"""Shared helpers of the ssbvb Python tests: the repository's paths, the `ssbvb` command
line (the oracle the module is checked against), and a PNG reader (the CLI writes PNGs;
numpy alone cannot read them)."""

import os
import pathlib
import struct
import subprocess
import zlib

import numpy as np
import pytest

ROOT = pathlib.Path(__file__).resolve().parents[3]
ASSETS = ROOT / "assets"
BUNNY = ASSETS / "models" / "bunny.obj"
DEFAULT_SCENE = ASSETS / "scenes" / "default.ron"


def ssbvb_bin() -> pathlib.Path:
    """The `ssbvb` binary: `SSBVB_BIN`, else the workspace's debug build. A missing binary
    fails the test (never a silent skip)."""
    path = pathlib.Path(os.environ.get("SSBVB_BIN") or ROOT / "target" / "debug" / "ssbvb")
    if not path.is_file():
        pytest.fail(f"{path} is missing: build it with `cargo build -p ssbvb` (or set SSBVB_BIN)")
    return path


def run_cli(*args) -> str:
    """Runs `ssbvb ARGS`, failing the test with its stderr when it fails."""
    done = subprocess.run(
        [str(ssbvb_bin()), *map(str, args)], capture_output=True, text=True, cwd=ROOT
    )
    if done.returncode != 0:
        pytest.fail(f"ssbvb {' '.join(map(str, args))} failed:\n{done.stderr}")
    return done.stdout


def read_png(path) -> np.ndarray:
    """An 8-bit RGB or RGBA PNG as an `(H, W, 4)` `uint8` array (the five row filters)."""
    data = pathlib.Path(path).read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n", f"{path} is not a PNG"
    pos, idat, header = 8, b"", None
    while pos < len(data):
        (length,) = struct.unpack(">I", data[pos : pos + 4])
        kind = data[pos + 4 : pos + 8]
        body = data[pos + 8 : pos + 8 + length]
        if kind == b"IHDR":
            header = struct.unpack(">IIBBBBB", body)
        elif kind == b"IDAT":
            idat += body
        pos += 12 + length
    width, height, depth, color_type, _, _, interlace = header
    assert depth == 8 and color_type in (2, 6) and interlace == 0, header
    bpp = 4 if color_type == 6 else 3
    raw = zlib.decompress(idat)
    stride = width * bpp
    out = np.zeros((height, stride), np.uint8)
    prev = np.zeros(stride, np.int32)
    for y in range(height):
        row = raw[y * (stride + 1) : (y + 1) * (stride + 1)]
        kind, line = row[0], np.frombuffer(row[1:], np.uint8).astype(np.int32)
        cur = np.zeros(stride, np.int32)
        for x in range(stride):
            a = cur[x - bpp] if x >= bpp else 0
            b = prev[x]
            c = prev[x - bpp] if x >= bpp else 0
            if kind == 0:
                pred = 0
            elif kind == 1:
                pred = a
            elif kind == 2:
                pred = b
            elif kind == 3:
                pred = (a + b) // 2
            else:
                p = a + b - c
                pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                pred = a if pa <= pb and pa <= pc else (b if pb <= pc else c)
            cur[x] = (line[x] + pred) & 0xFF
        out[y] = cur
        prev = cur
    image = out.reshape(height, width, bpp)
    if bpp == 3:
        image = np.concatenate([image, np.full((height, width, 1), 255, np.uint8)], axis=2)
    return image


@pytest.fixture(scope="session")
def bunny6():
    """The bunny at level 6 (the asset cache makes later calls cheap)."""
    import ssbvb

    return ssbvb.voxelize(BUNNY, 6)


def ball(n=24, r=None):
    """A solid ball of `n`³ cells as a bool grid."""
    r = n / 2 - 1 if r is None else r
    idx = np.indices((n, n, n)) - (n - 1) / 2
    return np.linalg.norm(idx, axis=0) <= r
