//! The `dualcal-params/1` parameter file (JSON): both arms' DH tables and reflectors and the right-arm
//! base in the left-arm base frame, plus optional method, fixed parameters, termination, statistics and
//! provenance. See `docs/formats.md`.
//!
//! [`ParamsFile`] mirrors the file one to one (so unknown extra fields survive a read/write round trip);
//! [`ParamsFile::to_model`] validates it and converts to the in-memory [`DualArmModel`] in mm and rad.

use crate::atomic::write_atomic;
use crate::dataset::{Dataset, Split};
use crate::kinematics::{ArmModel, DhRow, DualArmModel, N_JOINTS, N_PARAMS, param_name};
use crate::metrics::AccuracyReport;
use crate::side::{PerSide, Side};
use crate::solver::CalibrationResult;
use nalgebra::{Isometry3, Matrix3, Rotation3, Translation3, UnitQuaternion, Vector3};
use serde::{Deserialize, Serialize};
use serde_json::Value;
use std::path::{Path, PathBuf};

/// The format tag of a parameter file.
pub const PARAMS_FORMAT: &str = "dualcal-params/1";
/// Largest accepted deviation `max |RᵀR − I|` of the stored rotation before it is re-orthonormalised.
pub const ROTATION_TOLERANCE: f64 = 1e-6;

/// `path: ` or nothing for a file-less value.
fn prefix(path: &Option<PathBuf>) -> String {
    match path {
        Some(p) => format!("{}: ", p.display()),
        None => String::new(),
    }
}

#[derive(Debug, thiserror::Error)]
pub enum ParamsError {
    #[error("{path}: cannot read: {source}")]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("{path}: cannot write: {source}")]
    Write {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    /// Not UTF-8 text (UTF-16, binary data, bad bytes) or too large.
    #[error("{path}: {problem}")]
    Text {
        path: PathBuf,
        problem: crate::textfile::TextProblem,
    },
    /// Not valid JSON, or a field has the wrong type or is missing.
    #[error("{path}:{line}:{column}: {message}")]
    Json {
        path: PathBuf,
        line: usize,
        column: usize,
        message: String,
    },
    /// The `format` tag is missing or not `dualcal-params/1`.
    #[error("{path}: field `format`: {message}")]
    Format { path: PathBuf, message: String },
    /// A value is out of range (wrong number of DH rows, not finite, not a rotation, unknown unit, ...).
    #[error("{}field `{field}`: {message}", prefix(.path))]
    Invalid {
        /// The file, when the value came from one.
        path: Option<PathBuf>,
        field: String,
        message: String,
    },
}

impl ParamsError {
    /// Attach the file name to a validation error.
    fn in_file(self, file: &Path) -> Self {
        match self {
            ParamsError::Invalid {
                path: None,
                field,
                message,
            } => ParamsError::Invalid {
                path: Some(file.to_path_buf()),
                field,
                message,
            },
            other => other,
        }
    }
}

fn invalid(field: impl Into<String>, message: impl Into<String>) -> ParamsError {
    ParamsError::Invalid {
        path: None,
        field: field.into(),
        message: message.into(),
    }
}

/// Units of the file's lengths and angles (`mm`|`m`, `rad`|`deg`); written as mm and rad.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ParamsUnits {
    pub length: String,
    pub angle: String,
}

impl Default for ParamsUnits {
    fn default() -> Self {
        Self {
            length: "mm".into(),
            angle: "rad".into(),
        }
    }
}

/// One DH row: `a`, `d` in the length unit, `theta`, `alpha` in the angle unit.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DhEntry {
    pub a: f64,
    pub d: f64,
    pub theta: f64,
    pub alpha: f64,
}

/// Reflector coordinates in the flange frame (length unit).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ReflectorsEntry {
    pub a: [f64; 3],
    pub b: [f64; 3],
    pub c: [f64; 3],
}

/// One arm: 7 DH rows in chain order and the reflectors.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ArmParams {
    pub dh: Vec<DhEntry>,
    pub reflectors: ReflectorsEntry,
}

/// Both arms, under the keys `left` and `right`.
pub type ArmsParams = PerSide<ArmParams>;

/// The right-arm DH base frame in the left-arm DH base frame (`left_base_from_right_base`): a point
/// `p_right` maps to `rotation · p_right + translation`. `rotation` is row-major.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BaseTransform {
    pub translation: [f64; 3],
    pub rotation: [[f64; 3]; 3],
}

