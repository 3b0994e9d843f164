# Type stubs of the Python module fivebar (docs/python.md). Units: mm and radians; to_dict() gives
# the CLI's --json documents (mm, deg).
from typing import Any, Callable, Dict, List, Literal, Optional, Sequence, Tuple, Union, overload
import enum
import os

import numpy as np
import numpy.typing as npt

F64 = npt.NDArray[np.float64]
U8 = npt.NDArray[np.uint8]
ArrayLike = Union[F64, Sequence[float]]
Point = Tuple[float, float]
ProgressLine = Optional[Callable[[str], Any]]

class InputError(ValueError):
    file: Optional[str]
    line: Optional[int]
    key: Optional[str]
    def __init__(self, message: str = ...) -> None: ...

class IoError(OSError): ...

class Status(enum.IntEnum):
    ok = 0
    unreachable = 1
    singular_type1 = 2
    singular_type2 = 3

class Ellipse:
    def __init__(self, center: Point, axes: Point, angle: float = 0.0) -> None: ...
    @property
    def center(self) -> Point: ...
    @property
    def axes(self) -> Point: ...
    @property
    def angle(self) -> float: ...
    def boundary_point(self, t: float) -> Point: ...
    def to_dict(self) -> Dict[str, Any]: ...

class Pose:
    status: Status
    theta1: float
    theta2: float
    A1: Point
    A2: Point
    P: Point
    mode: str
    assembly: int
    J: F64
    jacobian_valid: bool
    lci: float
    force_capability: float
    transmission: List[float]
    type1_sin: List[float]
    type2_sin: float
    type1_distance_mm: float
    closure_error_mm: float
    within_joint_limits: bool
    def to_dict(self) -> Dict[str, Any]: ...

class Mechanism:
    def __init__(self, name: str = "lower", *, bases: Tuple[Point, Point], links: Tuple[float, float, float, float],
                 working_mode: str = "-+", assembly_mode: str = "+",
                 joint_limits: Optional[Tuple[Point, Point]] = None, min_lci: float = 0.0) -> None: ...
    name: str
    O1: Point
    O2: Point
    links: Tuple[float, float, float, float]
    working_mode: str
    assembly_mode: str
    joint_limits: Optional[Tuple[Point, Point]]
    min_lci: float
    length_scale: float
    def fk(self, theta1: float, theta2: float, branch: Optional[str] = None) -> Pose: ...
    def fk_all(self, theta1: float, theta2: float) -> List[Pose]: ...
    def ik(self, x: float, y: float, mode: Optional[str] = None) -> Pose: ...
    def ik_all(self, x: float, y: float) -> List[Pose]: ...
    def fk_batch(self, theta1: ArrayLike, theta2: ArrayLike, *, out: Optional[Tuple[F64, F64, U8]] = None) -> Tuple[F64, F64, U8]: ...
    def ik_batch(self, x: ArrayLike, y: ArrayLike, *, out: Optional[Tuple[F64, F64, U8]] = None) -> Tuple[F64, F64, U8]: ...
    def lci_batch(self, x: ArrayLike, y: ArrayLike, *, out: Optional[Tuple[F64, U8]] = None) -> Tuple[F64, U8]: ...
    def jacobian_batch(self, theta1: ArrayLike, theta2: ArrayLike) -> Tuple[F64, U8]: ...
    def to_dict(self) -> Dict[str, Any]: ...

class Station:
    name: str
    target: Ellipse
    lower: Optional[Mechanism]
    upper: Optional[Mechanism]
    mechanisms: List[Mechanism]
    def mechanism(self, which: str) -> Mechanism: ...

class Design:
    @staticmethod
    def from_yaml(text: str, origin: str = "<string>") -> Design: ...
    name: str
    source: str
    stations: List[Station]
    products: Optional[List[str]]
    def station(self, name: str) -> Station: ...
    def has_section(self, key: str) -> bool: ...
    def number(self, key: str) -> float: ...
    def with_numbers(self, values: Dict[str, float]) -> Design: ...
    def to_yaml(self) -> str: ...

class CoverageResult:
    covered: bool
    inside: bool
    margin_mm: float
    margin_error_mm: float
    decided: bool
    covered_fraction: float
    worst_point: Point
    min_lci: float
    min_lci_point: Point
    min_force_capability: float
    lci_ok: bool
    assembly_ok: bool
    method: str
    reason: str
    def to_dict(self) -> Dict[str, Any]: ...

