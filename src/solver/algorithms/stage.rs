//! The stage-solver interface: one outer iteration at a time, whatever the method (argmin's
//! `Solver::next_iter`). [`crate::solver::CalibrationRun`] is the one executor that drives it.

use super::sqp::SqpState;
use crate::side::PerSide;
use crate::solver::problems::problem::{MinimaxProblem, StageParams};
use crate::solver::types::Termination;
use nalgebra::Isometry3;

/// What one outer iteration reports.
#[derive(Clone, Debug, PartialEq)]
pub struct IterState {
    /// F_a, F_b, F_c at the new iterate: sums of squared distance errors over all pairs, mm².
    pub f_mm2: Vec<f64>,
    /// Norm of the scaled parameter step taken.
    pub step_norm: f64,
    /// First-order optimality residual: the KKT residual of the minimax problem (SQP) or the largest
    /// gradient component (least squares).
    pub residual: f64,
    /// The reflectors' weights λ_a, λ_b, λ_c in this iteration (SQP: the QP multipliers of the three
    /// objective rows); `None` for methods that have none.
    pub lambda: Option<Vec<f64>>,
    /// `Some` when the stage is over.
    pub termination: Option<Termination>,
}

/// One stage's iterative solver (SQP with the exact or the paper's QP, Gauss–Newton,
/// Levenberg–Marquardt, …) on its
/// problem. Implementations keep their own state between calls.
pub trait StageSolver: Send {
    /// One outer iteration. `stop` is polled inside long iterations; when it answers yes the iteration
    /// ends with [`Termination::Cancelled`] and the iterate is left as it was.
    fn next_iter(&mut self, stop: &dyn Fn() -> bool) -> IterState;
    /// The stage's parameters at the current iterate.
    fn current(&self) -> StageParams;
    /// F_a, F_b, F_c at the current iterate, mm² (sums over all pairs).
    fn objectives_mm2(&self) -> Vec<f64>;
    /// Configuration pairs per reflector (configurations, for the absolute methods).
    fn pair_count(&self) -> usize;
    /// Each arm's model base in the tracker frame at the current iterate, where the method identifies
    /// it (the absolute methods); none by default.
    fn tracker_frames(&self) -> PerSide<Option<Isometry3<f64>>> {
        PerSide::default()
    }
    /// The SQP's curvature (`None`: not an SQP).
    fn curvature(&self) -> Option<crate::solver::types::Hessian> {
        None
    }
}

impl<P: MinimaxProblem> StageSolver for SqpState<P> {
    fn next_iter(&mut self, stop: &dyn Fn() -> bool) -> IterState {
        let step = SqpState::next_iter(self, stop);
        let pairs = self.problem.pair_count() as f64;
        IterState {
            f_mm2: step.f.iter().map(|v| v * pairs).collect(),
            step_norm: step.step_norm,
            residual: step.kkt_residual,
            lambda: Some(step.lambda),
            termination: step.termination,
        }
    }

    fn current(&self) -> StageParams {
        self.problem.params_at(&self.y)
    }

    fn objectives_mm2(&self) -> Vec<f64> {
        let pairs = self.problem.pair_count() as f64;
        self.eval().f.iter().map(|v| v * pairs).collect()
    }

    fn pair_count(&self) -> usize {
        self.problem.pair_count()
    }

    fn curvature(&self) -> Option<crate::solver::types::Hessian> {
        Some(self.curvature_used())
    }
}
