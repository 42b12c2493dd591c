//! The report of a covariance: σ per parameter, the strongly correlated pairs, the condition number.

use crate::kinematics::ArmModel;
use nalgebra::DMatrix;
use serde::{Deserialize, Serialize};

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

/// The report of a covariance: σ per parameter, the correlated pairs, the condition number.
pub(super) fn summarise(
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
pub(super) fn scaled_condition(jtj: &DMatrix<f64>) -> f64 {
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
