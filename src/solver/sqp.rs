//! Algorithm I/II's outer loop: sequential quadratic programming on the minimax problem with a BFGS
//! Hessian of the Lagrangian, an ℓ1 merit line search and a parameter-step stopping rule. One call of
//! [`SqpState::step`] is one outer iteration.

use super::problem::{Eval, MinimaxProblem};
use super::qp::{Qp, QpSolution, SubgradientSettings, solve_exact, solve_paper};
use super::{QpMethod, Termination};
use nalgebra::{DMatrix, DVector};

/// Tunables of the outer loop.
#[derive(Clone, Copy, Debug)]
pub struct SqpSettings {
    pub qp: QpMethod,
    pub step_tolerance: f64,
    pub max_qp_iterations: usize,
}

/// What one outer iteration did.
#[derive(Clone, Debug)]
pub struct SqpStep {
    pub f: [f64; 3],
    pub psi: f64,
    pub step_norm: f64,
    pub kkt_residual: f64,
    pub qp_iterations: usize,
    /// `Some` when the loop should stop.
    pub termination: Option<Termination>,
}

/// The state of an SQP run; advance it with [`SqpState::step`].
pub struct SqpState<P: MinimaxProblem> {
    pub problem: P,
    pub y: DVector<f64>,
    eval: Eval,
    h: DMatrix<f64>,
    /// ℓ1 penalty of the merit function.
    rho: f64,
    settings: SqpSettings,
    pub iterations: usize,
    /// Multipliers and step length of the previous iteration (warm start of the paper's QP solver).
    last_nu: Option<DVector<f64>>,
    last_step_norm: Option<f64>,
}

/// Non-finite values in the problem at the start point.
#[derive(Debug)]
pub struct NonFiniteStart;

impl<P: MinimaxProblem> SqpState<P> {
    /// Start at y = 0 with the problem's Gauss–Newton matrix as H₀.
    pub fn new(problem: P, settings: SqpSettings) -> Result<Self, NonFiniteStart> {
        let h0 = problem.gauss_newton(&DVector::zeros(problem.dim()));
        Self::with_hessian(problem, settings, h0)
    }

    /// Start at y = 0 with a given H₀ (e.g. a Gauss–Newton matrix computed already).
    pub fn with_hessian(
        problem: P,
        settings: SqpSettings,
        h0: DMatrix<f64>,
    ) -> Result<Self, NonFiniteStart> {
        let y = DVector::zeros(problem.dim());
        let eval = problem.evaluate(&y);
        if !eval.is_finite() || h0.nrows() != y.len() || h0.ncols() != y.len() {
            return Err(NonFiniteStart);
        }
        let mut h = h0;
        let m = h.nrows();
        let mean_diag = (h.trace() / m.max(1) as f64).max(1e-12);
        for i in 0..m {
            h[(i, i)] += 1e-8 * mean_diag;
        }
        if !h.iter().all(|v| v.is_finite()) {
            return Err(NonFiniteStart);
        }
        Ok(Self {
            problem,
            y,
            eval,
            h,
            rho: 1.0,
            settings,
            iterations: 0,
            last_nu: None,
            last_step_norm: None,
        })
    }

    pub fn eval(&self) -> &Eval {
        &self.eval
    }

    fn merit(&self, f: &[f64; 3], cons: &[f64]) -> f64 {
        f.iter().copied().fold(f64::NEG_INFINITY, f64::max)
            + self.rho * cons.iter().map(|c| c.max(0.0)).sum::<f64>()
    }

    fn lagrangian_gradient(eval: &Eval, nu: &DVector<f64>) -> DVector<f64> {
        let mut g = DVector::zeros(eval.grad[0].len());
        for i in 0..3 {
            g.axpy(nu[i], &eval.grad[i], 1.0);
        }
        for (l, cg) in eval.cons_grad.iter().enumerate() {
            g.axpy(nu[3 + l], cg, 1.0);
        }
        g
    }

    /// Solve this iterate's QP.
    fn solve_qp(&self, stop: &dyn Fn() -> bool) -> Result<QpSolution, Termination> {
        let psi = self.eval.psi();
        let m = self.problem.dim();
        let p = 3 + self.eval.cons.len();
        let mut a = DMatrix::zeros(p, m);
        let mut b = DVector::zeros(p);
        for i in 0..3 {
            a.row_mut(i).copy_from(&self.eval.grad[i].transpose());
            b[i] = self.eval.f[i] - psi;
        }
        for (l, (c, g)) in self.eval.cons.iter().zip(&self.eval.cons_grad).enumerate() {
            a.row_mut(3 + l).copy_from(&g.transpose());
            b[3 + l] = *c;
        }
        let Some(chol) = self.h.clone().cholesky() else {
            return Err(Termination::Stalled);
        };
        let qp = Qp {
            h: &self.h,
            h_chol: &chol,
            a: &a,
            b: &b,
            n_obj: 3,
        };
        Ok(match self.settings.qp {
            QpMethod::Exact => solve_exact(&qp),
            QpMethod::Paper => solve_paper(
                &qp,
                SubgradientSettings {
                    max_iterations: self.settings.max_qp_iterations,
                    tolerance: 1e-12,
                    warm_nu: self.last_nu.clone(),
                    gamma_cap: None,
                },
                stop,
            ),
        })
    }

