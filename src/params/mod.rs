//! The `dualcal-params/1` parameter file (JSON): both arms' models — the built-in IRB 14000's DH
//! tables, or the joint-origin corrections of a URDF's arm chains — with their reflectors, and the
//! right-arm base in the left-arm base frame, plus optional method, fixed parameters, termination,
//! statistics and provenance. See `docs/formats.md`.
//!
//! [`ParamsFile`] mirrors the file one to one (so unknown extra fields survive a read/write round trip);
//! [`ParamsFile::to_model`] (DH files) and [`ParamsFile::to_model_for`] (any file, with the robot it
//! belongs to) validate it and convert to the in-memory [`DualArmModel`] in mm and rad.

mod arm;
mod records;

use crate::kinematics::{DualArmModel, PARAMS_PER_JOINT, nearest_rotation, param_name};
use crate::output::{FileError, write_atomic};
use crate::robot::RobotDescription;
use crate::side::{PerSide, Side};
pub use arm::{ArmParams, ChainParams, DhEntry, JointCorrection, ReflectorsEntry};
pub use arm::{MAX_ANGLE_RAD, MAX_LENGTH_MM, MAX_REFLECTOR_MM};
use arm::{Scale, arm_model, arm_model_for, arm_params, finite};
use nalgebra::{Isometry3, Matrix3, Translation3, UnitQuaternion, Vector3};
pub use records::{
    ConditioningRecord, ConfigRef, MethodRecord, Provenance, StatisticsRecord, utc_timestamp,
};
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
    /// A file is missing or unreadable, or could not be written.
    #[error(transparent)]
    File(#[from] FileError),
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

/// Both arms, under the keys `left` and `right`.
pub type ArmsParams = PerSide<ArmParams>;

/// The right arm's model base frame in the left arm's (`left_base_from_right_base`; DH frames 0 for
/// the built-in robot, the chains' base links otherwise): a point `p_right` maps to
/// `rotation · p_right + translation`. `rotation` is row-major.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BaseTransform {
    pub translation: [f64; 3],
    pub rotation: [[f64; 3]; 3],
}

/// Each arm's model base in the tracker frame, written by the methods that identify it (the absolute
/// methods `pose`, `position` in step 1 and `absolute` in step 2): a point `p` of the arm's base maps
/// to `rotation · p + translation` in the tracker frame. A model needs neither (the distance methods
/// cannot see them): `evaluate`'s distance figures are the same with or without; its absolute figures
/// (the markers' position errors in the tracker frame) need them.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct TrackerFrames {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tracker_from_left_base: Option<BaseTransform>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tracker_from_right_base: Option<BaseTransform>,
    /// Which stage identified them, e.g. `step 1 (position)` or `step 2 (absolute)`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub identified_by: Option<String>,
}

impl BaseTransform {
    /// The file form of a transform (mm).
    pub fn from_isometry(iso: &Isometry3<f64>) -> BaseTransform {
        let r = iso.rotation.to_rotation_matrix();
        let m = r.matrix();
        let t = iso.translation.vector;
        BaseTransform {
            translation: [t.x, t.y, t.z],
            rotation: [0, 1, 2].map(|i| [m[(i, 0)], m[(i, 1)], m[(i, 2)]]),
        }
    }

    /// Checked (finite, a rotation within [`ROTATION_TOLERANCE`], a plausible translation) and
    /// re-orthonormalised; `field` names it in messages.
    fn checked_isometry(&self, field: &str, scale: Scale) -> Result<Isometry3<f64>, ParamsError> {
        finite(&format!("{field}.translation"), &self.translation)?;
        finite(&format!("{field}.rotation"), self.rotation.as_flattened())?;
        let m = Matrix3::from_fn(|i, j| self.rotation[i][j]);
        let dev = (m.transpose() * m - Matrix3::identity()).abs().max();
        let det = m.determinant();
        if dev > ROTATION_TOLERANCE || det <= 0.0 {
            return Err(invalid(
                format!("{field}.rotation"),
                format!(
                    "not a rotation matrix: max |RᵀR − I| = {dev:.3e} (tolerance {ROTATION_TOLERANCE:e}), det = {det:.6}"
                ),
            ));
        }
        let rotation = UnitQuaternion::from_rotation_matrix(&nearest_rotation(&m));
        let translation = Translation3::from(Vector3::from(self.translation) * scale.mm);
        arm::plausible(
            &format!("{field}.translation"),
            translation.vector.as_slice(),
            arm::MAX_LENGTH_MM,
            "mm",
        )?;
        Ok(Isometry3::from_parts(translation, rotation))
    }
}

