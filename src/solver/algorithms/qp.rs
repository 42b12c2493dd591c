//! The QP subproblem (25) of each SQP iteration, in epigraph form:
//!
//! ```text
//!   minimise  ½ sᵀ H s + τ
//!   s.t.      b_j + a_jᵀ s − e_j τ ≤ 0,   j = 1..p
//! ```
//! where the first `n_obj` rows are the linearised objectives (`b_i = f_i − ψ`, `a_i = ∇f_i`, `e_i = 1`) and
//! the remaining rows the linearised constraints (`e_l = 0`). Its Lagrangian is
//! `L = ½ sᵀHs + τ + νᵀ(b + A s − e τ)` with `ν ≥ 0`; stationarity gives `s = −H⁻¹Aᵀν` and `eᵀν = 1`.
//!
//! Two solvers:
//! * [`solve_exact`]: the dual `max −½ νᵀ A H⁻¹ Aᵀ ν + bᵀν, ν ≥ 0, eᵀν = 1` has at most six variables, so every
//!   support set is tried and the best dual-feasible candidate is exact.
//! * [`solve_paper`]: the paper's primal-dual subgradient iteration (eqs. 29–31) on `z = (s, τ, ν)` with the
//!   normalised step `α_p = γ_p / ‖T^p‖`, `γ_p = γ₀ · P₀ / (P₀ + p)` (so Σγ_p = ∞, Σγ_p² < ∞).

use nalgebra::{Cholesky, DMatrix, DVector, Dyn};

/// A QP instance. `h` must be symmetric positive definite.
pub struct Qp<'a> {
    pub h: &'a DMatrix<f64>,
    pub h_chol: &'a Cholesky<f64, Dyn>,
    /// Constraint rows a_jᵀ (p × m).
    pub a: &'a DMatrix<f64>,
    pub b: &'a DVector<f64>,
    pub n_obj: usize,
}

/// A QP solution.
#[derive(Clone, Debug)]
pub struct QpSolution {
    pub s: DVector<f64>,
    pub tau: f64,
    /// Multipliers of the rows (objective rows sum to one).
    pub nu: DVector<f64>,
    /// Max of primal infeasibility, dual infeasibility and complementarity of (s, τ, ν).
    pub kkt_residual: f64,
    pub iterations: usize,
}

impl QpSolution {
    /// The solution with step `s` and multipliers `nu`, its τ and KKT residual computed on `qp`.
    fn new(qp: &Qp, s: DVector<f64>, nu: DVector<f64>, iterations: usize) -> Self {
        let tau = qp.tau_for(&s);
        let kkt_residual = qp.kkt_residual(&s, tau, &nu);
        Self {
            s,
            tau,
            nu,
            kkt_residual,
            iterations,
        }
    }
}

impl Qp<'_> {
    fn e(&self, j: usize) -> f64 {
        if j < self.n_obj { 1.0 } else { 0.0 }
    }

    /// τ that makes the objective rows feasible for this s.
    fn tau_for(&self, s: &DVector<f64>) -> f64 {
        (0..self.n_obj)
            .map(|j| self.b[j] + self.a.row(j).dot(&s.transpose()))
            .fold(f64::NEG_INFINITY, f64::max)
    }

    /// KKT residual of a candidate (scaled by the size of the data).
    pub fn kkt_residual(&self, s: &DVector<f64>, tau: f64, nu: &DVector<f64>) -> f64 {
        let stat = (self.h * s + self.a.transpose() * nu).amax();
        let sum_e: f64 = (0..self.n_obj).map(|j| nu[j]).sum();
        let mut primal: f64 = 0.0;
        let mut comp: f64 = 0.0;
        let mut dual_neg: f64 = 0.0;
        for j in 0..self.b.len() {
            let g = self.b[j] + self.a.row(j).dot(&s.transpose()) - self.e(j) * tau;
            primal = primal.max(g);
            comp = comp.max((nu[j] * g).abs());
            dual_neg = dual_neg.max(-nu[j]);
        }
        stat.max((1.0 - sum_e).abs())
            .max(primal)
            .max(comp)
            .max(dual_neg)
    }
}

