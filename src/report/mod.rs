//! The calibration report (`dualcal report DATASET --params PARAMS --out report.html`): one
//! self-contained HTML file — inline CSS and SVG, no script, nothing fetched — that says what was
//! calibrated, how, how well the data determine the parameters, how accurate the model is before and
//! after on the calibration and the verification configurations, which configurations are worst or
//! suspect, and what to distrust.
//!
//! [`Report::build`] gathers the figures from the engine — the parameter file's records
//! (`method`, `termination`, `fixed_parameters`, `uncertainty`, `quality`, `statistics`), the
//! accuracy of the nominal and the calibrated model ([`metrics::evaluate`](crate::metrics::evaluate)), their [`Analysis`](crate::analysis::Analysis)
//! (histograms, per-pair samples, per-configuration rows) and the screening — into a [`Report`];
//! [`render`] writes it as HTML. Nothing is estimated twice: where the parameter file lacks a record
//! the report computes it with the function that writes it (`solver::uncertainty`,
//! `quality::screen_model`) and says so.

mod build;
mod html;
pub mod svg;
mod warnings;

pub use html::{escape, render};
pub use warnings::{NOISE_RATIO_THRESHOLD, NoiseCheck, Warning, WarningLevel};

use crate::analysis::{AnalysisError, Histogram, Indicator};
use crate::comparison::BoxStats;
use crate::dataset::{Split, TrackerSpec};
use crate::metrics::{AccuracyReport, MetricsError};
use crate::params::{
    ConditioningRecord, FixedParameter, MethodRecord, ParamsError, Provenance, StatisticsRecord,
};
use crate::quality::{Flag, QualityRecord};
use crate::side::{PerSide, Side};
use crate::solver::StageSummary;
use crate::solver::uncertainty::ArmUncertainty;
use nalgebra::{Isometry3, Vector3};
use std::path::PathBuf;

/// Why a report cannot be made; each names the file concerned.
#[derive(Debug, thiserror::Error)]
pub enum ReportError {
    /// The parameter file does not read (its error names the file, line and field).
    #[error(transparent)]
    Params(#[from] ParamsError),
    /// The parameter file reads but does not fit the dataset's robot.
    // (The cause is in the message, not a `source`: a chain printed with `{:#}` would say it twice.)
    #[error("{}: {error}", path.display())]
    Model { path: PathBuf, error: ParamsError },
    /// The accuracy figures cannot be computed on the dataset.
    #[error("{}: the accuracy figures cannot be computed: {error}", path.display())]
    Metrics { path: PathBuf, error: MetricsError },
    /// The figures of a model cannot be computed on the dataset.
    #[error("{}: the figures cannot be computed: {error}", path.display())]
    Analysis { path: PathBuf, error: AnalysisError },
}

/// What a report is made on: a loaded dataset, its robot and the robot's nominal model (a
/// [`crate::workspace::Workspace`]'s parts).
#[derive(Clone, Copy)]
pub struct ReportInput<'a> {
    pub dataset: &'a crate::dataset::Dataset,
    pub robot: &'a crate::robot::RobotDescription,
    pub nominal: &'a crate::kinematics::DualArmModel,
}

/// Everything the report shows, computed; [`render`] only formats it.
#[derive(Clone, Debug)]
pub struct Report {
    /// When the report was made (UTC) and by which version.
    pub generated_utc: String,
    pub tool_version: String,
    pub params_path: PathBuf,
    /// The parameter file's `provenance`.
    pub provenance: Option<Provenance>,
    pub dataset: DatasetSummary,
    pub robot: RobotSummary,
    pub method: MethodSummary,
    pub arms: PerSide<ArmSummary>,
    /// The right arm's base in the left arm's base, nominal and calibrated.
    pub base: BaseChange,
    /// Nominal against calibrated, per split with enough configurations (calibration first).
    pub accuracy: Vec<SplitAccuracy>,
    pub figures: Figures,
    /// Per arm the configurations with the largest errors under the calibrated model.
    pub worst: PerSide<Vec<WorstRow>>,
    pub screening: ScreeningSummary,
    /// The residual after calibration against the tracker's noise, per arm.
    pub noise: PerSide<Option<NoiseCheck>>,
    pub warnings: Vec<Warning>,
}

/// The measurements.
#[derive(Clone, Debug)]
pub struct DatasetSummary {
    /// The dataset's directory.
    pub dir: PathBuf,
    pub arms: PerSide<ArmDataSummary>,
    /// Name and nominal position in the tip frame (mm) of each reflector.
    pub reflectors: Vec<(String, Vector3<f64>)>,
    pub tracker: TrackerSpec,
    /// The tracker's MPE at each arm's mean measuring distance, mm (the screening's figure).
    pub mpe_mm: PerSide<f64>,
    /// Both arms measured from one tracker station.
    pub one_station: bool,
    /// Which arms were measured (both, or one alone: the other has no data, no fit and no figures).
    pub measured: PerSide<bool>,
}

impl Report {
    /// The arms the dataset has measurements of, left first.
    pub fn measured_sides(&self) -> impl Iterator<Item = Side> + '_ {
        Side::BOTH.into_iter().filter(|&s| self.dataset.measured[s])
    }
}

/// One arm's measurements.
#[derive(Clone, Debug)]
pub struct ArmDataSummary {
    pub file: PathBuf,
    pub station: Option<String>,
    pub joints: usize,
    /// Configurations of the calibration and the verification split.
    pub cal: usize,
    pub ver: usize,
    /// Configurations left out of the calibration (and of the figures).
    pub excluded: usize,
}