/// A parameter held at its value during identification, and why.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct FixedParameter {
    /// A parameter name ([`crate::kinematics::ArmModel::param_name`]), e.g. `theta1`,
    /// `yumi_joint_2_l.rz`, `t_a.x`.
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

/// Weak parameters per arm ([`ParamsFile::weak_parameters`]).
#[derive(Clone, Debug, PartialEq, Default, Serialize, Deserialize)]
pub struct WeakParameters {
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub left: Vec<crate::solver::weak::WeakParameter>,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub right: Vec<crate::solver::weak::WeakParameter>,
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
    /// Each arm's base in the tracker frame, where the method identified it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tracker_frames: Option<TrackerFrames>,
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
    /// The identified parameters' standard deviations, strong correlations and condition number per
    /// arm (free form; dualcal writes `{"left": solver::uncertainty::ArmUncertainty, "right": …}`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub uncertainty: Option<Value>,
    /// The weak parameters per arm — identified, but barely constrained by the configurations across
    /// the workspace — with the reason in words and whether they were held at their nominal values
    /// (`solver::weak`); absent when there are none.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub weak_parameters: Option<WeakParameters>,
    /// Fields this version does not know; kept for round trips.
    #[serde(flatten)]
    pub extra: serde_json::Map<String, Value>,
}

impl ParamsFile {
    /// The file form of a model, in mm and rad, without the optional fields.
    pub fn from_model(model: &DualArmModel) -> ParamsFile {
        ParamsFile {
            format: PARAMS_FORMAT.to_string(),
            units: ParamsUnits::default(),
            arms: model.arms.as_ref().map(|_, arm| arm_params(arm)),
            right_base_in_left: BaseTransform::from_isometry(&model.left_base_from_right_base),
            method: None,
            fixed_parameters: None,
            tracker_frames: None,
            termination: None,
            statistics: None,
            converged: None,
            provenance: None,
            quality: None,
            uncertainty: None,
            weak_parameters: None,
            extra: Default::default(),
        }
    }

