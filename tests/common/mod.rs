//! Helpers shared by the integration tests (each test file includes this module with `mod common;`
//! and uses what it needs).
#![allow(dead_code)]

use dualcal::dataset::Dataset;
use dualcal::kinematics::DualArmModel;
use dualcal::solver::{CalibrationResult, CalibrationSettings, Calibrator, Termination};

/// Calibrate without observers. Panics when the input is refused or a stage ran out of iterations (a
/// test that means to check those calls [`Calibrator`] itself); a stall is returned for the test to
/// judge.
pub fn calibrate(
    dataset: &Dataset,
    nominal: &DualArmModel,
    settings: &CalibrationSettings,
) -> CalibrationResult {
    let result = Calibrator::new(dataset, nominal)
        .settings(settings.clone())
        .run()
        .expect("calibration");
    for stage in &result.stages {
        assert_ne!(
            stage.termination,
            Termination::MaxIterations,
            "{stage:?} ran out of iterations"
        );
    }
    result
}
