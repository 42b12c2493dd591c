//! Per-configuration geometry, computed once, and the pair loops that combine it.

use super::kabsch::kabsch_fit_points;
use super::{
    AccuracyStats, MIN_METRIC_CONFIGS, MetricsError, ORI_THRESHOLDS_RAD, POS_THRESHOLDS_MM,
};
use crate::dataset::{ArmData, Dataset, Measurement, Split};
use crate::kinematics::{ArmModel, DualArmModel, MAX_REFLECTORS, PerReflector};
use crate::par::prelude::*;
use crate::side::Side;
use nalgebra::{Isometry3, Vector3};

/// Everything the pair loops need about one configuration, as plain arrays: the pair loops run tens of
/// thousands of times per evaluation and plain arithmetic stays fast in unoptimised (test) builds too.
#[derive(Clone, Copy, Debug)]
pub(super) struct ConfigGeom {
    /// Measured reflector points, tracker frame, mm.
    pub(super) measured_mm: PerReflector<[f64; 3]>,
    /// Model reflector points in the reference base frame, mm.
    pub(super) model_mm: PerReflector<[f64; 3]>,
    /// `M = R_m · R_oᵀ` (row-major): the measured flange rotation (Kabsch fit, tracker frame) times the
    /// inverse of the model's (reference base frame). See [`pair_residual`]. The identity when the
    /// orientation is not measurable (fewer than three reflectors): [`ArmGeom::orientation`] says so.
    pub(super) measured_from_model_rot: [[f64; 3]; 3],
    /// RMS residual of that Kabsch fit, mm (0 without orientation).
    pub(super) fit_rms_mm: f64,
}

/// One arm's selected configurations: indices into `ArmData::measurements` and their geometry.
pub(super) struct ArmGeom {
    pub(super) side: Side,
    pub(super) indices: Vec<usize>,
    pub(super) geom: Vec<ConfigGeom>,
    /// Is the flange orientation measurable (three or more non-collinear reflectors)? Without it the
    /// orientation figures are "not measurable" (`None`), never zero.
    pub(super) orientation: bool,
}

/// Can the model's reflectors give the flange's orientation (three or more, not collinear)?
pub fn orientation_measurable(reflectors_mm: &[Vector3<f64>]) -> bool {
    if reflectors_mm.len() < 3 {
        return false;
    }
    let t = reflectors_mm;
    let (ab, ac) = (t[1] - t[0], t[2] - t[0]);
    let longest = ab.norm().max(ac.norm()).max((t[2] - t[1]).norm());
    ab.cross(&ac).norm() > 1e-9 * longest * longest
}

fn check_model_arm(side: Side, arm: &ArmModel) -> Result<(), MetricsError> {
    if let Some(name) = arm.first_non_finite() {
        return Err(MetricsError::NonFiniteModel {
            field: format!("{side} arm {name}"),
        });
    }
    // Three reflectors that a model made collinear give no orientation where the data would: refused
    // (one or two reflectors have none to give).
    if arm.reflector_count() == 3 && !orientation_measurable(&arm.reflectors_mm) {
        return Err(MetricsError::DegenerateReflectors { side });
    }
    Ok(())
}

fn check_base(b: &Isometry3<f64>) -> Result<(), MetricsError> {
    let finite = b.translation.vector.iter().all(|x| x.is_finite())
        && b.rotation.coords.iter().all(|x| x.is_finite());
    if finite {
        Ok(())
    } else {
        Err(MetricsError::NonFiniteModel {
            field: "left_base_from_right_base".into(),
        })
    }
}

fn check_measurement(side: Side, m: &Measurement, arm: &ArmModel) -> Result<(), MetricsError> {
    let joints = arm.joint_count();
    if m.q_rad.len() != joints {
        return Err(MetricsError::JointCount {
            side,
            id: m.id.clone(),
            found: m.q_rad.len(),
            expected: joints,
        });
    }
    let bad = |field: String| MetricsError::NonFiniteMeasurement {
        side,
        id: m.id.clone(),
        line: m.line,
        field,
    };
    if let Some(j) = m.q_rad.iter().position(|q| !q.is_finite()) {
        return Err(bad(format!("q{}", j + 1)));
    }
    if m.tracker_points_mm.len() != arm.reflector_count() {
        return Err(MetricsError::ReflectorCount {
            side,
            id: m.id.clone(),
            found: m.tracker_points_mm.len(),
            expected: arm.reflector_count(),
        });
    }
    for (k, p) in m.tracker_points_mm.iter().enumerate() {
        if let Some(c) = p.iter().position(|x| !x.is_finite()) {
            return Err(bad(format!(
                "{}{}",
                arm.reflector_names[k],
                ["x", "y", "z"][c]
            )));
        }
    }
    Ok(())
}

