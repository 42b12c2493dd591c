"""The Python package's other tasks: importing tracker files, planning, compensating targets (run by
tools/test beside test_dualcal.py)."""

import pathlib

import numpy as np
import pytest

import dualcal

ROOT = pathlib.Path(__file__).resolve().parents[2]
EXAMPLE = ROOT / "assets" / "datasets" / "example"


def rows(side):
    """The example's rows of one arm: id, joints (deg), points (3, 3) mm, split."""
    lines = (EXAMPLE / f"{side}.csv").read_text().splitlines()[2:]
    for line in lines:
        cells = line.split(",")
        numbers = [float(c) for c in cells[1:17]]
        yield cells[0], numbers[:7], [numbers[7:10], numbers[10:13], numbers[13:16]], cells[17]


def write_exports(directory, skip=()):
    """Per arm a SpatialAnalyzer point list and a joint log (degrees) written from the example."""
    files = {}
    for side in ("left", "right"):
        points = ["// SpatialAnalyzer ASCII export", "// Units: Millimeters"]
        joints = ["id,q1,q2,q3,q4,q5,q6,q7,split"]
        for ident, q, p, split in rows(side):
            for name, xyz in zip("abc", p):
                if (ident, name) not in skip:
                    points.append(f"{ident}_{name} {xyz[0]!r} {xyz[1]!r} {xyz[2]!r}")
            joints.append(",".join([ident, *map(repr, q), split]))
        files[f"{side}_points"] = directory / f"{side}.txt"
        files[f"{side}_joints"] = directory / f"{side}-joints.csv"
        files[f"{side}_points"].write_text("\n".join(points) + "\n")
        files[f"{side}_joints"].write_text("\n".join(joints) + "\n")
    return files


def test_import_round_trip_equals_the_dataset(tmp_path):
    files = write_exports(tmp_path, skip={("L003", "a")})
    imported = dualcal.import_files(**files, match="name")
    assert "unmatched configuration `L003`" in imported.report
    ds = imported.dataset
    assert ds.configuration_count("left") == 219
    assert ds.configuration_count("right") == 220
    assert ds.reflector_names == ["a", "b", "c"]
    out = tmp_path / "dataset"
    imported.save(out)
    assert (out / "import-report.txt").read_text() == imported.report
    with pytest.raises(dualcal.DualcalError, match="already exists"):
        imported.save(out)
    imported.save(out, overwrite=True)
    # The written dataset reads back and calibrates as the imported one does.
    a = dualcal.calibrate(ds, max_iterations=3)
    b = dualcal.calibrate(dualcal.Dataset.load(out), max_iterations=3)
    for side in ("left", "right"):
        assert a.params[side] == b.params[side]
    np.testing.assert_array_equal(
        a.params["left_base_from_right_base"], b.params["left_base_from_right_base"]
    )


def test_import_of_the_whole_example_calibrates_as_the_example(tmp_path):
    imported = dualcal.import_files(**write_exports(tmp_path))
    a = dualcal.calibrate(imported.dataset, max_iterations=3)
    b = dualcal.calibrate(dualcal.Dataset.load(EXAMPLE), max_iterations=3)
    for side in ("left", "right"):
        for name, value in b.params[side].items():
            assert a.params[side][name] == pytest.approx(value, abs=1e-9), name


def test_one_arm_alone(tmp_path):
    files = write_exports(tmp_path)
    imported = dualcal.import_files(files["left_points"], files["left_joints"])
    assert imported.dataset.configuration_count("right") == 0
    assert "right arm: not imported" in imported.report


def test_import_errors_name_file_and_line(tmp_path):
    files = write_exports(tmp_path)
    log = files["left_joints"]
    lines = log.read_text().splitlines()
    cells = lines[5].split(",")
    cells[2] = "forty"
    lines[5] = ",".join(cells)
    log.write_text("\n".join(lines) + "\n")
    with pytest.raises(dualcal.DualcalError) as caught:
        dualcal.import_files(**files)
    message = str(caught.value)
    assert "left-joints.csv" in message and ":6" in message and "forty" in message
    with pytest.raises(dualcal.DualcalError, match="match `nearest`"):
        dualcal.import_files(**write_exports(tmp_path), match="nearest")
    with pytest.raises(dualcal.DualcalError, match="nowhere.txt"):
        dualcal.import_files(tmp_path / "nowhere.txt", files["left_joints"])
    with pytest.raises(dualcal.DualcalError, match="right_joints without right_points"):
        dualcal.import_files(files["left_points"], files["left_joints"], right_joints=log)


def test_plan(tmp_path):
    planned = dualcal.plan((2000.0, 0.0, 800.0), 8, candidates=80)
    for side in ("left", "right"):
        q = planned.configurations(side)
        assert q.shape == (8, 7) and q.dtype == np.float64
        predicted = planned.predicted[side]
        if predicted is not None:
            assert predicted["point_sigma_mm"] > 0
    assert planned.summary.startswith("left arm: 8 configurations chosen from 80 candidates")
    files = planned.files()
    assert {"left.csv", "right.csv", "dataset.toml", "plan_left.mod"} <= set(files)
    planned.save(tmp_path / "plan")
    assert (tmp_path / "plan" / "left.csv").read_text() == files["left.csv"]
    again = dualcal.plan((2000.0, 0.0, 800.0), 8, candidates=80)
    np.testing.assert_array_equal(again.configurations("left"), planned.configurations("left"))
    with pytest.raises(dualcal.DualcalError, match="at least 2"):
        dualcal.plan((2000.0, 0.0, 800.0), 1)


def test_compensate(tmp_path):
    result = dualcal.calibrate(dualcal.Dataset.load(EXAMPLE), max_iterations=5)
    q = np.radians(np.array([r[1] for r in rows("left")][:4]))
    out = result.compensate("left", q)
    assert out["joints"].shape == (4, 7) and out["joints"].dtype == np.float64
    assert out["ok"].all() and out["reasons"] == [None] * 4
    assert (out["residual_mm"] < 1e-3).all()
    assert not np.allclose(out["joints"], q)
    targets = tmp_path / "targets.csv"
    targets.write_text(
        "id,q1,q2,q3,q4,q5,q6,q7\n"
        + "".join(f"T{k},{','.join(repr(float(v)) for v in np.degrees(row))}\n" for k, row in enumerate(q))
    )
    table = result.compensate_file("left", targets)
    assert table.splitlines()[0].startswith("id,q1,")
    assert all(line.endswith(",ok") for line in table.splitlines()[1:])
    with pytest.raises(dualcal.DualcalError, match="controller_base `robot`"):
        result.compensate("left", q, controller_base="robot")


def test_the_stubs_name_the_new_methods():
    stub = (pathlib.Path(dualcal.__file__).parent / "_dualcal.pyi").read_text()
    for cls in (dualcal._dualcal.ImportResult, dualcal.PlanResult, dualcal.CalibrationResult):
        for name in dir(cls):
            if not name.startswith("_"):
                assert f"def {name}(" in stub, f"{cls.__name__}.{name} is not in _dualcal.pyi"
    for name in ("import_files", "plan"):
        assert f"def {name}(" in stub
