//! The identifiability analysis repeated at a step-1 solution, with the parameters the start left free
//! as the only allowed ones: only its verdicts are used (a parameter no longer identifiable, a grown
//! condition number).
//!
//! A calibration's run takes it from the pair sums it computes at the solution anyway for the
//! weak-parameter analysis and the uncertainty ([`at_solution_of_sums`]: the Gram matrix of every
//! pair's rows over the free parameters, on the configurations the sums use — all up to
//! `uncertainty::MAX_CONFIGURATIONS`, every k-th beyond). [`at_solution`] forms it afresh on the
//! start's sample of pairs (the same evenly strided pairs) over every parameter, as the product `MMᵀ`
//! summed over blocks of rows without holding `M` (`arm_problem::pair_jacobian_gram`): what the
//! planner's [`identifiable_at`] uses, and the comparison in the tests (the verdicts of both agree
//! with the QR's on the test robots and the distance methods).

use super::analyse::{IdentifiabilityReport, gram_by_qr, scaled_condition};
use super::columns::{Analysis, Columns, analyse_columns};
use crate::kinematics::{ArmJacobians, ArmModel};
use crate::par::prelude::*;
use crate::solver::analysis::uncertainty::PairSums;
use crate::solver::problems::arm_problem::{pair_jacobian_columns, pair_jacobian_gram};
use nalgebra::DMatrix;

/// How the re-check forms the Gram matrix of the sampled pair Jacobian.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GramMethod {
    /// The product `MMᵀ / count`, summed over blocks of rows (what the re-check uses).
    Product,
    /// `RᵀR / count` of a QR of `Mᵀ` (the start's analysis of the built-in robot; for comparison).
    Qr,
}

/// The analysis of `arm` at the configurations `qs` (one arm's calibration split), on at most
/// `max_pairs` evenly strided pairs per reflector, with only `allowed_free` allowed to be free.
pub fn at_solution(
    arm: &ArmModel,
    qs: &[Vec<f64>],
    allowed_free: &[usize],
    max_pairs: usize,
    method: GramMethod,
) -> IdentifiabilityReport {
    let jac: Vec<ArmJacobians> = qs.par_iter().map(|q| arm.reflector_jacobians(q)).collect();
    let reflectors = vec![true; arm.reflector_count()];
    let gram: DMatrix<f64> = match method {
        GramMethod::Product => pair_jacobian_gram(&jac, max_pairs, &reflectors),
        GramMethod::Qr => gram_by_qr(&pair_jacobian_columns(&jac, max_pairs, &reflectors)),
    };
    let n_params = arm.param_count();
    let mut allowed = vec![false; n_params];
    for &k in allowed_free {
        allowed[k] = true;
    }
    analyse_columns(
        &gram,
        &Columns::Arm {
            arm,
            transform: None,
        },
        &Analysis::distances(&allowed),
    )
}

/// The analysis of `arm` at the solution its pair sums `sums` were computed at: their mean Gram matrix
/// over every reflector's pairs, with only their free parameters allowed (the others' columns are not
/// formed: they are fixed as at the start). Its `condition_before` is the condition number of all the
/// allowed parameters' scaled columns (not of every parameter's). `None` when the sums have no rows.
pub fn at_solution_of_sums(arm: &ArmModel, sums: &PairSums) -> Option<IdentifiabilityReport> {
    let reduced = sums.mean_gram()?;
    let free = sums.free();
    let n_params = arm.param_count();
    let mut gram = DMatrix::zeros(n_params, n_params);
    let mut allowed = vec![false; n_params];
    for (a, &ka) in free.iter().enumerate() {
        allowed[ka] = true;
        for (b, &kb) in free.iter().enumerate() {
            gram[(ka, kb)] = reduced[(a, b)];
        }
    }
    let mut report = analyse_columns(
        &gram,
        &Columns::Arm {
            arm,
            transform: None,
        },
        &Analysis::distances(&allowed),
    );
    report.condition_before = scaled_condition(&reduced, &(0..free.len()).collect::<Vec<_>>());
    Some(report)
}

/// The parameters of `arm` that distances measured at the configurations `qs` identify: the
/// calibration's own analysis (every parameter allowed, the start's sample of at most
/// `set_up::IDENTIFIABILITY_PAIRS` pairs per reflector, its tolerances), at `arm` as it is. What a
/// plan is designed and predicted for — which of a URDF joint's axis-line corrections the previous
/// joint's offset and shift absorb depends on the axes' directions, and only the numbers tell.
pub fn identifiable_at(arm: &ArmModel, qs: &[Vec<f64>]) -> Vec<usize> {
    let all: Vec<usize> = (0..arm.param_count()).collect();
    at_solution(
        arm,
        qs,
        &all,
        crate::solver::methods::set_up::IDENTIFIABILITY_PAIRS,
        GramMethod::Product,
    )
    .free
}
