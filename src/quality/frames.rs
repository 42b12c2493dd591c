//! Whole-file plausibility: does the robot description fit the data at all, were both arms measured
//! in one tracker frame, did the tracker move during one arm's measurements.

use super::residual::ArmResiduals;
use super::{Finding, ScreenSettings, Severity, mpe_mm};
use crate::dataset::Dataset;
use crate::kinematics::{ArmModel, DualArmModel, rotation_angle_rad};
use crate::par::prelude::*;
use crate::side::Side;
use crate::stats::{median, median_in_place};
use nalgebra::{Point3, Vector3};

/// The nominal model of a robot that matches its description is within a few millimetres of the
/// measured distances (the paper's IRB 14000: 2.5 and 5.6 mm RMS); when the typical pair error (the
/// median over pairs of the worst reflector's |Δd|) exceeds this, mm, the data and the description do
/// not belong together (joint order or unit, wrong robot, wrong arm).
pub const NOMINAL_MAX_TYPICAL_MM: f64 = 25.0;
/// Before fitting, typical collaborative distance errors this many times the worse arm's relative
/// ones …
pub const FRAME_RATIO: f64 = 5.0;
/// … and above this, mm, say the two arms were not measured in one tracker frame.
pub const FRAME_MIN_TYPICAL_MM: f64 = 10.0;
/// A calibrated right-arm base further than this from the robot description's, mm …
pub const BASE_MAX_SHIFT_MM: f64 = 20.0;
/// … or turned by more than this, rad (2°), says the same after fitting.
pub const BASE_MAX_TURN_RAD: f64 = 0.035;
/// A tracker that moved within one arm's rows: mean squared distance error across the change point
/// this many times that within either part …
pub const MOVED_RATIO: f64 = 4.0;
/// … and above this many times the tracker's MPE (RMS).
pub const MOVED_MIN_MPE: f64 = 5.0;
/// Each part of a change point has at least this many configurations.
pub const MOVED_MIN_PART: usize = 10;
/// A reinterpretation of a row's joint values (reordered, converted).
type JointMap = Box<dyn Fn(&[f64]) -> Vec<f64>>;

/// Pairs sampled for the whole-file RMS figures.
const SAMPLE_PAIRS: usize = 20_000;

/// The typical distance error of a set of pairs: the median over a sample of pairs of the
/// worst-reflector |Δd| (model points `pa`, `pb` in one frame), mm. A median, so that a few gross
/// outliers (a swapped label is 80 mm off) do not make a good robot look wrong.
fn typical(
    ma: &[Vec<Vector3<f64>>],
    pa: &[Vec<Vector3<f64>>],
    mb: &[Vec<Vector3<f64>>],
    pb: &[Vec<Vector3<f64>>],
    same: bool,
) -> f64 {
    let mut worst = Vec::new();
    let reflectors = ma.first().map_or(0, Vec::len);
    super::sampled_pairs(ma.len(), mb.len(), same, SAMPLE_PAIRS, |i, j| {
        worst.push(
            (0..reflectors)
                .map(|k| ((ma[i][k] - mb[j][k]).norm() - (pa[i][k] - pb[j][k]).norm()).abs())
                .fold(0.0, f64::max),
        );
    });
    median_in_place(&mut worst)
}

fn points(
    dataset: &Dataset,
    arm: &ArmModel,
    side: Side,
    map: impl Fn(&[f64]) -> Vec<f64>,
) -> Vec<Vec<Vector3<f64>>> {
    dataset
        .arm(side)
        .measurements
        .iter()
        .map(|m| arm.reflector_fk(&map(&m.q_rad)).points_mm)
        .collect()
}

