#!/usr/bin/env python3
"""How the band rheology of a split-bottom run depends on the band's definition.

Reads a run's coarse-grained fields (RUN/fields.csv, the (r, z) grid written by rheodem)
and, for each threshold X and pressure cut-off P_min, takes at every height the points
whose strain rate is at least X times that height's largest, keeps those with
P >= P_min, and fits tau = mu P + c by ordinary least squares, with tau either the shear
stress invariant or the stress resolved on the flow. Prints mu, c and c* = c d_p^2 / f_g
(d_p = 2.2 mm, f_g = 1.094e-4 N, as in the runs). rheodem's own band (X = 0.8,
P_min = 99.9 Pa, invariant) is the row marked *; its fit in summary.json is weighted by
the points' errors, so it differs from this one in the last digits.

A second table asks whether the band's inertial number makes the intercept: at rheodem's
band it fits tau = mu P + c only over the points with I <= I_max, and fits
tau = (mu + b I) P + c, a friction rising linearly with the local inertial number, over all
of them.

Usage: python3 validation/tools/band_sensitivity.py RUN_DIR...   (standard library only)
"""
import csv
import math
import sys

D_P, F_G = 2.2e-3, 1.094e-4


def fit(points):
    n = len(points)
    sx = sum(p for p, _ in points)
    sy = sum(t for _, t in points)
    sxx = sum(p * p for p, _ in points)
    sxy = sum(p * t for p, t in points)
    mu = (n * sxy - sx * sy) / (n * sxx - sx * sx)
    return mu, (sy - mu * sx) / n


def solve(a, b):
    """Solves the small linear system a x = b by Gaussian elimination with pivoting."""
    n = len(b)
    m = [row[:] + [b[k]] for k, row in enumerate(a)]
    for col in range(n):
        piv = max(range(col, n), key=lambda r: abs(m[r][col]))
        m[col], m[piv] = m[piv], m[col]
        for r in range(n):
            if r != col:
                f = m[r][col] / m[col][col]
                m[r] = [x - f * y for x, y in zip(m[r], m[col])]
    return [m[k][n] / m[k][k] for k in range(n)]


def fit_rate(points):
    """tau = mu P + b I P + c by least squares over (P, I, tau); returns mu, b, c."""
    cols = [(p, i * p, 1.0) for p, i, _ in points]
    a = [[sum(c[j] * c[k] for c in cols) for k in range(3)] for j in range(3)]
    rhs = [sum(c[j] * t for c, (_, _, t) in zip(cols, points)) for j in range(3)]
    return solve(a, rhs)


def band(rows, threshold, p_min, tau, extra=None):
    by_height = {}
    for r in rows:
        if not math.isnan(r["strain_rate"]):
            by_height.setdefault(r["z"], []).append(r)
    points = []
    for level in by_height.values():
        top = max(r["strain_rate"] for r in level)
        points += [(r["pressure"], r[tau]) if extra is None else (r["pressure"], r[extra], r[tau])
                   for r in level
                   if r["strain_rate"] >= threshold * top and r["pressure"] >= p_min]
    return points


def main(runs):
    for run in runs:
        with open(f"{run}/fields.csv") as f:
            rows = [{k: float(v) for k, v in r.items()} for r in csv.DictReader(f)]
        print(f"\n{run}\n\n| X | P_min (Pa) | tau | points | mu | c (Pa) | c* |\n|---|---|---|---|---|---|---|")
        for threshold in (0.5, 0.6, 0.7, 0.8, 0.9):
            for p_min in (50.0, 99.9, 200.0):
                for tau, name in (("shear_stress", "invariant"), ("resolved_shear_stress", "resolved")):
                    pts = band(rows, threshold, p_min, tau)
                    mu, c = fit(pts)
                    mark = " *" if (threshold, p_min, name) == (0.8, 99.9, "invariant") else ""
                    print(f"| {threshold}{mark} | {p_min} | {name} | {len(pts)} | {mu:.4f} | {c:.2f} | {c * D_P**2 / F_G:.3f} |")
        pts = band(rows, 0.8, 99.9, "shear_stress", "inertial_number")
        inertial = sorted(i for _, i, _ in pts)
        print(f"\nrate (X = 0.8, P_min = 99.9 Pa, invariant; band I from {inertial[0]:.2e}, "
              f"median {inertial[len(inertial) // 2]:.2e}, to {inertial[-1]:.2e})\n")
        print("| fit | points | mu | b | c (Pa) | c* |\n|---|---|---|---|---|---|")
        for i_max in (math.inf, 0.02, 0.01, 0.005):
            kept = [(p, t) for p, i, t in pts if i <= i_max]
            if len(kept) > 10:
                mu, c = fit(kept)
                print(f"| I <= {i_max} | {len(kept)} | {mu:.4f} | | {c:.2f} | {c * D_P**2 / F_G:.3f} |")
        mu, b, c = fit_rate(pts)
        print(f"| (mu + b I) P + c | {len(pts)} | {mu:.4f} | {b:.3f} | {c:.2f} | {c * D_P**2 / F_G:.3f} |")


if __name__ == "__main__":
    main(sys.argv[1:])
