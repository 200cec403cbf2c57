"""The robust smoothing on Dask tiles (nbhd.dask, TiledCloud.smooth_robust) equals
nbhd.smooth_robust on one machine bit for bit: points, normals, outputs and every figure of the
run, for float64 and float32, with exact duplicates on the tiles' borders, NaN holes, a noise
level that widens the rows, and an outlier whose tile must widen its halo. Two negative controls
show the comparison can fail: halos too narrow whose invalid values are used anyway, and the
median of the tiles' medians in place of the exact median."""

import concurrent.futures

import numpy as np
import pytest

import nbhd

da = pytest.importorskip("dask.array")
pytest.importorskip("distributed")  # the client fixture (conftest.py) needs it
ndask = pytest.importorskip("nbhd.dask")

SCALARS = ("spacing", "epsilon", "lambda", "min_neighbors", "wide_iterations")
ARRAYS = ("points", "normals", "noise", "moved", "dimension")


def cube(n, noise, seed=39):
    """n points on the surface of the unit cube (its six faces: sharp edges and corners) with
    Gaussian noise of ``noise`` mean spacings along every axis."""
    rng = np.random.default_rng(seed)
    p = rng.random((n, 3))
    face = rng.integers(0, 6, n)
    p[np.arange(n), face % 3] = (face // 3).astype(float)
    h = 0.5 * np.sqrt(6.0 / n)  # about the mean nearest distance of a uniform sample
    return p + rng.normal(scale=noise * h, size=p.shape)


def with_duplicates(p, count=400):
    """``count`` exact copies of points next to the tiles' dividing planes x = 0.5 and
    y = 0.5 (ties at distance 0 across tiles), appended."""
    near = np.flatnonzero((abs(p[:, 0] - 0.5) < 0.02) | (abs(p[:, 1] - 0.5) < 0.02))
    return np.vstack([p, p[near[:count]]])


def same(a, b):
    a, b = np.asarray(a), np.asarray(b)
    return a.dtype == b.dtype and a.shape == b.shape and a.tobytes() == b.tobytes()


def differing(got, ref):
    """The names of the arrays and figures that differ, and how many points moved otherwise."""
    names = [k for k in ARRAYS if not same(got[k], ref[k])]
    names += [k for k in SCALARS if got[k] != ref[k]]
    if (got["outputs"] is None) != (ref["outputs"] is None):
        names.append("outputs")
    elif ref["outputs"] is not None:
        assert got["outputs"].keys() == ref["outputs"].keys()
        names += ["outputs." + k for k in ref["outputs"] if not same(got["outputs"][k], ref["outputs"][k])]
    points = int(np.sum(np.any(got["points"].view(np.int64) != ref["points"].view(np.int64), axis=1)))
    return names, points


def tiled(client, tmp_path, pts, *, non_finite="reject", **options):
    cloud = ndask.tile_array(da.from_array(pts, chunks=(5_000, 3)), str(tmp_path), grid=(2, 2, 1),
                             non_finite=non_finite)
    return cloud.smooth_robust(non_finite=non_finite, client=client, **options)


@pytest.mark.parametrize("dtype", [np.float64, np.float32])
def test_robust_equals_one_machine(client, tmp_path, dtype):
    pts = with_duplicates(cube(12_000, 1.0)).astype(dtype)
    ref = nbhd.smooth_robust(pts, outputs=True)
    r = tiled(client, tmp_path, pts, outputs=True)
    got = r.assemble()
    assert differing(got, ref) == ([], 0)
    assert r.status["invalid"] == 0
    assert len(ref["moved"]) >= 2  # iterations ran: σ̂ and the stopping rule were reduced
    assert len(r.parts) == 4


def test_robust_wide_rows_equal_one_machine(client, tmp_path):
    # noise of 5 spacings reads as a ball: the rows widen, then shrink back on the proxy
    pts = cube(8_000, 5.0, seed=5)
    ref = nbhd.smooth_robust(pts)
    assert 0 < ref["wide_iterations"] < len(ref["moved"])
    got = tiled(client, tmp_path, pts).assemble()
    assert differing(got, ref) == ([], 0)


def test_robust_with_nan_holes(client, tmp_path):
    pts = with_duplicates(cube(10_000, 1.0, seed=3)).astype(np.float32)
    holes = np.arange(17, len(pts), 53)  # about 2 %
    pts[holes, 1] = np.nan
    pts[holes[::2], 2] = np.inf
    ref = nbhd.smooth_robust(pts, non_finite="skip", outputs=True)
    got = tiled(client, tmp_path / "skip", pts, non_finite="skip", outputs=True).assemble()
    assert differing(got, ref) == ([], 0)
    assert np.isnan(got["normals"][holes]).all()
    # refused by default, naming the first hole as one machine does
    with pytest.raises(ValueError, match=f"point {holes[0]}"):
        nbhd.smooth_robust(pts)
    cloud = ndask.tile_array(da.from_array(pts, chunks=(5_000, 3)), str(tmp_path / "reject"),
                             grid=(2, 2, 1), non_finite="skip")
    with pytest.raises(ValueError, match=f"point {holes[0]} "):
        cloud.smooth_robust(client=client)
    with pytest.raises(ValueError, match="only smooth_robust"):
        cloud.normals()


def test_robust_on_tile_files(client, tmp_path):
    # LAS/PLY tiles as a survey is delivered (each file a tile; the last file's points come from
    # everywhere, overlapping the others' boxes): the rows are the files in order
    pts = cube(9_000, 1.0, seed=23)
    order = np.argsort(pts[:, 0], kind="stable")
    files = []
    for i, g in enumerate(np.array_split(order[:8_000], 3) + [order[8_000:]]):
        path = tmp_path / (f"t{i}.las" if i % 2 else f"t{i}.ply")
        nbhd.write(str(path), pts[g], precision="double")
        files.append(str(path))
    ref_pts = np.vstack([nbhd.read(f)["positions"] for f in files])
    ref = nbhd.smooth_robust(ref_pts)
    cloud = ndask.tile_files(files, str(tmp_path / "store"))
    got = cloud.smooth_robust(client=client).assemble()
    assert differing(got, ref) == ([], 0)


def test_an_outlier_grows_its_tiles_halo(client, tmp_path):
    pts = np.vstack([cube(8_000, 0.3, seed=11), [[3.0, 2.5, 0.2]]])
    ref = nbhd.smooth_robust(pts)
    r = tiled(client, tmp_path, pts)
    assert differing(r.assemble(), ref) == ([], 0)
    assert r.status["grown"] > 0


def test_a_narrow_halo_differs(client, tmp_path, monkeypatch):
    # a halo of a tenth of the first width, and every tile's part taken as valid
    first = ndask._first_robust_halo
    monkeypatch.setattr(ndask, "_first_robust_halo", lambda spec, t, k: first(spec, t, k) / 10)
    monkeypatch.setattr(ndask, "_halo_ok", lambda part: True)
    pts = cube(12_000, 1.0, seed=13)
    ref = nbhd.smooth_robust(pts)
    r = tiled(client, tmp_path, pts)
    assert r.status["invalid"] > 0 and r.status["grown"] == 0
    names, points = differing(r.assemble(), ref)
    assert "points" in names and points > 0


def test_an_approximate_median_differs(client, tmp_path, monkeypatch):
    # what a naive port would do: σ̂ and the noise scale from the median of the tiles' medians
    def median_of_medians(job, parts, rank):
        everything = nbhd.RankSearch(0).to_bytes()  # no digit fixed: every value matches
        medians = []
        for v in job._each_value(ndask._tiles.robust_matching, everything):
            v = np.sort(v)
            if len(v):
                medians.append(v[len(v) // 2])
        return float(np.sort(medians)[len(medians) // 2])

    monkeypatch.setattr(ndask, "_exact_rank", median_of_medians)
    pts = cube(12_000, 1.0, seed=17)
    ref = nbhd.smooth_robust(pts)
    got = tiled(client, tmp_path, pts).assemble()
    names, points = differing(got, ref)
    assert "noise" in names and points > len(pts) // 2


def test_robust_progress_and_cancel(client, tmp_path):
    # compute=False: the job unstarted; progress after every tile task, the same result
    pts = cube(8_000, 1.0, seed=29)
    cloud = ndask.tile_array(da.from_array(pts, chunks=(5_000, 3)), str(tmp_path / "store"),
                             grid=(2, 2, 1))
    seen = []
    job = cloud.smooth_robust(client=client, compute=False, progress=seen.append)
    assert job.status["round"] is None and not seen
    r = job.submit().result(timeout=600)
    assert differing(r.assemble(), nbhd.smooth_robust(pts)) == ([], 0)
    rounds = [s["round"] for s in seen]
    assert rounds[:4] == ["nearest"] * 4 and rounds[-4:] == ["finish"] * 4
    assert {"start", "measure", "step"} <= set(rounds)
    # every round reports each of its 4 tiles once, in order
    assert [s["tiles_done"] for s in seen] == [1, 2, 3, 4] * (len(seen) // 4)
    assert all(s["tiles"] == 4 and s["points_per_s"] > 0 for s in seen)
    assert all(s["eta_s"] > 0 for s in seen[:-1]) and seen[-1]["eta_s"] == 0
    assert seen[-1]["iteration"] == len(r.report["moved"])

    # cancelled from the progress callback at the first step round's first tile: the run
    # stops there, writes no result, and the cluster stays usable
    def stop(status):
        if status["round"] == "step":
            stopped.cancel()

    stopped = cloud.smooth_robust(client=client, compute=False, progress=stop,
                                  out=str(tmp_path / "cancelled"))
    with pytest.raises(concurrent.futures.CancelledError):
        stopped.submit().result(timeout=600)
    assert stopped.status["cancelled"]
    assert stopped.status["round"] == "step" and stopped.status["iteration"] == 0
    assert not list((tmp_path / "cancelled").glob("tile_*.npz"))
    assert client.submit(sum, [1, 2], pure=False).result(timeout=60) == 3


def test_robust_options_are_smooth_robusts_keywords_and_pickle():
    # the options a tiled run sends to its workers: smooth_robust's keywords (but non_finite
    # and threads) with its defaults, checked when made, and the same after a pickle
    import inspect
    import pickle

    ours = inspect.signature(nbhd.RobustOptions).parameters
    theirs = inspect.signature(nbhd.smooth_robust).parameters
    assert list(ours) == [p for p in theirs if p not in ("points", "non_finite", "threads")]
    assert all(ours[p].default == theirs[p].default for p in ours)
    options = nbhd.RobustOptions(k=10, epsilon=0.5, epsilon_units="absolute", noise_scale=False,
                                 orientation="toward-point", orientation_point=(1.0, 2.0, 3.0))
    back = pickle.loads(pickle.dumps(options))
    assert repr(back) == repr(options)
    assert "k=10" in repr(back) and "orientation_point=[1.0, 2.0, 3.0]" in repr(back)
    with pytest.raises(ValueError):
        nbhd.RobustOptions(epsilon_units="inches")
    with pytest.raises(TypeError):
        nbhd.RobustOptions(non_finite="skip")