/// Findings before fitting: the nominal model far off the data (an error, with the likely cause when a
/// reordering or a unit explains it), and the arms in different tracker frames (a warning).
pub fn nominal_findings(dataset: &Dataset, nominal: &DualArmModel) -> Vec<Finding> {
    let mut out = Vec::new();
    let measured = |side: Side| -> Vec<Vec<Vector3<f64>>> {
        dataset
            .arm(side)
            .measurements
            .iter()
            .map(|m| m.tracker_points_mm.clone())
            .collect()
    };
    let mut relative = [0.0f64; 2];
    let mut model_pts = Vec::new();
    for (s, side) in Side::BOTH.into_iter().enumerate() {
        let arm = nominal.arm(side);
        let m = measured(side);
        let p = points(dataset, arm, side, <[f64]>::to_vec);
        relative[s] = typical(&m, &p, &m, &p, true);
        if relative[s] > NOMINAL_MAX_TYPICAL_MM {
            let file = dataset.arm(side).file.display();
            let candidates: [(&str, JointMap); 3] = [
                (
                    "the joint columns look like ABB axis order 1–7; q1..q7 are in chain order (ABB \
                     axes 1, 2, 7, 3, 4, 5, 6)",
                    Box::new(|q: &[f64]| {
                        if q.len() == crate::kinematics::ABB_AXIS_OF_CHAIN.len() {
                            crate::kinematics::ABB_AXIS_OF_CHAIN
                                .iter()
                                .map(|&a| q[a - 1])
                                .collect()
                        } else {
                            q.to_vec()
                        }
                    }),
                ),
                (
                    "the joint values fit as degrees: `units.angle` says rad",
                    Box::new(|q: &[f64]| q.iter().map(|v| v.to_radians()).collect()),
                ),
                (
                    "the joint values fit as radians: `units.angle` says deg",
                    Box::new(|q: &[f64]| q.iter().map(|v| v.to_degrees()).collect()),
                ),
            ];
            let hint = candidates
                .into_iter()
                .find(|(_, map)| {
                    let p = points(dataset, arm, side, map);
                    typical(&m, &p, &m, &p, true) < NOMINAL_MAX_TYPICAL_MM
                })
                .map_or_else(
                    || {
                        "are the joint columns in chain order and the unit right, and is this the \
                         robot (and the arm) that was measured?"
                            .to_string()
                    },
                    |(hint, _)| hint.to_string(),
                );
            out.push(Finding {
                severity: Severity::Error,
                side: Some(side),
                message: format!(
                    "{file}: the robot description's nominal model disagrees with the {side} arm's \
                     measured distances by {:.1} mm (median over pairs; a robot that matches its \
                     description is within a few mm): {hint}",
                    relative[s]
                ),
            });
        }
        model_pts.push(p);
    }
    // Arms declared as measured from different stations need no check of their common frame.
    if out.is_empty() && dataset.one_tracker_frame() {
        let (ml, mr) = (measured(Side::Left), measured(Side::Right));
        let b = nominal.left_base_from_right_base;
        let pr: Vec<Vec<Vector3<f64>>> = model_pts[1]
            .iter()
            .map(|p: &Vec<Vector3<f64>>| p.iter().map(|x| (b * Point3::from(*x)).coords).collect())
            .collect();
        let collaborative = typical(&ml, &model_pts[0], &mr, &pr, false);
        let worse = relative[0].max(relative[1]);
        if collaborative > (FRAME_RATIO * worse).max(FRAME_MIN_TYPICAL_MM) {
            out.push(Finding {
                severity: Severity::Warning,
                side: None,
                message: format!(
                    "the distances between the two arms' reflectors miss the nominal model by \
                     {collaborative:.1} mm, those within each arm by {worse:.1} mm (medians over \
                     pairs): were both \
                     arms measured from one tracker position? dualcal relies on one tracker frame \
                     for the base (step 2); each arm's own calibration is not affected (if the \
                     tracker was moved, name each arm's `station` in dataset.toml)"
                ),
            });
        }
    }
    out
}

