//! The native module of `import dualcal` (`dualcal._dualcal`): the crate's front door
//! ([`dualcal::Dataset`], [`dualcal::Robot`], [`dualcal::Calibration`]) for Python, with numpy arrays
//! in and out. The package's `__init__.py` re-exports it with the keyword defaults and docs.

use dualcal::kinematics::ArmLinks;
use dualcal::side::Side;
use numpy::{PyArray1, PyArray2, PyReadonlyArray2, PyReadonlyArray3};
use pyo3::create_exception;
use pyo3::exceptions::PyException;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use std::path::PathBuf;

mod tasks;

create_exception!(
    _dualcal,
    DualcalError,
    PyException,
    "A dualcal error: the engine's message, naming the file, line and field where an input was at fault."
);

fn err(e: impl std::fmt::Display) -> PyErr {
    DualcalError::new_err(e.to_string())
}

fn side_of(name: &str) -> PyResult<Side> {
    match name {
        "left" => Ok(Side::Left),
        "right" => Ok(Side::Right),
        other => Err(err(format!("side `{other}`: expected `left` or `right`"))),
    }
}

/// A JSON-serialisable value as the Python object `json.loads` makes of it.
fn to_python<'py>(py: Python<'py>, value: &impl serde::Serialize) -> PyResult<Bound<'py, PyAny>> {
    let text = serde_json::to_string(value).map_err(err)?;
    py.import("json")?.call_method1("loads", (text,))
}

/// A robot description: the built-in ABB IRB 14000, a URDF (file or text) or a `dualcal-dh/1` table.
#[pyclass(module = "dualcal._dualcal", name = "Robot", frozen)]
struct PyRobot {
    inner: dualcal::Robot,
}

#[pymethods]
impl PyRobot {
    #[staticmethod]
    fn builtin() -> Self {
        Self {
            inner: dualcal::Robot::builtin_irb14000(),
        }
    }

    #[staticmethod]
    fn from_file(py: Python<'_>, path: PathBuf) -> PyResult<Self> {
        let inner = py
            .detach(|| dualcal::Robot::from_file(&path))
            .map_err(err)?;
        Ok(Self { inner })
    }

    #[staticmethod]
    #[pyo3(signature = (text, path=None))]
    fn from_urdf_string(text: &str, path: Option<PathBuf>) -> PyResult<Self> {
        let inner = dualcal::Robot::from_urdf_str(text, path.as_deref()).map_err(err)?;
        Ok(Self { inner })
    }

    fn with_arms(
        &self,
        left_base: &str,
        left_tip: &str,
        right_base: &str,
        right_tip: &str,
    ) -> PyResult<Self> {
        let inner = self
            .inner
            .with_arms(
                ArmLinks::new(left_base, left_tip),
                ArmLinks::new(right_base, right_tip),
            )
            .map_err(err)?;
        Ok(Self { inner })
    }

    #[getter]
    fn name(&self) -> String {
        self.inner.name()
    }

    fn joint_names(&self, side: &str) -> PyResult<Vec<String>> {
        Ok(self.inner.joint_names(side_of(side)?))
    }

    #[getter]
    fn warnings(&self) -> Vec<String> {
        self.inner.warnings().to_vec()
    }

    fn __repr__(&self) -> String {
        format!("Robot({:?})", self.inner.name())
    }
}

/// Measurements with the robot they were taken on, loaded and checked.
#[pyclass(module = "dualcal._dualcal", name = "Dataset", frozen)]
struct PyDataset {
    inner: dualcal::Dataset,
    /// The directory it was loaded from (`None`: arrays).
    path: Option<PathBuf>,
}

