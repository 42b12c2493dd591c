//! What a method's set-up works with — its stage's data, the start model, the settings — and the steps
//! the methods share: the distance identifiability analysis (the one prologue of the set-ups and of
//! the executor's re-check at the solution), column scaling, the start of the tracker frame, and the
//! solvers.

use crate::kinematics::{ArmModel, DualArmModel, SharedJoints};
use crate::side::{PerSide, Side};
use crate::solver::algorithms::least_squares::{LeastSquaresProblem, LsqAlgorithm, LsqState};
use crate::solver::algorithms::sqp::{SqpSettings, SqpState};
use crate::solver::algorithms::stage::StageSolver;
use crate::solver::analysis::identifiability::{
    self, Analysis, Columns, IdentifiabilityReport, ParameterInfo, analyse_columns,
};
use crate::solver::error::CalibrationError;
use crate::solver::problems::absolute_problem::{
    AbsoluteData, AbsoluteProblem, as_triangle, moore_penrose_fit, triangle_area_mm2,
};
use crate::solver::problems::arm_problem::ArmProblem;
use crate::solver::problems::base_problem::BaseProblem;
use crate::solver::problems::problem::MinimaxProblem;
use crate::solver::problems::tree_problem::{TreeLayout, TreeProblem};
use crate::solver::types::{Reflector, Stage, StageOptions};
use nalgebra::{DMatrix, DVector, Isometry3, Vector3};

/// The reason of a parameter held as weak ([`ArmSetUp::held`]).
pub const HELD_WEAK: &str = "held at its nominal value: a weak parameter, barely constrained by these \
                             configurations across the workspace (--keep-weak fits it)";

/// Pairs per reflector sampled for identifiability, column scaling and the start Hessian.
pub const IDENTIFIABILITY_PAIRS: usize = 3000;

/// One arm's measurements of the selected split (exclusions left out), checked.
#[derive(Clone, Debug)]
pub struct ArmData {
    pub side: Side,
    /// The configurations' ids (for messages).
    pub ids: Vec<String>,
    pub qs: Vec<Vec<f64>>,
    /// Tracker-frame reflector positions, one per reflector per configuration, mm.
    pub measured: Vec<Vec<Vector3<f64>>>,
    /// Allowed deviation δ of the reflector triangle's sides (constraint 14, ε = δ²), mm.
    pub side_tolerance_mm: f64,
}

impl ArmData {
    /// No data: the arm a dataset of the other arm alone does not have (no stage fits it).
    pub fn none(side: Side) -> Self {
        Self {
            side,
            ids: Vec::new(),
            qs: Vec::new(),
            measured: Vec::new(),
            side_tolerance_mm: f64::NAN,
        }
    }

    /// The distance problem of `arm` on these data with every parameter free at unit scale (the
    /// probe of the identifiability analysis; [`ArmProblem::with_free`] makes it the stage's).
    pub fn distance_probe(&self, arm: &ArmModel) -> ArmProblem {
        let n_params = arm.param_count();
        ArmProblem::new(
            self.qs.clone(),
            &self.measured,
            arm,
            (0..n_params).collect(),
            DVector::from_element(n_params, 1.0),
            self.side_tolerance_mm,
        )
    }

    /// The start of `tracker_from_base` for `arm`: the Moore–Penrose fit of its model points to the
    /// measured ones.
    pub fn tracker_start(&self, arm: &ArmModel) -> Result<Isometry3<f64>, CalibrationError> {
        let model: Vec<Vector3<f64>> = self
            .qs
            .iter()
            .flat_map(|q| arm.reflector_fk(q).points_mm)
            .collect();
        let measured: Vec<Vector3<f64>> = self.measured.iter().flatten().copied().collect();
        moore_penrose_fit(&model, &measured).ok_or_else(|| CalibrationError::NonFinite {
            stage: Stage::Arm(self.side),
            detail: "the tracker-from-base fit of the start model".into(),
        })
    }

