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
  full_fmt6.las    LAS 1.4, point format 6: every standard field, a WKT CRS, three extra
                   bytes dimensions (scaled int16 with no-data, float32, uint64)
  full_fmt6.laz    the same, LAZ-compressed
  full_fmt3.las    LAS 1.2, point format 3: every legacy field, GPS time, colour, a uint8
                   extra byte
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


def random_records(las, k, extended):
    """Every standard field of the record with random values in its whole range."""
    las.intensity = rng.integers(0, 65536, k, dtype=np.uint16)
    # 4 bits in formats 6-10; 3 bits in 0-5, but a LAS 1.2 header counts returns 1-5 only
    top = 16 if extended else 6
    las.return_number = rng.integers(0, top, k, dtype=np.uint8)
    las.number_of_returns = rng.integers(0, top, k, dtype=np.uint8)
    las.scan_direction_flag = rng.integers(0, 2, k, dtype=np.uint8)
    las.edge_of_flight_line = rng.integers(0, 2, k, dtype=np.uint8)
    las.classification = rng.integers(0, 256 if extended else 32, k, dtype=np.uint8)
    las.synthetic = rng.integers(0, 2, k, dtype=np.uint8)
    las.key_point = rng.integers(0, 2, k, dtype=np.uint8)
    las.withheld = rng.integers(0, 2, k, dtype=np.uint8)
    if extended:
        las.overlap = rng.integers(0, 2, k, dtype=np.uint8)
        las.scanner_channel = rng.integers(0, 4, k, dtype=np.uint8)
        las.scan_angle = rng.integers(-30000, 30001, k, dtype=np.int16)
    else:
        las.scan_angle_rank = rng.integers(-90, 91, k, dtype=np.int8)
    las.user_data = rng.integers(0, 256, k, dtype=np.uint8)
    las.point_source_id = rng.integers(0, 65536, k, dtype=np.uint16)
    las.gps_time = 3.0e8 + rng.uniform(0, 1.0e5, k)


# LAS 1.4 point format 6 (what issue 39 names): every standard field, a WKT CRS record, and
# extra bytes: a scaled int16 with no-data, a float32 and an 8-byte unsigned.
k = 120
h6 = laspy.LasHeader(point_format=6, version="1.4")
h6.offsets = np.array([600000.0, 5200000.0, 0.0])
h6.scales = np.array([0.001, 0.001, 0.0005])
h6.add_extra_dim(
    laspy.ExtraBytesParams(
        name="Amplitude", type=np.int16, description="dB, scaled",
        scales=np.array([0.01]), offsets=np.array([-100.0]), no_data=np.array([-32768]),
    )
)
h6.add_extra_dim(laspy.ExtraBytesParams(name="Deviation", type=np.float32, description="pulse shape"))
h6.add_extra_dim(laspy.ExtraBytesParams(name="PulseId", type=np.uint64))
h6.vlrs.append(laspy.vlrs.known.WktCoordinateSystemVlr('PROJCS["ETRS89 / UTM zone 32N"]'))
h6.global_encoding.wkt = True
las6 = laspy.LasData(h6)
las6.x = 600000.0 + rng.uniform(0, 80, k)
las6.y = 5200000.0 + rng.uniform(0, 80, k)
las6.z = 300.0 + rng.uniform(0, 20, k)
random_records(las6, k, True)
amplitude = np.round(rng.uniform(-100, 200, k), 2)
amplitude[::17] = np.nan  # stored as the no-data value
las6.Amplitude = np.where(np.isnan(amplitude), -32768 * 0.01 - 100.0, amplitude)
las6.Deviation = rng.normal(0, 3, k).astype(np.float32)
las6.PulseId = rng.integers(0, 2**40, k, dtype=np.uint64)
las6.write(os.path.join(here, "full_fmt6.las"))
las6.write(os.path.join(here, "full_fmt6.laz"), laz_backend=laspy.LazBackend.Lazrs)

# LAS 1.2 point format 3: every legacy field, GPS time, 16-bit colour, one extra byte.
h3 = laspy.LasHeader(point_format=3, version="1.2")
h3.offsets = np.array([0.0, 0.0, 0.0])
h3.scales = np.array([0.01, 0.01, 0.01])
h3.add_extra_dim(laspy.ExtraBytesParams(name="label", type=np.uint8))
las3 = laspy.LasData(h3)
las3.x = rng.uniform(-50, 50, k)
las3.y = rng.uniform(-50, 50, k)
las3.z = rng.uniform(0, 10, k)
random_records(las3, k, False)
las3.red = rng.integers(0, 65536, k, dtype=np.uint16)
las3.green = rng.integers(0, 65536, k, dtype=np.uint16)
las3.blue = rng.integers(0, 65536, k, dtype=np.uint16)
las3.label = rng.integers(0, 256, k, dtype=np.uint8)
las3.write(os.path.join(here, "full_fmt3.las"))
