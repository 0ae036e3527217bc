"""One point of the stress-controlled shear box, against the fitted laws of Shi et al. 2020.

Runs the shear box at μ_p = 0.5, I = 0.05, p* = 0.01 without cohesion (the run directory
goes to --out; running again resumes or reads it back) and prints the steady state, each
quantity with its standard error, beside the laws' prediction at the same point.

    python examples/python/shear_box_point.py [--quick] [--out DIR]
"""

import argparse
from pathlib import Path

import rheodem

parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
parser.add_argument("--quick", action="store_true", help="a small, short box (not steady)")
parser.add_argument("--out", type=Path, default=Path("runs"), help="folder of the run")
args = parser.parse_args()

point = dict(mu_p=0.5, inertial=0.05, softness=0.01)
size = dict(particles=128, strain=1.0, transient_strain=0.5) if args.quick else {}
result = rheodem.shear_box(args.out / "shear-box-point", threads=1, snapshots=0, **point, **size)
law = rheodem.predict(**point)

estimates = result.estimates
phi = estimates["steady_state.volume_fraction"]
mu = estimates["steady_state.friction"]
print(f"shear box at {point}: steady = {result.steady}")
print(f"  φ = {phi.mean:.4f} ± {phi.error:.4f}   (laws: {law['phi_friction_law']['value']:.4f})")
print(f"  μ = {mu.mean:.4f} ± {mu.error:.4f}   (laws: {law['mu']['value']:.4f})")
for warning in result.warnings:
    print(f"  note: {warning}")
