"""Dense and sparse round trips, every input form against the others, and rendering a
grid against rendering the model it came from."""

import numpy as np
import pytest

import ssbvb
from conftest import ball, read_png


def cells(v):
    coords, colors, _ = v.sparse()
    order = np.lexsort(coords.T[::-1])
    return coords[order], colors[order]


def coverage_iou(a, b):
    """IoU of the pixels two depth images show a voxel at."""
    ma, mb = np.isfinite(a), np.isfinite(b)
    return (ma & mb).sum() / max((ma | mb).sum(), 1)


def test_from_dense_of_dense_renders_what_the_model_renders(bunny6):
    v = bunny6
    again = ssbvb.Voxels.from_dense(v.dense(), origin=v.origin, voxel_size=v.voxel_size)
    assert len(again) == len(v)
    camera = ssbvb.Camera((0.3, 0.4, 2.8), (0, 0, 0))
    depths = []
    for voxels in (v, again):
        r = ssbvb.Renderer(size=(96, 72))
        r.add(voxels)
        r.render(camera)
        depths.append(r.depth())
    covered = np.isfinite(depths[0]).sum()
    assert covered > 500, covered
    assert coverage_iou(*depths) >= 0.999


def test_sparse_round_trip_keeps_cells_and_colours(bunny6):
    coords, colors, _ = bunny6.sparse()
    shifted = coords - 40
    v = ssbvb.Voxels.from_sparse(shifted, colors, origin=(1.0, 2.0, 3.0), voxel_size=0.5)
    got_c, got_rgba = cells(v)
    order = np.lexsort(shifted.T[::-1])
    assert np.array_equal(got_c, shifted[order])
    assert np.array_equal(got_rgba, colors[order])
    # Negative coordinates: dense() starts at the smallest one.
    grid = v.dense()
    lo = shifted.min(axis=0)
    assert np.allclose(v.dense_origin, np.array([1.0, 2.0, 3.0]) + lo * 0.5)
    assert (grid[..., 3] > 0).sum() == len(v)


def test_orders_layouts_and_labels_agree():
    rng = np.random.default_rng(7)
    labels = rng.integers(0, 300, size=(9, 7, 5)).astype(np.int32)
    labels[rng.random(labels.shape) < 0.5] = 0
    palette = rng.integers(0, 256, size=(300, 3)).astype(np.uint8)
    base = cells(ssbvb.Voxels.from_dense(labels, palette=palette))
    assert len(base[0]) == (labels > 0).sum()
    # Fortran order, a z-y-x array with order="zyx", and other integer types.
    for grid, order in [
        (np.asfortranarray(labels), "xyz"),
        (np.ascontiguousarray(labels.transpose(2, 1, 0)), "zyx"),
        (labels.astype(np.uint16), "xyz"),
        (labels.astype(np.int16), "xyz"),
    ]:
        got = cells(ssbvb.Voxels.from_dense(grid, order=order, palette=palette))
        assert np.array_equal(got[0], base[0]) and np.array_equal(got[1], base[1])
    # The same voxels as RGB floats, as RGBA bytes, and as K3D's [x, y, z, label] rows.
    rgb = palette[labels].astype(np.float64) / 255.0
    rgb[labels == 0] = 0.0
    as_rgb = cells(ssbvb.Voxels.from_dense(rgb))
    set_nonblack = (palette[labels].any(axis=-1)) & (labels > 0)
    assert len(as_rgb[0]) == set_nonblack.sum()
    xyz = np.argwhere(labels > 0)
    k3d = np.concatenate([xyz, labels[labels > 0][:, None]], axis=1)
    got = cells(ssbvb.Voxels.from_sparse(k3d, palette=palette))
    assert np.array_equal(got[0], base[0]) and np.array_equal(got[1], base[1])


def test_occupancy_takes_one_colour_and_a_broadcast_view_is_read_in_place():
    grid = ball(12)
    v = ssbvb.Voxels.from_dense(grid, color=(255, 0, 0))
    _, colors = cells(v)
    assert len(v) == grid.sum() and (colors == [255, 0, 0, 255]).all()
    # A broadcast (zero-stride) view: a 12 x 12 x 12 slab of one row.
    row = np.zeros((1, 1, 12), bool)
    row[0, 0, 3:9] = True
    v = ssbvb.Voxels.from_dense(np.broadcast_to(row, (12, 12, 12)))
    assert len(v) == 12 * 12 * 6


