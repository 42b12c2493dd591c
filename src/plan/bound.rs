//! What any design from the candidates could reach: a lower bound on the predicted verification
//! accuracy (docs/planning.md, *The bound*).
//!
//! The exact design's information is made of the distances between chosen configurations, a
//! quadratic function of which configurations are chosen: relaxing the choice to weights there is
//! not convex. What the distances can tell is bounded instead by what the reflector positions tell
//! with the pose of the tracker unknown — once per reflector, as a reflector's distances do not see
//! where its own points lie relative to the other reflectors': a configuration's information is
//! `Xᵀ X` with `X = [J, N]` its Jacobian rows (3 per reflector) beside the nuisance columns `N` (a
//! translation and a rotation per reflector, `I` and `−[p]×` on that reflector's rows), and that of
//! the parameters is the Schur complement `S(w)` of `Σ w_i X_iᵀ X_i` — linear in the weights, so
//! `f(w) = trace(S(w)⁻¹ P)` is convex in them (`P` the information of the verification pairs).
//!
//! Why it is a bound: the least-squares distance fit, linearised, is a linear function of the point
//! errors, unbiased for the parameters whatever each reflector's rigid motion (the distances do not
//! change with it); by Gauss–Markov its covariance is at least `σ² S(1_design)⁻¹`, so the predicted
//! verification ratio `sqrt(1 + trace(C P) / 2σ²)` of any design is at least
//! `sqrt(1 + f(1_design) / 2)` (σ cancels). The relaxation minimises f over weights `0 ≤ w ≤ 1`
//! (each candidate at most once), `Σ w = N`, which holds every design of N candidates: its minimum
//! bounds every one of them from below. The minimum is not reached exactly: the multiplicative
//! algorithm `w ← w · d` (capped at 1, rescaled to `Σ w = N`; `d_i = −∂f/∂w_i`, all equal at the
//! minimum among the weights strictly between 0 and 1) approaches it,
//! and the Frank–Wolfe gap certifies it: `f* ≥ f(w) + Σ w_i d_i − (the N largest d_i)` at any w.
//!
//! What it is a bound on: the linearised least-squares prediction
//! ([`crate::solver::uncertainty::predicted_verification_ratio`]) on the same verification
//! configurations, for designs of N from the same candidates (plus any configurations already
//! measured) — not on a measured ratio, which is higher (the prediction is optimistic), nor on
//! designs from other candidates.

use crate::par::prelude::*;
use nalgebra::{DMatrix, Vector3};

/// Iterations of the relaxation at most.
pub const MAX_ITERATIONS: usize = 400;
/// It stops when the ratio of the certified bound is within this of the relaxed design's.
pub const RATIO_GAP: f64 = 5e-4;

/// The bound of one arm's design (module documentation): criteria `trace(S⁻¹ P)` with unit noise,
/// and the verification ratios they give, `sqrt(1 + criterion / 2)`.
#[derive(Clone, Debug, PartialEq)]
pub struct DesignBound {
    /// Configurations the relaxation chooses (besides any fixed ones).
    pub per_arm: usize,
    /// The certified lower bound on the relaxation's minimum.
    pub criterion_lower: f64,
    /// The best relaxed design's criterion (the minimum lies between the two).
    pub criterion_relaxed: f64,
    /// The chosen design's criterion with the same information (an efficient fit of its distances).
    pub criterion_design: f64,
    pub iterations: usize,
    /// Candidates with a weight above 0.01 in the best relaxed design.
    pub support: usize,
    /// The candidates of the `per_arm` largest weights in the best relaxed design, largest first:
    /// the relaxation rounded to a design.
    pub largest: Vec<usize>,
}

/// `sqrt(1 + criterion / 2)`: the verification accuracy over the noise floor.
pub fn ratio_of(criterion: f64) -> f64 {
    (1.0 + 0.5 * criterion.max(0.0)).sqrt()
}

