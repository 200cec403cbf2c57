"""Open3D's estimate_normals(KDTreeSearchParamKNN(16)) timed on the torus that bench_normals
writes (raw float32 x y z records), wall and process CPU time: the normals of the point and its 15 nearest others, as
cpp_examples/bench_normals.cpp times nbhd and PCL. Run by scripts/bench-normals.sh, which sets
OMP_NUM_THREADS before Python starts (Open3D's OpenMP reads it once).

    python bench_normals_open3d.py POINTS.f32 REPS
"""
import sys
import time

import numpy as np
import open3d as o3d


def main():
    path, reps = sys.argv[1], int(sys.argv[2])
    xyz = np.fromfile(path, dtype="<f4").reshape(-1, 3).astype(np.float64)
    times, cpu = [], []
    for _ in range(reps):
        # a fresh cloud each time: with normals present Open3D only re-orients them
        pc = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(xyz))
        t, c = time.perf_counter(), time.process_time()
        pc.estimate_normals(o3d.geometry.KDTreeSearchParamKNN(16))
        times.append(time.perf_counter() - t)
        cpu.append(time.process_time() - c)
    n = np.asarray(pc.normals)
    assert n.shape == xyz.shape and np.all(np.abs(np.linalg.norm(n, axis=1) - 1) < 1e-6)
    # wall and process CPU time (all threads), medians in ms, as bench_normals prints them
    med = lambda v: 1000 * sorted(v)[len(v) // 2]
    print(f"{med(times):.0f} | {med(cpu):.0f}")


if __name__ == "__main__":
    main()
