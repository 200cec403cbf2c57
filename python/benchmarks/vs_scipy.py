"""Benchmark (not a test) of nbhd.spatial.cKDTree against scipy.spatial.cKDTree, side by side in
one process: for each case the two run alternately (scipy, nbhd, scipy, nbhd, ...) for --reps
rounds after one untimed round whose answers are checked equal, and the table reports each side's
median time and the median of the per-round ratios scipy / nbhd (> 1: nbhd is faster) with their
spread (min–max). Only the ratios mean anything on a shared machine.

    python python/benchmarks/vs_scipy.py --points 1000000 --workers 2 --reps 5

Clouds (f64, fixed seeds): ``cube``, uniform in the unit cube; ``torus``, a scan-like surface —
points uniform by area on a torus (major radius 1, minor 0.35, the library's own torus shape) with
Gaussian noise of 0.1 % of the major radius along the normal. Every query batch is the cloud
itself (each point asks for its own neighbourhood, as a normal or a filter does). The radius r of
each cloud is chosen from its density so a row holds about --neighbours points (the table reports
the mean row length measured). Both trees are built with the defaults (leafsize 16, balanced);
every call passes ``workers`` (scipy's ``query_pairs`` and ``sparse_distance_matrix`` have no such
argument and run on one thread). ``query_pairs`` uses ``output_type='ndarray'`` and
``sparse_distance_matrix`` ``output_type='coo_matrix'``: the Python set or dict of millions of
entries would time the interpreter, not the trees.
"""

from __future__ import annotations

import argparse
import os
import statistics
import time
from typing import Any, Callable

import numpy as np
import scipy
import scipy.spatial

import nbhd
import nbhd.spatial


def cube(n: int, seed: int) -> np.ndarray:
    return np.random.default_rng(seed).random((n, 3))


def torus(n: int, seed: int, major: float = 1.0, minor: float = 0.35) -> np.ndarray:
    """n points uniform by area on the torus, moved along the normal by N(0, (1e-3 · major)²)."""
    rng = np.random.default_rng(seed)
    u = np.empty(0)
    while len(u) < n:  # the area element ∝ major + minor·cos v: rejection sampling of v
        v = rng.uniform(0, 2 * np.pi, 2 * n)
        keep = rng.uniform(0, major + minor, 2 * n) < major + minor * np.cos(v)
        u = np.concatenate([u, v[keep]])
    v = u[:n]
    w = rng.uniform(0, 2 * np.pi, n)
    rad = minor + rng.normal(0, 1e-3 * major, n)
    ring = major + rad * np.cos(v)
    return np.column_stack((ring * np.cos(w), ring * np.sin(w), rad * np.sin(v)))


def radius_for(name: str, n: int, neighbours: float) -> float:
    """The radius whose ball (cube) or disc (torus surface) holds `neighbours` points on average."""
    if name == "cube":
        return float((3 * neighbours / (4 * np.pi * n)) ** (1 / 3))
    area = 4 * np.pi**2 * 1.0 * 0.35
    return float(np.sqrt(neighbours * area / (np.pi * n)))


def same_knn(a: Any, b: Any) -> bool:
    (da, ia), (db, ib) = a, b
    return bool(np.allclose(da, db, rtol=1e-12, atol=0) and (np.mean(ia == ib) > 0.999))


def same_array(a: Any, b: Any) -> bool:
    return bool(np.array_equal(np.asarray(a), np.asarray(b)))


def same_pairs(a: Any, b: Any) -> bool:
    return same_array(a[np.lexsort((a[:, 1], a[:, 0]))], b)


def same_coo(a: Any, b: Any) -> bool:
    a, b = a.tocsr(), b.tocsr()
    a.sort_indices()
    b.sort_indices()
    return bool(
        a.nnz == b.nnz
        and np.array_equal(a.indptr, b.indptr)
        and np.array_equal(a.indices, b.indices)
        and np.allclose(a.data, b.data, rtol=1e-12, atol=0)
    )


def alternate(
    reps: int, scipy_call: Callable[[], Any], nbhd_call: Callable[[], Any], same: Callable
) -> tuple[float, float, list[float], bool]:
    """One untimed round (answers compared), then `reps` alternating timed rounds."""
    ok = same(scipy_call(), nbhd_call())
    ts, tn = [], []
    for _ in range(reps):
        for call, times in ((scipy_call, ts), (nbhd_call, tn)):
            start = time.perf_counter()
            call()
            times.append(time.perf_counter() - start)
    ratios = [s / t for s, t in zip(ts, tn)]
    return statistics.median(ts), statistics.median(tn), ratios, ok


