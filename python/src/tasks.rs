//! The front door's other tasks for Python: importing tracker files ([`dualcal::Import`]), planning
//! a measurement ([`dualcal::Plan`]) and compensating joint targets
//! ([`dualcal::Calibrated::compensate`]).

use super::{PyDataset, PyRobot, err, side_of, to_python};
use dualcal::controller::compensate::{CompensationSettings, ControllerBase, Target};
use dualcal::dataset::{AngleUnit, LengthUnit};
use dualcal::import::{ColumnMap, PointUnit};
use dualcal::side::Side;
use numpy::{PyArray1, PyArray2, PyReadonlyArray2};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::collections::HashMap;
use std::path::PathBuf;

/// The engine's value spelled `name` (its `Choice` table, as the command line reads it).
fn choice<T: dualcal::choice::Choice>(what: &str, name: &str) -> PyResult<T> {
    T::parse_choice(name).map_err(|e| {
        err(format!(
            "{what} `{name}`: expected one of {}",
            e.known.join(", ")
        ))
    })
}

/// `name`, one of `known` (by their names), else an error naming the option.
fn one_of<T: Copy>(what: &str, name: &str, known: &[(&str, T)]) -> PyResult<T> {
    known
        .iter()
        .find(|(n, _)| *n == name)
        .map(|(_, v)| *v)
        .ok_or_else(|| {
            let names: Vec<&str> = known.iter().map(|(n, _)| *n).collect();
            err(format!(
                "{what} `{name}`: expected one of {}",
                names.join(", ")
            ))
        })
}

fn angle_unit(name: &str) -> PyResult<AngleUnit> {
    AngleUnit::parse(name).ok_or_else(|| err(format!("angle unit `{name}`: expected deg or rad")))
}

fn length_unit(name: &str) -> PyResult<LengthUnit> {
    LengthUnit::parse(name).ok_or_else(|| err(format!("length unit `{name}`: expected mm or m")))
}

/// The options of [`import_files`] besides the robot and the files (keyword arguments).
#[derive(Default)]
pub struct ImportArgs {
    matching: Option<String>,
    points_format: Option<String>,
    length_unit: Option<String>,
    angle_unit: Option<String>,
    joint_length_unit: Option<String>,
    columns: Option<String>,
    joint_order: Option<String>,
    decimal_comma: bool,
    time_tolerance_s: Option<f64>,
    verify_last: Option<usize>,
    measured_together: bool,
    reflectors: Option<Vec<(String, [f64; 3])>>,
}

/// The result of [`import_files`]: the dataset and the report.
#[pyclass(module = "dualcal._dualcal", name = "ImportResult", frozen)]
pub struct PyImported {
    inner: dualcal::ImportedDataset,
}

#[pymethods]
impl PyImported {
    #[getter]
    fn dataset(&self) -> PyDataset {
        PyDataset {
            inner: self.inner.dataset().clone(),
            path: None,
        }
    }

    #[getter]
    fn report(&self) -> String {
        self.inner.report_text()
    }

    #[pyo3(signature = (path, overwrite=false))]
    fn save(&self, py: Python<'_>, path: PathBuf, overwrite: bool) -> PyResult<()> {
        py.detach(|| self.inner.save(&path, overwrite)).map_err(err)
    }

    fn __repr__(&self) -> String {
        let ds = self.inner.dataset();
        format!(
            "ImportResult(left={}, right={})",
            ds.configuration_count(Side::Left),
            ds.configuration_count(Side::Right)
        )
    }
}

/// The import of tracker point files and joint logs (`dualcal import`).
#[pyfunction]
#[allow(clippy::too_many_arguments)]
#[pyo3(signature = (robot=None, left_points=None, left_joints=None, right_points=None,
    right_joints=None, *, matching=None, points_format=None, length_unit=None, angle_unit=None,
    joint_length_unit=None, columns=None, joint_order=None, decimal_comma=false,
    time_tolerance_s=None, verify_last=None, measured_together=false, reflectors=None))]
