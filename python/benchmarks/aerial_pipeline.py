"""Benchmark (not a test): the LiDAR pipeline of python/DASK.md on the seeded synthetic aerial
survey (``nbhd.aerial_tile``, src/shapes/aerial.rs) as one Dask job on a LocalCluster —

1. the survey written as LAZ tiles (one task per tile, every LAS record kept),
2. ``tile_files`` of those tiles,
3. statistical outlier removal, the kept points as a tiled cloud (``select``),
4. a voxel grid, its centroids as a tiled cloud (``VoxelResult.cloud``),
5. normals and the robust smoothing of the centroids,
6. LAZ tiles written back: smoothed positions, normals and surface variation (extra bytes
   ``NormalX/Y/Z``, ``Curvature``), and the LAS records of each voxel's point nearest its
   centroid (class, returns, GPS time, intensity, strip, scan angle)

— printing per stage the wall time, the workers' CPU time and each worker's peak resident set.
``--check`` runs the same pipeline in this process with the one-machine calls and compares
every stage's result bit for bit.

    python python/benchmarks/aerial_pipeline.py --points 2000000 --workers 2 --check
"""

import argparse
import math
import os
import resource
import shutil
import tempfile
import time

import dask
import distributed
import numpy as np

import nbhd
from nbhd import dask as nd

DENSITY = 16.0  # pulses per m² of the generator's default; about 1.4 points per pulse


def worker_usage():
    """This worker process's CPU seconds and peak resident set (MB)."""
    r = resource.getrusage(resource.RUSAGE_SELF)
    with open("/proc/self/status") as f:
        hwm = next(int(line.split()[1]) for line in f if line.startswith("VmHWM:"))
    return r.ru_utime + r.ru_stime, hwm / 1024


def generate_tile(x0, y0, side, path):
    """Task: the survey's points in one square tile, written as LAZ with their records."""
    a = nbhd.aerial_tile(x0, y0, x0 + side, y0 + side, density=DENSITY)
    scalars = {k: v for k, v in a.items() if k != "positions"}
    nbhd.write(path, a["positions"], scalars=scalars, precision="keep")
    return len(a["positions"])


def original_rows(clean_rows, removed):
    """The rows of the input that the kept cloud's rows ``clean_rows`` are: a kept row r is
    the input row r + j, j the number of removed rows below it (``select``'s renumbering
    inverted through the removed rows less their rank)."""
    shifted = removed - np.arange(len(removed))
    return clean_rows + np.searchsorted(shifted, clean_rows, side="right")


def write_tile(robust_path, normals_path, voxel_path, removed, files, starts, out):
    """Task: one tile of the result as LAZ: the robust part's points and normals, the normals
    pass's surface variation, and the records of each voxel's nearest input point."""
    with np.load(robust_path) as z:
        points, normals = z["points"], z["normals"]
    with np.load(normals_path) as z:
        variation = z["surface_variation"]
    with np.load(voxel_path) as z:
        nearest = z["nearest"].astype(np.int64)
    rows = original_rows(nearest, removed)
    f_of = np.searchsorted(starts, rows, side="right") - 1
    records = {}
    for f in np.unique(f_of):
        sel = np.flatnonzero(f_of == f)
        src = nbhd.read(files[f])["scalars"]
        for k, v in src.items():
            records.setdefault(k, np.empty(len(rows), v.dtype))[sel] = v[rows[sel] - starts[f]]
    records["Curvature"] = variation
    nbhd.write(out, points, normals=normals, scalars=records, precision="keep")
    return len(points)


class Stages:
    """Wall time and the workers' CPU time of each stage."""

    def __init__(self, client):
        self.client = client
        self.rows = []
        self.start = None

    def cpu(self):
        return sum(c for c, _ in self.client.run(worker_usage).values())

    def __call__(self, name):
        now, cpu = time.perf_counter(), self.cpu()
        if self.start is not None:
            n0, c0, label = self.start
            self.rows.append((label, now - n0, cpu - c0))
        self.start = (now, cpu, name)

    def print(self, points):
        peaks = [m for _, m in self.client.run(worker_usage).values()]
        print("| stage | wall s | workers' CPU s |")
        print("|---|---:|---:|")
        for name, wall, cpu in self.rows:
            print(f"| {name} | {wall:.1f} | {cpu:.1f} |")
        wall = sum(r[1] for r in self.rows)
        cpu = sum(r[2] for r in self.rows)
        print(f"| **total** ({points:,} points) | {wall:.1f} | {cpu:.1f} |")
        print("peak resident set per worker (MB):", ", ".join(f"{m:.0f}" for m in peaks))