class Problem:
    def __init__(self, design: Design) -> None: ...
    dimension: int
    lower: List[float]
    upper: List[float]
    variables: List[str]
    objectives: List[Tuple[str, bool]]
    figures: List[str]
    def reference_values(self) -> List[float]: ...
    def design_at(self, x: ArrayLike) -> Design: ...
    def evaluate(self, x: ArrayLike) -> Dict[str, Any]: ...
    def fitness(self, x: ArrayLike) -> List[float]: ...
    def evaluate_many(self, X: npt.ArrayLike, *, threads: int = 0,
                      progress: Optional[Callable[[int, int], Any]] = None) -> Dict[str, np.ndarray]: ...

class Studio:
    """A design file open for editing by key path, as in `fivebar studio` (docs/studio.md)."""
    def __init__(self, file: str) -> None: ...
    file: str
    text: str
    sha256: str
    edits: Dict[str, Union[float, str]]
    edited_text: str
    def set(self, key: str, value: Union[float, str]) -> None: ...
    def unset(self, key: str) -> None: ...
    def clear(self) -> None: ...
    def figures(self, station: Optional[str] = None, full: bool = False, lower: Optional[Sequence[float]] = None,
                upper: Optional[Sequence[float]] = None) -> Dict[str, Any]: ...
    def pattern(self, kind: str, station: Optional[str] = None) -> Dict[str, Any]: ...
    def preview(self) -> Dict[str, Any]: ...
    def save(self) -> Dict[str, Any]: ...
    def reload(self) -> None: ...

def load(path: Union[str, os.PathLike[str]]) -> Design: ...
def version() -> str: ...
__version__: str

class Record:
    def __getattr__(self, name: str) -> Any: ...
    def field_names(self) -> List[str]: ...
    def to_dict(self) -> Any: ...

class Region(Record):
    area_mm2: float
    perimeter_mm: float
    components: int
    holes: int
    bounds: Tuple[float, float, float, float]
    boundary: List[F64]
    boundary_is_hole: List[bool]

class MechanismWorkspace(Region):
    mechanism: Mechanism
    fields: Dict[str, np.ndarray]
    assembly_area_mm2: float
    assembly_error_mm2: float
    assembly_contours: List[F64]
    lci_area_mm2: float
    lci_error_mm2: float
    lci_contours: List[F64]
    centre: Pose

class Workspace(Record):
    station: str
    target: Ellipse
    grid: Dict[str, Any]
    mechanisms: Dict[str, MechanismWorkspace]
    shared: Optional[Region]

class StationCoverage(Record):
    station: str
    covered: bool
    lower: Optional[CoverageResult]
    upper: Optional[CoverageResult]
    shared: Optional[CoverageResult]

class Candidate(Record):
    x: Dict[str, float]
    figures: Dict[str, float]
    verdict: str
    status: str
    violation: float
    feasible: bool

class OptimizeResult(Record):
    algorithm: str
    evaluations: int
    rounds: int
    seconds: float
    budget_time: bool
    front: Dict[str, np.ndarray]
    chosen: Optional[Candidate]
    polished: Optional[Candidate]
    reference: Candidate
    chosen_design: Optional[Design]
    hypervolume: List[Tuple[int, float]]
    files: List[str]

class MechanismSeries(Record):
    theta_ref: F64
    theta: F64
    w: F64
    current_A: F64
    duty: F64
    voltage_V: F64
    P_ref_mm: F64
    P_mm: F64
    force_N: F64
    slipping: npt.NDArray[np.bool_]
    energy_J: F64

class Simulation(Record):
    station: str
    reference: str
    status: str
    reason: str
    t_end: float
    steps: int
    t: F64
    mechanisms: Dict[str, MechanismSeries]

class ToleranceMap(Record):
    station: str
    mechanism: str
    grid: Dict[str, Any]
    fields: Dict[str, np.ndarray]
    robust_covered: bool
    robust_margin_mm: float
    worst_3sigma_mm: float
    worst_case_mm: float
    worst_case_first_order_mm: float

class ControlStudy(Record):
    station: str
    stable: bool
    mechanisms: Dict[str, Dict[str, Any]]

class GateCheck(Record):
    kind: str
    subject: str
    passed: bool
    detail: str

class ExportGate(Record):
    passed: bool
    stations: List[str]
    checks: List[GateCheck]
    reasons: List[str]
    joints: List[Tuple[str, float, float]]
    validation: Dict[str, Any]
    def __bool__(self) -> bool: ...

