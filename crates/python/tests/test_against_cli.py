"""The module against the `ssbvb` command line on the same adapter: the same pixels for
the same scene, camera and size, and the same cells as `ssbvb export`."""

import numpy as np

import ssbvb
from conftest import BUNNY, DEFAULT_SCENE, read_png, run_cli

SIZE = (96, 64)


def test_render_of_a_scene_is_the_cli_render_byte_for_byte(tmp_path):
    out = tmp_path / "cli.png"
    run_cli("render", DEFAULT_SCENE, "--size", f"{SIZE[0]}x{SIZE[1]}", "-o", out)
    cli = read_png(out)
    image = ssbvb.render(DEFAULT_SCENE, size=SIZE)
    assert image.shape == (SIZE[1], SIZE[0], 4) and image.dtype == np.uint8
    # Not an empty frame: the scene's objects cover part of it.
    assert (image[..., :3] != image[0, 0, :3]).any(axis=2).sum() > 200
    assert np.array_equal(np.asarray(image), cli)


def test_voxelize_is_the_export_cells(tmp_path):
    level = 7
    sparse = tmp_path / "bunny.npy"
    dense = tmp_path / "bunny_dense.npy"
    run_cli("export", BUNNY, "--level", level, "--format", "npy", "--sparse", "-o", sparse)
    run_cli("export", BUNNY, "--level", level, "--format", "npy", "-o", dense)
    v = ssbvb.voxelize(BUNNY, level)
    assert v.level == level
    assert v.origin == (-1.0, -1.0, -1.0) and v.voxel_size == 2.0 / 2**level
    records = np.load(sparse)
    coords, colors, normals = v.sparse()
    assert coords.dtype == np.int32 and colors.dtype == np.uint8 and normals.dtype == np.float32
    assert len(v) == len(records) > 10_000
    want = np.stack([records["x"], records["y"], records["z"]], axis=1).astype(np.int32)
    assert np.array_equal(coords, want)
    want_rgba = np.stack([records[c] for c in "rgba"], axis=1)
    assert np.array_equal(colors, want_rgba)
    want_n = np.stack([records["nx"], records["ny"], records["nz"]], axis=1)
    assert np.array_equal(normals, want_n)
    assert np.array_equal(v.dense(), np.load(dense))