impl DesignBound {
    /// No design of [`Self::per_arm`] from the candidates predicts a verification ratio below this.
    pub fn ratio(&self) -> f64 {
        ratio_of(self.criterion_lower)
    }
    /// The best relaxed design's ratio.
    pub fn relaxed_ratio(&self) -> f64 {
        ratio_of(self.criterion_relaxed)
    }
    /// The chosen design's ratio with an efficient fit of its distances (at most its least-squares
    /// prediction).
    pub fn design_ratio(&self) -> f64 {
        ratio_of(self.criterion_design)
    }
}

/// The verification information `P`: the mean of `g gᵀ` over the pairs of `ver` (indices into the
/// pool) and the reflectors, `g = (J_i,k − J_j,k)ᵀ u` — as
/// [`crate::solver::uncertainty::predicted_verification_ratio`] takes it.
pub fn verification_information(
    points: &[Vec<Vector3<f64>>],
    jac: &[DMatrix<f64>],
    ver: &[usize],
) -> Option<DMatrix<f64>> {
    let p = jac.first()?.ncols();
    let mut info = DMatrix::<f64>::zeros(p, p);
    let mut count = 0usize;
    for (k, &i) in ver.iter().enumerate() {
        for &j in &ver[k + 1..] {
            let g = super::pair_rows(points, jac, i, &[j]);
            for (r, (a, b)) in points[i].iter().zip(&points[j]).enumerate() {
                if (a - b).norm() <= 0.0 {
                    continue;
                }
                let row = g.row(r);
                info += row.transpose() * row;
                count += 1;
            }
        }
    }
    (count > 0).then(|| info / count as f64)
}

/// One configuration's rows `[J, N]` (module documentation), row-major, `3·reflectors × q` with
/// `q = p + 6·reflectors`; the positions centred by `centre` and divided by `scale`.
fn position_rows(
    points: &[Vector3<f64>],
    jac: &DMatrix<f64>,
    centre: &Vector3<f64>,
    scale: f64,
) -> Vec<f64> {
    let (rows, p) = jac.shape();
    let q = p + 2 * rows;
    let mut x = vec![0.0; rows * q];
    for r in 0..rows {
        let (k, t) = (r / 3, r % 3);
        for c in 0..p {
            x[r * q + c] = jac[(r, c)];
        }
        // d(point)/d(translation) = I; d(point)/d(rotation ω) = −[p]× (ω × p).
        x[r * q + p + 6 * k + t] = 1.0;
        let s = (points[k] - centre) / scale;
        let cross = [[0.0, s.z, -s.y], [-s.z, 0.0, s.x], [s.y, -s.x, 0.0]];
        for (e, v) in cross[t].iter().enumerate() {
            x[r * q + p + 6 * k + 3 + e] = *v;
        }
    }
    x
}

/// The reflector-position information of the pool's configurations with the nuisance columns, and
/// the verification information to judge it by.
struct Positions {
    /// Per configuration, [`position_rows`].
    x: Vec<Vec<f64>>,
    /// The parameters, and the columns with the nuisance.
    p: usize,
    q: usize,
    /// `[Q; 0]` with `P = Q Qᵀ`: `trace(S⁻¹ P) = trace(Q̃ᵀ M⁻¹ Q̃)` for the full information `M`.
    q_full: DMatrix<f64>,
}

impl Positions {
    /// `None` without configurations or verification pairs.
    fn new(points: &[Vec<Vector3<f64>>], jac: &[DMatrix<f64>], ver: &[usize]) -> Option<Self> {
        let (rows, p) = jac.first()?.shape();
        let q = p + 2 * rows;
        let ver_info = verification_information(points, jac, ver)?;
        // P = Q Qᵀ (its negative eigenvalues, rounding, dropped).
        let eigen = ver_info.symmetric_eigen();
        let mut q_full = DMatrix::<f64>::zeros(q, p);
        for (c, &lambda) in eigen.eigenvalues.iter().enumerate() {
            let s = lambda.max(0.0).sqrt();
            for r in 0..p {
                q_full[(r, c)] = eigen.eigenvectors[(r, c)] * s;
            }
        }
        // Positions centred and scaled for the rotation columns' conditioning (which does not
        // change the Schur complement: the nuisance columns span the same space).
        let all: Vec<&Vector3<f64>> = points.iter().flatten().collect();
        let count = all.len().max(1) as f64;
        let centre = all.iter().fold(Vector3::zeros(), |a, v| a + *v) / count;
        let scale = (all
            .iter()
            .map(|v| (*v - centre).norm_squared())
            .sum::<f64>()
            / count)
            .sqrt()
            .max(1e-9);
        let x = (0..jac.len())
            .map(|i| position_rows(&points[i], &jac[i], &centre, scale))
            .collect();
        Some(Self { x, p, q, q_full })
    }

