//! What the data cannot tell: the identified parameters the configurations barely constrain.
//!
//! At the measured configurations a parameter's uncertainty moves the distances by about the
//! tracker's noise — the fit sees to that. Elsewhere in the robot's workspace it may move them far
//! more: the reflector's offset along the flange's axis, fitted on configurations whose flange hardly
//! turns, has a σ of tens of mm that none of the measured distances notice and every other
//! orientation does. The rule ([`weak_parameters`]):
//!
//! 1. The covariance `C` of the least-squares distance fit on the measured configurations (the
//!    uncertainty's sandwich, [`predicted_covariance`], for a unit noise per axis) — a property of the
//!    configurations, whatever the method.
//! 2. Each free parameter j's 1σ as the data see it: θ_j moved by σ_j and the others by what they
//!    trade with it, `v_j = C e_j / σ_j` (a pair of parameters that compensate each other at the
//!    measured configurations is judged by how well they still compensate elsewhere).
//! 3. Its workspace effect: the RMS over [`WORKSPACE_CONFIGURATIONS`] configurations drawn uniformly
//!    within the joint limits (seeded, [`WORKSPACE_SEED`]; each paired with its next
//!    [`PARTNERS`]) and every reflector of the distance change `uᵀ (J_a − J_b) v_j`.
//! 4. Weak: that effect is more than [`WEAK_NOISE_RATIO`] times the tracker's noise per axis (the
//!    residuals' estimate). As both scale with the noise, the verdict is the configurations' alone.
//!
//! The reason in words comes from the measured configurations: for a reflector coordinate, how far
//! the flange turned about the two axes that would move it; for a DH parameter, how far its joint
//! moved of its range; otherwise what it trades with.