    /// One outer iteration: QP, line search, BFGS update.
    pub fn step(&mut self) -> SqpStep {
        self.step_with_stop(&|| false)
    }

    /// [`SqpState::step`], polling `stop` inside long QP solves; a stop ends the iteration with
    /// [`Termination::Cancelled`] and leaves the iterate unchanged.
    pub fn step_with_stop(&mut self, stop: &dyn Fn() -> bool) -> SqpStep {
        self.iterations += 1;
        let done = |state: &Self, term: Termination, kkt: f64, qp_it: usize| SqpStep {
            f: state.eval.f,
            psi: state.eval.psi(),
            step_norm: 0.0,
            kkt_residual: kkt,
            qp_iterations: qp_it,
            termination: Some(term),
        };
        let sol = match self.solve_qp(stop) {
            Ok(sol) => sol,
            Err(term) => return done(self, term, f64::NAN, 0),
        };
        if stop() {
            return done(self, Termination::Cancelled, f64::NAN, sol.iterations);
        }
        let kkt = self.first_order_residual(&sol.nu);
        // Penalty large enough for the constraint multipliers.
        let max_mu = sol.nu.iter().skip(3).copied().fold(0.0, f64::max);
        self.rho = self.rho.max(1.5 * max_mu + 1e-9);

        let phi0 = self.merit(&self.eval.f, &self.eval.cons);
        // Predicted change of the merit function along s (linear model).
        let predicted = sol.tau - self.rho * self.eval.violation();
        let s_norm = sol.s.norm();
        if s_norm < self.settings.step_tolerance || predicted > -1e-15 * phi0.abs().max(1e-300) {
            return done(self, Termination::Converged, kkt, sol.iterations);
        }
        // The full step is tried with values and gradients at once (it is accepted in most
        // iterations, and its evaluation is then reused); shorter steps with values only.
        let full = &self.y + &sol.s;
        let full_eval = self.problem.evaluate(&full);
        let mut alpha = 1.0;
        let accepted = loop {
            let y_new = &self.y + &sol.s * alpha;
            let (f, cons) = if alpha == 1.0 {
                (full_eval.f, full_eval.cons.clone())
            } else {
                self.problem.values(&y_new)
            };
            let phi = self.merit(&f, &cons);
            if phi.is_finite() && phi <= phi0 + 1e-4 * alpha * predicted {
                break Some((y_new, alpha));
            }
            alpha *= 0.5;
            if alpha < 1e-10 {
                break None;
            }
        };
        let Some((y_new, alpha)) = accepted else {
            return done(self, Termination::Stalled, kkt, sol.iterations);
        };
        let eval_new = if alpha == 1.0 {
            full_eval
        } else {
            self.problem.evaluate(&y_new)
        };
        if !eval_new.is_finite() {
            return done(self, Termination::Stalled, kkt, sol.iterations);
        }
        // BFGS on the Lagrangian with Powell's damping (keeps H positive definite).
        let step = &y_new - &self.y;
        let q = Self::lagrangian_gradient(&eval_new, &sol.nu)
            - Self::lagrangian_gradient(&self.eval, &sol.nu);
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
        let step_norm = step.norm();
        self.last_nu = Some(sol.nu.clone());
        self.last_step_norm = Some(step_norm);
        self.y = y_new;
        self.eval = eval_new;
        let termination =
            (step_norm < self.settings.step_tolerance).then_some(Termination::Converged);
        SqpStep {
            f: self.eval.f,
            psi: self.eval.psi(),
            step_norm,
            kkt_residual: kkt,
            qp_iterations: sol.iterations,
            termination,
        }
    }

    /// First-order optimality residual of the minimax problem at the current iterate for multipliers ν:
    /// ‖Σλ_i ∇f_i + Σμ_l ∇c_l‖∞ + Σλ_i (ψ − f_i) + Σ μ_l |c_l| + Σ c_l⁺, relative to the gradient scale.
    fn first_order_residual(&self, nu: &DVector<f64>) -> f64 {
        let g = Self::lagrangian_gradient(&self.eval, nu);
        let scale = self
            .eval
            .grad
            .iter()
            .map(|g| g.amax())
            .fold(0.0, f64::max)
            .max(1e-300);
        let psi = self.eval.psi();
        let psi_scale = psi.abs().max(1e-300);
        let comp: f64 = (0..3).map(|i| nu[i] * (psi - self.eval.f[i])).sum::<f64>() / psi_scale;
        let cons: f64 = self
            .eval
            .cons
            .iter()
            .enumerate()
            .map(|(l, c)| nu[3 + l] * c.abs() + c.max(0.0))
            .sum();
        g.amax() / scale + comp + cons
    }
}
