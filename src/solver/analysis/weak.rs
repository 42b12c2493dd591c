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

use super::uncertainty::{PairSums, predicted_covariance, predicted_covariance_of};
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
    weak_parameters_of(arm, qs, &PairSums::new(arm, qs, measured, free))
}

/// [`weak_parameters`] with the fit's pair sums at hand (computed on `qs` and the measured points;
/// the free parameters are theirs).
pub fn weak_parameters_of(arm: &ArmModel, qs: &[Vec<f64>], sums: &PairSums) -> Vec<WeakParameter> {
    let free = sums.free();
    let Some(noise_mm) = sums.point_sigma_mm() else {
        return Vec::new();
    };
    let Some((cov, ratios)) =
        covariance_and_ratios(arm, free, predicted_covariance_of(arm, sums, 1.0))
    else {
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
    covariance_and_ratios(arm, free, predicted_covariance(arm, qs, free, 1.0))
        .map(|(_, ratios)| ratios)
}

/// The unit-noise covariance `cov` of the fit and [`workspace_noise_ratios`].
fn covariance_and_ratios(
    arm: &ArmModel,
    free: &[usize],
    cov: Option<DMatrix<f64>>,
) -> Option<(DMatrix<f64>, Vec<f64>)> {
    let cov = cov?;
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
    let reflectors = arm.reflector_count();
    // A pair's distance change under column j's move is `uᵀ (J_a − J_b) v_j = uᵀ (W_a − W_b)_j` with
    // `W = J V` per configuration and reflector: one matrix product of V by the stacked Jacobian
    // rows (3 per configuration and reflector, as columns), then 6 products per pair and column —
    // instead of a p-long row per pair multiplied by V.
    let mut stack = DMatrix::<f64>::zeros(p, 3 * n * reflectors);
    for (a, j) in jac.iter().enumerate() {
        for (k, m) in j.jacobians.iter().enumerate() {
            for t in 0..3 {
                let mut column = stack.column_mut(3 * (a * reflectors + k) + t);
                for (c, &f) in free.iter().enumerate() {
                    column[c] = m[(t, f)];
                }
            }
        }
    }
    // Column 3 (a R + k) + t: row t of W for configuration a and reflector k.
    let w = v.transpose() * &stack;
    let w = w.as_slice();
    let partners = PARTNERS.min(n.saturating_sub(1));
    let mut squares = vec![0.0; p];
    let mut rows = 0usize;
    for a in 0..n {
        for s in 1..=partners {
            let b = (a + s) % n;
            for k in 0..reflectors {
                let d = jac[a].fk.points_mm[k] - jac[b].fk.points_mm[k];
                let dist = d.norm();
                if dist <= 0.0 {
                    continue;
                }
                let u = d / dist;
                let (ra, rb) = (3 * (a * reflectors + k) * p, 3 * (b * reflectors + k) * p);
                let (wa, wb) = (&w[ra..ra + 3 * p], &w[rb..rb + 3 * p]);
                for (c, sq) in squares.iter_mut().enumerate() {
                    let moved = u.x * (wa[c] - wb[c])
                        + u.y * (wa[p + c] - wb[p + c])
                        + u.z * (wa[2 * p + c] - wb[2 * p + c]);
                    *sq += moved * moved;
                }
                rows += 1;
            }
        }
    }
    squares
        .iter()
        .map(|sq| (sq / rows.max(1) as f64).sqrt())
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