/// After fitting: a right-arm base far from the robot description's (a warning: the arms were
/// probably measured in different tracker frames).
pub fn base_deviation(nominal: &DualArmModel, model: &DualArmModel) -> Option<Finding> {
    let a = &nominal.left_base_from_right_base;
    let b = &model.left_base_from_right_base;
    let shift = (a.translation.vector - b.translation.vector).norm();
    let turn = rotation_angle_rad(&(a.rotation.inverse() * b.rotation).to_rotation_matrix());
    (shift > BASE_MAX_SHIFT_MM || turn > BASE_MAX_TURN_RAD).then(|| Finding {
        severity: Severity::Warning,
        side: None,
        message: format!(
            "the calibrated right-arm base is {shift:.1} mm and {:.2}° from the robot description's: \
             were both arms measured from one tracker position? If the tracker moved between the \
             arms, the base (collaborative accuracy) is wrong by that motion; each arm's own \
             calibration is not affected",
            turn.to_degrees()
        ),
    })
}

/// A tracker that moved within `side`'s measurements (rows in file order): the change point where the
/// distance errors across it are far larger than within either part, under `model`. The rows in
/// `suspects` (flagged configurations of this arm) are left out: a few gross errors near one end of
/// the file must not look like a change point.
pub fn tracker_moved(
    dataset: &Dataset,
    model: &DualArmModel,
    side: Side,
    suspects: &[usize],
    settings: &ScreenSettings,
) -> Option<Finding> {
    let fit = ArmResiduals::new(dataset, model.arm(side), side);
    tracker_moved_with(dataset, &fit, suspects, settings)
}

/// [`tracker_moved`] with the arm's points and scale under the model at hand
/// ([`super::residual::fits`]).
pub(crate) fn tracker_moved_with(
    dataset: &Dataset,
    fit: &ArmResiduals,
    suspects: &[usize],
    _settings: &ScreenSettings,
) -> Option<Finding> {
    let side = fit.side;
    let all = &dataset.arm(side).measurements;
    // Many suspects are no outliers: they may be what a moved tracker did; keep them then.
    let few = suspects.len() * 10 <= all.len();
    let rows: Vec<usize> = (0..all.len())
        .filter(|i| !(few && suspects.contains(i)))
        .collect();
    let n = rows.len();
    if n < 2 * MOVED_MIN_PART {
        return None;
    }
    let ms: Vec<&crate::dataset::Measurement> = rows.iter().map(|&i| &all[i]).collect();
    // The kept rows' points, per reflector and axis, for the pair loop.
    let column = |points: &[Vec<Vector3<f64>>], k: usize, a: usize| -> Vec<f64> {
        rows.iter().map(|&i| points[i][k][a]).collect()
    };
    let reflectors = fit.sigma_mm.len();
    let measured: Vec<[Vec<f64>; 3]> = (0..reflectors)
        .map(|k| std::array::from_fn(|a| column(&fit.measured, k, a)))
        .collect();
    let model: Vec<[Vec<f64>; 3]> = (0..reflectors)
        .map(|k| std::array::from_fn(|a| column(&fit.model, k, a)))
        .collect();
    // Squared worst-reflector errors, capped so a few gross outliers do not make a change point.
    let sigma = median(&fit.sigma_mm);
    let cap = (10.0 * sigma).powi(2);
    // Row i's values with every later row j, written to `out[j − i − 1]`.
    let row = |i: usize, out: &mut Vec<f64>| {
        out.clear();
        out.resize(n - i - 1, 0.0);
        for k in 0..reflectors {
            let ([mx, my, mz], [px, py, pz]) = (&measured[k], &model[k]);
            let (mx, my, mz) = (&mx[i + 1..], &my[i + 1..], &mz[i + 1..]);
            let (px, py, pz) = (&px[i + 1..], &py[i + 1..], &pz[i + 1..]);
            let (mi, pi) = (
                [measured[k][0][i], measured[k][1][i], measured[k][2][i]],
                [model[k][0][i], model[k][1][i], model[k][2][i]],
            );
            let out = &mut out[..mx.len()];
            for j in 0..out.len() {
                let (a, b, c) = (mi[0] - mx[j], mi[1] - my[j], mi[2] - mz[j]);
                let (d, e, f) = (pi[0] - px[j], pi[1] - py[j], pi[2] - pz[j]);
                let dd = ((a * a + b * b + c * c).sqrt() - (d * d + e * e + f * f).sqrt()).abs();
                out[j] = out[j].max(dd);
            }
        }
        for v in out.iter_mut() {
            *v = (*v * *v).min(cap);
        }
    };
    let (before, after) = pair_row_sums(n, &row);
    // Split k: rows 0..k and k..n. Move row k-1 from the right part to the left one at a time.
    let mut cross = 0.0;
    let mut left = 0.0;
    let mut right: f64 = after.iter().sum();
    let mut best: Option<(f64, usize, f64, f64)> = None;
    for k in 1..n {
        let r = k - 1;
        // Row r leaves the right part: its pairs with later rows become cross pairs; its pairs with
        // earlier rows (cross until now) become left pairs.
        right -= after[r];
        cross += after[r] - before[r];
        left += before[r];
        if k < MOVED_MIN_PART || n - k < MOVED_MIN_PART {
            continue;
        }
        let (nl, nr) = (k as f64, (n - k) as f64);
        let cross_mean = cross / (nl * nr);
        let within_mean = (left + right) / (nl * (nl - 1.0) / 2.0 + nr * (nr - 1.0) / 2.0);
        let ratio = cross_mean / within_mean.max(1e-300);
        if best.is_none_or(|b| ratio > b.0) {
            best = Some((ratio, k, cross_mean.sqrt(), within_mean.sqrt()));
        }
    }
    let (ratio, k, cross_rms, within_rms) = best?;
    let mpe = mpe_mm(dataset, side);
    (ratio > MOVED_RATIO && cross_rms > MOVED_MIN_MPE * mpe).then(|| Finding {
        severity: Severity::Warning,
        side: Some(side),
        message: format!(
            "{}: the tracker (or the robot) seems to have moved between lines {} and {} (`{}` and \
             `{}`): distances across those rows miss the model by {cross_rms:.3} mm RMS, by \
             {within_rms:.3} mm within either part. The calibration mixes two frames: measure again, \
             or calibrate with one part only",
            dataset.arm(side).file.display(),
            ms[k - 1].line,
            ms[k].line,
            ms[k - 1].id,
            ms[k].id
        ),
    })
}