    /// An absolute problem of `arm` on these data with the parameters `free` (unit scales), or the
    /// typed error of a configuration whose measured reflectors are collinear (pose data).
    pub fn absolute_probe(
        &self,
        data: AbsoluteData,
        arm: &ArmModel,
        free: Vec<usize>,
    ) -> Result<AbsoluteProblem, CalibrationError> {
        if matches!(data, AbsoluteData::Pose { .. }) && arm.reflector_count() != 3 {
            return Err(CalibrationError::NeedsThreeReflectors {
                side: self.side,
                found: arm.reflector_count(),
            });
        }
        let t0 = self.tracker_start(arm)?;
        self.absolute_problem(data, arm, t0, free)
    }

    /// An absolute problem of `arm` on these data from the transform `t0` with the parameters `free`
    /// (unit scales), or the typed error of a configuration whose measured reflectors are collinear.
    pub fn absolute_problem(
        &self,
        data: AbsoluteData,
        arm: &ArmModel,
        t0: Isometry3<f64>,
        free: Vec<usize>,
    ) -> Result<AbsoluteProblem, CalibrationError> {
        let scale = DVector::from_element(free.len() + 6, 1.0);
        AbsoluteProblem::new(
            data,
            self.side,
            self.qs.clone(),
            self.measured.clone(),
            arm,
            t0,
            free,
            scale,
        )
        .map_err(|i| CalibrationError::DegenerateReflectors {
            side: self.side,
            id: self.ids[i].clone(),
            area_mm2: as_triangle(&self.measured[i]).map_or(0.0, |t| triangle_area_mm2(t).0),
        })
    }
}

/// The identifiability analysis of `arm`'s distances on `probe` (its every parameter free at unit
/// scale, [`ArmData::distance_probe`], restricted to the reflectors it fits): the mean Gram matrix of
/// [`IDENTIFIABILITY_PAIRS`] sampled pairs per reflector — a few thousand show every dependency (they
/// are exact) and estimate the scaling well — and the report. The set-ups of the distance methods run
/// it at the start model, the executor again at the solution.
pub fn distance_identifiability(
    probe: &ArmProblem,
    arm: &ArmModel,
    analysis: &Analysis,
) -> (DMatrix<f64>, IdentifiabilityReport) {
    let n_params = arm.param_count();
    let start = DVector::zeros(n_params);
    let gram = probe.sample_pair_jacobian_gram(&start, IDENTIFIABILITY_PAIRS);
    let report = analyse_columns(
        &gram,
        &Columns::Arm {
            arm,
            transform: None,
        },
        analysis,
    );
    (gram, report)
}

/// Scales `1/√G_kk` of the columns `idx` of a mean Gram matrix (unit RMS sensitivity).
pub fn column_scales(gram: &DMatrix<f64>, idx: impl Iterator<Item = usize>) -> Vec<f64> {
    idx.map(|k| 1.0 / gram[(k, k)].max(0.0).sqrt().max(1e-12))
        .collect()
}

/// The start of the distance methods on the free parameters of `report`: each scaled by its RMS
/// sensitivity ([`column_scales`]) and H₀ = 2·D·G·D, the Gauss–Newton matrix in those variables;
/// `RankDeficient` when no parameter is free.
fn scaled_start(
    gram: &DMatrix<f64>,
    report: &IdentifiabilityReport,
    stage: Stage,
) -> Result<(DVector<f64>, DMatrix<f64>), CalibrationError> {
    if report.free.is_empty() {
        return Err(CalibrationError::RankDeficient {
            stage,
            detail: "no parameter is identifiable from these configurations".into(),
        });
    }
    let scale = DVector::from_vec(column_scales(gram, report.free.iter().copied()));
    let h0 = DMatrix::from_fn(report.free.len(), report.free.len(), |i, j| {
        2.0 * gram[(report.free[i], report.free[j])] * scale[i] * scale[j]
    });
    Ok((scale, h0))
}

/// `RankDeficient` unless some kinematic parameter (not a reflector coordinate) is free: data in
/// which every configuration is the same show nothing of the arm.
pub fn require_kinematics(
    stage: Stage,
    arm: &ArmModel,
    report: &IdentifiabilityReport,
) -> Result<(), CalibrationError> {
    if report.free.iter().any(|&k| k < arm.reflector_offset()) {
        return Ok(());
    }
    Err(CalibrationError::RankDeficient {
        stage,
        detail:
            "no kinematic parameter is identifiable from these configurations (are they all the \
                 same?)"
                .into(),
    })
}

