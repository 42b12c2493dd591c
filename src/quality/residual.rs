//! The model-based check: how far each configuration's reflectors seem displaced, given a model,
//! from their distances to all the other configurations of the arm — and, for a suspect row, which
//! simple mistake (swapped labels, swapped joint columns, a row of the other arm) would explain it.
//!
//! For configuration `i`, reflector `k` and every other configuration `j`:
//! `Δd_ij = |m_i − m_j| − |p_i − p_j|` (measured minus model distance) and, to first order,
//! `Δd_ij ≈ w_ij · e_i − w_ij · e_j` with `w_ij` the unit measured direction from `j` to `i` and `e` the
//! measurement errors. Treating the others' errors as noise, `e_i` is the Huber (robust least-squares)
//! fit of `w_ij · e_i` to the `Δd_ij`: the others' gross errors are down-weighted, so one bad row does
//! not smear over the good ones.

use super::stats::{mad_sigma, median};
use super::triangle::RELABELLINGS;
use super::{Flag, FlagKind, ScreenSettings, mpe_mm};
use crate::dataset::{Dataset, Measurement};
use crate::kinematics::{ArmModel, DualArmModel, REFLECTOR_NAMES};
use crate::side::{ConfigId, Side};
use nalgebra::{Matrix3, Vector3};
use rayon::prelude::*;

/// Fewer configurations than this give no reliable residual screening.
pub const MIN_CONFIGS: usize = 10;
/// Median of the χ distribution with 3 degrees of freedom: `median |e| = 1.5382 σ` for an isotropic
/// Gaussian error of σ per axis.
const CHI3_MEDIAN: f64 = 1.5382;
/// Huber threshold of the pair residuals, in robust standard deviations.
const HUBER_K: f64 = 2.0;
/// Re-weighting iterations.
const IRLS_ITERATIONS: usize = 8;
/// Pairs per reflector used for the residual scale.
const SCALE_PAIRS: usize = 50_000;

/// One arm's measured and model points, and the robust scale of its distance errors per reflector.
pub struct ArmResiduals {
    pub side: Side,
    /// Measured points (tracker frame) and model points (the arm's base frame), per configuration.
    pub measured: Vec<[Vector3<f64>; 3]>,
    pub model: Vec<[Vector3<f64>; 3]>,
    /// Robust standard deviation of the pair distance errors Δd per reflector, mm.
    pub sigma_mm: [f64; 3],
}

impl ArmResiduals {
    /// All configurations of `side` (every split) with `arm`'s forward kinematics.
    pub fn new(dataset: &Dataset, arm: &ArmModel, side: Side) -> Self {
        let ms = &dataset.arm(side).measurements;
        let measured: Vec<[Vector3<f64>; 3]> = ms.iter().map(|m| m.tracker_points_mm).collect();
        let model: Vec<[Vector3<f64>; 3]> = ms
            .par_iter()
            .map(|m| arm.reflector_fk(&m.q_rad).points_mm)
            .collect();
        let n = ms.len();
        let pairs = n * n.saturating_sub(1) / 2;
        let stride = pairs.div_ceil(SCALE_PAIRS).max(1);
        let floor = mpe_mm(dataset, side);
        let sigma_mm = std::array::from_fn(|k| {
            let mut dd = Vec::with_capacity(pairs / stride + 1);
            let mut idx = 0usize;
            for i in 0..n {
                for j in i + 1..n {
                    if idx.is_multiple_of(stride) {
                        dd.push(
                            (measured[i][k] - measured[j][k]).norm()
                                - (model[i][k] - model[j][k]).norm(),
                        );
                    }
                    idx += 1;
                }
            }
            mad_sigma(&dd).max(floor)
        });
        Self {
            side,
            measured,
            model,
            sigma_mm,
        }
    }

