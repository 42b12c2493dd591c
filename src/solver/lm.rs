//! Ordinary least squares of all distance errors by Levenberg–Marquardt — the baseline the minimax
//! objective is compared with (it ignores the reflector-triangle constraints).

use super::Termination;
use super::problem::MinimaxProblem;
use nalgebra::DVector;

/// A failed damping search counts as convergence when the Gauss–Newton step predicts a decrease of
/// the cost below this (relative): a stationary point to working precision.
pub const STATIONARY_RTOL: f64 = 1e-10;

pub struct LmState<P: MinimaxProblem> {
    pub problem: P,
    pub y: DVector<f64>,
    lambda: f64,
    cost: f64,
    step_tolerance: f64,
    pub iterations: usize,
}

/// One LM iteration's outcome.
pub struct LmStep {
    pub f: [f64; 3],
    pub step_norm: f64,
    pub gradient_norm: f64,
    pub termination: Option<Termination>,
}

impl<P: MinimaxProblem> LmState<P> {
    pub fn new(problem: P, step_tolerance: f64) -> Self {
        let y = DVector::zeros(problem.dim());
        let (f, _) = problem.values(&y);
        let cost = f.iter().sum::<f64>() * problem.pair_count() as f64;
        Self {
            problem,
            y,
            lambda: 1e-3,
            cost,
            step_tolerance,
            iterations: 0,
        }
    }

    /// One Levenberg–Marquardt iteration.
    pub fn next_iter(&mut self) -> LmStep {
        self.iterations += 1;
        let sys = self.problem.least_squares(&self.y);
        let gradient_norm = sys.jtr.amax();
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
            let y_new = &self.y + &delta;
            let (f, _) = self.problem.values(&y_new);
            let cost = f.iter().sum::<f64>() * self.problem.pair_count() as f64;
            if cost.is_finite() && cost <= self.cost {
                self.lambda = (self.lambda / 3.0).max(1e-12);
                self.cost = cost;
                self.y = y_new;
                let step_norm = delta.norm();
                return LmStep {
                    f,
                    step_norm,
                    gradient_norm,
                    termination: (step_norm < self.step_tolerance)
                        .then_some(Termination::Converged),
                };
            }
            self.lambda *= 4.0;
        }
        // No damping found a decrease. That is convergence only if the Gauss–Newton model itself
        // predicts no meaningful decrease (a stationary point to working precision); otherwise the
        // iteration is stuck above the optimum.
        let (f, _) = self.problem.values(&self.y);
        let predicted = sys.jtj.clone().cholesky().map_or(f64::INFINITY, |chol| {
            let delta = chol.solve(&sys.jtr);
            sys.jtr.dot(&delta)
        });
        let stationary = predicted.is_finite() && predicted <= STATIONARY_RTOL * self.cost.abs();
        LmStep {
            f,
            step_norm: 0.0,
            gradient_norm,
            termination: Some(if stationary {
                Termination::Converged
            } else {
                Termination::Stalled
            }),
        }
    }
}