/// A parameter held at its value during identification, and why.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct FixedParameter {
    /// A name from [`crate::kinematics::param_name`], e.g. `theta1`, `t_a.x`.
    pub name: String,
    pub reason: String,
}

/// Fixed (not identified) parameters per arm.
#[derive(Clone, Debug, PartialEq, Eq, Default, Serialize, Deserialize)]
pub struct FixedParameters {
    #[serde(default)]
    pub left: Vec<FixedParameter>,
    #[serde(default)]
    pub right: Vec<FixedParameter>,
}

/// Where a parameter file came from.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Provenance {
    /// Program name, `dualcal`.
    pub tool: String,
    /// Program version.
    pub version: String,
    /// The dataset the parameters were identified from.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub dataset: Option<String>,
    /// UTC time of writing, `YYYY-MM-DDTHH:MM:SSZ`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub date_utc: Option<String>,
    /// Anything else a tool recorded.
    #[serde(flatten)]
    pub extra: serde_json::Map<String, Value>,
}

impl Provenance {
    /// This program, now, with an optional dataset path.
    pub fn now(dataset: Option<&Path>) -> Self {
        Self {
            tool: env!("CARGO_PKG_NAME").to_string(),
            version: env!("CARGO_PKG_VERSION").to_string(),
            dataset: dataset.map(|p| p.display().to_string()),
            date_utc: Some(utc_timestamp(std::time::SystemTime::now())),
            extra: Default::default(),
        }
    }
}

/// `YYYY-MM-DDTHH:MM:SSZ` of a system time (UTC, proleptic Gregorian calendar).
pub fn utc_timestamp(t: std::time::SystemTime) -> String {
    let secs: i64 = match t.duration_since(std::time::UNIX_EPOCH) {
        Ok(d) => i64::try_from(d.as_secs()).unwrap_or(i64::MAX / 2),
        Err(e) => -i64::try_from(e.duration().as_secs()).unwrap_or(i64::MAX / 2),
    };
    let days = secs.div_euclid(86_400);
    let sod = secs.rem_euclid(86_400);
    let (y, m, d) = civil_from_days(days);
    format!(
        "{y:04}-{m:02}-{d:02}T{:02}:{:02}:{:02}Z",
        sod / 3600,
        (sod / 60) % 60,
        sod % 60
    )
}

/// Calendar date of a day count since 1970-01-01 (the usual era-of-400-years computation, with March
/// as the first month of the computational year so that leap days fall at the end).
fn civil_from_days(days: i64) -> (i64, u32, u32) {
    let z = days + 719_468; // days since 0000-03-01
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097; // [0, 146096]
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365; // [0, 399]
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100); // [0, 365]
    let mp = (5 * doy + 2) / 153; // March = 0
    let d = (doy - (153 * mp + 2) / 5 + 1) as u32;
    let m = if mp < 10 { mp + 3 } else { mp - 9 } as u32;
    let y = yoe + era * 400 + i64::from(m <= 2);
    (y, m, d)
}

/// The whole parameter file. Required: `format`, `units`, `arms`, `right_base_in_left`; the rest is
/// optional and kept as written.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ParamsFile {
    pub format: String,
    pub units: ParamsUnits,
    pub arms: ArmsParams,
    pub right_base_in_left: BaseTransform,
    /// The identification method and its settings (free form, e.g. `"minimax"` or an object).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub method: Option<Value>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub fixed_parameters: Option<FixedParameters>,
    /// Why the solver stopped, iterations, final objective (free form).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub termination: Option<Value>,
    /// Accuracy figures and the like (free form).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub statistics: Option<Value>,
    /// `false` when the calibration that wrote the file did not converge (a stage hit the iteration
    /// limit, was cancelled or stalled; `termination` says which); absent otherwise.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub converged: Option<bool>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub provenance: Option<Provenance>,
    /// Suspect configurations and the ones left out (free form; dualcal writes a
    /// `quality::QualityRecord`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub quality: Option<Value>,
    /// Fields this version does not know; kept for round trips.
    #[serde(flatten)]
    pub extra: serde_json::Map<String, Value>,
}

fn arm_params(arm: &ArmModel) -> ArmParams {
    let t = |k: usize| {
        let v = arm.reflectors_mm[k];
        [v.x, v.y, v.z]
    };
    ArmParams {
        dh: arm
            .dh
            .iter()
            .map(|r| DhEntry {
                a: r.a_mm,
                d: r.d_mm,
                theta: r.theta_rad,
                alpha: r.alpha_rad,
            })
            .collect(),
        reflectors: ReflectorsEntry {
            a: t(0),
            b: t(1),
            c: t(2),
        },
    }
}

