//! Algorithm I/II's outer loop: sequential quadratic programming on the minimax problem with a
//! Gauss–Newton (default) or BFGS (the paper's) Hessian of the Lagrangian, an ℓ1 merit line search and
//! a parameter-step stopping rule. One call of [`SqpState::next_iter`] is one outer iteration.

use super::qp::{Qp, QpSolution, SubgradientSettings, solve_exact, solve_paper};
use crate::solver::problems::problem::{Eval, MinimaxProblem};
use crate::solver::types::{Hessian, QpMethod, Termination};
use nalgebra::{DMatrix, DVector};

/// Tunables of the outer loop.
#[derive(Clone, Copy, Debug)]
pub struct SqpSettings {
    pub qp: QpMethod,
    pub hessian: Hessian,
    pub step_tolerance: f64,
    /// See [`PROGRESS_RTOL`]; 0 disables the no-progress rule.
    pub progress_tolerance: f64,
    pub max_qp_iterations: usize,
}

/// What one outer iteration did.
#[derive(Clone, Debug)]
pub struct SqpStep {
    /// One objective per reflector.
    pub f: Vec<f64>,
    pub psi: f64,
    pub step_norm: f64,
    pub kkt_residual: f64,
    /// Multipliers λ_k of the objective rows in this iteration's QP, one per reflector (λ_a, λ_b, λ_c
    /// in the paper's set-up; they sum to one; at a minimax optimum ψ is stationary for the λ-weighted
    /// sum of the F_k). NaN if no QP was solved.
    pub lambda: Vec<f64>,
    pub qp_iterations: usize,
    /// `Some` when the loop should stop.
    pub termination: Option<Termination>,
}

/// The state of an SQP run; advance it with [`SqpState::next_iter`].
pub struct SqpState<P: MinimaxProblem> {
    pub problem: P,
    pub y: DVector<f64>,
    eval: Eval,
    h: DMatrix<f64>,
    /// ℓ1 penalty of the merit function.
    rho: f64,
    settings: SqpSettings,
    pub iterations: usize,
    /// Multipliers of the previous iteration (warm start of the paper's QP solver).
    last_nu: Option<DVector<f64>>,
    /// (ψ, constraint violation) after each accepted step, for the no-progress rule (the merit
    /// function is recomputed with the current penalty, which may have grown since).
    merit_history: Vec<(f64, f64)>,
    /// The largest objective gradient component at the start: the scale of a single objective's
    /// stationarity (one reflector), where the current gradient cannot scale itself.
    start_gradient_scale: f64,
    /// The problem had no Gauss–Newton matrix where one was asked for: BFGS was used.
    gauss_newton_unavailable: bool,
}

/// Outer iterations over which the no-progress rule looks back.
pub const PROGRESS_WINDOW: usize = 5;
/// The largest multiple of the iteration budget the paper's QP solver gets when its answer is no
/// descent direction away from a stationary point.
pub const MAX_RETRY_FACTOR: usize = 64;
/// Default of the no-progress rule: the stage has converged to working precision when the merit
/// function fell by less than this (relative) over the last [`PROGRESS_WINDOW`] iterations. A sum of
/// squares that changes by 1e-8 changes the RMS distance error by 5e-9 of itself, nanometres at most.
pub const PROGRESS_RTOL: f64 = 1e-8;
/// A stage that stops counts as converged if the exact QP at its final iterate predicts a decrease of
/// the merit function below this (relative); otherwise it has stalled above the optimum.
pub const STATIONARY_RTOL: f64 = 1e-4;
/// The paper's QP solver is asked again (with a larger budget, [`MAX_RETRY_FACTOR`]) while the exact
/// QP predicts a decrease of the merit function above this (relative).
pub const PAPER_RETRY_RTOL: f64 = 1e-8;
/// ... or below this absolute amount (the merit is a mean over pairs in mm²: 1e-12 mm² is a nanometre
/// RMS), which matters on noise-free data where ψ itself is at the rounding level.
pub const STATIONARY_ABS_MM2: f64 = 1e-12;

/// The floor added to each objective's QP multiplier in the Gauss–Newton curvature
/// ([`Hessian::GaussNewton`]): at a minimax kink the multipliers often put (nearly) all weight on one
/// or two reflectors, and parameters that only the others see (their reflector coordinates) would get
/// no curvature at all; with the floor their steps stay those of a damped Gauss–Newton step.
pub const CURVATURE_FLOOR: f64 = 0.02;

