"""dualcal: two-step minimax kinematic calibration of dual-arm robots from laser-tracker data.

The same engine as the ``dualcal`` command line and workbench (Rust), with numpy arrays in and out::

    import dualcal
    ds = dualcal.Dataset.load("assets/datasets/example")
    result = dualcal.calibrate(ds)                     # the paper's minimax, both steps
    ver = result.accuracy["verification"]["calibrated"]
    print(ver["collaborative"]["pos_rms_mm"])
    result.save("params.json")

Arrays: joint values ``(n, J)`` float64 in rad (a prismatic joint's in mm), chain order; tracker
points ``(n, K, 3)`` float64 in mm, the tracker frame; nominal reflector coordinates ``(K, 3)`` mm in
the arm's tip frame. Errors raise :class:`DualcalError` with the engine's message (file, line, field).
The calibration releases the interpreter lock while it runs.
"""

from __future__ import annotations

from typing import Iterable, Optional, Sequence

import numpy as np

from ._dualcal import (
    BASE_METHODS,
    METHODS,
    CalibrationResult,
    Dataset as _NativeDataset,
    DualcalError,
    ImportResult as _NativeImportResult,
    PlanResult,
    Robot,
    calibrate as _calibrate,
    evaluate,
    import_files as _import_files,
    plan as _plan,
)

__all__ = [
    "BASE_METHODS",
    "METHODS",
    "CalibrationResult",
    "Dataset",
    "DualcalError",
    "ImportResult",
    "PlanResult",
    "Robot",
    "calibrate",
    "evaluate",
    "import_files",
    "plan",
]


def _f64(array, ndim: int, name: str) -> np.ndarray:
    out = np.ascontiguousarray(array, dtype=np.float64)
    if out.ndim != ndim:
        raise DualcalError(f"{name} has {out.ndim} dimension(s), expected {ndim}")
    return out


class Dataset:
    """Measurements with the robot they were taken on, loaded and checked (joint counts, limits)."""

    __slots__ = ("_native",)

    def __init__(self, native: _NativeDataset):
        self._native = native

    @staticmethod
    def load(path, robot: Optional[Robot] = None) -> "Dataset":
        """A dataset directory (``dataset.toml`` and its CSVs) with the robot its manifest names
        (else the built-in IRB 14000), or with ``robot``."""
        return Dataset(_NativeDataset.load(str(path), robot))

    @staticmethod
    def from_arrays(
        robot: Robot,
        reflector_names: Sequence[str],
        nominal_reflectors_mm,
        left_joints=None,
        left_points_mm=None,
        right_joints=None,
        right_points_mm=None,
        *,
        left_split: Optional[Sequence[str]] = None,
        right_split: Optional[Sequence[str]] = None,
        left_ids: Optional[Sequence[str]] = None,
        right_ids: Optional[Sequence[str]] = None,
        measured_together: bool = False,
    ) -> "Dataset":
        """Measurements in memory: per arm joints ``(n, J)`` (rad; mm for prismatic joints) and
        points ``(n, K, 3)`` (mm); ``*_split`` per configuration ``"cal"`` or ``"ver"`` (default
        all ``"cal"``). An arm left out (``None``) is not measured."""
        arm = lambda a, n, name: None if a is None else _f64(a, n, name)  # noqa: E731
        return Dataset(
            _NativeDataset.from_arrays(
                robot,
                list(reflector_names),
                _f64(nominal_reflectors_mm, 2, "nominal_reflectors_mm"),
                arm(left_joints, 2, "left_joints"),
                arm(left_points_mm, 3, "left_points_mm"),
                None if left_split is None else list(left_split),
                None if left_ids is None else list(left_ids),
                arm(right_joints, 2, "right_joints"),
                arm(right_points_mm, 3, "right_points_mm"),
                None if right_split is None else list(right_split),
                None if right_ids is None else list(right_ids),
                measured_together,
            )
        )

    def configuration_count(self, side: str) -> int:
        """Configurations of ``side`` (``"left"`` or ``"right"``), both splits."""
        return self._native.configuration_count(side)

    @property
    def reflector_names(self) -> list:
        return self._native.reflector_names

    @property
    def warnings(self) -> list:
        return self._native.warnings

    @property
    def robot_name(self) -> str:
        return self._native.robot_name

    def __repr__(self) -> str:
        return repr(self._native)


def calibrate(
    dataset: Dataset,
    robot: Optional[Robot] = None,
    method: Optional[str] = None,
    base_method: str = "minimax",
    model: str = "geometric",
    split: str = "cal",
    exclude: Iterable[str] = (),
    max_iterations: Optional[int] = None,
    keep_weak: bool = False,
) -> CalibrationResult:
    """Both steps of the calibration with the command line's defaults (``dualcal calibrate``).

    ``method``: step 1's, one of :data:`METHODS` (default: ``"minimax"``, or ``"position"`` for one
    marker per hand measured together in one camera frame); ``base_method``: step 2's, one of
    :data:`BASE_METHODS`; ``model``: ``"geometric"`` (the paper's), ``"elastic"``, ``"harmonic"``,
    ``"full"``, …; ``split``: ``"cal"`` or ``"all"``; ``exclude``: configuration ids left out;
    ``robot``: calibrate a dataset loaded from a directory on another robot description;
    ``keep_weak``: keep the weak parameters — those the configurations barely constrain across the
    workspace — free rather than held at their nominal values (``--keep-weak``).
    """
    native = dataset._native if isinstance(dataset, Dataset) else dataset
    return _calibrate(
        native,
        robot,
        method,
        base_method,
        model,
        split,
        [str(e) for e in exclude],
        max_iterations,
        keep_weak,
    )


