"""Bad input raises an exception of the nbhd.NbhdError hierarchy carrying the library's
message; nothing crashes the interpreter."""

import numpy as np
import pytest

import nbhd


def test_hierarchy():
    assert issubclass(nbhd.NbhdValueError, nbhd.NbhdError)
    assert issubclass(nbhd.NbhdValueError, ValueError)
    assert issubclass(nbhd.DegenerateError, nbhd.NbhdValueError)
    assert issubclass(nbhd.NbhdMemoryError, MemoryError)
    assert issubclass(nbhd.NbhdIOError, OSError)


def test_non_finite_points_are_named():
    pts = np.zeros((10, 3))
    pts[7, 2] = np.nan
    with pytest.raises(nbhd.NbhdValueError, match="7") as e:
        nbhd.KdTree(pts)
    assert "coordinate 2" in str(e.value) or "2" in str(e.value)
    pts[7, 2] = np.inf
    with pytest.raises(nbhd.NbhdValueError):
        nbhd.KdTree(pts)


def test_dimensionless_inputs():
    with pytest.raises(nbhd.NbhdValueError, match="dimension"):
        nbhd.KdTree(np.zeros((4, 0)))
    with pytest.raises(nbhd.NbhdValueError, match="2-D"):
        nbhd.KdTree(np.zeros(3))
    with pytest.raises(nbhd.NbhdValueError, match="2-D"):
        nbhd.KdTree(np.zeros((2, 2, 3)))


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_no_point_and_no_query_are_valid(dtype):
    # A tree over no point (none given, or every one skipped) finds nothing; a batch of no
    # query is a table of no row; scipy's cKDTree answers both the same way.
    for tree, rows in [
        (nbhd.KdTree(np.zeros((0, 3), dtype)), 0),
        (nbhd.KdTree(np.full((3, 3), np.nan, dtype), non_finite="skip"), 3),
    ]:
        assert tree.size == 0
        i, d = tree.knn(np.zeros(3, dtype), 4)
        assert i.shape == (0,) and d.shape == (0,)
        i, d = tree.knn(np.zeros((2, 3), dtype), 4)
        assert i.shape == (2, 0) and d.shape == (2, 0)
        assert len(tree.radius(np.zeros((5, 3), dtype), 1.0)) == 5
        assert len(tree.neighborhoods(k=2)) == rows
        assert len(tree.neighborhoods(radius=1.0)) == rows
        back = nbhd.KdTree.from_bytes(tree.to_bytes())
        assert back.size == 0
    tree = nbhd.KdTree(np.random.default_rng(3).random((20, 3)).astype(dtype))
    i, d = tree.knn(np.zeros((0, 3), dtype), 4)
    assert i.shape == (0, 4) and d.shape == (0, 4)
    assert len(tree.radius(np.zeros((0, 3)), 0.5)) == 0
    assert len(tree.knn_radius(np.zeros((0, 3)), 2, 0.5)) == 0
    dyn = nbhd.DynamicKdTree(3, dtype=np.dtype(dtype).name)
    assert dyn.insert(np.zeros((0, 3))) == 0
    dyn.insert(np.ones((4, 3)))
    assert dyn.insert(np.zeros((0, 3))) == 4 and dyn.size == 4
    i, d = dyn.knn(np.zeros((0, 3)), 2)
    assert i.shape == (0, 2)


@pytest.mark.parametrize(
    "bad",
    [
        np.zeros((4, 3), np.complex128),
        np.array([[1.0, 2.0, 3.0j]]),
        np.array([[1.0, 2.0, 3.0]], dtype=object),
        [[1.0, 2.0, "3"]],
    ],
)
def test_complex_and_object_arrays_are_refused(bad):
    # No silent cast (numpy only warns when it drops an imaginary part): a clear error.
    import warnings

    tree = nbhd.KdTree(np.zeros((5, 3)))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with pytest.raises(nbhd.NbhdValueError, match="real numbers"):
            nbhd.KdTree(bad)
        with pytest.raises(nbhd.NbhdValueError, match="real numbers"):
            tree.knn(bad, 2)
        with pytest.raises(nbhd.NbhdValueError, match="real numbers"):
            nbhd.DynamicKdTree(3).insert(bad)


