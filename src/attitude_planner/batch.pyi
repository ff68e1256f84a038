# Type stubs of attitude_planner.batch (src/attitude_planner/batch.py).
import os
from typing import Any, Callable, Dict, List, Optional, Union

COLUMNS: List[str]

class Job:
    row_from: str
    row_to: str
    scene: Union[Dict[str, Any], str]
    options: Dict[str, Any]

def jobs_of(requests: Union[Dict[str, Any], str, os.PathLike], base_dir: str = ...) -> List[Job]: ...
def solve_row(job: Job) -> Dict[str, str]: ...
def plan_batch(requests: Union[Dict[str, Any], str, os.PathLike], out: str,
               workers: Optional[int] = ..., scheduler: Any = ..., progress: bool = ...,
               on_row: Optional[Callable[[Dict[str, str]], None]] = ...) -> int: ...
def main(argv: Optional[List[str]] = ...) -> int: ...
