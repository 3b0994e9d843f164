"""fivebar from Python: NumPy-native bindings of the fivebar library (docs/python.md).

Units follow the library: lengths in mm, angles in radians; ``fk`` and ``jacobian`` take
``unit="deg"`` for degrees and refuse, without it, an angle beyond one turn (``fk(m, 100, 80)``
raises instead of meaning 100 rad). Every result's ``to_dict()`` gives the document the CLI prints
with ``--json`` (mm and degrees). ``fivebar.__version__`` is the library's version.

    import fivebar, numpy as np
    design = fivebar.load("designs/iros2022.yaml")
    lower = design.station("index").lower
    pose = fivebar.fk(lower, 100, 80, unit="deg")                      # one Pose
    x, y, status = fivebar.fk(lower, theta1_array, theta2_array)       # arrays, GIL released

Batch kernels read C-contiguous float64 arrays in place and write into ``out=`` arrays when given;
every element has a status (``fivebar.Status`` values, uint8), never NaN. Bad input raises
``fivebar.InputError`` (a ``ValueError``) naming the file, line and key, or ``TypeError`` /
``ValueError`` naming the argument. Long calls take ``progress=`` callbacks and stop on Ctrl-C
(``KeyboardInterrupt``).
"""

from __future__ import annotations

import os
import re
import tempfile
from typing import Any, Callable, Dict, Iterable, List, Optional, Sequence, Union

import numpy as np


class InputError(ValueError):
    """Bad input (design file, key path, argument): the library's message, which names the file,
    line and key path ("designs/x.yaml:12: stations.index.mechanisms.lower.links[2] = -3 mm: must
    be > 0"). ``file``, ``line`` and ``key`` are parsed from it (None when the message has none)."""

    _located = re.compile(r"^(?P<file>[^\n]+?):(?P<line>\d+): (?P<rest>.*)$", re.S)
    _keyed = re.compile(r"^(?P<key>[A-Za-z_][\w.\[\]-]*)(?: = |: )")
    _whole_file = re.compile(r"^(?P<file>[^\s:]+\.(?:yaml|yml)|<[^>\n]+>): ")

    def __init__(self, message: str = "") -> None:
        super().__init__(message)
        self.file: Optional[str] = None
        self.line: Optional[int] = None
        self.key: Optional[str] = None
        m = self._located.match(message)
        if m:
            self.file, self.line = m.group("file"), int(m.group("line"))
            k = self._keyed.match(m.group("rest"))
            if k:
                self.key = k.group("key")
        else:
            # Problems of a whole file: "x.yaml: no such design file".
            f = self._whole_file.match(message)
            if f:
                self.file = f.group("file")

    def __setattr__(self, name: str, value: Any) -> None:
        # The library's ValidationError sets rule_key (the key relative to what it validated):
        # the key of the message, when it has one, is the fuller path.
        if name == "rule_key" and getattr(self, "key", None) is None:
            object.__setattr__(self, "key", value)
        object.__setattr__(self, name, value)


class IoError(OSError):
    """A file could not be read or written (the library's IoError)."""


from ._fivebar import (  # noqa: E402  (the exception types above are handed to the module)
    CoverageResult,
    Design,
    Ellipse,
    Mechanism,
    Pose,
    Problem,
    Station,
    Status,
    Studio,
    _set_exception_types,
    load,
    version,
)
from . import _fivebar as _native  # noqa: E402

_set_exception_types(InputError, IoError)

#: The package's version: the library's, set once by CMakeLists.txt's project(VERSION).
__version__: str = version()

__all__ = [
    "InputError", "IoError", "Design", "Station", "Mechanism", "Ellipse", "Pose", "Status", "CoverageResult",
    "Problem", "load", "version", "fk", "ik", "jacobian", "lci", "workspace", "coverage", "sweep", "optimize",
    "simulate", "tolerance", "control", "export_gate", "Record", "Studio", "__version__",
    "collision", "collision_map", "CollisionMap", "pattern", "replay", "replay_sil", "SilReplay", "runtime",
    "Collision", "PatternResult", "Replay",
    "calibrate", "Calibration", "calibrate_hard_stops", "calibration_plan", "CalibrationPlan", "identify", "Identification", "parts", "Part",
]

