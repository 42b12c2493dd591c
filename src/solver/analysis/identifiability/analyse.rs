//! Which parameters can distance data identify?
//!
//! The identification Jacobian (rows −u_ijᵀ(J_i − J_j), one per pair and reflector, on a sample of
//! pairs) is summarised by its mean Gram matrix `G = MᵀM / rows` ([`gram_by_product`], or
//! [`gram_by_qr`] for the built-in robot, whose calibrations stay bit-identical to earlier releases).
//! Columns are scaled to unit RMS sensitivity and taken greedily in a preferred order
//! ([`crate::kinematics::ArmModel::identifiability_order`]); a column is kept only if the part of it
//! that the already kept columns cannot explain has norm ≥ [`NEAR_DEPENDENT_TOL`]. That is modified
//! Gram–Schmidt in the G inner product, i.e. a Cholesky factorisation of G in the preference order
//! that skips the columns it cannot extend — a column-pivoted QR with a physically motivated pivot
//! order, so the report can say *what* a fixed parameter depends on. Squaring the condition number puts
//! the residuals' noise floor near √ε ≈ 1e-8, below [`UNIDENTIFIABLE_TOL`]. The fixed parameters stay
//! at their start values.

use nalgebra::DMatrix;
use serde::{Deserialize, Serialize};

/// Relative residual below which a column counts as exactly unidentifiable (numerical zero).
pub const UNIDENTIFIABLE_TOL: f64 = 1e-7;
/// Relative residual below which a column counts as near-dependent and is fixed too.
pub const NEAR_DEPENDENT_TOL: f64 = 2e-3;
/// A column whose norm is below this fraction of the largest column's is unidentifiable outright,
/// before any scaling. URDF angles written as `1.570796325` or `1.5708` leave a parameter that is
/// physically a rigid motion (a shift along joint 1's axis) with a sensitivity of 1e-9 … 1e-6 of the
/// others; scaled to unit norm, such a column looks independent and its value runs off to 1e8 mm.
pub const NEGLIGIBLE_COLUMN: f64 = 1e-6;

/// A fixed parameter and why.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FixedParameter {
    pub index: usize,
    pub name: String,
    /// Residual norm of its scaled column after projecting out the kept ones (0 = fully dependent).
    pub residual: f64,
    pub reason: String,
}

/// Outcome of the analysis.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct IdentifiabilityReport {
    pub free: Vec<usize>,
    pub fixed: Vec<FixedParameter>,
    /// Condition number of the column-scaled Jacobian with every parameter (∞ when singular).
    pub condition_before: f64,
    /// Condition number with the fixed parameters removed.
    pub condition_after: f64,
}

/// The mean Gram matrix `MMᵀ / count` of `columns` (one column per sampled pair and reflector), as one
/// matrix product.
pub fn gram_by_product(columns: &DMatrix<f64>) -> DMatrix<f64> {
    let n = columns.ncols().max(1);
    columns * columns.transpose() / n as f64
}

/// The mean Gram matrix `RᵀR / count` of `columns` through nalgebra's thin QR of their transpose
/// (`Mᵀ = Q R`, zero rows appended up to `M`'s row count): the same matrix as [`gram_by_product`] up
/// to rounding. The start's analysis of the built-in robot used it until the sixteenth session (the
/// product is what every analysis uses now); kept for the tests and benches that compare the two.
pub fn gram_by_qr(columns: &DMatrix<f64>) -> DMatrix<f64> {
    let (p, count) = columns.shape();
    let mut padded = DMatrix::<f64>::zeros(count.max(p), p);
    padded.rows_mut(0, count).copy_from(&columns.transpose());
    let r = padded.qr().r();
    r.transpose() * &r / count.max(1) as f64
}

/// What the analysis needs to know about the parameters.
pub struct ParameterInfo<'a> {
    /// Order in which the parameters are considered (every index once).
    pub order: &'a [usize],
    /// Parameters that may be free at all (the others are fixed by the user).
    pub allowed: &'a [bool],
    pub name: &'a dyn Fn(usize) -> String,
    /// Why a parameter is unidentifiable, when physics says so.
    pub reason: &'a dyn Fn(usize) -> Option<String>,
    /// What the method fits, for the reasons: `distances` (the paper's and ref. \[26\]'s methods),
    /// `absolute positions`, `poses`.
    pub data: &'a str,
    /// Why a parameter that is not `allowed` is fixed (e.g. `fixed by the user`).
    pub not_allowed: &'a str,
}

impl ParameterInfo<'_> {
    /// What the distance methods fit.
    pub const DISTANCES: &'static str = "distances";
    /// The reason of a parameter the user held.
    pub const FIXED_BY_USER: &'static str = "fixed by the user";
}

/// Condition number of the scaled Gram submatrix of `idx` (the square root of its eigenvalue ratio).
fn condition(scaled: &DMatrix<f64>, idx: &[usize]) -> f64 {
    if idx.is_empty() {
        return 1.0;
    }
    let sub = DMatrix::from_fn(idx.len(), idx.len(), |i, j| scaled[(idx[i], idx[j])]);
    let ev = sub.symmetric_eigenvalues();
    let (max, min) = (ev.max(), ev.min());
    if min <= max * 1e-15 {
        f64::INFINITY
    } else {
        (max / min).sqrt()
    }
}