/// One arm's arrays from numpy: joints (n, J), points (n, K, 3), splits and ids.
fn arm_arrays(
    joints: Option<PyReadonlyArray2<'_, f64>>,
    points: Option<PyReadonlyArray3<'_, f64>>,
    split: Option<Vec<String>>,
    ids: Option<Vec<String>>,
    side: &str,
) -> PyResult<Option<dualcal::ArmArrays>> {
    let (joints, points) = match (joints, points) {
        (None, None) => return Ok(None),
        (Some(j), Some(p)) => (j, p),
        _ => {
            return Err(err(format!(
                "the {side} arm: give both its joints (n, J) and its points (n, K, 3), or neither"
            )));
        }
    };
    let joints = joints.as_array();
    let points = points.as_array();
    if points.shape()[2] != 3 {
        return Err(err(format!(
            "the {side} arm's points have shape {:?}: expected (n, K, 3), mm",
            points.shape()
        )));
    }
    let split = split
        .unwrap_or_default()
        .iter()
        .map(|s| match s.as_str() {
            "cal" => Ok(dualcal::Split::Cal),
            "ver" => Ok(dualcal::Split::Ver),
            other => Err(err(format!(
                "the {side} arm's split `{other}`: expected `cal` or `ver`"
            ))),
        })
        .collect::<PyResult<Vec<_>>>()?;
    Ok(Some(dualcal::ArmArrays {
        joints: joints.rows().into_iter().map(|r| r.to_vec()).collect(),
        points_mm: points
            .outer_iter()
            .map(|config| config.outer_iter().map(|p| [p[0], p[1], p[2]]).collect())
            .collect(),
        split,
        ids: ids.unwrap_or_default(),
    }))
}

#[pymethods]
impl PyDataset {
    #[staticmethod]
    #[pyo3(signature = (path, robot=None))]
    fn load(py: Python<'_>, path: PathBuf, robot: Option<&PyRobot>) -> PyResult<Self> {
        let inner = py
            .detach(|| match robot {
                Some(robot) => dualcal::Dataset::load_with_robot(&path, &robot.inner),
                None => dualcal::Dataset::load(&path),
            })
            .map_err(err)?;
        Ok(Self {
            inner,
            path: Some(path),
        })
    }

    #[staticmethod]
    #[allow(clippy::too_many_arguments)]
    #[pyo3(signature = (robot, reflector_names, nominal_reflectors_mm, left_joints=None,
        left_points_mm=None, left_split=None, left_ids=None, right_joints=None,
        right_points_mm=None, right_split=None, right_ids=None, measured_together=false))]
    fn from_arrays(
        py: Python<'_>,
        robot: &PyRobot,
        reflector_names: Vec<String>,
        nominal_reflectors_mm: PyReadonlyArray2<'_, f64>,
        left_joints: Option<PyReadonlyArray2<'_, f64>>,
        left_points_mm: Option<PyReadonlyArray3<'_, f64>>,
        left_split: Option<Vec<String>>,
        left_ids: Option<Vec<String>>,
        right_joints: Option<PyReadonlyArray2<'_, f64>>,
        right_points_mm: Option<PyReadonlyArray3<'_, f64>>,
        right_split: Option<Vec<String>>,
        right_ids: Option<Vec<String>>,
        measured_together: bool,
    ) -> PyResult<Self> {
        let nominal = nominal_reflectors_mm.as_array();
        if nominal.shape()[1] != 3 {
            return Err(err(format!(
                "nominal_reflectors_mm has shape {:?}: expected (K, 3), mm",
                nominal.shape()
            )));
        }
        let arrays = dualcal::Arrays {
            reflector_names,
            nominal_reflectors_mm: nominal
                .rows()
                .into_iter()
                .map(|r| [r[0], r[1], r[2]])
                .collect(),
            left: arm_arrays(left_joints, left_points_mm, left_split, left_ids, "left")?,
            right: arm_arrays(
                right_joints,
                right_points_mm,
                right_split,
                right_ids,
                "right",
            )?,
            tracker: Default::default(),
            measured_together,
        };
        let inner = py
            .detach(|| dualcal::Dataset::from_arrays(&robot.inner, arrays))
            .map_err(err)?;
        Ok(Self { inner, path: None })
    }

    fn configuration_count(&self, side: &str) -> PyResult<usize> {
        Ok(self.inner.configuration_count(side_of(side)?))
    }

    #[getter]
    fn reflector_names(&self) -> Vec<String> {
        self.inner.reflector_names().to_vec()
    }

    #[getter]
    fn warnings(&self) -> Vec<String> {
        self.inner.warnings()
    }

    #[getter]
    fn robot_name(&self) -> String {
        self.inner.robot().name()
    }

    fn __repr__(&self) -> String {
        format!(
            "Dataset(left={}, right={}, reflectors={:?})",
            self.inner.configuration_count(Side::Left),
            self.inner.configuration_count(Side::Right),
            self.inner.reflector_names()
        )
    }
}