/// The robot description.
#[derive(Clone, Debug)]
pub struct RobotSummary {
    pub name: String,
    pub builtin: bool,
    /// What the nominal model is (Table 3, or the URDF's joint origins).
    pub nominal_model: String,
    /// Per arm: its chain (`BASE → TIP`) and its joints' names.
    pub arms: PerSide<(String, Vec<String>)>,
}

/// How the parameters were identified, as the parameter file records it.
#[derive(Clone, Debug)]
pub struct MethodSummary {
    /// The `method` record; `Err` with the reason when the field is absent, free-form or does not read.
    pub record: Result<MethodRecord, String>,
    /// The `termination` record's stages (`None`: absent or unreadable).
    pub stages: Option<Vec<StageSummary>>,
    /// Whether every stage converged (the file's `converged` flag and the stages' terminations).
    pub converged: bool,
    /// The `statistics` record, if it reads.
    pub statistics: Option<StatisticsRecord>,
}

/// One arm's identifiability and parameters.
#[derive(Clone, Debug)]
pub struct ArmSummary {
    /// Every parameter of the arm's vector, in order.
    pub parameters: Vec<ParamRow>,
    /// The parameters held at their value, with why (`fixed_parameters`).
    pub fixed: Vec<FixedParameter>,
    /// The weak parameters, with why (`weak_parameters`; empty when the file has none).
    pub weak: Vec<crate::solver::weak::WeakParameter>,
    /// The `statistics.identifiability` record of the arm.
    pub conditioning: Option<ConditioningRecord>,
    pub uncertainty: Option<ArmUncertainty>,
    /// Where the σ come from.
    pub uncertainty_source: UncertaintySource,
}

/// Where the report's σ come from.
#[derive(Clone, Debug, PartialEq)]
pub enum UncertaintySource {
    /// The parameter file's `uncertainty` record.
    Recorded,
    /// Computed by the report from the data (the file has no record), as `dualcal calibrate` does.
    Computed,
    /// Neither: why.
    NotAvailable(String),
}

/// One parameter of an arm.
#[derive(Clone, Debug, PartialEq)]
pub struct ParamRow {
    pub name: String,
    /// An angle (rad; changes and σ in mrad) or a length (mm).
    pub angle: bool,
    /// Its unit when neither (an error parameter beyond geometry: `mrad/(N·m)`).
    pub unit: &'static str,
    pub nominal: f64,
    pub calibrated: f64,
    /// One standard deviation, mm or mrad (`None` for a fixed parameter or without uncertainty).
    pub sigma: Option<f64>,
    /// Held at its value: why.
    pub fixed: Option<String>,
}

impl ParamRow {
    /// The change in its display unit: mm, or mrad for an angle.
    pub fn change(&self) -> f64 {
        let d = self.calibrated - self.nominal;
        if self.angle { d * 1e3 } else { d }
    }
}

/// `left_base_from_right_base`, nominal and calibrated.
#[derive(Clone, Debug)]
pub struct BaseChange {
    pub nominal: Isometry3<f64>,
    pub calibrated: Isometry3<f64>,
}

/// The accuracy of the nominal and the calibrated model on one split.
#[derive(Clone, Debug)]
pub struct SplitAccuracy {
    pub split: Split,
    pub before: AccuracyReport,
    pub after: AccuracyReport,
}

/// The figures of the distance errors, before and after, on one split.
#[derive(Clone, Debug)]
pub struct Figures {
    /// The split shown (verification where it has enough configurations).
    pub split: Split,
    /// Per pair kind (left, right, collaborative): the histograms of every reflector's signed `Δd`,
    /// nominal and calibrated ([`crate::analysis::SplitFigures::histogram`]).
    pub histograms: Vec<(Indicator, Option<Histogram>, Option<Histogram>)>,
    /// Per pair kind: the box plot of the per-pair worst-reflector `Δd`, nominal and calibrated.
    pub boxes: Vec<(Indicator, Option<BoxStats>, Option<BoxStats>)>,
}

/// A configuration with a large error.
#[derive(Clone, Debug, PartialEq)]
pub struct WorstRow {
    pub id: String,
    pub split: Split,
    /// Largest |Δd| over every pair involving it, calibrated and nominal model, mm.
    pub worst_pos_mm: f64,
    pub nominal_worst_pos_mm: Option<f64>,
    /// Largest Δo, calibrated model, rad.
    pub worst_ori_rad: Option<f64>,
    /// Largest deviation of its reflectors' measured distances from the model's, mm.
    pub rigidity_mm: f64,
    pub excluded: bool,
    /// The screening's flag of it, if any (its kind's label).
    pub flag: Option<&'static str>,
}

/// The screening of the calibrated model.
#[derive(Clone, Debug)]
pub struct ScreeningSummary {
    /// The parameter file's `quality` record, or recomputed.
    pub recorded: bool,
    pub record: QualityRecord,
    /// The flagged configurations the calibration kept.
    pub kept_suspects: Vec<Flag>,
}

/// The figures' split: verification where both arms have two configurations there, else calibration.
fn shown_split(accuracy: &[SplitAccuracy]) -> Split {
    if accuracy.iter().any(|a| a.split == Split::Ver) {
        Split::Ver
    } else {
        Split::Cal
    }
}