def one_machine(files, k, ratio, leaf):
    pts = np.concatenate([nbhd.read(f)["positions"] for f in files])
    kept = nbhd.KdTree(pts).remove_statistical_outliers(k=k, std_ratio=ratio)
    vox = nbhd.voxel_grid(pts[kept], leaf)
    c = vox["centroids"]
    normals, variation, _ = nbhd.normals(c, k=15)
    robust = nbhd.smooth_robust(c)
    return kept, vox, normals, variation, robust


def same(a, b):
    return a.dtype == b.dtype and a.shape == b.shape and a.tobytes() == b.tobytes()


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--points", type=int, default=2_000_000)
    ap.add_argument("--tile-points", type=int, default=500_000, help="input points per LAZ tile")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--memory-limit", default="2GB", help="per worker")
    ap.add_argument("--sor-k", type=int, default=10)
    ap.add_argument("--sor-ratio", type=float, default=3.0)
    ap.add_argument("--leaf", type=float, default=0.3, help="voxel edge, m")
    ap.add_argument("--dir", default=None, help="working directory (default: a new temp one)")
    ap.add_argument("--check", action="store_true", help="compare with one machine")
    a = ap.parse_args()

    per_pulse = 1.4  # points per pulse of the generator, measured
    side = math.sqrt(a.tile_points / (DENSITY * per_pulse))
    tiles = max(1, round(math.sqrt(a.points / a.tile_points)))
    work = a.dir or tempfile.mkdtemp(prefix="nbhd-aerial-")
    os.makedirs(work, exist_ok=True)
    client = distributed.Client(distributed.LocalCluster(
        n_workers=a.workers, threads_per_worker=1, memory_limit=a.memory_limit,
        dashboard_address=":0", silence_logs=40))
    stage = Stages(client)
    try:
        stage("generate LAZ tiles")
        files = [os.path.join(work, f"in_{i:03d}_{j:03d}.laz")
                 for i in range(tiles) for j in range(tiles)]
        counts = dask.compute(*[
            dask.delayed(generate_tile, pure=False)(i * side, j * side, side, files[i * tiles + j])
            for i in range(tiles) for j in range(tiles)])
        n = sum(counts)
        starts = np.concatenate([[0], np.cumsum(counts)]).astype(np.int64)
        stage("tile_files")
        cloud = nd.tile_files(files, os.path.join(work, "store"))
        stage("outlier removal")
        kept = cloud.remove_statistical_outliers(k=a.sor_k, std_ratio=a.sor_ratio)
        clean = cloud.select(kept)
        stage("voxel grid")
        vox = clean.voxel_grid(a.leaf)
        vc = vox.cloud()
        stage("normals")
        nres = vc.normals(k=15)
        stage("robust smoothing")
        rres = vc.smooth_robust()
        stage("write LAZ tiles")
        removed = kept.removed()
        done = dask.compute(*[
            dask.delayed(write_tile, pure=False)(
                rp["path"], np_["path"], vp["path"], removed, files, starts,
                os.path.join(work, f"out_{t:04d}.laz"))
            for t, (rp, np_, vp) in enumerate(zip(rres.parts, nres.parts, vox.parts))])
        stage(None)
        print(f"{n:,} input points in {len(files)} LAZ tiles, {kept.n - len(removed):,} kept, "
              f"{vc.n:,} voxels in {vc.tiles} tiles, {sum(done):,} points written")
        stage.print(n)
        if a.check:
            t0 = time.perf_counter()
            k_ref, v_ref, n_ref, s_ref, r_ref = one_machine(files, a.sor_k, a.sor_ratio, a.leaf)
            print(f"one machine: {time.perf_counter() - t0:.1f} s")
            got_v = vox.assemble()
            got_n = nres.assemble()
            got_r = rres.assemble()
            checks = {
                "kept": np.array_equal(kept.assemble(), k_ref),
                "voxels": all(same(got_v[key], v_ref[key]) for key in v_ref),
                "normals": same(got_n["normals"], n_ref),
                "surface variation": same(got_n["surface_variation"], s_ref),
                "robust points": same(got_r["points"], r_ref["points"]),
                "robust normals": same(got_r["normals"], r_ref["normals"]),
            }
            print("identical to one machine:", checks)
            if not all(checks.values()):
                raise SystemExit(1)
    finally:
        client.close()
        if a.dir is None:
            shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    main()