    /// The robust displacement estimate of each reflector of a row with measured points `m` and model
    /// points `p`, against every configuration of this arm but `skip`, mm (tracker frame).
    pub fn displacement(
        &self,
        m: &[Vector3<f64>; 3],
        p: &[Vector3<f64>; 3],
        skip: Option<usize>,
    ) -> [Vector3<f64>; 3] {
        std::array::from_fn(|k| {
            let rows: Vec<(Vector3<f64>, f64)> = (0..self.measured.len())
                .filter(|&j| Some(j) != skip)
                .filter_map(|j| {
                    let v = m[k] - self.measured[j][k];
                    let dm = v.norm();
                    (dm > 1e-9).then(|| (v / dm, dm - (p[k] - self.model[j][k]).norm()))
                })
                .collect();
            huber_fit(&rows, HUBER_K * self.sigma_mm[k])
        })
    }

    /// [`ArmResiduals::displacement`] of configuration `i` as measured.
    pub fn displacement_of(&self, i: usize) -> [Vector3<f64>; 3] {
        self.displacement(&self.measured[i], &self.model[i], Some(i))
    }
}

/// Huber fit of `e` to rows `(w, r)` with `r ≈ w · e`: iteratively re-weighted least squares from the
/// ordinary least-squares start.
fn huber_fit(rows: &[(Vector3<f64>, f64)], c: f64) -> Vector3<f64> {
    let solve = |weights: &dyn Fn(f64) -> f64, e: &Vector3<f64>| -> Option<Vector3<f64>> {
        let mut a = Matrix3::zeros();
        let mut b = Vector3::zeros();
        for (w, r) in rows {
            let omega = weights(r - w.dot(e));
            a += omega * w * w.transpose();
            b += omega * r * w;
        }
        a.try_inverse().map(|inv| inv * b)
    };
    let Some(mut e) = solve(&|_| 1.0, &Vector3::zeros()) else {
        return Vector3::repeat(f64::NAN);
    };
    for _ in 0..IRLS_ITERATIONS {
        let huber = |res: f64| if res.abs() <= c { 1.0 } else { c / res.abs() };
        match solve(&huber, &e) {
            Some(next) => e = next,
            None => break,
        }
    }
    e
}

/// Largest of three displacements and its reflector.
fn largest(e: &[Vector3<f64>; 3]) -> (f64, usize) {
    e.iter().enumerate().fold(
        (0.0, 0),
        |b, (k, v)| if v.norm() > b.0 { (v.norm(), k) } else { b },
    )
}

/// The displacement estimates of every configuration of `side` under `model`, and the flag threshold,
/// mm; `None` with fewer than [`MIN_CONFIGS`] configurations.
pub fn displacements(
    dataset: &Dataset,
    model: &DualArmModel,
    side: Side,
    settings: &ScreenSettings,
) -> Option<(Vec<[Vector3<f64>; 3]>, f64)> {
    let n = dataset.arm(side).measurements.len();
    if n < MIN_CONFIGS {
        return None;
    }
    let fit = ArmResiduals::new(dataset, model.arm(side), side);
    let e: Vec<[Vector3<f64>; 3]> = (0..n)
        .into_par_iter()
        .map(|i| fit.displacement_of(i))
        .collect();
    Some((e.clone(), threshold(dataset, side, &e, settings)))
}

fn threshold(
    dataset: &Dataset,
    side: Side,
    e: &[[Vector3<f64>; 3]],
    settings: &ScreenSettings,
) -> f64 {
    let sizes: Vec<f64> = e.iter().flatten().map(|v| v.norm()).collect();
    let sigma = median(&sizes) / CHI3_MEDIAN;
    (settings.residual_k * sigma).max(settings.mpe_floor * mpe_mm(dataset, side))
}

