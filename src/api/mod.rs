//! The front door: the few types a program needs to calibrate (re-exported at the crate root).
//! [`Dataset`] and [`Robot`] load what was measured on what; [`Calibration`] runs the paper's two
//! steps with the command line's defaults; [`Calibrated`] holds what came of it — parameters with
//! their σ, accuracy before and after, per-configuration errors, and the exports (parameter file,
//! calibrated URDF and overlay, ABB base frames, compensated targets). [`Import`] makes a dataset of
//! tracker exports and joint logs; [`Plan`] says which configurations to measure; [`evaluate`] gives
//! a parameter file's accuracy on a dataset.

mod calibration;
mod dataset;
mod error;
mod import;
mod plan;
mod robot;

pub use calibration::{
    Accuracy, Calibrated, Calibration, Parameter, PerSplit, SplitAccuracy, evaluate,
};
pub use dataset::{ArmArrays, Arrays, Dataset};
pub use error::{Error, Result};
pub use import::{Import, ImportedDataset};
pub use plan::{Plan, Planned};
pub use robot::Robot;
