//! The types the solver's parts share: the settings of a run, its stages, how a stage ended, the
//! progress records and events, and the limits a stage is held to.

use crate::dataset::Split;
use crate::kinematics::ErrorTerms;
use crate::side::{ConfigId, PerSide, Side};
use crate::solver::methods::table::{BaseMethod, Method};
use serde::{Deserialize, Serialize};

/// How the QP subproblem of each SQP iteration is solved.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, Serialize, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "lowercase")]
pub enum QpMethod {
    /// The paper's primal-dual subgradient method, eqs. (29)–(31).
    Paper,
    /// An exact dual active-set solution of the same QP.
    #[default]
    Exact,
}

/// The curvature model of the SQP's quadratic subproblems (the Hessian of the Lagrangian).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, Serialize, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "kebab-case")]
pub enum Hessian {
    /// Gauss–Newton curvature of the active sums, `Σ_k λ_k ∇²F_k ≈ Σ_k λ_k 2 J_kᵀJ_k` with the QP's
    /// multipliers (a small floor keeps every reflector's curvature): exact for the residual-free
    /// part of the paper's sums of squares, recomputed at every iterate. On ill-conditioned data with
    /// unmodelled errors it converges as least squares does (docs/solver.md, "Curvature").
    GaussNewton,
    /// The paper's BFGS update of the Lagrangian's Hessian (Powell's damping), started from the
    /// Gauss–Newton matrix: the method of Algorithm I as published (the default until the
    /// Gauss–Newton curvature has been through the whole test suite as the default).
    #[default]
    Bfgs,
}

impl Hessian {
    /// The name on the command line and in parameter files.
    pub fn name(self) -> &'static str {
        match self {
            Hessian::GaussNewton => "gauss-newton",
            Hessian::Bfgs => "bfgs",
        }
    }

    /// What parameter files written before the setting existed used.
    fn of_older_files() -> Self {
        Hessian::Bfgs
    }

    /// The paper's BFGS (written in parameter files only when another curvature was used).
    fn is_bfgs(&self) -> bool {
        *self == Hessian::Bfgs
    }
}

/// The first, second or third reflector of the dataset (`a`, `b`, `c` in the paper's set-up; by position
/// in the dataset's order whatever their names), for the single-reflector method.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "lowercase")]
pub enum Reflector {
    A,
    B,
    C,
}

impl Reflector {
    pub const ALL: [Reflector; 3] = [Reflector::A, Reflector::B, Reflector::C];

    /// 0, 1, 2 for a, b, c.
    pub fn index(self) -> usize {
        match self {
            Reflector::A => 0,
            Reflector::B => 1,
            Reflector::C => 2,
        }
    }

    pub fn from_index(k: usize) -> Option<Reflector> {
        Self::ALL.get(k).copied()
    }

    pub fn name(self) -> &'static str {
        crate::kinematics::REFLECTOR_NAMES[self.index()]
    }
}

impl std::fmt::Display for Reflector {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// Settings of a calibration run.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CalibrationSettings {
    /// Configurations used for identification (`cal` or `all`).
    pub split: Split,
    /// Step 1's method (each arm).
    pub method: Method,
    /// Step 2's method (the right-arm base); files without it mean the paper's minimax.
    #[serde(default)]
    pub base_method: BaseMethod,
    /// The reflector of [`Method::DistanceSingle`] (`None`: the one with the largest nominal error,
    /// chosen per arm); refused with any other method.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reflector: Option<Reflector>,
    pub qp: QpMethod,
    /// The SQP's curvature model (files without it were computed with BFGS).
    #[serde(
        default = "Hessian::of_older_files",
        skip_serializing_if = "Hessian::is_bfgs"
    )]
    pub hessian: Hessian,
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
    /// Configurations left out of the identification (suspect measurements: see
    /// [`crate::quality`]). Indices refer to the dataset given to the calibration.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub exclude: Vec<ConfigId>,
    /// Fit only the tracker frame and the reflector coordinates, the kinematic parameters held at the
    /// start model's (the absolute methods only; no step 2): the nominal robot's figure with its frame
    /// and markers fitted.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub hold_kinematics: bool,
    /// The model's errors beyond geometry, identified with it by step 1's method
    /// ([`crate::kinematics::joint_errors`]); geometric (the paper's) by default.
    #[serde(default, skip_serializing_if = "ErrorTerms::is_geometric")]
    pub model: ErrorTerms,
    /// Gravity's direction in the left arm's model base frame, for the elastic terms (`None`: −z of that
    /// frame; the command line and the workbench give the robot's: −z of its root link).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub gravity_in_left_base: Option<[f64; 3]>,
    /// The elastic terms' held lumped masses per arm — per movable joint kg and first moment kg·mm in
    /// the next joint frame — from the robot description's inertials
    /// ([`crate::robot::RobotDescription::lumped_masses`]); `None`: 1 kg at each next joint.
    #[serde(default, skip_serializing_if = "no_masses")]
    pub held_masses: PerSide<Option<crate::kinematics::joint_errors::LinkMasses>>,
    /// Gear ratios (motor turns per joint turn) by joint name: with harmonics in the model, the
    /// motor's harmonics are identified too for each joint whose ratio is not ±1 (the command line
    /// and the workbench give the URDF's `<transmission>` reductions, `--gear-ratio` overrides).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub gear_ratios: Vec<(String, f64)>,
    /// Keep the weak parameters free ([`crate::solver::analysis::weak`]): by default each arm's step
    /// 1 is solved again with them held at their nominal values (`--keep-weak`).
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub keep_weak: bool,
}

