//! How well the data determine each identified parameter: standard deviations, strong correlations
//! and the condition number of step 1's fit, from the residuals at the solution.
//!
//! The distance errors of step 1 are `r_ij,k = |m_i,k − m_j,k| − |p_i,k(x) − p_j,k(x)|` over every pair
//! of configurations and reflector k. They are **not** independent: a measured point's error enters all
//! n − 1 distances of its configuration, so `σ² (JᵀJ)⁻¹` (independent rows) would be too small.
//! With independent point errors `e_i,k` of variance `σ_p²` per axis, the least-squares estimate's
//! covariance is the sandwich
//!
//! `C = (JᵀJ)⁻¹ (σ_p² Σ_i,k A_i,k A_i,kᵀ) (JᵀJ)⁻¹`,  `A_i,k = Σ_{j≠i} ∂r_ij,k/∂x · û_ij,kᵀ`
//!
//! (û the measured direction, as `r` depends on `e_i − e_j` through it), with J the Jacobian of the
//! identified (free) parameters. `σ_p²` is estimated from the residuals at the solution,
//! `Σ r² / (2 (rows − p))` (a distance error has the variance of two point errors along the line): a
//! geometric model that does not explain the data counts as noise here, so the σ grow with it.
//!
//! Each method's σ is its own ([`Weighting`]). The minimax: at its solution the KKT condition is
//! `Σ λ_k ∇F_k = 0` over the active reflectors, so locally it is the least squares of `Σ λ_k F_k` —
//! the same sandwich with reflector k's rows weighted by λ_k in `JᵀJ` and by λ_k² in the middle, the
//! λ_k recomputed here from the gradients at the solution ([`MINIMAX_WEIGHT_FLOOR`] keeps a reflector
//! of zero weight in it). The single-reflector method: its reflector's rows only. The absolute
//! methods: their own residuals and Jacobian with the tracker transform (`absolute_uncertainty`).
//! `tests/sigma_coverage.rs` checks every method's RMS(error/σ) on simulations (docs/solver.md).
//! Beyond [`MAX_CONFIGURATIONS`] per arm the sums use every k-th
//! configuration and the covariance is scaled by the fraction used (a covariance falls as 1/n).
//! The condition number is that of the column-scaled Jacobian of the free parameters: how much a
//! relative error of the data can grow in the parameters; above ~1e3 single parameters are poorly
//! determined even when the fit's accuracy is good (they trade off against each other — the
//! correlations say which).

use crate::kinematics::{ArmJacobians, ArmModel};
use crate::par::prelude::*;
use nalgebra::{DMatrix, DVector, Vector3};
use serde::{Deserialize, Serialize};

mod sums;
use sums::Sums;
pub use sums::{Directions, PairSums};

/// At most this many configurations per arm enter the sums (every k-th beyond; the pair sums grow as
/// n², and 80 keep both arms at ~3 ms).
pub const MAX_CONFIGURATIONS: usize = 80;
/// Correlations at or above this magnitude are reported.
pub const REPORTED_CORRELATION: f64 = 0.9;

/// One identified parameter's standard deviation.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ParameterSigma {
    pub name: String,
    /// One standard deviation in `unit`.
    pub sigma: f64,
    /// `mm` or `mrad`; an error parameter's own (`mrad/(N·m)`, …).
    pub unit: String,
}

/// Two parameters the data hardly tell apart.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CorrelatedPair {
    pub a: String,
    pub b: String,
    pub correlation: f64,
}

/// The uncertainty of one arm's identified parameters (module documentation).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ArmUncertainty {
    /// The point noise per axis estimated from the residuals, mm.
    pub point_sigma_mm: f64,
    /// Configurations of the fit, and how many entered the sums.
    pub configurations: usize,
    pub configurations_used: usize,
    /// Condition number of the column-scaled Jacobian of the identified parameters.
    pub condition: f64,
    /// Every identified parameter, in parameter order.
    pub parameters: Vec<ParameterSigma>,
    /// Pairs with |correlation| ≥ [`REPORTED_CORRELATION`], strongest first.
    pub correlations: Vec<CorrelatedPair>,
}

