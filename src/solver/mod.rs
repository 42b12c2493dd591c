//! The paper's two-step minimax calibration (Algorithms I and II).
//!
//! Step 1 identifies each arm's DH parameters and reflector coordinates by minimising the maximum over
//! the reflectors of the summed squared relative distance errors; step 2 identifies the right-arm base
//! in the left-arm base frame by the same minimax over collaborative distance errors.
//!
//! The run is an executor loop around solver states that advance one outer SQP iteration per call;
//! observers receive an event per iteration and the caller's cancel flag is polled between (and inside)
//! iterations.

pub mod arm;
pub mod base;
pub mod identifiability;
pub mod lm;
pub mod problem;
pub mod qp;
pub mod sqp;

use crate::dataset::{Dataset, MIN_CONFIGS, SplitSelect};
use crate::kinematics::{DualArmModel, N_PARAMS, Side};
use arm::ArmProblem;
use base::BaseProblem;
use identifiability::IdentifiabilityReport;
use lm::LmState;
use nalgebra::{DMatrix, DVector, Vector3};
use problem::MinimaxProblem;
use serde::{Deserialize, Serialize};
use sqp::{SqpSettings, SqpState};
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

/// How the QP subproblem of each SQP iteration is solved.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum QpMethod {
    /// The paper's primal-dual subgradient method, eqs. (29)–(31).
    Paper,
    /// An exact dual active-set solution of the same QP.
    #[default]
    Exact,
}

/// Objective of the identification.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Method {
    /// The paper's minimax of the three reflectors' summed squared distance errors.
    #[default]
    Minimax,
    /// Ordinary least squares of all distance errors (Levenberg–Marquardt), for comparison.
    LeastSquares,
}

/// Settings of a calibration run.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CalibrationSettings {
    /// Configurations used for identification (`cal` or `all`).
    pub split: SplitSelect,
    pub method: Method,
    pub qp: QpMethod,
    /// Outer SQP iterations per stage.
    pub max_iterations: usize,
    /// Stop when the scaled parameter step norm falls below this.
    pub step_tolerance: f64,
    /// Also stop (as converged) when ψ fell by less than this, relative, over the last five outer
    /// iterations; 0 disables the rule and leaves only the step-norm test.
    #[serde(default = "default_progress_tolerance")]
    pub progress_tolerance: f64,
    /// Iterations of the paper's subgradient QP solver per outer iteration.
    pub max_qp_iterations: usize,
}

fn default_progress_tolerance() -> f64 {
    sqp::PROGRESS_RTOL
}

impl Default for CalibrationSettings {
    fn default() -> Self {
        Self {
            split: SplitSelect::Cal,
            method: Method::Minimax,
            qp: QpMethod::Exact,
            max_iterations: 100,
            step_tolerance: 1e-8,
            progress_tolerance: default_progress_tolerance(),
            max_qp_iterations: 2000,
        }
    }
}

/// Which part of the two-step calibration.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum Stage {
    /// Step 1: geometric parameters of one arm.
    Arm(Side),
    /// Step 2: right-arm base in the left-arm base frame.
    Base,
}

impl Termination {
    /// Whether the stage ended at a stationary point of its problem (to working precision).
    pub fn is_converged(self) -> bool {
        matches!(self, Termination::Converged | Termination::NoProgress)
    }
}

impl std::fmt::Display for Termination {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Termination::Converged => "converged",
            Termination::NoProgress => "converged (ψ stationary)",
            Termination::Stalled => "stalled above the optimum",
            Termination::MaxIterations => "iteration limit reached",
            Termination::Cancelled => "cancelled",
        })
    }
}

impl std::fmt::Display for Stage {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Stage::Arm(side) => write!(f, "step 1 ({side} arm)"),
            Stage::Base => f.write_str("step 2 (base)"),
        }
    }
}