fn no_masses(m: &PerSide<Option<crate::kinematics::joint_errors::LinkMasses>>) -> bool {
    m.left.is_none() && m.right.is_none()
}

fn default_progress_tolerance() -> f64 {
    crate::solver::algorithms::sqp::PROGRESS_RTOL
}

impl Default for CalibrationSettings {
    fn default() -> Self {
        Self {
            split: Split::Cal,
            method: Method::Minimax,
            base_method: BaseMethod::Minimax,
            reflector: None,
            qp: QpMethod::Exact,
            hessian: Hessian::Bfgs,
            // The command line's `--max-iterations` default too, so that the workbench and the
            // library end a stage where `dualcal calibrate` does: a minimax stage at a three-way tie
            // with a vanishing multiplier can crawl for more than 100 iterations before "ψ
            // stationary" (docs/planning.md, *The estimator*: 175 on a public-YuMi simulation).
            max_iterations: 200,
            step_tolerance: 1e-8,
            progress_tolerance: default_progress_tolerance(),
            max_qp_iterations: 2000,
            exclude: Vec::new(),
            hold_kinematics: false,
            model: ErrorTerms::GEOMETRIC,
            gravity_in_left_base: None,
            held_masses: PerSide::default(),
            gear_ratios: Vec::new(),
            keep_weak: false,
        }
    }
}

/// Which part of the two-step calibration.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum Stage {
    /// Step 1: geometric parameters of one arm.
    Arm(Side),
    /// Step 1 of a robot whose arms share joints (a torso): both arms' parameters in one fit, the
    /// shared joints' corrections once ([`crate::solver::tree_problem`]).
    Arms,
    /// Step 2: right-arm base in the left-arm base frame.
    Base,
}

impl Termination {
    /// Whether the stage ended at a stationary point of its problem (to working precision).
    pub fn is_converged(self) -> bool {
        matches!(self, Termination::Converged | Termination::NoProgress)
    }
}

/// How far a step-1 iterate may move from the nominal model before the stage is stopped as
/// [`Termination::Diverged`]: calibration corrects millimetres and milliradians, so a DH length or
/// reflector coordinate moved by more than this is no calibration but a solver running away along a
/// direction the data do not constrain (or data that do not belong to this robot), mm.
pub const DIVERGED_LENGTH_MM: f64 = 100.0;
/// … and a DH angle moved by more than this, rad (about 29°).
pub const DIVERGED_ANGLE_RAD: f64 = 0.5;

/// The smallest number of calibration configurations per arm from which `n_params` parameters can be
/// identified by distances: each reflector's `n` measured points give `3n − 6` independent distances
/// (the point cloud up to a rigid motion), so three reflectors give `9n − 18`.
pub fn min_configurations(n_params: usize) -> usize {
    (n_params + 18).div_ceil(9).max(crate::dataset::MIN_CONFIGS)
}

/// The parameters of an arm that distances can identify at most: all but those physics rules out (for
/// the built-in robot `d1`, `θ1`, absorbed by the tracker frame, and the four of the last joint,
/// absorbed by the reflector coordinates: 31 of 37).
pub fn identifiable_params(arm: &crate::kinematics::ArmModel) -> usize {
    (0..arm.param_count())
        .filter(|&k| arm.unidentifiable_reason(k).is_none())
        .count()
}

impl std::fmt::Display for Termination {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Termination::Converged => "converged",
            Termination::NoProgress => "converged (ψ stationary)",
            Termination::Stalled => "stalled above the optimum",
            Termination::MaxIterations => "iteration limit reached",
            Termination::Cancelled => "cancelled",
            Termination::Diverged => "diverged (parameters left the plausible range)",
            Termination::NonFinite => "stopped at a non-finite value",
        })
    }
}

impl std::fmt::Display for Stage {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Stage::Arm(side) => write!(f, "step 1 ({side} arm)"),
            Stage::Arms => f.write_str("step 1 (both arms, shared joints)"),
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
    /// F_k per reflector (F_a, F_b, F_c in the paper's set-up), mm².
    pub f_mm2: Vec<f64>,
    /// Norm of the scaled parameter step.
    pub step_norm: f64,
    /// The stage's first-order optimality residual after this iteration: for an SQP stage the KKT
    /// residual of the QP solution (relative to the gradient size, plus complementarity and
    /// infeasibility); for a least-squares stage the largest component of the cost's gradient `Jᵀr`
    /// in the scaled variables, mm² (the KKT condition of a problem without constraints). Read from
    /// the name `kkt_residual` too, which earlier versions used.
    #[serde(alias = "kkt_residual")]
    pub optimality_residual: f64,
    /// Multipliers λ_k of the reflectors' rows in this iteration's QP (summing to one):
    /// how much each reflector's F_k weighs in the step. `None` for methods without such weights
    /// (least squares), NaN when an SQP iteration solved no QP.
    #[serde(default)]
    pub lambda: Option<Vec<f64>>,
    /// Time since the start of the whole run.
    pub elapsed_secs: f64,
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
    /// A parameter moved implausibly far from the nominal model ([`DIVERGED_LENGTH_MM`],
    /// [`DIVERGED_ANGLE_RAD`]); the stage keeps the last plausible iterate.
    Diverged,
    /// The objective became NaN or infinite; the stage keeps the last finite iterate.
    NonFinite,
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

/// Summary of one stage.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct StageSummary {
    pub stage: Stage,
    pub n_configs: usize,
    pub iterations: usize,
    pub termination: Termination,
    /// Final ψ and F_i (sums of squares over all pairs), mm².
    pub psi_mm2: f64,
    pub f_mm2: Vec<f64>,
    /// Initial ψ, mm².
    pub psi_start_mm2: f64,
}