/// Exact solution through the dual.
pub fn solve_exact(qp: &Qp) -> QpSolution {
    let p = qp.b.len();
    let m = qp.h.nrows();
    let hinv_at = qp.h_chol.solve(&qp.a.transpose()); // m × p
    let mm = qp.a * &hinv_at; // p × p, PSD
    let ridge = 1e-13 * (1.0 + mm.diagonal().amax());
    let mut best: Option<(f64, DVector<f64>)> = None;
    for mask in 1u32..(1u32 << p) {
        if (0..qp.n_obj).all(|j| mask & (1 << j) == 0) {
            continue;
        }
        let idx: Vec<usize> = (0..p).filter(|j| mask & (1 << j) != 0).collect();
        let k = idx.len();
        let mut kkt = DMatrix::zeros(k + 1, k + 1);
        let mut rhs = DVector::zeros(k + 1);
        for (r, &jr) in idx.iter().enumerate() {
            for (c, &jc) in idx.iter().enumerate() {
                kkt[(r, c)] = mm[(jr, jc)] + if r == c { ridge } else { 0.0 };
            }
            kkt[(r, k)] = qp.e(jr);
            kkt[(k, r)] = qp.e(jr);
            rhs[r] = qp.b[jr];
        }
        rhs[k] = 1.0;
        let Some(sol) = kkt.lu().solve(&rhs) else {
            continue;
        };
        if sol.iter().take(k).any(|v| !v.is_finite() || *v < -1e-12) {
            continue;
        }
        let mut nu = DVector::zeros(p);
        for (r, &j) in idx.iter().enumerate() {
            nu[j] = sol[r].max(0.0);
        }
        let sum: f64 = (0..qp.n_obj).map(|j| nu[j]).sum();
        if sum <= 0.0 {
            continue;
        }
        for j in 0..qp.n_obj {
            nu[j] /= sum;
        }
        let value = -0.5 * nu.dot(&(&mm * &nu)) + qp.b.dot(&nu);
        if best.as_ref().is_none_or(|(v, _)| value > *v) {
            best = Some((value, nu));
        }
    }
    let nu = best.map(|(_, nu)| nu).unwrap_or_else(|| {
        // Cannot happen for a consistent QP (a single objective row is always a candidate), but keep a
        // defined answer: the equal-weight objective combination.
        let mut nu = DVector::zeros(p);
        for j in 0..qp.n_obj {
            nu[j] = 1.0 / qp.n_obj as f64;
        }
        nu
    });
    let s = -(&hinv_at * &nu);
    debug_assert_eq!(s.len(), m);
    QpSolution::new(qp, s, nu, 1usize << p)
}

/// Settings of the paper's subgradient solver.
#[derive(Clone, Debug)]
pub struct SubgradientSettings {
    pub max_iterations: usize,
    /// Stop when ‖T‖ falls below this.
    pub tolerance: f64,
    /// Start multipliers (the previous outer iteration's); `None` starts from λ⁰ = 0 as the paper does.
    pub warm_nu: Option<DVector<f64>>,
}

/// The paper's primal-dual subgradient method (eqs. 29–31, Algorithm I's inner loop).
///
/// The iteration runs on an equivalent, preconditioned form of the QP: with `H = L Lᵀ`, the variables
/// `w = Lᵀ s / √σ` and the objective divided by σ (the size of the objective rows), the Hessian is the
/// identity and every block of `T` is of order one, while the multipliers are unchanged. Started at
/// `Δx⁰ = 0` and `λ⁰ = 0` (or the previous outer iteration's multipliers when given), with the normalised
/// step `α_p = γ_p / ‖T^p‖`. The dual part of `T` is the constraint residual and the multipliers are
/// projected onto `ν ≥ 0` after each step (the paper writes the projection as `(·)⁺`). The answer is the
/// iterate with the smallest KKT residual, or — when better — the primal recovered from the ergodic
/// average ν̄ of the multipliers over the second half of the run, `s = −H⁻¹Aᵀν̄`.
/// `stop` is polled every 256 iterations; when it says yes the best answer so far is returned.
pub fn solve_paper(qp: &Qp, settings: SubgradientSettings, stop: &dyn Fn() -> bool) -> QpSolution {
    let p = qp.b.len();
    let m = qp.h.nrows();
    let l = qp.h_chol.l();
    // Ã = A L⁻ᵀ  (p × m)
    let a_t = l
        .solve_lower_triangular(&qp.a.transpose())
        .unwrap_or_else(|| qp.a.transpose())
        .transpose();
    let sigma = (0..qp.n_obj)
        .map(|j| qp.b[j].abs().max(a_t.row(j).norm_squared()))
        .fold(1e-300, f64::max);
    let a_w = &a_t / sigma.sqrt();
    let b_w = qp.b / sigma;
    let eye = DMatrix::<f64>::identity(m, m);
    let Some(eye_chol) = eye.clone().cholesky() else {
        return solve_exact(qp);
    };
    let scaled = Qp {
        h: &eye,
        h_chol: &eye_chol,
        a: &a_w,
        b: &b_w,
        n_obj: qp.n_obj,
    };
    let (w, nu, iterations) = subgradient(&scaled, &settings, stop);
    // Back to s = √σ L⁻ᵀ w.
    let s = l
        .transpose()
        .solve_upper_triangular(&(w * sigma.sqrt()))
        .unwrap_or_else(|| DVector::zeros(m));
    debug_assert_eq!(nu.len(), p);
    QpSolution::new(qp, s, nu, iterations)
}