/// A calibration's result.
#[pyclass(module = "dualcal._dualcal", name = "CalibrationResult", frozen)]
struct PyCalibrated {
    inner: dualcal::Calibrated,
}

/// Per-configuration errors of one model as numpy arrays, one dict per arm.
fn configuration_errors<'py>(
    py: Python<'py>,
    rows: &[dualcal::analysis::ConfigRow],
) -> PyResult<Bound<'py, PyDict>> {
    let out = PyDict::new(py);
    for side in Side::BOTH {
        let rows: Vec<&dualcal::analysis::ConfigRow> =
            rows.iter().filter(|r| r.config.side == side).collect();
        if rows.is_empty() {
            continue;
        }
        let arm = PyDict::new(py);
        arm.set_item("ids", rows.iter().map(|r| r.id.clone()).collect::<Vec<_>>())?;
        arm.set_item(
            "split",
            rows.iter().map(|r| r.split.name()).collect::<Vec<_>>(),
        )?;
        arm.set_item(
            "worst_position_mm",
            PyArray1::from_vec(py, rows.iter().map(|r| r.worst_pos_mm).collect()),
        )?;
        arm.set_item(
            "worst_orientation_rad",
            PyArray1::from_vec(
                py,
                rows.iter()
                    .map(|r| r.worst_ori_rad.unwrap_or(f64::NAN))
                    .collect(),
            ),
        )?;
        let points: Vec<Vec<f64>> = rows.iter().map(|r| r.point_errors_mm()).collect();
        arm.set_item(
            "point_errors_mm",
            PyArray2::from_vec2(py, &points).map_err(err)?,
        )?;
        arm.set_item(
            "excluded",
            PyArray1::from_vec(py, rows.iter().map(|r| r.excluded).collect()),
        )?;
        out.set_item(side.name(), arm)?;
    }
    Ok(out)
}

#[pymethods]
impl PyCalibrated {
    #[getter]
    fn converged(&self) -> bool {
        self.inner.is_converged()
    }

    #[getter]
    fn method(&self) -> (&'static str, &'static str) {
        let s = self.inner.settings();
        (s.method.name(), s.base_method.name())
    }

    #[getter]
    fn stages<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyList>> {
        let list = PyList::empty(py);
        for s in self.inner.stages() {
            let d = PyDict::new(py);
            d.set_item("stage", s.stage.to_string())?;
            d.set_item("iterations", s.iterations)?;
            d.set_item("termination", s.termination.to_string())?;
            d.set_item("converged", s.termination.is_converged())?;
            d.set_item("psi_start_mm2", s.psi_start_mm2)?;
            d.set_item("psi_mm2", s.psi_mm2)?;
            list.append(d)?;
        }
        Ok(list)
    }

