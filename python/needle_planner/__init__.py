"""needle-planner from Python: plan and simulate bevel-tip steerable needle insertions.

The numbers are the ``needle`` command's, bit for bit: ``plan`` and ``simulate`` run the same
library code as ``needle plan --json`` and ``needle simulate --json``, and their errors carry the
command's messages. The planner and the simulator run with the GIL released.

>>> import needle_planner as npl
>>> paper = npl.Scenario.from_toml("examples/paper.toml")
>>> npl.plan(paper).best.form
'RL'
"""

from __future__ import annotations

import json as _json
import os
from typing import Any, Dict, List, Mapping, Optional, Sequence, Union

import numpy as np

from ._native import (
    DeviceError,
    NeedleError,
    PlanError,
    Scenario,
    ScenarioError,
)
from . import _native

__all__ = [
    "Scenario",
    "Device",
    "Plan",
    "FormOutcome",
    "BestPath",
    "Simulation",
    "plan",
    "simulate",
    "cover",
    "sweep",
    "NeedleError",
    "ScenarioError",
    "PlanError",
    "DeviceError",
]


class _Record:
    """A JSON object whose keys read as attributes (``form.length`` for ``form["length"]``)."""

    def __init__(self, fields: Dict[str, Any]):
        self._fields = fields

    def __getattr__(self, key: str) -> Any:
        fields = self.__dict__.get("_fields", {})
        if key in fields:
            return fields[key]
        raise AttributeError(f"{type(self).__name__} has no field {key!r}")

    def __getitem__(self, key: str) -> Any:
        return self._fields[key]

    def keys(self) -> List[str]:
        """The fields, as the command's JSON names them."""
        return list(self._fields)

    def to_dict(self) -> Dict[str, Any]:
        """The fields as the command's JSON has them."""
        return self._fields

    def __repr__(self) -> str:
        return f"{type(self).__name__}({self._fields.get('form', '')!r})"


class FormOutcome(_Record):
    """One form's outcome: the keys of a ``forms`` entry of ``needle plan --json`` (``form``,
    ``feasible``, ``status``, ``length``, ``risk``, ``objective``, ``min_clearance``,
    ``target_error``, ``kkt_residual``, ``iterations``, ``evaluations``, ``insertion``,
    ``segments``; with an ``[execution]`` table ``collision_probability`` and
    ``target_error_p95``)."""


class BestPath(FormOutcome):
    """The chosen form: a form's fields plus ``penalty``, ``control_degree``, ``schedule`` (the
    driver's motor schedule) and ``points``, an ``(n, 3)`` array of the path at most 1 mm apart."""

    def __init__(self, fields: Dict[str, Any], points: np.ndarray):
        super().__init__(fields)
        self.points = points


class Plan:
    """Every form's outcome, the best path and the planning statistics: ``needle plan --json``."""

    def __init__(self, text: str, report: Dict[str, Any], points: Optional[np.ndarray]):
        self.json: str = text
        """The report exactly as ``needle plan --json`` prints it (without its newline)."""
        self.forms: List[FormOutcome] = [FormOutcome(f) for f in report["forms"]]
        """One outcome per form tried, in the catalogue's order."""
        best = report.get("best")
        if best is not None:
            best["points"] = points if points is not None else np.empty((0, 3))
        self.best: Optional[BestPath] = None if best is None else BestPath(best, best["points"])
        """The chosen form, ``None`` when no form is feasible."""
        self.stats: Dict[str, Any] = report["stats"]
        """``time_us`` (the planning's wall-clock time), ``iterations``, ``evaluations``."""
        self.execution: Optional[Dict[str, Any]] = report.get("execution")
        """With an ``[execution]`` table or a collision bound: the world assumed and the bound."""

    def to_dict(self) -> Dict[str, Any]:
        """The report as ``json.loads(needle plan --json)`` gives it (points as lists)."""
        return _json.loads(self.json)

    def __repr__(self) -> str:
        chosen = "no feasible form" if self.best is None else f"best {self.best.form}"
        return f"<Plan of {len(self.forms)} forms, {chosen}>"