/// Is a predicted change of the merit function negligible against its value `phi0`?
fn negligible(predicted: f64, phi0: f64) -> bool {
    predicted > -1e-15 * phi0.abs().max(1e-300)
}

/// The multipliers of the `n_obj` objective rows of a QP solution.
fn objective_multipliers(sol: &QpSolution, n_obj: usize) -> Vec<f64> {
    sol.nu.iter().take(n_obj).copied().collect()
}

/// `h` with a ridge of 1e-8 of its mean diagonal (positive definite where it is only semi-definite:
/// parameters the data hardly see).
fn regularised(mut h: DMatrix<f64>) -> DMatrix<f64> {
    let m = h.nrows();
    let mean_diag = (h.trace() / m.max(1) as f64).max(1e-12);
    for i in 0..m {
        h[(i, i)] += 1e-8 * mean_diag;
    }
    h
}

/// Non-finite values in the problem at the start point.
#[derive(Debug)]
pub struct NonFiniteStart;

impl<P: MinimaxProblem> SqpState<P> {
    /// The curvature this solve uses: the settings', or BFGS where the problem has no Gauss–Newton
    /// matrix.
    pub fn curvature_used(&self) -> Hessian {
        if self.gauss_newton_unavailable {
            Hessian::Bfgs
        } else {
            self.settings.hessian.resolved(None)
        }
    }

    /// Start at y = 0 with the initial curvature H₀ (typically the problem's Gauss–Newton matrix).
    pub fn new(
        problem: P,
        settings: SqpSettings,
        h0: DMatrix<f64>,
    ) -> Result<Self, NonFiniteStart> {
        let y = DVector::zeros(problem.dim());
        let eval = problem.evaluate(&y);
        if !eval.is_finite() || h0.nrows() != y.len() || h0.ncols() != y.len() {
            return Err(NonFiniteStart);
        }
        let h = regularised(h0);
        if !h.iter().all(|v| v.is_finite()) {
            return Err(NonFiniteStart);
        }
        let start_gradient_scale = eval.grad.iter().map(|g| g.amax()).fold(0.0, f64::max);
        Ok(Self {
            problem,
            y,
            eval,
            h,
            start_gradient_scale,
            gauss_newton_unavailable: false,
            rho: 1.0,
            settings,
            iterations: 0,
            last_nu: None,
            merit_history: Vec::new(),
        })
    }

    pub fn eval(&self) -> &Eval {
        &self.eval
    }

    fn merit(&self, f: &[f64], cons: &[f64]) -> f64 {
        f.iter().copied().fold(f64::NEG_INFINITY, f64::max)
            + self.rho * cons.iter().map(|c| c.max(0.0)).sum::<f64>()
    }

    fn lagrangian_gradient(eval: &Eval, nu: &DVector<f64>) -> DVector<f64> {
        let n_obj = eval.f.len();
        let mut g = DVector::zeros(eval.grad[0].len());
        for i in 0..n_obj {
            g.axpy(nu[i], &eval.grad[i], 1.0);
        }
        for (l, cg) in eval.cons_grad.iter().enumerate() {
            g.axpy(nu[n_obj + l], cg, 1.0);
        }
        g
    }

    /// Rows `A` and constants `b` of this iterate's epigraph QP (objective rows first).
    fn qp_rows(&self) -> (DMatrix<f64>, DVector<f64>) {
        let psi = self.eval.psi();
        let m = self.problem.dim();
        let n_obj = self.eval.f.len();
        let p = n_obj + self.eval.cons.len();
        let mut a = DMatrix::zeros(p, m);
        let mut b = DVector::zeros(p);
        for i in 0..n_obj {
            a.row_mut(i).copy_from(&self.eval.grad[i].transpose());
            b[i] = self.eval.f[i] - psi;
        }
        for (l, (c, g)) in self.eval.cons.iter().zip(&self.eval.cons_grad).enumerate() {
            a.row_mut(n_obj + l).copy_from(&g.transpose());
            b[n_obj + l] = *c;
        }
        (a, b)
    }