    /// `m += weight · X_iᵀ X_i` (lower triangle).
    fn add(&self, i: usize, weight: f64, m: &mut DMatrix<f64>) {
        let q = self.q;
        for r in self.x[i].chunks_exact(q) {
            for a in 0..q {
                let ra = weight * r[a];
                if ra == 0.0 {
                    continue;
                }
                for b in 0..=a {
                    m[(a, b)] += ra * r[b];
                }
            }
        }
    }

    /// `trace(S⁻¹ P)` and `M⁻¹ Q̃` of the information `m` (lower triangle filled); `None` where it
    /// is singular.
    fn solve(&self, mut m: DMatrix<f64>) -> Option<(f64, DMatrix<f64>)> {
        m.fill_upper_triangle_with_lower_triangle();
        let z = m.cholesky()?.solve(&self.q_full);
        Some((self.q_full.dot(&z), z))
    }

    /// The information of the configurations `design`, each once.
    fn information(&self, design: &[usize]) -> DMatrix<f64> {
        let mut m = DMatrix::<f64>::zeros(self.q, self.q);
        for &i in design {
            self.add(i, 1.0, &mut m);
        }
        m
    }

    /// `d_i = ‖X_i Z‖²_F = −∂f/∂w_i` for the configurations `0..count`, `z = M⁻¹ Q̃`.
    fn sensitivities(&self, z: &DMatrix<f64>, count: usize) -> Vec<f64> {
        let (p, q) = (self.p, self.q);
        // z row-major: q rows of p.
        let zt: Vec<f64> = z.transpose().as_slice().to_vec();
        (0..count)
            .into_par_iter()
            .map(|i| {
                let mut y = vec![0.0; p];
                let mut sum = 0.0;
                for r in self.x[i].chunks_exact(q) {
                    y.fill(0.0);
                    for (t, &xr) in r.iter().enumerate() {
                        if xr != 0.0 {
                            for (yc, zc) in y.iter_mut().zip(&zt[t * p..(t + 1) * p]) {
                                *yc += xr * zc;
                            }
                        }
                    }
                    sum += y.iter().map(|v| v * v).sum::<f64>();
                }
                sum
            })
            .collect()
    }
}

/// The criterion `trace(S⁻¹ P)` of the configurations `design` (indices into the pool of
/// `points`/`jac`), each measured once, judged on the pairs of `ver`: what an efficient fit of their
/// distances predicts ([`ratio_of`] gives the ratio). `None` where the information is singular.
pub fn design_criterion(
    points: &[Vec<Vector3<f64>>],
    jac: &[DMatrix<f64>],
    design: &[usize],
    ver: &[usize],
) -> Option<f64> {
    let positions = Positions::new(points, jac, ver)?;
    positions
        .solve(positions.information(design))
        .map(|(f, _)| f)
}

