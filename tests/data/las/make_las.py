"""Writes the LAS/LAZ test files of tests/io_las.rs with laspy (and lazrs for LAZ).

    pip install 'laspy[lazrs]'
    python3 tests/data/las/make_las.py

Files (committed; rerunning gives the same points):
  small.las        LAS 1.2, point format 2 (RGB), 300 points, georeferenced coordinates
                   (offset 500000, 4100000, 200; scale 0.001), 16-bit colours
  small.laz        the same points, LAZ-compressed (lazrs)
  small_fmt0.las   LAS 1.4, point format 0 (no colour), 50 points, scale 0.01
  small.ref.txt    the values laspy holds for small.las/small.laz, one point per line:
                   x y z intensity classification red green blue (x y z as Python's repr of
                   the float64 that laspy computes, X * scale + offset)
  small_fmt0.ref.txt  x y z intensity classification of small_fmt0.las
"""
import os

import laspy
import numpy as np

here = os.path.dirname(os.path.abspath(__file__))
rng = np.random.default_rng(20261124)

n = 300
h = laspy.LasHeader(point_format=2, version="1.2")
h.offsets = np.array([500000.0, 4100000.0, 200.0])
h.scales = np.array([0.001, 0.001, 0.001])
las = laspy.LasData(h)
t = rng.uniform(0, 2 * np.pi, n)
las.x = 500000.0 + 25.0 * np.cos(t) + rng.normal(0, 0.01, n)
las.y = 4100000.0 + 25.0 * np.sin(t) + rng.normal(0, 0.01, n)
las.z = 200.0 + rng.uniform(0, 10, n)
las.intensity = rng.integers(0, 65536, n, dtype=np.uint16)
las.classification = rng.choice(np.array([1, 2, 5, 6, 9], dtype=np.uint8), n)
las.red = rng.integers(0, 65536, n, dtype=np.uint16)
las.green = rng.integers(0, 65536, n, dtype=np.uint16)
las.blue = rng.integers(0, 65536, n, dtype=np.uint16)
las.write(os.path.join(here, "small.las"))
las.write(os.path.join(here, "small.laz"), laz_backend=laspy.LazBackend.Lazrs)

back = laspy.read(os.path.join(here, "small.las"))
with open(os.path.join(here, "small.ref.txt"), "w") as f:
    for i in range(n):
        f.write(
            f"{float(back.x[i])!r} {float(back.y[i])!r} {float(back.z[i])!r} "
            f"{int(back.intensity[i])} {int(back.classification[i])} "
            f"{int(back.red[i])} {int(back.green[i])} {int(back.blue[i])}\n"
        )

m = 50
h0 = laspy.LasHeader(point_format=0, version="1.4")
h0.offsets = np.array([0.0, 0.0, 0.0])
h0.scales = np.array([0.01, 0.01, 0.01])
las0 = laspy.LasData(h0)
las0.x = rng.uniform(-5, 5, m)
las0.y = rng.uniform(-5, 5, m)
las0.z = rng.uniform(-5, 5, m)
las0.intensity = rng.integers(0, 1000, m, dtype=np.uint16)
las0.classification = rng.choice(np.array([0, 1, 2], dtype=np.uint8), m)
las0.write(os.path.join(here, "small_fmt0.las"))
back0 = laspy.read(os.path.join(here, "small_fmt0.las"))
with open(os.path.join(here, "small_fmt0.ref.txt"), "w") as f:
    for i in range(m):
        f.write(
            f"{float(back0.x[i])!r} {float(back0.y[i])!r} {float(back0.z[i])!r} "
            f"{int(back0.intensity[i])} {int(back0.classification[i])}\n"
        )