    /// Mm and rad per unit of the file (`mm`|`m`, `rad`|`deg`), checked.
    fn scale(&self) -> Result<Scale, ParamsError> {
        if self.format != PARAMS_FORMAT {
            return Err(invalid(
                "format",
                format!(
                    "unknown format tag \"{}\"; expected \"{PARAMS_FORMAT}\"",
                    crate::textfile::excerpt(&self.format)
                ),
            ));
        }
        let mm = match self.units.length.as_str() {
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
        let rad = match self.units.angle.as_str() {
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
        Ok(Scale { mm, rad })
    }

    /// `right_base_in_left`, checked (finite, a rotation within [`ROTATION_TOLERANCE`]) and
    /// re-orthonormalised.
    fn base_transform(&self, scale: Scale) -> Result<Isometry3<f64>, ParamsError> {
        self.right_base_in_left
            .checked_isometry("right_base_in_left", scale)
    }

    /// The tracker frames, checked like `right_base_in_left`.
    pub fn tracker_from_base(&self) -> Result<PerSide<Option<Isometry3<f64>>>, ParamsError> {
        let scale = self.scale()?;
        let Some(frames) = &self.tracker_frames else {
            return Ok(PerSide::default());
        };
        Ok(PerSide::new(
            frames
                .tracker_from_left_base
                .map(|b| b.checked_isometry("tracker_frames.tracker_from_left_base", scale))
                .transpose()?,
            frames
                .tracker_from_right_base
                .map(|b| b.checked_isometry("tracker_frames.tracker_from_right_base", scale))
                .transpose()?,
        ))
    }

    /// Every fixed-parameter name must be a parameter of its arm.
    fn check_fixed_names(&self) -> Result<(), ParamsError> {
        let Some(fixed) = &self.fixed_parameters else {
            return Ok(());
        };
        for (side, list) in [(Side::Left, &fixed.left), (Side::Right, &fixed.right)] {
            let reflector_names = self.arms[side]
                .reflectors
                .0
                .iter()
                .flat_map(|(r, _)| ["x", "y", "z"].map(|c| format!("t_{r}.{c}")));
            let names = match &self.arms[side].chain {
                None => {
                    let mut names: Vec<String> =
                        (0..crate::kinematics::N_DH).map(param_name).collect();
                    names.extend(reflector_names);
                    names
                }
                Some(chain) => {
                    let mut names: Vec<String> = chain
                        .joints
                        .iter()
                        .flat_map(|j| {
                            crate::kinematics::CORRECTION_NAMES
                                .iter()
                                .map(move |c| format!("{}.{c}", j.name))
                        })
                        .collect();
                    names.extend(reflector_names);
                    debug_assert_eq!(
                        names.len(),
                        PARAMS_PER_JOINT * chain.joints.len()
                            + 3 * self.arms[side].reflectors.0.len()
                    );
                    names
                }
            };
            // An arm with errors beyond geometry names their parameters too (as its `errors` lists them).
            let names = match &self.arms[side].errors {
                Some(e) => {
                    let mut names = names;
                    names.extend(e.parameters.0.iter().map(|(n, _)| n.clone()));
                    names
                }
                None => names,
            };
            for (i, f) in list.iter().enumerate() {
                if !names.contains(&f.name) {
                    return Err(invalid(
                        format!("fixed_parameters.{side}[{i}].name"),
                        format!(
                            "unknown parameter `{}`; expected one of {} … {}",
                            crate::textfile::excerpt(&f.name),
                            names.first().map_or("", String::as_str),
                            names.last().map_or("", String::as_str)
                        ),
                    ));
                }
            }
        }
        Ok(())
    }

    /// Check everything that can be checked without the robot description: the format tag, the units
    /// (`mm`|`m`, `rad`|`deg`), one form per arm (7 DH rows, or a chain with joints), finite numbers,
    /// fixed-parameter names, and that the rotation is orthonormal with determinant +1 within
    /// [`ROTATION_TOLERANCE`].
    pub fn validate(&self) -> Result<(), ParamsError> {
        let scale = self.scale()?;
        for (side, arm) in self.arms.iter() {
            arm::validate(side.name(), arm, scale)?;
        }
        self.base_transform(scale)?;
        self.tracker_from_base()?;
        self.check_fixed_names()
    }

    /// Validate ([`ParamsFile::validate`]) and convert a file of DH arms (the built-in IRB 14000) to
    /// the in-memory model (mm, rad); the rotation is re-orthonormalised. A file of chain arms needs
    /// its robot: [`ParamsFile::to_model_for`].
    pub fn to_model(&self) -> Result<DualArmModel, ParamsError> {
        self.validate()?;
        let scale = self.scale()?;
        let arms = self
            .arms
            .as_ref()
            .try_map(|side, arm| arm_model(side.name(), arm, scale))?;
        Ok(DualArmModel {
            arms,
            left_base_from_right_base: self.base_transform(scale)?,
        })
    }

    /// Validate and convert to the model of `robot`: DH arms need the built-in IRB 14000, chain arms
    /// the robot's arm chains (the same links and joints, in order).
    pub fn to_model_for(&self, robot: &RobotDescription) -> Result<DualArmModel, ParamsError> {
        self.validate()?;
        let scale = self.scale()?;
        let arms = self
            .arms
            .as_ref()
            .try_map(|side, arm| arm_model_for(side, arm, scale, robot))?;
        Ok(DualArmModel {
            arms,
            left_base_from_right_base: self.base_transform(scale)?,
        })
    }

    /// Parse a parameter file. JSON syntax and type errors carry the line and column.
    pub fn read(path: &Path) -> Result<ParamsFile, ParamsError> {
        use crate::textfile::ReadError;
        let text = crate::textfile::read(path).map_err(|e| match e {
            ReadError::Io(error) => FileError::read(path, error).into(),
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

    /// Write as pretty JSON, atomically. The content is validated first ([`ParamsFile::validate`]),
    /// so a file that could not be read back is never written.
    pub fn write(&self, path: &Path) -> Result<(), ParamsError> {
        self.validate().map_err(|e| e.in_file(path))?;
        let mut bytes = serde_json::to_vec_pretty(self)
            .map_err(|e| FileError::write(path, std::io::Error::other(e)))?;
        bytes.push(b'\n');
        write_atomic(path, &bytes).map_err(|error| FileError::write(path, error).into())
    }
}

/// Read a parameter file of DH arms into a model (mm, rad).
pub fn read_model(path: &Path) -> Result<DualArmModel, ParamsError> {
    ParamsFile::read(path)?
        .to_model()
        .map_err(|e| e.in_file(path))
}

/// Read a parameter file into the model of `robot` (mm, rad).
pub fn read_model_for(path: &Path, robot: &RobotDescription) -> Result<DualArmModel, ParamsError> {
    ParamsFile::read(path)?
        .to_model_for(robot)
        .map_err(|e| e.in_file(path))
}

/// Write a model as a parameter file without the optional fields.
pub fn write_model(model: &DualArmModel, path: &Path) -> Result<(), ParamsError> {
    ParamsFile::from_model(model).write(path)
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Rotation3;

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
