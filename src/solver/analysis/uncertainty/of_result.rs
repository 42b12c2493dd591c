//! The uncertainty of a calibration's result: each arm's, a shared torso's, an absolute method's.

use super::covariance::{arm_uncertainty_from, arm_uncertainty_weighted};
use super::report::{ArmUncertainty, summarise};
use super::sums::{Directions, MAX_CONFIGURATIONS, PairSums};
use super::weighting::Weighting;
use crate::kinematics::{ArmJacobians, ArmModel};
use crate::par::prelude::*;
use nalgebra::{DMatrix, DVector, Vector3};

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
        let (qs, measured) = fitted(&kept, settings, side);
        match result.pair_sums[side]
            .as_deref()
            .filter(|s| s.matches(arm, &qs, &measured, &report.free))
        {
            Some(sums) => arm_uncertainty_from(arm, sums, &weighting),
            None => arm_uncertainty_weighted(arm, &qs, &measured, &report.free, &weighting),
        }
    })
}

/// The joint values and measured points of `side`'s configurations of `kept` that `settings` fit.
pub(super) fn fitted(
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
        let kept = dataset.excluding(&settings.exclude);
        // A single-reflector method's reflector is known once it ran: computed again then.
        let weighting = Weighting::of(settings.method, None).unwrap_or(Weighting::LeastSquares);
        let (qs, measured) = fitted(&kept, settings, side);
        let value = arm_uncertainty_weighted(&arm, &qs, &measured, &free, &weighting);
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
pub(super) fn tree_uncertainty(
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

/// The uncertainty of an absolute method's fit (`pose`, `position`) of `side`: its own residuals and
/// Jacobian at the solution, the tracker-from-base transform's six columns with the arm's `free`
/// ones. Rows of one kind (positions, mm; a pose's origin, mm, and its weighted rotation) are taken
/// as independent with one variance per kind, estimated from the residuals:
/// `C = (JᵀJ)⁻¹ (Σ_rows s²_kind j jᵀ) (JᵀJ)⁻¹`, the arm's block reported.
pub(super) fn absolute_uncertainty(
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
