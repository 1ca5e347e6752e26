"""Type stubs of the native module (Rust, PyO3); use the package ``needle_planner``."""

import os
import pathlib
from typing import Any, Dict, List, Optional, Sequence, Tuple, Union

import numpy as np

class NeedleError(Exception): ...
class ScenarioError(NeedleError): ...
class PlanError(NeedleError): ...
class DeviceError(NeedleError): ...

class Scenario:
    """A needle-planner scenario (docs/scenario.md)."""

    def __init__(self, **tables: Any) -> None: ...
    @staticmethod
    def from_toml(source: Union[str, os.PathLike[str]]) -> "Scenario": ...
    def to_toml(self) -> str: ...
    def replace(self, **tables: Any) -> "Scenario": ...
    @property
    def path(self) -> Optional[pathlib.Path]: ...
    @property
    def name(self) -> Optional[str]: ...

class Device:
    def __init__(
        self,
        tcp: Optional[str] = None,
        port: Optional[str] = None,
        baud: int = 115200,
        timeout: Optional[float] = None,
        retries: Optional[int] = None,
        deadline: float = 120.0,
    ) -> None: ...
    def info(self) -> Dict[str, Any]: ...
    def plan(
        self,
        scenario: Scenario,
        forms: Union[None, str, Sequence[str]] = None,
        max_degree: Optional[int] = None,
    ) -> Tuple[str, Dict[str, Any], Optional[np.ndarray], Optional[str]]: ...

def plan(
    scenario: Scenario,
    forms: Union[None, str, Sequence[str]] = None,
    max_degree: Optional[int] = None,
) -> Tuple[str, Dict[str, Any], Optional[np.ndarray], Optional[str]]: ...
def simulate(
    scenario: Scenario,
    runs: int = 100,
    seed: int = 1,
    closed_loop: bool = False,
    perturb: Optional[Dict[str, Any]] = None,
    faults: Optional[Dict[str, Any]] = None,
    steer: Optional[Dict[str, Any]] = None,
    form: Optional[str] = None,
    threads: Optional[int] = None,
    compare_open_loop: bool = False,
    world: Optional[str] = None,
) -> Tuple[str, Dict[str, Any]]: ...
def cover(
    image: str,
    labels: Optional[List[int]] = None,
    segments: Optional[List[str]] = None,
    margin: float = 0.0,
    max_spheres: Optional[int] = None,
    tightness: Optional[float] = None,
    voxel: Optional[float] = None,
    unit: Optional[str] = None,
) -> Dict[str, Any]: ...
def sweep(
    scenario: Scenario,
    weight: str,
    start: float,
    stop: float,
    steps: int = 10,
    log: bool = False,
    threads: Optional[int] = None,
) -> Dict[str, Any]: ...