def test_bad_queries(cloud):
    tree = nbhd.KdTree(cloud)
    with pytest.raises(nbhd.NbhdValueError, match="k must be at least 1"):
        tree.knn(cloud[0], 0)
    with pytest.raises(nbhd.NbhdValueError, match="k must be at least 1"):
        tree.neighborhoods(k=0)
    with pytest.raises(nbhd.NbhdValueError, match="radius"):
        tree.radius(cloud[0], -1.0)
    with pytest.raises(nbhd.NbhdValueError, match="radius"):
        tree.radius(cloud[:4], float("nan"))
    with pytest.raises(nbhd.NbhdValueError, match="dimension"):
        tree.knn(np.zeros(2), 3)
    with pytest.raises(nbhd.NbhdValueError, match="dimension"):
        tree.knn(np.zeros((5, 4)), 3)
    with pytest.raises(nbhd.NbhdValueError, match="query"):
        tree.knn(np.array([0.0, np.nan, 0.0]), 3)
    bad = np.zeros((6, 3))
    bad[4, 1] = np.inf
    with pytest.raises(nbhd.NbhdValueError, match="4"):
        tree.knn(bad, 3)
    with pytest.raises(nbhd.NbhdValueError, match="give k, radius"):
        tree.neighborhoods()


def test_float32_radius_beyond_its_range(rng):
    tree = nbhd.KdTree(rng.random((10, 3)).astype(np.float32))
    with pytest.raises(nbhd.NbhdValueError, match="f32"):
        tree.radius(np.zeros(3), 1e200)


def test_bad_options(cloud):
    with pytest.raises(nbhd.NbhdValueError, match="unknown pivot"):
        nbhd.KdTree(cloud, pivot="middle")
    with pytest.raises(nbhd.NbhdValueError, match="unknown median"):
        nbhd.KdTree(cloud, median="fast")
    with pytest.raises(nbhd.NbhdValueError, match="leaf_size"):
        nbhd.KdTree(cloud, leaf_size=0)
    with pytest.raises(nbhd.NbhdValueError, match="thread"):
        nbhd.KdTree(cloud, threads=nbhd.MAX_THREADS + 1)
    with pytest.raises(OverflowError):
        nbhd.KdTree(cloud).knn(cloud[0], -1)
    with pytest.raises(nbhd.NbhdValueError, match="non_finite"):
        nbhd.KdTree(cloud, non_finite="ignore")


def test_table_row_out_of_range(cloud):
    t = nbhd.KdTree(cloud).neighborhoods(k=2)
    with pytest.raises(nbhd.NbhdValueError, match="2000"):
        t.row(2000)


def test_geometry_errors():
    from conftest import sphere

    p = sphere(500)
    with pytest.raises(nbhd.DegenerateError, match="ε|epsilon|spacing"):
        nbhd.normals(p, epsilon=0.01)  # 0.01 h: no neighbour
    with pytest.raises(nbhd.NbhdValueError, match="dimension"):
        nbhd.normals(p[:, :2])
    with pytest.raises(nbhd.NbhdValueError, match="k must be at least 1"):
        nbhd.smooth(p, k=0)
    with pytest.raises(nbhd.NbhdValueError, match="tau"):
        nbhd.smooth_robust(p, tau=2.0)
    with pytest.raises(nbhd.NbhdValueError, match="k_plane"):
        nbhd.smooth_robust(p, k=30, k_plane=10)
    with pytest.raises(nbhd.NbhdValueError, match="units"):
        nbhd.normals(p, epsilon_units="metres")
    q = p.copy()
    q[3, 0] = np.nan
    with pytest.raises(nbhd.NbhdValueError, match="3"):
        nbhd.smooth(q)
    with pytest.raises(nbhd.NbhdValueError, match="empty"):
        nbhd.normals(np.zeros((0, 3)))


def test_io_errors(tmp_path):
    with pytest.raises(nbhd.NbhdIOError, match="missing.ply"):
        nbhd.read(tmp_path / "missing.ply")
    bad = tmp_path / "bad.ply"
    bad.write_bytes(b"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nend_header\n1\n")
    with pytest.raises(nbhd.NbhdIOError, match="bad.ply"):
        nbhd.read(bad)
    with pytest.raises(nbhd.NbhdValueError, match="unknown format"):
        nbhd.write(tmp_path / "x.ply", np.zeros((2, 3)), format="stl")
    with pytest.raises(nbhd.NbhdValueError):
        nbhd.write(tmp_path / "x.ply", np.zeros((2, 3)), normals=np.zeros((3, 3)))