/// Condition number of the columns `idx` of the Gram matrix `gram`, each scaled to unit norm (∞ when
/// one of them has none).
pub(super) fn scaled_condition(gram: &DMatrix<f64>, idx: &[usize]) -> f64 {
    let norms: Vec<f64> = idx.iter().map(|&k| gram[(k, k)].max(0.0).sqrt()).collect();
    if !norms.iter().all(|&n| n > 0.0 && n.is_finite()) {
        return f64::INFINITY;
    }
    let scaled = DMatrix::from_fn(idx.len(), idx.len(), |a, b| {
        gram[(idx[a], idx[b])] / (norms[a] * norms[b])
    });
    condition(&scaled, &(0..idx.len()).collect::<Vec<_>>())
}

/// The kept parameters that column `k` leans on most (largest coefficients of its projection).
fn leaning_on(scaled: &DMatrix<f64>, kept: &[usize], k: usize, info: &ParameterInfo) -> String {
    let g = DMatrix::from_fn(kept.len(), kept.len(), |i, j| scaled[(kept[i], kept[j])]);
    let b = nalgebra::DVector::from_fn(kept.len(), |i, _| scaled[(kept[i], k)]);
    let coef = g
        .svd(true, true)
        .solve(&b, 1e-12)
        .unwrap_or_else(|_| nalgebra::DVector::zeros(kept.len()));
    let mut lean: Vec<(usize, f64)> = kept
        .iter()
        .copied()
        .zip(coef.iter().map(|c| c.abs()))
        .collect();
    crate::sort::sort_by(&mut lean, |x, y| y.1.total_cmp(&x.1));
    let names: Vec<String> = lean.iter().take(3).map(|(j, _)| (info.name)(*j)).collect();
    names.join(", ")
}

/// Analyse the mean Gram matrix `gram` of the unscaled pair Jacobian.
pub fn analyse(gram: &DMatrix<f64>, info: &ParameterInfo) -> IdentifiabilityReport {
    let p = gram.ncols();
    let norms: Vec<f64> = (0..p).map(|k| gram[(k, k)].max(0.0).sqrt()).collect();
    let max_norm = norms.iter().copied().fold(0.0, f64::max).max(1e-300);
    let usable: Vec<bool> = norms
        .iter()
        .map(|&n| n.is_finite() && n > NEGLIGIBLE_COLUMN * max_norm)
        .collect();
    let scaled = DMatrix::from_fn(p, p, |a, b| {
        if usable[a] && usable[b] {
            gram[(a, b)] / (norms[a] * norms[b])
        } else {
            0.0
        }
    });
    let condition_before = if usable.iter().all(|&u| u) {
        condition(&scaled, &(0..p).collect::<Vec<_>>())
    } else {
        f64::INFINITY
    };
    // Rows of the Cholesky factor of the kept columns, in kept order.
    let mut kept: Vec<usize> = Vec::new();
    let mut l: Vec<Vec<f64>> = Vec::new();
    let mut fixed = Vec::new();
    for &k in info.order {
        if !info.allowed.get(k).copied().unwrap_or(false) {
            fixed.push(FixedParameter {
                index: k,
                name: (info.name)(k),
                residual: f64::NAN,
                reason: info.not_allowed.into(),
            });
            continue;
        }
        let res = if usable[k] {
            let mut lk = Vec::with_capacity(kept.len() + 1);
            for (jpos, &j) in kept.iter().enumerate() {
                let dot: f64 = lk.iter().zip(&l[jpos]).map(|(a, b)| a * b).sum();
                lk.push((scaled[(k, j)] - dot) / l[jpos][jpos]);
            }
            let res = (1.0 - lk.iter().map(|v| v * v).sum::<f64>())
                .max(0.0)
                .sqrt();
            if res >= NEAR_DEPENDENT_TOL {
                lk.push(res);
                l.push(lk);
                kept.push(k);
                continue;
            }
            res
        } else {
            0.0
        };
        let reason = if res < UNIDENTIFIABLE_TOL {
            let data = info.data;
            match (info.reason)(k) {
                Some(why) => format!("unidentifiable from {data} ({why})"),
                None if !usable[k] => {
                    format!("unidentifiable from {data}: the {data} do not depend on it")
                }
                None => format!(
                    "unidentifiable from {data}: its column is a combination of the kept ones"
                ),
            }
        } else {
            format!(
                "near-dependent (residual {res:.1e} of its scaled column) on {}",
                leaning_on(&scaled, &kept, k, info)
            )
        };
        fixed.push(FixedParameter {
            index: k,
            name: (info.name)(k),
            residual: res,
            reason,
        });
    }
    kept.sort_unstable();
    crate::sort::sort_by_key(&mut fixed, |f| f.index);
    let condition_after = condition(&scaled, &kept);
    IdentifiabilityReport {
        free: kept,
        fixed,
        condition_before,
        condition_after,
    }
}