fn finite(field: &str, values: &[f64]) -> Result<(), ParamsError> {
    match values.iter().find(|x| !x.is_finite()) {
        Some(x) => Err(invalid(field, format!("{x} is not a finite number"))),
        None => Ok(()),
    }
}

/// Largest plausible |DH length| and |base translation|, mm (100 m).
pub const MAX_LENGTH_MM: f64 = 100_000.0;
/// Largest plausible |DH angle|, rad (a few turns; offsets are normally within ±π).
pub const MAX_ANGLE_RAD: f64 = 100.0;
/// Largest plausible distance of a reflector from the flange origin, mm.
pub const MAX_REFLECTOR_MM: f64 = 10_000.0;

/// Values (already in mm or rad) within ±`max`: an absurd magnitude is a unit or export error.
fn plausible(field: &str, values: &[f64], max: f64, unit: &str) -> Result<(), ParamsError> {
    match values.iter().find(|x| x.abs() > max) {
        Some(x) => Err(invalid(
            field,
            format!("{x:e} {unit} is not a plausible value (|value| ≤ {max} {unit}); wrong unit?"),
        )),
        None => Ok(()),
    }
}

fn arm_model(
    side: &str,
    arm: &ArmParams,
    mm_per_unit: f64,
    rad_per_unit: f64,
) -> Result<ArmModel, ParamsError> {
    if arm.dh.len() != N_JOINTS {
        return Err(invalid(
            format!("arms.{side}.dh"),
            format!(
                "{} rows; expected {N_JOINTS} (one per joint, chain order)",
                arm.dh.len()
            ),
        ));
    }
    let mut dh = [DhRow::new(0.0, 0.0, 0.0, 0.0); N_JOINTS];
    for (i, (row, e)) in dh.iter_mut().zip(&arm.dh).enumerate() {
        for (name, v) in [
            ("a", e.a),
            ("d", e.d),
            ("theta", e.theta),
            ("alpha", e.alpha),
        ] {
            finite(&format!("arms.{side}.dh[{i}].{name}"), &[v])?;
        }
        for (name, v, per_unit, max, unit) in [
            ("a", e.a, mm_per_unit, MAX_LENGTH_MM, "mm"),
            ("d", e.d, mm_per_unit, MAX_LENGTH_MM, "mm"),
            ("theta", e.theta, rad_per_unit, MAX_ANGLE_RAD, "rad"),
            ("alpha", e.alpha, rad_per_unit, MAX_ANGLE_RAD, "rad"),
        ] {
            plausible(
                &format!("arms.{side}.dh[{i}].{name}"),
                &[v * per_unit],
                max,
                unit,
            )?;
        }
        *row = DhRow::new(
            e.a * mm_per_unit,
            e.d * mm_per_unit,
            e.theta * rad_per_unit,
            e.alpha * rad_per_unit,
        );
    }
    let r = &arm.reflectors;
    let mut reflectors_mm = [Vector3::zeros(); 3];
    for (k, (name, v)) in [("a", r.a), ("b", r.b), ("c", r.c)].into_iter().enumerate() {
        finite(&format!("arms.{side}.reflectors.{name}"), &v)?;
        reflectors_mm[k] = Vector3::from(v) * mm_per_unit;
        plausible(
            &format!("arms.{side}.reflectors.{name}"),
            &[reflectors_mm[k].norm()],
            MAX_REFLECTOR_MM,
            "mm",
        )?;
    }
    Ok(ArmModel { dh, reflectors_mm })
}

/// The rotation closest to `m` (Frobenius norm) via the SVD, with the determinant forced to +1.
fn nearest_rotation(m: &Matrix3<f64>) -> Rotation3<f64> {
    let svd = m.svd(true, true);
    match (svd.u, svd.v_t) {
        (Some(u), Some(v_t)) => {
            let mut d = Matrix3::identity();
            if (u * v_t).determinant() < 0.0 {
                d[(2, 2)] = -1.0;
            }
            Rotation3::from_matrix_unchecked(u * d * v_t)
        }
        _ => Rotation3::from_matrix(m),
    }
}