/// One outer iteration's progress.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct IterationRecord {
    pub stage: Stage,
    pub iteration: usize,
    /// ψ = max_i F_i, mm².
    pub psi_mm2: f64,
    /// F_a, F_b, F_c, mm².
    pub f_mm2: [f64; 3],
    /// Norm of the scaled parameter step.
    pub step_norm: f64,
    /// KKT residual of the QP solution.
    pub kkt_residual: f64,
    /// Multipliers λ_a, λ_b, λ_c of the three reflectors' rows in this iteration's QP (summing to one):
    /// how much each reflector's F_k weighs in the step. The least-squares method weighs them equally.
    /// NaN when the iteration solved no QP.
    #[serde(default = "nan3")]
    pub lambda: [f64; 3],
    /// Time since the start of the whole run.
    pub elapsed_secs: f64,
}

fn nan3() -> [f64; 3] {
    [f64::NAN; 3]
}

/// Why a stage stopped.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Termination {
    /// Step norm below the tolerance, or no descent left: a KKT point.
    Converged,
    /// No further decrease of the merit function was possible, away from a KKT point.
    Stalled,
    /// The merit function changed by less than 1e-8 (relative) over the last 5 iterations: converged
    /// to working precision while the step norm is still above the tolerance (typically at a kink of
    /// the max where one active F_i has a vanishing multiplier, where SQP steps shrink only slowly).
    NoProgress,
    MaxIterations,
    Cancelled,
}

/// Progress events delivered to an observer.
#[derive(Clone, Debug, PartialEq)]
pub enum CalibrationEvent {
    /// A stage begins: `n_configs` configurations (both arms' for step 2) and `n_pairs` pairs per
    /// reflector.
    StageStarted {
        stage: Stage,
        n_configs: usize,
        n_pairs: usize,
    },
    Iteration(IterationRecord),
    StageFinished {
        stage: Stage,
        termination: Termination,
    },
}

/// Typed failures of a calibration.
#[derive(Debug, thiserror::Error)]
pub enum CalibrationError {
    #[error(
        "{side} arm: {found} configurations in the selected split, at least {needed} are needed (paper Table 2)"
    )]
    TooFewConfigurations {
        side: Side,
        found: usize,
        needed: usize,
    },
    #[error("{stage}: the identification Jacobian is rank deficient: {detail}")]
    RankDeficient { stage: Stage, detail: String },
    #[error("{stage}: non-finite value ({detail})")]
    NonFinite { stage: Stage, detail: String },
    #[error(
        "{stage}: not converged after {iterations} iterations (last step norm {step_norm:.3e}, ψ {psi_mm2:.6} mm²)"
    )]
    NotConverged {
        stage: Stage,
        iterations: usize,
        step_norm: f64,
        psi_mm2: f64,
    },
    #[error("cancelled")]
    Cancelled,
}

/// Summary of one stage.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct StageSummary {
    pub stage: Stage,
    pub n_configs: usize,
    pub iterations: usize,
    pub termination: Termination,
    /// Final ψ and F_i (sums of squares over all pairs), mm².
    pub psi_mm2: f64,
    pub f_mm2: [f64; 3],
    /// Initial ψ, mm².
    pub psi_start_mm2: f64,
}

/// Result of a successful two-step calibration.
#[derive(Clone, Debug)]
pub struct CalibrationResult {
    pub nominal: DualArmModel,
    pub calibrated: DualArmModel,
    pub settings: CalibrationSettings,
    pub history: Vec<IterationRecord>,
    pub stages: Vec<StageSummary>,
    /// Which parameters of each arm were identified and which fixed, and why.
    pub identifiability: Vec<(Side, IdentifiabilityReport)>,
    /// Allowed deviation δ of the reflector triangle's sides (constraint 14, ε = δ²), mm, per arm.
    pub side_tolerance_mm: Vec<(Side, f64)>,
    pub elapsed_secs: f64,
}