/// The residual flags of one arm under `model`, each explained where a simple mistake fits.
pub fn flags(
    dataset: &Dataset,
    model: &DualArmModel,
    side: Side,
    settings: &ScreenSettings,
) -> Vec<Flag> {
    let n = dataset.arm(side).measurements.len();
    if n < MIN_CONFIGS {
        return Vec::new();
    }
    let fit = ArmResiduals::new(dataset, model.arm(side), side);
    let e: Vec<[Vector3<f64>; 3]> = (0..n)
        .into_par_iter()
        .map(|i| fit.displacement_of(i))
        .collect();
    let tau = threshold(dataset, side, &e, settings);
    let other = (dataset.arm(side.other()).measurements.len() >= MIN_CONFIGS)
        .then(|| ArmResiduals::new(dataset, model.arm(side.other()), side.other()));
    let suspects: Vec<usize> = (0..n)
        .filter(|&i| {
            let (size, _) = largest(&e[i]);
            size > tau || size.is_nan()
        })
        .collect();
    suspects
        .into_par_iter()
        .map(|i| {
            let m = &dataset.arm(side).measurements[i];
            let (size, k) = largest(&e[i]);
            let size = if size.is_nan() { f64::INFINITY } else { size };
            let repair = explain(&fit, other.as_ref(), model, m, i, size, tau);
            let (kind, reflector, reason) = match repair {
                Some((kind, what, after)) => (
                    kind,
                    None,
                    format!(
                        "{what}: its reflectors seem displaced by up to {size:.3} mm as measured \
                         (threshold {tau:.3} mm), by {after:.3} mm with that correction"
                    ),
                ),
                None => {
                    let single = e[i]
                        .iter()
                        .enumerate()
                        .all(|(j, v)| j == k || v.norm() <= tau);
                    let what = if single {
                        format!(
                            "reflector {} seems displaced by {size:.3} mm",
                            REFLECTOR_NAMES[k]
                        )
                    } else {
                        format!(
                            "its reflectors seem displaced by {:.3}, {:.3}, {:.3} mm (a, b, c)",
                            e[i][0].norm(),
                            e[i][1].norm(),
                            e[i][2].norm()
                        )
                    };
                    (
                        FlagKind::Residual,
                        single.then_some(k),
                        format!(
                            "{what}: its distances to the other configurations do not fit the model \
                             (threshold {tau:.3} mm)"
                        ),
                    )
                }
            };
            Flag {
                config: ConfigId::new(side, i),
                id: m.id.clone(),
                line: m.line,
                split: m.split,
                kind,
                size_mm: size,
                threshold_mm: tau,
                reflector,
                reason,
            }
        })
        .collect()
}

/// A simple mistake that makes row `i` fit: its labels permuted, two of its joint columns swapped, or
/// the row belonging to the other arm. Returns the kind, a description and the largest displacement
/// after the correction, if it brings the row within the threshold and to well below its size.
fn explain(
    fit: &ArmResiduals,
    other: Option<&ArmResiduals>,
    model: &DualArmModel,
    m: &Measurement,
    i: usize,
    size: f64,
    tau: f64,
) -> Option<(FlagKind, String, f64)> {
    let arm = model.arm(fit.side);
    let mut candidates: Vec<(FlagKind, String, f64)> = Vec::new();
    for (perm, name) in RELABELLINGS {
        let e = fit.displacement(
            &perm.map(|k| m.tracker_points_mm[k]),
            &fit.model[i],
            Some(i),
        );
        candidates.push((
            FlagKind::LabelsSwapped,
            format!("reflector labels look swapped ({name})"),
            largest(&e).0,
        ));
    }
    let nq = m.q_rad.len();
    for a in 0..nq {
        for b in a + 1..nq {
            let mut q = m.q_rad.clone();
            q.swap(a, b);
            let p = arm.reflector_fk(&q).points_mm;
            let e = fit.displacement(&m.tracker_points_mm, &p, Some(i));
            candidates.push((
                FlagKind::JointsSwapped,
                format!(
                    "joint columns q{} and q{} look swapped in this row",
                    a + 1,
                    b + 1
                ),
                largest(&e).0,
            ));
        }
    }
    if let Some(other) = other {
        let p = model.arm(other.side).reflector_fk(&m.q_rad).points_mm;
        let e = other.displacement(&m.tracker_points_mm, &p, None);
        candidates.push((
            FlagKind::OtherArm,
            format!(
                "this row fits the {} arm's measurements: a row of the other arm's file?",
                other.side
            ),
            largest(&e).0,
        ));
    }
    candidates
        .into_iter()
        .filter(|c| c.2.is_finite() && c.2 <= tau && c.2 < 0.25 * size)
        .min_by(|a, b| a.2.total_cmp(&b.2))
}