impl ParamsFile {
    /// The file form of a model, in mm and rad, without the optional fields.
    pub fn from_model(model: &DualArmModel) -> ParamsFile {
        let iso = &model.left_base_from_right_base;
        let r = iso.rotation.to_rotation_matrix();
        let m = r.matrix();
        let t = iso.translation.vector;
        ParamsFile {
            format: PARAMS_FORMAT.to_string(),
            units: ParamsUnits::default(),
            arms: model.arms.as_ref().map(|_, arm| arm_params(arm)),
            right_base_in_left: BaseTransform {
                translation: [t.x, t.y, t.z],
                rotation: [0, 1, 2].map(|i| [m[(i, 0)], m[(i, 1)], m[(i, 2)]]),
            },
            method: None,
            fixed_parameters: None,
            termination: None,
            statistics: None,
            converged: None,
            provenance: None,
            quality: None,
            extra: Default::default(),
        }
    }

    /// Validate and convert to the in-memory model (mm, rad). Checks the format tag, the units
    /// (`mm`|`m`, `rad`|`deg`), 7 DH rows per arm, finite numbers, fixed-parameter names, and that the
    /// rotation is orthonormal with determinant +1 within [`ROTATION_TOLERANCE`]; the rotation is then
    /// re-orthonormalised.
    pub fn to_model(&self) -> Result<DualArmModel, ParamsError> {
        if self.format != PARAMS_FORMAT {
            return Err(invalid(
                "format",
                format!(
                    "unknown format tag \"{}\"; expected \"{PARAMS_FORMAT}\"",
                    crate::textfile::excerpt(&self.format)
                ),
            ));
        }
        let mm_per_unit = match self.units.length.as_str() {
            "mm" => 1.0,
            "m" => 1000.0,
            other => {
                return Err(invalid(
                    "units.length",
                    format!(
                        "unknown length unit \"{}\"; expected \"mm\" or \"m\"",
                        crate::textfile::excerpt(other)
                    ),
                ));
            }
        };
        let rad_per_unit = match self.units.angle.as_str() {
            "rad" => 1.0,
            "deg" => std::f64::consts::PI / 180.0,
            other => {
                return Err(invalid(
                    "units.angle",
                    format!(
                        "unknown angle unit \"{}\"; expected \"rad\" or \"deg\"",
                        crate::textfile::excerpt(other)
                    ),
                ));
            }
        };
        let arms = self
            .arms
            .as_ref()
            .try_map(|side, arm| arm_model(side.name(), arm, mm_per_unit, rad_per_unit))?;

        let b = &self.right_base_in_left;
        finite("right_base_in_left.translation", &b.translation)?;
        finite("right_base_in_left.rotation", b.rotation.as_flattened())?;
        let m = Matrix3::from_fn(|i, j| b.rotation[i][j]);
        let dev = (m.transpose() * m - Matrix3::identity()).abs().max();
        let det = m.determinant();
        if dev > ROTATION_TOLERANCE || det <= 0.0 {
            return Err(invalid(
                "right_base_in_left.rotation",
                format!(
                    "not a rotation matrix: max |RᵀR − I| = {dev:.3e} (tolerance {ROTATION_TOLERANCE:e}), det = {det:.6}"
                ),
            ));
        }
        let rotation = UnitQuaternion::from_rotation_matrix(&nearest_rotation(&m));
        let translation = Translation3::from(Vector3::from(b.translation) * mm_per_unit);
        plausible(
            "right_base_in_left.translation",
            translation.vector.as_slice(),
            MAX_LENGTH_MM,
            "mm",
        )?;

        if let Some(fixed) = &self.fixed_parameters {
            let names: Vec<String> = (0..N_PARAMS).map(param_name).collect();
            for (side, list) in [("left", &fixed.left), ("right", &fixed.right)] {
                for (i, f) in list.iter().enumerate() {
                    if !names.contains(&f.name) {
                        return Err(invalid(
                            format!("fixed_parameters.{side}[{i}].name"),
                            format!(
                                "unknown parameter `{}`; expected one of {} … {}",
                                crate::textfile::excerpt(&f.name),
                                names[0],
                                names[N_PARAMS - 1]
                            ),
                        ));
                    }
                }
            }
        }

        Ok(DualArmModel {
            arms,
            left_base_from_right_base: Isometry3::from_parts(translation, rotation),
        })
    }

    /// Parse a parameter file. JSON syntax and type errors carry the line and column.
    pub fn read(path: &Path) -> Result<ParamsFile, ParamsError> {
        use crate::textfile::ReadError;
        let text = crate::textfile::read(path).map_err(|e| match e {
            ReadError::Io(source) => ParamsError::Io {
                path: path.to_path_buf(),
                source,
            },
            ReadError::Text(problem) => ParamsError::Text {
                path: path.to_path_buf(),
                problem,
            },
        })?;
        Self::parse(path, text.as_bytes())
    }

