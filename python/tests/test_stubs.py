"""The type stubs (nbhd/_nbhd.pyi) against what the compiled module returns. mypy's stubtest
checks the names and signatures (scripts/wheel-test.sh); it cannot see return types or the keys
of the dicts the functions return. Here the dicts' keys are compared with the stubs' TypedDicts,
and this file is annotated and checked by `mypy --strict` (scripts/wheel-test.sh), so a return
type in the stubs that disagrees with the annotated use below fails there, while the asserts
check the same facts at run time."""

import ast
import pathlib
from typing import Union

import numpy as np
import numpy.typing as npt
import pytest

import nbhd
from nbhd import _nbhd

Floats = Union[npt.NDArray[np.float32], npt.NDArray[np.float64]]


def stub_typed_dicts() -> dict[str, set[str]]:
    """The keys of every TypedDict of the installed stubs, inherited keys included."""
    stub = pathlib.Path(_nbhd.__file__).with_name("_nbhd.pyi")
    fields: dict[str, set[str]] = {}
    for node in ast.parse(stub.read_text(encoding="utf-8")).body:
        call = node.value if isinstance(node, ast.Assign) else None
        if isinstance(call, ast.Call) and isinstance(call.func, ast.Name) and call.func.id == "TypedDict":
            # Name = TypedDict("Name", {"key": type, ...}): the spelling for keys like "lambda"
            assert isinstance(call.args[1], ast.Dict)
            fields[ast.literal_eval(call.args[0])] = {ast.literal_eval(k) for k in call.args[1].keys if k}
            continue
        if not isinstance(node, ast.ClassDef):
            continue
        bases = [b.id for b in node.bases if isinstance(b, ast.Name)]
        if "TypedDict" not in bases and not any(b in fields for b in bases):
            continue
        keys = {s.target.id for s in node.body if isinstance(s, ast.AnnAssign) and isinstance(s.target, ast.Name)}
        for b in bases:
            keys |= fields.get(b, set())
        fields[node.name] = keys
    return fields


def sphere(n: int) -> npt.NDArray[np.float64]:
    """n points on the unit sphere (a Fibonacci lattice) with a little deterministic noise."""
    i = np.arange(n) + 0.5
    phi = np.arccos(1 - 2 * i / n)
    theta = np.pi * (1 + 5**0.5) * i
    p = np.column_stack([np.cos(theta) * np.sin(phi), np.sin(theta) * np.sin(phi), np.cos(phi)])
    noisy: npt.NDArray[np.float64] = p + np.random.default_rng(3).normal(scale=0.002, size=p.shape)
    return noisy


def test_queries_return_what_the_stubs_say() -> None:
    pts = sphere(500)
    tree = nbhd.KdTree(pts, leaf_size=8)
    idx, sq = tree.knn(pts[:20], 5)
    assert idx.dtype == np.uint32 and sq.dtype == np.float64 and idx.shape == (20, 5)
    table = tree.radius(pts[:20], 0.2)
    assert isinstance(table, nbhd.Table)
    offsets: npt.NDArray[np.uint64] = table.offsets
    assert offsets.dtype == np.uint64 and len(table) == 20
    hood: nbhd.Table = tree.neighborhoods(k=8)
    row_idx, row_sq = hood.row(0)
    assert row_idx.dtype == np.uint32 and len(row_sq) == 8
    stats: dict[str, int] = tree.stats()
    assert all(isinstance(v, int) for v in stats.values())
    dyn = nbhd.DynamicKdTree(3, dtype="float64")
    first: int = dyn.insert(pts)
    assert first == 0 and dyn.size == len(pts)
    back = nbhd.KdTree.from_bytes(tree.to_bytes())
    assert back.size == tree.size
    kept: npt.NDArray[np.uint32] = tree.remove_statistical_outliers(k=8, std_ratio=2.0)
    near: npt.NDArray[np.uint32] = dyn.remove_radius_outliers(0.2, min_neighbors=3)
    assert kept.dtype == np.uint32 and near.dtype == np.uint32