/// The reflector `distance-single` uses by default: the one whose distance errors the nominal model
/// fits worst (largest F_k), as ref. \[26\] is compared in the paper.
pub fn worst_reflector(objectives_mm2: &[f64]) -> Reflector {
    let k = (0..objectives_mm2.len().min(Reflector::ALL.len()))
        .max_by(|&a, &b| objectives_mm2[a].total_cmp(&objectives_mm2[b]))
        .unwrap_or(0);
    Reflector::from_index(k).unwrap_or(Reflector::A)
}

/// The paper's SQP on `problem` from the start Hessian `h0`, with the settings' QP and tolerances.
pub fn sqp_solver<P: MinimaxProblem + 'static>(
    problem: P,
    stage: Stage,
    h0: DMatrix<f64>,
    options: &StageOptions,
) -> Result<Box<dyn StageSolver>, CalibrationError> {
    let sqp = SqpSettings {
        qp: options.qp,
        hessian: options.hessian,
        step_tolerance: options.step_tolerance,
        progress_tolerance: options.progress_tolerance,
        max_qp_iterations: options.max_qp_iterations,
    };
    Ok(Box::new(SqpState::new(problem, sqp, h0).map_err(|_| {
        CalibrationError::NonFinite {
            stage,
            detail: "objective or gradient at the start point".into(),
        }
    })?))
}

/// `algorithm` on the least-squares `problem`, with the settings' step tolerance.
pub fn least_squares_solver<P: LeastSquaresProblem + 'static>(
    problem: P,
    algorithm: LsqAlgorithm,
    options: &StageOptions,
) -> Box<dyn StageSolver> {
    Box::new(LsqState::new(problem, algorithm, options.step_tolerance))
}

/// What a step-1 method's set-up is given: the arm's data, its start model, the settings.
pub struct ArmSetUp<'a> {
    pub data: &'a ArmData,
    /// The arm's start (nominal) model.
    pub start: &'a ArmModel,
    pub options: StageOptions,
    /// Parameters held at their start values as weak ([`crate::solver::weak`]; the distance
    /// methods of all the reflectors hold them, the others find none).
    pub held: &'a [usize],
}

/// What a step-1 method's set-up returns: the stage's solver and what it identifies.
pub struct ArmStage {
    pub solver: Box<dyn StageSolver>,
    /// Which of the arm's parameters the solver identifies and which it holds, and why.
    pub identifiability: IdentifiabilityReport,
    /// The reflector a single-reflector method fits.
    pub reflector: Option<Reflector>,
}

/// The distance problem of all three reflectors on the identifiable parameters, scaled, with the
/// Gauss–Newton start Hessian.
pub struct DistanceStart {
    pub problem: ArmProblem,
    /// `2·D·G·D`, G the mean Gram matrix of the pair Jacobian, D the column scales.
    pub h0: DMatrix<f64>,
    pub report: IdentifiabilityReport,
}

impl ArmSetUp<'_> {
    pub fn stage(&self) -> Stage {
        Stage::Arm(self.data.side)
    }

    /// The set-up of the methods that fit all three reflectors' distances: identifiability at the
    /// start model, every free parameter scaled by its RMS sensitivity, and H₀ the Gauss–Newton matrix
    /// in those variables.
    pub fn all_distances(&self) -> Result<DistanceStart, CalibrationError> {
        let start = self.start;
        let probe = self.data.distance_probe(start);
        let allowed: Vec<bool> = (0..start.param_count())
            .map(|k| !self.held.contains(&k))
            .collect();
        let analysis = Analysis {
            allowed: &allowed,
            data: ParameterInfo::DISTANCES,
            not_allowed: HELD_WEAK,
        };
        let (gram, report) = distance_identifiability(&probe, start, &analysis);
        let (scale, h0) = scaled_start(&gram, &report, self.stage())?;
        Ok(DistanceStart {
            problem: probe.with_free(report.free.clone(), scale),
            h0,
            report,
        })
    }
}

