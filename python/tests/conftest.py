"""Shared fixtures of the nbhd Python tests. Data come from the repository's tests/data or are
generated with a fixed seed; nothing is read from outside the repository."""

import os
import pathlib
import shutil

import numpy as np
import pytest

REPO = pathlib.Path(__file__).resolve().parents[2]
DATA = REPO / "tests" / "data"


@pytest.fixture
def rng():
    return np.random.default_rng(20261124)


@pytest.fixture
def cloud(rng):
    """2,000 uniform points in the unit cube, float64."""
    return rng.random((2000, 3))


def sphere(n, radius=1.0, noise=0.0, seed=7):
    """n points uniformly on a sphere (Fibonacci lattice: even spacing), with optional
    Gaussian noise along all three axes."""
    i = np.arange(n) + 0.5
    phi = np.arccos(1 - 2 * i / n)
    theta = np.pi * (1 + 5**0.5) * i
    p = radius * np.column_stack(
        [np.cos(theta) * np.sin(phi), np.sin(theta) * np.sin(phi), np.cos(phi)]
    )
    if noise:
        p = p + np.random.default_rng(seed).normal(scale=noise, size=p.shape)
    return p


def cli_binary():
    """The nbhd command-line tool built from this repository, if any: $NBHD_CLI, else
    target/{release,debug}/nbhd under $CARGO_TARGET_DIR or the repository. With
    NBHD_REQUIRE_CLI=1 (scripts/python-test.sh builds it) a missing tool fails the tests that
    compare with it instead of skipping them."""
    candidates = []
    if os.environ.get("NBHD_CLI"):
        candidates.append(pathlib.Path(os.environ["NBHD_CLI"]))
    roots = [pathlib.Path(os.environ["CARGO_TARGET_DIR"])] if os.environ.get("CARGO_TARGET_DIR") else []
    roots.append(REPO / "target")
    for r in roots:
        candidates += [r / "debug" / "nbhd", r / "release" / "nbhd"]
    for c in candidates:
        if c.is_file() and os.access(c, os.X_OK):
            return str(c)
    found = shutil.which("nbhd")
    return found


@pytest.fixture
def cli():
    path = cli_binary()
    if path is None:
        if os.environ.get("NBHD_REQUIRE_CLI") == "1":
            pytest.fail("NBHD_REQUIRE_CLI=1 but the nbhd command-line tool was not found")
        pytest.skip("the nbhd command-line tool is not built (cargo build -p nbhd-cli)")
    return path


@pytest.fixture(scope="module")
def client():
    """A distributed.LocalCluster of three one-thread worker processes (1 GiB each) and its client,
    one per test module that asks for it."""
    distributed = pytest.importorskip("distributed")
    cluster = distributed.LocalCluster(
        n_workers=3,
        threads_per_worker=1,
        processes=True,
        memory_limit="1GiB",
        dashboard_address=":0",
    )
    c = distributed.Client(cluster)
    yield c
    c.close()
    cluster.close()


def pytest_configure(config):
    # scipy's k-d tree suite (test_scipy_suite.py runs it on nbhd.spatial) marks its slow
    # tests with scipy's own plugin marker; registered here, where scipy's conftest.py is
    # never loaded
    config.addinivalue_line(
        "markers", "fail_slow(seconds): scipy's marker of a slow test (no effect here)"
    )