    /// `{"left": {name: value}, "right": {...}, "left_base_from_right_base": (4, 4) array, mm}`.
    #[getter]
    fn params<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        self.parameters(py, |p| Some(p.calibrated))
    }

    /// The nominal values, keyed like `params`.
    #[getter]
    fn nominal_params<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        self.parameters(py, |p| Some(p.nominal))
    }

    /// `{"left": {name: 1σ}, "right": {...}}` of the identified parameters.
    #[getter]
    fn sigma<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let out = self.parameters(py, |p| p.sigma)?;
        out.del_item("left_base_from_right_base")?;
        Ok(out)
    }

    /// `{"left": {name: unit}, "right": {...}}`.
    #[getter]
    fn units<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let out = PyDict::new(py);
        for side in Side::BOTH {
            let arm = PyDict::new(py);
            for p in self.inner.parameters(side) {
                arm.set_item(p.name, p.unit)?;
            }
            out.set_item(side.name(), arm)?;
        }
        Ok(out)
    }

    /// The names of the parameters each arm's calibration identified.
    #[getter]
    fn identified<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let out = PyDict::new(py);
        for side in Side::BOTH {
            let names: Vec<String> = self
                .inner
                .parameters(side)
                .into_iter()
                .filter(|p| p.identified)
                .map(|p| p.name)
                .collect();
            out.set_item(side.name(), names)?;
        }
        Ok(out)
    }

    /// Each arm's uncertainty as the parameter file records it (σ, correlations, condition).
    #[getter]
    fn uncertainty<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let out = PyDict::new(py);
        for side in Side::BOTH {
            match self.inner.uncertainty(side) {
                Some(u) => out.set_item(side.name(), to_python(py, u)?)?,
                None => out.set_item(side.name(), py.None())?,
            }
        }
        Ok(out)
    }

    /// `{"calibration"|"verification": {"nominal": figures, "calibrated": figures}}`, the paper's
    /// eqs. 5–8 (mm, rad) without the excluded configurations.
    #[getter]
    fn accuracy<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let accuracy = py.detach(|| self.inner.accuracy()).map_err(err)?;
        let out = PyDict::new(py);
        for (name, split) in [
            ("calibration", &accuracy.calibration),
            ("verification", &accuracy.verification),
        ] {
            let Some(split) = split else { continue };
            let d = PyDict::new(py);
            d.set_item("nominal", to_python(py, &split.nominal)?)?;
            d.set_item("calibrated", to_python(py, &split.calibrated)?)?;
            out.set_item(name, d)?;
        }
        Ok(out)
    }

    /// Per configuration under the calibrated model: `{"left": {"ids", "split",
    /// "worst_position_mm" (n,), "worst_orientation_rad" (n,), "point_errors_mm" (n, K),
    /// "excluded" (n,)}, "right": …}`.
    #[getter]
    fn errors<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let rows = py.detach(|| self.inner.configurations()).map_err(err)?;
        configuration_errors(py, &rows)
    }

    /// [`errors`] under the nominal model.
    #[getter]
    fn nominal_errors<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let rows = py
            .detach(|| self.inner.nominal_configurations())
            .map_err(err)?;
        configuration_errors(py, &rows)
    }

    /// The per-pair samples of the paper's histograms (Figs. 6–8) on `split` (`"cal"` or `"ver"`)
    /// under the calibrated model, or with `model="nominal"` the nominal one: `{"left_position_mm",
    /// "right_position_mm", "collaborative_position_mm", "left_orientation_rad", …}`, float64 (n_pairs,).
    #[pyo3(signature = (split="ver", model="calibrated"))]
    fn pair_errors<'py>(
        &self,
        py: Python<'py>,
        split: &str,
        model: &str,
    ) -> PyResult<Bound<'py, PyDict>> {
        let split = match split {
            "cal" => dualcal::Split::Cal,
            "ver" => dualcal::Split::Ver,
            other => return Err(err(format!("split `{other}`: expected `cal` or `ver`"))),
        };
        let nominal = match model {
            "calibrated" => false,
            "nominal" => true,
            other => {
                return Err(err(format!(
                    "model `{other}`: expected `calibrated` or `nominal`"
                )));
            }
        };
        let samples = py
            .detach(|| self.inner.pair_samples(split, nominal))
            .map_err(err)?;
        let out = PyDict::new(py);
        for (indicator, values) in samples {
            use dualcal::analysis::Indicator;
            let key = match indicator {
                Indicator::RelativePosition(s) => format!("{}_position_mm", s.name()),
                Indicator::RelativeOrientation(s) => format!("{}_orientation_rad", s.name()),
                Indicator::CollaborativePosition => "collaborative_position_mm".into(),
                Indicator::CollaborativeOrientation => "collaborative_orientation_rad".into(),
            };
            let values: Vec<f64> = values.into_iter().map(f64::from).collect();
            out.set_item(key, PyArray1::from_vec(py, values))?;
        }
        Ok(out)
    }

    #[getter]
    fn warnings(&self) -> Vec<String> {
        self.inner.warnings()
    }

    fn params_json(&self) -> String {
        self.inner.params_json()
    }

    fn save(&self, path: PathBuf) -> PyResult<()> {
        self.inner.save_params(path).map_err(err)
    }

    fn to_urdf(&self) -> PyResult<String> {
        self.inner.urdf().map_err(err)
    }

    fn save_urdf(&self, path: PathBuf) -> PyResult<()> {
        self.inner.save_urdf(path).map_err(err)
    }

    #[pyo3(signature = (json=false))]
    fn overlay(&self, json: bool) -> PyResult<String> {
        self.inner.overlay(json).map_err(err)
    }

    fn abb_base_frames(&self) -> String {
        self.inner.abb_base_frames()
    }

    /// Nominal joint targets `(n, J)` of `side` compensated for the calibrated robot.
    #[pyo3(signature = (side, joints, controller_base="nominal"))]
    fn compensate<'py>(
        &self,
        py: Python<'py>,
        side: &str,
        joints: numpy::PyReadonlyArray2<'_, f64>,
        controller_base: &str,
    ) -> PyResult<Bound<'py, PyDict>> {
        tasks::compensate(py, &self.inner, side, joints, controller_base)
    }

    /// A target list file of `side` compensated: the table `dualcal compensate` writes.
    #[pyo3(signature = (side, path, angle_unit="deg", length_unit="mm", controller_base="nominal"))]
    fn compensate_file(
        &self,
        py: Python<'_>,
        side: &str,
        path: PathBuf,
        angle_unit: &str,
        length_unit: &str,
        controller_base: &str,
    ) -> PyResult<String> {
        tasks::compensate_file(
            py,
            &self.inner,
            side,
            path,
            (angle_unit, length_unit),
            controller_base,
        )
    }

    fn __repr__(&self) -> String {
        let (m, b) = self.method();
        format!(
            "CalibrationResult(method={m:?}, base_method={b:?}, converged={})",
            self.inner.is_converged()
        )
    }
}