/// Geometry of one arm's selected configurations, model quantities expressed in the frame
/// `reference_from_base` maps to (the left-arm base for collaborative use; any frame for relative use,
/// which is invariant under a common rigid motion).
pub(super) fn arm_geometry(
    data: &ArmData,
    side: Side,
    arm: &ArmModel,
    reference_from_base: &Isometry3<f64>,
    split: Split,
) -> Result<ArmGeom, MetricsError> {
    check_model_arm(side, arm)?;
    let selected: Vec<(usize, &Measurement)> = data
        .measurements
        .iter()
        .enumerate()
        .filter(|(_, m)| split.contains(m.split))
        .collect();
    // An arm the dataset does not have (one arm measured alone) has no geometry, and no figures.
    if selected.len() < MIN_METRIC_CONFIGS && data.is_measured() {
        return Err(MetricsError::TooFewConfigurations {
            side,
            split,
            found: selected.len(),
            min: MIN_METRIC_CONFIGS,
        });
    }
    for (_, m) in &selected {
        check_measurement(side, m, arm)?;
    }
    let orientation = orientation_measurable(&arm.reflectors_mm);
    let n_refl = arm.reflector_count();
    let reference_rot = reference_from_base.rotation.to_rotation_matrix();
    let geom = selected
        .par_iter()
        .map(|(_, m)| {
            let fk = arm.reflector_fk(&m.q_rad);
            let model_mm = PerReflector::from_fn(n_refl, |k| {
                reference_from_base
                    .transform_point(&fk.points_mm[k].into())
                    .coords
            });
            let model_rot = reference_rot * fk.base_from_flange.rotation.to_rotation_matrix();
            let (measured_from_model_rot, fit_rms_mm) = if orientation {
                let fit = kabsch_fit_points(&arm.reflectors_mm, &m.tracker_points_mm).ok_or_else(
                    || MetricsError::FitFailed {
                        side,
                        id: m.id.clone(),
                    },
                )?;
                (
                    (fit.rotation * model_rot.transpose())
                        .into_inner()
                        .transpose()
                        .into(),
                    fit.rms_mm,
                )
            } else {
                ([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]], 0.0)
            };
            let g = ConfigGeom {
                measured_mm: PerReflector::from_fn(n_refl, |k| m.tracker_points_mm[k].into()),
                model_mm: model_mm.map(|p| p.into()),
                measured_from_model_rot,
                fit_rms_mm,
            };
            let finite = model_mm.iter().all(|p| p.iter().all(|x| x.is_finite()))
                && model_rot.matrix().iter().all(|x| x.is_finite());
            if finite {
                Ok(g)
            } else {
                Err(MetricsError::NonFiniteResult {
                    what: format!("forward kinematics of {side} configuration `{}`", m.id),
                })
            }
        })
        .collect::<Result<Vec<_>, _>>()?;
    Ok(ArmGeom {
        side,
        indices: selected.iter().map(|(i, _)| *i).collect(),
        geom,
        orientation,
    })
}

/// `Δd` per reflector and `Δo` of one pair `(i, j)` = `(a, b)`.
///
/// `Δo = ‖log(E)‖` with `E = (R_m,iᵀ R_m,j)ᵀ (R_o,iᵀ R_o,j) = R_m,jᵀ M_i R_o,j`, `M = R_m R_oᵀ`. The angle
/// of a rotation is invariant under conjugation, and `R_o,j E R_o,jᵀ = M_jᵀ M_i`, so `Δo` is the angle of
/// `M_jᵀ M_i`: one matrix product per pair.
#[inline]
pub(super) fn pair_residual(a: &ConfigGeom, b: &ConfigGeom) -> (PerReflector<f64>, f64) {
    let dd = PerReflector::from_fn(a.measured_mm.len(), |k| {
        distance(&a.measured_mm[k], &b.measured_mm[k]) - distance(&a.model_mm[k], &b.model_mm[k])
    });
    let (mb, ma) = (&b.measured_from_model_rot, &a.measured_from_model_rot);
    // E = M_bᵀ M_a, row-major: E[r][c] = Σ_k M_b[k][r] · M_a[k][c].
    let e = |r: usize, c: usize| mb[0][r] * ma[0][c] + mb[1][r] * ma[1][c] + mb[2][r] * ma[2][c];
    // The angle of E as in `rotation_angle_rad`: atan2 of the sine (half the skew part's norm) and
    // the cosine ((trace − 1) / 2).
    let cos = ((e(0, 0) + e(1, 1) + e(2, 2) - 1.0) * 0.5).clamp(-1.0, 1.0);
    let (sx, sy, sz) = (e(2, 1) - e(1, 2), e(0, 2) - e(2, 0), e(1, 0) - e(0, 1));
    let sin = 0.5 * (sx * sx + sy * sy + sz * sz).sqrt();
    (dd, angle_rad(sin, cos))
}

