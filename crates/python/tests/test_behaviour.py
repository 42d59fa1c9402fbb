"""What a Python user relies on: the GIL released during GPU work, Ctrl-C between
frames, warnings as `warnings.warn`, and memory flat over many renders."""

import os
import signal
import sys
import threading
import time

import numpy as np
import pytest

import ssbvb
from conftest import ball


@pytest.fixture(scope="module")
def renderer():
    r = ssbvb.Renderer(size=(48, 32))
    r.add(ssbvb.Voxels.from_dense(ball(16)))
    r.render()
    return r


def test_the_gil_is_released_while_rendering(renderer):
    # With a switch interval of 0.2 s the main thread never hands the GIL over by itself
    # (it runs Python for far less between frames):
    # the counting thread runs only while a call has released it.
    counts = [0]
    stop = threading.Event()

    def count():
        while not stop.is_set():
            counts[0] += 1

    old = sys.getswitchinterval()
    sys.setswitchinterval(0.2)
    try:
        t = threading.Thread(target=count)
        t.start()
        before = counts[0]
        renderer.render_many([ssbvb.Camera.orbit(a, 10, 40, target=(8, 8, 8)) for a in range(4)])
        during = counts[0] - before
        stop.set()
        t.join()
    finally:
        sys.setswitchinterval(old)
    assert during > 1000, during


def test_ctrl_c_stops_render_many_between_frames(renderer):
    cams = [ssbvb.Camera.orbit(a, 10, 40, target=(8, 8, 8)) for a in range(400)]
    timer = threading.Timer(0.3, lambda: os.kill(os.getpid(), signal.SIGINT))
    timer.start()
    t0 = time.perf_counter()
    with pytest.raises(KeyboardInterrupt):
        renderer.render_many(cams)
    timer.cancel()
    # Stopped well before 400 frames.
    one = time.perf_counter()
    renderer.render()
    frame = time.perf_counter() - one
    assert time.perf_counter() - t0 < 0.3 + 50 * frame + 5


def test_engine_warnings_are_python_warnings(tmp_path):
    model = tmp_path / "tri.obj"
    model.write_text("mtllib missing.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl red\nf 1 2 3\n")
    with pytest.warns(ssbvb.SsbvbWarning, match="missing.mtl"):
        ssbvb.voxelize(model, 4)


def rss_mib():
    with open("/proc/self/status") as f:
        for line in f:
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) / 1024
    raise RuntimeError("no VmRSS")


def test_memory_is_flat_over_200_renders(renderer):
    cam = ssbvb.Camera.orbit(30, 10, 40, target=(8, 8, 8))
    for _ in range(20):
        renderer.render(cam)
    start = rss_mib()
    for k in range(200):
        image = renderer.render(cam)
        assert image.shape == (32, 48, 4)
    grown = rss_mib() - start
    # 200 frames of 6 KiB each would be 1.2 MiB if kept; allocator noise stays below 16.
    assert grown < 16, f"RSS grew {grown:.1f} MiB over 200 renders"