/// The iteration z ← z − γ_p T/‖T‖ on a QP whose Hessian is the identity (the preconditioned form
/// [`solve_paper`] builds: `H s = s`, `H⁻¹ d = d`); returns (s, ν, iterations). Each iteration is two
/// products with `A` and `Aᵀ` and a pass over the rows, with no fresh memory: the polishing retries of
/// the SQP's last iterations run it for 10⁵ iterations and more.
fn subgradient(
    qp: &Qp,
    settings: &SubgradientSettings,
    stop: &dyn Fn() -> bool,
) -> (DVector<f64>, DVector<f64>, usize) {
    let p = qp.b.len();
    let m = qp.a.ncols();
    let n_obj = qp.n_obj;
    let at = qp.a.transpose();
    let warm = settings.warm_nu.as_ref().filter(|w| w.len() == p);
    // γ₀, the scale of s: the length of the Newton step of the Lagrangian at the start multipliers
    // (with λ⁰ = 0, of the worst objective). It vanishes at a KKT point.
    let worst = (0..n_obj)
        .max_by(|&i, &j| qp.b[i].total_cmp(&qp.b[j]))
        .unwrap_or(0);
    let direction = match warm {
        Some(w) => &at * w,
        None => qp.a.row(worst).transpose(),
    };
    let gamma0 = direction.norm().max(1e-12);
    let p0 = 50.0;
    let mut s = DVector::zeros(m);
    let mut nu = warm.cloned().unwrap_or_else(|| DVector::zeros(p));
    let mut tau = qp.tau_for(&s);
    let mut best = (f64::INFINITY, s.clone(), nu.clone());
    let mut iterations = 0;
    // A s, Aᵀν, and T = [s + Aᵀν ; 1 − eᵀν ; projected −(b + A s − e τ)].
    let mut a_s = DVector::zeros(p);
    let mut ts = DVector::zeros(m);
    let mut tnu = DVector::zeros(p);
    // Ergodic average of the multipliers over the second half of the run (primal recovery below).
    let mut nu_sum = DVector::zeros(p);
    let mut nu_count = 0usize;
    for it in 0..settings.max_iterations {
        if it % 256 == 255 && stop() {
            break;
        }
        iterations = it + 1;
        a_s.gemv(1.0, qp.a, &s, 0.0);
        ts.gemv(1.0, &at, &nu, 0.0);
        ts += &s;
        let sum_e: f64 = nu.rows(0, n_obj).iter().sum();
        let ttau = 1.0 - sum_e;
        // τ that makes the objective rows feasible for this s: the KKT residual's.
        let tau_s = (0..n_obj)
            .map(|j| qp.b[j] + a_s[j])
            .fold(f64::NEG_INFINITY, f64::max);
        // The KKT residual of (s, τ(s), ν) (as `Qp::kkt_residual`) and the projected dual part of
        // T: a multiplier at zero with a satisfied constraint does not move.
        let (mut primal, mut comp, mut dual_neg) = (0.0f64, 0.0f64, 0.0f64);
        for j in 0..p {
            let e = qp.e(j);
            let g = qp.b[j] + a_s[j] - e * tau;
            tnu[j] = if nu[j] <= 0.0 && g < 0.0 { 0.0 } else { -g };
            let g_s = qp.b[j] + a_s[j] - e * tau_s;
            primal = primal.max(g_s);
            comp = comp.max((nu[j] * g_s).abs());
            dual_neg = dual_neg.max(-nu[j]);
        }
        let norm = (ts.norm_squared() + ttau * ttau + tnu.norm_squared()).sqrt();
        let res = ts
            .amax()
            .max(ttau.abs())
            .max(primal)
            .max(comp)
            .max(dual_neg);
        if res < best.0 {
            best.0 = res;
            best.1.copy_from(&s);
            best.2.copy_from(&nu);
        }
        if norm < settings.tolerance {
            break;
        }
        let gamma = gamma0 * p0 / (p0 + it as f64);
        let alpha = gamma / norm;
        s.axpy(-alpha, &ts, 1.0);
        tau -= ttau * alpha;
        nu.axpy(-alpha, &tnu, 1.0);
        nu.apply(|v| *v = v.max(0.0));
        if 2 * it >= settings.max_iterations {
            nu_sum += &nu;
            nu_count += 1;
        }
    }
    // Primal recovery: the exact minimiser of the Lagrangian for the averaged multipliers
    // (normalised so that the objective multipliers sum to one), if its KKT residual is smaller.
    if nu_count > 0 {
        let mut nu_avg = nu_sum / nu_count as f64;
        let sum: f64 = (0..n_obj).map(|j| nu_avg[j]).sum();
        if sum > 0.0 {
            for j in 0..n_obj {
                nu_avg[j] /= sum;
            }
            let s_avg = -(&at * &nu_avg);
            let res = qp.kkt_residual(&s_avg, qp.tau_for(&s_avg), &nu_avg);
            if res < best.0 {
                best = (res, s_avg, nu_avg);
            }
        }
    }
    (best.1, best.2, iterations)
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    fn random_qp(
        rng: &mut ChaCha8Rng,
        m: usize,
        n_obj: usize,
        n_con: usize,
    ) -> (DMatrix<f64>, DMatrix<f64>, DVector<f64>) {
        let l = DMatrix::from_fn(m, m, |_, _| rng.random_range(-1.0..1.0));
        let h = &l * l.transpose() + DMatrix::identity(m, m) * 0.5;
        let a = DMatrix::from_fn(n_obj + n_con, m, |_, _| rng.random_range(-1.0..1.0));
        let b = DVector::from_fn(n_obj + n_con, |j, _| {
            if j < n_obj {
                -rng.random_range(0.0..1.0)
            } else {
                rng.random_range(-1.0..0.2)
            }
        });
        (h, a, b)
    }

    /// Brute-force check: the exact solution is not beaten by any of many random feasible points.
    #[test]
    fn exact_solution_is_optimal_and_kkt() {
        let mut rng = ChaCha8Rng::seed_from_u64(1);
        for _ in 0..50 {
            let (h, a, b) = random_qp(&mut rng, 5, 3, 3);
            let chol = h.clone().cholesky().unwrap();
            let qp = Qp {
                h: &h,
                h_chol: &chol,
                a: &a,
                b: &b,
                n_obj: 3,
            };
            let sol = solve_exact(&qp);
            assert!(sol.kkt_residual < 1e-8, "kkt {}", sol.kkt_residual);
            let obj = |s: &DVector<f64>| 0.5 * s.dot(&(&h * s)) + qp.tau_for(s);
            let feasible =
                |s: &DVector<f64>| (3..6).all(|j| b[j] + a.row(j).dot(&s.transpose()) <= 1e-12);
            let best = obj(&sol.s);
            for _ in 0..2000 {
                let s = &sol.s + DVector::from_fn(5, |_, _| rng.random_range(-0.3..0.3));
                if feasible(&s) {
                    assert!(obj(&s) >= best - 1e-9);
                }
            }
        }
    }

    #[test]
    fn paper_solver_approaches_exact_solution() {
        let mut rng = ChaCha8Rng::seed_from_u64(2);
        let (h, a, b) = random_qp(&mut rng, 4, 3, 2);
        let chol = h.clone().cholesky().unwrap();
        let qp = Qp {
            h: &h,
            h_chol: &chol,
            a: &a,
            b: &b,
            n_obj: 3,
        };
        let exact = solve_exact(&qp);
        let paper = solve_paper(
            &qp,
            SubgradientSettings {
                max_iterations: 20_000,
                tolerance: 1e-10,
                warm_nu: None,
            },
            &|| false,
        );
        let obj = |s: &DVector<f64>| 0.5 * s.dot(&(&h * s)) + qp.tau_for(s);
        let gap = (obj(&paper.s) - obj(&exact.s)).abs();
        assert!(gap < 1e-2 * (1.0 + obj(&exact.s).abs()), "gap {gap}");
        assert!((&paper.s - &exact.s).norm() < 0.1 * (1.0 + exact.s.norm()));
    }
}