/// `sin.atan2(cos)` for `sin ≥ 0`. Below π/2 (every Δo of a working calibration) as `atan(sin / cos)`,
/// which agrees with it to an ulp and takes about half the time; below 0.1 rad (every Δo of a
/// calibrated model, and most of a nominal one) `atan` by its series ([`atan_small`]), within an ulp
/// of the library's and a third of its cost. The pair loops spend a third of their time here.
#[inline]
pub(super) fn angle_rad(sin: f64, cos: f64) -> f64 {
    if cos > 0.0 {
        let t = sin / cos;
        if t < ATAN_SERIES_MAX {
            atan_small(t)
        } else {
            t.atan()
        }
    } else {
        sin.atan2(cos)
    }
}

/// Below this [`atan_small`] is used.
const ATAN_SERIES_MAX: f64 = 0.1;

/// `atan(t)` for `0 ≤ t < 0.1` by its Taylor series `t − t³/3 + t⁵/5 − …` to the `t¹⁷` term: the first
/// term left out is below `t · 10⁻¹⁸/19`, far below half an ulp, so the result is within an ulp of
/// the correctly rounded value (Horner's rounding).
#[inline]
fn atan_small(t: f64) -> f64 {
    let u = t * t;
    let mut p = 1.0 / 17.0;
    for c in [
        -1.0 / 15.0,
        1.0 / 13.0,
        -1.0 / 11.0,
        1.0 / 9.0,
        -1.0 / 7.0,
        1.0 / 5.0,
        -1.0 / 3.0,
        1.0,
    ] {
        p = p * u + c;
    }
    t * p
}

#[inline]
fn distance(p: &[f64; 3], q: &[f64; 3]) -> f64 {
    let (x, y, z) = (p[0] - q[0], p[1] - q[1], p[2] - q[2]);
    (x * x + y * y + z * z).sqrt()
}

/// Pairs [`residuals_against`] computes at once.
const PAIR_LANES: usize = 4;

/// [`pair_residual`]`(a, b)` for every `b` of `others`, handed to `visit` in order: [`PAIR_LANES`]
/// pairs at a time in plain arrays the compiler keeps in SIMD lanes (the square roots, the division
/// and the series of `Δo` four at once). Each pair's arithmetic is [`pair_residual`]'s, operation for
/// operation, and the pairs reach `visit` in the same order: the sums over them are the same to the bit
/// (a test holds it).
#[inline]
pub(super) fn residuals_against(
    a: &ConfigGeom,
    others: &[ConfigGeom],
    mut visit: impl FnMut(&[f64], f64),
) {
    let n_refl = a.measured_mm.len();
    let ma = &a.measured_from_model_rot;
    let mut chunks = others.chunks_exact(PAIR_LANES);
    for chunk in &mut chunks {
        // Per reflector, per lane.
        let mut dd = [[0.0; PAIR_LANES]; MAX_REFLECTORS];
        for (k, dd_k) in dd.iter_mut().enumerate().take(n_refl) {
            let (am, ao) = (&a.measured_mm[k], &a.model_mm[k]);
            let measured: [f64; PAIR_LANES] =
                std::array::from_fn(|l| distance(am, &chunk[l].measured_mm[k]));
            let model: [f64; PAIR_LANES] =
                std::array::from_fn(|l| distance(ao, &chunk[l].model_mm[k]));
            for (d, (m, p)) in dd_k.iter_mut().zip(measured.iter().zip(&model)) {
                *d = m - p;
            }
        }
        let mut cos = [0.0; PAIR_LANES];
        let mut sin = [0.0; PAIR_LANES];
        for l in 0..PAIR_LANES {
            let mb = &chunk[l].measured_from_model_rot;
            let e = |r: usize, c: usize| {
                mb[0][r] * ma[0][c] + mb[1][r] * ma[1][c] + mb[2][r] * ma[2][c]
            };
            cos[l] = ((e(0, 0) + e(1, 1) + e(2, 2) - 1.0) * 0.5).clamp(-1.0, 1.0);
            let (sx, sy, sz) = (e(2, 1) - e(1, 2), e(0, 2) - e(2, 0), e(1, 0) - e(0, 1));
            sin[l] = 0.5 * (sx * sx + sy * sy + sz * sz).sqrt();
        }
        let mut series = [0.0; PAIR_LANES];
        let mut small = [false; PAIR_LANES];
        for l in 0..PAIR_LANES {
            let t = sin[l] / cos[l];
            small[l] = cos[l] > 0.0 && t < ATAN_SERIES_MAX;
            series[l] = atan_small(t);
        }
        for l in 0..PAIR_LANES {
            // `angle_rad`'s own branch where the series does not apply.
            let ori = if small[l] {
                series[l]
            } else {
                angle_rad(sin[l], cos[l])
            };
            let lane: [f64; MAX_REFLECTORS] = std::array::from_fn(|k| dd[k][l]);
            visit(&lane[..n_refl], ori);
        }
    }
    for b in chunks.remainder() {
        let (dd, ori) = pair_residual(a, b);
        visit(&dd, ori);
    }
}

