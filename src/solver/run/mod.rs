//! Running a calibration: the entry point ([`Calibrator`]), the executor of the stages
//! ([`CalibrationRun`]), step 1's two arms at once, the checks of a run's input and what a dataset
//! calls for by default.

mod arms_at_once;
pub mod calibrator;
pub mod executor;
mod inputs;
pub mod policy;

pub use calibrator::Calibrator;
pub use executor::{CONDITION_GROWTH, CalibrationRun, Observer, Progress};
pub use policy::{default_method, default_method_reason, planned_stages};
