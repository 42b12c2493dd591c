//! The types the solver's parts share: the options a stage is given, its stages, how a stage ended, the
//! progress records and events, and the limits a stage is held to.

use crate::side::Side;
use serde::{Deserialize, Serialize};

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

impl crate::choice::Choice for QpMethod {
    const WHAT: &'static str = "QP solver";

    fn all() -> &'static [Self] {
        &[QpMethod::Paper, QpMethod::Exact]
    }

    fn spelling(self) -> &'static str {
        match self {
            QpMethod::Paper => "paper",
            QpMethod::Exact => "exact",
        }
    }

    fn help(self) -> Option<&'static str> {
        Some(match self {
            QpMethod::Paper => "The paper's primal-dual subgradient method, eqs. (29)–(31)",
            QpMethod::Exact => "An exact dual active-set solution of the same QP",
        })
    }
}

/// The curvature model of the SQP's quadratic subproblems (the Hessian of the Lagrangian).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Hessian {
    /// Gauss–Newton curvature where the data are ill-conditioned, the paper's BFGS elsewhere: per
    /// arm stage by the condition number of the start's scaled Jacobian of the identified parameters
    /// (above [`AUTO_GAUSS_NEWTON_CONDITION`]: Gauss–Newton); step 2 (six parameters) BFGS
    /// (docs/solver.md, "Curvature").
    #[default]
    Auto,
    /// Gauss–Newton curvature of the active sums, `Σ_k λ_k ∇²F_k ≈ Σ_k λ_k 2 J_kᵀJ_k` with the QP's
    /// multipliers (a small floor keeps every reflector's curvature): exact for the residual-free
    /// part of the paper's sums of squares, recomputed at every iterate. On ill-conditioned data with
    /// unmodelled errors it converges as least squares does (docs/solver.md, "Curvature").
    GaussNewton,
    /// The paper's BFGS update of the Lagrangian's Hessian (Powell's damping), started from the
    /// Gauss–Newton matrix: the method of Algorithm I as published.
    Bfgs,
}

/// Under [`Hessian::Auto`], an arm stage whose identified parameters' scaled Jacobian has a larger
/// condition number at the start is solved with the Gauss–Newton curvature. Measured: 14–16 on the
/// paper-size simulations (BFGS and Gauss–Newton take about the same iterations there, BFGS each
/// cheaper), 600–710 on the ill-conditioned one-reflector arm (BFGS 173 iterations over five seeds,
/// Gauss–Newton 100, least squares 87), 1.2e3 on the Leica-measured arm of issue 47 (BFGS 200+,
/// least squares 20).
pub const AUTO_GAUSS_NEWTON_CONDITION: f64 = 100.0;

impl Hessian {
    /// The name on the command line and in parameter files.
    pub fn name(self) -> &'static str {
        match self {
            Hessian::Auto => "auto",
            Hessian::GaussNewton => "gauss-newton",
            Hessian::Bfgs => "bfgs",
        }
    }

    /// The curvature a stage uses: [`Hessian::Auto`] resolved by the condition number of the
    /// start's scaled Jacobian of the identified parameters (`None`: a stage without one, step 2:
    /// BFGS).
    pub fn resolved(self, condition: Option<f64>) -> Hessian {
        match self {
            Hessian::Auto => match condition {
                Some(c) if c > AUTO_GAUSS_NEWTON_CONDITION => Hessian::GaussNewton,
                _ => Hessian::Bfgs,
            },
            other => other,
        }
    }

    /// What parameter files written before the setting existed used.
    pub(crate) fn of_older_files() -> Self {
        Hessian::Bfgs
    }

    /// The paper's BFGS (written in parameter files only when another curvature was used).
    pub(crate) fn is_bfgs(&self) -> bool {
        *self == Hessian::Bfgs
    }
}

impl crate::choice::Choice for Hessian {
    const WHAT: &'static str = "curvature";