pub fn import_files(
    py: Python<'_>,
    robot: Option<&PyRobot>,
    left_points: Option<PathBuf>,
    left_joints: Option<PathBuf>,
    right_points: Option<PathBuf>,
    right_joints: Option<PathBuf>,
    matching: Option<String>,
    points_format: Option<String>,
    length_unit: Option<String>,
    angle_unit: Option<String>,
    joint_length_unit: Option<String>,
    columns: Option<String>,
    joint_order: Option<String>,
    decimal_comma: bool,
    time_tolerance_s: Option<f64>,
    verify_last: Option<usize>,
    measured_together: bool,
    reflectors: Option<Vec<(String, [f64; 3])>>,
) -> PyResult<PyImported> {
    let options = ImportArgs {
        matching,
        points_format,
        length_unit,
        angle_unit,
        joint_length_unit,
        columns,
        joint_order,
        decimal_comma,
        time_tolerance_s,
        verify_last,
        measured_together,
        reflectors,
    };
    let files = [
        (Side::Left, left_points, left_joints),
        (Side::Right, right_points, right_joints),
    ];
    let import = import_of(robot, files, options)?;
    let inner = py.detach(|| import.run()).map_err(err)?;
    Ok(PyImported { inner })
}

/// The import [`import_files`] runs.
fn import_of(
    robot: Option<&PyRobot>,
    files: [(Side, Option<PathBuf>, Option<PathBuf>); 2],
    options: ImportArgs,
) -> PyResult<dualcal::Import> {
    let robot = robot.map_or_else(dualcal::Robot::builtin_irb14000, |r| r.inner.clone());
    let mut import = dualcal::Import::new(&robot);
    for (side, points, joints) in files {
        match (points, joints) {
            (Some(points), joints) => import = import.arm(side, points, joints),
            (None, Some(_)) => {
                return Err(err(format!(
                    "{side}_joints without {side}_points: give the {side} arm's point file"
                )));
            }
            (None, None) => {}
        }
    }
    if let Some(m) = &options.matching {
        import = import.matching(choice("match", m)?);
    }
    if let Some(f) = &options.points_format {
        import = import.points_format(choice("points_format", f)?);
    }
    if let Some(u) = &options.length_unit {
        import = import.length_unit(
            PointUnit::parse(u)
                .ok_or_else(|| err(format!("length_unit `{u}`: expected mm, m, um, in or ft")))?,
        );
    }
    if let Some(u) = &options.angle_unit {
        import = import.angle_unit(angle_unit(u)?);
    }
    if let Some(u) = &options.joint_length_unit {
        import = import.joint_length_unit(length_unit(u)?);
    }
    if let Some(n) = options.verify_last {
        import = import.verify_last(n);
    }
    if let Some(r) = options.reflectors {
        import = import.reflectors(r);
    }
    let columns = options
        .columns
        .as_deref()
        .map(ColumnMap::parse)
        .transpose()
        .map_err(|e| err(format!("columns: {e}")))?;
    let joint_order = options
        .joint_order
        .as_deref()
        .map(dualcal::import::parse_joint_order)
        .transpose()
        .map_err(|e| err(format!("joint_order: {e}")))?;
    import = import.options(|o| {
        o.columns = columns;
        o.joint_order = joint_order;
        o.decimal_comma = options.decimal_comma;
        o.measured_together = options.measured_together;
        if let Some(t) = options.time_tolerance_s {
            o.time_tolerance_s = t;
        }
    });
    Ok(import)
}

/// A planned measurement.
#[pyclass(module = "dualcal._dualcal", name = "PlanResult", frozen)]
pub struct PyPlanned {
    inner: dualcal::Planned,
}

#[pymethods]
impl PyPlanned {
    /// The configurations of `side` in visiting order, `(n, J)` float64 (rad; mm for prismatic).
    fn configurations<'py>(
        &self,
        py: Python<'py>,
        side: &str,
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        PyArray2::from_vec2(py, self.inner.configurations(side_of(side)?)).map_err(err)
    }

    #[getter]
    fn predicted<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let out = PyDict::new(py);
        for side in Side::BOTH {
            let Some(p) = self.inner.predicted(side) else {
                out.set_item(side.name(), py.None())?;
                continue;
            };
            let d = PyDict::new(py);
            d.set_item("point_sigma_mm", p.point_sigma_mm)?;
            d.set_item("verification_ratio", p.verification_ratio)?;
            d.set_item("uncertainty", to_python(py, &p.uncertainty)?)?;
            out.set_item(side.name(), d)?;
        }
        Ok(out)
    }

    #[getter]
    fn summary(&self) -> String {
        self.inner.summary()
    }

    fn files(&self) -> HashMap<String, String> {
        self.inner.files().into_iter().collect()
    }

    #[pyo3(signature = (path, overwrite=false))]
    fn save(&self, py: Python<'_>, path: PathBuf, overwrite: bool) -> PyResult<()> {
        py.detach(|| self.inner.save(&path, overwrite)).map_err(err)
    }

    fn __repr__(&self) -> String {
        format!(
            "PlanResult(left={}, right={})",
            self.inner.configurations(Side::Left).len(),
            self.inner.configurations(Side::Right).len()
        )
    }
}