/// What a step-1 method's set-up for both arms at once is given, where the arms share joints (a
/// torso): both arms' data, the start (nominal) model, its shared joints, the settings.
pub struct TreeSetUp<'a> {
    pub data: &'a PerSide<ArmData>,
    pub start: &'a DualArmModel,
    pub shared: &'a SharedJoints,
    pub options: StageOptions,
}

/// What a set-up for both arms at once returns: the stage's solver and each arm's identifiability
/// (the tree's, split: a shared parameter is in both).
pub struct TreeStage {
    pub solver: Box<dyn StageSolver>,
    pub identifiability: PerSide<IdentifiabilityReport>,
}

/// The tree's distance problem on its identifiable parameters, scaled, with the Gauss–Newton start
/// Hessian, and each arm's part of the identifiability report.
pub struct TreeStart {
    pub problem: TreeProblem,
    pub h0: DMatrix<f64>,
    pub reports: PerSide<IdentifiabilityReport>,
}

impl TreeSetUp<'_> {
    /// The set-up of the distance methods for both arms at once: the identifiability analysis of the
    /// tree's parameters on both arms' sampled pair Jacobians (one Gram matrix), every free parameter
    /// scaled by its RMS sensitivity, H₀ the Gauss–Newton matrix in those variables.
    pub fn all_distances(&self) -> Result<TreeStart, CalibrationError> {
        let arms = &self.start.arms;
        let layout = TreeLayout::new(&arms.left, &arms.right, self.shared);
        let probes = PerSide::from_fn(|side| self.data[side].distance_probe(&arms[side]));
        let columns = PerSide::from_fn(|side| {
            probes[side].sample_pair_jacobian(
                &DVector::zeros(arms[side].param_count()),
                IDENTIFIABILITY_PAIRS,
            )
        });
        let mut m = DMatrix::zeros(layout.len, columns.left.ncols() + columns.right.ncols());
        let mut first = 0;
        for side in Side::BOTH {
            let c = &columns[side];
            for (k, &x) in layout.index[side].iter().enumerate() {
                for j in 0..c.ncols() {
                    m[(x, first + j)] = c[(k, j)];
                }
            }
            first += c.ncols();
        }
        let gram = identifiability::gram_by_product(&m);
        let allowed = vec![true; layout.len];
        let columns = Columns::Tree {
            layout: &layout,
            arms,
            transform: false,
        };
        let report = analyse_columns(&gram, &columns, &Analysis::distances(&allowed));
        let (scale, h0) = scaled_start(&gram, &report, Stage::Arms)?;
        let reports = layout.split_report(&report, arms);
        Ok(TreeStart {
            problem: TreeProblem::new(probes, &layout, &report.free, &scale),
            h0,
            reports,
        })
    }
}

/// What a step-2 method's set-up is given: both arms' data, the model with step 1's arms (and the
/// nominal base, the start), the settings.
pub struct BaseSetUp<'a> {
    pub data: &'a PerSide<ArmData>,
    pub model: &'a DualArmModel,
    pub options: StageOptions,
}

impl BaseSetUp<'_> {
    /// The collaborative distance problem on step 1's arms from the model's base, and its
    /// Gauss–Newton matrix (the SQP's start Hessian); `RankDeficient` when that is singular.
    pub fn collaborative_distances(&self) -> Result<(BaseProblem, DMatrix<f64>), CalibrationError> {
        let model_points = |side: Side| -> Vec<Vec<Vector3<f64>>> {
            self.data[side]
                .qs
                .iter()
                .map(|q| self.model.arm(side).reflector_fk(q).points_mm)
                .collect()
        };
        let problem = BaseProblem::new(
            model_points(Side::Left),
            model_points(Side::Right),
            &self.data.left.measured,
            &self.data.right.measured,
            self.model.arm(Side::Left).reflector_count(),
            self.model.left_base_from_right_base,
        );
        let h0 = problem.gauss_newton(&DVector::zeros(6));
        let sv = h0.singular_values();
        if sv.min() <= sv.max() * 1e-12 {
            return Err(CalibrationError::RankDeficient {
                stage: Stage::Base,
                detail: format!("collaborative Jacobian singular values {:?}", sv.as_slice()),
            });
        }
        Ok((problem, h0))
    }
}