ProgressLine = Optional[Callable[[str], Any]]


# --- Results -------------------------------------------------------------------------------------


class Record:
    """A result of a study: its fields as attributes (NumPy arrays for fields and polylines),
    ``field_names()`` their names, ``to_dict()`` the document the CLI prints with --json."""

    __slots__ = ("_fields",)

    def __init__(self, fields: Dict[str, Any]) -> None:
        object.__setattr__(self, "_fields", dict(fields))

    def __getattr__(self, name: str) -> Any:
        try:
            return self._fields[name]
        except KeyError:
            raise AttributeError(
                f"{type(self).__name__} has no field {name!r} (fields: {', '.join(self.field_names())})") from None

    def __setattr__(self, name: str, value: Any) -> None:
        raise AttributeError(f"{type(self).__name__} is read-only")

    def __dir__(self) -> List[str]:
        return sorted(set(super().__dir__()) | set(self.field_names()))

    def field_names(self) -> List[str]:
        return [k for k in self._fields if k != "summary"]

    def to_dict(self) -> Any:
        """The document the CLI prints for this result (mm, deg), as dicts and lists."""
        return self._fields.get("summary")

    def __repr__(self) -> str:
        shown = []
        for k, v in self._fields.items():
            if k == "summary":
                continue
            if isinstance(v, (bool, int, float, str)) or v is None:
                shown.append(f"{k}={v!r}")
            elif isinstance(v, np.ndarray):
                shown.append(f"{k}=<{v.dtype} array {v.shape}>")
        return f"{type(self).__name__}({', '.join(shown[:8])}{', ...' if len(shown) > 8 else ''})"


class Region(Record):
    """An exact region: area_mm2, perimeter_mm, components, holes, bounds (xmin, ymin, xmax, ymax),
    boundary (closed polylines, n x 2 mm arrays) and boundary_is_hole."""

    __slots__ = ()


class MechanismWorkspace(Region):
    """One mechanism's workspace: its Region fields, mechanism, fields (2-D arrays over the
    station's grid, row j = y: reach, status, assembly_ok, lci, type1_distance_mm, type1_sin,
    type2_sin, transmission_deg, force_capability; read-only views, no copy), assembly_area_mm2 /
    lci_area_mm2 with their error estimates and contours, centre (Pose at the target centre)."""

    __slots__ = ()


class Workspace(Record):
    """A station's workspace (fivebar workspace): station, target, grid (x0, y0, spacing_mm, nx, ny
    and the x, y coordinate arrays), mechanisms {name: MechanismWorkspace}, shared (Region or None)."""

    __slots__ = ()


class StationCoverage(Record):
    """Coverage of a station's target: covered, lower / upper / shared (CoverageResult or None)."""

    __slots__ = ()


class Candidate(Record):
    """One evaluated design of an optimisation: x {variable: value}, figures {figure: value},
    verdict, status, violation, feasible."""

    __slots__ = ()


class OptimizeResult(Record):
    """An optimisation run: front (columns: variables, figures, verdict, ...; pandas.DataFrame(front)),
    chosen / polished / reference (Candidate), chosen_design (Design), hypervolume [(evaluations,
    value)], files, algorithm, evaluations, rounds, seconds."""

    __slots__ = ()


class MechanismSeries(Record):
    """One mechanism's time series (n samples at the loop rate): theta_ref, theta (rad), w (rad/s),
    current_A, duty, voltage_V (n x 2, joints 1 and 2), P_ref_mm, P_mm, force_N (n x 2, x and y),
    slipping, energy_J (n)."""

    __slots__ = ()


class Simulation(Record):
    """One simulated reference (fivebar simulate): station, reference, status, reason, t (s),
    mechanisms {name: MechanismSeries}."""

    __slots__ = ()


class ToleranceMap(Record):
    """One mechanism's tolerance study (fivebar tolerance): grid, fields (status, three_sigma_mm and
    worst_case_first_order_mm, first order; resolution_um, play_mm: 2-D views), robust_covered,
    robust_margin_mm (first order), worst_3sigma_mm (first order), worst_case_mm (the +-3 sigma
    corner on the real kinematics) beside worst_case_first_order_mm."""

    __slots__ = ()


