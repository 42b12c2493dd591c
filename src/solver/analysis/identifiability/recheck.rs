//! The identifiability analysis repeated at a step-1 solution: the distance Jacobian of the calibrated
//! arm on the start's sample of pairs (the same evenly strided pairs), with the parameters the start
//! left free as the only allowed ones. Its Gram matrix is the product `MMᵀ` summed over blocks of
//! rows without holding `M` (`arm_problem::pair_jacobian_gram`) whatever the robot: only its verdicts
//! are used (a parameter no longer identifiable, a grown condition number), and they are those of the
//! QR the start uses for the built-in robot (a test holds them on the test robots and the distance
//! methods).

use super::analyse::{IdentifiabilityReport, gram_by_qr};
use super::columns::{Analysis, Columns, analyse_columns};
use crate::kinematics::{ArmJacobians, ArmModel};
use crate::par::prelude::*;
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
