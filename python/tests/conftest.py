"""Shared fixtures of the Python package's tests: the repository, a small scenario, the
command-line program and helpers to hide optional packages."""

from __future__ import annotations

import os
import sys
from pathlib import Path

import pytest

import rheodem

REPO = Path(__file__).resolve().parents[2]

# 200 spheres compressed to φ = 0.55 in a periodic box, then 400 steps with friction and
# rolling resistance: a few seconds on one core.
SMALL = """
title = "small packing for the Python tests"
seed = 7

[domain]
size = [0.02, 0.02, 0.02]
periodic = [true, true, true]

[[species]]
name = "glass"
density = 2000.0

[[contact]]
normal = { stiffness = 100.0, restitution = 0.8 }
friction = { stiffness_ratio = 0.2857142857, damping_ratio = 0.2857142857, mu = 0.5 }
rolling = { stiffness_ratio = 0.2857142857, damping_ratio = 0.2857142857, mu = 0.1 }

[[particles]]
kind = "random"
species = "glass"
count = 200
mean_diameter = 2.2e-3
polydispersity = 2.0
velocity_spread = 0.01

[preparation]
volume_fraction = 0.55

[run]
steps = 400

[output]
timeseries_rows = 10
snapshots = 0
checkpoints = 2
"""


@pytest.fixture
def small_scenario() -> rheodem.Scenario:
    return rheodem.Scenario.from_toml(SMALL)


@pytest.fixture
def cli() -> Path:
    """The command-line program, built by the README's test command (`cargo test
    --release`) or named by RHEODEM_BIN."""
    path = Path(os.environ.get("RHEODEM_BIN", REPO / "target" / "release" / "rheodem"))
    if not path.exists():
        pytest.fail(
            f"{path} does not exist: build it with `cargo build --release -p rheodem-cli` "
            "or name it with RHEODEM_BIN"
        )
    return path


@pytest.fixture
def without(monkeypatch):
    """`without("pandas")` makes `import pandas` fail for the rest of the test."""

    def hide(*names: str) -> None:
        for name in names:
            for key in [k for k in sys.modules if k == name or k.startswith(name + ".")]:
                monkeypatch.delitem(sys.modules, key)
            monkeypatch.setitem(sys.modules, name, None)

    return hide
