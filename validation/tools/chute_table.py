#!/usr/bin/env python3
"""The chute runs of validation/chute.sh as Markdown tables (VALIDATION.md, "Inclined chute
flow"): per run the steady verdict, the bulk's μ, I, φ with their block errors, the
mid-depth p* and Bo, the force balance (σ_zz over the weight above, bulk mean and worst
slab; the worst relative deviation of μ from tan θ over the bulk slabs) and Bagnold's fit; then each
shear-box point beside the chute run it was set from.

Usage: python3 validation/tools/chute_table.py [RUNS_DIR]   (default validation/runs-chute)
Standard library only.
"""

import csv
import json
import math
import sys
from pathlib import Path


def est(e, digits=4):
    if not e:
        return "n/a"
    return f"{e['mean']:.{digits}f} ± {e['error']:.{digits}f}"


def worst_friction(run: Path, bulk, tan):
    """The largest |μ/tan θ − 1| over the bulk slabs of profiles.csv."""
    worst = 0.0
    with open(run / "profiles.csv") as f:
        for row in csv.DictReader(f):
            z, mu = float(row["z"]), float(row["friction"])
            if bulk["z"][0] <= z <= bulk["z"][1] and math.isfinite(mu):
                worst = max(worst, abs(mu / tan - 1.0))
    return worst


def chute_rows(runs: Path):
    print("| run | θ (°) | steady | μ (bulk) | tan θ | I (bulk) | φ (bulk) | p* (mid) | Bo (mid) "
          "| σ_zz / weight (bulk; worst slab) | worst slab μ/tan θ − 1 | Bagnold rms / v_max |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|")
    for run in sorted(runs.glob("*-theta*")):
        if run.name.startswith("box-"):
            continue
        summary = run / "summary.json"
        if not summary.exists():
            continue
        s = json.loads(summary.read_text())
        if s.get("status") != "completed":
            print(f"| {run.name} | — | running (t = {s.get('time', 0):.2f} s) |")
            continue
        r = s["results"]
        b = r["bulk"]
        tan = r["tan_theta"]
        bag = r["bagnold"]
        bag = f"{100 * bag['Ok']['relative_residual']:.1f} %" if "Ok" in bag else "no fit"
        print(
            f"| {run.name} | {s['spec']['angle_deg']} | {'yes' if r['steady'] else 'no'} "
            f"| {est(b['friction'])} | {tan:.4f} | {est(b['inertial_number'])} "
            f"| {est(b['volume_fraction'])} | {b['softness_mid']:.2e} | {b['bond_mid']:.3f} "
            f"| {est(b['normal_stress_ratio'])}; {b['normal_stress_worst']:.3f} "
            f"| {worst_friction(run, b, tan):.3f} | {bag} |"
        )


def box_rows(runs: Path):
    boxes = sorted(runs.glob("box-*"))
    if not boxes:
        return
    print()
    print("| shear box | from | I (asked) | p* (asked) | Bo | μ box | μ chute | φ box | φ chute | steady |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for box in boxes:
        f = box / "steady_state.json"
        chute = runs / box.name[len("box-"):] / "summary.json"
        if not f.exists() or not chute.exists():
            continue
        p = json.loads(f.read_text())
        st, spec = p["steady_state"], p["spec"]
        b = json.loads(chute.read_text())["results"]["bulk"]
        print(
            f"| {box.name} | {chute.parent.name} | {spec['inertial']} | {spec['softness']} "
            f"| {spec.get('bond', 0)} | {est(st['friction'])} | {est(b['friction'])} "
            f"| {est(st['volume_fraction'])} | {est(b['volume_fraction'])} "
            f"| {'yes' if st['steady'] else 'no'} |"
        )


if __name__ == "__main__":
    runs = Path(sys.argv[1] if len(sys.argv) > 1 else "validation/runs-chute")
    chute_rows(runs)
    box_rows(runs)