/// Blocks of rows the pair sums of [`pair_row_sums`] are split into (a fixed number, so that the
/// sums do not depend on the number of threads).
const PAIR_BLOCKS: usize = 16;

/// Row sums of the symmetric pair matrix `s(i, j)` (`i < j`) towards earlier rows (`before[j] = Σ_{i<j}
/// s(i, j)`) and later ones (`after[i] = Σ_{j>i} s(i, j)`), each pair evaluated once: `row(i, out)`
/// writes `s(i, j)` of every `j > i` to `out[j − i − 1]`. Blocks of rows of about equal pair counts
/// run in parallel, each with its own `before` column, added in block order.
fn pair_row_sums(n: usize, row: &(dyn Fn(usize, &mut Vec<f64>) + Sync)) -> (Vec<f64>, Vec<f64>) {
    // Block c starts where the pairs before it are c/PAIR_BLOCKS of all: row i has n − i − 1 pairs.
    let start = |c: usize| -> usize {
        let left = 1.0 - c as f64 / PAIR_BLOCKS as f64;
        ((n as f64 * (1.0 - left.sqrt())).round() as usize).min(n)
    };
    let blocks: Vec<(Vec<f64>, Vec<f64>)> = (0..PAIR_BLOCKS)
        .into_par_iter()
        .map(|c| {
            let mut before = vec![0.0; n];
            let mut values = Vec::with_capacity(n);
            let after: Vec<f64> = (start(c)..start(c + 1))
                .map(|i| {
                    row(i, &mut values);
                    for (b, v) in before[i + 1..].iter_mut().zip(&values) {
                        *b += v;
                    }
                    values.iter().sum()
                })
                .collect();
            (before, after)
        })
        .collect();
    let mut before = vec![0.0; n];
    let mut after = Vec::with_capacity(n);
    for (b, a) in blocks {
        for (x, y) in before.iter_mut().zip(b) {
            *x += y;
        }
        after.extend(a);
    }
    (before, after)
}