    /// Parse parameter-file text; `path` is only used in messages.
    pub fn parse(path: &Path, bytes: &[u8]) -> Result<ParamsFile, ParamsError> {
        let json_err = |e: serde_json::Error| ParamsError::Json {
            path: path.to_path_buf(),
            line: e.line(),
            column: e.column(),
            message: {
                // serde_json appends " at line L column C"; the variant shows them already. Its
                // message may quote the input: keep it short.
                let s = e.to_string();
                let s = match s.rfind(" at line ") {
                    Some(i) => s[..i].to_string(),
                    None => s,
                };
                crate::textfile::excerpt_n(&s, 200)
            },
        };
        if bytes.iter().all(u8::is_ascii_whitespace) {
            return Err(ParamsError::Json {
                path: path.to_path_buf(),
                line: 1,
                column: 1,
                message: "the file is empty; expected a dualcal-params/1 JSON object".into(),
            });
        }
        // Syntax first, then the format tag (so another format gets the right message), then the types.
        let value: Value = serde_json::from_slice(bytes).map_err(json_err)?;
        match value.get("format") {
            Some(Value::String(s)) if s == PARAMS_FORMAT => {}
            Some(other) => {
                return Err(ParamsError::Format {
                    path: path.to_path_buf(),
                    message: format!(
                        "unknown format tag {}; expected \"{PARAMS_FORMAT}\"",
                        crate::textfile::excerpt(&other.to_string())
                    ),
                });
            }
            None => {
                return Err(ParamsError::Format {
                    path: path.to_path_buf(),
                    message: format!("missing; expected \"format\": \"{PARAMS_FORMAT}\""),
                });
            }
        }
        serde_json::from_slice(bytes).map_err(json_err)
    }

    /// Write as pretty JSON, atomically. The content is validated first (as [`ParamsFile::to_model`]),
    /// so a file that could not be read back is never written.
    pub fn write(&self, path: &Path) -> Result<(), ParamsError> {
        self.to_model().map_err(|e| e.in_file(path))?;
        let mut bytes = serde_json::to_vec_pretty(self).map_err(|e| ParamsError::Write {
            path: path.to_path_buf(),
            source: std::io::Error::other(e),
        })?;
        bytes.push(b'\n');
        write_atomic(path, &bytes).map_err(|source| ParamsError::Write {
            path: path.to_path_buf(),
            source,
        })
    }
}

/// The `method` record of a calibration's parameter file.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct MethodRecord {
    pub name: String,
    /// `Minimax` or `LeastSquares`.
    pub objective: String,
    /// `Exact` or `Paper`.
    pub qp: String,
    /// `Cal`, `Ver` or `All`: the configurations used for identification.
    pub split: String,
    pub max_iterations: usize,
    pub step_tolerance: f64,
    pub progress_tolerance: f64,
    /// Configurations left out of the identification (`--exclude`, `--auto-exclude`, the workbench).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub excluded: Vec<ConfigRef>,
}

/// A configuration by arm and id, as in the dataset's CSV.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct ConfigRef {
    pub arm: Side,
    pub id: String,
}

/// Conditioning of one arm's identification (`statistics.identifiability.<arm>`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ConditioningRecord {
    /// Number of identified (free) parameters.
    pub identified: usize,
    /// Condition number of the scaled Jacobian with every parameter; `null` when infinite.
    pub condition_before: Option<f64>,
    /// ... with the fixed parameters removed; `null` when infinite.
    pub condition_after: Option<f64>,
}

/// The `statistics` record of a calibration's parameter file.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct StatisticsRecord {
    /// Accuracy of the calibrated model on the calibration configurations (`null` if there are too few).
    pub cal: Option<AccuracyReport>,
    /// ... on the verification configurations.
    pub ver: Option<AccuracyReport>,
    /// Per arm; `null` for an arm whose stage did not run.
    pub identifiability: PerSide<Option<ConditioningRecord>>,
    /// Allowed deviation of the reflector triangle's sides (constraint 14), mm.
    pub reflector_side_tolerance_mm: PerSide<f64>,
    pub elapsed_secs: f64,
}

/// `Some(v)` for a finite `v` (JSON has no infinity).
fn finite_or_none(v: f64) -> Option<f64> {
    v.is_finite().then_some(v)
}