impl ArmUncertainty {
    /// The parameter with the largest σ of `unit` (`mm` or `mrad`).
    pub fn largest(&self, unit: &str) -> Option<&ParameterSigma> {
        self.parameters
            .iter()
            .filter(|p| p.unit == unit)
            .max_by(|a, b| a.sigma.total_cmp(&b.sigma))
    }
}

/// The uncertainty of `arm`'s parameters `free` (indices into its parameter vector) fitted to the
/// configurations `qs` and their measured points `measured` (tracker frame, one per reflector).
/// `None` with fewer than three configurations, no free parameter, or a singular fit.
pub fn arm_uncertainty(
    arm: &ArmModel,
    qs: &[Vec<f64>],
    measured: &[Vec<Vector3<f64>>],
    free: &[usize],
) -> Option<ArmUncertainty> {
    uncertainty(arm, qs, measured, free, None)
}

/// The uncertainty a measurement of `arm` at `qs` would give with a tracker noise of `point_sigma_mm`
/// per axis (measurement planning, [`crate::plan`]): the model's own points stand for the measured
/// ones, and the noise is the one given rather than the residuals'.
pub fn predicted(
    arm: &ArmModel,
    qs: &[Vec<f64>],
    free: &[usize],
    point_sigma_mm: f64,
) -> Option<ArmUncertainty> {
    let points: Vec<Vec<Vector3<f64>>> = qs.iter().map(|q| arm.reflector_fk(q).points_mm).collect();
    uncertainty(arm, qs, &points, free, Some(point_sigma_mm))
}

/// What a planned measurement predicts ([`predicted_for_tracker`]).
#[derive(Clone, Debug)]
pub struct PredictedDesign {
    /// The tracker's noise per axis at the arm, mm (half its MPE at the distance).
    pub point_sigma_mm: f64,
    pub uncertainty: ArmUncertainty,
    /// [`predicted_verification_ratio`] on the sample given (`None` without one).
    pub verification_ratio: Option<f64>,
}

/// [`predicted`] for a planned measurement of `side` of `robot`: the tracker's noise at its distance
/// to the arm's base (half the MPE, per axis), over the parameters distances between `qs` identify
/// (the calibration's analysis, [`crate::solver::identifiability::identifiable_at`]); and the
/// verification accuracy predicted on `ver` (configurations where the robot goes). `None` where the
/// information is singular.
pub fn predicted_for_tracker(
    robot: &crate::robot::RobotDescription,
    arm: &ArmModel,
    side: crate::side::Side,
    qs: &[Vec<f64>],
    ver: &[Vec<f64>],
    tracker: &crate::dataset::TrackerSpec,
    tracker_in_body_mm: &Vector3<f64>,
) -> Option<PredictedDesign> {
    // The parameters a calibration on `qs` frees (its own analysis).
    let free = crate::solver::analysis::identifiability::identifiable_at(arm, qs);
    let base = robot.body_from_arm_base(side).translation.vector;
    let sigma_mm =
        0.5e-3 * (tracker.mpe_um + tracker.mpe_um_per_m * (tracker_in_body_mm - base).norm() / 1e3);
    let uncertainty = predicted(arm, qs, &free, sigma_mm)?;
    let verification_ratio = if ver.len() >= 2 {
        predicted_verification_ratio(arm, qs, ver, &free, sigma_mm)
    } else {
        None
    };
    Some(PredictedDesign {
        point_sigma_mm: sigma_mm,
        uncertainty,
        verification_ratio,
    })
}

