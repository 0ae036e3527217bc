#!/usr/bin/env python3
"""The band rheology of finished split-bottom runs side by side, as a Markdown table.

For each run directory: rheodem's own band fit from summary.json (points, mu, c* with their
standard errors, P_avg, the wall torque and T_macro / T), and two measures that do not let
the fit trade mu against c: the cohesion with mu held at MU_FIXED (the mean of
tau - MU_FIXED P over the band's points, scaled by d_p^2 / f_g) and the ratio of the
band's mean shear stress to its mean pressure. The band is rheodem's (strain rate at least
0.8 of the height's maximum, P >= 99.9 Pa, the shear stress invariant), rebuilt from
fields.csv by band_sensitivity.py. Unfinished runs are skipped.

Usage: python3 validation/tools/band_table.py RUN_DIR...   (standard library only)
"""
import csv
import json
import sys

from band_sensitivity import D_P, F_G, band

MU_FIXED = 0.15
SCALE = D_P**2 / F_G

print(f"| run | band points (fitted) | `μ` | `c*` | `c*` at `μ` = {MU_FIXED} | `⟨τ⟩/⟨P⟩` | "
      "`P_avg` (Pa) | wall torque (N m) | `T_macro / T` |")
print("|---|---|---|---|---|---|---|---|---|")
for run in sys.argv[1:]:
    with open(f"{run}/summary.json") as f:
        summary = json.load(f)
    if summary.get("stage") != "done":
        continue
    b = summary["band_rheology"]
    fit = b["fit"]
    with open(f"{run}/fields.csv") as f:
        rows = [{k: float(v) for k, v in r.items()} for r in csv.DictReader(f)]
    pts = band(rows, 0.8, 99.9, "shear_stress")
    fixed = sum(t - MU_FIXED * p for p, t in pts) / len(pts) * SCALE
    ratio = sum(t for _, t in pts) / sum(p for p, _ in pts)
    torque = b["torque_measured"]
    print(f"| {run} | {b['points']} ({fit['points']}) | {fit['slope']:.4f} ± {fit['slope_err']:.4f} | "
          f"{b['cohesion_scaled']:.3f} ± {fit['intercept_err'] * SCALE:.3f} | {fixed:.3f} | {ratio:.4f} | "
          f"{b['pressure_avg']:.1f} | {torque:.4f} | {b['torque_macro'] / torque:.2f} |")