class ControlStudy(Record):
    """A station's loop study (fivebar control): station, stable, mechanisms {name: {grid, rho,
    status, max_rho, stable, kp_margin, kd_margin}} (rho NaN outside the reachable region, status
    says why)."""

    __slots__ = ()


class GateCheck(Record):
    """One check of the export gate: kind, subject, passed, detail."""

    __slots__ = ()


class ExportGate(Record):
    """The export gate's verdict (fivebar export): passed, stations, checks [GateCheck], reasons,
    joints [(name, lo, hi) rad], validation (the loop checks' figures)."""

    __slots__ = ()

    def __bool__(self) -> bool:
        return bool(self._fields["passed"])


class Collision(Record):
    """Two tactor targets of a station under the priority rule (fivebar collision --upper --lower):
    station, collides (at the requested targets), clearance_mm (exact, negative = overlap; None when
    a target has no pose), closest_pair, required_clearance_mm, status (clear, moved,
    upper_unusable, lower_unusable, no_free_point), reason, upper_target / lower_target /
    lower_point (mm, the commanded lower point), moved_mm, clearance_after_mm, upper_pose /
    lower_pose (Pose at the commanded points)."""

    __slots__ = ()

    def __bool__(self) -> bool:
        return not self._fields["collides"]


class CollisionMap(Record):
    """Every pair of tactor positions on a grid in the target ellipse (fivebar collision without
    points; no picture): station, spacing_mm, points (n x 2 mm), upper_ok / lower_ok (usable by
    each mechanism), upper_fraction / lower_fraction (per point: the share of usable positions of
    the other tactor that collide with it), centre_collides (per point: 1 when the lower tactor
    there collides with the upper at the centre, 0 when not, 2 when unusable), pairs, colliding,
    colliding_fraction, any_free; to_dict() adds the separation bins and the priority rule at the
    centre."""

    __slots__ = ()

    def __bool__(self) -> bool:
        return bool(self._fields["any_free"])


class PatternResult(Record):
    """A skin-deformation pattern checked sample by sample (fivebar pattern): station, pattern,
    passed, centre (mm), max_joint_speed (rad/s), t (s, n), clearance_mm and
    commanded_clearance_mm (n, NaN where a pose is missing), moved_mm (n), mechanisms {"lower",
    "upper": {target_mm, point_mm (n x 2), theta (n x 2, rad, continuous), joint_speed (n x 2,
    rad/s), lci (n), status (n, uint8: index into status_names)}}, status_names, first_failure."""

    __slots__ = ()

    def __bool__(self) -> bool:
        return bool(self._fields["passed"])


class Replay(Record):
    """A device log through the runtime (fivebar replay LOG --config EXPORTED.json): passed, rows,
    max_duty_difference, mismatches, joints, mechanisms, t (rows), logged_duty and runtime_duty
    (rows x joints), status (rows x mechanisms, fivebar.runtime.Status values)."""

    __slots__ = ()

    def __bool__(self) -> bool:
        return bool(self._fields["passed"])


class SilReplay(Record):
    """Software in the loop (fivebar replay DESIGN --sil): ok, runs [one dict per pattern: station,
    reference, simulated, ok, log (the path of its log, the device's format; None when not
    simulated), figures (simulate's figures and the run's status, as the CLI's --json)]."""

    __slots__ = ()

    def __bool__(self) -> bool:
        return bool(self._fields["ok"])


class Calibration(Record):
    """A kinematic calibration (fivebar calibrate DESIGN MEAS.csv): station, mechanisms, poses;
    per parameter (arrays in the order of ``keys``, the design key paths; ``names`` such as
    "lower.L3", ``units``): value, sigma (posterior, 0 when held), design_value, identified;
    covariance over the identified parameters (``covariance_names``, file units) and
    key_covariance (``key_covariance_keys``); unidentifiable [(parameter, combination)],
    requested_unidentifiable, condition_number, observability_index, sigma_mm; the quality gate's
    gate_passed and gate_reasons (one line per refused value); design: the patched Design the CLI
    would write with --out (provenance entries included), or None when the gate refused."""

    __slots__ = ()

    def __bool__(self) -> bool:
        return bool(self._fields["gate_passed"]) and not self._fields["requested_unidentifiable"]