class Collision(Record):
    station: str
    collides: bool
    clearance_mm: Optional[float]
    closest_pair: Optional[str]
    required_clearance_mm: float
    status: Literal["clear", "moved", "upper_unusable", "lower_unusable", "no_free_point"]
    reason: str
    upper_target: F64
    lower_target: F64
    lower_point: F64
    moved_mm: float
    clearance_after_mm: Optional[float]
    upper_pose: Pose
    lower_pose: Pose
    def __bool__(self) -> bool: ...

class CollisionMap(Record):
    station: str
    spacing_mm: float
    points: F64
    upper_ok: npt.NDArray[np.bool_]
    lower_ok: npt.NDArray[np.bool_]
    upper_fraction: F64
    lower_fraction: F64
    centre_collides: U8
    pairs: int
    colliding: int
    colliding_fraction: float
    any_free: bool
    def __bool__(self) -> bool: ...

class PatternResult(Record):
    station: str
    pattern: str
    passed: bool
    centre: F64
    max_joint_speed: float
    t: F64
    clearance_mm: F64
    commanded_clearance_mm: F64
    moved_mm: F64
    mechanisms: Dict[str, Dict[str, np.ndarray]]
    status_names: List[str]
    first_failure: Optional[Dict[str, Any]]
    def __bool__(self) -> bool: ...

class Replay(Record):
    passed: bool
    rows: int
    max_duty_difference: float
    mismatches: int
    joints: List[str]
    mechanisms: List[str]
    t: F64
    logged_duty: F64
    runtime_duty: F64
    status: U8
    def __bool__(self) -> bool: ...

class SilReplay(Record):
    ok: bool
    runs: List[Dict[str, Any]]
    def __bool__(self) -> bool: ...

class Calibration(Record):
    station: str
    mechanisms: List[str]
    poses: int
    keys: List[str]
    names: List[str]
    units: List[str]
    value: F64
    sigma: F64
    design_value: F64
    identified: npt.NDArray[np.bool_]
    covariance: F64
    covariance_names: List[str]
    key_covariance: F64
    key_covariance_keys: List[str]
    unidentifiable: List[Tuple[str, str]]
    requested_unidentifiable: bool
    condition_number: float
    observability_index: float
    sigma_mm: float
    gate_passed: bool
    gate_reasons: List[str]
    design: Optional[Design]
    def __bool__(self) -> bool: ...

class CalibrationPlan(Record):
    plans: List[Dict[str, Any]]
    csv: str
    def __bool__(self) -> bool: ...

class Identification(Record):
    joints: List[Dict[str, Any]]
    refused: List[str]
    gate_passed: bool
    gate_reasons: List[str]
    patched: List[str]
    not_patched: List[str]
    design: Optional[Design]
    def __bool__(self) -> bool: ...

class Part(Record):
    station: str
    name: str
    kind: Literal["proximal_link", "distal_link", "tactor_tip", "station_base"]
    uses: List[str]
    mechanisms: List[str]
    count: int
    length_mm: Optional[float]
    height_mm: Optional[float]
    scad: str

@overload
def fk(mechanism: Mechanism, theta1: float, theta2: float, *, unit: Optional[Literal["rad", "deg"]] = None,
       branch: Optional[str] = None) -> Pose: ...
@overload
def fk(mechanism: Mechanism, theta1: ArrayLike, theta2: ArrayLike, *, unit: Optional[Literal["rad", "deg"]] = None,
       out: Optional[Tuple[F64, F64, U8]] = None) -> Tuple[F64, F64, U8]: ...
@overload
def ik(mechanism: Mechanism, x: float, y: float, *, mode: Optional[str] = None) -> Pose: ...
@overload
def ik(mechanism: Mechanism, x: ArrayLike, y: ArrayLike, *,
       out: Optional[Tuple[F64, F64, U8]] = None) -> Tuple[F64, F64, U8]: ...
@overload
def jacobian(mechanism: Mechanism, theta1: float, theta2: float, *,
             unit: Optional[Literal["rad", "deg"]] = None) -> Tuple[F64, Status]: ...
@overload
def jacobian(mechanism: Mechanism, theta1: ArrayLike, theta2: ArrayLike, *,
             unit: Optional[Literal["rad", "deg"]] = None) -> Tuple[F64, U8]: ...