impl PyCalibrated {
    fn parameters<'py>(
        &self,
        py: Python<'py>,
        value: impl Fn(&dualcal::Parameter) -> Option<f64>,
    ) -> PyResult<Bound<'py, PyDict>> {
        let out = PyDict::new(py);
        for side in Side::BOTH {
            let arm = PyDict::new(py);
            for p in self.inner.parameters(side) {
                if let Some(v) = value(&p) {
                    arm.set_item(p.name, v)?;
                }
            }
            out.set_item(side.name(), arm)?;
        }
        let m = self.inner.left_base_from_right_base().to_homogeneous();
        let rows: Vec<Vec<f64>> = (0..4)
            .map(|i| (0..4).map(|j| m[(i, j)]).collect())
            .collect();
        out.set_item(
            "left_base_from_right_base",
            PyArray2::from_vec2(py, &rows).map_err(err)?,
        )?;
        Ok(out)
    }
}

#[pyfunction]
#[allow(clippy::too_many_arguments)]
#[pyo3(signature = (dataset, robot=None, method=None, base_method="minimax", model="geometric",
    split="cal", exclude=Vec::new(), max_iterations=None, keep_weak=false))]
fn calibrate(
    py: Python<'_>,
    dataset: &PyDataset,
    robot: Option<&PyRobot>,
    method: Option<&str>,
    base_method: &str,
    model: &str,
    split: &str,
    exclude: Vec<String>,
    max_iterations: Option<usize>,
    keep_weak: bool,
) -> PyResult<PyCalibrated> {
    let method = method
        .map(|m| dualcal::Method::named(m).ok_or_else(|| err(unknown("method", m, method_names()))))
        .transpose()?;
    let base_method = dualcal::BaseMethod::named(base_method)
        .ok_or_else(|| err(unknown("base_method", base_method, base_method_names())))?;
    let model = dualcal::ErrorTerms::from_name(model).map_err(err)?;
    let split = match split {
        "cal" => dualcal::Split::Cal,
        "all" => dualcal::Split::All,
        other => return Err(err(format!("split `{other}`: expected `cal` or `all`"))),
    };
    let reloaded;
    let dataset = match (robot, &dataset.path) {
        (None, _) => &dataset.inner,
        (Some(robot), Some(path)) => {
            reloaded = py
                .detach(|| dualcal::Dataset::load_with_robot(path, &robot.inner))
                .map_err(err)?;
            &reloaded
        }
        (Some(_), None) => {
            return Err(err(
                "a dataset made from arrays has its robot already: give it to Dataset.from_arrays",
            ));
        }
    };
    let inner = py
        .detach(|| {
            let mut c = dualcal::Calibration::new(dataset)
                .base_method(base_method)
                .model(model)
                .split(split)
                .exclude(&exclude)
                .keep_weak(keep_weak);
            if let Some(method) = method {
                c = c.method(method);
            }
            if let Some(n) = max_iterations {
                c = c.max_iterations(n);
            }
            c.run()
        })
        .map_err(err)?;
    Ok(PyCalibrated { inner })
}

