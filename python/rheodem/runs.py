"""Runs into run directories: the registered set-ups and scenario files, through the same
driver as the command line (the same directory layout, resumption and outputs)."""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Dict, Iterator, List, NamedTuple, Optional, Tuple, Union

from . import _rheodem

PathLike = Union[str, "os.PathLike[str]"]


class Estimate(NamedTuple):
    """A time average with its standard error (same unit as the quantity)."""

    mean: float
    error: float
    samples: Optional[int] = None


def _estimates(value: Any, key: str) -> Iterator[Tuple[str, Estimate]]:
    if isinstance(value, dict):
        if isinstance(value.get("mean"), (int, float)) and isinstance(
            value.get("error"), (int, float)
        ):
            yield key, Estimate(value["mean"], value["error"], value.get("samples"))
        for k, v in value.items():
            if k not in ("mean", "error", "samples"):
                yield from _estimates(v, f"{key}.{k}" if key else k)
    elif isinstance(value, list):
        for k, v in enumerate(value):
            yield from _estimates(v, f"{key}[{k}]")


@dataclass(frozen=True)
class SetUpResult:
    """A finished set-up run.

    ``summary`` is the run's summary (its ``summary.json`` or point result, with the
    resolved parameters, version, commit, seed and results), ``report`` the result in
    words as the command line prints it, ``warnings`` what the run warned of (not steady,
    too few rows to average), ``directory`` the run directory. ``result["key"]`` reads the
    summary.
    """

    directory: Path
    summary: Dict[str, Any]
    report: str
    warnings: List[str] = field(default_factory=list)

    def __getitem__(self, key: str) -> Any:
        return self.summary[key]

    @property
    def estimates(self) -> Dict[str, Estimate]:
        """Every mean with its standard error in the summary, by dotted key
        (``steady_state.friction``, ``results.torque``)."""
        return dict(_estimates(self.summary, ""))

    @property
    def steady(self) -> Optional[bool]:
        """Whether the run reached a steady state, where the set-up judges it."""
        state = self.summary.get("steady_state")
        if isinstance(state, dict) and "steady" in state:
            return bool(state["steady"])
        if isinstance(self.summary.get("steady"), bool):
            return bool(self.summary["steady"])
        return None


def run_setup(
    name: str,
    out: Optional[PathLike] = None,
    *,
    threads: Optional[int] = None,
    force: bool = False,
    from_run: Optional[PathLike] = None,
    config: Optional[PathLike] = None,
    max_memory: Optional[int] = None,
    **params: Any,
) -> SetUpResult:
    """Runs the registered set-up ``name`` (``rheodem.setups()`` lists them with their
    parameters, units and ranges) into the run directory ``out`` (default
    ``runs/<name>``), as ``rheodem <name>`` does: an unfinished run of the same settings
    resumes, one of other settings is refused unless ``force``. ``params`` are the
    set-up's keys (a value of None keeps the default), ``config`` a TOML file of them that
    ``params`` override, ``from_run`` an earlier run to start from (where the set-up can),
    ``max_memory`` a limit in bytes on the estimated memory (default: the machine's).
    Raises ScenarioError naming a key out of range, RunError when the run cannot go on.
    """
    directory = Path(out) if out is not None else Path("runs") / name
    summary, report, warnings = _rheodem.run_setup(
        name,
        os.fspath(directory),
        params=params,
        threads=threads,
        force=force,
        from_run=None if from_run is None else os.fspath(from_run),
        config=None if config is None else os.fspath(config),
        max_memory=max_memory,
    )
    return SetUpResult(directory, summary, report, list(warnings))


def shear_box(out: Optional[PathLike] = None, **params: Any) -> SetUpResult:
    """One point of the stress-controlled Lees-Edwards shear box (``rheodem shear-box``):
    ``mu_p`` (interparticle friction), ``inertial`` (inertial number I), ``softness``
    (p* = p d/k_n), ``bond`` (Bond number), ``cohesion`` (adhesive law) and the other keys
    of ``rheodem.setups()``; the steady state is ``result.summary["steady_state"]``, each
    quantity a mean with its standard error (``result.estimates``). See ``run_setup`` for
    ``out``, ``threads``, ``force`` and ``config``."""
    return run_setup("shear-box", out, **params)


def split_bottom(out: Optional[PathLike] = None, **params: Any) -> SetUpResult:
    """The split-bottom ring shear cell (``rheodem split-bottom``): rotation rate
    ``omega`` (rad/s), the adhesive law and its parameters, the averaging window and the
    other keys of ``rheodem.setups()``; ``from_run`` starts from a settled run. See
    ``run_setup``."""
    return run_setup("split-bottom", out, **params)


def chute(out: Optional[PathLike] = None, **params: Any) -> SetUpResult:
    """Inclined chute flow on a rough base (``rheodem chute``): inclination
    ``angle_deg``, layer ``height`` in mean diameters, ``mu_p``, the adhesive law and its
    parameters, the averaging window and the other keys of ``rheodem.setups()``; the depth
    profiles are ``result.summary["results"]["profiles"]`` and the bulk values
    ``result.summary["results"]["bulk"]``; ``from_run`` tilts the settled layer of an
    earlier chute run. See ``run_setup``."""
    return run_setup("chute", out, **params)


def run_scenario(
    scenario: Union[_rheodem.Scenario, PathLike, None],
    out: PathLike,
    *,
    threads: Optional[int] = None,
    force: bool = False,
    resume: bool = False,
) -> Dict[str, Any]:
    """Runs a scenario (a Scenario or the path of its file) into the run directory
    ``out`` as ``rheodem run`` does, or with ``resume`` continues the run there as
    ``rheodem resume`` does; returns its summary. ``Simulation.from_run(out)`` opens the
    final state."""
    if scenario is not None and not isinstance(scenario, _rheodem.Scenario):
        scenario = _rheodem.Scenario.from_file(os.fspath(scenario))
    return _rheodem.run_scenario(
        scenario, os.fspath(out), threads=threads, force=force, resume=resume
    )
