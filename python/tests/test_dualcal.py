"""The Python package against the bundled example and the command line (run by tools/test)."""

import json
import math
import os
import pathlib
import shutil
import subprocess

import numpy as np
import pytest

import dualcal

ROOT = pathlib.Path(__file__).resolve().parents[2]
EXAMPLE = ROOT / "assets" / "datasets" / "example"


@pytest.fixture(scope="module")
def example():
    return dualcal.Dataset.load(EXAMPLE)


@pytest.fixture(scope="module")
def result(example):
    return dualcal.calibrate(example)


def cli_binary():
    given = os.environ.get("DUALCAL_BIN")
    if given:
        return given
    for profile in ("release", "debug"):
        path = ROOT / "target" / profile / "dualcal"
        if path.exists():
            return str(path)
    pytest.skip("no dualcal binary: set DUALCAL_BIN or build it (tools/test sets it)")


def numbers(value, path=""):
    """Every number of a JSON value with its path (timings left out)."""
    if isinstance(value, dict):
        for k, v in value.items():
            if k in ("elapsed_secs",):
                continue
            yield from numbers(v, f"{path}.{k}")
    elif isinstance(value, list):
        for i, v in enumerate(value):
            yield from numbers(v, f"{path}[{i}]")
    elif isinstance(value, (int, float)) and not isinstance(value, bool):
        yield path, float(value)


def test_example_loads(example):
    assert example.configuration_count("left") == 220
    assert example.configuration_count("right") == 220
    assert example.reflector_names == ["a", "b", "c"]
    assert example.warnings == []


def test_calibration_reaches_the_noise_floor(result):
    assert result.converged
    assert result.method == ("minimax", "minimax")
    ver = result.accuracy["verification"]
    before = ver["nominal"]["collaborative"]["pos_rms_mm"]
    after = ver["calibrated"]["collaborative"]["pos_rms_mm"]
    assert before > 1.0
    assert after < 0.05
    assert [s["stage"] for s in result.stages][:2] == ["step 1 (left arm)", "step 1 (right arm)"]
    assert all(s["converged"] for s in result.stages)


def test_parameters_and_sigma(result):
    params, sigma, units = result.params, result.sigma, result.units
    assert set(params) == {"left", "right", "left_base_from_right_base"}
    base = params["left_base_from_right_base"]
    assert base.shape == (4, 4) and base.dtype == np.float64
    np.testing.assert_allclose(base[3], [0, 0, 0, 1])
    for side in ("left", "right"):
        identified = result.identified[side]
        assert len(identified) > 20
        # every identified parameter has a σ, positive and finite; the fixed ones none
        assert set(sigma[side]) == set(identified)
        assert all(0 < s < math.inf for s in sigma[side].values())
        assert set(units[side]) == set(params[side])
        nominal = result.nominal_params[side]
        moved = [n for n in params[side] if params[side][n] != nominal[n]]
        assert set(moved) <= set(identified) and moved


def test_per_configuration_errors(result):
    errors = result.errors
    for side in ("left", "right"):
        arm = errors[side]
        n = 220
        assert len(arm["ids"]) == n and len(arm["split"]) == n
        assert arm["worst_position_mm"].shape == (n,)
        assert arm["worst_position_mm"].dtype == np.float64
        assert arm["worst_orientation_rad"].shape == (n,)
        assert arm["point_errors_mm"].shape == (n, 3)
        assert arm["point_errors_mm"].dtype == np.float64
        assert arm["excluded"].dtype == np.bool_ and not arm["excluded"].any()
        nominal = result.nominal_errors[side]["worst_position_mm"]
        assert np.median(arm["worst_position_mm"]) < np.median(nominal) / 10


def test_equal_to_the_command_line(result, tmp_path):
    binary = cli_binary()
    cli_out = tmp_path / "cli.json"
    subprocess.run(
        [binary, "calibrate", str(EXAMPLE), "--out", str(cli_out), "--quiet"],
        check=True,
        capture_output=True,
    )
    py_out = tmp_path / "py.json"
    result.save(py_out)
    cli = dict(numbers(json.loads(cli_out.read_text())))
    ours = dict(numbers(json.loads(py_out.read_text())))
    assert cli.keys() == ours.keys()
    worst = max(abs(cli[k] - ours[k]) / max(1.0, abs(cli[k])) for k in cli)
    assert worst <= 1e-12, worst
    assert json.loads(result.params_json())["format"] == json.loads(cli_out.read_text())["format"]


def test_evaluate_a_parameter_file(example, result, tmp_path):
    path = tmp_path / "params.json"
    result.save(path)
    figures = dualcal.evaluate(example, path)
    # The model read back from the file (its rotations as written) gives the same figures to
    # rounding: the file holds the calibration.
    read = dict(numbers(figures["verification"]))
    held = dict(numbers(result.accuracy["verification"]["calibrated"]))
    assert read.keys() == held.keys()
    for key in read:
        assert read[key] == pytest.approx(held[key], rel=1e-9, abs=1e-12), key


def test_exports(result, tmp_path):
    urdf = result.to_urdf()
    assert urdf.lstrip().startswith("<") and "<robot" in urdf
    result.save_urdf(tmp_path / "calibrated.urdf")
    assert (tmp_path / "calibrated.urdf").read_text() == urdf
    assert "ROB_L" in result.abb_base_frames() and "ROB_R" in result.abb_base_frames()
    assert json.loads(result.overlay(json=True))