class CalibrationPlan(Record):
    """The poses to measure (fivebar calibrate --plan N): plans [one dict per mechanism: station,
    mechanism, theta (N x 2 rad), volts (N x 2, the readings at the design's calibration),
    point_mm (N x 2, the tactor by FK), candidates, observability_index and the random sets'
    median, names, expected_sigma and random_sigma (file units), predicted_target_error_mm
    (linearised) and the random sets' median, problem ("" or why there is no plan)], csv (the text
    of calibration-plan.csv)."""

    __slots__ = ()

    def __bool__(self) -> bool:
        return all(not p["problem"] for p in self._fields["plans"])


class Identification(Record):
    """A motor identification (fivebar identify DESIGN LOG.csv, the motor rig): joints [one dict per
    joint: joint, method, keys, value, sigma, identified (arrays in the order of keys),
    unidentifiable, estimate_names, estimate_value, estimate_sigma, covariance, correlation (of the
    mechanical base parameters' estimate), residual_sigma, drive_fit_percent], refused (keys
    asked for with fit= that the log cannot identify), gate_passed, gate_reasons, patched,
    not_patched, design (the patched Design the CLI would write, or None)."""

    __slots__ = ()

    def __bool__(self) -> bool:
        return bool(self._fields["gate_passed"]) and not self._fields["refused"]


class Part(Record):
    """One printable part (fivebar parts --no-render): station, name (the file stem), kind, uses
    ("lower/L1", ...), mechanisms (["lower", "upper"]), count, length_mm (links' centre distance, else None), height_mm
    (or None), scad (the text of its top-level .scad file)."""

    __slots__ = ()


# --- Kinematics ------------------------------------------------------------------------------------


def _scalar(*values: Any) -> bool:
    return all(not isinstance(v, np.ndarray) and np.ndim(v) == 0 for v in values)


def _broadcast(a: Any, an: str, b: Any, bn: str) -> Any:
    """a and b broadcast to one shape, NumPy's rules (a Python number becomes a float64 array);
    arrays of one shape already pass through untouched (the kernels read them in place). The
    dtype stays the caller's: the kernels refuse what is not float64, naming the argument."""
    a = np.asarray(a, dtype=np.float64) if np.ndim(a) == 0 and not isinstance(a, np.ndarray) else a
    b = np.asarray(b, dtype=np.float64) if np.ndim(b) == 0 and not isinstance(b, np.ndarray) else b
    if not isinstance(a, np.ndarray) or not isinstance(b, np.ndarray) or a.shape == b.shape:
        return a, b
    try:
        shape = np.broadcast_shapes(a.shape, b.shape)
    except ValueError:
        raise ValueError(f"shape mismatch: {an} has shape {a.shape}, {bn} has {b.shape}, "
                         "which do not broadcast together") from None
    return np.ascontiguousarray(np.broadcast_to(a, shape)), np.ascontiguousarray(np.broadcast_to(b, shape))


_ANGLE_UNITS = ("rad", "deg")


def _angles(theta1: Any, theta2: Any, unit: Optional[str]) -> Any:
    """Motor angles in radians from the caller's unit. Without unit= they are radians, and a value
    beyond one turn (|theta| > 2 pi) is refused: fk(m, 100, 80) is degrees given as radians far
    more often than 16 turns of a motor."""
    if unit not in (None, *_ANGLE_UNITS):
        raise ValueError(f"unit = {unit!r}: must be 'rad' or 'deg'")
    if unit == "deg":
        return np.deg2rad(theta1), np.deg2rad(theta2)
    if unit is None:
        for name, value in (("theta1", theta1), ("theta2", theta2)):
            v = np.asarray(value)
            if v.dtype.kind not in "fiu" or not v.size:
                continue
            # Two reductions that skip NaN and allocate nothing (the batch kernels promise that);
            # NaN and infinities are left to the kernels, which name their index.
            hi, lo = float(np.fmax.reduce(v, axis=None)), float(np.fmin.reduce(v, axis=None))
            worst = max((x for x in (hi, -lo) if np.isfinite(x)), default=0.0)
            if worst > 2 * np.pi:
                shown = hi if hi == worst else lo
                raise InputError(f"{name} = {shown:g}: angles are in radians unless unit='deg' is given, and "
                                 f"{abs(shown):g} rad is more than one turn (pass unit='deg' for degrees, or "
                                 "unit='rad' to mean radians beyond one turn)")
    return theta1, theta2