    /// Solve this iterate's QP. A `retry` factor above 1 asks the paper's solver for a cold start
    /// (λ⁰ = 0, as the paper starts) with that many times the iteration budget.
    fn solve_qp(&self, stop: &dyn Fn() -> bool, retry: usize) -> Result<QpSolution, Termination> {
        let (a, b) = self.qp_rows();
        let Some(chol) = self.h.clone().cholesky() else {
            return Err(Termination::Stalled);
        };
        let qp = Qp {
            h: &self.h,
            h_chol: &chol,
            a: &a,
            b: &b,
            n_obj: self.eval.f.len(),
        };
        Ok(match self.settings.qp {
            QpMethod::Exact => solve_exact(&qp),
            QpMethod::Paper => solve_paper(
                &qp,
                SubgradientSettings {
                    max_iterations: self.settings.max_qp_iterations.saturating_mul(retry),
                    tolerance: 1e-12,
                    warm_nu: if retry > 1 {
                        None
                    } else {
                        self.last_nu.clone()
                    },
                },
                stop,
            ),
        })
    }

    /// One outer iteration — QP, line search, BFGS update — polling `stop` inside long QP solves; a
    /// stop ends the iteration with [`Termination::Cancelled`] and leaves the iterate unchanged.
    pub fn next_iter(&mut self, stop: &dyn Fn() -> bool) -> SqpStep {
        let mut step = self.iterate(stop);
        // Whatever ended the stage, it counts as converged only if the exact QP at the final iterate
        // predicts no meaningful decrease; a stop above the optimum is reported as `Stalled`.
        if let Some(
            term @ (Termination::Converged | Termination::NoProgress | Termination::Stalled),
        ) = step.termination
        {
            step.termination = Some(match (term, self.is_stationary()) {
                (Termination::Stalled, true) => Termination::Converged,
                (_, false) => Termination::Stalled,
                (term, true) => term,
            });
        }
        step
    }

    /// Whether the exact solution of the current iterate's QP predicts a decrease of the merit
    /// function below [`STATIONARY_RTOL`] (relative) or [`STATIONARY_ABS_MM2`]: a first-order
    /// stationary point to working precision.
    fn is_stationary(&self) -> bool {
        self.is_stationary_within(STATIONARY_RTOL)
    }

    /// [`Self::is_stationary`] with `rtol` in place of [`STATIONARY_RTOL`].
    fn is_stationary_within(&self, rtol: f64) -> bool {
        let Some(chol) = self.h.clone().cholesky() else {
            return false;
        };
        let (a, b) = self.qp_rows();
        let exact = solve_exact(&Qp {
            h: &self.h,
            h_chol: &chol,
            a: &a,
            b: &b,
            n_obj: self.eval.f.len(),
        });
        let phi = self.merit(&self.eval.f, &self.eval.cons);
        self.predicted_change(&exact) > -(rtol * phi.abs() + STATIONARY_ABS_MM2)
    }

    /// A stopped iteration: the iterate unchanged, `term` as its termination.
    fn done(&self, term: Termination, kkt: f64, sol: Option<&QpSolution>) -> SqpStep {
        let n_obj = self.eval.f.len();
        SqpStep {
            f: self.eval.f.clone(),
            psi: self.eval.psi(),
            step_norm: 0.0,
            kkt_residual: kkt,
            lambda: sol.map_or_else(
                || vec![f64::NAN; n_obj],
                |s| objective_multipliers(s, n_obj),
            ),
            qp_iterations: sol.map_or(0, |s| s.iterations),
            termination: Some(term),
        }
    }