/// The bound (module documentation) for designs of `per_arm` of the candidates `0..candidates` of
/// the pool (`points`, `jac`: scaled Jacobians as for [`super::select_by_distances`]) beside the
/// configurations `fixed` (indices from `candidates` on: those already measured), judged on the
/// pairs of `ver`; with the chosen `design` (every index of it, the fixed ones included) in the same
/// measure. `None` where the information is singular or there are too few candidates.
pub fn relaxed_bound(
    points: &[Vec<Vector3<f64>>],
    jac: &[DMatrix<f64>],
    candidates: usize,
    fixed: &[usize],
    per_arm: usize,
    design: &[usize],
    ver: &[usize],
) -> Option<DesignBound> {
    let candidates = candidates.min(jac.len());
    if per_arm == 0 || candidates < per_arm {
        return None;
    }
    let positions = Positions::new(points, jac, ver)?;
    let fixed_info = positions.information(fixed);
    let top_sum = |d: &[f64]| -> f64 {
        let mut sorted = d.to_vec();
        crate::sort::sort_by(&mut sorted, |a, b| b.total_cmp(a));
        sorted.iter().take(per_arm).sum()
    };
    let (criterion_design, _) = positions.solve(positions.information(design))?;
    let mut w = vec![per_arm as f64 / candidates as f64; candidates];
    let (mut lower, mut relaxed, mut best_w) = (f64::NEG_INFINITY, f64::INFINITY, w.clone());
    let mut iterations = 0;
    while iterations < MAX_ITERATIONS {
        iterations += 1;
        let mut m = fixed_info.clone();
        for (i, &wi) in w.iter().enumerate() {
            if wi > 0.0 {
                positions.add(i, wi, &mut m);
            }
        }
        let (f, z) = positions.solve(m)?;
        let d = positions.sensitivities(&z, candidates);
        // Frank–Wolfe: f* ≥ f(w) + ∇f·(s − w) for the s of the feasible set minimising it — the
        // indicator of the N largest d_i.
        let weighted: f64 = w.iter().zip(&d).map(|(a, b)| a * b).sum();
        lower = lower.max(f + weighted - top_sum(&d));
        if f < relaxed {
            relaxed = f;
            best_w.clone_from(&w);
        }
        if ratio_of(relaxed) - ratio_of(lower) <= RATIO_GAP {
            break;
        }
        let grown: Vec<f64> = w.iter().zip(&d).map(|(a, b)| a * b.max(0.0)).collect();
        w = capped(&grown, per_arm as f64);
    }
    Some(DesignBound {
        per_arm,
        criterion_lower: lower.max(0.0),
        criterion_relaxed: relaxed,
        criterion_design,
        iterations,
        support: best_w.iter().filter(|&&v| v > 0.01).count(),
        largest: {
            let mut order: Vec<usize> = (0..best_w.len()).collect();
            crate::sort::sort_by(&mut order, |&a, &b| best_w[b].total_cmp(&best_w[a]));
            order.truncate(per_arm);
            order
        },
    })
}

