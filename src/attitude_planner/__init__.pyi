# Type stubs of the Python module attitude_planner (src/attitude_planner/__init__.py).
import os
from typing import Any, Dict, List, Optional, Union

import numpy as np
import numpy.typing as npt

Array = npt.NDArray[np.float64]
SceneLike = Union["Problem", Dict[str, Any], str, os.PathLike]

class InputError(ValueError):
    field: str
    detail: str

class StepTooLargeError(InputError): ...

class Problem:
    yaml: str
    source: str
    def __init__(self, scene: Union[Dict[str, Any], str, os.PathLike, None] = ...,
                 **keys: Any) -> None: ...
    @classmethod
    def from_yaml(cls, text: str, source: str = ...) -> "Problem": ...
    @property
    def scene(self) -> Dict[str, Any]: ...

class _Trajectory:
    t: Array
    quaternions: Array
    rotations: Array
    rates: Array
    torques: Array
    time_step: float
    @property
    def steps(self) -> int: ...

class Result(_Trajectory):
    @property
    def summary(self) -> Dict[str, Any]: ...
    termination: str
    message: str
    @property
    def converged(self) -> bool: ...
    @property
    def attempts(self) -> List[Dict[str, Any]]: ...
    cost: float
    duration: float
    minimum_duration: float
    solve_time_s: float

class Simulation(_Trajectory):
    max_step_residual: float
    max_step_iterations: int

def plan(problem: SceneLike, warm_start: Optional[Result] = ..., *,
         steps: int = ..., scheme: str = ..., solver: str = ..., precision: str = ...,
         tolerance: float = ..., max_iterations: int = ..., time_budget: float = ...,
         target_miss: float = ..., target_cost_error: float = ..., objective: str = ...,
         time_margin: float = ..., direction: str = ..., extra_revolutions: int = ...,
         advanced: Union[str, Dict[str, Any]] = ...) -> Result: ...

def simulate(problem: SceneLike, torques: Union[_Trajectory, npt.ArrayLike],
             time_step: Optional[float] = ..., scheme: Optional[str] = ...) -> Simulation: ...