pub(super) fn worst(dd: &[f64]) -> f64 {
    dd.iter()
        .copied()
        .fold(0.0, |w, d| if d.abs() > w.abs() { d } else { w })
}

/// Running sums for [`AccuracyStats`]; mergeable for parallel reduction.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct Accumulator {
    n: usize,
    pos_sum_sq: PerReflector<f64>,
    pos_max: f64,
    pos_within: [usize; 2],
    ori_sum_sq: f64,
    ori_max: f64,
    ori_within: [usize; 2],
}

impl Accumulator {
    #[inline]
    pub(super) fn add(&mut self, dd: &[f64], ori: f64) {
        if self.pos_sum_sq.len() < dd.len() {
            self.pos_sum_sq = PerReflector::from_fn(dd.len(), |_| 0.0);
        }
        self.n += 1;
        let mut w = 0.0f64;
        for (s, d) in self.pos_sum_sq.iter_mut().zip(dd) {
            *s += d * d;
            w = w.max(d.abs());
        }
        self.pos_max = self.pos_max.max(w);
        self.ori_sum_sq += ori * ori;
        self.ori_max = self.ori_max.max(ori);
        for t in 0..2 {
            self.pos_within[t] += usize::from(w <= POS_THRESHOLDS_MM[t]);
            self.ori_within[t] += usize::from(ori <= ORI_THRESHOLDS_RAD[t]);
        }
    }

    pub(super) fn merge(mut self, o: Self) -> Self {
        self.n += o.n;
        if self.pos_sum_sq.len() < o.pos_sum_sq.len() {
            self.pos_sum_sq = PerReflector::from_fn(o.pos_sum_sq.len(), |_| 0.0);
        }
        for k in 0..o.pos_sum_sq.len() {
            self.pos_sum_sq[k] += o.pos_sum_sq[k];
        }
        self.pos_max = self.pos_max.max(o.pos_max);
        self.ori_sum_sq += o.ori_sum_sq;
        self.ori_max = self.ori_max.max(o.ori_max);
        for t in 0..2 {
            self.pos_within[t] += o.pos_within[t];
            self.ori_within[t] += o.ori_within[t];
        }
        self
    }

    /// The figures; `orientation`: is the orientation measurable (else its figures are `None`)?
    pub(super) fn finish(
        self,
        n_configs: usize,
        orientation: bool,
        what: &str,
    ) -> Result<AccuracyStats, MetricsError> {
        let n = self.n.max(1) as f64;
        let per = self.pos_sum_sq.map(|s| (s / n).sqrt());
        let frac = |c: usize| c as f64 / n;
        let ori = |v: f64| orientation.then_some(v);
        let stats = AccuracyStats {
            pos_rms_mm: per.iter().copied().fold(0.0, f64::max),
            pos_rms_per_reflector_mm: per,
            pos_max_mm: self.pos_max,
            ori_rms_rad: ori((self.ori_sum_sq / n).sqrt()),
            ori_max_rad: ori(self.ori_max),
            pos_within_0_3mm_frac: frac(self.pos_within[0]),
            pos_within_0_6mm_frac: frac(self.pos_within[1]),
            ori_within_0_005rad_frac: ori(frac(self.ori_within[0])),
            ori_within_0_01rad_frac: ori(frac(self.ori_within[1])),
            n_configs,
            n_pairs: self.n,
        };
        // `f64::max` ignores NaN, so a NaN pair shows up only in the sums.
        let finite = per.iter().all(|x| x.is_finite())
            && stats.pos_max_mm.is_finite()
            && stats.ori_rms_rad.is_none_or(f64::is_finite);
        if finite {
            Ok(stats)
        } else {
            Err(MetricsError::NonFiniteResult {
                what: format!("the {what} accuracy"),
            })
        }
    }
}