impl CalibrationResult {
    /// Per-pair residuals of the calibrated model on the identification split: every relative pair of
    /// `side` (`Some`) or every collaborative left × right pair (`None`), with the signed Δd per reflector
    /// and Δo (computed on demand: at 1000 configurations per arm these are 500 000 pairs).
    pub fn pair_residuals(
        &self,
        dataset: &Dataset,
        side: Option<Side>,
    ) -> Result<Vec<crate::metrics::PairError>, crate::metrics::MetricsError> {
        let kind = match side {
            Some(side) => crate::metrics::PairKind::Relative(side),
            None => crate::metrics::PairKind::Collaborative,
        };
        crate::metrics::pairs(dataset, &self.calibrated, self.settings.split, kind)
    }

    /// One warning per stage that stopped above its optimum (`Stalled`); empty when all converged.
    /// The command line and the workbench both show these.
    pub fn stall_warnings(&self) -> Vec<String> {
        self.stages
            .iter()
            .filter(|s| !s.termination.is_converged())
            .map(|s| {
                format!(
                    "{} stopped where the exact QP still predicts a decrease of ψ by more than {:.0e} \
                     of itself; the parameters are usable but not optimal{}",
                    s.stage,
                    sqp::STATIONARY_RTOL,
                    if self.settings.qp == QpMethod::Paper {
                        " (the paper's subgradient QP is inexact: try the exact QP)"
                    } else {
                        ""
                    }
                )
            })
            .collect()
    }

    /// The `dualcal-params/1` file of this result: the calibrated model plus method, fixed parameters
    /// and why, per-stage termination, accuracy on the cal and ver splits of `dataset`, conditioning and
    /// provenance. The command line and the workbench both export this.
    pub fn params_file(&self, dataset: &Dataset) -> crate::params::ParamsFile {
        use crate::params::{FixedParameter, FixedParameters, ParamsFile, Provenance};
        let finite_or_null = |v: f64| {
            if v.is_finite() {
                serde_json::json!(v)
            } else {
                serde_json::Value::Null
            }
        };
        let mut file = ParamsFile::from_model(&self.calibrated);
        file.method = Some(serde_json::json!({
            "name": "two-step minimax calibration (paper Algorithms I and II)",
            "objective": format!("{:?}", self.settings.method),
            "qp": format!("{:?}", self.settings.qp),
            "split": format!("{:?}", self.settings.split),
            "max_iterations": self.settings.max_iterations,
            "step_tolerance": self.settings.step_tolerance,
            "progress_tolerance": self.settings.progress_tolerance,
        }));
        let fixed = |side: Side| -> Vec<FixedParameter> {
            self.identifiability
                .iter()
                .filter(|(s, _)| *s == side)
                .flat_map(|(_, rep)| {
                    rep.fixed.iter().map(|f| FixedParameter {
                        name: f.name.clone(),
                        reason: f.reason.clone(),
                    })
                })
                .collect()
        };
        file.fixed_parameters = Some(FixedParameters {
            left: fixed(Side::Left),
            right: fixed(Side::Right),
        });
        file.termination = Some(serde_json::json!(self.stages));
        let stats = |split| crate::metrics::evaluate(dataset, &self.calibrated, split).ok();
        let conditioning: serde_json::Map<String, serde_json::Value> = self
            .identifiability
            .iter()
            .map(|(side, rep)| {
                (
                    side.name().to_string(),
                    serde_json::json!({
                        "identified": rep.free.len(),
                        "condition_before": finite_or_null(rep.condition_before),
                        "condition_after": finite_or_null(rep.condition_after),
                    }),
                )
            })
            .collect();
        let tolerances: serde_json::Map<String, serde_json::Value> = self
            .side_tolerance_mm
            .iter()
            .map(|(s, t)| (s.name().to_string(), serde_json::json!(t)))
            .collect();
        file.statistics = Some(serde_json::json!({
            "cal": stats(SplitSelect::Cal),
            "ver": stats(SplitSelect::Ver),
            "identifiability": conditioning,
            "reflector_side_tolerance_mm": tolerances,
            "elapsed_secs": self.elapsed_secs,
        }));
        file.provenance = Some(Provenance::now(Some(&dataset.dir)));
        file
    }