/// A measurement planned for a tracker at `tracker_mm` (`dualcal plan`).
#[pyfunction]
#[allow(clippy::too_many_arguments)]
#[pyo3(signature = (robot, tracker_mm, n=20, *, candidates=600, seed=1, max_incidence_deg=60.0,
    keep_out=Vec::new(), extend=None))]
pub fn plan(
    py: Python<'_>,
    robot: Option<&PyRobot>,
    tracker_mm: [f64; 3],
    n: usize,
    candidates: usize,
    seed: u64,
    max_incidence_deg: f64,
    keep_out: Vec<([f64; 3], [f64; 3])>,
    extend: Option<&PyDataset>,
) -> PyResult<PyPlanned> {
    if !(max_incidence_deg > 0.0 && max_incidence_deg <= 90.0) {
        return Err(err("max_incidence_deg: expected an angle in (0, 90]"));
    }
    let robot = robot.map_or_else(dualcal::Robot::builtin_irb14000, |r| r.inner.clone());
    let mut plan = dualcal::Plan::new(&robot, tracker_mm)
        .configurations(n)
        .candidates(candidates)
        .seed(seed)
        .max_incidence_deg(max_incidence_deg);
    for (lo, hi) in keep_out {
        plan = plan.keep_out(lo, hi);
    }
    if let Some(ds) = extend {
        plan = plan.extend(&ds.inner);
    }
    let inner = py.detach(|| plan.run()).map_err(err)?;
    Ok(PyPlanned { inner })
}

fn controller_base(name: &str) -> PyResult<ControllerBase> {
    one_of(
        "controller_base",
        name,
        &[
            ("nominal", ControllerBase::Nominal),
            ("calibrated", ControllerBase::Calibrated),
        ],
    )
}

/// [`dualcal::Calibrated::compensate`] of nominal joint targets `(n, J)`: `{"joints": (n, J)
/// (NaN rows where refused), "ok": (n,) bool, "residual_mm": (n,), "largest_change": (n,),
/// "reasons": [str | None]}`.
pub fn compensate<'py>(
    py: Python<'py>,
    result: &dualcal::Calibrated,
    side: &str,
    joints: PyReadonlyArray2<'_, f64>,
    base: &str,
) -> PyResult<Bound<'py, PyDict>> {
    let side = side_of(side)?;
    let settings = CompensationSettings {
        controller_base: controller_base(base)?,
        ..CompensationSettings::default()
    };
    let joints = joints.as_array();
    let targets: Vec<Target> = joints
        .rows()
        .into_iter()
        .map(|r| Target::Joints(r.to_vec()))
        .collect();
    let width = joints.shape()[1];
    let results = py.detach(|| result.compensate(side, &targets, &settings));
    let out = PyDict::new(py);
    let rows: Vec<Vec<f64>> = results
        .iter()
        .map(|r| r.as_ref().map_or(vec![f64::NAN; width], |c| c.q.clone()))
        .collect();
    out.set_item("joints", PyArray2::from_vec2(py, &rows).map_err(err)?)?;
    let field = |f: fn(&dualcal::controller::compensate::Compensated) -> f64| {
        results
            .iter()
            .map(|r| r.as_ref().map_or(f64::NAN, f))
            .collect::<Vec<f64>>()
    };
    out.set_item(
        "ok",
        PyArray1::from_vec(py, results.iter().map(Result::is_ok).collect()),
    )?;
    out.set_item(
        "residual_mm",
        PyArray1::from_vec(py, field(|c| c.residual_mm)),
    )?;
    out.set_item(
        "largest_change",
        PyArray1::from_vec(py, field(|c| c.largest_change)),
    )?;
    let reasons: Vec<Option<String>> = results
        .iter()
        .map(|r| r.as_ref().err().map(ToString::to_string))
        .collect();
    out.set_item("reasons", reasons)?;
    Ok(out)
}

/// [`dualcal::Calibrated::compensate_file`]: the table `dualcal compensate` writes.
pub fn compensate_file(
    py: Python<'_>,
    result: &dualcal::Calibrated,
    side: &str,
    path: PathBuf,
    units: (&str, &str),
    base: &str,
) -> PyResult<String> {
    let side = side_of(side)?;
    let settings = CompensationSettings {
        controller_base: controller_base(base)?,
        ..CompensationSettings::default()
    };
    let units = dualcal::controller::targets::TargetUnits {
        angle: angle_unit(units.0)?,
        length: length_unit(units.1)?,
    };
    py.detach(|| result.compensate_file(side, &path, units, &settings))
        .map_err(err)
}
