# Type stubs of fivebar.runtime (docs/python.md, docs/runtime.md): the C++ device runtime's controller.
import os
from typing import Any, Dict, List, Union

class Status:
    ok: int
    moved_by_priority: int
    unreachable: int
    singular: int
    limit: int
    sensor_fault: int

class Controller:
    def __init__(self, config: Union[str, os.PathLike[str]]) -> None: ...
    @property
    def joints(self) -> List[str]: ...
    @property
    def mechanisms(self) -> List[str]: ...
    @property
    def loop_rate_hz(self) -> float: ...
    def step(self, readings: Any, targets_m: Any, kind: str = "counts") -> Dict[str, Any]: ...
    def reset(self) -> None: ...