    fn iterate(&mut self, stop: &dyn Fn() -> bool) -> SqpStep {
        self.iterations += 1;
        let sol = match self.solve_qp_with_retries(stop) {
            Ok(sol) => sol,
            Err((term, sol)) => return self.done(term, f64::NAN, sol.as_ref()),
        };
        let phi0 = self.merit(&self.eval.f, &self.eval.cons);
        let kkt = self.first_order_residual(&sol.nu);
        // Penalty large enough for the constraint multipliers.
        let n_obj = self.eval.f.len();
        let max_mu = sol.nu.iter().skip(n_obj).copied().fold(0.0, f64::max);
        self.rho = self.rho.max(1.5 * max_mu + 1e-9);
        // Predicted change of the merit function along s (linear model).
        let predicted = self.predicted_change(&sol);
        if sol.s.norm() < self.settings.step_tolerance || negligible(predicted, phi0) {
            return self.done(Termination::Converged, kkt, Some(&sol));
        }
        let Some((y_new, eval_new)) = self.line_search(&sol, phi0, predicted) else {
            return self.done(Termination::Stalled, kkt, Some(&sol));
        };
        self.update_curvature(&y_new, &eval_new, &sol.nu);
        let step_norm = (&y_new - &self.y).norm();
        self.last_nu = Some(sol.nu.clone());
        self.y = y_new;
        self.eval = eval_new;
        self.merit_history
            .push((self.eval.psi(), self.eval.violation()));
        // The paper's QP is inexact: a short step there ends the stage only where the exact QP
        // finds no decrease above `PAPER_RETRY_RTOL` (else the next iteration's QP is retried).
        let short_step_ends = step_norm < self.settings.step_tolerance
            && (self.settings.qp != QpMethod::Paper || self.is_stationary_within(PAPER_RETRY_RTOL));
        let termination = if short_step_ends {
            Some(Termination::Converged)
        } else if self.no_progress() {
            Some(Termination::NoProgress)
        } else {
            None
        };
        SqpStep {
            f: self.eval.f.clone(),
            psi: self.eval.psi(),
            step_norm,
            kkt_residual: kkt,
            lambda: objective_multipliers(&sol, n_obj),
            qp_iterations: sol.iterations,
            termination,
        }
    }

    /// This iterate's QP. The subgradient method is inexact: an answer that is no descent direction
    /// (or a step shorter than the stopping rule's) says little about the iterate, so it is solved
    /// again from the paper's cold start with 4, then 16, then 64 times the budget, as long as no
    /// descent is found and the exact QP predicts a decrease above [`PAPER_RETRY_RTOL`] (it only
    /// decides whether to keep going; the step is the subgradient method's).
    fn solve_qp_with_retries(
        &self,
        stop: &dyn Fn() -> bool,
    ) -> Result<QpSolution, (Termination, Option<QpSolution>)> {
        let mut sol = self.solve_qp(stop, 1).map_err(|term| (term, None))?;
        if stop() {
            return Err((Termination::Cancelled, Some(sol)));
        }
        let phi0 = self.merit(&self.eval.f, &self.eval.cons);
        // No descent, or a step the stopping rule would take for convergence.
        let short = |sol: &QpSolution| {
            negligible(self.predicted_change(sol), phi0)
                || sol.s.norm() < self.settings.step_tolerance
        };
        if self.settings.qp != QpMethod::Paper || !short(&sol) {
            return Ok(sol);
        }
        let mut used = sol.iterations;
        let mut factor = 4;
        loop {
            if let Ok(again) = self.solve_qp(stop, factor) {
                used += again.iterations;
                if again.tau < sol.tau {
                    sol = again;
                }
            }
            if stop() {
                return Err((Termination::Cancelled, Some(sol)));
            }
            if !short(&sol)
                || factor >= MAX_RETRY_FACTOR
                || self.is_stationary_within(PAPER_RETRY_RTOL)
            {
                break;
            }
            factor *= 4;
        }
        sol.iterations = used;
        Ok(sol)
    }

    /// Backtracking (Armijo) line search on the ℓ1 merit function along the QP step. The full step is
    /// tried with values and gradients at once (it is accepted in most iterations, and its evaluation
    /// is then reused); shorter steps with values only. `None` when no step decreases the merit.
    fn line_search(
        &self,
        sol: &QpSolution,
        phi0: f64,
        predicted: f64,
    ) -> Option<(DVector<f64>, Eval)> {
        let full = &self.y + &sol.s;
        let full_eval = self.problem.evaluate(&full);
        let mut alpha = 1.0;
        let (y_new, alpha) = loop {
            let y_new = &self.y + &sol.s * alpha;
            let (f, cons) = if alpha == 1.0 {
                (full_eval.f.clone(), full_eval.cons.clone())
            } else {
                self.problem.values(&y_new)
            };
            let phi = self.merit(&f, &cons);
            if phi.is_finite() && phi <= phi0 + 1e-4 * alpha * predicted {
                break (y_new, alpha);
            }
            alpha *= 0.5;
            if alpha < 1e-10 {
                return None;
            }
        };
        let eval_new = if alpha == 1.0 {
            full_eval
        } else {
            self.problem.evaluate(&y_new)
        };
        eval_new.is_finite().then_some((y_new, eval_new))
    }