def test_result_dicts_have_the_stubs_keys(tmp_path: pathlib.Path) -> None:
    fields = stub_typed_dicts()
    pts = sphere(800)
    curv = nbhd.curvatures(pts, k=12)
    assert set(curv) == fields["Curvatures"]
    smoothed = nbhd.smooth(pts, k=12, steps=1, outputs=True)
    assert set(smoothed) == fields["SmoothResult"]
    outputs = smoothed["outputs"]
    assert outputs is not None and set(outputs) == fields["Outputs"]
    robust = nbhd.smooth_robust(pts, max_iterations=1)
    assert set(robust) == fields["RobustResult"]
    path = tmp_path / "cloud.ply"
    nbhd.write(path, pts)
    cloud = nbhd.read(path)
    assert set(cloud) == fields["CloudFile"]
    assert set(nbhd.KdTree(pts).spacing()) == fields["Spacing"]
    grid = nbhd.voxel_grid(pts, 0.25)
    assert set(grid) == fields["VoxelGrid"]
    tree = nbhd.KdTree(pts, leaf_size=8)
    nodes = tree.nodes()
    assert set(nodes) == fields["Nodes"]
    split_dims: npt.NDArray[np.int64] = nodes["split_dim"]
    sums: npt.NDArray[np.float64] = tree.node_weights(np.ones(len(pts)).tolist())
    assert split_dims.dtype == np.int64 and sums.dtype == np.float64 and sums[0] == len(pts)
    members: npt.NDArray[np.uint32] = grid["members"]
    voxel_rows: npt.NDArray[np.uint64] = grid["offsets"]
    assert members.dtype == np.uint32 and voxel_rows[-1] == len(pts)
    positions: npt.NDArray[np.float64] = cloud["positions"]
    assert positions.shape == pts.shape
    normals, variation, flags = nbhd.normals(pts, k=12)
    assert normals.shape == pts.shape and variation.shape == (len(pts),) and flags.dtype == np.uint8


def test_robust_step_api_returns_what_the_stubs_say() -> None:
    # one tile that owns every point (an unbounded region) driven round by round: the dicts
    # have the stubs' keys, and the run is smooth_robust's, bit for bit
    fields = stub_typed_dicts()
    pts = sphere(800)
    inf = float("inf")
    options = nbhd.RobustOptions(max_iterations=2)
    tile = nbhd.RobustTile(pts, [True] * len(pts), [-inf] * 3, [inf] * 3, options)
    near, valid = tile.nearest()
    assert bool(valid.all())
    run = nbhd.RobustRun(nbhd.RobustRun.spacing_of_nearest(near), options)
    while (r := run.round())["kind"] != "finish":
        assert set(r) <= fields["RobustRound"]
        part = tile.round(r)
        assert set(part) == fields["RobustPart"]
        values: npt.NDArray[np.float64] = np.sort(part["values"])
        median = float(values[nbhd.RobustRun.median_rank(len(values))]) if len(values) else None
        run.feed(r, count=part["count"], max_len=part["max_len"], min_narrow=part["min_narrow"],
                 median=median, moved_sq=part["moved_sq"])
    done = tile.finish(r)
    assert set(done) == fields["RobustTileResult"]
    report = run.report()
    assert set(report) == fields["RobustRunReport"]
    ref = nbhd.smooth_robust(pts, max_iterations=2)
    assert done["points"].tobytes() == ref["points"].tobytes()
    assert done["normals"].tobytes() == ref["normals"].tobytes()
    assert report["noise"].tobytes() == ref["noise"].tobytes()
    assert report["spacing"] == ref["spacing"] and report["lambda"] == ref["lambda"]

@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_tree_type_follows_the_array(dtype: type[np.floating[npt.NBitBase]]) -> None:
    tree = nbhd.KdTree(sphere(100).astype(dtype))
    sq: Floats = tree.knn(np.zeros(3), 3)[1]
    assert sq.dtype == dtype and tree.dtype_name == np.dtype(dtype).name