def fk(mechanism: Mechanism, theta1: Any, theta2: Any, *, unit: Optional[str] = None, branch: Optional[str] = None,
       out: Any = None) -> Any:
    """Forward kinematics at motor angles: radians, or degrees with unit="deg" (without unit= a
    value beyond one turn raises InputError). Scalars -> Pose; arrays (float64, shapes that
    broadcast) -> (x, y, status) arrays (mm, mm, uint8) from the batch kernel, written into
    out=(x, y, status) when given. branch ("+", "-", "any") for scalars only (arrays use the
    design's assembly mode)."""
    theta1, theta2 = _angles(theta1, theta2, unit)
    if _scalar(theta1, theta2) and out is None:
        return mechanism.fk(float(theta1), float(theta2), branch)
    if branch is not None:
        raise ValueError("branch: only for scalar angles (the batch kernel uses the design's assembly mode)")
    theta1, theta2 = _broadcast(theta1, "theta1", theta2, "theta2")
    return mechanism.fk_batch(theta1, theta2, out=out)


def ik(mechanism: Mechanism, x: Any, y: Any, *, mode: Optional[str] = None, out: Any = None) -> Any:
    """Inverse kinematics at tactor points (mm). Scalars -> Pose; arrays (shapes that broadcast) ->
    (theta1, theta2, status) (rad, rad, uint8). mode (e.g. "+-") for scalars only."""
    if _scalar(x, y) and out is None:
        return mechanism.ik(float(x), float(y), mode)
    if mode is not None:
        raise ValueError("mode: only for scalar points (the batch kernel uses the design's working mode)")
    x, y = _broadcast(x, "x", y, "y")
    return mechanism.ik_batch(x, y, out=out)


def jacobian(mechanism: Mechanism, theta1: Any, theta2: Any, *, unit: Optional[str] = None) -> Any:
    """Jacobian dP/dtheta (mm/rad) at motor angles (rad, or deg with unit="deg", as fk) -> (J, status):
    a 2x2 array and a Status for scalars, J[..., 2, 2] and a uint8 array for arrays (shapes that
    broadcast); J is zero where it does not exist."""
    theta1, theta2 = _angles(theta1, theta2, unit)
    if _scalar(theta1, theta2):
        J, status = mechanism.jacobian_batch(np.array([float(theta1)]), np.array([float(theta2)]))
        return J[0], Status(int(status[0]))
    theta1, theta2 = _broadcast(theta1, "theta1", theta2, "theta2")
    return mechanism.jacobian_batch(theta1, theta2)


def lci(mechanism: Mechanism, x: Any, y: Any, *, out: Any = None) -> Any:
    """Local conditioning index 1/cond(J) at tactor points (mm) in the working mode -> (lci, status);
    lci is 0 where the point is unreachable or singular. Arrays broadcast as ik's."""
    if _scalar(x, y) and out is None:
        value, status = mechanism.lci_batch(np.array([float(x)]), np.array([float(y)]))
        return float(value[0]), Status(int(status[0]))
    x, y = _broadcast(x, "x", y, "y")
    return mechanism.lci_batch(x, y, out=out)


# --- Studies ---------------------------------------------------------------------------------------


def _station(subject: Union[Design, Station], station: Optional[str]) -> Station:
    if isinstance(subject, Station):
        if station is not None and station != subject.name:
            raise ValueError(f"station={station!r} given with the station {subject.name!r}")
        return subject
    if isinstance(subject, Design):
        if station is None:
            with_mechanisms = [s for s in subject.stations if s.mechanisms]
            if len(with_mechanisms) != 1:
                raise ValueError("station: name one of " + ", ".join(s.name for s in with_mechanisms))
            return with_mechanisms[0]
        return subject.station(station)
    raise TypeError(f"expected a fivebar.Design or fivebar.Station, got {type(subject).__name__}")


