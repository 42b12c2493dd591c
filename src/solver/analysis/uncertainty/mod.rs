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

mod covariance;
mod of_result;
mod report;
mod sums;
mod weighting;

pub use covariance::{
    PredictedDesign, arm_uncertainty, arm_uncertainty_from, arm_uncertainty_weighted, predicted,
    predicted_covariance, predicted_covariance_of, predicted_for_tracker,
    predicted_verification_ratio,
};
pub use of_result::{EarlyArmUncertainty, for_result, for_result_reusing, sigma_ratios};
pub use report::{ArmUncertainty, CorrelatedPair, ParameterSigma, REPORTED_CORRELATION};
pub use sums::{Directions, MAX_CONFIGURATIONS, PairSums};
pub use weighting::{ACTIVE_TOLERANCE, MINIMAX_WEIGHT_FLOOR, Weighting, minimax_multipliers};
