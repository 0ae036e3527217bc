#!/usr/bin/env python3
"""Velocity and volume-fraction profiles across the gradient direction y of a shear-box run.

Reads the snapshots of a run directory (snapshots/*.vtp, written by rheodem) and the box
height L_y of the same step from timeseries.csv, cuts the box into SLABS slabs along y and
prints, for every snapshot, the local shear rate of each slab (the difference of the
volume-weighted mean v_x of neighbouring slabs over their distance) divided by the mean
rate of the whole box, and the slab volume fractions. Under affine drag (as the run's
scenario.toml says) the stored velocities exclude the mean flow, which is added back, so
the profile is the lab frame's in every dynamics. Uniform simple shear gives local
rates of 1 within noise; a shear band shows as a few slabs carrying most of the rate.

Usage: python3 validation/tools/velocity_profile.py RUN_DIR [SLABS]   (standard library only)
"""

import csv
import glob
import math
import os
import re
import sys
import tomllib


def arrays(path):
    """The named arrays of one .vtp snapshot (the unnamed one is the positions)."""
    text = open(path).read()
    out = {}
    for m in re.finditer(r"<DataArray ([^>]*)>(.*?)</DataArray>", text, re.S):
        attrs, body = m.group(1), m.group(2)
        name = re.search(r'Name="([^"]+)"', attrs)
        comps = re.search(r'NumberOfComponents="(\d+)"', attrs)
        values = [float(x) for x in body.split()]
        c = int(comps.group(1)) if comps else 1
        out[name.group(1) if name else "points"] = [values[i : i + c] for i in range(0, len(values), c)]
    return out


def box_heights(run):
    """L_y (m) of every recorded step of timeseries.csv."""
    with open(os.path.join(run, "timeseries.csv")) as f:
        return {int(row["step"]): float(row["box_y"]) for row in csv.DictReader(f)}


def mean_flow(run):
    """(γ̇, lo_y) when the run's stored velocities exclude the mean flow (affine drag),
    so that γ̇ (y − lo_y) is added back to v_x; (0, 0) otherwise."""
    with open(os.path.join(run, "scenario.toml"), "rb") as f:
        domain = tomllib.load(f)["domain"]
    if domain.get("shear_dynamics") == "affine-drag":
        return domain["shear_rate"], domain.get("lo", [0.0, 0.0, 0.0])[1]
    return 0.0, 0.0


def profile(snapshot, height, slabs, flow=(0.0, 0.0)):
    """Slab volume fractions and volume-weighted mean lab-frame v_x, bottom to top."""
    rate, lo_y = flow
    a = arrays(snapshot)
    vol = [0.0] * slabs
    mom = [0.0] * slabs
    for (x, y, z), (r,), (vx, vy, vz) in zip(a["points"], a["radius"], a["velocity"]):
        s = min(slabs - 1, max(0, int(math.floor((y % height) / height * slabs))))
        v = 4.0 / 3.0 * math.pi * r**3
        vol[s] += v
        mom[s] += v * (vx + rate * (y - lo_y))
    return vol, [m / v for m, v in zip(mom, vol)]


def main():
    run = sys.argv[1]
    slabs = int(sys.argv[2]) if len(sys.argv) > 2 else 8
    heights = box_heights(run)
    steps = sorted(heights)
    flow = mean_flow(run)
    print(f"{run}: {slabs} slabs; local shear rate / mean rate, then slab volume fractions")
    deviations = []
    for snap in sorted(glob.glob(os.path.join(run, "snapshots", "*.vtp")))[1:]:
        step = int(re.search(r"(\d+)\.vtp$", snap).group(1))
        near = min(steps, key=lambda s: abs(s - step))
        height = heights[near]
        vol, vx = profile(snap, height, slabs, flow)
        dy = height / slabs
        rates = [(vx[k + 1] - vx[k]) / dy for k in range(slabs - 1)]
        mean = (vx[-1] - vx[0]) / (dy * (slabs - 1))
        # slab volume L_x L_z dy, with L_x L_z from the particle volume and the box's φ
        width = sum(vol) / (height * phi_of(run, near))
        phis = [v / (width * dy) for v in vol]
        deviations += [(r / mean - 1.0) ** 2 for r in rates]
        print(
            f"step {step:>9}: rate " + " ".join(f"{r / mean:5.2f}" for r in rates)
            + " | phi " + " ".join(f"{p:.3f}" for p in phis)
        )


    if deviations:
        rms = math.sqrt(sum(deviations) / len(deviations))
        print(f"rms deviation of the local rates from the mean rate: {rms:.2f}")


def phi_of(run, step):
    with open(os.path.join(run, "timeseries.csv")) as f:
        for row in csv.DictReader(f):
            if int(row["step"]) == step:
                return float(row["volume_fraction"])
    raise KeyError(step)


if __name__ == "__main__":
    main()
