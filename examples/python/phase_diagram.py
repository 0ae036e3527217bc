"""The Δφ(μ_p, Bo) phase diagram drawn from the shipped results.

Stores the archived shear-box points of validation/results-phase-diagram in a results
database, reads them back as a table (a pandas DataFrame when pandas is installed), and
prints Δφ = φ(μ_p, Bo) − φ(μ_p, 0), the change of the steady volume fraction that
cohesion brings at I = 0.02 and p* = 0.01 (lab-frame shear), with its standard error. With
matplotlib, it also draws Δφ against Bo, one line per μ_p (phase_diagram.png in --out).

    python examples/python/phase_diagram.py [--quick] [--out DIR]
"""

import argparse
import math
from collections import defaultdict
from pathlib import Path

import rheodem

parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
parser.add_argument("--quick", action="store_true", help="(the same: reads archived results)")
parser.add_argument("--out", type=Path, default=Path("."), help="folder of the database and figure")
args = parser.parse_args()

archive = Path(__file__).parents[2] / "validation" / "results-phase-diagram"
args.out.mkdir(parents=True, exist_ok=True)
db = args.out / "phase-diagram.sqlite"
db.unlink(missing_ok=True)
rheodem.import_results(archive, db, study="phase-diagram")
rows = rheodem.results(db, form="records")

phi = {}
for r in rows:
    if r["shear_dynamics"] == "lab":
        phi[(r["mu_p"], r["bond"])] = (r["phi"], r["phi_err"])
curves = defaultdict(list)
for (mu_p, bond), (value, error) in sorted(phi.items()):
    base, base_error = phi[(mu_p, 0.0)]
    # Δφ is zero at Bo = 0 by its definition.
    spread = 0.0 if bond == 0.0 else math.hypot(error, base_error)
    curves[mu_p].append((bond, value - base, spread))

print(f"{'μ_p':>5} {'Bo':>4} {'Δφ':>9} {'±':>8}")
for mu_p, curve in curves.items():
    for bond, delta, error in curve:
        print(f"{mu_p:5.2f} {bond:4.0f} {delta:+9.4f} {error:8.4f}")

try:
    import matplotlib.pyplot as plt
except ImportError:
    print("(matplotlib is not installed: no figure)")
else:
    fig, ax = plt.subplots(figsize=(5, 3.5))
    for mu_p, curve in curves.items():
        bond, delta, error = zip(*curve)
        ax.errorbar(bond, delta, yerr=error, marker="o", ms=3, capsize=2, label=f"μ_p = {mu_p:g}")
    ax.axhline(0.0, color="grey", lw=0.5)
    ax.set_xlabel("Bond number Bo")
    ax.set_ylabel("Δφ = φ(Bo) − φ(0)")
    ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(args.out / "phase_diagram.png", dpi=120)
    print(f"figure: {args.out / 'phase_diagram.png'}")
