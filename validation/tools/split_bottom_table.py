#!/usr/bin/env python3
"""Markdown tables of the split-bottom validation runs (validation/runs-split-bottom/*).

Reads each run's summary.json and timeseries.csv; prints, per run, the settled height,
the band fits per slab, the steady net torque (full ring, and in units of f_g d_p), the
torque balance, the torque per part, and the surface centre predicted by the law
1 - R_c/R_s = (H/R_s)^(5/2) (Fenistein & van Hecke 2003) for the settled height.
Standard-library Python only.  Usage: python3 validation/tools/split_bottom_table.py [DIR]
"""
import csv
import json
import os
import sys

root = sys.argv[1] if len(sys.argv) > 1 else os.path.join(os.path.dirname(__file__), "..", "runs-split-bottom")
runs = sorted(d for d in os.listdir(root) if os.path.isfile(os.path.join(root, d, "summary.json")))


def est(e, scale=1.0, digits=4):
    if not e:
        return "n/a"
    return f"{e['mean'] * scale:.{digits}g} ± {e['error'] * scale:.2g}"


print("| run | Ω (rad/s) | law | Φ (°) | h (mm) | window (rad) | R_c surface (mm) | law R_c (mm) | W surface (mm) | R_c middle (mm) | W middle (mm) | R_c bottom (mm) | W bottom (mm) | net torque (N m) | T* = T/(f_g d_p) | balance (N m) |")
print("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|")
for d in runs:
    s = json.load(open(os.path.join(root, d, "summary.json")))
    spec, geo, res = s["spec"], s["geometry"], s.get("results") or {}
    if s["stage"] != "done":
        print(f"| {d} | (stage {s['stage']}, t = {s['time']:.3f} s) |")
        continue
    h = s["settled"]["surface_height"]
    law = spec["cohesion"]["law"]
    if law == "willett":
        law = f"Willett γ_s={spec['cohesion']['surface_tension']} N/m, V_b={spec['cohesion']['volume'] * 1e12:.0f} nl"
    rs = geo["split_radius"]
    rc_law = rs * (1 - (h / rs) ** 2.5)
    fits = {b["slab"]: b["fit"].get("Ok") for b in res["band"]}

    def f(slab, key):
        x = fits.get(slab)
        return f"{x[key] * 1e3:.2f} ± {x[key + '_err'] * 1e3:.2f}" if x else "no fit"

    window = [spec["omega"] * t for t in res["window"]]
    print(
        f"| {d} | {spec['omega']} | {law} | {spec['wedge_deg']:g} | {h * 1e3:.1f} | {window[0]:.2f}–{window[1]:.2f} "
        f"| {f('surface', 'centre')} | {rc_law * 1e3:.1f} | {f('surface', 'width')} "
        f"| {f('middle', 'centre')} | {f('middle', 'width')} | {f('bottom', 'centre')} | {f('bottom', 'width')} "
        f"| {est(res['net_torque'])} | {res['net_torque_scaled']:.4g} | {est(res['balance'], digits=2)} |"
    )

print()
print("Torque per part (full ring, N m, on the part from the grains):")
print()
print("| run | " + " | ".join(["inner-wall", "inner-bottom", "outer-bottom", "outer-wall", "backstops"]) + " |")
print("|---|---|---|---|---|---|")
for d in runs:
    s = json.load(open(os.path.join(root, d, "summary.json")))
    res = s.get("results")
    if s["stage"] != "done" or not res:
        continue
    print(f"| {d} | " + " | ".join(est(t, digits=3) for t in res["torque"]) + " |")

print()
print("Net torque against the rotation angle (means over bins of 0.25 rad, N m):")
print()
for d in runs:
    path = os.path.join(root, d, "timeseries.csv")
    rows = [r for r in csv.DictReader(open(path)) if r["stage"] == "shear"]
    bins = {}
    for r in rows:
        b = int(float(r["angle"]) / 0.25)
        bins.setdefault(b, []).append(float(r["net_torque"]))
    cells = " ".join(f"{b * 0.25:.2f}–{(b + 1) * 0.25:.2f}: {sum(v) / len(v):.4f};" for b, v in sorted(bins.items()))
    print(f"- {d}: {cells}")
