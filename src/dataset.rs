//! The `dualcal-dataset/1` measurement format: a directory with `dataset.toml` and one CSV per arm.
//! See `docs/formats.md`. Everything is converted to mm and rad on load.

use crate::kinematics::{N_JOINTS, Side};
use nalgebra::Vector3;
use std::path::{Path, PathBuf};

/// The format tag written in `dataset.toml`.
pub const DATASET_FORMAT: &str = "dualcal-dataset/1";
/// Minimum number of configurations per arm (paper Table 2: 4 configurations make the truss rigid).
pub const MIN_CONFIGS: usize = 4;

/// Calibration or verification configuration.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Split {
    Cal,
    Ver,
}

/// Which configurations an operation uses.
#[derive(
    Clone, Copy, Debug, PartialEq, Eq, Hash, Default, serde::Serialize, serde::Deserialize,
)]
#[serde(rename_all = "lowercase")]
pub enum SplitSelect {
    Cal,
    Ver,
    #[default]
    All,
}

impl SplitSelect {
    pub fn accepts(self, split: Split) -> bool {
        match self {
            SplitSelect::All => true,
            SplitSelect::Cal => split == Split::Cal,
            SplitSelect::Ver => split == Split::Ver,
        }
    }
}

/// One measured configuration of one arm.
#[derive(Clone, Debug, PartialEq)]
pub struct Measurement {
    pub id: String,
    /// Joint values in chain order, rad.
    pub q_rad: [f64; N_JOINTS],
    /// Measured reflector positions a, b, c in the tracker frame, mm.
    pub tracker_points_mm: [Vector3<f64>; 3],
    /// `cal` or `ver`; rows without a split column are `cal`.
    pub split: Split,
    /// 1-based line number in the CSV (for messages).
    pub line: usize,
}

/// The tracker's maximum permissible error `mpe_um + mpe_um_per_m · distance`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TrackerSpec {
    pub mpe_um: f64,
    pub mpe_um_per_m: f64,
}

impl Default for TrackerSpec {
    /// FARO Vantage, as in the paper: 16 µm + 0.8 µm/m.
    fn default() -> Self {
        Self {
            mpe_um: 16.0,
            mpe_um_per_m: 0.8,
        }
    }
}

/// One arm's measurements.
#[derive(Clone, Debug, PartialEq)]
pub struct ArmData {
    pub side: Side,
    pub file: PathBuf,
    pub measurements: Vec<Measurement>,
}

impl ArmData {
    pub fn select(&self, split: SplitSelect) -> Vec<&Measurement> {
        self.measurements
            .iter()
            .filter(|m| split.accepts(m.split))
            .collect()
    }
}

/// A loaded dataset.
#[derive(Clone, Debug, PartialEq)]
pub struct Dataset {
    /// Directory the dataset was loaded from.
    pub dir: PathBuf,
    /// Robot description (resolved path), or `None` for the built-in IRB 14000.
    pub robot: Option<PathBuf>,
    pub tracker: TrackerSpec,
    /// Nominal reflector coordinates in the flange frame, mm.
    pub nominal_reflectors_mm: [Vector3<f64>; 3],
    pub left: ArmData,
    pub right: ArmData,
}

impl Dataset {
    pub fn arm(&self, side: Side) -> &ArmData {
        match side {
            Side::Left => &self.left,
            Side::Right => &self.right,
        }
    }
}

/// Typed loading errors. Every variant names the file; CSV errors also name the line and the field.
#[derive(Debug, thiserror::Error)]
pub enum DatasetError {
    #[error("{path}: cannot read: {source}")]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("{path}: {message}")]
    Manifest { path: PathBuf, message: String },
    #[error("{path}:{line}: field `{field}`: {message}")]
    Field {
        path: PathBuf,
        line: usize,
        field: String,
        message: String,
    },
    #[error("{path}: {message}")]
    Content { path: PathBuf, message: String },
}

/// Load a dataset from its directory or from the path of its `dataset.toml`.
pub fn load(path: &Path) -> Result<Dataset, DatasetError> {
    Err(DatasetError::Content {
        path: path.to_path_buf(),
        message: "not implemented yet".into(),
    })
}