def test_never_writes_over_an_input(result, tmp_path):
    copy = tmp_path / "example"
    shutil.copytree(EXAMPLE, copy)
    ds = dualcal.Dataset.load(copy)
    res = dualcal.calibrate(ds, method="lsq")
    before = (copy / "left.csv").read_bytes()
    with pytest.raises(dualcal.DualcalError):
        res.save(copy / "left.csv")
    assert (copy / "left.csv").read_bytes() == before


def read_arm(name):
    rows = (EXAMPLE / f"{name}.csv").read_text().splitlines()
    header = rows[1].split(",")
    body = [r.split(",") for r in rows[2:] if r.strip()]
    q = [i for i, h in enumerate(header) if h.startswith("q")]
    p = [i for i, h in enumerate(header) if h[:1] in "abc" and h[1:] in ("x", "y", "z")]
    joints = np.radians(np.array([[float(r[i]) for i in q] for r in body]))
    points = np.array([[float(r[i]) for i in p] for r in body]).reshape(len(body), 3, 3)
    return joints, points, [r[-1] for r in body], [r[0] for r in body]


def test_from_arrays_equals_the_files(result):
    robot = dualcal.Robot.builtin()
    lj, lp, ls, li = read_arm("left")
    rj, rp, rs, ri = read_arm("right")
    ds = dualcal.Dataset.from_arrays(
        robot,
        ["a", "b", "c"],
        [[45.0, 0.0, 40.0], [-25.0, 40.0, 40.0], [-25.0, -40.0, 40.0]],
        lj,
        lp,
        rj,
        rp,
        left_split=ls,
        right_split=rs,
        left_ids=li,
        right_ids=ri,
    )
    assert ds.configuration_count("left") == 220
    res = dualcal.calibrate(ds)
    for side in ("left", "right"):
        for name, value in res.params[side].items():
            assert value == pytest.approx(result.params[side][name], abs=1e-6), name


def test_one_arm_from_arrays():
    lj, lp, ls, _ = read_arm("left")
    ds = dualcal.Dataset.from_arrays(
        dualcal.Robot.builtin(),
        ["a", "b", "c"],
        np.array([[45.0, 0.0, 40.0], [-25.0, 40.0, 40.0], [-25.0, -40.0, 40.0]]),
        left_joints=lj,
        left_points_mm=lp,
        left_split=ls,
    )
    res = dualcal.calibrate(ds, method="lsq")
    assert res.converged
    assert set(res.errors) == {"left"}


def test_errors_name_what_is_wrong(tmp_path):
    with pytest.raises(dualcal.DualcalError, match="nowhere"):
        dualcal.Dataset.load(tmp_path / "nowhere")
    bad = tmp_path / "bad"
    shutil.copytree(EXAMPLE, bad)
    lines = (bad / "left.csv").read_text().splitlines()
    cells = lines[4].split(",")
    cells[3] = "forty"
    lines[4] = ",".join(cells)
    (bad / "left.csv").write_text("\n".join(lines) + "\n")
    with pytest.raises(dualcal.DualcalError) as caught:
        dualcal.Dataset.load(bad)
    message = str(caught.value)
    assert "left.csv" in message and "5" in message and "q3" in message
    with pytest.raises(dualcal.DualcalError, match="method `newton`"):
        dualcal.calibrate(dualcal.Dataset.load(EXAMPLE), method="newton")
    with pytest.raises(dualcal.DualcalError, match=r"\(n, K, 3\)"):
        dualcal.Dataset.from_arrays(
            dualcal.Robot.builtin(),
            ["a"],
            [[0.0, 0.0, 40.0]],
            np.zeros((3, 7)),
            np.zeros((3, 1, 2)),
        )
    with pytest.raises(dualcal.DualcalError, match="3 rows of points|rows of points"):
        dualcal.Dataset.from_arrays(
            dualcal.Robot.builtin(),
            ["a"],
            [[0.0, 0.0, 40.0]],
            np.zeros((4, 7)),
            np.zeros((3, 1, 3)),
        )


def test_pair_errors_are_the_histograms_samples(result):
    calibrated = result.pair_errors("ver")
    nominal = result.pair_errors("ver", model="nominal")
    keys = {
        "left_position_mm",
        "right_position_mm",
        "collaborative_position_mm",
        "left_orientation_rad",
        "right_orientation_rad",
        "collaborative_orientation_rad",
    }
    assert set(calibrated) == keys == set(nominal)
    n = 100  # verification configurations per arm
    assert calibrated["left_position_mm"].shape == (n * (n - 1) // 2,)
    assert calibrated["collaborative_position_mm"].shape == (n * n,)
    assert calibrated["left_position_mm"].dtype == np.float64
    rms = lambda v: float(np.sqrt(np.mean(v**2)))  # noqa: E731
    ver = result.accuracy["verification"]["calibrated"]
    # the worst reflector's Δd per pair: its RMS lies between the per-reflector RMS and the maximum
    assert ver["collaborative"]["pos_rms_mm"] <= rms(calibrated["collaborative_position_mm"]) * 1.0001
    assert rms(calibrated["collaborative_position_mm"]) < rms(nominal["collaborative_position_mm"]) / 10
    with pytest.raises(dualcal.DualcalError, match="split `all`"):
        result.pair_errors("all")


def test_the_stubs_name_every_method():
    stub = (pathlib.Path(dualcal.__file__).parent / "_dualcal.pyi").read_text()
    for cls in (dualcal.Robot, dualcal._dualcal.Dataset, dualcal.CalibrationResult):
        for name in dir(cls):
            if not name.startswith("_"):
                assert f"def {name}(" in stub, f"{cls.__name__}.{name} is not in _dualcal.pyi"
