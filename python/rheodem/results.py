"""The results database (``rheodem db``) as a pandas DataFrame, or as a list of dicts
where pandas is not installed."""

from __future__ import annotations

import csv
import io
import os
from typing import Any, Dict, List, Optional, Union

from . import _rheodem

PathLike = Union[str, "os.PathLike[str]"]


def _number(text: str) -> Any:
    if text == "":
        return None
    for kind in (int, float):
        try:
            return kind(text)
        except ValueError:
            pass
    return text


def results(
    db: PathLike,
    table: str = "points",
    study: Optional[str] = None,
    form: str = "auto",
) -> Any:
    """A table of the results database ``db``: ``"points"`` (shear-box points, one row
    each, means with their ``*_error`` columns), ``"cells"`` (split-bottom cells) or
    ``"values"`` (every stored number in long form), of one ``study`` or of all.

    ``form``: ``"pandas"`` (a DataFrame), ``"records"`` (a list of dicts, numbers as int or
    float, missing values None), or ``"auto"``: a DataFrame when pandas is installed,
    records otherwise.
    """
    text = _rheodem.export_results(os.fspath(db), table, study)
    if form not in ("auto", "pandas", "records"):
        raise ValueError(f"form = {form!r}: must be one of auto, pandas, records")
    if form != "records":
        try:
            import pandas
        except ImportError:
            if form == "pandas":
                raise
        else:
            return pandas.read_csv(io.StringIO(text))
    rows: List[Dict[str, Any]] = []
    for row in csv.DictReader(io.StringIO(text)):
        rows.append({k: _number(v) for k, v in row.items()})
    return rows


def import_results(archive: PathLike, db: PathLike, study: Optional[str] = None) -> int:
    """Stores the shear-box points of a result archive (a folder of point results, as a
    study writes) in the database ``db`` under ``study`` (default: the folder's name), as
    ``rheodem db import`` does; returns how many were stored."""
    return _rheodem.import_results(os.fspath(archive), os.fspath(db), study)
