#!/usr/bin/env python3
"""Write the standard throughput problem's packing as a LAMMPS data file.

Usage: python3 lammps_data.py PACKING OUTPUT

PACKING is the repository's packing, crates/rheodem/data/bench-packing.txt:

    # L <edge> N <count> phi <solid fraction> ; columns: diameter x y z (density 1)
    <diameter> <x> <y> <z>        (one row per sphere, 0 <= x, y, z < edge)

OUTPUT is a LAMMPS data file for `atom_style sphere` (rows `id type diameter density x y z`,
one atom type, density 1) in a zero-tilt triclinic box [0, edge)^3, which `fix deform` can
then tilt for Lees-Edwards shear. The numbers are copied as written in the packing, so no
digits are lost. Standard library only.
"""

import sys


def fail(message):
    sys.exit(f"lammps_data.py: {message}")


def read_packing(path):
    """Return (edge, phi, rows) with edge and phi as written and rows as lists of 4 strings."""
    try:
        with open(path, encoding="utf-8") as f:
            lines = f.read().splitlines()
    except OSError as e:
        fail(f"cannot read the packing {path}: {e.strerror}")
    if not lines:
        fail(f"{path}: empty file")

    # Header: "# L <edge> N <count> phi <phi> ; ..."
    words = lines[0].split(";")[0].split()
    if len(words) != 7 or words[0] != "#" or words[1::2] != ["L", "N", "phi"]:
        fail(f"{path}:1: expected a header '# L <edge> N <count> phi <phi> ; ...', "
             f"got {lines[0]!r}")
    edge, count, phi = words[2], words[4], words[6]
    try:
        edge_value, count_value, _ = float(edge), int(count), float(phi)
    except ValueError:
        fail(f"{path}:1: L, N and phi must be numbers (N an integer), got {lines[0]!r}")
    if not edge_value > 0 or count_value <= 0:
        fail(f"{path}:1: need L > 0 and N > 0, got L = {edge}, N = {count}")

    rows = []
    for number, line in enumerate(lines[1:], start=2):
        if not line.strip() or line.lstrip().startswith("#"):
            continue
        fields = line.split()
        if len(fields) != 4:
            fail(f"{path}:{number}: expected 'diameter x y z', got {line!r}")
        try:
            diameter, *position = (float(v) for v in fields)
        except ValueError:
            fail(f"{path}:{number}: not a number in {line!r}")
        if not diameter > 0:
            fail(f"{path}:{number}: diameter must be positive, got {fields[0]}")
        if not all(0 <= c < edge_value for c in position):
            fail(f"{path}:{number}: position outside the box [0, {edge}): {line!r}")
        rows.append(fields)

    if len(rows) != count_value:
        fail(f"{path}: header says N = {count} but the file has {len(rows)} spheres")
    return edge, phi, rows


def write_data(path, edge, phi, rows):
    out = [
        f"phi={phi} sheared-box benchmark packing",
        "",
        f"{len(rows)} atoms",
        "1 atom types",
        "",
        f"0 {edge} xlo xhi",
        f"0 {edge} ylo yhi",
        f"0 {edge} zlo zhi",
        "0 0 0 xy xz yz",
        "",
        "Atoms",
        "",
    ]
    # atom_style sphere: id type diameter density x y z
    out += [f"{i} 1 {d} 1 {x} {y} {z}" for i, (d, x, y, z) in enumerate(rows, start=1)]
    try:
        with open(path, "w", encoding="utf-8") as f:
            f.write("\n".join(out) + "\n")
    except OSError as e:
        fail(f"cannot write {path}: {e.strerror}")


def main():
    if len(sys.argv) != 3:
        sys.exit(__doc__.split("\n\n")[1])
    edge, phi, rows = read_packing(sys.argv[1])
    write_data(sys.argv[2], edge, phi, rows)


if __name__ == "__main__":
    main()
