"""Writes the short points that test_setups.py reproduces (run from the repository's
root: `python python/tests/data/archive.py`). Rerun it only when a change of the engine
changes the bits on purpose (validation/same-bits.sh tells), and say so in the commit."""

import json
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import rheodem  # noqa: E402
from test_setups import SHEAR_BOX, SPLIT_BOTTOM  # noqa: E402

here = Path(__file__).parent
with tempfile.TemporaryDirectory() as tmp:
    point = rheodem.shear_box(Path(tmp) / "point", threads=1, **SHEAR_BOX)
    cell = rheodem.split_bottom(Path(tmp) / "cell", threads=1, **SPLIT_BOTTOM)
keep = {"spec": point["spec"], "steady_state": point["steady_state"]}
(here / "shear-box-point.json").write_text(json.dumps(keep, indent=1) + "\n")
keep = {"commit": cell["commit"], "results": cell["results"]}
(here / "split-bottom-cell.json").write_text(json.dumps(keep, indent=1) + "\n")
print("archived", rheodem.COMMIT)