    /// Per-configuration residuals of the calibrated model on the given split (worst |Δd| involving each
    /// configuration, its orientation errors and its reflector-triangle rigidity).
    pub fn config_residuals(
        &self,
        dataset: &Dataset,
        split: SplitSelect,
    ) -> Result<Vec<crate::metrics::ConfigError>, crate::metrics::MetricsError> {
        crate::metrics::per_config(dataset, &self.calibrated, split)
    }
}

/// Either solver of a stage.
enum Runner<P: MinimaxProblem> {
    Sqp(Box<SqpState<P>>),
    Lm(Box<LmState<P>>),
}

impl<P: MinimaxProblem> Runner<P> {
    fn y(&self) -> &DVector<f64> {
        match self {
            Runner::Sqp(s) => &s.y,
            Runner::Lm(s) => &s.y,
        }
    }

    fn problem(&self) -> &P {
        match self {
            Runner::Sqp(s) => &s.problem,
            Runner::Lm(s) => &s.problem,
        }
    }

    /// One outer iteration.
    fn step(&mut self, stop: &dyn Fn() -> bool) -> RunnerStep {
        match self {
            Runner::Sqp(s) => {
                let r = s.step_with_stop(stop);
                RunnerStep {
                    f: r.f,
                    step_norm: r.step_norm,
                    residual: r.kkt_residual,
                    lambda: r.lambda,
                    termination: r.termination,
                }
            }
            Runner::Lm(s) => {
                let r = s.step();
                RunnerStep {
                    f: r.f,
                    step_norm: r.step_norm,
                    residual: r.gradient_norm,
                    lambda: [1.0 / 3.0; 3],
                    termination: r.termination,
                }
            }
        }
    }
}

/// What one outer iteration of either method reports.
struct RunnerStep {
    f: [f64; 3],
    step_norm: f64,
    /// KKT residual (SQP) or gradient norm (LM).
    residual: f64,
    lambda: [f64; 3],
    termination: Option<Termination>,
}

enum StageState {
    Arm {
        side: Side,
        runner: Box<Runner<ArmProblem>>,
    },
    Base {
        runner: Box<Runner<BaseProblem>>,
    },
    Done,
}

/// Per-arm measurements of the selected split.
struct ArmInput {
    qs: Vec<[f64; 7]>,
    measured: Vec<[Vector3<f64>; 3]>,
    side_tolerance_mm: f64,
}

/// Outcome of [`Calibration::step`].
#[derive(Debug)]
pub enum Progress {
    Running,
    Finished(Box<CalibrationResult>),
}

/// A two-step calibration that advances one outer iteration per [`Calibration::step`] call, so it can
/// run on a worker thread (see [`calibrate`]) or be stepped from a UI frame loop.
pub struct Calibration {
    settings: CalibrationSettings,
    nominal: DualArmModel,
    current: DualArmModel,
    inputs: [ArmInput; 2],
    state: StageState,
    stage_iterations: usize,
    stage_start_psi: f64,
    history: Vec<IterationRecord>,
    stages: Vec<StageSummary>,
    identifiability: Vec<(Side, IdentifiabilityReport)>,
    started: Instant,
    pending_start: bool,
}

/// Pairs per reflector sampled for identifiability, column scaling and the start Hessian.
const IDENTIFIABILITY_PAIRS: usize = 3000;

fn side_index(side: Side) -> usize {
    match side {
        Side::Left => 0,
        Side::Right => 1,
    }
}