    fn all() -> &'static [Self] {
        &[Hessian::Auto, Hessian::GaussNewton, Hessian::Bfgs]
    }

    fn spelling(self) -> &'static str {
        self.name()
    }

    fn help(self) -> Option<&'static str> {
        Some(match self {
            Hessian::Auto => {
                "Gauss–Newton where an arm's data are ill-conditioned (the identified parameters' \
                 scaled Jacobian has a condition number above 100 at the start: a flange that \
                 hardly turns, one reflector), the paper's BFGS elsewhere and in step 2; the \
                 command says when it chose Gauss–Newton"
            }
            Hessian::GaussNewton => {
                "Gauss–Newton curvature of the active sums, `Σ_k λ_k ∇²F_k ≈ Σ_k λ_k 2 J_kᵀJ_k` with \
                 the QP's multipliers (a small floor keeps every reflector's curvature): exact for the \
                 residual-free part of the paper's sums of squares, recomputed at every iterate. On \
                 ill-conditioned data with unmodelled errors it converges as least squares does \
                 (docs/solver.md, \"Curvature\")"
            }
            Hessian::Bfgs => {
                "The paper's BFGS update of the Lagrangian's Hessian (Powell's damping), started \
                 from the Gauss–Newton matrix: the method of Algorithm I as published"
            }
        })
    }
}

crate::choice_strings!(QpMethod, Hessian);

/// The first, second or third reflector of the dataset (`a`, `b`, `c` in the paper's set-up; by position
/// in the dataset's order whatever their names), for the single-reflector method.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
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

impl crate::choice::Choice for Reflector {
    const WHAT: &'static str = "reflector";

    fn all() -> &'static [Self] {
        &Self::ALL
    }

    fn spelling(self) -> &'static str {
        self.name()
    }
}

impl std::fmt::Display for Reflector {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// What a stage's set-up and solver are told of the run's settings
/// ([`crate::solver::CalibrationSettings::stage_options`]): the QP, the curvature, the tolerances.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StageOptions {
    /// How the SQP's QP subproblems are solved.
    pub qp: QpMethod,
    /// The SQP's curvature model.
    pub hessian: Hessian,
    /// Stop when the scaled parameter step norm falls below this.
    pub step_tolerance: f64,
    /// Also stop when ψ fell by less than this, relative, over the last five outer iterations.
    pub progress_tolerance: f64,
    /// Iterations of the paper's subgradient QP solver per outer iteration.
    pub max_qp_iterations: usize,
    /// The absolute methods: fit only the tracker frame and the reflectors.
    pub hold_kinematics: bool,
    /// The single-reflector method's reflector (`None`: the one with the largest nominal error).
    pub reflector: Option<Reflector>,
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
    /// The SQP's curvature in this stage (`None`: not an SQP stage).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub curvature: Option<Hessian>,
}

/// A parameter the configurations barely constrain, and why ([`crate::solver::weak`]).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct WeakParameter {
    pub name: String,
    /// Its index in the arm's parameter vector.
    #[serde(skip)]
    pub index: usize,
    /// One standard deviation in `unit` (`mm`, `mrad`, or an error parameter's own).
    pub sigma: f64,
    pub unit: String,
    /// RMS over the workspace of the distance change its 1σ brings, mm.
    pub workspace_mm: f64,
    /// The tracker's noise per axis it is compared with (the residuals' estimate), mm.
    pub noise_mm: f64,
    /// Why, in words.
    pub reason: String,
    /// Held at its nominal value in the calibration (`false`: kept free, `--keep-weak`).
    pub held: bool,
}

impl WeakParameter {
    /// One line: the name, the reason, the figures, and what was done.
    pub fn describe(&self) -> String {
        let done = if self.held {
            "held at its nominal value (--keep-weak fits it)"
        } else {
            "kept free (--keep-weak)"
        };
        format!(
            "{}: {}; its 1σ of {:.3} {} would move distances across the workspace by {:.3} mm RMS, \
             {:.0}× the noise ({:.4} mm); {done}",
            self.name,
            self.reason,
            self.sigma,
            self.unit,
            self.workspace_mm,
            self.workspace_mm / self.noise_mm,
            self.noise_mm
        )
    }
}