def workspace(subject: Union[Design, Station], station: Optional[str] = None, *, spacing_mm: float = 0.2,
              mechanism: str = "", progress: ProgressLine = None) -> Workspace:
    """The workspace of a station (fivebar workspace): exact regions, fields on a grid of
    spacing_mm, restricted areas, the shared region. progress(line) receives each stage."""
    d = _native._workspace(_station(subject, station), spacing_mm, mechanism, progress)
    d["mechanisms"] = {k: MechanismWorkspace(v) for k, v in d["mechanisms"].items()}
    if d["shared"] is not None:
        d["shared"] = Region(d["shared"])
    return Workspace(d)


def coverage(subject: Union[Design, Station, Mechanism], station: Optional[str] = None, *,
             target: Optional[Ellipse] = None) -> Union[StationCoverage, CoverageResult]:
    """Coverage of the target ellipse (fivebar coverage): for a station (or a design and a station
    name) a StationCoverage with lower, upper and shared; for a Mechanism and a target a
    CoverageResult. target overrides the station's ellipse."""
    if isinstance(subject, Mechanism):
        if target is None:
            raise ValueError("target: a mechanism's coverage needs the target Ellipse")
        return _native._coverage_mechanism(subject, target)
    return StationCoverage(_native._coverage_station(_station(subject, station), target))


def sweep(design: Design, *, threads: int = 0, chunk: int = 4096,
          progress: Optional[Callable[[int, int, float], Any]] = None) -> Dict[str, np.ndarray]:
    """Runs the design's sweep: section in memory (the CLI's `fivebar sweep` without files) and
    returns its columns: index, the swept values (<name>_mm), status, covered, margins, min_lci,
    min_force_capability, footprints, collision_fraction, robust_margin_mm (NaN where not
    evaluated: status says why) and pareto (on the non-dominated set). pandas.DataFrame(result)
    makes the table. threads 0: every core. progress(done, total, seconds) after each chunk."""
    return _native._sweep(design, threads, chunk, progress)


def optimize(design: Design, *, out_dir: Optional[str] = None, evaluations: int = 0, seconds: float = 0.0,
             threads: int = 0, plots: bool = False, full_figures: bool = False, resume: bool = False,
             progress: Optional[Callable[[int, int, float, int], Any]] = None) -> OptimizeResult:
    """Runs the design's optimize: section (fivebar optimize) and returns the front as columns with
    the chosen design. Files (front.csv, chosen.yaml, checkpoint.json, ...) go to out_dir (a
    temporary directory, removed after, when None). evaluations / seconds override the budget.
    progress(evaluations, budget, seconds, front_size) after each round; Ctrl-C stops after the
    round (the checkpoint in out_dir resumes it with resume=True) and raises KeyboardInterrupt."""
    def run(directory: str) -> OptimizeResult:
        d = _native._optimize(design, directory, evaluations, seconds, threads, plots, full_figures, resume, progress)
        for k in ("chosen", "polished", "reference"):
            if d[k] is not None:
                d[k] = Candidate(d[k])
        return OptimizeResult(d)

    if out_dir is not None:
        return run(str(out_dir))
    with tempfile.TemporaryDirectory(prefix="fivebar-optimize-") as directory:
        result = run(directory)
        return OptimizeResult({**result._fields, "files": []})


def simulate(design: Design, *, station: str = "", pattern: Optional[str] = None, step: bool = False,
             rtol: float = 1e-6, max_wall_s: float = 120.0, progress: ProgressLine = None) -> List[Simulation]:
    """Simulates the station's patterns (or one pattern, or a 1 mm step) under the PID loop
    (fivebar simulate --no-render: the links' masses from the closed form) and returns one
    Simulation per reference with its time series as arrays."""
    runs = _native._simulate(design, station, pattern, step, rtol, max_wall_s, progress)
    out = []
    for d in runs:
        d["mechanisms"] = {k: MechanismSeries(v) for k, v in d["mechanisms"].items()}
        out.append(Simulation(d))
    return out


def tolerance(design: Design, *, station: str = "", spacing_mm: float = 0.25,
              progress: ProgressLine = None) -> List[ToleranceMap]:
    """The tolerance study of every mechanism (fivebar tolerance --no-files): error maps over the
    reachable region, figures at the centre and over the target, robust coverage."""
    return [ToleranceMap(d) for d in _native._tolerance(design, station, spacing_mm, progress)]