/// [`arm_uncertainty`], the point noise estimated from the residuals or given.
fn uncertainty(
    arm: &ArmModel,
    qs: &[Vec<f64>],
    measured: &[Vec<Vector3<f64>>],
    free: &[usize],
    point_sigma_mm: Option<f64>,
) -> Option<ArmUncertainty> {
    let fit = covariance(
        arm,
        qs,
        measured,
        free,
        point_sigma_mm,
        &Weighting::LeastSquares,
    )?;
    Some(summarise(
        arm,
        free,
        &fit.cov,
        fit.point_var,
        fit.used,
        fit.configurations,
        &fit.jtj,
    ))
}

/// A fit's covariance and what it was made of.
struct Covariance {
    /// Rows and columns: the free parameters.
    cov: DMatrix<f64>,
    /// The point noise per axis, squared (given, or estimated from the residuals).
    point_var: f64,
    configurations: usize,
    used: usize,
    jtj: DMatrix<f64>,
}

/// The configurations of `n_all` that enter the sums: all up to [`MAX_CONFIGURATIONS`], else every
/// k-th.
fn used_configurations(n_all: usize) -> Vec<usize> {
    let stride = n_all.div_ceil(MAX_CONFIGURATIONS).max(1);
    (0..n_all).step_by(stride).collect()
}

/// The sandwich covariance of the distance fit of `arm` at `qs` against `measured`, weighed as
/// `weighting` says (at most [`MAX_CONFIGURATIONS`] of them in the sums, the covariance scaled by the
/// fraction used).
fn covariance(
    arm: &ArmModel,
    qs: &[Vec<f64>],
    measured: &[Vec<Vector3<f64>>],
    free: &[usize],
    point_sigma_mm: Option<f64>,
    weighting: &Weighting,
) -> Option<Covariance> {
    let sums = PairSums::new(arm, qs, measured, free);
    covariance_of(arm, &sums, point_sigma_mm, weighting, Directions::Measured)
}

/// [`covariance`] of sums at hand, the sandwich's middle of `directions`.
fn covariance_of(
    arm: &ArmModel,
    sums: &PairSums,
    point_sigma_mm: Option<f64>,
    weighting: &Weighting,
    directions: Directions,
) -> Option<Covariance> {
    let (n_all, n) = sums.configurations();
    let free = sums.free();
    let p = free.len();
    if n < 3 || p == 0 {
        return None;
    }
    let first = sums.weighed(&weighting.first_weights(arm), directions);
    let dof = first.rows.checked_sub(p).filter(|&d| d > 0)?;
    let point_var = match point_sigma_mm {
        Some(s) => s * s,
        None => first.cost / (2.0 * dof as f64),
    };
    // The minimax: the sums again, each reflector weighed by its multiplier at the solution.
    let weighted = match weighting {
        Weighting::Minimax => {
            // A reflector below the floor (λ_k = 0: F_k not active, or a kink) still fits its own
            // coordinates; the floor keeps them in the covariance.
            let lambda: Vec<f64> = minimax_weights(arm, free, &first)
                .iter()
                .map(|l| l.max(MINIMAX_WEIGHT_FLOOR))
                .collect();
            Some(sums.weighed(&lambda, directions))
        }
        _ => None,
    };
    let (a, b) = weighted
        .as_ref()
        .map_or((&first.jtj, &first.meat), |w| (&w.jtj, &w.meat));
    let inverse = a.clone().cholesky()?.inverse();
    let mut cov = &inverse * b * &inverse * point_var;
    if n < n_all {
        cov *= n as f64 / n_all as f64;
    }
    Some(Covariance {
        cov,
        point_var,
        configurations: n_all,
        used: n,
        jtj: first.jtj,
    })
}

/// The covariance (rows and columns: `free`) the least-squares fit of `arm` at `qs` would have with a
/// point noise of `point_sigma_mm` per axis — the matrix behind [`predicted`]'s σ.
pub fn predicted_covariance(
    arm: &ArmModel,
    qs: &[Vec<f64>],
    free: &[usize],
    point_sigma_mm: f64,
) -> Option<DMatrix<f64>> {
    let points: Vec<Vec<Vector3<f64>>> = qs.iter().map(|q| arm.reflector_fk(q).points_mm).collect();
    predicted_covariance_of(arm, &PairSums::new(arm, qs, &points, free), point_sigma_mm)
}