/// A record as the file's free-form JSON value.
fn record(value: &impl Serialize) -> Option<Value> {
    serde_json::to_value(value).ok()
}

impl ParamsFile {
    /// The file of a calibration: the calibrated model plus method, fixed parameters and why, per-stage
    /// termination, accuracy on the cal and ver splits of `dataset`, conditioning and provenance, and
    /// `converged: false` when the run did not converge. The command line and the workbench both
    /// export this.
    pub fn from_calibration(result: &CalibrationResult, dataset: &Dataset) -> ParamsFile {
        let settings = &result.settings;
        let mut file = ParamsFile::from_model(&result.calibrated);
        file.method = record(&MethodRecord {
            name: "two-step minimax calibration (paper Algorithms I and II)".into(),
            objective: format!("{:?}", settings.method),
            qp: format!("{:?}", settings.qp),
            split: format!("{:?}", settings.split),
            max_iterations: settings.max_iterations,
            step_tolerance: settings.step_tolerance,
            progress_tolerance: settings.progress_tolerance,
            excluded: settings
                .exclude
                .iter()
                .filter_map(|c| {
                    let m = dataset.arm(c.side).measurements.get(c.index)?;
                    Some(ConfigRef {
                        arm: c.side,
                        id: m.id.clone(),
                    })
                })
                .collect(),
        });
        let fixed = |side: Side| -> Vec<FixedParameter> {
            result.identifiability[side]
                .iter()
                .flat_map(|rep| {
                    rep.fixed.iter().map(|f| FixedParameter {
                        name: f.name.clone(),
                        reason: f.reason.clone(),
                    })
                })
                .collect()
        };
        file.fixed_parameters = Some(FixedParameters {
            left: fixed(Side::Left),
            right: fixed(Side::Right),
        });
        file.termination = record(&result.stages);
        // The figures leave the excluded configurations out, as the solver did.
        let kept = dataset.excluding(&settings.exclude);
        let accuracy = |split| crate::metrics::evaluate(&kept, &result.calibrated, split).ok();
        file.statistics = record(&StatisticsRecord {
            cal: accuracy(Split::Cal),
            ver: accuracy(Split::Ver),
            identifiability: result.identifiability.as_ref().map(|_, rep| {
                rep.as_ref().map(|rep| ConditioningRecord {
                    identified: rep.free.len(),
                    condition_before: finite_or_none(rep.condition_before),
                    condition_after: finite_or_none(rep.condition_after),
                })
            }),
            reflector_side_tolerance_mm: result.side_tolerance_mm,
            elapsed_secs: result.elapsed_secs,
        });
        file.converged = (!result.is_converged()).then_some(false);
        file.provenance = Some(Provenance::now(Some(&dataset.dir)));
        file
    }
}

/// Read a parameter file into a model (mm, rad).
pub fn read_model(path: &Path) -> Result<DualArmModel, ParamsError> {
    ParamsFile::read(path)?
        .to_model()
        .map_err(|e| e.in_file(path))
}

/// Write a model as a parameter file without the optional fields.
pub fn write_model(model: &DualArmModel, path: &Path) -> Result<(), ParamsError> {
    ParamsFile::from_model(model).write(path)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn civil_dates() {
        assert_eq!(civil_from_days(0), (1970, 1, 1));
        assert_eq!(civil_from_days(-1), (1969, 12, 31));
        assert_eq!(civil_from_days(11_016), (2000, 2, 29));
        assert_eq!(civil_from_days(11_017), (2000, 3, 1));
        assert_eq!(civil_from_days(19_723), (2024, 1, 1));
        let t = std::time::UNIX_EPOCH + std::time::Duration::from_secs(1_700_000_000);
        assert_eq!(utc_timestamp(t), "2023-11-14T22:13:20Z");
    }

    #[test]
    fn nearest_rotation_fixes_small_noise_and_keeps_exact_rotations() {
        let r = Rotation3::from_euler_angles(0.3, -1.1, 2.0);
        let back = nearest_rotation(r.matrix());
        assert!((back.matrix() - r.matrix()).abs().max() < 1e-15);
        let noisy = r.matrix() + Matrix3::from_fn(|i, j| 1e-7 * ((i * 3 + j) as f64 - 4.0));
        let fixed = nearest_rotation(&noisy);
        let m = fixed.matrix();
        assert!((m.transpose() * m - Matrix3::identity()).abs().max() < 1e-14);
        assert!((m - r.matrix()).abs().max() < 1e-6);
    }
}