/// `min(1, c·v_i)` with c such that they sum to `total`: the k largest at 1 for the smallest k at
/// which `c_k = (total − k) / (the sum of the others)` keeps the largest of the others at or below 1
/// (`c_k` grows with k, so the k largest are then above 1 too); the `total` largest at 1 where the
/// others are zero.
fn capped(v: &[f64], total: f64) -> Vec<f64> {
    let mut order: Vec<usize> = (0..v.len()).collect();
    crate::sort::sort_by(&mut order, |&a, &b| v[b].total_cmp(&v[a]));
    let mut rest: f64 = v.iter().sum();
    for (k, &i) in order.iter().enumerate() {
        let c = (total - k as f64) / rest;
        if rest > 0.0 && c * v[i] <= 1.0 {
            return v.iter().map(|&x| (c * x).min(1.0)).collect();
        }
        rest -= v[i];
    }
    let mut out = vec![0.0; v.len()];
    for &i in order.iter().take(total as usize) {
        out[i] = 1.0;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::plan::{pair_rows, synthetic_pool};

    /// The least-squares distance fit's criterion `trace(C P)` of the design (unit point noise):
    /// `C = K Kᵀ`, `K = (JᵀJ)⁻¹ Jᵀ U` with `U` the distances' dependence on the point errors —
    /// what `solver::uncertainty::predicted_verification_ratio` computes for a robot.
    fn least_squares_criterion(
        points: &[Vec<Vector3<f64>>],
        jac: &[DMatrix<f64>],
        design: &[usize],
        p_ver: &DMatrix<f64>,
    ) -> f64 {
        let reflectors = points[0].len();
        let mut rows: Vec<(DMatrix<f64>, Vec<f64>)> = Vec::new();
        for (a, &i) in design.iter().enumerate() {
            for (b, &j) in design.iter().enumerate().skip(a + 1) {
                let g = pair_rows(points, jac, i, &[j]);
                for k in 0..reflectors {
                    let u = (points[i][k] - points[j][k]).normalize();
                    let mut noise = vec![0.0; 3 * reflectors * design.len()];
                    for t in 0..3 {
                        noise[(a * reflectors + k) * 3 + t] = u[t];
                        noise[(b * reflectors + k) * 3 + t] = -u[t];
                    }
                    rows.push((g.rows(k, 1).into_owned(), noise));
                }
            }
        }
        let p = jac[0].ncols();
        let j = DMatrix::from_fn(rows.len(), p, |r, c| rows[r].0[(0, c)]);
        let u = DMatrix::from_fn(rows.len(), rows[0].1.len(), |r, c| rows[r].1[c]);
        let k = (j.transpose() * &j).try_inverse().unwrap() * j.transpose() * u;
        (&k * k.transpose() * p_ver).trace()
    }

    /// On a small made-up pool (two reflectors), over every design of four: the certified bound lies
    /// below the design's criterion with an efficient fit, which lies below the least-squares fit's
    /// (Gauss–Markov, computed independently here) — a nuisance the distances do see, or a
    /// certificate of the wrong sign, would break one of them.
    #[test]
    fn the_bound_lies_below_every_design_of_the_pool() {
        let (points, jac) = synthetic_pool(12, 2, 4, 3);
        let pool = points.len();
        let ver: Vec<usize> = (0..pool).collect();
        let n = 4;
        let bound = relaxed_bound(&points, &jac, pool, &[], n, &[0, 1, 2, 3], &ver).unwrap();
        assert!(0.0 < bound.criterion_lower && bound.criterion_lower <= bound.criterion_relaxed);
        assert!(bound.ratio() > 1.0 && bound.ratio() <= bound.design_ratio());
        let p_ver = verification_information(&points, &jac, &ver).unwrap();
        let mut best = f64::INFINITY;
        let mut designs = 0;
        for a in 0..pool {
            for b in a + 1..pool {
                for c in b + 1..pool {
                    for d in c + 1..pool {
                        let design = [a, b, c, d];
                        let efficient = design_criterion(&points, &jac, &design, &ver).unwrap();
                        let lsq = least_squares_criterion(&points, &jac, &design, &p_ver);
                        assert!(bound.criterion_lower <= efficient * (1.0 + 1e-9));
                        assert!(efficient <= lsq * (1.0 + 1e-9), "{efficient} vs {lsq}");
                        best = best.min(efficient);
                        designs += 1;
                    }
                }
            }
        }
        assert_eq!(designs, 495);
        // Not vacuous: within a factor of the best design here.
        assert!(
            bound.criterion_lower > 0.5 * best,
            "{} vs {best}",
            bound.criterion_lower
        );
        // With configurations already measured (fixed, outside the candidates) it holds alike.
        let fixed = relaxed_bound(&points, &jac, 8, &[8, 9], 2, &[8, 9, 0, 1], &ver).unwrap();
        assert!(fixed.criterion_lower <= fixed.criterion_design * (1.0 + 1e-9));
    }

    #[test]
    fn capped_weights_sum_to_the_total_and_stay_within_one() {
        for v in [
            vec![1.0, 1.0, 1.0, 1.0],
            vec![100.0, 1.0, 1.0, 1.0, 0.5],
            vec![5.0, 0.0, 0.0, 0.0],
        ] {
            let w = capped(&v, 2.0);
            assert!((w.iter().sum::<f64>() - 2.0).abs() < 1e-12, "{w:?}");
            assert!(w.iter().all(|x| (0.0..=1.0 + 1e-12).contains(x)), "{w:?}");
        }
    }
}
