"""Type stub of the native module rheodem._rheodem (crates/rheodem-py). SI units."""

from os import PathLike
from typing import Any, Callable, Dict, List, Optional, Tuple, Union

import numpy as np
import numpy.typing as npt

_Path = Union[str, PathLike[str]]

__version__: str
COMMIT: str

class ScenarioError(ValueError):
    """An invalid scenario or set-up parameter; the message names the key and the allowed
    range. For a value out of range, `key`, `value` and `allowed` hold them."""

    key: str
    value: str
    allowed: str

class RunError(RuntimeError):
    """A run that could not go on (unstable state, busy or foreign run directory, a file
    not read or written, a checkpoint of another version)."""

class Buffer:
    """The base object of a state view (`view.base`); keeps the viewed memory alive."""

class Scenario:
    """A scenario (the TOML format of the README's "Scenario files") read from a file or
    from TOML text."""

    @staticmethod
    def from_file(path: _Path) -> Scenario:
        """Reads a scenario file; relative paths in it are read from its folder."""
    @staticmethod
    def from_toml(text: str, base_dir: Optional[_Path] = None) -> Scenario:
        """Parses TOML text; relative paths are read from `base_dir` (default: '.')."""
    def to_toml(self) -> str:
        """The scenario with every default written out."""
    def with_seed(self, seed: int) -> Scenario:
        """The same scenario with another seed."""
    @property
    def seed(self) -> int:
        """Seed of the random generator."""
    @property
    def title(self) -> Optional[str]:
        """The title, if the file gives one."""
    def check(self) -> str:
        """Checks without building; the derived values as a JSON text."""

class Simulation:
    """A DEM simulation driven from Python (docs/python.md)."""

    def __init__(self, scenario: Scenario, threads: Optional[int] = None) -> None:
        """Builds the scenario (placement, preparation) for `threads` workers (default:
        all logical CPUs)."""
    @staticmethod
    def load(path: _Path, threads: Optional[int] = None) -> Simulation:
        """A checkpoint written by `checkpoint`; continues bit-identically with its own
        thread count (the default)."""
    @staticmethod
    def from_run(directory: _Path, threads: Optional[int] = None) -> Simulation:
        """The last checkpoint of a `rheodem run` directory."""
    @staticmethod
    def standard_problem(cohesion: str = "none", threads: Optional[int] = None) -> Simulation:
        """The standard throughput problem of BENCHMARKS.md (model units)."""
    def checkpoint(self, path: _Path) -> None:
        """Writes the complete state (atomically)."""
    def run(self, steps: Optional[int] = None, duration: Optional[float] = None) -> None:
        """Advances `steps` steps, `duration` seconds (whole steps, rounded up), or to the
        scenario's end. Ctrl-C raises KeyboardInterrupt between steps."""
    def step(self) -> None:
        """Advances one step."""
    def attach(
        self,
        callback: Callable[[Simulation], Any],
        every: Optional[int] = None,
        dt: Optional[float] = None,
    ) -> int:
        """Calls `callback(sim)` at steps that are multiples of `every`, or at the first
        step at or after each multiple of `dt` (s); returns a handle for `detach`."""
    def detach(self, handle: int) -> None:
        """Removes an attached measurement."""
    @property
    def time(self) -> float:
        """Simulated time (s)."""
    @property
    def step_count(self) -> int:
        """Steps taken."""
    @property
    def end_step(self) -> int:
        """The scenario's last step; 0 when unknown."""
    @property
    def dt(self) -> float:
        """Time step (s)."""
    @property
    def threads(self) -> int:
        """Worker threads."""
    @property
    def box_bounds(self) -> Tuple[Tuple[float, float, float], Tuple[float, float, float]]:
        """Lower and upper corners of the box (m)."""
    @property
    def part_names(self) -> List[str]:
        """Names of the wall parts, indexed by `parts`."""
    @property
    def resolved(self) -> Optional[Dict[str, Any]]:
        """The scenario's derived values (dt, contact time, counts, radii, seed)."""
    @property
    def positions(self) -> npt.NDArray[np.float64]:
        """Centre positions (m), (N, 3), read-only view."""
    @property
    def velocities(self) -> npt.NDArray[np.float64]:
        """Velocities (m/s), (N, 3), read-only view."""
    @property
    def angular_velocities(self) -> npt.NDArray[np.float64]:
        """Angular velocities (rad/s), (N, 3), read-only view."""
    @property
    def forces(self) -> npt.NDArray[np.float64]:
        """Total forces of the last evaluation (N), (N, 3), read-only view."""
    @property
    def torques(self) -> npt.NDArray[np.float64]:
        """Total torques of the last evaluation (N m), (N, 3), read-only view."""
    @property
    def radii(self) -> npt.NDArray[np.float64]:
        """Radii (m), (N,), read-only view."""
    @property
    def masses(self) -> npt.NDArray[np.float64]:
        """Masses (kg), (N,), read-only view."""
    @property
    def ids(self) -> npt.NDArray[np.uint32]:
        """Permanent particle ids of the rows (row order changes at rebuilds)."""
    @property
    def parts(self) -> npt.NDArray[np.uint16]:
        """Wall part of each particle (index into `part_names`; 65535 for none)."""
    @property
    def species(self) -> npt.NDArray[np.uint16]:
        """Species index of each particle."""
    def contacts(self) -> Dict[str, npt.NDArray[Any]]:
        """The contacts of the current state, a computed copy: `i`, `j` (ids; `j` a wall
        index where `wall`), `wall`, `overlap` (m), `branch`, `normal` (unit, j to i),
        `force`, `normal_force`, `tangential_force` (N, on i), `force_on_j` (N, in j's
        frame), `bridge`."""
    def observables(self) -> Dict[str, Any]:
        """Stress tensor (Pa), energies (J), coordination and the other observables of
        the current state."""
    def __len__(self) -> int: ...

def run_setup(
    name: str,
    out: _Path,
    params: Optional[Dict[str, Any]] = None,
    threads: Optional[int] = None,
    force: bool = False,
    from_run: Optional[_Path] = None,
    config: Optional[_Path] = None,
    max_memory: Optional[int] = None,
) -> Tuple[Dict[str, Any], str, List[str]]:
    """Runs a registered set-up into `out`: (summary, report, warnings)."""

def setups() -> List[Dict[str, Any]]:
    """The registered set-ups with their parameters (key, kind, unit, meaning, allowed
    range, required, default)."""

def run_scenario(
    scenario: Optional[Scenario],
    out: _Path,
    threads: Optional[int] = None,
    force: bool = False,
    resume: bool = False,
) -> Dict[str, Any]:
    """Runs a scenario into `out` (or resumes the run there); its summary."""

def predict(mu_p: float, inertial: float, softness: float, bond: float = 0.0) -> Dict[str, Any]:
    """The fitted laws of Shi et al. 2020 at (μ_p, I, p*, Bo)."""

def export_results(db: _Path, table: str = "points", study: Optional[str] = None) -> str:
    """A table of the results database as CSV text."""

def import_results(archive: _Path, db: _Path, study: Optional[str] = None) -> int:
    """Stores an archive's shear-box points in the database; how many."""