use super::uncertainty::{MAX_CONFIGURATIONS, predicted_covariance};
use crate::kinematics::{ArmJacobians, ArmModel, N_DH};
use crate::par::prelude::*;
use nalgebra::{DMatrix, Vector3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// Configurations drawn within the joint limits to judge the workspace effect.
pub const WORKSPACE_CONFIGURATIONS: usize = 200;
/// Each drawn configuration is paired with this many next ones (2000 pairs per reflector).
pub const PARTNERS: usize = 10;
/// The draw's seed: the same verdict on every run.
pub const WORKSPACE_SEED: u64 = 47;
/// A parameter whose 1σ moves distances across the workspace by more than this many times the
/// tracker's noise per axis is weak. The noise of a distance is √2 ≈ 1.4 times the noise per axis;
/// 3 leaves a margin of 2 over it, and on the paper-size data the largest ratio is far below
/// (docs/reliability.md, *Weak parameters*).
pub const WEAK_NOISE_RATIO: f64 = 3.0;

pub use crate::solver::types::WeakParameter;

/// The weak parameters among `free` (indices into `arm`'s parameters) of `arm` fitted to the
/// configurations `qs` and their measured points `measured` (module documentation); every one with
/// `held: false`. Empty when the fit cannot be summarised (fewer than three configurations, a
/// singular fit, no residual degrees of freedom).
pub fn weak_parameters(
    arm: &ArmModel,
    qs: &[Vec<f64>],
    measured: &[Vec<Vector3<f64>>],
    free: &[usize],
) -> Vec<WeakParameter> {
    let Some(noise_mm) = residual_noise_mm(arm, qs, measured, free.len()) else {
        return Vec::new();
    };
    let Some((cov, ratios)) = covariance_and_ratios(arm, qs, free) else {
        return Vec::new();
    };
    let p = free.len();
    let sigma: Vec<f64> = (0..p).map(|c| cov[(c, c)].max(0.0).sqrt()).collect();
    let spread = orientation_spread_deg(arm, qs);
    (0..p)
        .filter(|&c| ratios[c] > WEAK_NOISE_RATIO)
        .map(|c| {
            let k = free[c];
            let (sigma, unit) = match arm.param_unit(k) {
                "rad" => (sigma[c] * noise_mm * 1000.0, "mrad"),
                unit => (sigma[c] * noise_mm, unit),
            };
            WeakParameter {
                name: arm.param_name(k),
                index: k,
                sigma,
                unit: unit.to_string(),
                workspace_mm: ratios[c] * noise_mm,
                noise_mm,
                reason: reason(arm, qs, free, &cov, c, &spread),
                held: false,
            }
        })
        .collect()
}

/// Each of `free`'s workspace effect over the tracker's noise per axis (steps 1–3 of the module
/// documentation): the figure [`WEAK_NOISE_RATIO`] bounds. `None` where the fit is singular.
pub fn workspace_noise_ratios(arm: &ArmModel, qs: &[Vec<f64>], free: &[usize]) -> Option<Vec<f64>> {
    covariance_and_ratios(arm, qs, free).map(|(_, ratios)| ratios)
}

/// The unit-noise covariance of the fit on `qs` and [`workspace_noise_ratios`].
fn covariance_and_ratios(
    arm: &ArmModel,
    qs: &[Vec<f64>],
    free: &[usize],
) -> Option<(DMatrix<f64>, Vec<f64>)> {
    let cov = predicted_covariance(arm, qs, free, 1.0)?;
    let p = free.len();
    let sigma: Vec<f64> = (0..p).map(|c| cov[(c, c)].max(0.0).sqrt()).collect();
    // Column j: the parameters' move when θ_j moves by its 1σ (unit noise).
    let v = DMatrix::from_fn(p, p, |r, c| {
        if sigma[c] > 0.0 {
            cov[(r, c)] / sigma[c]
        } else {
            0.0
        }
    });
    let ratios = workspace_ratios(arm, free, &v);
    Some((cov, ratios))
}

/// The noise per axis the residuals of `arm` on `measured` show, mm: `Σ e² / (2 (rows − p))` over
/// the pairs of at most [`MAX_CONFIGURATIONS`] configurations (as the uncertainty estimates it).
fn residual_noise_mm(
    arm: &ArmModel,
    qs: &[Vec<f64>],
    measured: &[Vec<Vector3<f64>>],
    p: usize,
) -> Option<f64> {
    let n_all = qs.len().min(measured.len());
    let stride = n_all.div_ceil(MAX_CONFIGURATIONS).max(1);
    let used: Vec<usize> = (0..n_all).step_by(stride).collect();
    let model: Vec<Vec<Vector3<f64>>> = used
        .iter()
        .map(|&i| arm.reflector_fk(&qs[i]).points_mm)
        .collect();
    let (mut cost, mut rows) = (0.0, 0usize);
    for a in 0..used.len() {
        for b in a + 1..used.len() {
            for k in 0..arm.reflector_count() {
                let m = (measured[used[a]][k] - measured[used[b]][k]).norm();
                let d = (model[a][k] - model[b][k]).norm();
                if m > 0.0 && d > 0.0 {
                    cost += (m - d) * (m - d);
                    rows += 1;
                }
            }
        }
    }
    let dof = rows.checked_sub(p).filter(|&d| d > 0)?;
    let noise = (cost / (2.0 * dof as f64)).sqrt();
    (noise.is_finite() && noise > 0.0).then_some(noise)
}

/// Per column of `v` (the free parameters' 1σ moves), the RMS distance change across the workspace
/// ([`WORKSPACE_CONFIGURATIONS`] drawn within the limits, each with its next [`PARTNERS`]).
fn workspace_ratios(arm: &ArmModel, free: &[usize], v: &DMatrix<f64>) -> Vec<f64> {
    let limits = arm.joint_limits_rad();
    let mut rng = ChaCha8Rng::seed_from_u64(WORKSPACE_SEED);
    let qs: Vec<Vec<f64>> = (0..WORKSPACE_CONFIGURATIONS)
        .map(|_| {
            limits
                .iter()
                .map(|&(lo, hi)| {
                    if lo < hi {
                        rng.random_range(lo..hi)
                    } else {
                        lo
                    }
                })
                .collect()
        })
        .collect();
    let jac: Vec<ArmJacobians> = qs.par_iter().map(|q| arm.reflector_jacobians(q)).collect();
    let p = free.len();
    let n = jac.len();
    // The rows g = (J_a − J_b)ᵀ u of every pair and reflector, then every column's move `G v_j` at
    // once (one matrix product: the rows' dot products with each v_j one by one were three quarters
    // of the analysis' time).
    let partners = PARTNERS.min(n.saturating_sub(1));
    let mut g = DMatrix::<f64>::zeros(n * partners * arm.reflector_count(), p);
    let mut rows = 0usize;
    for a in 0..n {
        for s in 1..=partners {
            let b = (a + s) % n;
            for k in 0..arm.reflector_count() {
                let d = jac[a].fk.points_mm[k] - jac[b].fk.points_mm[k];
                let dist = d.norm();
                if dist <= 0.0 {
                    continue;
                }
                let u = d / dist;
                let (ja, jb) = (&jac[a].jacobians[k], &jac[b].jacobians[k]);
                for (c, &f) in free.iter().enumerate() {
                    g[(rows, c)] = (ja.column(f) - jb.column(f)).dot(&u);
                }
                rows += 1;
            }
        }
    }
    let moved = g.rows(0, rows) * v;
    moved
        .column_iter()
        .map(|m| (m.norm_squared() / rows.max(1) as f64).sqrt())
        .collect()
}

/// How far the flange turned about its own x, y and z across the configurations `qs`, degrees: the
/// range of each component of its rotation from the first configuration's.
fn orientation_spread_deg(arm: &ArmModel, qs: &[Vec<f64>]) -> [f64; 3] {
    let Some(first) = qs.first() else {
        return [0.0; 3];
    };
    let reference = arm.base_from_flange(first).rotation;
    let mut lo = [0.0f64; 3];
    let mut hi = [0.0f64; 3];
    for q in qs {
        let w = (reference.inverse() * arm.base_from_flange(q).rotation).scaled_axis();
        for c in 0..3 {
            lo[c] = lo[c].min(w[c]);
            hi[c] = hi[c].max(w[c]);
        }
    }
    std::array::from_fn(|c| (hi[c] - lo[c]).to_degrees())
}

/// Why free parameter `c` (its index into `free`) is weak, in words.
fn reason(
    arm: &ArmModel,
    qs: &[Vec<f64>],
    free: &[usize],
    cov: &DMatrix<f64>,
    c: usize,
    spread_deg: &[f64; 3],
) -> String {
    const AXES: [&str; 3] = ["x", "y", "z"];
    let k = free[c];
    let off = arm.reflector_offset();
    if k >= off && k < arm.error_offset() {
        let axis = (k - off) % 3;
        let (a, b) = ((axis + 1) % 3, (axis + 2) % 3);
        let (a, b) = (a.min(b), a.max(b));
        let name = arm.param_name(k);
        let reflector = name
            .strip_prefix("t_")
            .and_then(|n| n.split('.').next())
            .unwrap_or("?");
        return format!(
            "the flange turned at most {:.1}° about {} and {:.1}° about {} across these \
             configurations: reflector {reflector}'s offset along {} is not determined",
            spread_deg[a], AXES[a], spread_deg[b], AXES[b], AXES[axis]
        );
    }
    if arm.dh().is_some() && k < N_DH {
        let joint = k / 4;
        let limits = arm.joint_limits_rad();
        let (lo, hi) = qs
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), q| {
                (lo.min(q[joint]), hi.max(q[joint]))
            });
        let range = limits[joint].1 - limits[joint].0;
        if hi - lo < 0.25 * range {
            return format!(
                "joint {} moved over {:.0}° of its {:.0}° range across these configurations: {} \
                 is not determined",
                joint + 1,
                (hi - lo).to_degrees(),
                range.to_degrees(),
                arm.param_name(k)
            );
        }
    }
    // What it trades with most.
    let partner = (0..free.len()).filter(|&d| d != c).max_by(|&x, &y| {
        let rho = |d: usize| (cov[(c, d)] / (cov[(c, c)] * cov[(d, d)]).sqrt()).abs();
        rho(x).total_cmp(&rho(y))
    });
    match partner {
        Some(d) => format!(
            "these configurations do not tell it from {} (correlation {:.3})",
            arm.param_name(free[d]),
            cov[(c, d)] / (cov[(c, c)] * cov[(d, d)]).sqrt()
        ),
        None => "these configurations do not determine it".into(),
    }
}

#[cfg(test)]
mod tests;
