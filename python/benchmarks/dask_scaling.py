"""Benchmark (not a test) of nbhd.dask on a distributed.LocalCluster: a generated cloud larger
than one worker's memory limit is tiled, then its k-nearest table and its normals are computed
tile by tile; reported per worker count: times, the CPU time the workers spent, the peak memory
of every worker process and the speed-up over one worker.

    python python/benchmarks/dask_scaling.py --points 12000000 --memory-limit 150MB --workers 1,2

The cloud is an aerial-scan-like terrain over 1 km x 1 km (z a smooth relief plus noise,
coordinates on a 1 cm grid as in LAS files), generated chunk by chunk on the workers (never whole
in one process): each chunk is a strip along x, as flight lines or delivered tiles arrive
(``--scattered``: every chunk spread over the whole square instead, the worst case for the tiling,
whose every tile then gathers a piece of every chunk). Results go to a store under --dir
(deleted afterwards). Each task runs nbhd on one thread (threads=1): the workers are the
parallelism.

Peak memory is each worker process's high-water resident set (``VmHWM`` of /proc, the kernel's
exact peak of the resident set Dask's memory limit is about; the same figure as getrusage's
``ru_maxrss``, which is the fallback elsewhere); "idle" is the same before any task. The memory
limit is enforced as a hard bound: no spilling or pausing, a worker above 95 % of it is killed
and restarted by its nanny (the scheduler reruns its tasks; the table counts such kills).
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


def terrain(block, block_info=None, dtype_name="float64", scattered=False):
    info = block_info[None]
    c, n, strips = info["chunk-location"][0], info["chunk-shape"][0], info["num-chunks"][0]
    rng = np.random.default_rng([1000, c])
    side = 1000.0
    if scattered:
        x = rng.random(n) * side
    else:
        x = (c + rng.random(n)) * (side / strips)
    y = rng.random(n) * side
    z = 5 * np.sin(x / 50) * np.cos(y / 70) + rng.normal(scale=0.05, size=n)
    return np.round(np.column_stack([x, y, z]), 2).astype(dtype_name)


def peak_rss_mb():
    """This process's largest resident set so far (MB, 10^6 bytes)."""
    try:
        with open("/proc/self/status") as f:
            for line in f:
                if line.startswith("VmHWM:"):
                    return int(line.split()[1]) * 1024 / 1e6
    except OSError:
        pass
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024 / 1e6


def cpu_s():
    r = resource.getrusage(resource.RUSAGE_SELF)
    return r.ru_utime + r.ru_stime


def run(workers, args):
    import distributed
    from nbhd import dask as ndask

    # the memory limit as a hard bound: no pausing or spilling (the tasks hold nothing to spill;
    # their results are files), a worker above 95 % of it is killed and restarted by its nanny
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
        cpu0 = client.run(cpu_s)
        client_cpu0 = cpu_s()  # this process: the client, the scheduler and the nannies
        blank = da.empty((args.points, 3), chunks=(args.chunk, 3), dtype=args.dtype)
        pts = da.map_blocks(terrain, blank, dtype=args.dtype, dtype_name=args.dtype,
                            scattered=args.scattered)
        t0 = time.perf_counter()
        cloud = ndask.tile_array(pts, store, points_per_tile=args.points_per_tile)
        t1 = time.perf_counter()
        cloud.knn(args.k, threads=1)
        t2 = time.perf_counter()
        cloud.normals(k=args.k_normals, epsilon=args.epsilon, epsilon_units="absolute", threads=1)
        t3 = time.perf_counter()
        peak = client.run(peak_rss_mb)
        cpu1 = client.run(cpu_s)
        return {
            "workers": workers, "tiles": cloud.tiles, "tile_s": t1 - t0, "knn_s": t2 - t1,
            "normals_s": t3 - t2, "total_s": t3 - t0,
            # CPU seconds of each worker process during the run (utime + stime)
            "cpu_s": sorted(cpu1[a] - cpu0.get(a, 0.0) for a in cpu1),
            "client_cpu_s": cpu_s() - client_cpu0,
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
    ap.add_argument("--points", type=int, default=12_000_000)
    ap.add_argument("--dtype", default="float64", choices=["float32", "float64"])
    ap.add_argument("--chunk", type=int, default=100_000)
    ap.add_argument("--scattered", action="store_true",
                    help="every chunk spread over the whole square (default: strips)")
    ap.add_argument("--points-per-tile", type=int, default=25_000)
    ap.add_argument("--k", type=int, default=10)
    ap.add_argument("--k-normals", type=int, default=10)
    ap.add_argument("--epsilon", type=float, default=1.5, help="absolute ε of the normals")
    ap.add_argument("--memory-limit", default="150MB")
    ap.add_argument("--workers", default="1,2",
                    help="worker counts, run in this order (1,2,2,1 cancels a steady drift of "
                    "the machine's load)")
    ap.add_argument("--dir", default=None, help="where the store goes (default: the temp dir)")
    args = ap.parse_args()
    size_mb = args.points * 3 * np.dtype(args.dtype).itemsize / 1e6
    print(f"cloud: {args.points} points {args.dtype} = {size_mb:.0f} MB; "
          f"worker memory_limit {args.memory_limit}; k = {args.k}; "
          f"normals k = {args.k_normals}, ε = {args.epsilon}; cpus {os.cpu_count()}, "
          f"load average {os.getloadavg()[0]:.1f}")
    rows = []
    for w in args.workers.split(","):
        rows.append(run(int(w), args))
        print("done:", rows[-1], flush=True)
    ones = [r["total_s"] for r in rows if r["workers"] == 1] or [rows[0]["total_s"]]
    one = sum(ones) / len(ones)  # speed-up over the mean of the one-worker runs
    cpu_ones = [sum(r["cpu_s"]) for r in rows if r["workers"] == 1] or [sum(rows[0]["cpu_s"])]
    cpu_one = sum(cpu_ones) / len(cpu_ones)
    print(f"load average at the end {os.getloadavg()[0]:.1f}")
    # speed-up: wall-clock over the one-worker runs'; CPU-bound speed-up: the one-worker runs' CPU
    # time over the busiest worker's, i.e. the speed-up if every worker had a core of its own
    # (what the wall clock shows on an idle machine with a core per worker; on a loaded one the
    # workers wait for a core and the wall-clock ratio measures the machine's load)
    print("| workers | tiles | tiling (s) | kNN table (s) | normals (s) | total (s) | speed-up | "
          "CPU per worker (s) | CPU-bound speed-up | client CPU (s) | peak RSS per worker (MB) | "
          "idle RSS (MB) | workers killed |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    for r in rows:
        print(f"| {r['workers']} | {r['tiles']} | {r['tile_s']:.1f} | {r['knn_s']:.1f} | "
              f"{r['normals_s']:.1f} | {r['total_s']:.1f} | {one / r['total_s']:.2f} | "
              f"{', '.join(f'{c:.1f}' for c in r['cpu_s'])} | {cpu_one / max(r['cpu_s']):.2f} | "
              f"{r['client_cpu_s']:.1f} | "
              f"{', '.join(f'{m:.0f}' for m in r['peak_mb'])} | "
              f"{', '.join(f'{m:.0f}' for m in r['idle_mb'])} | {r['restarted']} |")


if __name__ == "__main__":
    main()
