"""The results database and the coarse-grained fields, with and without pandas and xarray."""

from __future__ import annotations

import math

import numpy as np
import pytest

import rheodem
from conftest import REPO, SMALL

ARCHIVE = REPO / "validation" / "results-phase-diagram"


@pytest.fixture
def db(tmp_path):
    path = tmp_path / "results.sqlite"
    assert rheodem.import_results(ARCHIVE, path, study="phase-diagram") == 72
    return path


def test_results_as_a_dataframe_and_as_records_agree(db, without):
    import pandas

    frame = rheodem.results(db)
    assert isinstance(frame, pandas.DataFrame) and len(frame) == 72
    assert {"mu_p", "bond", "phi", "phi_err", "mu", "mu_err", "shear_dynamics"} <= set(frame)
    assert set(frame["study"]) == {"phase-diagram"}
    records = rheodem.results(db, form="records")
    assert len(records) == 72
    for row, (_, expected) in zip(records, frame.iterrows()):
        assert row["name"] == expected["name"]
        assert math.isclose(row["phi"], expected["phi"], rel_tol=1e-15)
        assert row["particles"] == expected["particles"] and isinstance(row["particles"], int)
    # The same records where pandas is not installed.
    without("pandas")
    assert rheodem.results(db) == records
    with pytest.raises(ImportError):
        rheodem.results(db, form="pandas")
    assert rheodem.results(db, study="no-such-study") == []
    assert len(rheodem.results(db, table="values")) > 72 * 10
    with pytest.raises(rheodem.ScenarioError, match="table"):
        rheodem.results(db, table="pointz")


def test_results_of_a_missing_database_raise(tmp_path):
    with pytest.raises(rheodem.RunError, match="does not exist"):
        rheodem.results(tmp_path / "none.sqlite")


FIELDS = SMALL + """
[fields]
grid = "slabs"
axis = "y"
bins = [6]
width = 2.2e-3
"""


def test_fields_as_arrays_and_as_a_dataset(tmp_path, without):
    import xarray

    out = tmp_path / "run"
    rheodem.run_scenario(rheodem.Scenario.from_toml(FIELDS), out, threads=1)
    ds = rheodem.fields(out)
    assert isinstance(ds, xarray.Dataset)
    assert ds["volume_fraction"].dims == ("y",) and ds.sizes["y"] == 6
    assert ds["stress"].dims == ("y", "row", "column")
    f = rheodem.fields(out, form="numpy")
    assert list(f.coords) == ["y"] and f.components == ("x", "y", "z")
    assert f.velocity.shape == (6, 3) and f.tensors["stress"].shape == (6, 3, 3)
    np.testing.assert_array_equal(ds["volume_fraction"].values, f.scalars["volume_fraction"])
    # The table's own numbers, on the grid.
    table = np.loadtxt(out / "fields.csv", delimiter=",", skiprows=1)
    np.testing.assert_array_equal(f.coords["y"], table[:, 0])
    header = (out / "fields.csv").read_text().splitlines()[0].split(",")
    np.testing.assert_array_equal(
        f.tensors["stress"][:, 0, 1], table[:, header.index("stress_xy")]
    )
    # Slabs through a uniform packing: about the packing's volume fraction everywhere.
    assert np.all(np.abs(f.scalars["volume_fraction"] - 0.55) < 0.1)
    # Where xarray is not installed, the arrays.
    without("xarray")
    plain = rheodem.fields(out)
    assert isinstance(plain, rheodem.Fields)
    np.testing.assert_array_equal(plain.scalars["pressure"], f.scalars["pressure"])
    with pytest.raises(ImportError):
        rheodem.fields(out, form="xarray")