impl Calibration {
    pub fn new(
        dataset: &Dataset,
        nominal: &DualArmModel,
        settings: &CalibrationSettings,
    ) -> Result<Self, CalibrationError> {
        let input = |side: Side| -> Result<ArmInput, CalibrationError> {
            let ms = dataset.arm(side).select(settings.split);
            if ms.len() < MIN_CONFIGS {
                return Err(CalibrationError::TooFewConfigurations {
                    side,
                    found: ms.len(),
                    needed: MIN_CONFIGS,
                });
            }
            let qs: Vec<[f64; 7]> = ms.iter().map(|m| m.q_rad).collect();
            let measured: Vec<[Vector3<f64>; 3]> = ms.iter().map(|m| m.tracker_points_mm).collect();
            if qs
                .iter()
                .flatten()
                .chain(measured.iter().flatten().flat_map(|v| v.iter()))
                .any(|v| !v.is_finite())
            {
                return Err(CalibrationError::NonFinite {
                    stage: Stage::Arm(side),
                    detail: "measurement data".into(),
                });
            }
            // ε of constraint (14): the tracker's MPE at the mean measuring distance, squared.
            let mean_dist_m = measured.iter().flatten().map(|p| p.norm()).sum::<f64>()
                / (3.0 * measured.len() as f64)
                / 1000.0;
            let side_tolerance_mm =
                (dataset.tracker.mpe_um + dataset.tracker.mpe_um_per_m * mean_dist_m) / 1000.0;
            Ok(ArmInput {
                qs,
                measured,
                side_tolerance_mm,
            })
        };
        let inputs = [input(Side::Left)?, input(Side::Right)?];
        let mut cal = Self {
            settings: settings.clone(),
            nominal: nominal.clone(),
            current: nominal.clone(),
            inputs,
            state: StageState::Done,
            stage_iterations: 0,
            stage_start_psi: 0.0,
            history: Vec::new(),
            stages: Vec::new(),
            identifiability: Vec::new(),
            started: Instant::now(),
            pending_start: true,
        };
        cal.state = cal.start_arm(Side::Left)?;
        Ok(cal)
    }

    fn sqp_settings(&self) -> SqpSettings {
        SqpSettings {
            qp: self.settings.qp,
            step_tolerance: self.settings.step_tolerance,
            progress_tolerance: self.settings.progress_tolerance,
            max_qp_iterations: self.settings.max_qp_iterations,
        }
    }

    fn start_arm(&mut self, side: Side) -> Result<StageState, CalibrationError> {
        let stage = Stage::Arm(side);
        let input = &self.inputs[side_index(side)];
        let start = self.nominal.arm(side).clone();
        let all: Vec<usize> = (0..N_PARAMS).collect();
        let probe = ArmProblem::new(
            input.qs.clone(),
            &input.measured,
            &start,
            all,
            DVector::from_element(N_PARAMS, 1.0),
            input.side_tolerance_mm,
        );
        // A few thousand pairs show every dependency (they are exact) and estimate the scaling well.
        let rows = probe.sample_pair_jacobian(&DVector::zeros(N_PARAMS), IDENTIFIABILITY_PAIRS);
        let (report, gram) = identifiability::analyse_with_gram(&rows, &[true; N_PARAMS]);
        if report.free.is_empty() {
            return Err(CalibrationError::RankDeficient {
                stage,
                detail: "no parameter is identifiable from these configurations".into(),
            });
        }
        // Scale every free parameter by its RMS sensitivity; H₀ is the Gauss–Newton matrix in those
        // variables, 2·D·G·D with G the mean Gram matrix of the pair Jacobian.
        let scale = DVector::from_iterator(
            report.free.len(),
            report
                .free
                .iter()
                .map(|&k| 1.0 / gram[(k, k)].sqrt().max(1e-12)),
        );
        let h0 = DMatrix::from_fn(report.free.len(), report.free.len(), |i, j| {
            2.0 * gram[(report.free[i], report.free[j])] * scale[i] * scale[j]
        });
        let problem = probe.with_free(report.free.clone(), scale);
        self.identifiability.retain(|(s, _)| *s != side);
        self.identifiability.push((side, report));
        let runner = self.make_runner(problem, stage, Some(h0))?;
        Ok(StageState::Arm {
            side,
            runner: Box::new(runner),
        })
    }