_evaluate = evaluate


def evaluate(dataset: Dataset, params) -> dict:  # noqa: F811
    """The accuracy of a parameter file's model on ``dataset``: ``{"calibration": …,
    "verification": …}`` (what ``dualcal evaluate`` prints)."""
    native = dataset._native if isinstance(dataset, Dataset) else dataset
    return _evaluate(native, str(params))


class ImportResult:
    """What :func:`import_files` made: the :class:`Dataset` (ready to calibrate) and the report."""

    __slots__ = ("_native",)

    def __init__(self, native: _NativeImportResult):
        self._native = native

    @property
    def dataset(self) -> Dataset:
        """The imported measurements with their robot, checked and screened."""
        return Dataset(self._native.dataset)

    @property
    def report(self) -> str:
        """What matched and what did not, and why (file and line): ``dualcal import``'s report."""
        return self._native.report

    def save(self, path, overwrite: bool = False) -> None:
        """Write the dataset directory ``path`` (``dataset.toml``, the arms' CSVs, the report as
        ``import-report.txt``); an existing non-empty directory only with ``overwrite``."""
        self._native.save(str(path), overwrite)

    def __repr__(self) -> str:
        return repr(self._native)


def import_files(
    left_points=None,
    left_joints=None,
    right_points=None,
    right_joints=None,
    *,
    robot: Optional[Robot] = None,
    match: str = "auto",
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
    reflectors: Optional[dict] = None,
) -> ImportResult:
    """Tracker point files and the controller's joint logs as a dataset (``dualcal import``).

    Per arm a point file (SpatialAnalyzer, Leica Tracker Pilot, figaroh, or any CSV with
    ``columns="target=1,x=2,y=3,z=4"``) and a joint log (``id,q1..qN[,split]``; ``None`` when the
    point file holds the joints); one arm alone makes a dataset of that arm. ``match``: ``"auto"``,
    ``"name"`` (targets ``<id>_<reflector>``), ``"order"`` or ``"time"``; ``length_unit``: of point
    files that do not state theirs (``"mm"``, ``"m"``, ``"um"``, ``"in"``, ``"ft"``); ``angle_unit``:
    of the joint logs (``"deg"``, ``"rad"``; default the header's, else degrees); ``reflectors``:
    ``{name: (x, y, z)}`` in the tip frame, mm (default ``a``, ``b``, ``c`` at the paper's positions);
    ``robot``: the robot measured (default the built-in IRB 14000). Errors name file, line and field.
    """
    return ImportResult(
        _import_files(
            robot,
            None if left_points is None else str(left_points),
            None if left_joints is None else str(left_joints),
            None if right_points is None else str(right_points),
            None if right_joints is None else str(right_joints),
            matching=match,
            points_format=points_format,
            length_unit=length_unit,
            angle_unit=angle_unit,
            joint_length_unit=joint_length_unit,
            columns=columns,
            joint_order=joint_order,
            decimal_comma=decimal_comma,
            time_tolerance_s=time_tolerance_s,
            verify_last=verify_last,
            measured_together=measured_together,
            reflectors=None
            if reflectors is None
            else [(str(k), tuple(float(c) for c in v)) for k, v in reflectors.items()],
        )
    )


def plan(
    tracker_mm,
    n: int = 20,
    *,
    robot: Optional[Robot] = None,
    candidates: int = 600,
    seed: int = 1,
    max_incidence_deg: float = 60.0,
    keep_out: Iterable = (),
    extend: Optional[Dataset] = None,
) -> PlanResult:
    """The configurations to measure (``dualcal plan``): ``n`` per arm, collision-free, the
    reflectors facing a tracker at ``tracker_mm`` (x, y, z in the robot's body frame, mm), in a
    short visiting order, with the predicted accuracy. ``keep_out``: boxes ``((x0, y0, z0), (x1, y1,
    z1))`` of the cell (mm) no arm may come near; ``extend``: a dataset whose configurations start
    the design. The result's ``configurations(side)`` is ``(n, J)`` float64 (rad)."""
    boxes = [
        (tuple(float(c) for c in lo), tuple(float(c) for c in hi)) for lo, hi in keep_out
    ]
    return _plan(
        robot,
        tuple(float(c) for c in tracker_mm),
        n,
        candidates=candidates,
        seed=seed,
        max_incidence_deg=max_incidence_deg,
        keep_out=boxes,
        extend=None if extend is None else extend._native,
    )
