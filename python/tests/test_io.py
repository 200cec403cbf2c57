"""The files of nbhd::io: round trips through every writable format, and the repository's test
files read with the counts and values their READMEs and reference files give."""

import numpy as np
import pytest

import nbhd
from conftest import DATA


@pytest.mark.parametrize(
    "name,encoding",
    [("a.ply", None), ("a.ply", "ascii"), ("a.ply", "binary-big-endian"), ("a.pcd", None),
     ("a.pcd", "ascii"), ("a.pcd", "binary-compressed"), ("a.xyz", None)],
)
def test_round_trip_keeps_positions_normals_scalars(tmp_path, rng, name, encoding):
    pos = rng.random((300, 3)) * 10
    nrm = rng.normal(size=(300, 3))
    nrm /= np.linalg.norm(nrm, axis=1, keepdims=True)
    k1 = rng.random(300)
    path = tmp_path / name
    nbhd.write(path, pos, normals=nrm, scalars={"k1": k1}, encoding=encoding, precision="double")
    back = nbhd.read(path)
    tol = dict(rtol=1e-12) if encoding != "ascii" and not name.endswith(".xyz") else dict(rtol=1e-6)
    np.testing.assert_allclose(back["positions"], pos, **tol)
    np.testing.assert_allclose(back["normals"], nrm, atol=1e-6)
    np.testing.assert_allclose(back["scalars"]["k1"], k1, **tol)
    assert back["format"] == name.split(".")[1].upper()


def test_single_precision_is_float32(tmp_path, rng):
    pos = rng.random((50, 3))
    nbhd.write(tmp_path / "s.pcd", pos)
    back = nbhd.read(tmp_path / "s.pcd")
    np.testing.assert_array_equal(back["positions"], pos.astype(np.float32).astype(np.float64))
    assert back["source_precision"] == "single"


def test_pcl_files_read_with_their_header_counts():
    milk = nbhd.read(DATA / "pcl" / "milk.pcd")
    assert milk["positions"].shape == (13704, 3) and milk["format"] == "PCD"
    mug = nbhd.read(DATA / "pcl" / "table_scene_mug_stereo_textured.pcd")
    assert mug["grid"] is not None
    w, h = mug["grid"]
    assert mug["positions"].shape == (w * h, 3)
    holes = ~np.isfinite(mug["positions"]).all(axis=1)
    assert holes.any()  # an organized stereo scan with NaN holes
    tree = nbhd.KdTree(mug["positions"], non_finite="skip")
    assert tree.size == int((~holes).sum()) and tree.n == w * h


def test_las_and_laz_equal_the_reference_text():
    ref = np.loadtxt(DATA / "las" / "small.ref.txt", comments="#", ndmin=2)
    las = nbhd.read(DATA / "las" / "small.las")
    laz = nbhd.read(DATA / "las" / "small.laz")
    np.testing.assert_array_equal(las["positions"], laz["positions"])
    np.testing.assert_allclose(las["positions"], ref[:, :3], rtol=0, atol=1e-6)
    np.testing.assert_array_equal(las["scalars"]["intensity"], ref[:, 3])


def test_obj_vertices_and_xyz_columns(tmp_path):
    fan = nbhd.read(DATA / "meshes" / "fandisk.obj")
    assert fan["format"] == "OBJ" and fan["positions"].shape[1] == 3
    p = tmp_path / "cols.txt"
    p.write_text("1 2 3 7\n4 5 6 8\n")
    got = nbhd.read(p, columns="x y z intensity")
    np.testing.assert_array_equal(got["positions"], [[1, 2, 3], [4, 5, 6]])
    np.testing.assert_array_equal(got["scalars"]["intensity"], [7, 8])
    assert got["text_columns"] == ["x", "y", "z", "intensity"]


def test_las_write_keeps_positions(tmp_path, rng):
    pos = np.round(rng.random((100, 3)) * 100, 3)
    nbhd.write(tmp_path / "o.laz", pos, scalars={"intensity": np.arange(100.0)})
    back = nbhd.read(tmp_path / "o.laz")
    np.testing.assert_allclose(back["positions"], pos, atol=1e-3)
    np.testing.assert_array_equal(back["scalars"]["intensity"], np.arange(100.0))