    fn start_base(&mut self) -> Result<StageState, CalibrationError> {
        let stage = Stage::Base;
        let [l, r] = &self.inputs;
        let left_mm =
            l.qs.iter()
                .map(|q| self.current.left.reflector_fk(q).points_mm)
                .collect();
        let right_mm =
            r.qs.iter()
                .map(|q| self.current.right.reflector_fk(q).points_mm)
                .collect();
        let problem = BaseProblem::new(
            left_mm,
            right_mm,
            &l.measured,
            &r.measured,
            self.nominal.left_base_from_right_base,
        );
        let h = problem.gauss_newton(&DVector::zeros(6));
        let sv = h.singular_values();
        if sv.min() <= sv.max() * 1e-12 {
            return Err(CalibrationError::RankDeficient {
                stage,
                detail: format!("collaborative Jacobian singular values {:?}", sv.as_slice()),
            });
        }
        let runner = self.make_runner(problem, stage, None)?;
        Ok(StageState::Base {
            runner: Box::new(runner),
        })
    }

    fn make_runner<P: MinimaxProblem>(
        &mut self,
        problem: P,
        stage: Stage,
        h0: Option<DMatrix<f64>>,
    ) -> Result<Runner<P>, CalibrationError> {
        self.stage_iterations = 0;
        self.pending_start = true;
        let runner = match self.settings.method {
            Method::Minimax => {
                let settings = self.sqp_settings();
                let state = match h0 {
                    Some(h0) => SqpState::with_hessian(problem, settings, h0),
                    None => SqpState::new(problem, settings),
                };
                Runner::Sqp(Box::new(state.map_err(|_| {
                    CalibrationError::NonFinite {
                        stage,
                        detail: "objective or gradient at the start point".into(),
                    }
                })?))
            }
            Method::LeastSquares => Runner::Lm(Box::new(LmState::new(
                problem,
                self.settings.step_tolerance,
            ))),
        };
        let (f, _) = runner.problem().values(runner.y());
        self.stage_start_psi = f.iter().copied().fold(f64::NEG_INFINITY, f64::max)
            * runner.problem().pair_count() as f64;
        Ok(runner)
    }

    /// The stage that the next [`Calibration::step`] advances (`None` when finished).
    pub fn stage(&self) -> Option<Stage> {
        match &self.state {
            StageState::Arm { side, .. } => Some(Stage::Arm(*side)),
            StageState::Base { .. } => Some(Stage::Base),
            StageState::Done => None,
        }
    }

    /// The model as it stands (calibrated arms so far, current base estimate).
    pub fn current_model(&self) -> DualArmModel {
        let mut m = self.current.clone();
        match &self.state {
            StageState::Arm { side, runner } => {
                *m.arm_mut(*side) = runner.problem().model_at(runner.y())
            }
            StageState::Base { runner } => {
                m.left_base_from_right_base = runner.problem().transform_at(runner.y())
            }
            StageState::Done => {}
        }
        m
    }

    /// Advance one outer iteration, reporting to `observer`.
    pub fn step(
        &mut self,
        observer: &mut dyn FnMut(&CalibrationEvent),
    ) -> Result<Progress, CalibrationError> {
        self.step_cancellable(observer, &AtomicBool::new(false))
    }

