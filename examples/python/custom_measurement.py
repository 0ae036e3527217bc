"""A measurement of your own during a run.

The dense packing of the README's default job relaxes with friction; every 250 steps a
Python function reads the state (NumPy views of the particle arrays and the contact
table) and records the coordination number, the mean and largest overlap and the kinetic
energy. The rows go to custom_measurement.csv in --out.

    python examples/python/custom_measurement.py [--quick] [--out DIR]
"""

import argparse
import csv
from pathlib import Path

import numpy as np

import rheodem

parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
parser.add_argument("--quick", action="store_true", help="2000 steps instead of the whole run")
parser.add_argument("--out", type=Path, default=Path("."), help="folder of the CSV table")
args = parser.parse_args()

scenario = rheodem.Scenario.from_file(Path(__file__).parents[1] / "dense-packing.toml")
sim = rheodem.Simulation(scenario, threads=1)
print(f"{len(sim)} particles, dt = {sim.dt:.3e} s")

rows = []


def measure(s: rheodem.Simulation) -> None:
    """Coordination, overlaps (relative to the mean diameter) and kinetic energy (J)."""
    contacts = s.contacts()
    touching = contacts["overlap"] > 0
    diameter = 2.0 * s.radii.mean()
    kinetic = 0.5 * np.sum(s.masses * np.einsum("ij,ij->i", s.velocities, s.velocities))
    rows.append(
        {
            "time": s.time,
            "coordination": 2.0 * touching.sum() / len(s),
            "mean_overlap": contacts["overlap"][touching].mean() / diameter,
            "max_overlap": contacts["overlap"].max() / diameter,
            "kinetic_energy": kinetic,
        }
    )


sim.attach(measure, every=250)
sim.run(steps=2000 if args.quick else None)

args.out.mkdir(parents=True, exist_ok=True)
with open(args.out / "custom_measurement.csv", "w", newline="") as f:
    writer = csv.DictWriter(f, fieldnames=list(rows[0]))
    writer.writeheader()
    writer.writerows(rows)
print(f"{'t (s)':>10} {'Z':>6} {'<δ>/d':>9} {'δmax/d':>9} {'E_kin (J)':>10}")
for r in rows:
    print(
        f"{r['time']:10.4f} {r['coordination']:6.3f} {r['mean_overlap']:9.2e} "
        f"{r['max_overlap']:9.2e} {r['kinetic_energy']:10.3e}"
    )
