//! Nonlinear least squares for the paper's comparison methods (its Table 1): Gauss–Newton with the
//! normal equations (ref. \[26\]), Gauss–Newton with a QR decomposition of the Jacobian (ref. \[19\]) and
//! Levenberg–Marquardt (ref. \[18\]), on any [`LeastSquaresProblem`] — the single-reflector distances,
//! the absolute positions, the full poses, the collaborative distances and the bases in the tracker
//! frame. [`LsqState`] performs one outer iteration per [`StageSolver::next_iter`], like the SQP.

use super::stage::{IterState, StageSolver};
use crate::side::PerSide;
use crate::solver::problems::problem::{LeastSquaresSystem, MinimaxProblem, StageParams};
use crate::solver::types::Termination;
use nalgebra::{DMatrix, DVector, Isometry3};

/// A failed step search counts as convergence when the Gauss–Newton model predicts a decrease of
/// the cost below this (relative): a stationary point to working precision.
pub const STATIONARY_RTOL: f64 = 1e-10;
/// An accepted step that lowered the cost by less than this (relative) ends the stage as converged
/// ([`Termination::NoProgress`]): the cost is stationary to working precision.
pub const NO_PROGRESS_RTOL: f64 = 1e-13;
/// A failed step search also counts as convergence when the cost has fallen below this fraction of
/// its start value: the data are fitted to rounding (noise-free data, where the relative test above
/// meets the round-off of the cost itself).
pub const FITTED_RTOL: f64 = 1e-12;
/// Step halvings tried by Gauss–Newton before it gives up on a direction.
const MAX_HALVINGS: usize = 30;

/// A nonlinear least-squares problem `min Σ r(y)²` in scaled variables `y` (y = 0 is the start).
pub trait LeastSquaresProblem: Send + Sync {
    /// Number of (scaled) variables.
    fn dim(&self) -> usize;
    /// The stage's parameters at y.
    fn params_at(&self, y: &DVector<f64>) -> StageParams;
    /// The objective minimised, Σ r², mm².
    fn cost(&self, y: &DVector<f64>) -> f64;
    /// What the progress lines report as F_a, F_b, F_c (sums of squares per reflector), mm².
    fn objectives_mm2(&self, y: &DVector<f64>) -> Vec<f64>;
    /// The normal equations `JᵀJ`, `Jᵀr` (r = measured − model, J = ∂r/∂y) and the cost at y.
    fn normal_equations(&self, y: &DVector<f64>) -> LeastSquaresSystem;
    /// The residuals and their Jacobian ∂r/∂y, for methods solved by QR; `None` where only the normal
    /// equations are formed.
    fn residuals_jacobian(&self, _y: &DVector<f64>) -> Option<(DVector<f64>, DMatrix<f64>)> {
        None
    }
    /// Configuration pairs per reflector (distance problems) or configurations (absolute problems).
    fn pair_count(&self) -> usize;
    /// Each arm's model base in the tracker frame at y, where the problem identifies it.
    fn tracker_frames(&self, _y: &DVector<f64>) -> PerSide<Option<Isometry3<f64>>> {
        PerSide::default()
    }
}

/// How each iteration's step is found.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LsqAlgorithm {
    /// Gauss–Newton, the step from the normal equations (Cholesky), halved until the cost decreases.
    GaussNewton,
    /// Gauss–Newton, the step from a QR decomposition of the Jacobian (never forming JᵀJ), halved
    /// until the cost decreases.
    GaussNewtonQr,
    /// Levenberg–Marquardt with Marquardt's diagonal damping.
    LevenbergMarquardt,
}

/// The state of a least-squares stage.
pub struct LsqState<P: LeastSquaresProblem> {
    pub problem: P,
    pub y: DVector<f64>,
    algorithm: LsqAlgorithm,
    cost: f64,
    start_cost: f64,
    lambda: f64,
    step_tolerance: f64,
}

/// One iteration's outcome.
struct LsqStep {
    step_norm: f64,
    gradient_norm: f64,
    termination: Option<Termination>,
}

impl<P: LeastSquaresProblem> LsqState<P> {
    pub fn new(problem: P, algorithm: LsqAlgorithm, step_tolerance: f64) -> Self {
        let y = DVector::zeros(problem.dim());
        let cost = problem.cost(&y);
        Self {
            problem,
            y,
            algorithm,
            cost,
            start_cost: cost,
            lambda: 1e-3,
            step_tolerance,
        }
    }

    /// The cost at the current iterate, mm².
    pub fn cost(&self) -> f64 {
        self.cost
    }

    /// Accept `delta` (already known to lower the cost to `cost`).
    fn accept(&mut self, delta: DVector<f64>, cost: f64, gradient_norm: f64) -> LsqStep {
        let decrease = self.cost - cost;
        self.y += &delta;
        let previous = self.cost;
        self.cost = cost;
        let step_norm = delta.norm();
        let termination = if step_norm < self.step_tolerance {
            Some(Termination::Converged)
        } else if decrease <= NO_PROGRESS_RTOL * previous.abs() {
            Some(Termination::NoProgress)
        } else {
            None
        };
        LsqStep {
            step_norm,
            gradient_norm,
            termination,
        }
    }

    /// No step lowered the cost: converged if the Gauss–Newton model predicts no meaningful decrease
    /// (`predicted` = Jᵀr · δ_GN), stalled otherwise.
    fn no_descent(&self, predicted: f64, gradient_norm: f64) -> LsqStep {
        let stationary = (predicted.is_finite() && predicted <= STATIONARY_RTOL * self.cost.abs())
            || self.cost <= FITTED_RTOL * self.start_cost;
        LsqStep {
            step_norm: 0.0,
            gradient_norm,
            termination: Some(if stationary {
                Termination::Converged
            } else {
                Termination::Stalled
            }),
        }
    }

