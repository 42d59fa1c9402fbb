"""Bad input gets a Python exception with a clear message, never a crash; an empty grid
renders the background and warns; a grid past the finest level is refused before any
allocation."""

import numpy as np
import pytest

import ssbvb
from conftest import BUNNY, DEFAULT_SCENE, ball


def test_float64_with_five_channels_is_a_value_error():
    with pytest.raises(ValueError, match=r"\(X, Y, Z, 4\) or \(X, Y, Z, 3\), got \[2, 2, 2, 5\]"):
        ssbvb.Voxels.from_dense(np.zeros((2, 2, 2, 5)))


def test_a_2d_array_is_a_value_error():
    with pytest.raises(ValueError, match=r"got \[4, 4\]"):
        ssbvb.Voxels.from_dense(np.ones((4, 4), bool))


def test_a_missing_file_is_file_not_found():
    with pytest.raises(FileNotFoundError):
        ssbvb.voxelize("no/such/model.obj", 5)
    with pytest.raises(FileNotFoundError):
        ssbvb.render("no/such/scene.ron")


def test_level_99_is_a_value_error():
    with pytest.raises(ValueError, match="level must be 1..=16, got 99"):
        ssbvb.voxelize(BUNNY, 99)


def test_a_nan_origin_is_a_value_error():
    with pytest.raises(ValueError, match="origin must be finite"):
        ssbvb.Voxels.from_dense(ball(4), origin=(0.0, float("nan"), 0.0))


def test_a_zero_voxel_size_is_a_value_error():
    with pytest.raises(ValueError, match="voxel_size must be a positive finite number"):
        ssbvb.Voxels.from_dense(ball(4), voxel_size=0.0)


def test_non_integer_coordinates_are_a_type_error():
    with pytest.raises(TypeError, match="sparse coordinates must be an integer type, got float32"):
        ssbvb.Voxels.from_sparse(np.zeros((3, 3), np.float32))
    with pytest.raises(TypeError, match="must hold numbers"):
        ssbvb.Voxels.from_sparse(np.array([["a", "b", "c"]]))


def test_labels_without_a_palette_are_a_value_error():
    with pytest.raises(ValueError, match="an integer grid is labels: give palette="):
        ssbvb.Voxels.from_dense(np.ones((3, 3, 3), np.int32))
    with pytest.raises(ValueError, match=r"\[x, y, z, label\] rows: give palette="):
        ssbvb.Voxels.from_sparse(np.ones((3, 4), np.int32))
    with pytest.raises(ValueError, match="label 5 at \\[0, 0, 0\\] has no palette row"):
        ssbvb.Voxels.from_dense(np.full((1, 1, 1), 5), palette=np.zeros((3, 3), np.uint8))


def test_float_colours_outside_0_1_are_refused_with_their_element():
    rgba = np.zeros((2, 2, 2, 4), np.float32)
    rgba[1, 0, 1] = [0.5, 2.0, 0.0, 1.0]
    with pytest.raises(ValueError, match=r"element \[1, 0, 1, 1\] is 2"):
        ssbvb.Voxels.from_dense(rgba)


def test_an_empty_grid_renders_the_background_and_warns():
    with pytest.warns(ssbvb.SsbvbWarning, match="no voxel is set"):
        v = ssbvb.Voxels.from_dense(np.zeros((8, 8, 8), bool))
    assert len(v) == 0
    r = ssbvb.Renderer(size=(16, 12))
    with pytest.warns(ssbvb.SsbvbWarning, match="no voxel is set"):
        r.add(v)
    image = r.render()
    assert image.shape == (12, 16, 4)
    assert (image == image[0, 0]).all()
    assert np.isinf(r.depth()).all()


def test_a_grid_of_2_14_cells_on_an_axis_is_refused_before_allocating():
    # A broadcast view claims 16384 x 16384 x 16384 cells (4 TiB) in one byte: read in
    # place, refused from its shape; a copy would run out of memory instead.
    huge = np.broadcast_to(np.ones((1, 1, 1), bool), (2**14, 2**14, 2**14))
    with pytest.raises(ValueError, match="16384 cells along axis 0"):
        ssbvb.Voxels.from_dense(huge)
    with pytest.raises(ValueError, match="cells along axis 1"):
        ssbvb.Voxels.from_sparse(np.array([[0, 0, 0], [0, 2**14, 0]]))


def test_bad_renderer_and_camera_arguments():
    with pytest.raises(ValueError, match="size must be"):
        ssbvb.Renderer(size=(0, 10))
    with pytest.raises(ValueError, match="is neither a form"):
        ssbvb.Renderer(pipeline="no-such-form")
    with pytest.raises(ValueError, match="gpu_budget_mib must be 1..="):
        ssbvb.Renderer(gpu_budget_mib=0)
    with pytest.raises(ValueError, match="backend must be"):
        ssbvb.Renderer(backend="opengl")
    with pytest.raises(ValueError, match="eye and target must differ"):
        ssbvb.Camera((1, 1, 1), (1, 1, 1))
    with pytest.raises(ValueError, match="fov_y"):
        ssbvb.Camera((0, 0, 3), fov_y=180)
    r = ssbvb.Renderer(size=(8, 8))
    with pytest.raises(TypeError, match="add takes Voxels or the path"):
        r.add(42)
    with pytest.raises(ValueError, match="transform must be affine"):
        r.add(ssbvb.Voxels.from_dense(ball(4)), transform=np.ones((4, 4)))
    with pytest.raises(ValueError, match="render a frame first"):
        r.depth()
    with pytest.raises(ValueError, match="order must be"):
        ssbvb.Voxels.from_dense(ball(4), order="yxz")
    with pytest.raises(ValueError, match="color: component 1"):
        ssbvb.Voxels.from_dense(ball(4), color=(10, 300, 0))


def test_a_level_for_a_scene_is_a_value_error():
    with pytest.raises(ValueError, match="default.ron: level applies to a model file"):
        ssbvb.render(DEFAULT_SCENE, level=5)


def test_a_malformed_scene_is_an_ssbvb_error_naming_the_file(tmp_path):
    bad = tmp_path / "bad.ron"
    bad.write_text("Scene(objects: [ (model: 3) ])")
    with pytest.raises(ssbvb.Error, match="bad.ron"):
        ssbvb.render(bad, size=(8, 8))
