"""Type stubs of dualcal's native module (the package re-exports it)."""

from typing import Any, Dict, List, Optional, Sequence, Tuple

import numpy as np
import numpy.typing as npt

METHODS: List[str]
BASE_METHODS: List[str]

class DualcalError(Exception):
    """The engine's message, naming the file, line and field where an input was at fault."""

class Robot:
    """A robot description: the built-in ABB IRB 14000, a URDF (file or text) or a DH table."""
    @staticmethod
    def builtin() -> Robot: ...
    @staticmethod
    def from_file(path: str) -> Robot: ...
    @staticmethod
    def from_urdf_string(text: str, path: Optional[str] = None) -> Robot: ...
    def with_arms(self, left_base: str, left_tip: str, right_base: str, right_tip: str) -> Robot: ...
    @property
    def name(self) -> str: ...
    def joint_names(self, side: str) -> List[str]: ...
    @property
    def warnings(self) -> List[str]: ...

class Dataset:
    @staticmethod
    def load(path: str, robot: Optional[Robot] = None) -> Dataset: ...
    @staticmethod
    def from_arrays(
        robot: Robot,
        reflector_names: List[str],
        nominal_reflectors_mm: npt.NDArray[np.float64],
        left_joints: Optional[npt.NDArray[np.float64]] = None,
        left_points_mm: Optional[npt.NDArray[np.float64]] = None,
        left_split: Optional[List[str]] = None,
        left_ids: Optional[List[str]] = None,
        right_joints: Optional[npt.NDArray[np.float64]] = None,
        right_points_mm: Optional[npt.NDArray[np.float64]] = None,
        right_split: Optional[List[str]] = None,
        right_ids: Optional[List[str]] = None,
        measured_together: bool = False,
    ) -> Dataset: ...
    def configuration_count(self, side: str) -> int: ...
    @property
    def reflector_names(self) -> List[str]: ...
    @property
    def warnings(self) -> List[str]: ...
    @property
    def robot_name(self) -> str: ...

class CalibrationResult:
    @property
    def converged(self) -> bool: ...
    @property
    def method(self) -> Tuple[str, str]: ...
    @property
    def stages(self) -> List[Dict[str, Any]]: ...
    @property
    def params(self) -> Dict[str, Any]:
        """``{"left": {name: value}, "right": {...}, "left_base_from_right_base": (4, 4) mm}``."""
    @property
    def nominal_params(self) -> Dict[str, Any]: ...
    @property
    def sigma(self) -> Dict[str, Dict[str, float]]: ...
    @property
    def units(self) -> Dict[str, Dict[str, str]]: ...
    @property
    def identified(self) -> Dict[str, List[str]]: ...
    @property
    def uncertainty(self) -> Dict[str, Optional[Dict[str, Any]]]: ...
    @property
    def accuracy(self) -> Dict[str, Dict[str, Dict[str, Any]]]: ...
    @property
    def errors(self) -> Dict[str, Dict[str, Any]]:
        """Per arm: ``ids``, ``split``, ``worst_position_mm`` (n,), ``worst_orientation_rad`` (n,),
        ``point_errors_mm`` (n, K), ``excluded`` (n,) bool."""
    @property
    def nominal_errors(self) -> Dict[str, Dict[str, Any]]: ...
    def pair_errors(
        self, split: str = "ver", model: str = "calibrated"
    ) -> Dict[str, npt.NDArray[np.float64]]:
        """Per-pair samples of the paper's histograms: ``left_position_mm``, ``collaborative_position_mm``, …"""
    @property
    def warnings(self) -> List[str]: ...
    def params_json(self) -> str: ...
    def save(self, path: str) -> None: ...
    def to_urdf(self) -> str: ...
    def save_urdf(self, path: str) -> None: ...
    def overlay(self, json: bool = False) -> str: ...
    def abb_base_frames(self) -> str: ...
    def compensate(
        self, side: str, joints: npt.NDArray[np.float64], controller_base: str = "nominal"
    ) -> Dict[str, Any]:
        """Nominal joint targets ``(n, J)`` (rad) compensated for the calibrated robot: ``joints``
        ``(n, J)`` (NaN rows where refused), ``ok`` ``(n,)`` bool, ``residual_mm`` ``(n,)``,
        ``largest_change`` ``(n,)``, ``reasons`` (``None`` or why a target was refused)."""
    def compensate_file(
        self,
        side: str,
        path: str,
        angle_unit: str = "deg",
        length_unit: str = "mm",
        controller_base: str = "nominal",
    ) -> str:
        """A target list file compensated: the CSV ``dualcal compensate`` writes."""

class ImportResult:
    @property
    def dataset(self) -> Dataset: ...
    @property
    def report(self) -> str: ...
    def save(self, path: str, overwrite: bool = False) -> None: ...

class PlanResult:
    def configurations(self, side: str) -> npt.NDArray[np.float64]:
        """The configurations of ``side`` in visiting order, ``(n, J)`` float64 (rad)."""
    @property
    def predicted(self) -> Dict[str, Optional[Dict[str, Any]]]:
        """Per arm ``point_sigma_mm``, ``verification_ratio`` and ``uncertainty`` (σ per parameter)."""
    @property
    def summary(self) -> str: ...
    def files(self) -> Dict[str, str]: ...
    def save(self, path: str, overwrite: bool = False) -> None: ...

def calibrate(
    dataset: Dataset,
    robot: Optional[Robot] = None,
    method: Optional[str] = None,
    base_method: str = "minimax",
    model: str = "geometric",
    split: str = "cal",
    exclude: Sequence[str] = ...,
    max_iterations: Optional[int] = None,
    keep_weak: bool = False,
) -> CalibrationResult: ...
def evaluate(dataset: Dataset, params: str) -> Dict[str, Any]: ...
def import_files(
    robot: Optional[Robot] = None,
    left_points: Optional[str] = None,
    left_joints: Optional[str] = None,
    right_points: Optional[str] = None,
    right_joints: Optional[str] = None,
    *,
    matching: Optional[str] = None,
    points_format: Optional[str] = None,
    length_unit: Optional[str] = None,
    angle_unit: Optional[str] = None,
    joint_length_unit: Optional[str] = None,
    columns: Optional[str] = None,
    joint_order: Optional[str] = None,
    decimal_comma: bool = False,
    time_tolerance_s: Optional[float] = None,
    verify_last: Optional[int] = None,
    measured_together: bool = False,
    reflectors: Optional[List[Tuple[str, Tuple[float, float, float]]]] = None,
) -> ImportResult: ...
def plan(
    robot: Optional[Robot],
    tracker_mm: Tuple[float, float, float],
    n: int = 20,
    *,
    candidates: int = 600,
    seed: int = 1,
    max_incidence_deg: float = 60.0,
    keep_out: Sequence[Tuple[Tuple[float, float, float], Tuple[float, float, float]]] = ...,
    extend: Optional[Dataset] = None,
) -> PlanResult: ...