def control(design: Design, *, station: str = "", progress: ProgressLine = None) -> List[ControlStudy]:
    """The loop study of every station (fivebar control --no-render): stability over the target,
    spectral-radius fields, margins and performance."""
    studies = []
    for d in _native._control(design, station, progress):
        studies.append(ControlStudy(d))
    return studies


def export_gate(design: Design, *, stations: Sequence[str] = (), progress: ProgressLine = None) -> ExportGate:
    """The export gate (fivebar export's checks, nothing written): passed, every check, reasons."""
    d = _native._export_gate(design, list(stations), progress)
    d["checks"] = [GateCheck(c) for c in d["checks"]]
    return ExportGate(d)


# --- Device: collision, patterns, replay ------------------------------------------------------------


def _point(value: Any, name: str) -> Any:
    """(x, y) in mm from a sequence or array of two numbers, or InputError naming the argument."""
    try:
        a = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise InputError(f"{name}: expected 2 numbers (x, y) in mm, got {value!r}") from None
    if a.shape != (2,):
        got = f"{a.size} numbers" if a.ndim == 1 else f"an array of shape {a.shape}"
        raise InputError(f"{name}: expected 2 numbers (x, y) in mm, got {got}")
    return (float(a[0]), float(a[1]))


def collision(design: Design, upper: Sequence[float], lower: Sequence[float], *, station: str = "") -> Collision:
    """The upper tactor at ``upper`` and the lower at ``lower`` (x, y mm) on a station with both
    mechanisms (``station=``, default the only one): exact clearance of the link outlines and the
    paper's priority rule (the upper keeps its target; a colliding lower target moves to the
    closest collision-free point). Nothing is written."""
    return Collision(_native._collision(design, station, _point(upper, "upper"), _point(lower, "lower")))


def collision_map(design: Design, *, station: str = "", spacing_mm: float = 0.75) -> CollisionMap:
    """The collision map of a station with both mechanisms (``fivebar collision DESIGN`` without
    --upper and --lower): every pair of grid points of spacing ``spacing_mm`` inside the target
    ellipse, checked exactly. Nothing is written."""
    return CollisionMap(_native._collision_map(design, station, float(spacing_mm)))


def pattern(design: Design, kind: str, *, station: str = "", amplitude_mm: Optional[float] = None,
            amplitude_deg: Optional[float] = None, frequency_hz: Optional[float] = None,
            duration_s: Optional[float] = None, rate_hz: Optional[float] = None,
            separation_mm: Optional[float] = None, center: Optional[Sequence[float]] = None,
            max_joint_speed_deg_s: Optional[float] = None) -> PatternResult:
    """The pattern ``kind`` (stretch, slip, twist, pivot) on a station with both mechanisms, as
    ``fivebar pattern`` computes it: parameters not given come from the design's ``patterns:``
    section, else the defaults (the CLI's options of the same names). Nothing is written."""
    return PatternResult(_native._pattern(design, station, kind, amplitude_mm, amplitude_deg, frequency_hz,
                                          duration_s, rate_hz, separation_mm,
                                          None if center is None else _point(center, "center"), max_joint_speed_deg_s))


def replay(log: Union[str, "os.PathLike[str]"], config: Union[str, "os.PathLike[str]"], *,
           tolerance: float = 1e-9) -> Replay:
    """Feeds a device log (CSV of measured joints, reference points and logged duties) through a
    fresh runtime of the exported configuration ``config`` (fivebar export --format json) and
    compares the duties row by row, as ``fivebar replay LOG --config EXPORTED.json``."""
    return Replay(_native._replay(str(log), str(config), float(tolerance)))


def replay_sil(design: Design, out_dir: Union[str, "os.PathLike[str]"], *, station: str = "",
               pattern: Optional[str] = None, config: Optional[Union[str, "os.PathLike[str]"]] = None) -> SilReplay:
    """The runtime closed around the simulator for the patterns of each station with both
    mechanisms (or ``station``, ``pattern``), as ``fivebar replay DESIGN --sil``: with ``config``
    the exported file's gains and calibration, else the design's export in memory. Writes each
    run's log (``<station>-<pattern>-sil.csv``, replayable by ``fivebar.replay``) into ``out_dir``
    and nothing elsewhere."""
    return SilReplay(_native._replay_sil(design, os.fspath(out_dir), station, pattern,
                                         None if config is None else os.fspath(config)))