    /// The next iterate's curvature: the problem's Gauss–Newton matrix weighted by this iteration's
    /// multipliers (each floored at [`CURVATURE_FLOOR`]), or the BFGS update where the settings ask
    /// for it or the problem has no Gauss–Newton matrix.
    fn update_curvature(&mut self, y_new: &DVector<f64>, eval_new: &Eval, nu: &DVector<f64>) {
        if self.settings.hessian == Hessian::GaussNewton {
            let weights: Vec<f64> = (0..eval_new.f.len())
                .map(|i| nu[i].max(0.0) + CURVATURE_FLOOR)
                .collect();
            if let Some(h) = self.problem.curvature(y_new, &weights)
                && h.iter().all(|v| v.is_finite())
            {
                self.h = regularised(h);
                return;
            }
            self.gauss_newton_unavailable = true;
        }
        self.bfgs_update(y_new, eval_new, nu);
    }

    /// BFGS on the Lagrangian with Powell's damping (keeps H positive definite).
    fn bfgs_update(&mut self, y_new: &DVector<f64>, eval_new: &Eval, nu: &DVector<f64>) {
        let step = y_new - &self.y;
        let q = Self::lagrangian_gradient(eval_new, nu) - Self::lagrangian_gradient(&self.eval, nu);
        let hs = &self.h * &step;
        let shs = step.dot(&hs);
        let sq = step.dot(&q);
        if shs > 0.0 {
            let theta = if sq >= 0.2 * shs {
                1.0
            } else {
                0.8 * shs / (shs - sq)
            };
            let r = &q * theta + &hs * (1.0 - theta);
            let sr = step.dot(&r);
            if sr > 0.0 {
                self.h += &r * r.transpose() / sr - &hs * hs.transpose() / shs;
                // Keep exact symmetry.
                self.h = (&self.h + self.h.transpose()) * 0.5;
            }
        }
    }

    /// The no-progress rule: the merit fell by less than the progress tolerance (relative) over the
    /// last [`PROGRESS_WINDOW`] accepted steps (recomputed with the current penalty, which may have
    /// grown since).
    fn no_progress(&self) -> bool {
        let n = self.merit_history.len();
        self.settings.progress_tolerance > 0.0 && n > PROGRESS_WINDOW && {
            let merit = |(psi, violation): (f64, f64)| psi + self.rho * violation;
            let now = merit(self.merit_history[n - 1]);
            let before = merit(self.merit_history[n - 1 - PROGRESS_WINDOW]);
            before - now <= self.settings.progress_tolerance * now.abs()
        }
    }

    /// Change of the merit function along the QP step that the linear model predicts.
    fn predicted_change(&self, sol: &QpSolution) -> f64 {
        sol.tau - self.rho * self.eval.violation()
    }

    /// First-order optimality residual of the minimax problem at the current iterate for multipliers ν:
    /// ‖Σλ_i ∇f_i + Σμ_l ∇c_l‖∞ + Σλ_i (ψ − f_i) + Σ μ_l |c_l| + Σ c_l⁺, relative to the gradient scale.
    fn first_order_residual(&self, nu: &DVector<f64>) -> f64 {
        let g = Self::lagrangian_gradient(&self.eval, nu);
        let current = self.eval.grad.iter().map(|g| g.amax()).fold(0.0, f64::max);
        // Several objectives: their gradients stay large at a minimax optimum while the λ-weighted
        // sum vanishes, so they scale it. One objective (one reflector): its own gradient vanishes,
        // so the start's scales it.
        let scale = if self.eval.f.len() == 1 {
            self.start_gradient_scale
        } else {
            current
        }
        .max(1e-300);
        let psi = self.eval.psi();
        let psi_scale = psi.abs().max(1e-300);
        let n_obj = self.eval.f.len();
        let comp: f64 = (0..n_obj)
            .map(|i| nu[i] * (psi - self.eval.f[i]))
            .sum::<f64>()
            / psi_scale;
        let cons: f64 = self
            .eval
            .cons
            .iter()
            .enumerate()
            .map(|(l, c)| nu[n_obj + l] * c.abs() + c.max(0.0))
            .sum();
        g.amax() / scale + comp + cons
    }
}
