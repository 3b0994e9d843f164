"""fivebar.runtime: the device's controller, fivebar::runtime::Controller (docs/runtime.md), the
C++ code an exported device runs, driven one control cycle at a time from Python."""

from __future__ import annotations

import os
from typing import Any, Dict, List, Union

from . import _fivebar as _native

__all__ = ["Controller", "Status"]


class Status:
    """Per mechanism and cycle (the runtime's codes, fivebar/runtime/controller.hpp)."""

    ok = 0
    moved_by_priority = 1
    unreachable = 2
    singular = 3
    limit = 4
    sensor_fault = 5


class Controller:
    """The C++ runtime's controller for an exported configuration: ``config`` is the JSON text or
    the path of the file ``fivebar export --format json`` writes (fivebar.InputError naming the key
    when it is broken). ``step(readings, targets_m, kind="counts")`` runs one control cycle
    (readings: one per joint in ``joints`` order, ADC counts, volts or radians; targets_m: x, y in
    m per mechanism in ``mechanisms`` order) and returns a dict of NumPy arrays: duties (one per
    joint, in [-1, 1]), status (per mechanism, uint8 ``Status`` codes) and status_names,
    theta_measured, theta_follow, theta_command (mechanisms x 2, rad), point_command_m (mechanisms
    x 2, m), moved_m. ``reset()`` brings integrators, derivative memories and held commands back
    to their state after construction."""

    def __init__(self, config: Union[str, "os.PathLike[str]"]) -> None:
        self._native = _native._Controller(os.fspath(config))

    @property
    def joints(self) -> List[str]:
        """Joint names in the order of readings and duties (``<station>_<mechanism>_theta<1|2>``)."""
        return list(self._native.joints)

    @property
    def mechanisms(self) -> List[str]:
        """``station/mechanism`` in the order of targets and statuses."""
        return list(self._native.mechanisms)

    @property
    def loop_rate_hz(self) -> float:
        return float(self._native.loop_rate_hz)

    def step(self, readings: Any, targets_m: Any, kind: str = "counts") -> Dict[str, Any]:
        """One control cycle (see the class); the arrays are new on every call."""
        return self._native.step(readings, targets_m, kind)

    def reset(self) -> None:
        self._native.reset()
