//! The app's view of the engine: a loaded dataset and robot, the nominal model and (after a run) the
//! calibrated one, each with the accuracy figures, pair errors and per-configuration rows the panels
//! show. This is the only app module that calls into `dataset`, `robot` and `metrics`.

use super::registration::best_fit_rigid;
use crate::dataset::{self, Dataset, Split, SplitSelect};
use crate::kinematics::{DualArmModel, Side};
use crate::metrics::{self, AccuracyReport, ConfigError, PairError, PairKind};
use crate::robot::RobotDescription;
use crate::solver::CalibrationResult;
use anyhow::Context as _;
use nalgebra::{Isometry3, Point3, Vector3};
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// Which accuracy figure: relative (one arm) or collaborative, position or orientation.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Figure {
    RelativePosition(Side),
    RelativeOrientation(Side),
    CollaborativePosition,
    CollaborativeOrientation,
}

impl Figure {
    pub const ALL: [Figure; 6] = [
        Figure::RelativePosition(Side::Left),
        Figure::RelativePosition(Side::Right),
        Figure::CollaborativePosition,
        Figure::RelativeOrientation(Side::Left),
        Figure::RelativeOrientation(Side::Right),
        Figure::CollaborativeOrientation,
    ];

    pub fn label(self) -> String {
        match self {
            Figure::RelativePosition(s) => format!("relative Δd, {s} arm (mm)"),
            Figure::RelativeOrientation(s) => format!("relative Δo, {s} arm (rad)"),
            Figure::CollaborativePosition => "collaborative Δd (mm)".into(),
            Figure::CollaborativeOrientation => "collaborative Δo (rad)".into(),
        }
    }

    pub fn is_position(self) -> bool {
        matches!(
            self,
            Figure::RelativePosition(_) | Figure::CollaborativePosition
        )
    }

    pub fn pair_kind(self) -> PairKind {
        match self {
            Figure::RelativePosition(s) | Figure::RelativeOrientation(s) => PairKind::Relative(s),
            Figure::CollaborativePosition | Figure::CollaborativeOrientation => {
                PairKind::Collaborative
            }
        }
    }

    /// The matching summary line of a report: (rms, max, [frequency within the two thresholds]).
    pub fn summary(self, report: &AccuracyReport) -> (f64, f64, [f64; 2]) {
        let stats = match self.pair_kind() {
            PairKind::Relative(side) => report.relative(side),
            PairKind::Collaborative => &report.collaborative,
        };
        if self.is_position() {
            (
                stats.pos_rms_mm,
                stats.pos_max_mm,
                [stats.pos_within_0_3mm_frac, stats.pos_within_0_6mm_frac],
            )
        } else {
            (
                stats.ori_rms_rad,
                stats.ori_max_rad,
                [
                    stats.ori_within_0_005rad_frac,
                    stats.ori_within_0_01rad_frac,
                ],
            )
        }
    }
}

/// The pair errors of one split for the three pair kinds (left, right, collaborative).
#[derive(Clone, Debug, Default)]
pub struct PairSet {
    pub relative: [Vec<PairError>; 2],
    pub collaborative: Vec<PairError>,
}

impl PairSet {
    pub fn of(&self, kind: PairKind) -> &[PairError] {
        match kind {
            PairKind::Relative(Side::Left) => &self.relative[0],
            PairKind::Relative(Side::Right) => &self.relative[1],
            PairKind::Collaborative => &self.collaborative,
        }
    }

    /// Histogram samples of a figure: every reflector's signed Δd (mm) or Δo (rad).
    pub fn samples(&self, figure: Figure) -> Vec<f64> {
        let pairs = self.of(figure.pair_kind());
        if figure.is_position() {
            pairs.iter().flat_map(|p| p.pos_error_mm).collect()
        } else {
            pairs.iter().map(|p| p.ori_error_rad).collect()
        }
    }
}

/// One configuration as drawn and listed: identity, errors and its reflector points in the body frame.
#[derive(Clone, Debug)]
pub struct ConfigRow {
    pub side: Side,
    /// Index into `ArmData::measurements`.
    pub index: usize,
    pub id: String,
    pub split: Split,
    /// Largest |Δd| over every pair (relative and collaborative) involving it, mm.
    pub worst_pos_mm: f64,
    /// Largest Δo over every pair involving it, rad.
    pub worst_ori_rad: f64,
    /// Largest deviation of the measured triangle's sides from the model's, mm.
    pub rigidity_mm: f64,
    /// Measured points a, b, c in the body frame (after registration), mm.
    pub measured_body_mm: [Vector3<f64>; 3],
    /// Model points a, b, c in the body frame, mm.
    pub model_body_mm: [Vector3<f64>; 3],
}

impl ConfigRow {
    /// Distance between measured and model point of each reflector after registration, mm.
    pub fn point_errors_mm(&self) -> [f64; 3] {
        std::array::from_fn(|k| (self.measured_body_mm[k] - self.model_body_mm[k]).norm())
    }
}

/// Everything derived from one model on one dataset.
#[derive(Clone, Debug)]
pub struct Analysis {
    pub model: DualArmModel,
    /// Reports on the calibration and verification splits (`None` when a split has too few
    /// configurations).
    pub reports: [Option<AccuracyReport>; 2],
    /// Pair errors on the calibration and verification splits.
    pub pairs: [PairSet; 2],
    /// Every configuration of both arms (left first).
    pub configs: Vec<ConfigRow>,
    /// Tracker → left DH base registration used for drawing.
    pub left_base_from_tracker: Isometry3<f64>,
    /// RMS of the registration residuals, mm.
    pub registration_rms_mm: f64,
}

