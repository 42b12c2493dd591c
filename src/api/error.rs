//! The front door's one error type: every failure a user can meet, with the engine's own message
//! (file, line and field where the input was at fault).

use std::path::PathBuf;

/// What went wrong, and where. `Display` gives the engine's message unchanged (the one the command line
/// prints), naming the file, line and field where a file was at fault.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// A dataset or its robot description could not be loaded or did not fit each other.
    #[error(transparent)]
    Load(#[from] crate::workspace::LoadError),
    /// A dataset could not be read.
    #[error(transparent)]
    Dataset(#[from] crate::dataset::DatasetError),
    /// A robot description could not be read or compiled.
    #[error(transparent)]
    Robot(#[from] crate::robot::RobotError),
    /// The data refuse a calibration as they are (the screening's whole-file errors).
    #[error("{}", .0.join("; "))]
    Refused(Vec<String>),
    /// The calibration could not run (too few configurations, a method that does not fit the data).
    #[error(transparent)]
    Calibration(#[from] crate::solver::CalibrationError),
    /// A parameter file could not be read or written.
    #[error(transparent)]
    Params(#[from] crate::params::ParamsError),
    /// The accuracy figures could not be computed.
    #[error(transparent)]
    Metrics(#[from] crate::metrics::MetricsError),
    /// The per-configuration figures could not be computed.
    #[error(transparent)]
    Analysis(#[from] crate::analysis::AnalysisError),
    /// Tracker or controller files could not be imported (the file, line and field at fault).
    #[error(transparent)]
    Import(#[from] crate::import::ImportError),
    /// A measurement could not be planned (too few candidates facing the tracker, options).
    #[error(transparent)]
    Plan(#[from] crate::plan::PlanError),
    /// A target list could not be read (the file, line and field at fault).
    #[error(transparent)]
    Targets(#[from] crate::controller::targets::TargetsError),
    /// An option's value is not one the engine knows (a method's or model's name, a configuration id).
    #[error("{0}")]
    Invalid(String),
    /// A file could not be read.
    #[error(transparent)]
    File(#[from] crate::output::FileError),
    /// An output would replace an input file, or a file or directory that exists.
    #[error(transparent)]
    Output(#[from] crate::output::OutputError),
    /// A file could not be written.
    #[error("writing {}: {source}", path.display())]
    Write {
        /// The file.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
}

/// The front door's result type.
pub type Result<T, E = Error> = std::result::Result<T, E>;