/// Blocks a parallel sum over configurations is cut into (fixed: see [`ordered_sum`]).
pub(super) const SUM_BLOCKS: usize = 32;

/// `fold` every index of `0..n` into a value per block of [`SUM_BLOCKS`] consecutive indices, in
/// parallel, then `merge` the blocks' values in block order. The blocks do not depend on the threads,
/// so the floating-point sums are the same on every run and machine — a rayon `fold`/`reduce` splits
/// where its scheduler did, which moves a figure's last bits from one run to the next.
pub(super) fn ordered_sum<A: Send>(
    n: usize,
    init: impl Fn() -> A + Sync + Send,
    fold: impl Fn(&mut A, usize) + Sync + Send,
    merge: impl Fn(A, A) -> A,
) -> A {
    let per_block = n.div_ceil(SUM_BLOCKS).max(1);
    let parts: Vec<A> = (0..n.div_ceil(per_block))
        .into_par_iter()
        .map(|b| {
            let mut acc = init();
            for i in b * per_block..((b + 1) * per_block).min(n) {
                fold(&mut acc, i);
            }
            acc
        })
        .collect();
    parts.into_iter().fold(init(), merge)
}

pub(super) fn relative_accumulate(g: &[ConfigGeom]) -> Accumulator {
    ordered_sum(
        g.len(),
        Accumulator::default,
        |acc, i| residuals_against(&g[i], &g[i + 1..], |dd, o| acc.add(dd, o)),
        Accumulator::merge,
    )
}

pub(super) fn collaborative_accumulate(left: &[ConfigGeom], right: &[ConfigGeom]) -> Accumulator {
    ordered_sum(
        left.len(),
        Accumulator::default,
        |acc, i| residuals_against(&left[i], right, |dd, o| acc.add(dd, o)),
        Accumulator::merge,
    )
}

/// The pairs of one id in both arms — both hands at one instant (`measured_together` data) — among
/// `left` and `right` (selected configurations' geometry, each with its index into the arm's
/// measurements), accumulated; and how many there are.
pub(super) fn same_instant_accumulate(
    dataset: &Dataset,
    (left, left_indices): (&[ConfigGeom], &[usize]),
    (right, right_indices): (&[ConfigGeom], &[usize]),
) -> (Accumulator, usize) {
    let id = |side: Side, i: usize| dataset.arm(side).measurements[i].id.as_str();
    let right_of: std::collections::HashMap<&str, usize> = right_indices
        .iter()
        .enumerate()
        .map(|(k, &i)| (id(Side::Right, i), k))
        .collect();
    let mut acc = Accumulator::default();
    let mut pairs = 0;
    for (k, &i) in left_indices.iter().enumerate() {
        if let Some(&r) = right_of.get(id(Side::Left, i)) {
            let (dd, o) = pair_residual(&left[k], &right[r]);
            acc.add(&dd, o);
            pairs += 1;
        }
    }
    (acc, pairs)
}

/// Both arms' geometry with the model expressed in the left-arm base frame.
pub(super) fn both_arms(
    dataset: &Dataset,
    model: &DualArmModel,
    split: Split,
) -> Result<(ArmGeom, ArmGeom), MetricsError> {
    check_base(&model.left_base_from_right_base)?;
    let left = arm_geometry(
        dataset.arm(Side::Left),
        Side::Left,
        model.arm(Side::Left),
        &Isometry3::identity(),
        split,
    )?;
    let right = arm_geometry(
        dataset.arm(Side::Right),
        Side::Right,
        model.arm(Side::Right),
        &model.left_base_from_right_base,
        split,
    )?;
    Ok((left, right))
}

