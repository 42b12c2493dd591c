//! The sandwich covariance of a distance fit, and what a design predicts.

use super::report::{ArmUncertainty, summarise};
use super::sums::{Directions, PairSums};
use super::weighting::{MINIMAX_WEIGHT_FLOOR, Weighting, minimax_weights};
use crate::kinematics::{ArmJacobians, ArmModel};
use nalgebra::{DMatrix, Vector3};

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
pub(super) fn uncertainty(
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
    Some(fit.summary(arm, free))
}

/// A fit's covariance and what it was made of.
pub(super) struct Covariance {
    /// Rows and columns: the free parameters.
    cov: DMatrix<f64>,
    /// The point noise per axis, squared (given, or estimated from the residuals).
    point_var: f64,
    configurations: usize,
    used: usize,
    jtj: DMatrix<f64>,
}

impl Covariance {
    /// The report of this covariance of `arm`'s parameters `free` ([`summarise`]).
    fn summary(&self, arm: &ArmModel, free: &[usize]) -> ArmUncertainty {
        summarise(
            arm,
            free,
            &self.cov,
            self.point_var,
            self.used,
            self.configurations,
            &self.jtj,
        )
    }
}

/// The sandwich covariance of the distance fit of `arm` at `qs` against `measured`, weighed as
/// `weighting` says (at most [`MAX_CONFIGURATIONS`] of them in the sums, the covariance scaled by the
/// fraction used).
pub(super) fn covariance(
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
pub(super) fn covariance_of(
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

/// [`arm_uncertainty`] of a fit weighing the reflectors as `weighting` says.
pub fn arm_uncertainty_weighted(
    arm: &ArmModel,
    qs: &[Vec<f64>],
    measured: &[Vec<Vector3<f64>>],
    free: &[usize],
    weighting: &Weighting,
) -> Option<ArmUncertainty> {
    let fit = covariance(arm, qs, measured, free, None, weighting)?;
    Some(fit.summary(arm, free))
}

/// [`arm_uncertainty_weighted`] of the fit's pair sums at hand.
pub fn arm_uncertainty_from(
    arm: &ArmModel,
    sums: &PairSums,
    weighting: &Weighting,
) -> Option<ArmUncertainty> {
    let fit = covariance_of(arm, sums, None, weighting, Directions::Measured)?;
    Some(fit.summary(arm, sums.free()))
}
