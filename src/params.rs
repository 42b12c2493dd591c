//! The `dualcal-params/1` parameter file (JSON): both arms' DH tables and reflectors and the right-arm
//! base in the left-arm base frame, plus optional provenance and statistics.

use crate::kinematics::DualArmModel;
use std::path::Path;

pub const PARAMS_FORMAT: &str = "dualcal-params/1";

#[derive(Debug, thiserror::Error)]
pub enum ParamsError {
    #[error("{path}: cannot read: {source}")]
    Io {
        path: std::path::PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("{path}: {message}")]
    Invalid {
        path: std::path::PathBuf,
        message: String,
    },
}

/// Read a parameter file into a model.
pub fn read(path: &Path) -> Result<DualArmModel, ParamsError> {
    Err(ParamsError::Invalid {
        path: path.to_path_buf(),
        message: "not implemented yet".into(),
    })
}