/// [`predicted_covariance`] of the configurations `sums` were computed on (the model's directions in
/// the sandwich's middle; the measured points enter nothing else).
pub fn predicted_covariance_of(
    arm: &ArmModel,
    sums: &PairSums,
    point_sigma_mm: f64,
) -> Option<DMatrix<f64>> {
    covariance_of(
        arm,
        sums,
        Some(point_sigma_mm),
        &Weighting::LeastSquares,
        Directions::Model,
    )
    .map(|c| c.cov)
}

/// The verification accuracy a design predicts, as a multiple of the noise floor: over the pairs of
/// the configurations `ver` (where the robot will be verified or used) and every reflector, the mean
/// squared distance error of the model calibrated from `design` — the tracker's noise on a distance,
/// `2σ²`, plus the parameters' uncertainty carried to it, `gᵀ C g` with `g = (J_i − J_j)ᵀ u` and `C`
/// of [`predicted_covariance`] — over the noise's alone, square-rooted. 1.0: the true parameters'
/// accuracy. A least-squares prediction (minimax fits spread wider: docs/solver.md).
pub fn predicted_verification_ratio(
    arm: &ArmModel,
    design: &[Vec<f64>],
    ver: &[Vec<f64>],
    free: &[usize],
    point_sigma_mm: f64,
) -> Option<f64> {
    let cov = predicted_covariance(arm, design, free, point_sigma_mm)?;
    let jac: Vec<ArmJacobians> = ver.iter().map(|q| arm.reflector_jacobians(q)).collect();
    let (mut sum, mut count) = (0.0, 0usize);
    let mut g = nalgebra::DVector::<f64>::zeros(free.len());
    for i in 0..jac.len() {
        for j in i + 1..jac.len() {
            for k in 0..arm.reflector_count() {
                let v = jac[i].fk.points_mm[k] - jac[j].fk.points_mm[k];
                let dist = v.norm();
                if dist <= 0.0 {
                    continue;
                }
                let u = v / dist;
                for (c, &f) in free.iter().enumerate() {
                    let d = jac[i].jacobians[k].column(f) - jac[j].jacobians[k].column(f);
                    g[c] = d.dot(&u);
                }
                sum += (cov.transpose() * &g).dot(&g);
                count += 1;
            }
        }
    }
    if count == 0 {
        return None;
    }
    let noise = 2.0 * point_sigma_mm * point_sigma_mm;
    Some(((noise + sum / count as f64) / noise).sqrt())
}

/// The report of a covariance: σ per parameter, the correlated pairs, the condition number.
fn summarise(
    arm: &ArmModel,
    free: &[usize],
    cov: &DMatrix<f64>,
    point_var: f64,
    n: usize,
    n_all: usize,
    jtj: &DMatrix<f64>,
) -> ArmUncertainty {
    let p = free.len();
    let sigma: Vec<f64> = (0..p).map(|c| cov[(c, c)].max(0.0).sqrt()).collect();
    let parameters = free
        .iter()
        .zip(&sigma)
        .map(|(&k, &s)| {
            // Angles in mrad; lengths in mm; the error parameters in their own units.
            let (sigma, unit) = match arm.param_unit(k) {
                "rad" => (s * 1000.0, "mrad"),
                unit => (s, unit),
            };
            ParameterSigma {
                name: arm.param_name(k),
                sigma,
                unit: unit.to_string(),
            }
        })
        .collect();
    let mut correlations = Vec::new();
    for a in 0..p {
        for b in a + 1..p {
            let rho = cov[(a, b)] / (sigma[a] * sigma[b]);
            if rho.abs() >= REPORTED_CORRELATION {
                correlations.push(CorrelatedPair {
                    a: arm.param_name(free[a]),
                    b: arm.param_name(free[b]),
                    correlation: rho,
                });
            }
        }
    }
    crate::sort::sort_by(&mut correlations, |x, y| {
        y.correlation.abs().total_cmp(&x.correlation.abs())
    });
    ArmUncertainty {
        point_sigma_mm: point_var.sqrt(),
        configurations: n_all,
        configurations_used: n,
        condition: scaled_condition(jtj),
        parameters,
        correlations,
    }
}