def plan(
    scenario: Scenario,
    forms: Union[None, str, Sequence[str]] = None,
    max_degree: Optional[int] = None,
) -> Plan:
    """Plans ``scenario`` as ``needle plan`` does; ``forms`` and ``max_degree`` as ``--forms``
    and ``--max-degree``. Raises ``PlanError`` where the command exits 1 after its report (no
    feasible form, no plan within the collision bound): the exception's ``plan`` holds the
    report."""
    return _made(_native.plan(scenario, forms, max_degree))


def _made(native: Any) -> Plan:
    text, report, points, verdict = native
    made = Plan(text, report, points)
    if verdict is not None:
        error = PlanError(verdict)
        error.plan = made  # type: ignore[attr-defined]
        raise error
    return made


class Device:
    """A planner device (the firmware on a board, in QEMU, or ``hil-sim``), reached as ``needle
    info`` and ``needle send`` reach it: ``Device(tcp="127.0.0.1:7878")`` or
    ``Device(port="/dev/ttyACM0")``. Link failures raise ``DeviceError``."""

    def __init__(
        self,
        tcp: Optional[str] = None,
        port: Optional[str] = None,
        baud: int = 115200,
        timeout: Optional[float] = None,
        retries: Optional[int] = None,
        deadline: float = 120.0,
    ):
        self._link = _native.Device(tcp, port, baud, timeout, retries, deadline)

    def info(self) -> Dict[str, Any]:
        """What ``needle info --json`` prints: protocol, name, firmware, capacities."""
        return self._link.info()

    def plan(
        self,
        scenario: Scenario,
        forms: Union[None, str, Sequence[str]] = None,
        max_degree: Optional[int] = None,
    ) -> Plan:
        """Plans ``scenario`` on the device as ``needle send`` does (the answer re-checked
        here); the same report as ``plan`` (``stats.time_us`` is the device's round trip)."""
        return _made(self._link.plan(scenario, forms, max_degree))


class Simulation:
    """Simulated insertions: the summary of ``needle simulate --json`` and every run's figures as
    arrays, in seed order (run ``i`` has seed ``seed + i``)."""

    def __init__(self, text: str, per_run: Dict[str, Any]):
        self.json: str = text
        """The output exactly as ``needle simulate --json`` prints it (without its newline)."""
        report = _json.loads(text)
        self.summary: Dict[str, Any] = report["summary"]
        self.perturbation: Dict[str, Any] = report["perturbation"]
        self.plan: Dict[str, Any] = report["plan"]
        """The plan executed: ``form``, ``length_mm``, ``curvature_reserve`` (the share of the
        curvature kept for steering) and ``curvature_reserve_asked`` (more where no path kept it)."""
        self.controller: Optional[Dict[str, Any]] = report.get("controller")
        self.open_loop_summary: Optional[Dict[str, Any]] = report.get("open_loop_summary")
        self.runs: int = report["runs"]
        self.closed_loop: bool = report["closed_loop"]
        self.seeds: np.ndarray = per_run["seeds"]
        self.target_errors: np.ndarray = per_run["target_errors"]
        """Distance of each run's true end to its true target (mm)."""
        self.path_deviations: np.ndarray = per_run["path_rms"]
        """Each run's RMS distance from the planned path (mm)."""
        self.path_max_deviations: np.ndarray = per_run["path_max"]
        """Each run's largest distance from the planned path (mm)."""
        self.collided: np.ndarray = per_run["collided"]
        """Whether each run's true path entered an obstacle."""
        self.min_clearances: np.ndarray = per_run["min_clearances"]
        self.paths: List[np.ndarray] = per_run["paths"]
        """Each run's true tip path, an ``(n, 3)`` array of points at most 1 mm apart."""
        self.stop_reasons: Optional[List[Optional[str]]] = per_run.get("stop_reasons")
        """Closed loop: why the controller stopped each run before the target, ``None`` where it
        did not (the controller's own verdict; ``outcomes`` says how the run truly ended)."""
        self.outcomes: Optional[List[str]] = per_run.get("outcomes")
        """Closed loop: how each run ended, judged on the true tip and path: ``"reached"``,
        ``"missed"``, ``"collided"`` (the true path entered an obstacle, whatever the controller
        concluded) or ``"stopped"``."""

    def to_dict(self) -> Dict[str, Any]:
        """The output as ``json.loads(needle simulate --json)`` gives it."""
        return _json.loads(self.json)

    def __repr__(self) -> str:
        kind = "closed-loop" if self.closed_loop else "open-loop"
        return f"<Simulation of {self.runs} {kind} runs>"


