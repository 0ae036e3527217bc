"""The set-ups run through the driver from Python: archived short points reproduced,
resumption, errors that name the key, Ctrl-C, and the fitted laws."""

from __future__ import annotations

import json
import math
import os
import signal
import subprocess
import threading
from pathlib import Path

import pytest

import rheodem

DATA = Path(__file__).parent / "data"

# The short points archived in data/ (their summaries), written by data/archive.py with the
# same arguments; one thread, so the bits are those of any machine with this build.
SHEAR_BOX = dict(
    mu_p=0.5, inertial=0.05, softness=0.01, particles=128, strain=1.0,
    transient_strain=0.5, snapshots=0, checkpoints=2,
)
SPLIT_BOTTOM = dict(
    wedge_deg=15.0, height=0.01, duration=0.1, average_from=0.05, settle_max_time=0.05,
    rows=5, snapshots=0, checkpoints=1,
)


def results_of(summary: dict, keys) -> dict:
    return {k: summary[k] for k in keys}


def test_the_shear_box_reproduces_its_archived_point(tmp_path):
    r = rheodem.shear_box(tmp_path / "point", threads=1, **SHEAR_BOX)
    archived = json.loads((DATA / "shear-box-point.json").read_text())
    assert r.summary["steady_state"] == archived["steady_state"]
    assert r.summary["spec"] == archived["spec"]
    assert r.directory == tmp_path / "point" and (r.directory / "checkpoint.bin").exists()
    assert r.steady is False and any("steady state" in w for w in r.warnings)
    mu = r.estimates["steady_state.friction"]
    assert mu.mean == archived["steady_state"]["friction"]["mean"] and mu.error > 0
    assert "μ =" in r.report
    # Run again with the same settings: the finished run is read back, not rerun.
    again = rheodem.shear_box(tmp_path / "point", threads=1, **SHEAR_BOX)
    assert again.summary["steady_state"] == archived["steady_state"]
    # Other settings in the same directory are refused unless forced.
    with pytest.raises(rheodem.RunError, match=r"other settings \(strain: 1.0 → 2.0\).*force=True"):
        rheodem.shear_box(tmp_path / "point", threads=1, **dict(SHEAR_BOX, strain=2.0))


def test_the_split_bottom_cell_reproduces_its_archived_run(tmp_path):
    r = rheodem.split_bottom(tmp_path / "cell", threads=1, **SPLIT_BOTTOM)
    archived = json.loads((DATA / "split-bottom-cell.json").read_text())
    assert r.summary["results"] == archived["results"]
    assert r.summary["status"] == "completed"
    assert "results.net_torque" in r.estimates
    assert any("settle_max_time" in w for w in r.warnings)


# A small layer at rest at 10°, then the same grains tilted to 30° (tests/chute.rs holds
# the same layer to its closed forms).
CHUTE = dict(
    angle_deg=10.0, height=6.0, length=6.0, width=6.0, duration=0.1, average_from=0.04,
    bulk_margin=1.5, rows=20, snapshots=0, checkpoints=2, cg_every=0.004,
)


def test_the_chute_runs_from_python_and_tilts_its_settled_layer(tmp_path):
    rest = rheodem.chute(tmp_path / "rest", threads=1, **CHUTE)
    assert rest.summary["status"] == "completed" and rest.steady
    bulk = rest.estimates["results.bulk.friction"]
    tan = math.tan(math.radians(10.0))
    assert abs(bulk.mean / tan - 1.0) < 0.02 and bulk.error > 0
    profiles = rest.summary["results"]["profiles"]
    assert {"z", "volume_fraction", "friction", "inertial_number"} <= profiles[0].keys()
    steep = rheodem.chute(
        tmp_path / "steep", threads=1, from_run=tmp_path / "rest",
        **dict(CHUTE, angle_deg=30.0, duration=0.05, average_from=0.02),
    )
    assert steep.summary["from"] == str(tmp_path / "rest")
    assert steep.summary["free_particles"] == rest.summary["free_particles"]


def test_set_up_errors_name_the_key(tmp_path):
    with pytest.raises(rheodem.ScenarioError) as e:
        rheodem.shear_box(tmp_path / "a", mu_p=0.5, inertial=3.0, softness=0.01)
    assert e.value.key == "inertial" and "(0, 2]" in e.value.allowed
    with pytest.raises(rheodem.ScenarioError, match="it takes mu_p, inertial"):
        rheodem.shear_box(tmp_path / "b", mu_p=0.5, inertial=0.1, softness=0.01, frcition=1)
    with pytest.raises(rheodem.ScenarioError, match="must be a number"):
        rheodem.shear_box(tmp_path / "c", mu_p="high", inertial=0.1, softness=0.01)
    with pytest.raises(rheodem.ScenarioError, match="not a set-up"):
        rheodem.run_setup("hopper", tmp_path / "d")
    assert not (tmp_path / "a").exists()
    names = [s["name"] for s in rheodem.setups()]
    assert names[:3] == ["shear-box", "split-bottom", "chute"]
    keys = {f["key"]: f for f in rheodem.setups()[0]["parameters"]}
    assert keys["inertial"]["required"] and keys["stiffness"]["unit"] == "N/m"


def test_ctrl_c_stops_a_set_up_which_then_resumes(tmp_path):
    params = dict(SHEAR_BOX, strain=3.0, checkpoints=30)
    timer = threading.Timer(0.5, lambda: os.kill(os.getpid(), signal.SIGINT))
    timer.start()
    with pytest.raises(KeyboardInterrupt):
        rheodem.shear_box(tmp_path / "p", threads=1, **params)
    timer.join()
    summary = json.loads((tmp_path / "p" / "summary.json").read_text())
    assert summary["status"] == "running"
    # The directory is free again, and the run resumes from its last checkpoint.
    r = rheodem.shear_box(tmp_path / "p", threads=1, **params)
    assert r.summary["steady_state"]["friction"]["samples"] > 0
    fresh = rheodem.shear_box(tmp_path / "q", threads=1, **params)
    assert r.summary["steady_state"] == fresh.summary["steady_state"]


def test_predict_gives_the_command_lines_numbers(cli):
    p = rheodem.predict(mu_p=0.3, inertial=0.01, softness=0.01, bond=2.0)
    text = subprocess.run(
        [cli, "predict", "--mu-p", "0.3", "--inertial", "0.01", "--softness", "0.01",
         "--bond", "2", "--json"],
        check=True, capture_output=True, text=True,
    ).stdout
    assert p == json.loads(text)
    assert 0.5 < p["phi_friction_law"]["value"] < 0.7
    with pytest.raises(rheodem.ScenarioError, match="inertial"):
        rheodem.predict(mu_p=0.3, inertial=-1.0, softness=0.01)
