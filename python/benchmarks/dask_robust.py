"""Benchmark (not a test) of the robust smoothing on Dask tiles against one machine: the same
noisy cube surface smoothed by ``nbhd.smooth_robust`` in this process and by
``TiledCloud.smooth_robust`` on a LocalCluster, alternating, ``--repeat`` times each; checks that
the results are the same bits and prints wall times, the rounds the run took, the halos, and
each worker's peak resident set (``VmHWM``).

    python python/benchmarks/dask_robust.py --points 400000 --workers 2 --grid 2,2,1
"""

import argparse
import shutil
import tempfile
import time

import dask.array as da
import distributed
import numpy as np

import nbhd
from nbhd import dask as nd


def cube(n, noise, seed=39):
    rng = np.random.default_rng(seed)
    p = rng.random((n, 3))
    face = rng.integers(0, 6, n)
    p[np.arange(n), face % 3] = (face // 3).astype(float)
    h = 0.5 * np.sqrt(6.0 / n)
    return p + rng.normal(scale=noise * h, size=p.shape)


def peak_rss_mb():
    with open("/proc/self/status") as f:
        for line in f:
            if line.startswith("VmHWM:"):
                return int(line.split()[1]) / 1024
    return float("nan")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--points", type=int, default=400_000)
    ap.add_argument("--noise", type=float, default=1.0, help="in mean spacings")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--grid", default="2,2,1")
    ap.add_argument("--repeat", type=int, default=2)
    a = ap.parse_args()
    grid = tuple(int(g) for g in a.grid.split(","))
    pts = cube(a.points, a.noise)
    client = distributed.Client(distributed.LocalCluster(
        n_workers=a.workers, threads_per_worker=1, dashboard_address=":0", silence_logs=40))
    store = tempfile.mkdtemp(prefix="nbhd-robust-")
    try:
        one, tiled = [], []
        for i in range(a.repeat):
            t0 = time.perf_counter()
            ref = nbhd.smooth_robust(pts)
            one.append(time.perf_counter() - t0)
            t0 = time.perf_counter()
            cloud = nd.tile_array(da.from_array(pts, chunks=(100_000, 3)), f"{store}/{i}",
                                  grid=grid)
            r = cloud.smooth_robust(client=client)
            got = r.assemble()
            tiled.append(time.perf_counter() - t0)
            assert got["points"].tobytes() == ref["points"].tobytes(), "tiled result differs"
            assert got["noise"].tobytes() == ref["noise"].tobytes()
        rss = client.run(peak_rss_mb)
        print(f"{a.points} points, noise {a.noise} h, {len(r.parts)} tiles, {a.workers} workers")
        print(f"iterations {len(ref['moved'])}, wide {ref['wide_iterations']}, "
              f"rounds {r.status['rounds']}, halos grown {r.status['grown']}")
        print("halo widths (in h):", [round(p["halo"] / ref["spacing"], 1) for p in r.parts])
        print("gathered / owned:", round(sum(p["points"] for p in r.parts) / a.points, 3))
        print("one machine s:", [round(t, 2) for t in one])
        print("tiled s (incl. tiling):", [round(t, 2) for t in tiled])
        print("worker peak RSS MB:", {k[-5:]: round(v) for k, v in rss.items()})
    finally:
        client.close()
        shutil.rmtree(store, ignore_errors=True)


if __name__ == "__main__":
    main()