/// Worst `|Δd|`, RMS and max `Δo` of one configuration against a set of others.
pub(super) fn against(
    g: &ConfigGeom,
    others: &[ConfigGeom],
    skip: Option<usize>,
) -> (f64, f64, f64) {
    let (mut pos_max, mut ori_sum_sq, mut ori_max, mut n) = (0.0f64, 0.0, 0.0f64, 0usize);
    let (before, after) = match skip {
        Some(j) if j < others.len() => (&others[..j], &others[j + 1..]),
        _ => (others, &others[..0]),
    };
    for part in [before, after] {
        residuals_against(g, part, |dd, ori| {
            pos_max = dd.iter().fold(pos_max, |m, d| m.max(d.abs()));
            ori_sum_sq += ori * ori;
            ori_max = ori_max.max(ori);
            n += 1;
        });
    }
    (pos_max, (ori_sum_sq / n.max(1) as f64).sqrt(), ori_max)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The lanes give every pair's residual bit for bit as [`pair_residual`] does, in order: one to four
    /// reflectors, angles on both sides of the series' range and of π/2, lengths that leave a remainder.
    #[test]
    fn lanes_give_pair_residual_bit_for_bit() {
        use nalgebra::Rotation3;
        let mut state = 0x2545_f491_4f6c_dd1du64;
        let mut next = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
        };
        for n_refl in 1..=MAX_REFLECTORS {
            let mut config = |scale: f64| {
                let point = |s: f64, r: &mut dyn FnMut() -> f64| [s * r(), s * r(), s * r()];
                let axis = Vector3::new(next(), next(), next()) * scale;
                let rot: [[f64; 3]; 3] = Rotation3::from_scaled_axis(axis).into_inner().into();
                ConfigGeom {
                    measured_mm: PerReflector::from_fn(n_refl, |_| point(800.0, &mut next)),
                    model_mm: PerReflector::from_fn(n_refl, |_| point(800.0, &mut next)),
                    measured_from_model_rot: rot,
                    fit_rms_mm: 0.0,
                }
            };
            // Rotations from 1e-4 rad (the series) to ~3 rad (past π/2: atan2).
            let g: Vec<ConfigGeom> = (0..23)
                .map(|i| config([1e-4, 0.03, 0.3, 1.7][i % 4]))
                .collect();
            for i in 0..g.len() {
                for start in [0, i] {
                    let mut got = Vec::new();
                    residuals_against(&g[i], &g[start..], |dd, o| got.push((dd.to_vec(), o)));
                    let want: Vec<_> = g[start..]
                        .iter()
                        .map(|b| {
                            let (dd, o) = pair_residual(&g[i], b);
                            (dd.to_vec(), o)
                        })
                        .collect();
                    assert_eq!(got.len(), want.len());
                    for ((gd, go), (wd, wo)) in got.iter().zip(&want) {
                        assert_eq!(go.to_bits(), wo.to_bits(), "{n_refl} reflectors, Δo");
                        for (x, y) in gd.iter().zip(wd) {
                            assert_eq!(x.to_bits(), y.to_bits(), "{n_refl} reflectors, Δd");
                        }
                    }
                }
            }
        }
    }

    /// The series agrees with the library's `atan` to an ulp over its whole range, and the switch at
    /// 0.1 is seamless.
    #[test]
    fn atan_series_is_within_an_ulp() {
        let ulp = |x: f64| f64::from_bits(x.to_bits() + 1) - x;
        let mut worst = 0.0f64;
        for k in 0..200_000u64 {
            let t = ATAN_SERIES_MAX * (k as f64 / 200_000.0).powi(3);
            let (got, want) = (atan_small(t), t.atan());
            if t > 0.0 {
                worst = worst.max((got - want).abs() / ulp(want));
            } else {
                assert_eq!(got, 0.0);
            }
        }
        assert!(worst <= 1.0, "{worst} ulp");
        let edge = ATAN_SERIES_MAX * (1.0 - 1e-16);
        assert!((angle_rad(edge, 1.0) - angle_rad(ATAN_SERIES_MAX, 1.0)).abs() < 1e-16);
        // The angle of sin, cos as atan2 gives it, on both sides of 0.1 rad and of π/2.
        for a in [1e-9, 1e-4, 0.0999, 0.1001, 1.0, 2.0, 3.1] {
            let (sin, cos) = (f64::sin(a), f64::cos(a));
            assert!(
                (angle_rad(sin, cos) - sin.atan2(cos)).abs() <= 2.0 * ulp(a),
                "{a}"
            );
        }
    }
}
