"""nbhd.aerial_tile, the seeded synthetic aerial survey (src/shapes/aerial.rs): a tile generated
alone is, bit for bit, the same tile generated as part of a larger box, and its LAS fields come
back from a LAZ file nbhd writes."""

import numpy as np
import pytest

import nbhd

FIELDS = ("classification", "return_number", "number_of_returns", "gps_time", "intensity",
          "point_source_id", "scan_angle")


def by_pulse(tile):
    """The tile's arrays in (gps time, return number) order: a pulse's returns share a time,
    and no two pulses do."""
    order = np.lexsort((tile["return_number"], tile["gps_time"]))
    return {k: v[order] for k, v in tile.items()}


def test_a_tile_alone_equals_the_same_tile_among_its_neighbours():
    # four 100 m tiles around the origin (negative strips, scan lines and parcels) and the
    # 200 m block they make
    block = nbhd.aerial_tile(-100.0, -100.0, 100.0, 100.0, density=2.0, outliers=1e-3)
    tiles = [nbhd.aerial_tile(x, y, x + 100.0, y + 100.0, density=2.0, outliers=1e-3)
             for x in (-100.0, 0.0) for y in (-100.0, 0.0)]
    assert all(len(t["positions"]) > 20_000 for t in tiles)
    joined = {k: np.concatenate([t[k] for t in tiles]) for k in block}
    a, b = by_pulse(block), by_pulse(joined)
    for key in block:
        assert a[key].dtype == b[key].dtype and a[key].tobytes() == b[key].tobytes(), key
    assert len(np.unique(block["gps_time"])) == np.sum(block["return_number"] == 1)
    assert set(np.unique(block["classification"])) == {2, 5, 6, 7}
    # the seed fixes the scene
    other = nbhd.aerial_tile(-100.0, -100.0, 0.0, 0.0, density=2.0, seed=40)
    assert other["positions"].tobytes() != tiles[0]["positions"].tobytes()
    with pytest.raises(ValueError):
        nbhd.aerial_tile(0.0, 0.0, 10.0, 10.0, density=0.0)
    with pytest.raises(ValueError):
        nbhd.aerial_tile(0.0, 0.0, float("nan"), 10.0)
    with pytest.raises(ValueError, match="smaller tiles"):
        nbhd.aerial_tile(0.0, 0.0, 1e6, 1e6)
    assert len(nbhd.aerial_tile(5.0, 0.0, 5.0, 10.0)["positions"]) == 0


def test_a_tile_written_as_laz_keeps_its_fields(tmp_path):
    t = nbhd.aerial_tile(150.0, 0.0, 200.0, 50.0)  # two strips overlap there
    assert set(np.unique(t["point_source_id"])) == {0, 1}
    path = tmp_path / "tile.laz"
    nbhd.write(str(path), t["positions"], scalars={k: t[k] for k in FIELDS})
    back = nbhd.read(str(path))
    assert np.abs(back["positions"] - t["positions"]).max() < 1e-3
    for key in FIELDS:
        assert back["scalars"][key].tobytes() == t[key].astype(np.float64).tobytes(), key