/// Condition number of `JᵀJ` with unit-scaled columns, as of J: √(λ_max / λ_min).
fn scaled_condition(jtj: &DMatrix<f64>) -> f64 {
    let d: Vec<f64> = (0..jtj.nrows())
        .map(|c| 1.0 / jtj[(c, c)].max(f64::MIN_POSITIVE).sqrt())
        .collect();
    let scaled = DMatrix::from_fn(jtj.nrows(), jtj.ncols(), |a, b| jtj[(a, b)] * d[a] * d[b]);
    let eig = scaled.symmetric_eigenvalues();
    let (lo, hi) = eig.iter().fold((f64::INFINITY, 0.0f64), |(lo, hi), &v| {
        (lo.min(v), hi.max(v))
    });
    if lo > 0.0 {
        (hi / lo).sqrt()
    } else {
        f64::INFINITY
    }
}

/// The uncertainty of each arm's step-1 parameters of `result`, fitted to `dataset` (its split and
/// exclusions), the method's own ([`Weighting`]; the absolute methods from their own residuals);
/// `None` for an arm without an identifiability report or whose fit cannot be summarised.
pub fn for_result(
    dataset: &crate::dataset::Dataset,
    result: &crate::solver::result::CalibrationResult,
) -> crate::side::PerSide<Option<ArmUncertainty>> {
    for_result_reusing(dataset, result, Default::default())
}

/// [`for_result`], taking each arm's [`EarlyArmUncertainty`] where it applies (the same numbers: the
/// same computation on the same arm).
pub fn for_result_reusing(
    dataset: &crate::dataset::Dataset,
    result: &crate::solver::result::CalibrationResult,
    mut early: crate::side::PerSide<Option<EarlyArmUncertainty>>,
) -> crate::side::PerSide<Option<ArmUncertainty>> {
    let settings = &result.settings;
    let kept = dataset.excluding(&settings.exclude);
    let shared = result.calibrated.shared_joints();
    // Arms that share joints were fitted at once, unless one arm was measured alone (its chain is
    // then fitted whole, as any arm's).
    if !shared.is_empty() && dataset.both_measured() {
        return tree_uncertainty(&kept, result, &shared).unwrap_or_default();
    }
    crate::side::PerSide::from_fn(|side| {
        let report = result.identifiability[side].as_ref()?;
        if settings.method.is_absolute() {
            return absolute_uncertainty(&kept, result, side, &report.free);
        }
        let weighting = Weighting::of(settings.method, result.reflector_used[side])?;
        let arm = result.calibrated.arm(side);
        if let Some(early) = early[side].take()
            && early.arm == *arm
            && early.free == report.free
            && early.weighting == weighting
        {
            return early.value;
        }
        arm_uncertainty_on(&kept, settings, side, arm, &report.free, &weighting)
    })
}

/// [`arm_uncertainty`] of `side`'s fitted configurations of `kept` (the split `settings` fits).
fn arm_uncertainty_on(
    kept: &crate::dataset::Dataset,
    settings: &crate::solver::settings::CalibrationSettings,
    side: crate::side::Side,
    arm: &ArmModel,
    free: &[usize],
    weighting: &Weighting,
) -> Option<ArmUncertainty> {
    let (qs, measured) = fitted(kept, settings, side);
    arm_uncertainty_weighted(arm, &qs, &measured, free, weighting)
}

