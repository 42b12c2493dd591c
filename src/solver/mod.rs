//! The paper's two-step minimax calibration (Algorithms I and II), and the least-squares baseline.
//!
//! Step 1 identifies each arm's kinematic parameters (the built-in IRB 14000's DH table, or the
//! joint-origin corrections of a URDF chain) and reflector coordinates by minimising the maximum over
//! the reflectors of the summed squared relative distance errors; step 2 identifies the right-arm base
//! in the left-arm base frame by the same minimax over collaborative distance errors.
//!
//! The shape follows argmin: each stage is a problem ([`problem::MinimaxProblem`]: the step-1
//! [`arm_problem::ArmProblem`] or the step-2 [`base_problem::BaseProblem`]) driven by a
//! [`StageSolver`] (SQP with the exact or the paper's QP, or Levenberg–Marquardt) that performs one
//! outer iteration per [`StageSolver::next_iter`]. One executor, [`CalibrationRun`], runs the stages in
//! turn, reports to [`Observer`]s and polls the cancel flag; [`Calibrator`] is its entry point:
//!
//! ```no_run
//! # fn demo(dataset: &dualcal::dataset::Dataset, nominal: &dualcal::kinematics::DualArmModel)
//! # -> Result<(), dualcal::solver::CalibrationError> {
//! use dualcal::solver::{CalibrationEvent, CalibrationSettings, Calibrator};
//! let mut progress = |e: &CalibrationEvent| eprintln!("{e:?}");
//! let result = Calibrator::new(dataset, nominal)
//!     .settings(CalibrationSettings::default())
//!     .observer(&mut progress)
//!     .run()?;
//! assert!(result.is_converged());
//! # Ok(()) }
//! ```
//!
//! A run that hits the iteration limit or is cancelled still returns its result: the model reached,
//! the history, and per stage why it ended ([`Termination`]).
//!
//! The folder by kind: [`problems`] (what each stage minimises), [`algorithms`] (the solvers that
//! minimise it), [`methods`] (the table of methods, each setting its stage up), [`run`] (the executor
//! and its entry point), [`analysis`] (identifiability, uncertainty); the types they share in
//! [`types`] and [`error`], a run's [`settings`], a run's outcome in [`result`]. This file only declares and re-exports:
//! every `crate::solver::X` path of the rest of the crate is one of the lines below.

pub mod algorithms;
pub mod analysis;
pub mod error;
pub mod methods;
pub mod problems;
pub mod result;
pub mod run;
pub mod settings;
pub mod types;

pub use algorithms::stage::{IterState, StageSolver};
pub use algorithms::{least_squares, qp, sqp};
pub use analysis::{identifiability, uncertainty, weak};
pub use error::CalibrationError;
pub use methods::{BaseMethod, BaseMethodSpec, Method, MethodSpec, Observes, SolverKind};
pub use problems::{
    absolute_problem, arm_problem, base_problem, problem, tree_absolute, tree_problem,
};
pub use result::{CalibrationResult, STAGES};
pub use run::{
    CalibrationRun, Calibrator, Observer, Progress, default_method, default_method_reason,
    planned_stages,
};
pub use settings::CalibrationSettings;
pub use types::{
    AUTO_GAUSS_NEWTON_CONDITION, CalibrationEvent, DIVERGED_ANGLE_RAD, DIVERGED_LENGTH_MM, Hessian,
    IterationRecord, QpMethod, Reflector, Stage, StageOptions, StageSummary, Termination,
    identifiable_params, min_configurations,
};
