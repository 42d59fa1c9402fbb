"""ssbvb's Python module measured: against matplotlib's ``ax.voxels`` on the same grids and
cameras (a sphere shell and the bunny at 32³ and 64³: time to a saved PNG), the first image
of a 512³ grid holding about 10⁷ voxels (preparation included) and its later frames, and
the Python call's overhead over the engine's own frame at 640×480.

    python crates/python/bench/bench.py [--out DIR] [--skip-matplotlib] [--skip-large]

Writes ``DIR/python_bench.json`` and the images (default ``bench-out/python``). Run from
the repository root with the module installed (``pip install ./crates/python`` or ``cargo
xtask python-test``'s environment) and matplotlib (``pip install matplotlib``).
"""

import argparse
import json
import os
import pathlib
import platform
import statistics
import time

import numpy as np

import ssbvb

ROOT = pathlib.Path(__file__).resolve().parents[3]
SIZE = (640, 480)


def shell(n):
    """A sphere shell two cells thick in an ``n``³ grid."""
    d = np.linalg.norm(np.indices((n, n, n)) - (n - 1) / 2, axis=0)
    r = n / 2 - 1
    return (d <= r) & (d > r - 2)


def bunny(n):
    """The bunny's occupancy and colours at ``n``³ (its level ``log2 n``)."""
    level = int(np.log2(n))
    v = ssbvb.voxelize(ROOT / "assets/models/bunny.obj", level)
    dense = v.dense()
    return dense[..., 3] > 0, dense


def grids():
    for n in (32, 64):
        filled = shell(n)
        rgba = np.zeros(filled.shape + (4,), np.uint8)
        rgba[filled] = (90, 140, 220, 255)
        yield f"shell {n}³", filled, rgba
        filled, rgba = bunny(n)
        yield f"bunny {n}³", filled, rgba


def camera_for(n):
    """The same view for both: from azimuth 30°, elevation 25°, looking at the centre."""
    return ssbvb.Camera.orbit(30, 25, 2.2 * n, target=(n / 2, n / 2, n / 2), fov_y=40)


def time_ssbvb(rgba, n, out):
    """Seconds from the array to a saved PNG: voxels prepared, a renderer opened, one
    frame, the PNG written (``ssbvb.render`` in one call)."""
    t0 = time.perf_counter()
    image = ssbvb.render(ssbvb.Voxels.from_dense(rgba), size=SIZE, camera=camera_for(n))
    image.save(out)
    return time.perf_counter() - t0


def time_ssbvb_warm(renderer, n, out):
    """Seconds for a frame of a new view to a saved PNG with the renderer kept (the device,
    pipeline and voxels already on the GPU: what a notebook re-running a cell pays)."""
    t0 = time.perf_counter()
    renderer.render(camera_for(n)).save(out)
    return time.perf_counter() - t0


def time_matplotlib(filled, rgba, n, out):
    """Seconds from the array to a saved PNG with ``ax.voxels`` at the same size and about
    the same view (Agg backend, 100 dpi; matplotlib's z is up, so the grid's y and z axes
    are swapped for it)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    t0 = time.perf_counter()
    fig = plt.figure(figsize=(SIZE[0] / 100, SIZE[1] / 100), dpi=100)
    ax = fig.add_subplot(projection="3d")
    ax.voxels(filled.transpose(0, 2, 1), facecolors=rgba.transpose(0, 2, 1, 3) / 255.0)
    ax.view_init(elev=25, azim=30)
    ax.set_axis_off()
    fig.savefig(out)
    plt.close(fig)
    return time.perf_counter() - t0


def warm(f, *args, runs=2):
    """The best of ``runs`` calls after one warm-up call (seconds)."""
    f(*args)
    return min(f(*args) for _ in range(runs))


def large(out):
    """A 512³ grid with about 10⁷ voxels (a solid ball of radius 134): the first image,
    preparation included, and the median later frame."""
    n = 512
    idx = np.indices((n, n, n), dtype=np.float32) - (n - 1) / 2
    filled = (idx**2).sum(axis=0) <= 134.0**2
    del idx
    count = int(filled.sum())
    t0 = time.perf_counter()
    voxels = ssbvb.Voxels.from_dense(filled)
    prepared = time.perf_counter() - t0
    r = ssbvb.Renderer(size=SIZE)
    r.add(voxels)
    r.render().save(out / "large.png")
    first = time.perf_counter() - t0
    frames = []
    for a in range(5):
        t = time.perf_counter()
        r.render(ssbvb.Camera.orbit(30 + 10 * a, 20, 2.0 * n, target=(n / 2,) * 3))
        frames.append(time.perf_counter() - t)
    return {
        "voxels": count,
        "prepare_s": prepared,
        "first_image_s": first,
        "later_frame_ms": statistics.median(frames) * 1e3,
        "engine_frame_ms": r.info["frame"]["frame_wall_ms"],
    }


def overhead():
    """The Python call against the engine's own frame and readback at 640×480: the bunny
    at level 8, 20 frames."""
    r = ssbvb.Renderer(size=SIZE)
    r.add(ssbvb.voxelize(ROOT / "assets/models/bunny.obj", 8))
    cam = ssbvb.Camera((0.0, 0.3, 2.6), (0, 0, 0))
    r.render(cam)
    py, engine = [], []
    for _ in range(20):
        t = time.perf_counter()
        r.render(cam)
        py.append((time.perf_counter() - t) * 1e3)
        engine.append(r.info["engine_ms"])
    p, e = statistics.median(py), statistics.median(engine)
    return {"python_ms": p, "engine_ms": e, "overhead": (p - e) / e, "adapter": r.info["adapter"]}


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--out", default="bench-out/python")
    ap.add_argument("--skip-matplotlib", action="store_true")
    ap.add_argument("--skip-large", action="store_true")
    args = ap.parse_args()
    out = pathlib.Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    report = {"machine": platform.platform(), "cpus": os.cpu_count(), "size": SIZE, "grids": []}
    for name, filled, rgba in grids():
        n = filled.shape[0]
        stem = name.replace(" ", "_").replace("³", "")
        row = {"grid": name, "voxels": int(filled.sum())}
        row["ssbvb_s"] = warm(time_ssbvb, rgba, n, out / f"{stem}_ssbvb.png")
        kept = ssbvb.Renderer(size=SIZE)
        kept.add(ssbvb.Voxels.from_dense(rgba))
        row["ssbvb_warm_frame_s"] = warm(time_ssbvb_warm, kept, n, out / f"{stem}_warm.png")
        if not args.skip_matplotlib:
            row["matplotlib_s"] = warm(
                time_matplotlib, filled, rgba, n, out / f"{stem}_matplotlib.png", runs=1
            )
            row["speedup"] = row["matplotlib_s"] / row["ssbvb_s"]
            row["speedup_warm_frame"] = row["matplotlib_s"] / row["ssbvb_warm_frame_s"]
        print(json.dumps(row), flush=True)
        report["grids"].append(row)
    report["overhead"] = overhead()
    print(json.dumps(report["overhead"]), flush=True)
    if not args.skip_large:
        report["large"] = large(out)
        print(json.dumps(report["large"]), flush=True)
    (out / "python_bench.json").write_text(json.dumps(report, indent=2))


if __name__ == "__main__":
    main()
