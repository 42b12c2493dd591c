//! What a calibration run returns, however it ended.

use crate::dataset::{Dataset, Split};
use crate::kinematics::DualArmModel;
use crate::metrics::{ConfigResiduals, MetricsError, PairKind, PairResiduals};
use crate::side::{PerSide, Side};
use crate::solver::analysis::identifiability::IdentifiabilityReport;
use crate::solver::analysis::uncertainty::PairSums;
use crate::solver::settings::CalibrationSettings;
use crate::solver::types::{
    IterationRecord, QpMethod, Reflector, Stage, StageSummary, Termination, WeakParameter,
};
use nalgebra::Isometry3;
use std::sync::Arc;

/// The stages of a two-step calibration, in the order they run (arms that share no joint).
pub const STAGES: [Stage; 3] = [Stage::Arm(Side::Left), Stage::Arm(Side::Right), Stage::Base];

/// The outcome of a calibration run: the model reached, the history and, per stage, why it ended.
/// A run that hit the iteration limit or was cancelled returns one too ([`CalibrationResult::is_converged`]
/// tells).
#[derive(Clone, Debug)]
pub struct CalibrationResult {
    pub nominal: DualArmModel,
    /// The model reached: the stages that ran, at their final iterates; the nominal values for the
    /// parts of stages that did not run.
    pub calibrated: DualArmModel,
    pub settings: CalibrationSettings,
    pub history: Vec<IterationRecord>,
    /// The stages that ran (left arm, right arm, base), each with its termination.
    pub stages: Vec<StageSummary>,
    /// Which parameters of each arm were identified and which fixed, and why (`None` for an arm whose
    /// stage did not start).
    pub identifiability: PerSide<Option<IdentifiabilityReport>>,
    /// The same analysis repeated at each arm's solution (`None` for an arm whose stage did not end
    /// normally); [`CalibrationResult::warnings`] reports parameters that lost their identifiability.
    pub identifiability_at_solution: PerSide<Option<IdentifiabilityReport>>,
    /// What the run found wrong on the way (divergence, non-finite values, dependencies at the
    /// solution), one sentence each; part of [`CalibrationResult::warnings`].
    pub diagnostics: Vec<String>,
    /// Allowed deviation δ of the reflector triangle's sides (constraint 14, ε = δ²), mm, per arm.
    pub side_tolerance_mm: PerSide<f64>,
    /// The reflector each arm's step 1 used, for [`crate::solver::Method::DistanceSingle`] (`None` otherwise
    /// or for an arm whose stage did not start).
    pub reflector_used: PerSide<Option<Reflector>>,
    /// Each arm's model base in the tracker frame, where a method identified it (the absolute methods
    /// [`crate::solver::Method::Pose`], [`crate::solver::Method::Position`] in step 1 and
    /// [`crate::solver::BaseMethod::Absolute`] in step 2, which overrides step 1's); `None` for the distance
    /// methods, which cannot see it.
    pub tracker_from_base: PerSide<Option<Isometry3<f64>>>,
    /// Why step 2 was not run, when the data cannot measure the base (the arms were measured from
    /// different tracker stations): the base stays nominal and is no calibration result.
    pub base_not_measurable: Option<String>,
    /// The arm measured alone, when the dataset has one arm only: its stage is the only one (the
    /// other arm keeps its nominal parameters, and has no figures).
    pub alone: Option<Side>,
    /// Each arm's weak parameters ([`crate::solver::weak`]): identified, but barely constrained
    /// across the workspace; held at their nominal values unless the settings keep them
    /// ([`CalibrationSettings::keep_weak`]). Empty for the methods the analysis does not cover.
    pub weak: PerSide<Vec<WeakParameter>>,
    /// Each arm's pair sums at its step-1 solution, which the identifiability re-check and the
    /// weak-parameter analysis took ([`crate::solver::CalibrationRun::pair_sums`]):
    /// [`crate::solver::uncertainty::for_result`] takes the arm's σ from them instead of a pass of its
    /// own. `None` for the methods that do not fit distances and for a cancelled stage.
    pub pair_sums: PerSide<Option<Arc<PairSums>>>,
    pub elapsed_secs: f64,
}

impl CalibrationResult {
    /// Did every stage run and converge?
    pub fn is_converged(&self) -> bool {
        self.stages.len() == self.planned_stages().count()
            && self.stages.iter().all(|s| s.termination.is_converged())
    }