/// The joint values and measured points of `side`'s configurations of `kept` that `settings` fit.
fn fitted(
    kept: &crate::dataset::Dataset,
    settings: &crate::solver::settings::CalibrationSettings,
    side: crate::side::Side,
) -> (Vec<Vec<f64>>, Vec<Vec<Vector3<f64>>>) {
    let ms = kept.arm(side).select(settings.split);
    let qs = ms.iter().map(|m| m.q_rad.clone()).collect();
    let measured = ms.iter().map(|m| m.tracker_points_mm.clone()).collect();
    (qs, measured)
}

/// An arm's uncertainty computed as soon as its step-1 stage ended (beside step 2, which does not
/// change the arm); [`for_result_reusing`] takes it where the result's arm and free parameters are
/// the ones it was computed for, and computes it again otherwise.
pub struct EarlyArmUncertainty {
    arm: ArmModel,
    free: Vec<usize>,
    weighting: Weighting,
    value: Option<ArmUncertainty>,
}

impl EarlyArmUncertainty {
    /// The uncertainty of `arm` (its step-1 solution, `free` its free parameters) on `dataset` as
    /// `settings` fit it.
    pub fn new(
        dataset: &crate::dataset::Dataset,
        settings: &crate::solver::settings::CalibrationSettings,
        side: crate::side::Side,
        arm: ArmModel,
        free: Vec<usize>,
    ) -> Self {
        Self::reusing(dataset, settings, side, arm, free, None)
    }

    /// [`EarlyArmUncertainty::new`] from the pair sums of the run's weak-parameter analysis
    /// ([`crate::solver::CalibrationRun::pair_sums`]) where they are this arm's (the same numbers,
    /// without the second pass over the pairs); computed afresh otherwise.
    pub fn reusing(
        dataset: &crate::dataset::Dataset,
        settings: &crate::solver::settings::CalibrationSettings,
        side: crate::side::Side,
        arm: ArmModel,
        free: Vec<usize>,
        sums: Option<&PairSums>,
    ) -> Self {
        let kept = dataset.excluding(&settings.exclude);
        // A single-reflector method's reflector is known once it ran: computed again then.
        let weighting = Weighting::of(settings.method, None).unwrap_or(Weighting::LeastSquares);
        let (qs, measured) = fitted(&kept, settings, side);
        let value = match sums.filter(|s| s.matches(&arm, &qs, &measured, &free)) {
            Some(sums) => arm_uncertainty_from(&arm, sums, &weighting),
            None => arm_uncertainty_weighted(&arm, &qs, &measured, &free, &weighting),
        };
        Self {
            arm,
            free,
            weighting,
            value,
        }
    }
}

