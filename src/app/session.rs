//! The app's view of the engine: a loaded dataset and robot, the nominal model and (after a run) the
//! calibrated one, each with its [`Analysis`] (accuracy figures, pair residuals and the
//! per-configuration rows the panels show).

use crate::analysis::{Analysis, ConfigRow};
use crate::dataset::{self, Dataset};
use crate::robot::RobotDescription;
use crate::side::{ConfigId, Side};
use crate::solver::CalibrationResult;
use anyhow::Context as _;
use nalgebra::Isometry3;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// A finished calibration and its figures.
#[derive(Clone, Debug)]
pub struct Calibrated {
    pub result: CalibrationResult,
    pub analysis: Analysis,
}

/// A loaded dataset with its robot and figures.
#[derive(Clone)]
pub struct Session {
    pub dataset: Arc<Dataset>,
    pub robot: Arc<RobotDescription>,
    /// Where the robot came from (`None`: built in).
    pub robot_source: Option<PathBuf>,
    pub nominal: Analysis,
    pub calibrated: Option<Calibrated>,
}

impl Session {
    /// Load a dataset (directory or `dataset.toml`) with the given robot, or the one the dataset names,
    /// or the built-in IRB 14000.
    pub fn load(dataset_path: &Path, urdf: Option<&Path>) -> anyhow::Result<Self> {
        let dataset = dataset::load(dataset_path)?;
        let robot_path = urdf
            .map(Path::to_path_buf)
            .or_else(|| dataset.robot.clone());
        let robot = RobotDescription::for_dataset_with(
            &dataset,
            robot_path.as_deref(),
            &Default::default(),
        )?;
        Self::new(dataset, robot, robot_path)
    }

    pub fn new(
        dataset: Dataset,
        robot: RobotDescription,
        robot_source: Option<PathBuf>,
    ) -> anyhow::Result<Self> {
        // The description's own model: Table 3 for the built-in robot, the URDF's chains otherwise
        // (the same nominal model as `dualcal calibrate` and `evaluate --nominal`).
        robot.check_dataset(&dataset)?;
        let nominal_model = robot.nominal_model(dataset.nominal_reflectors_mm);
        let nominal = Analysis::compute(
            &dataset,
            &nominal_model,
            &robot.body_from_arm_base(Side::Left),
        )
        .context("nominal accuracy")?;
        Ok(Self {
            dataset: Arc::new(dataset),
            robot: Arc::new(robot),
            robot_source,
            nominal,
            calibrated: None,
        })
    }

    /// The newest model's figures: calibrated if there is one, else nominal.
    pub fn current(&self) -> &Analysis {
        self.analysis(true)
    }

    /// The calibrated model's figures when `calibrated` is asked for and there are any, else the
    /// nominal model's.
    pub fn analysis(&self, calibrated: bool) -> &Analysis {
        match &self.calibrated {
            Some(c) if calibrated => &c.analysis,
            _ => &self.nominal,
        }
    }

    pub fn body_from_left_base(&self) -> Isometry3<f64> {
        self.robot.body_from_arm_base(Side::Left)
    }
}

/// One configuration's row of an analysis.
pub fn config_row(analysis: &Analysis, config: ConfigId) -> Option<&ConfigRow> {
    analysis.configs.iter().find(|r| r.config == config)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn example() -> PathBuf {
        Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/datasets/example")
    }

    /// With the true parameters the registered measured points land on the model's (up to the
    /// tracker noise); with the nominal ones they do not. This checks the whole drawing chain:
    /// tracker → left base (registration) → body frame.
    #[test]
    fn registration_of_the_example_matches_the_truth_to_the_noise() {
        let session = Session::load(&example(), None).unwrap();
        let truth = crate::params::read_model(&example().join("truth.json")).unwrap();
        let analysis =
            Analysis::compute(&session.dataset, &truth, &session.body_from_left_base()).unwrap();
        assert!(
            analysis.registration_rms_mm < 0.05,
            "registration RMS with the truth {} mm",
            analysis.registration_rms_mm
        );
        assert!(
            session.nominal.registration_rms_mm > 10.0 * analysis.registration_rms_mm,
            "nominal {} mm vs truth {} mm",
            session.nominal.registration_rms_mm,
            analysis.registration_rms_mm
        );
        let worst_point = analysis
            .configs
            .iter()
            .flat_map(|r| r.point_errors_mm())
            .fold(0.0f64, f64::max);
        assert!(
            worst_point < 0.2,
            "worst point error with the truth {worst_point} mm"
        );
        // Every configuration of both arms is listed once, in dataset order.
        let n = session.dataset.arms.left.measurements.len()
            + session.dataset.arms.right.measurements.len();
        assert_eq!(analysis.configs.len(), n);
        assert_eq!(
            analysis.configs[0].id,
            session.dataset.arms.left.measurements[0].id
        );
        // The model points sit where the robot's flange is drawn (body frame, not a base frame).
        let row = &analysis.configs[0];
        let flange = session
            .robot
            .body_from_flange(Side::Left, &session.dataset.arms.left.measurements[0].q_rad);
        let centroid = (row.model_body_mm[0] + row.model_body_mm[1] + row.model_body_mm[2]) / 3.0;
        let d = (centroid - flange.translation.vector).norm();
        assert!(d < 150.0, "reflectors {d} mm from the drawn flange");
    }

    #[test]
    fn a_missing_dataset_is_an_error_naming_it() {
        let err = Session::load(Path::new("/nonexistent/dataset"), None)
            .err()
            .expect("error");
        assert!(
            format!("{err:#}").contains("/nonexistent/dataset"),
            "{err:#}"
        );
    }
}