    /// The stages the data call for: both arms, and the base unless it is not measurable.
    /// (Arms that share joints: both in one stage, [`Stage::Arms`]; one arm measured alone: its
    /// stage only.)
    pub fn planned_stages(&self) -> impl Iterator<Item = Stage> + '_ {
        let arms: Vec<Stage> = match self.alone {
            Some(side) => vec![Stage::Arm(side)],
            None if self.nominal.shared_joints().is_empty() => STAGES[..2].to_vec(),
            None => vec![Stage::Arms],
        };
        arms.into_iter()
            .chain((self.base_not_measurable.is_none()).then_some(Stage::Base))
    }

    /// Was `stage` solved by the paper's SQP (the minimax methods) rather than least squares?
    pub fn uses_sqp(&self, stage: Stage) -> bool {
        let solver = match stage {
            Stage::Arm(_) | Stage::Arms => self.settings.method.spec().solver,
            Stage::Base => self.settings.base_method.spec().solver,
        };
        solver == crate::solver::methods::spec::SolverKind::Sqp
    }

    /// The summary of `stage`, if it ran.
    pub fn stage(&self, stage: Stage) -> Option<&StageSummary> {
        self.stages.iter().find(|s| s.stage == stage)
    }

    /// One warning per stage that did not converge, one for each stage that did not run, and the
    /// run's diagnostics (divergence, non-finite values, parameters no longer identifiable at the
    /// solution); empty when all is well. The command line and the workbench both show these.
    pub fn warnings(&self) -> Vec<String> {
        let mut out: Vec<String> = self
            .stages
            .iter()
            .filter(|s| !s.termination.is_converged())
            .map(|s| match s.termination {
                Termination::MaxIterations => format!(
                    "{} stopped at the iteration limit ({} iterations) before converging; the \
                     parameters are those reached (raise the iteration limit to continue)",
                    s.stage, s.iterations
                ),
                Termination::Cancelled => format!(
                    "{} was cancelled after {} iterations; the parameters are those reached",
                    s.stage, s.iterations
                ),
                Termination::Diverged | Termination::NonFinite => format!(
                    "{} {} after {} iterations; the parameters are the last plausible ones, not a \
                     calibration",
                    s.stage, s.termination, s.iterations
                ),
                _ if !self.uses_sqp(s.stage) => format!(
                    "{} stopped where the Gauss–Newton model still predicts a decrease of the cost \
                     by more than {:.0e} of itself; the parameters are usable but not optimal",
                    s.stage,
                    crate::solver::algorithms::least_squares::STATIONARY_RTOL,
                ),
                _ => format!(
                    "{} stopped where the exact QP still predicts a decrease of ψ by more than {:.0e} \
                     of itself; the parameters are usable but not optimal{}",
                    s.stage,
                    crate::solver::algorithms::sqp::STATIONARY_RTOL,
                    if self.settings.qp == QpMethod::Paper {
                        " (the paper's subgradient QP is inexact: try the exact QP)"
                    } else {
                        ""
                    }
                ),
            })
            .collect();
        for stage in self.planned_stages() {
            if self.stage(stage).is_none() {
                out.push(format!("{stage} did not run; its parameters are nominal"));
            }
        }
        if let Some(why) = &self.base_not_measurable {
            out.push(format!(
                "{} not measurable from this data ({why}): the right-arm base stays nominal",
                Stage::Base
            ));
        }
        out.extend(self.diagnostics.iter().cloned());
        out
    }

    /// Per-pair residuals of the calibrated model on the identification split: every relative pair of
    /// `side` (`Some`) or every collaborative left × right pair (`None`), with the signed Δd per reflector
    /// and Δo (computed on demand: at 1000 configurations per arm these are 500 000 pairs).
    pub fn pair_residuals(
        &self,
        dataset: &Dataset,
        side: Option<Side>,
    ) -> Result<Vec<PairResiduals>, MetricsError> {
        let kind = match side {
            Some(side) => PairKind::Relative(side),
            None => PairKind::Collaborative,
        };
        crate::metrics::pairs(dataset, &self.calibrated, self.settings.split, kind)
    }

    /// Per-configuration residuals of the calibrated model on the given split (worst |Δd| involving each
    /// configuration, its orientation errors and its reflector-triangle rigidity).
    pub fn config_residuals(
        &self,
        dataset: &Dataset,
        split: Split,
    ) -> Result<Vec<ConfigResiduals>, MetricsError> {
        crate::metrics::per_config(dataset, &self.calibrated, split)
    }
}