/// [`for_result`] of arms that share joints (a torso), fitted at once: both arms' sums in the tree's
/// free parameters (a shared one is one column; `solver::tree_problem`), one covariance, each arm's
/// part of it reported in that arm's names (a shared parameter in both, with the same σ). `None` where
/// the fit cannot be summarised (too few configurations, a singular fit).
fn tree_uncertainty(
    kept: &crate::dataset::Dataset,
    result: &crate::solver::result::CalibrationResult,
    shared: &crate::kinematics::SharedJoints,
) -> Option<crate::side::PerSide<Option<ArmUncertainty>>> {
    use crate::side::{PerSide, Side};
    let settings = &result.settings;
    let reports =
        PerSide::try_from_fn(|side| result.identifiability[side].as_ref().ok_or(())).ok()?;
    // The tree's columns: the left arm's free parameters, then the right arm's that are not shared.
    let mut cols: PerSide<Vec<usize>> =
        PerSide::new((0..reports.left.free.len()).collect(), Vec::new());
    let mut next = reports.left.free.len();
    for &b in &reports.right.free {
        let col = match shared.left_param_of(b) {
            Some(a) => reports.left.free.iter().position(|&k| k == a)?,
            None => {
                next += 1;
                next - 1
            }
        };
        cols.right.push(col);
    }
    let p = next;
    let mut jtj = DMatrix::<f64>::zeros(p, p);
    let mut meat = DMatrix::<f64>::zeros(p, p);
    let (mut cost, mut rows, mut used_all, mut n_all_all) = (0.0, 0usize, 0usize, 0usize);
    let mut counts: PerSide<(usize, usize)> = PerSide::default();
    for side in Side::BOTH {
        let arm = result.calibrated.arm(side);
        let ms = kept.arm(side).select(settings.split);
        let n_all = ms.len();
        let stride = n_all.div_ceil(MAX_CONFIGURATIONS).max(1);
        let used: Vec<usize> = (0..n_all).step_by(stride).collect();
        if used.len() < 3 {
            return None;
        }
        let jac: Vec<ArmJacobians> = used
            .par_iter()
            .map(|&i| arm.reflector_jacobians(&ms[i].q_rad))
            .collect();
        let points: Vec<&Vec<Vector3<f64>>> =
            used.iter().map(|&i| &ms[i].tracker_points_mm).collect();
        let weights = vec![1.0; arm.reflector_count()];
        let sums = PairSums::from_jacobians(arm, &jac, &points, &reports[side].free, n_all)
            .weighed(&weights, Directions::Measured);
        let c = &cols[side];
        for i in 0..c.len() {
            for j in 0..c.len() {
                jtj[(c[i], c[j])] += sums.jtj[(i, j)];
                meat[(c[i], c[j])] += sums.meat[(i, j)];
            }
        }
        cost += sums.cost;
        rows += sums.rows;
        counts[side] = (used.len(), n_all);
        used_all += used.len();
        n_all_all += n_all;
    }
    let dof = rows.checked_sub(p).filter(|&d| d > 0)?;
    let point_var = cost / (2.0 * dof as f64);
    let inverse = jtj.clone().cholesky()?.inverse();
    let mut cov = &inverse * &meat * &inverse * point_var;
    if used_all < n_all_all {
        cov *= used_all as f64 / n_all_all as f64;
    }
    Some(PerSide::from_fn(|side| {
        let c = &cols[side];
        let sub = |m: &DMatrix<f64>| DMatrix::from_fn(c.len(), c.len(), |i, j| m[(c[i], c[j])]);
        let (used, n_all) = counts[side];
        Some(summarise(
            result.calibrated.arm(side),
            &reports[side].free,
            &sub(&cov),
            point_var,
            used,
            n_all,
            &sub(&jtj),
        ))
    }))
}