def simulate(
    scenario: Scenario,
    runs: int = 100,
    seed: int = 1,
    closed_loop: bool = False,
    perturb: Optional[Mapping[str, Any]] = None,
    faults: Optional[Mapping[str, Any]] = None,
    steer: Optional[Mapping[str, Any]] = None,
    form: Optional[str] = None,
    threads: Optional[int] = None,
    compare_open_loop: bool = False,
    world: Optional[str] = None,
) -> Simulation:
    """Plans ``scenario`` and executes the plan in ``runs`` perturbed worlds, as ``needle
    simulate`` does: ``perturb``, ``faults`` and ``steer`` are its ``--perturb``, ``--fault`` and
    ``--steer`` as a dict (``{"curvature_sd": 0.05}``), ``threads`` its ``--threads`` (default:
    every core), ``world`` its ``--world`` (``"default"`` or ``"clinical"``; ``None``: the
    scenario's ``[execution]`` world; ``perturb`` and ``faults`` change it). An unknown world
    raises ``ScenarioError`` with the command's message. The result is the same on any thread
    count."""
    text, per_run = _native.simulate(
        scenario,
        runs,
        seed,
        closed_loop,
        None if perturb is None else dict(perturb),
        None if faults is None else dict(faults),
        None if steer is None else dict(steer),
        form,
        threads,
        compare_open_loop,
        None if world is None else str(world),
    )
    return Simulation(text, per_run)


def cover(
    image: Union[str, "os.PathLike[str]"],
    labels: Optional[Sequence[int]] = None,
    segments: Optional[Sequence[str]] = None,
    margin: float = 0.0,
    max_spheres: Optional[int] = None,
    tightness: Optional[float] = None,
    voxel: Optional[float] = None,
    unit: Optional[str] = None,
) -> Dict[str, Any]:
    """Covers the segments of a label map (``.nrrd``, Slicer's ``.seg.nrrd``, ``.nii``,
    ``.nii.gz``) or a closed mesh (``.stl``) with spheres, as ``needle cover`` does, and returns its
    ``--json`` report: ``segments``, each with its ``spheres`` (``center``, ``radius``, RAS mm),
    ``outside_ratio`` and ``farthest_mm``. Bad files and selections raise ``ScenarioError`` with
    the command's message. ``max_spheres``, ``tightness``, ``voxel`` and ``unit`` default to the
    command's defaults."""
    return _native.cover(
        str(image),
        None if labels is None else [int(l) for l in labels],
        None if segments is None else [str(s) for s in segments],
        float(margin),
        None if max_spheres is None else int(max_spheres),
        None if tightness is None else float(tightness),
        None if voxel is None else float(voxel),
        None if unit is None else str(unit),
    )


def sweep(
    scenario: Scenario,
    weight: str,
    start: float,
    stop: float,
    steps: int = 10,
    log: bool = False,
    threads: Optional[int] = None,
) -> Dict[str, Any]:
    """Re-plans ``scenario`` for ``steps`` values of one weight (``length``, ``risk``,
    ``penalty``, ``control`` or ``a1``..``a4``) from ``start`` to ``stop`` (spaced evenly, or
    geometrically with ``log``), as ``needle sweep --weight W --from START --to STOP --json``
    does, and returns its report: ``weight`` and one entry per value in ``points``."""
    return _native.sweep(scenario, str(weight), float(start), float(stop), int(steps), bool(log), threads)
