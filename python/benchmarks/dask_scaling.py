"""Benchmark (not a test) of nbhd.dask on a distributed.LocalCluster: a generated cloud several
times larger than one worker's memory limit is tiled, then its k-nearest table and its normals
are computed tile by tile; reported per worker count: times, peak memory of every worker
process (its largest resident set), and the speed-up over one worker.

    python python/benchmarks/dask_scaling.py --points 25000000 --memory-limit 200MB --workers 1,2

The cloud is an aerial-scan-like terrain (x, y uniform over a square, z a smooth relief plus
noise), generated chunk by chunk on the workers (never whole in one process). Results go to a
store under --dir (deleted afterwards). Each task runs nbhd on one thread (threads=1), so the
workers are the parallelism.
"""

from __future__ import annotations

import argparse
import os
import resource
import shutil
import tempfile
import time

import dask
import dask.array as da
import numpy as np


def terrain(block, block_info=None, dtype_name="float64"):
    loc = block_info[None]["chunk-location"][0]
    n = block_info[None]["chunk-shape"][0]
    rng = np.random.default_rng(1000 + loc)
    side = 1000.0
    xy = rng.random((n, 2)) * side
    z = 5 * np.sin(xy[:, 0] / 50) * np.cos(xy[:, 1] / 70) + rng.normal(scale=0.05, size=n)
    return np.column_stack([xy, z]).astype(dtype_name)


def peak_rss_mb():
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


def run(workers, args):
    import distributed
    from nbhd import dask as ndask

    # the memory limit as a hard bound: no pausing or spilling (the tasks hold nothing to spill;
    # their results are files), a worker above 95 % of it is killed, failing the run
    dask.config.set({"distributed.worker.memory.target": False,
                     "distributed.worker.memory.spill": False,
                     "distributed.worker.memory.pause": False,
                     "distributed.worker.memory.terminate": 0.95})
    cluster = distributed.LocalCluster(
        n_workers=workers, threads_per_worker=1, processes=True,
        memory_limit=args.memory_limit, dashboard_address=":0",
    )
    client = distributed.Client(cluster)
    store = tempfile.mkdtemp(prefix="nbhd-dask-bench-", dir=args.dir)
    try:
        base = client.run(peak_rss_mb)
        blank = da.empty((args.points, 3), chunks=(args.chunk, 3), dtype=args.dtype)
        pts = da.map_blocks(terrain, blank, dtype=args.dtype, dtype_name=args.dtype)
        t0 = time.perf_counter()
        cloud = ndask.tile_array(pts, store, points_per_tile=args.points_per_tile)
        t1 = time.perf_counter()
        cloud.knn(args.k, threads=1)
        t2 = time.perf_counter()
        cloud.normals(k=15, epsilon=args.epsilon, epsilon_units="absolute", threads=1)
        t3 = time.perf_counter()
        peak = client.run(peak_rss_mb)
        return {
            "workers": workers, "tiles": cloud.tiles, "tile_s": t1 - t0, "knn_s": t2 - t1,
            "normals_s": t3 - t2, "total_s": t3 - t0,
            "peak_mb": sorted(peak.values()), "idle_mb": sorted(base.values()),
            # a worker killed above its limit comes back under a new address
            "restarted": len(set(peak) - set(base)),
        }
    finally:
        client.close()
        cluster.close()
        shutil.rmtree(store, ignore_errors=True)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--points", type=int, default=25_000_000)
    ap.add_argument("--dtype", default="float64", choices=["float32", "float64"])
    ap.add_argument("--chunk", type=int, default=250_000)
    ap.add_argument("--points-per-tile", type=int, default=80_000)
    ap.add_argument("--k", type=int, default=10)
    ap.add_argument("--epsilon", type=float, default=3.0, help="absolute ε of the normals")
    ap.add_argument("--memory-limit", default="200MB")
    ap.add_argument("--workers", default="1,2")
    ap.add_argument("--dir", default=None, help="where the store goes (default: the temp dir)")
    args = ap.parse_args()
    size_mb = args.points * 3 * np.dtype(args.dtype).itemsize / 1e6
    print(f"cloud: {args.points} points {args.dtype} = {size_mb:.0f} MB; "
          f"worker memory_limit {args.memory_limit}; k = {args.k}; "
          f"normals k = 15, ε = {args.epsilon}; cpus {os.cpu_count()}")
    rows = []
    for w in args.workers.split(","):
        rows.append(run(int(w), args))
        print("done:", rows[-1], flush=True)
    one = rows[0]["total_s"]
    print("| workers | tiles | tiling (s) | kNN table (s) | normals (s) | total (s) | speed-up | "
          "peak RSS per worker (MB) | idle RSS (MB) | workers killed |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for r in rows:
        print(f"| {r['workers']} | {r['tiles']} | {r['tile_s']:.1f} | {r['knn_s']:.1f} | "
              f"{r['normals_s']:.1f} | {r['total_s']:.1f} | {one / r['total_s']:.2f} | "
              f"{', '.join(f'{m:.0f}' for m in r['peak_mb'])} | "
              f"{', '.join(f'{m:.0f}' for m in r['idle_mb'])} | {r['restarted']} |")


if __name__ == "__main__":
    main()