def cases(pts: np.ndarray, r: float, workers: int, periodic: bool) -> list[tuple[str, Any, Any]]:
    """(name, call on a tree module, comparison) of one cloud."""
    w = workers
    out: list[tuple[str, Any, Any]] = [
        ("build", lambda m: m.cKDTree(pts), lambda a, b: True),
        ("query(k=10)", lambda m, t: t.query(pts, k=10, workers=w), same_knn),
        (
            "query_ball_point(r, return_length=True)",
            lambda m, t: t.query_ball_point(pts, r, return_length=True, workers=w),
            same_array,
        ),
        (
            "query_pairs(r, 'ndarray')",
            lambda m, t: t.query_pairs(r, output_type="ndarray"),
            same_pairs,
        ),
        (
            "sparse_distance_matrix(self, r, 'coo')",
            lambda m, t: t.sparse_distance_matrix(t, r, output_type="coo_matrix"),
            same_coo,
        ),
        ("query(k=10, p=1)", lambda m, t: t.query(pts, k=10, p=1, workers=w), same_knn),
        ("query(k=10, p=inf)", lambda m, t: t.query(pts, k=10, p=np.inf, workers=w), same_knn),
        (
            "query_ball_point(r, p=1, return_length)",
            lambda m, t: t.query_ball_point(pts, r, p=1, return_length=True, workers=w),
            same_array,
        ),
        (
            "query_ball_point(r, p=inf, return_length)",
            lambda m, t: t.query_ball_point(pts, r, p=np.inf, return_length=True, workers=w),
            same_array,
        ),
        (
            "query(k=10, eps=0.5)",
            lambda m, t: t.query(pts, k=10, eps=0.5, workers=w),
            lambda a, b: True,  # approximate: both within scipy's bound, not equal
        ),
    ]
    if periodic:
        out += [
            ("periodic build (boxsize=1)", lambda m: m.cKDTree(pts, boxsize=1.0), lambda a, b: True),
            ("periodic query(k=10)", "periodic", same_knn),
            ("periodic query_ball_point(r, return_length)", "periodic-ball", same_array),
        ]
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--points", type=int, default=1_000_000)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--reps", type=int, default=5)
    parser.add_argument("--neighbours", type=float, default=20.0)
    parser.add_argument("--clouds", default="cube,torus")
    parser.add_argument("--only", default="", help="comma-separated substrings of case names")
    args = parser.parse_args()
    only = [s for s in args.only.split(",") if s]
    load = os.getloadavg()[0]
    print(
        f"nbhd {nbhd.__version__} vs scipy {scipy.__version__}; {args.points} points, "
        f"workers={args.workers}, {args.reps} alternating rounds; "
        f"{time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}; "
        f"load average {load:.1f} on {os.cpu_count()} CPUs"
    )
    print()
    print("| cloud | call | scipy s | nbhd s | ratio (median) | spread | row |")
    print("|---|---|---:|---:|---:|---|---:|")
    for name in args.clouds.split(","):
        pts = cube(args.points, 1) if name == "cube" else torus(args.points, 2)
        r = radius_for(name, args.points, args.neighbours)
        trees = {m: m.cKDTree(pts) for m in (scipy.spatial, nbhd.spatial)}
        periodic = {}
        row = float(np.mean(trees[scipy.spatial].query_ball_point(pts[:: 97], r, return_length=True)))
        for case, call, same in cases(pts, r, args.workers, name == "cube"):
            if only and not any(s in case for s in only):
                continue
            if case.startswith("periodic") and not periodic:
                periodic = {m: m.cKDTree(pts, boxsize=1.0) for m in (scipy.spatial, nbhd.spatial)}
            if call == "periodic":
                calls = [lambda m=m: periodic[m].query(pts, k=10, workers=args.workers)
                         for m in (scipy.spatial, nbhd.spatial)]
            elif call == "periodic-ball":
                calls = [
                    lambda m=m: periodic[m].query_ball_point(
                        pts, r, return_length=True, workers=args.workers
                    )
                    for m in (scipy.spatial, nbhd.spatial)
                ]
            elif "build" in case:
                calls = [lambda m=m, c=call: c(m) for m in (scipy.spatial, nbhd.spatial)]
            else:
                calls = [lambda m=m, c=call: c(m, trees[m]) for m in (scipy.spatial, nbhd.spatial)]
            ts, tn, ratios, ok = alternate(args.reps, calls[0], calls[1], same)
            print(
                f"| {name} | {case} | {ts:.3f} | {tn:.3f} | {statistics.median(ratios):.2f} | "
                f"{min(ratios):.2f}–{max(ratios):.2f} | {row:.1f} |"
                + ("" if ok else " **answers differ**"),
                flush=True,
            )


if __name__ == "__main__":
    main()
