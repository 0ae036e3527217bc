"""Coarse-grained fields of a run (its ``fields.csv``) as NumPy arrays on their grid, or
as an ``xarray.Dataset`` when xarray is installed."""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Dict, List, Tuple, Union

import numpy as np

PathLike = Union[str, "os.PathLike[str]"]

# The first scalar column of the table; the columns before it are the grid's coordinates.
_FIRST_SCALAR = "density"
_TENSORS = ("stress", "kinetic_stress", "contact_stress")


@dataclass(frozen=True)
class Fields:
    """Fields on a grid: ``coords`` maps each axis name (``r``, ``z``; ``x``, ``y``,
    ``z``) to its sorted coordinates (m); ``scalars`` maps each scalar field (density in
    kg/m³, volume_fraction, pressure in Pa, strain_rate in 1/s, friction, inertial_number,
    …) to an array over the axes; ``velocity`` (m/s) has a last axis of ``components``;
    ``tensors`` (``stress``, ``kinetic_stress``, ``contact_stress``, Pa) have two. NaN
    where a quantity is undefined (no material)."""

    coords: Dict[str, np.ndarray]
    scalars: Dict[str, np.ndarray]
    components: Tuple[str, ...]
    velocity: np.ndarray
    tensors: Dict[str, np.ndarray]

    def to_xarray(self) -> Any:
        """The fields as an ``xarray.Dataset`` (needs xarray)."""
        import xarray

        dims = tuple(self.coords)
        data: Dict[str, Any] = {k: (dims, v) for k, v in self.scalars.items()}
        data["velocity"] = (dims + ("component",), self.velocity)
        for name, t in self.tensors.items():
            data[name] = (dims + ("row", "column"), t)
        coords: Dict[str, Any] = dict(self.coords)
        coords["component"] = list(self.components)
        coords["row"] = list(self.components)
        coords["column"] = list(self.components)
        return xarray.Dataset(data, coords=coords)


def _read_table(path: Path) -> Tuple[List[str], np.ndarray]:
    with open(path, encoding="utf-8") as f:
        header = f.readline().strip().split(",")
    table = np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)
    if table.shape[1] != len(header):
        raise ValueError(f"{path}: {table.shape[1]} columns, the header names {len(header)}")
    return header, table


def read_fields(path: PathLike) -> Fields:
    """The fields of a ``fields.csv`` table, or of the one in a run directory."""
    path = Path(path)
    if path.is_dir():
        path = path / "fields.csv"
    header, table = _read_table(path)
    if _FIRST_SCALAR not in header:
        raise ValueError(f"{path}: no column {_FIRST_SCALAR!r}; not a rheodem fields table")
    n_axes = header.index(_FIRST_SCALAR)
    axes = header[:n_axes]
    coords = {a: np.unique(table[:, k]) for k, a in enumerate(axes)}
    shape = tuple(len(c) for c in coords.values())
    index = tuple(np.searchsorted(coords[a], table[:, k]) for k, a in enumerate(axes))
    column = {name: k for k, name in enumerate(header)}

    def on_grid(name: str) -> np.ndarray:
        out = np.full(shape, np.nan)
        out[index] = table[:, column[name]]
        return out

    components = tuple(h[len("velocity_"):] for h in header if h.startswith("velocity_"))
    scalars = {
        h: on_grid(h)
        for h in header[n_axes:]
        if not h.startswith("velocity_") and not h.startswith(_TENSORS)
    }
    velocity = np.stack([on_grid(f"velocity_{c}") for c in components], axis=-1)
    tensors = {
        t: np.stack(
            [np.stack([on_grid(f"{t}_{a}{b}") for b in components], -1) for a in components],
            -2,
        )
        for t in _TENSORS
        if f"{t}_{components[0]}{components[0]}" in column
    }
    return Fields(coords, scalars, components, velocity, tensors)


def fields(path: PathLike, form: str = "auto") -> Any:
    """The coarse-grained fields of a run directory (or of a ``fields.csv``):
    ``form="numpy"`` gives a :class:`Fields` of NumPy arrays, ``"xarray"`` an
    ``xarray.Dataset``, ``"auto"`` the Dataset when xarray is installed and the
    :class:`Fields` otherwise."""
    if form not in ("auto", "numpy", "xarray"):
        raise ValueError(f"form = {form!r}: must be one of auto, numpy, xarray")
    f = read_fields(path)
    if form == "numpy":
        return f
    try:
        return f.to_xarray()
    except ImportError:
        if form == "xarray":
            raise
        return f