    /// [`Calibration::step`], polling `cancel` inside long iterations (the paper's QP solver) too.
    pub fn step_cancellable(
        &mut self,
        observer: &mut dyn FnMut(&CalibrationEvent),
        cancel: &AtomicBool,
    ) -> Result<Progress, CalibrationError> {
        if cancel.load(Ordering::Relaxed) {
            return Err(CalibrationError::Cancelled);
        }
        let stop = || cancel.load(Ordering::Relaxed);
        let Some(stage) = self.stage() else {
            return Ok(Progress::Finished(Box::new(self.result())));
        };
        if self.pending_start {
            self.pending_start = false;
            let (n_configs, n_pairs) = match stage {
                Stage::Arm(side) => {
                    let n = self.inputs[side_index(side)].qs.len();
                    (n, n * n.saturating_sub(1) / 2)
                }
                Stage::Base => {
                    let (l, r) = (self.inputs[0].qs.len(), self.inputs[1].qs.len());
                    (l + r, l * r)
                }
            };
            observer(&CalibrationEvent::StageStarted {
                stage,
                n_configs,
                n_pairs,
            });
        }
        let (r, pairs) = match &mut self.state {
            StageState::Arm { runner, .. } => (runner.step(&stop), runner.problem().pair_count()),
            StageState::Base { runner } => (runner.step(&stop), runner.problem().pair_count()),
            StageState::Done => unreachable!("handled above"),
        };
        let (f, step_norm, term) = (r.f, r.step_norm, r.termination);
        if term == Some(Termination::Cancelled) {
            return Err(CalibrationError::Cancelled);
        }
        self.stage_iterations += 1;
        let f_mm2 = f.map(|v| v * pairs as f64);
        let psi_mm2 = f_mm2.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        if !psi_mm2.is_finite() || !step_norm.is_finite() {
            return Err(CalibrationError::NonFinite {
                stage,
                detail: format!("ψ = {psi_mm2}, step norm = {step_norm}"),
            });
        }
        let record = IterationRecord {
            stage,
            iteration: self.stage_iterations,
            psi_mm2,
            f_mm2,
            step_norm,
            kkt_residual: r.residual,
            lambda: r.lambda,
            elapsed_secs: self.started.elapsed().as_secs_f64(),
        };
        observer(&CalibrationEvent::Iteration(record.clone()));
        self.history.push(record);
        let termination = term.or((self.stage_iterations >= self.settings.max_iterations)
            .then_some(Termination::MaxIterations));
        let Some(termination) = termination else {
            return Ok(Progress::Running);
        };
        if termination == Termination::MaxIterations {
            return Err(CalibrationError::NotConverged {
                stage,
                iterations: self.stage_iterations,
                step_norm,
                psi_mm2,
            });
        }
        observer(&CalibrationEvent::StageFinished { stage, termination });
        let n_configs = match stage {
            Stage::Arm(side) => self.inputs[side_index(side)].qs.len(),
            Stage::Base => self.inputs[0].qs.len() + self.inputs[1].qs.len(),
        };
        self.stages.push(StageSummary {
            stage,
            n_configs,
            iterations: self.stage_iterations,
            termination,
            psi_mm2,
            f_mm2,
            psi_start_mm2: self.stage_start_psi,
        });
        // Commit the stage's parameters and start the next stage.
        self.current = self.current_model();
        self.state = match stage {
            Stage::Arm(Side::Left) => self.start_arm(Side::Right)?,
            Stage::Arm(Side::Right) => self.start_base()?,
            Stage::Base => StageState::Done,
        };
        Ok(match self.state {
            StageState::Done => Progress::Finished(Box::new(self.result())),
            _ => Progress::Running,
        })
    }

    fn result(&self) -> CalibrationResult {
        CalibrationResult {
            nominal: self.nominal.clone(),
            calibrated: self.current.clone(),
            settings: self.settings.clone(),
            history: self.history.clone(),
            stages: self.stages.clone(),
            identifiability: self.identifiability.clone(),
            side_tolerance_mm: vec![
                (Side::Left, self.inputs[0].side_tolerance_mm),
                (Side::Right, self.inputs[1].side_tolerance_mm),
            ],
            elapsed_secs: self.started.elapsed().as_secs_f64(),
        }
    }
}

/// Run the two-step calibration (step 1 for each arm, then step 2), reporting to `observer` and
/// polling `cancel` between outer iterations (each takes milliseconds on paper-size data) and inside
/// the paper's QP solver (every 256 subgradient iterations).
pub fn calibrate(
    dataset: &Dataset,
    nominal: &DualArmModel,
    settings: &CalibrationSettings,
    observer: &mut dyn FnMut(&CalibrationEvent),
    cancel: &AtomicBool,
) -> Result<CalibrationResult, CalibrationError> {
    let mut cal = Calibration::new(dataset, nominal, settings)?;
    loop {
        if let Progress::Finished(result) = cal.step_cancellable(observer, cancel)? {
            return Ok(*result);
        }
    }
}