def test_render_many_is_each_render():
    r = ssbvb.Renderer(size=(40, 30))
    r.add(ssbvb.Voxels.from_dense(ball(16)))
    cams = [ssbvb.Camera.orbit(a, 15, 40, target=(8, 8, 8)) for a in (0, 90, 200)]
    many = r.render_many(cams)
    assert many.shape == (3, 30, 40, 4) and many.dtype == np.uint8
    for k, c in enumerate(cams):
        assert np.array_equal(many[k], r.render(c))
    assert not np.array_equal(many[0], many[1])


def test_smoothing_off_changes_shading_not_coverage():
    v = ssbvb.Voxels.from_dense(ball(20))
    cam = ssbvb.Camera.orbit(30, 20, 45, target=(10, 10, 10))
    out = []
    for smooth in (True, False):
        r = ssbvb.Renderer(size=(64, 48), smooth=smooth)
        r.add(v)
        out.append((r.render(cam), r.depth()))
    (a, da), (b, db) = out
    assert np.array_equal(np.isfinite(da), np.isfinite(db))
    assert not np.array_equal(a, b)


def test_two_objects_with_transforms_and_instance_ids():
    v = ssbvb.Voxels.from_dense(ball(10))
    # Instance ids are read from the SSBVB: the paper's form has one.
    r = ssbvb.Renderer(size=(64, 32), pipeline="ssbvb-unique")
    left = np.eye(4)
    left[0, 3] = -12.0
    r.add(v, transform=left)
    r.add(v)
    r.render()
    ids = r.instance_ids()
    seen = set(np.unique(ids).tolist())
    assert {0, 1}.issubset(seen), seen
    # The moved copy is the left one.
    cols0 = np.nonzero((ids == 0).any(axis=0))[0]
    cols1 = np.nonzero((ids == 1).any(axis=0))[0]
    assert cols0.mean() < cols1.mean()


def test_the_image_shows_in_jupyter_and_is_a_plain_array_too(tmp_path):
    image = ssbvb.render(ssbvb.Voxels.from_dense(ball(8)), size=(32, 24))
    png = image._repr_png_()
    assert png[:8] == b"\x89PNG\r\n\x1a\n"
    # The PNG holds the pixels (read back by an independent decoder).
    image.save(tmp_path / "ball.png")
    assert np.array_equal(read_png(tmp_path / "ball.png"), np.asarray(image))
    assert not list(tmp_path.glob("*.tmp"))
    plain = np.asarray(image)
    assert type(plain) is np.ndarray and plain.shape == (24, 32, 4)
    r = ssbvb.Renderer(size=(32, 24))
    r.add(ssbvb.Voxels.from_dense(ball(8)))
    r.render()
    info = r.info
    assert info["form"] in ssbvb.forms() or info["pipeline"]
    assert info["frame"]["passes"] and info["adapter"]
    assert info["memory"][0]["voxels"] > 0
    assert info["engine_ms"] > 0
    # The counters of the frame: the march took steps.
    counters = info["counted"]["counters"]
    assert any(isinstance(v, (int, float)) and v > 0 for v in counters.values()), counters


@pytest.mark.parametrize("pipeline", ["ssbvb-pixel", "esvo"])
def test_a_named_pipeline_draws_the_same_coverage(pipeline):
    v = ssbvb.Voxels.from_dense(ball(16))
    cam = ssbvb.Camera.orbit(20, 10, 40, target=(8, 8, 8))
    depth = []
    for p in (None, pipeline):
        r = ssbvb.Renderer(size=(48, 36), pipeline=p)
        r.add(v)
        r.render(cam)
        depth.append(r.depth())
    assert coverage_iou(*depth) >= 0.99


def test_new_content_keeps_the_device_and_draws_what_a_fresh_renderer_draws():
    a = ssbvb.Voxels.from_dense(ball(12))
    b = ssbvb.Voxels.from_sparse(np.argwhere(ball(16))[::2], color=(200, 60, 60))
    cam = ssbvb.Camera.orbit(25, 15, 40, target=(8, 8, 8))
    fresh = ssbvb.Renderer(size=(48, 36))
    fresh.add(b)
    want = fresh.render(cam)
    r = ssbvb.Renderer(size=(48, 36))
    r.add(a)
    before = r.render(cam)
    r.clear()
    r.add(b)
    got = r.render(cam)
    assert r.info["pipelines_kept"] is True
    assert not np.array_equal(before, got)
    assert np.array_equal(got, want)
    # The one-call render keeps its renderer too.
    first = ssbvb.render(a, size=(48, 36), camera=cam)
    second = ssbvb.render(b, size=(48, 36), camera=cam)
    assert np.array_equal(first, before) and np.array_equal(second, want)