fn method_names() -> Vec<&'static str> {
    dualcal::Method::ALL.iter().map(|m| m.name()).collect()
}

fn base_method_names() -> Vec<&'static str> {
    dualcal::BaseMethod::ALL.iter().map(|m| m.name()).collect()
}

fn unknown(what: &str, given: &str, known: Vec<&str>) -> String {
    format!("{what} `{given}`: expected one of {}", known.join(", "))
}

/// The accuracy of a parameter file's model on a dataset: `{"calibration": figures,
/// "verification": figures}`.
#[pyfunction]
fn evaluate<'py>(
    py: Python<'py>,
    dataset: &PyDataset,
    params: PathBuf,
) -> PyResult<Bound<'py, PyDict>> {
    let figures = py
        .detach(|| dualcal::evaluate(&dataset.inner, &params))
        .map_err(err)?;
    let out = PyDict::new(py);
    if let Some(r) = &figures.calibration {
        out.set_item("calibration", to_python(py, r)?)?;
    }
    if let Some(r) = &figures.verification {
        out.set_item("verification", to_python(py, r)?)?;
    }
    Ok(out)
}

#[pymodule]
fn _dualcal(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyRobot>()?;
    m.add_class::<PyDataset>()?;
    m.add_class::<PyCalibrated>()?;
    m.add_function(wrap_pyfunction!(calibrate, m)?)?;
    m.add_function(wrap_pyfunction!(evaluate, m)?)?;
    m.add_class::<tasks::PyImported>()?;
    m.add_class::<tasks::PyPlanned>()?;
    m.add_function(wrap_pyfunction!(tasks::import_files, m)?)?;
    m.add_function(wrap_pyfunction!(tasks::plan, m)?)?;
    m.add("DualcalError", m.py().get_type::<DualcalError>())?;
    m.add("METHODS", method_names())?;
    m.add("BASE_METHODS", base_method_names())?;
    Ok(())
}