def calibrate(design: Design, measurements: Union[str, "os.PathLike[str]"], *, station: str = "",
              mechanism: str = "", frame: str = "fixed", fit: Sequence[str] = (), loss: str = "none",
              loss_scale: float = 2.0, sigma_mm: Optional[float] = None, holdout: int = 0) -> Calibration:
    """Fits link lengths, base joints and potentiometer calibration to a measurement file, as
    ``fivebar calibrate DESIGN MEAS.csv`` with the options of the same names (--frame, --fit,
    --loss, --loss-scale, --sigma, --holdout). Nothing is written; ``result.design`` is the
    patched design when the quality gate passed."""
    return Calibration(_native._calibrate(design, os.fspath(measurements), station, mechanism, frame, list(fit), loss,
                                          float(loss_scale), sigma_mm, int(holdout)))


def calibrate_hard_stops(design: Design, log: Union[str, "os.PathLike[str]"]) -> Calibration:
    """The potentiometers' V0 (and k when both stops of a joint are read) from readings taken with
    a proximal link on a hard stop (CSV ``station,mechanism,joint,stop,volts``), as ``fivebar
    calibrate DESIGN --hard-stops LOG``. Nothing is written; ``result.design`` is the patched
    design when the quality gate passed."""
    return Calibration(_native._calibrate_hard_stops(design, os.fspath(log)))


def calibration_plan(design: Design, poses: int, *, station: str = "", mechanism: str = "", sigma_mm: float = 0.02,
                     criterion: str = "i", seed: int = 1) -> CalibrationPlan:
    """Chooses ``poses`` poses per mechanism to measure, as ``fivebar calibrate DESIGN --plan N``
    (--station, --mechanism, --plan-sigma, --plan-criterion i or d, --seed). Nothing is written:
    ``result.csv`` is the text of calibration-plan.csv."""
    return CalibrationPlan(_native._calibration_plan(design, int(poses), station, mechanism, float(sigma_mm), criterion,
                                                     int(seed)))


def identify(design: Design, logs: Union[str, "os.PathLike[str]", Sequence[Union[str, "os.PathLike[str]"]]], *,
             rig: str = "motor", validation: Optional[Union[str, "os.PathLike[str]"]] = None, joint: str = "",
             method: str = "idim",
             closed_loop: bool = False, output_error: bool = True, per_direction: bool = False,
             instant_drive: bool = False, cutoff_hz: Optional[float] = None, decimation: Optional[int] = None,
             filter_order: int = 4, load_inertia: float = 0.0, fit: Sequence[str] = ()) -> Identification:
    """Identifies the motor model of each joint of the logs (one path or several fitted together),
    as ``fivebar identify DESIGN LOG.csv --no-files`` with the options of the same names
    (``output_error=False`` is --no-output-error; ``rig="index/lower"`` is --rig mechanism
    index/lower, the assembled mechanism from a device log; --plan is not bound).
    Nothing is written; ``result.design`` is the patched design when the quality gate passed."""
    paths = [os.fspath(logs)] if isinstance(logs, (str, os.PathLike)) else [os.fspath(p) for p in logs]
    return Identification(_native._identify(design, paths, rig, "" if validation is None else os.fspath(validation), joint,
                                            method, bool(closed_loop), bool(output_error), bool(per_direction),
                                            bool(instant_drive), cutoff_hz, decimation, int(filter_order),
                                            float(load_inertia), list(fit)))


def parts(design: Design, *, station: Optional[str] = None, fn: Optional[int] = None) -> List[Part]:
    """The printable parts of every station (or ``station``) with their OpenSCAD text, as
    ``fivebar parts --no-render`` writes them (``fn`` overrides print.fn). Nothing is written or
    rendered: ``part.scad`` is the file's text (it uses the library ``fivebar.scad``)."""
    return [Part(d) for d in _native._parts(design, station, fn)]


from . import runtime  # noqa: E402  (fivebar.runtime.Controller: the device runtime)