@overload
def lci(mechanism: Mechanism, x: float, y: float) -> Tuple[float, Status]: ...
@overload
def lci(mechanism: Mechanism, x: ArrayLike, y: ArrayLike, *, out: Optional[Tuple[F64, U8]] = None) -> Tuple[F64, U8]: ...

def workspace(subject: Union[Design, Station], station: Optional[str] = None, *, spacing_mm: float = 0.2,
              mechanism: str = "", progress: ProgressLine = None) -> Workspace: ...
@overload
def coverage(subject: Mechanism, station: None = None, *, target: Ellipse) -> CoverageResult: ...
@overload
def coverage(subject: Union[Design, Station], station: Optional[str] = None, *,
             target: Optional[Ellipse] = None) -> StationCoverage: ...
def sweep(design: Design, *, threads: int = 0, chunk: int = 4096,
          progress: Optional[Callable[[int, int, float], Any]] = None) -> Dict[str, np.ndarray]: ...
def optimize(design: Design, *, out_dir: Optional[str] = None, evaluations: int = 0, seconds: float = 0.0,
             threads: int = 0, plots: bool = False, full_figures: bool = False, resume: bool = False,
             progress: Optional[Callable[[int, int, float, int], Any]] = None) -> OptimizeResult: ...
def simulate(design: Design, *, station: str = "", pattern: Optional[str] = None, step: bool = False,
             rtol: float = 1e-6, max_wall_s: float = 120.0, progress: ProgressLine = None) -> List[Simulation]: ...
def tolerance(design: Design, *, station: str = "", spacing_mm: float = 0.25,
              progress: ProgressLine = None) -> List[ToleranceMap]: ...
def control(design: Design, *, station: str = "", progress: ProgressLine = None) -> List[ControlStudy]: ...
def export_gate(design: Design, *, stations: Sequence[str] = (), progress: ProgressLine = None) -> ExportGate: ...
def collision(design: Design, upper: Sequence[float], lower: Sequence[float], *, station: str = "") -> Collision: ...
def collision_map(design: Design, *, station: str = "", spacing_mm: float = 0.75) -> CollisionMap: ...
def pattern(design: Design, kind: Literal["stretch", "slip", "twist", "pivot"], *, station: str = "",
            amplitude_mm: Optional[float] = None, amplitude_deg: Optional[float] = None,
            frequency_hz: Optional[float] = None, duration_s: Optional[float] = None, rate_hz: Optional[float] = None,
            separation_mm: Optional[float] = None, center: Optional[Sequence[float]] = None,
            max_joint_speed_deg_s: Optional[float] = None) -> PatternResult: ...
def replay(log: Union[str, os.PathLike[str]], config: Union[str, os.PathLike[str]], *,
           tolerance: float = 1e-9) -> Replay: ...
def replay_sil(design: Design, out_dir: Union[str, os.PathLike[str]], *, station: str = "",
               pattern: Optional[str] = None, config: Optional[Union[str, os.PathLike[str]]] = None) -> SilReplay: ...
def calibrate(design: Design, measurements: Union[str, os.PathLike[str]], *, station: str = "", mechanism: str = "",
              frame: Literal["fixed", "fit"] = "fixed", fit: Sequence[str] = (),
              loss: Literal["none", "huber", "cauchy"] = "none", loss_scale: float = 2.0,
              sigma_mm: Optional[float] = None, holdout: int = 0) -> Calibration: ...
def calibrate_hard_stops(design: Design, log: Union[str, os.PathLike[str]]) -> Calibration: ...
def calibration_plan(design: Design, poses: int, *, station: str = "", mechanism: str = "", sigma_mm: float = 0.02,
                     criterion: Literal["i", "d"] = "i", seed: int = 1) -> CalibrationPlan: ...
def identify(design: Design, logs: Union[str, os.PathLike[str], Sequence[Union[str, os.PathLike[str]]]], *,
             rig: str = "motor", validation: Optional[Union[str, os.PathLike[str]]] = None, joint: str = "",
             method: Literal["idim", "oe"] = "idim", closed_loop: bool = False, output_error: bool = True,
             per_direction: bool = False, instant_drive: bool = False, cutoff_hz: Optional[float] = None,
             decimation: Optional[int] = None, filter_order: int = 4, load_inertia: float = 0.0,
             fit: Sequence[str] = ()) -> Identification: ...
def parts(design: Design, *, station: Optional[str] = None, fn: Optional[int] = None) -> List[Part]: ...

from . import runtime as runtime