pub fn split_index(split: Split) -> usize {
    match split {
        Split::Cal => 0,
        Split::Ver => 1,
    }
}

pub fn split_select(split: Split) -> SplitSelect {
    match split {
        Split::Cal => SplitSelect::Cal,
        Split::Ver => SplitSelect::Ver,
    }
}

impl Analysis {
    /// Compute the figures of `model` on `dataset`; `body_from_left_base` places the drawing.
    pub fn compute(
        dataset: &Dataset,
        model: &DualArmModel,
        body_from_left_base: &Isometry3<f64>,
    ) -> anyhow::Result<Self> {
        let mut reports = [None, None];
        let mut pairs: [PairSet; 2] = Default::default();
        for split in [Split::Cal, Split::Ver] {
            let select = split_select(split);
            let k = split_index(split);
            // A split may be absent (datasets without a `split` column are all `cal`).
            if let Ok(report) = metrics::evaluate(dataset, model, select) {
                reports[k] = Some(report);
                let get = |kind| metrics::pairs(dataset, model, select, kind);
                pairs[k] = PairSet {
                    relative: [
                        get(PairKind::Relative(Side::Left))?,
                        get(PairKind::Relative(Side::Right))?,
                    ],
                    collaborative: get(PairKind::Collaborative)?,
                };
            }
        }
        let per_config: Vec<ConfigError> = metrics::per_config(dataset, model, SplitSelect::All)
            .context("per-configuration errors")?;

        // Model points in the left base, and the registration of the tracker onto them.
        let mut model_left: Vec<[Vector3<f64>; 3]> = Vec::new();
        let mut from = Vec::new();
        let mut to = Vec::new();
        for side in Side::BOTH {
            let arm = model.arm(side);
            let left_base_from_base = model.left_base_from(side);
            for m in &dataset.arm(side).measurements {
                let fk = arm.reflector_fk(&m.q_rad);
                let pts = fk
                    .points_mm
                    .map(|p| (left_base_from_base * Point3::from(p)).coords);
                from.extend(m.tracker_points_mm);
                to.extend(pts);
                model_left.push(pts);
            }
        }
        let left_base_from_tracker = best_fit_rigid(&from, &to)
            .context("cannot register the tracker frame to the robot (degenerate points)")?;
        let sum_sq: f64 = from
            .iter()
            .zip(&to)
            .map(|(p, q)| ((left_base_from_tracker * Point3::from(*p)).coords - q).norm_squared())
            .sum();
        let registration_rms_mm = (sum_sq / from.len().max(1) as f64).sqrt();

        let body_from_tracker = body_from_left_base * left_base_from_tracker;
        let mut configs = Vec::with_capacity(model_left.len());
        let mut n = 0;
        for side in Side::BOTH {
            for (index, m) in dataset.arm(side).measurements.iter().enumerate() {
                let model_pts = model_left[n];
                n += 1;
                let err = per_config
                    .iter()
                    .find(|c| c.side == side && c.index == index);
                let (worst_pos_mm, worst_ori_rad, rigidity_mm) =
                    err.map_or((f64::NAN, f64::NAN, f64::NAN), |c| {
                        (
                            c.relative_pos_max_mm.max(c.collaborative_pos_max_mm),
                            c.relative_ori_max_rad.max(c.collaborative_ori_max_rad),
                            c.rigidity_mm,
                        )
                    });
                configs.push(ConfigRow {
                    side,
                    index,
                    id: m.id.clone(),
                    split: m.split,
                    worst_pos_mm,
                    worst_ori_rad,
                    rigidity_mm,
                    measured_body_mm: m
                        .tracker_points_mm
                        .map(|p| (body_from_tracker * Point3::from(p)).coords),
                    model_body_mm: model_pts
                        .map(|p| (body_from_left_base * Point3::from(p)).coords),
                });
            }
        }
        Ok(Self {
            model: model.clone(),
            reports,
            pairs,
            configs,
            left_base_from_tracker,
            registration_rms_mm,
        })
    }
}

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
        let robot = match &robot_path {
            Some(p) => RobotDescription::load(p)?,
            None => RobotDescription::builtin_irb14000(),
        };
        Self::new(dataset, robot, robot_path)
    }

    pub fn new(
        dataset: Dataset,
        robot: RobotDescription,
        robot_source: Option<PathBuf>,
    ) -> anyhow::Result<Self> {
        // A URDF of our own (e.g. an exported calibrated one) carries its DH model; the built-in
        // robot is Table 3.
        let nominal_model = match &robot_source {
            Some(_) => robot
                .dh_model(dataset.nominal_reflectors_mm)
                .with_context(|| "the robot description does not encode a DH model")?,
            None => robot.nominal_model(dataset.nominal_reflectors_mm),
        };
        let nominal = Analysis::compute(
            &dataset,
            &nominal_model,
            &robot.body_from_dh_base(Side::Left),
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
        self.calibrated
            .as_ref()
            .map_or(&self.nominal, |c| &c.analysis)
    }

    pub fn body_from_left_base(&self) -> Isometry3<f64> {
        self.robot.body_from_dh_base(Side::Left)
    }
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
        let n = session.dataset.left.measurements.len() + session.dataset.right.measurements.len();
        assert_eq!(analysis.configs.len(), n);
        assert_eq!(
            analysis.configs[0].id,
            session.dataset.left.measurements[0].id
        );
        // The model points sit where the robot's flange is drawn (body frame, not a base frame).
        let row = &analysis.configs[0];
        let flange = session
            .robot
            .body_from_flange(Side::Left, &session.dataset.left.measurements[0].q_rad);
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
