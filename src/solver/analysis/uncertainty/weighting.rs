//! How each step-1 method weighs the reflectors' distance errors, and the minimax's multipliers.

use super::sums::{Directions, PairSums, Sums};
use crate::kinematics::{ArmJacobians, ArmModel};
use nalgebra::{DMatrix, DVector, Vector3};

/// How a step-1 method weighs the reflectors' distance errors: the covariance is the sandwich of
/// that weighted fit (module documentation).
#[derive(Clone, Debug, PartialEq)]
pub enum Weighting {
    /// Least squares of every reflector's distance errors (`lsq`).
    LeastSquares,
    /// Least squares of one reflector's distance errors (`distance-single`, the reflector's index).
    Reflector(usize),
    /// Given weights per reflector.
    Weights(Vec<f64>),
    /// The minimax (`minimax`): each reflector weighed by its multiplier λ_k at the solution
    /// ([`minimax_multipliers`]).
    Minimax,
}

impl Weighting {
    /// The weighting of `method`'s fit (`reflector`: the one a single-reflector method used); `None`
    /// for a method not fitted by distances.
    pub fn of(
        method: crate::solver::methods::table::Method,
        reflector: Option<crate::solver::types::Reflector>,
    ) -> Option<Weighting> {
        if method.is_absolute() {
            return None;
        }
        Some(match reflector {
            Some(r) => Weighting::Reflector(r as usize),
            None if method.spec().solver == crate::solver::methods::SolverKind::Sqp => {
                Weighting::Minimax
            }
            None => Weighting::LeastSquares,
        })
    }

    /// The weights of the first pass over the pairs (the minimax's: equal, for its multipliers).
    pub(super) fn first_weights(&self, arm: &ArmModel) -> Vec<f64> {
        let n = arm.reflector_count();
        match self {
            Weighting::Reflector(k) => (0..n).map(|r| f64::from(u8::from(r == *k))).collect(),
            Weighting::Weights(w) => w.clone(),
            Weighting::LeastSquares | Weighting::Minimax => vec![1.0; n],
        }
    }
}

/// The smallest weight of a reflector in the minimax's covariance (its multipliers sum to one).
pub const MINIMAX_WEIGHT_FLOOR: f64 = 0.1;

/// Relative tolerance below the largest F_k within which a reflector counts as active at a minimax
/// solution.
pub const ACTIVE_TOLERANCE: f64 = 1e-3;

/// The minimax's multipliers λ_k at its solution (summing to one): over the active reflectors, the
/// convex combination of their gradients ∇F_k closest to zero (the KKT condition Σ λ_k ∇F_k = 0), in
/// the column-scaled geometric parameters (the reflector coordinates also answer to the triangle's
/// side constraints, whose multipliers are not known here).
pub(super) fn minimax_weights(arm: &ArmModel, free: &[usize], sums: &Sums) -> Vec<f64> {
    let n = sums.f_k.len();
    let top = sums.f_k.iter().copied().fold(0.0f64, f64::max);
    let active: Vec<usize> = (0..n)
        .filter(|&k| sums.f_k[k] >= top * (1.0 - ACTIVE_TOLERANCE))
        .collect();
    let off = arm.reflector_offset();
    let cols: Vec<usize> = (0..free.len())
        .filter(|&c| free[c] < off || free[c] >= off + 3 * n)
        .collect();
    let scaled = |k: usize| -> DVector<f64> {
        DVector::from_iterator(
            cols.len(),
            cols.iter()
                .map(|&c| sums.g_k[k][c] / sums.jtj[(c, c)].max(f64::MIN_POSITIVE).sqrt()),
        )
    };
    let h: Vec<DVector<f64>> = active.iter().map(|&k| scaled(k)).collect();
    let m = active.len();
    let gram = DMatrix::from_fn(m, m, |a, b| h[a].dot(&h[b]));
    // Every non-empty subset S: λ_S ∝ G_S⁻¹ 1, kept if non-negative; the smallest λᵀGλ.
    let mut best: Option<(f64, Vec<f64>)> = None;
    for mask in 1u32..(1 << m) {
        let set: Vec<usize> = (0..m).filter(|&a| mask & (1 << a) != 0).collect();
        let g = DMatrix::from_fn(set.len(), set.len(), |a, b| gram[(set[a], set[b])]);
        let Some(mu) = g.lu().solve(&DVector::from_element(set.len(), 1.0)) else {
            continue;
        };
        let total = mu.sum();
        if !(total.is_finite() && total != 0.0) || mu.iter().any(|&x| x / total < 0.0) {
            continue;
        }
        let mut lambda = vec![0.0; m];
        for (a, &i) in set.iter().enumerate() {
            lambda[i] = mu[a] / total;
        }
        let value = (0..m)
            .map(|a| {
                (0..m)
                    .map(|b| lambda[a] * gram[(a, b)] * lambda[b])
                    .sum::<f64>()
            })
            .sum::<f64>();
        if best.as_ref().is_none_or(|(v, _)| value < *v) {
            best = Some((value, lambda));
        }
    }
    let mut weights = vec![0.0; n];
    match best {
        Some((_, lambda)) => {
            for (a, &k) in active.iter().enumerate() {
                weights[k] = lambda[a];
            }
        }
        None => active.iter().for_each(|&k| weights[k] = 1.0 / m as f64),
    }
    weights
}

/// The minimax's multipliers ([`Weighting::Minimax`]) of `arm` at `qs` against `measured`: one per
/// reflector, summing to one.
pub fn minimax_multipliers(
    arm: &ArmModel,
    qs: &[Vec<f64>],
    measured: &[Vec<Vector3<f64>>],
    free: &[usize],
) -> Vec<f64> {
    let jac: Vec<ArmJacobians> = qs.iter().map(|q| arm.reflector_jacobians(q)).collect();
    let points: Vec<&Vec<Vector3<f64>>> = measured.iter().collect();
    let sums = PairSums::from_jacobians(arm, &jac, &points, free, qs.len());
    let ones = vec![1.0; arm.reflector_count()];
    minimax_weights(arm, free, &sums.weighed(&ones, Directions::Measured))
}
