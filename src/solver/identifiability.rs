//! Which parameters can distance data identify?
//!
//! The identification Jacobian (rows −u_ijᵀ(J_i − J_j), one per pair and reflector) is column-scaled to
//! unit RMS sensitivity. Columns are then taken greedily in a preferred order — the reflector
//! coordinates first, then joints 2…6, then joint 1, then joint 7 — and a column is kept only if the
//! part of it that the already kept columns cannot explain is large enough (modified Gram–Schmidt,
//! re-orthogonalised). The rest are fixed at their start values. This is a column-pivoted QR with a
//! physically motivated pivot order, so the report can say *what* a fixed parameter depends on.

use crate::kinematics::{N_DH, N_PARAMS, param_name};
use nalgebra::{DMatrix, DVector, SVector};
use serde::{Deserialize, Serialize};

/// Relative residual below which a column counts as exactly unidentifiable (numerical zero).
pub const UNIDENTIFIABLE_TOL: f64 = 1e-7;
/// Relative residual below which a column counts as near-dependent and is fixed too.
pub const NEAR_DEPENDENT_TOL: f64 = 2e-3;

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

/// Preferred order in which columns are considered.
fn preference_order() -> Vec<usize> {
    let mut order: Vec<usize> = (N_DH..N_PARAMS).collect();
    order.extend(4..24); // joints 2..6
    order.extend([0, 3, 1, 2]); // joint 1: a, alpha, then d, theta
    order.extend(24..28); // joint 7
    order
}

fn physical_reason(k: usize) -> Option<&'static str> {
    match k {
        1 => Some(
            "joint 1 d: a translation along the first axis moves every point alike and is absorbed by the tracker/base frame",
        ),
        2 => Some(
            "joint 1 θ: a rotation about the first axis turns every point alike and is absorbed by the tracker/base frame",
        ),
        24..=27 => {
            Some("joint 7: a constant flange transform is absorbed by the reflector coordinates")
        }
        _ => None,
    }
}

fn condition_number(cols: &[DVector<f64>]) -> f64 {
    if cols.is_empty() {
        return 1.0;
    }
    let m = DMatrix::from_columns(cols);
    let sv = m.singular_values();
    let max = sv.max();
    let min = sv.min();
    if min <= max * 1e-15 {
        f64::INFINITY
    } else {
        max / min
    }
}

/// Analyse sampled Jacobian rows (full 37 columns, unscaled). `allowed` restricts which parameters may
/// be free at all (e.g. the user fixed some).
///
/// The rows are reduced once by a thin QR, `M = Q R`: `R` (37 × 37) has the same column norms, inner
/// products and singular values as `M`, so all the work below is on 37-vectors whatever the number of
/// pairs.
pub fn analyse(
    rows: &[SVector<f64, N_PARAMS>],
    allowed: &[bool; N_PARAMS],
) -> IdentifiabilityReport {
    analyse_with_gram(rows, allowed).0
}

/// [`analyse`], also returning the mean Gram matrix `MᵀM / rows` of the unscaled rows (whose diagonal is
/// the squared RMS sensitivity of each parameter and which is the Gauss–Newton matrix up to a factor 2).
pub fn analyse_with_gram(
    rows: &[SVector<f64, N_PARAMS>],
    allowed: &[bool; N_PARAMS],
) -> (IdentifiabilityReport, DMatrix<f64>) {
    let n = rows.len().max(1);
    let mut m = DMatrix::<f64>::zeros(rows.len().max(N_PARAMS), N_PARAMS);
    for (i, r) in rows.iter().enumerate() {
        m.row_mut(i).copy_from(&r.transpose());
    }
    let r = m.qr().r(); // N_PARAMS × N_PARAMS
    let gram = r.transpose() * &r / n as f64;
    let column = |k: usize| r.column(k).into_owned();
    let norms: Vec<f64> = (0..N_PARAMS).map(|k| column(k).norm()).collect();
    let max_norm = norms.iter().copied().fold(0.0, f64::max).max(1e-300);
    let scaled: Vec<DVector<f64>> = (0..N_PARAMS)
        .map(|k| {
            if norms[k] > 1e-12 * max_norm {
                column(k) / norms[k]
            } else {
                DVector::zeros(N_PARAMS)
            }
        })
        .collect();
    let has_zero = scaled.iter().any(|c| c.norm() == 0.0);
    let nonzero: Vec<DVector<f64>> = scaled.iter().filter(|c| c.norm() > 0.0).cloned().collect();
    let condition_before = if has_zero {
        f64::INFINITY
    } else {
        condition_number(&nonzero)
    };
    let mut basis: Vec<DVector<f64>> = Vec::new();
    let mut kept: Vec<usize> = Vec::new();
    let mut fixed = Vec::new();
    for k in preference_order() {
        if !allowed[k] {
            fixed.push(FixedParameter {
                index: k,
                name: param_name(k),
                residual: f64::NAN,
                reason: "fixed by the user".into(),
            });
            continue;
        }
        let mut r = scaled[k].clone();
        for _ in 0..2 {
            for b in &basis {
                let c = b.dot(&r);
                r.axpy(-c, b, 1.0);
            }
        }
        let res = r.norm();
        if res >= NEAR_DEPENDENT_TOL {
            basis.push(r / res);
            kept.push(k);
            continue;
        }
        let reason = if res < UNIDENTIFIABLE_TOL {
            match physical_reason(k) {
                Some(why) => format!("unidentifiable from distances ({why})"),
                None => {
                    "unidentifiable from distances: its column is a combination of the kept ones"
                        .into()
                }
            }
        } else {
            // Name the kept parameters it leans on most.
            let a =
                DMatrix::from_columns(&kept.iter().map(|&j| scaled[j].clone()).collect::<Vec<_>>());
            let coef = a
                .clone()
                .svd(true, true)
                .solve(&scaled[k], 1e-12)
                .unwrap_or_else(|_| DVector::zeros(kept.len()));
            let mut lean: Vec<(usize, f64)> = kept
                .iter()
                .copied()
                .zip(coef.iter().map(|c| c.abs()))
                .collect();
            lean.sort_by(|x, y| y.1.total_cmp(&x.1));
            let names: Vec<String> = lean.iter().take(3).map(|(j, _)| param_name(*j)).collect();
            format!(
                "near-dependent (residual {res:.1e} of its scaled column) on {}",
                names.join(", ")
            )
        };
        fixed.push(FixedParameter {
            index: k,
            name: param_name(k),
            residual: res,
            reason,
        });
    }
    kept.sort_unstable();
    fixed.sort_by_key(|f| f.index);
    let condition_after =
        condition_number(&kept.iter().map(|&k| scaled[k].clone()).collect::<Vec<_>>());
    (
        IdentifiabilityReport {
            free: kept,
            fixed,
            condition_before,
            condition_after,
        },
        gram,
    )
}