/// Each identified parameter's error against a known `truth` over its reported σ, both arms of
/// `result` (the parameters of `uncertainty`, matched by name): the measure of how well the σ describe
/// the errors on simulations — their RMS is 1 when they do (`examples/sigma_coverage.rs`).
pub fn sigma_ratios(
    result: &crate::solver::result::CalibrationResult,
    uncertainty: &crate::side::PerSide<Option<ArmUncertainty>>,
    truth: &crate::kinematics::DualArmModel,
) -> Vec<f64> {
    let mut ratios = Vec::new();
    for side in crate::side::Side::BOTH {
        let Some(u) = &uncertainty[side] else {
            continue;
        };
        let (arm, true_arm) = (result.calibrated.arm(side), truth.arm(side));
        let (x, t) = (arm.to_vector(), true_arm.to_vector());
        for p in &u.parameters {
            let Some(k) = (0..arm.param_count()).find(|&k| arm.param_name(k) == p.name) else {
                continue;
            };
            let scale = if p.unit == "mrad" { 1000.0 } else { 1.0 };
            if p.sigma > 0.0 && k < t.len() {
                ratios.push((x[k] - t[k]) * scale / p.sigma);
            }
        }
    }
    ratios
}

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
    fn first_weights(&self, arm: &ArmModel) -> Vec<f64> {
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
fn minimax_weights(arm: &ArmModel, free: &[usize], sums: &Sums) -> Vec<f64> {
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

/// [`arm_uncertainty`] of a fit weighing the reflectors as `weighting` says.
pub fn arm_uncertainty_weighted(
    arm: &ArmModel,
    qs: &[Vec<f64>],
    measured: &[Vec<Vector3<f64>>],
    free: &[usize],
    weighting: &Weighting,
) -> Option<ArmUncertainty> {
    let fit = covariance(arm, qs, measured, free, None, weighting)?;
    Some(summarise(
        arm,
        free,
        &fit.cov,
        fit.point_var,
        fit.used,
        fit.configurations,
        &fit.jtj,
    ))
}

/// [`arm_uncertainty_weighted`] of the fit's pair sums at hand.
pub fn arm_uncertainty_from(
    arm: &ArmModel,
    sums: &PairSums,
    weighting: &Weighting,
) -> Option<ArmUncertainty> {
    let fit = covariance_of(arm, sums, None, weighting, Directions::Measured)?;
    Some(summarise(
        arm,
        sums.free(),
        &fit.cov,
        fit.point_var,
        fit.used,
        fit.configurations,
        &fit.jtj,
    ))
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

/// The uncertainty of an absolute method's fit (`pose`, `position`) of `side`: its own residuals and
/// Jacobian at the solution, the tracker-from-base transform's six columns with the arm's `free`
/// ones. Rows of one kind (positions, mm; a pose's origin, mm, and its weighted rotation) are taken
/// as independent with one variance per kind, estimated from the residuals:
/// `C = (JᵀJ)⁻¹ (Σ_rows s²_kind j jᵀ) (JᵀJ)⁻¹`, the arm's block reported.
fn absolute_uncertainty(
    kept: &crate::dataset::Dataset,
    result: &crate::solver::result::CalibrationResult,
    side: crate::side::Side,
    free: &[usize],
) -> Option<ArmUncertainty> {
    use crate::solver::problems::absolute_problem::{AbsoluteData, AbsoluteProblem};
    let ms = kept.arm(side).select(result.settings.split);
    let qs: Vec<Vec<f64>> = ms.iter().map(|m| m.q_rad.clone()).collect();
    let measured: Vec<Vec<Vector3<f64>>> = ms.iter().map(|m| m.tracker_points_mm.clone()).collect();
    let arm = result.calibrated.arm(side);
    let (data, kinds) = if result.settings.method == crate::solver::methods::table::Method::Pose {
        let w = AbsoluteProblem::rotation_weight_mm(&result.nominal.arm(side).reflectors_mm);
        (
            AbsoluteData::Pose {
                rotation_weight_mm: w,
            },
            2,
        )
    } else {
        (AbsoluteData::Position, 1)
    };
    let (n, p) = (qs.len(), free.len());
    let dim = p + 6;
    let problem = AbsoluteProblem::new(
        data,
        side,
        qs,
        measured,
        arm,
        result.tracker_from_base[side]?,
        free.to_vec(),
        DVector::from_element(dim, 1.0),
    )
    .ok()?;
    let (r, j) = problem.jacobian(&DVector::zeros(dim));
    let rows = r.len();
    let per_config = rows / n.max(1);
    let kind = |row: usize| {
        if kinds == 2 {
            (row % per_config) / 3
        } else {
            0
        }
    };
    let dof_fraction = 1.0 - dim as f64 / rows as f64;
    if dof_fraction <= 0.0 {
        return None;
    }
    let mut var = vec![0.0; kinds];
    let mut count = vec![0usize; kinds];
    for row in 0..rows {
        var[kind(row)] += r[row] * r[row];
        count[kind(row)] += 1;
    }
    for c in 0..kinds {
        var[c] /= count[c] as f64 * dof_fraction;
    }
    let jtj = j.tr_mul(&j);
    let weighted = DMatrix::from_fn(rows, dim, |row, c| j[(row, c)] * var[kind(row)]);
    let meat = j.tr_mul(&weighted);
    let inverse = jtj.clone().cholesky()?.inverse();
    let cov = &inverse * meat * &inverse;
    let arm_block = cov.view((0, 0), (p, p)).into_owned();
    Some(summarise(arm, free, &arm_block, var[0], n, n, &jtj))
}