    /// The Gauss–Newton step and the decrease it predicts, by the normal equations or QR; `None`
    /// when the linear system is singular.
    fn gauss_newton_step(&self, sys: &LeastSquaresSystem) -> Option<(DVector<f64>, f64)> {
        let delta = match self.algorithm {
            LsqAlgorithm::GaussNewtonQr => {
                let (r, j) = self.problem.residuals_jacobian(&self.y)?;
                // The linearised residual r + J δ (r = measured − model, J = ∂r/∂y) is smallest
                // for the least-squares solution of J δ = −r: R δ = Qᵀ(−r).
                let qr = j.qr();
                let rhs = qr.q().transpose() * (-r);
                let rm = qr.r();
                let diag_max = rm.diagonal().amax();
                if rm.diagonal().iter().any(|d| d.abs() <= 1e-13 * diag_max) {
                    return None;
                }
                rm.solve_upper_triangular(&rhs)?
            }
            _ => -sys.jtj.clone().cholesky()?.solve(&sys.jtr),
        };
        let predicted = -sys.jtr.dot(&delta);
        Some((delta, predicted))
    }

    fn next_iter(&mut self) -> LsqStep {
        let sys = self.problem.normal_equations(&self.y);
        let gradient_norm = sys.jtr.amax();
        match self.algorithm {
            LsqAlgorithm::GaussNewton | LsqAlgorithm::GaussNewtonQr => {
                let Some((mut delta, predicted)) = self.gauss_newton_step(&sys) else {
                    return LsqStep {
                        step_norm: 0.0,
                        gradient_norm,
                        termination: Some(Termination::Stalled),
                    };
                };
                for _ in 0..MAX_HALVINGS {
                    let trial = &self.y + &delta;
                    let cost = self.problem.cost(&trial);
                    if cost.is_finite() && cost <= self.cost {
                        return self.accept(delta, cost, gradient_norm);
                    }
                    delta *= 0.5;
                }
                self.no_descent(predicted, gradient_norm)
            }
            LsqAlgorithm::LevenbergMarquardt => {
                let m = self.y.len();
                for _ in 0..30 {
                    let mut a = sys.jtj.clone();
                    for i in 0..m {
                        a[(i, i)] += self.lambda * sys.jtj[(i, i)].max(1e-12);
                    }
                    let Some(chol) = a.cholesky() else {
                        self.lambda *= 10.0;
                        continue;
                    };
                    let delta = -chol.solve(&sys.jtr);
                    let cost = self.problem.cost(&(&self.y + &delta));
                    if cost.is_finite() && cost <= self.cost {
                        self.lambda = (self.lambda / 3.0).max(1e-12);
                        return self.accept(delta, cost, gradient_norm);
                    }
                    self.lambda *= 4.0;
                }
                let predicted = sys
                    .jtj
                    .clone()
                    .cholesky()
                    .map_or(f64::INFINITY, |chol| sys.jtr.dot(&chol.solve(&sys.jtr)));
                self.no_descent(predicted, gradient_norm)
            }
        }
    }
}

impl<P: LeastSquaresProblem> StageSolver for LsqState<P> {
    fn next_iter(&mut self, stop: &dyn Fn() -> bool) -> IterState {
        if stop() {
            return IterState {
                f_mm2: self.problem.objectives_mm2(&self.y),
                step_norm: 0.0,
                residual: f64::NAN,
                lambda: None,
                termination: Some(Termination::Cancelled),
            };
        }
        let step = LsqState::next_iter(self);
        IterState {
            f_mm2: self.problem.objectives_mm2(&self.y),
            step_norm: step.step_norm,
            residual: step.gradient_norm,
            lambda: None,
            termination: step.termination,
        }
    }

    fn current(&self) -> StageParams {
        self.problem.params_at(&self.y)
    }

    fn objectives_mm2(&self) -> Vec<f64> {
        self.problem.objectives_mm2(&self.y)
    }

    fn pair_count(&self) -> usize {
        self.problem.pair_count()
    }

    fn tracker_frames(&self) -> PerSide<Option<Isometry3<f64>>> {
        self.problem.tracker_frames(&self.y)
    }
}

/// A distance problem of the minimax form solved as least squares of the distance errors of the
/// reflectors in `reflectors` (all for the collaborative distances of ref. \[26\]'s step 2, one for its
/// step 1, where the problem's normal equations are restricted to that reflector too).
pub struct DistanceLeastSquares<P: MinimaxProblem> {
    pub problem: P,
    pub reflectors: Vec<bool>,
}

impl<P: MinimaxProblem> LeastSquaresProblem for DistanceLeastSquares<P> {
    fn dim(&self) -> usize {
        self.problem.dim()
    }

    fn params_at(&self, y: &DVector<f64>) -> StageParams {
        self.problem.params_at(y)
    }

    fn cost(&self, y: &DVector<f64>) -> f64 {
        let f = self.problem.values(y).0;
        let pairs = self.problem.pair_count() as f64;
        (0..self.reflectors.len())
            .filter(|&k| self.reflectors[k])
            .map(|k| f[k] * pairs)
            .sum()
    }

    fn objectives_mm2(&self, y: &DVector<f64>) -> Vec<f64> {
        let pairs = self.problem.pair_count() as f64;
        self.problem
            .values(y)
            .0
            .into_iter()
            .map(|f| f * pairs)
            .collect()
    }

    fn normal_equations(&self, y: &DVector<f64>) -> LeastSquaresSystem {
        self.problem.least_squares(y)
    }

    fn pair_count(&self) -> usize {
        self.problem.pair_count()
    }
}
