#!/usr/bin/env python3
"""The split-bottom cell's rate series extrapolated to the quasi-static limit, as Markdown.

For each finished run directory (dry, one rotation rate each, the same angles): the rate
Omega, the band's median inertial number I (summary.json,
band_rheology.shear_box_laws.inertial_median), the wall torque T* = T / (f_g d_p) (T the
net torque, fixed parts minus rotating parts, over the full ring), and the error-function
fit of the surface slab, its centre R_c and width W (in d_p). Each quantity y is then fitted
by least squares as y = y0 + b x with x = I and with x = sqrt(I); y0 from the fit in I is
the quasi-static estimate, the difference between the two intercepts its extrapolation
error, and the last columns say how far each run is from y0.

Scales: d_p = 2.2 mm, f_g = rho_p (pi/6) d_p^3 g = 1.0939e-4 N (the runs' defaults). The
papers' dry torque (Roy et al. 2016, Fig. 11 intercept) is T* = 4.964e5.

Usage: python3 validation/tools/rate_series.py RUN_DIR...   (standard library only)
"""
import json
import math
import os
import sys

D_P = 2.2e-3
F_G = 2000.0 * math.pi / 6.0 * D_P**3 * 9.81
PAPER_T = 4.964e5


def read(run):
    """(Omega, median I, T*, its error, R_c/d_p, W/d_p, commit) of a finished run."""
    with open(os.path.join(run, "summary.json")) as f:
        s = json.load(f)
    if s.get("stage") not in ("Done", "done"):
        return None
    res = s["results"]
    torque = res["net_torque"]
    surface = next(b for b in res["band"] if b["slab"] == "surface")["fit"]["Ok"]
    laws = (s.get("band_rheology") or {}).get("shear_box_laws") or {}
    return {
        "run": os.path.basename(run.rstrip("/")),
        "omega": s["spec"]["omega"],
        "I": laws.get("inertial_median", float("nan")),
        "T": torque["mean"] / (F_G * D_P),
        "T_err": torque["error"] / (F_G * D_P),
        "Rc": surface["centre"] / D_P,
        "W": surface["width"] / D_P,
        "commit": s.get("commit", "?"),
    }


def intercept(xs, ys):
    """Least-squares intercept and slope of y = a + b x."""
    n = len(xs)
    mx, my = sum(xs) / n, sum(ys) / n
    sxx = sum((x - mx) ** 2 for x in xs)
    b = sum((x - mx) * (y - my) for x, y in zip(xs, ys)) / sxx
    return my - b * mx, b


def main(dirs):
    dirs = [d for d in dirs if os.path.isfile(os.path.join(d, "summary.json"))]
    runs = [r for r in (read(d) for d in dirs) if r is not None]
    runs.sort(key=lambda r: -r["omega"])
    print("| run | Ω (rad/s) | median I | T* | R_c/d_p (surface) | W/d_p (surface) | commit |")
    print("|---|---|---|---|---|---|---|")
    for r in runs:
        print(
            f"| {r['run']} | {r['omega']:.4g} | {r['I']:.4f} | "
            f"{r['T']:.4e} ± {r['T_err']:.1e} | {r['Rc']:.3f} | {r['W']:.3f} | {r['commit']} |"
        )
    if len(runs) < 2:
        print("\n(at least two finished rates are needed to extrapolate)")
        return
    print()
    print("| quantity | quasi-static y0 (fit in I) | fit in √I | extrapolation error | "
          + " | ".join(f"Ω = {r['omega']:.4g}: y/y0 − 1" for r in runs) + " |")
    print("|---|---|---|---|" + "---|" * len(runs))
    xs = [r["I"] for r in runs]
    for key, name in (("T", "T*"), ("Rc", "R_c/d_p"), ("W", "W/d_p")):
        ys = [r[key] for r in runs]
        y0, _ = intercept(xs, ys)
        y0s, _ = intercept([math.sqrt(x) for x in xs], ys)
        rel = " | ".join(f"{100 * (y / y0 - 1):+.1f} %" for y in ys)
        print(f"| {name} | {y0:.4g} | {y0s:.4g} | {abs(y0 - y0s):.2g} | {rel} |")
    t0, _ = intercept(xs, [r["T"] for r in runs])
    print(f"\nPapers' T* = {PAPER_T:.4g}: quasi-static T* / paper − 1 = {100 * (t0 / PAPER_T - 1):+.1f} %")


if __name__ == "__main__":
    main(sys.argv[1:])
