//! Accuracy metrics of the paper (eqs. 5–8): relative positioning and orientation accuracy of each arm and
//! collaborative accuracy of the two arms, with the frequency figures of the paper's Tables 4 and 7.
//!
//! Definitions, over the configurations of one [`SplitSelect`] (model points `p_o` from forward kinematics
//! of the [`DualArmModel`], measured points `p_m` in the tracker frame):
//!
//! - **Relative positioning** (eq. 5), per arm, for every pair `i < j` and reflector `k`:
//!   `Δd = |p_m,i,k − p_m,j,k| − |p_o,i,k − p_o,j,k|`. `pos_rms_mm` is the largest of the three reflectors'
//!   RMS, `pos_max_mm` the largest `|Δd|`.
//! - **Relative orientation** (eq. 6): each configuration's measured flange rotation `R_m` is the Kabsch
//!   fit of the model's reflector coordinates (flange frame) to the three measured points; per pair
//!   `Δo = ‖log((R_m,iᵀ R_m,j)ᵀ (R_o,iᵀ R_o,j))‖`.
//! - **Collaborative** (eqs. 7, 8): every left configuration `l` with every right configuration `r`, the
//!   same reflector on both arms, the model's right-arm quantities mapped into the left-arm base by
//!   `B = left_base_from_right_base`: `Δd = |p_m,L,l,k − p_m,R,r,k| − |p_o,L,l,k − B·p_o,R,r,k|` and
//!   `Δo = ‖log((R_m,lᵀ R_m,r)ᵀ (R_o,lᵀ R_B R_o,r))‖`.
//! - **Frequencies**: the fraction of pairs whose worst-reflector `|Δd|` is within 0.3 mm and 0.6 mm, and
//!   of pairs whose `Δo` is within 0.005 rad and 0.01 rad.
//!
//! Forward kinematics and the Kabsch fit are computed once per configuration; the pair loops only combine
//! precomputed points and rotations (no allocation per pair) and run in parallel with rayon.

use crate::dataset::{ArmData, Dataset, Measurement, SplitSelect};
use crate::kinematics::{ArmModel, DualArmModel, REFLECTOR_NAMES, Side, rotation_angle_rad};
use nalgebra::{Isometry3, Matrix3, Rotation3, Translation3, UnitQuaternion, Vector3};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::fmt::Write as _;

/// The metrics need at least two configurations per arm (one pair).
pub const MIN_CONFIGS: usize = 2;
/// Positioning thresholds of the paper's Tables 4 and 7, mm.
pub const POS_THRESHOLDS_MM: [f64; 2] = [0.3, 0.6];
/// Orientation thresholds of the paper's Tables 4 and 7, rad.
pub const ORI_THRESHOLDS_RAD: [f64; 2] = [0.005, 0.01];

/// Accuracy figures over one set of pairs (one arm's relative pairs, or the collaborative pairs).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct AccuracyStats {
    /// Largest of the three reflectors' RMS of `Δd`, mm.
    pub pos_rms_mm: f64,
    /// RMS of `Δd` of reflectors a, b, c, mm.
    pub pos_rms_per_reflector_mm: [f64; 3],
    /// Largest `|Δd|` over all pairs and reflectors, mm.
    pub pos_max_mm: f64,
    /// RMS of `Δo`, rad.
    pub ori_rms_rad: f64,
    /// Largest `Δo`, rad.
    pub ori_max_rad: f64,
    /// Fraction (0..1) of pairs whose worst-reflector `|Δd|` ≤ 0.3 mm.
    pub pos_within_0_3mm_frac: f64,
    /// Fraction (0..1) of pairs whose worst-reflector `|Δd|` ≤ 0.6 mm.
    pub pos_within_0_6mm_frac: f64,
    /// Fraction (0..1) of pairs with `Δo` ≤ 0.005 rad.
    pub ori_within_0_005rad_frac: f64,
    /// Fraction (0..1) of pairs with `Δo` ≤ 0.01 rad.
    pub ori_within_0_01rad_frac: f64,
    /// Configurations involved (left + right for the collaborative figures).
    pub n_configs: usize,
    /// Pairs evaluated: `n(n−1)/2` per arm, `n_left · n_right` collaborative.
    pub n_pairs: usize,
}

/// The three sets of figures; serialises to
/// `{"relative_left": {...}, "relative_right": {...}, "collaborative": {...}}`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct AccuracyReport {
    pub relative_left: AccuracyStats,
    pub relative_right: AccuracyStats,
    pub collaborative: AccuracyStats,
}

impl AccuracyReport {
    /// The relative figures of one arm.
    pub fn relative(&self, side: Side) -> &AccuracyStats {
        match side {
            Side::Left => &self.relative_left,
            Side::Right => &self.relative_right,
        }
    }
}

/// Which pairs: one arm's configuration pairs `i < j`, or every left configuration with every right one.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum PairKind {
    Relative(Side),
    Collaborative,
}

/// The errors of one pair, for histograms and inspection.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct PairError {
    /// Index into `ArmData::measurements` of the first configuration (the left arm's, if collaborative).
    pub first: usize,
    /// Index into `ArmData::measurements` of the second configuration (the right arm's, if collaborative).
    pub second: usize,
    /// Signed `Δd` of reflectors a, b, c, mm.
    pub pos_error_mm: [f64; 3],
    /// The `Δd` of largest magnitude among the three reflectors (signed), mm.
    pub pos_worst_mm: f64,
    /// `Δo`, rad.
    pub ori_error_rad: f64,
}

impl PairError {
    /// The configuration ids of the pair.
    pub fn ids<'a>(&self, dataset: &'a Dataset, kind: PairKind) -> (&'a str, &'a str) {
        let (a, b) = match kind {
            PairKind::Relative(side) => (dataset.arm(side), dataset.arm(side)),
            PairKind::Collaborative => (&dataset.left, &dataset.right),
        };
        let id =
            |arm: &'a ArmData, i: usize| arm.measurements.get(i).map_or("?", |m| m.id.as_str());
        (id(a, self.first), id(b, self.second))
    }
}

/// Per-configuration summary, for finding the configurations that dominate the errors.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ConfigError {
    pub side: Side,
    /// Index into `ArmData::measurements`.
    pub index: usize,
    pub id: String,
    /// Largest `|Δd|` over the relative pairs involving this configuration, mm.
    pub relative_pos_max_mm: f64,
    /// RMS of `Δo` over the relative pairs involving this configuration, rad.
    pub relative_ori_rms_rad: f64,
    /// Largest `Δo` over the relative pairs involving this configuration, rad.
    pub relative_ori_max_rad: f64,
    /// Largest `|Δd|` over the collaborative pairs involving this configuration, mm.
    pub collaborative_pos_max_mm: f64,
    /// RMS of `Δo` over the collaborative pairs involving this configuration, rad.
    pub collaborative_ori_rms_rad: f64,
    /// Largest `Δo` over the collaborative pairs involving this configuration, rad.
    pub collaborative_ori_max_rad: f64,
    /// Measured minus model reflector-triangle sides `|ab|`, `|bc|`, `|ca|`, mm.
    pub triangle_side_errors_mm: [f64; 3],
    /// Largest `|triangle_side_errors_mm|` (rigidity of the measured reflector triangle), mm.
    pub rigidity_mm: f64,
    /// RMS residual of the Kabsch fit of the model reflectors to the measured points, mm.
    pub fit_rms_mm: f64,
}

/// Why the metrics cannot be computed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum MetricsError {
    #[error(
        "{side} arm: {found} configuration(s) in split `{}`, the accuracy metrics need at least {min}",
        split_name(*.split)
    )]
    TooFewConfigurations {
        side: Side,
        split: SplitSelect,
        found: usize,
        min: usize,
    },
    #[error("{side} arm, configuration `{id}` (line {line}): {field} is not finite")]
    NonFiniteMeasurement {
        side: Side,
        id: String,
        line: usize,
        field: String,
    },
    #[error("model: {field} is not finite")]
    NonFiniteModel { field: String },
    #[error(
        "model: the {side} arm's reflectors t_a, t_b, t_c are (nearly) collinear, no flange rotation can be fitted"
    )]
    DegenerateReflectors { side: Side },
    #[error("{side} arm, configuration `{id}`: the Kabsch fit did not converge")]
    FitFailed { side: Side, id: String },
    #[error("{what} is not finite (the model or the data overflow)")]
    NonFiniteResult { what: String },
}

fn split_name(split: SplitSelect) -> &'static str {
    match split {
        SplitSelect::Cal => "cal",
        SplitSelect::Ver => "ver",
        SplitSelect::All => "all",
    }
}

// ------------------------------------------------------------------------------------------------------
// Kabsch fit

/// A rigid fit `measured ≈ rotation · model + translation`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct KabschFit {
    pub rotation: Rotation3<f64>,
    pub translation_mm: Vector3<f64>,
    /// RMS of the residuals `|measured − (R·model + t)|` over the points, mm.
    pub rms_mm: f64,
    /// Singular values of the centred cross-covariance, in decreasing order; two (near) zeros mean the
    /// points are collinear and the rotation about their line is undetermined.
    pub singular_values: Vector3<f64>,
}

impl KabschFit {
    /// The fit as a transform `measured_from_model`.
    pub fn isometry(&self) -> Isometry3<f64> {
        Isometry3::from_parts(
            Translation3::from(self.translation_mm),
            UnitQuaternion::from_rotation_matrix(&self.rotation),
        )
    }

    /// Are the points (nearly) collinear, so that the rotation is not determined?
    pub fn is_degenerate(&self) -> bool {
        let largest = self.singular_values.max();
        largest <= 0.0
            || self
                .singular_values
                .iter()
                .filter(|&&x| x <= largest * 1e-12)
                .count()
                >= 2
    }
}

/// Least-squares proper rotation and translation taking `model_pts` onto `measured_pts` (Kabsch, via SVD,
/// `det R = +1`). `None` only if the SVD does not converge (non-finite input).
pub fn kabsch_fit(
    model_pts: &[Vector3<f64>; 3],
    measured_pts: &[Vector3<f64>; 3],
) -> Option<KabschFit> {
    kabsch_fit_points(model_pts, measured_pts)
}

/// [`kabsch_fit`] over any number of point pairs. `None` for no or unequal numbers of points, or
/// non-finite input.
pub fn kabsch_fit_points(
    model_pts: &[Vector3<f64>],
    measured_pts: &[Vector3<f64>],
) -> Option<KabschFit> {
    if model_pts.is_empty() || model_pts.len() != measured_pts.len() {
        return None;
    }
    let n = model_pts.len() as f64;
    let cm = model_pts.iter().sum::<Vector3<f64>>() / n;
    let cq = measured_pts.iter().sum::<Vector3<f64>>() / n;
    let mut h = Matrix3::zeros();
    for (p, q) in model_pts.iter().zip(measured_pts) {
        h += (p - cm) * (q - cq).transpose();
    }
    if !h.iter().all(|x| x.is_finite()) {
        return None;
    }
    let svd = h.try_svd(true, true, f64::EPSILON, 1000)?;
    let (u, v_t) = (svd.u?, svd.v_t?);
    let v = v_t.transpose();
    // Flip the direction of least variance (singular values are sorted, largest first) if the plain
    // solution is a reflection.
    let mut d = Matrix3::identity();
    if (v * u.transpose()).determinant() < 0.0 {
        d[(2, 2)] = -1.0;
    }
    let rotation = Rotation3::from_matrix_unchecked(v * d * u.transpose());
    let translation_mm = cq - rotation * cm;
    let sum_sq: f64 = model_pts
        .iter()
        .zip(measured_pts)
        .map(|(p, q)| (q - (rotation * p + translation_mm)).norm_squared())
        .sum();
    Some(KabschFit {
        rotation,
        translation_mm,
        rms_mm: (sum_sq / n).sqrt(),
        singular_values: svd.singular_values,
    })
}

/// The rotation of [`kabsch_fit`]; the identity if the fit fails (non-finite input).
pub fn kabsch_rotation(
    model_pts: &[Vector3<f64>; 3],
    measured_pts: &[Vector3<f64>; 3],
) -> Rotation3<f64> {
    kabsch_fit(model_pts, measured_pts).map_or_else(Rotation3::identity, |f| f.rotation)
}

// ------------------------------------------------------------------------------------------------------
// Per-configuration geometry, computed once

/// Everything the pair loops need about one configuration, as plain arrays: the pair loops run tens of
/// thousands of times per evaluation and plain arithmetic stays fast in unoptimised (test) builds too.
#[derive(Clone, Copy, Debug)]
struct ConfigGeom {
    /// Measured reflector points, tracker frame, mm.
    measured_mm: [[f64; 3]; 3],
    /// Model reflector points in the reference base frame, mm.
    model_mm: [[f64; 3]; 3],
    /// `M = R_m · R_oᵀ` (row-major): the measured flange rotation (Kabsch fit, tracker frame) times the
    /// inverse of the model's (reference base frame). See [`pair_error`].
    measured_from_model_rot: [[f64; 3]; 3],
    fit_rms_mm: f64,
}

/// One arm's selected configurations: indices into `ArmData::measurements` and their geometry.
struct ArmGeom {
    side: Side,
    indices: Vec<usize>,
    geom: Vec<ConfigGeom>,
}

fn check_model_arm(side: Side, arm: &ArmModel) -> Result<(), MetricsError> {
    for (i, row) in arm.dh.iter().enumerate() {
        for (name, v) in [
            ("a", row.a_mm),
            ("d", row.d_mm),
            ("theta", row.theta_rad),
            ("alpha", row.alpha_rad),
        ] {
            if !v.is_finite() {
                return Err(MetricsError::NonFiniteModel {
                    field: format!("{side} arm DH {name}{}", i + 1),
                });
            }
        }
    }
    for (k, t) in arm.reflectors_mm.iter().enumerate() {
        if !t.iter().all(|x| x.is_finite()) {
            return Err(MetricsError::NonFiniteModel {
                field: format!("{side} arm reflector t_{}", REFLECTOR_NAMES[k]),
            });
        }
    }
    let t = &arm.reflectors_mm;
    let (ab, ac) = (t[1] - t[0], t[2] - t[0]);
    let longest = ab.norm().max(ac.norm()).max((t[2] - t[1]).norm());
    if ab.cross(&ac).norm() <= 1e-9 * longest * longest {
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

fn check_measurement(side: Side, m: &Measurement) -> Result<(), MetricsError> {
    let bad = |field: String| MetricsError::NonFiniteMeasurement {
        side,
        id: m.id.clone(),
        line: m.line,
        field,
    };
    if let Some(j) = m.q_rad.iter().position(|q| !q.is_finite()) {
        return Err(bad(format!("q{}", j + 1)));
    }
    for (k, p) in m.tracker_points_mm.iter().enumerate() {
        if let Some(c) = p.iter().position(|x| !x.is_finite()) {
            return Err(bad(format!("{}{}", REFLECTOR_NAMES[k], ["x", "y", "z"][c])));
        }
    }
    Ok(())
}

/// Geometry of one arm's selected configurations, model quantities expressed in the frame
/// `reference_from_base` maps to (the left-arm base for collaborative use; any frame for relative use,
/// which is invariant under a common rigid motion).
fn arm_geometry(
    data: &ArmData,
    side: Side,
    arm: &ArmModel,
    reference_from_base: &Isometry3<f64>,
    split: SplitSelect,
) -> Result<ArmGeom, MetricsError> {
    check_model_arm(side, arm)?;
    let selected: Vec<(usize, &Measurement)> = data
        .measurements
        .iter()
        .enumerate()
        .filter(|(_, m)| split.accepts(m.split))
        .collect();
    if selected.len() < MIN_CONFIGS {
        return Err(MetricsError::TooFewConfigurations {
            side,
            split,
            found: selected.len(),
            min: MIN_CONFIGS,
        });
    }
    for (_, m) in &selected {
        check_measurement(side, m)?;
    }
    let reference_rot = reference_from_base.rotation.to_rotation_matrix();
    let geom = selected
        .par_iter()
        .map(|(_, m)| {
            let fk = arm.reflector_fk(&m.q_rad);
            let model_mm = fk
                .points_mm
                .map(|p| reference_from_base.transform_point(&p.into()).coords);
            let model_rot = reference_rot * fk.base_from_flange.rotation.to_rotation_matrix();
            let fit = kabsch_fit(&arm.reflectors_mm, &m.tracker_points_mm).ok_or_else(|| {
                MetricsError::FitFailed {
                    side,
                    id: m.id.clone(),
                }
            })?;
            let g = ConfigGeom {
                measured_mm: m.tracker_points_mm.map(|p| p.into()),
                model_mm: model_mm.map(|p| p.into()),
                measured_from_model_rot: (fit.rotation * model_rot.transpose())
                    .into_inner()
                    .transpose()
                    .into(),
                fit_rms_mm: fit.rms_mm,
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
    })
}

/// `Δd` per reflector and `Δo` of one pair `(i, j)` = `(a, b)`.
///
/// `Δo = ‖log(E)‖` with `E = (R_m,iᵀ R_m,j)ᵀ (R_o,iᵀ R_o,j) = R_m,jᵀ M_i R_o,j`, `M = R_m R_oᵀ`. The angle
/// of a rotation is invariant under conjugation, and `R_o,j E R_o,jᵀ = M_jᵀ M_i`, so `Δo` is the angle of
/// `M_jᵀ M_i`: one matrix product per pair.
#[inline]
fn pair_error(a: &ConfigGeom, b: &ConfigGeom) -> ([f64; 3], f64) {
    let dd = std::array::from_fn(|k| {
        distance(&a.measured_mm[k], &b.measured_mm[k]) - distance(&a.model_mm[k], &b.model_mm[k])
    });
    let (mb, ma) = (&b.measured_from_model_rot, &a.measured_from_model_rot);
    // E = M_bᵀ M_a, row-major: E[r][c] = Σ_k M_b[k][r] · M_a[k][c].
    let e = |r: usize, c: usize| mb[0][r] * ma[0][c] + mb[1][r] * ma[1][c] + mb[2][r] * ma[2][c];
    #[rustfmt::skip]
    let e = Matrix3::new(
        e(0, 0), e(0, 1), e(0, 2),
        e(1, 0), e(1, 1), e(1, 2),
        e(2, 0), e(2, 1), e(2, 2),
    );
    (dd, rotation_angle_rad(&Rotation3::from_matrix_unchecked(e)))
}

#[inline]
fn distance(p: &[f64; 3], q: &[f64; 3]) -> f64 {
    let (x, y, z) = (p[0] - q[0], p[1] - q[1], p[2] - q[2]);
    (x * x + y * y + z * z).sqrt()
}

fn worst(dd: &[f64; 3]) -> f64 {
    dd.iter()
        .copied()
        .fold(0.0, |w, d| if d.abs() > w.abs() { d } else { w })
}

/// Running sums for [`AccuracyStats`]; mergeable for parallel reduction.
#[derive(Clone, Copy, Debug, Default)]
struct Accumulator {
    n: usize,
    pos_sum_sq: [f64; 3],
    pos_max: f64,
    pos_within: [usize; 2],
    ori_sum_sq: f64,
    ori_max: f64,
    ori_within: [usize; 2],
}

impl Accumulator {
    #[inline]
    fn add(&mut self, dd: &[f64; 3], ori: f64) {
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

    fn merge(mut self, o: Self) -> Self {
        self.n += o.n;
        for k in 0..3 {
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

    fn finish(self, n_configs: usize, what: &str) -> Result<AccuracyStats, MetricsError> {
        let n = self.n.max(1) as f64;
        let per = self.pos_sum_sq.map(|s| (s / n).sqrt());
        let frac = |c: usize| c as f64 / n;
        let stats = AccuracyStats {
            pos_rms_mm: per.iter().copied().fold(0.0, f64::max),
            pos_rms_per_reflector_mm: per,
            pos_max_mm: self.pos_max,
            ori_rms_rad: (self.ori_sum_sq / n).sqrt(),
            ori_max_rad: self.ori_max,
            pos_within_0_3mm_frac: frac(self.pos_within[0]),
            pos_within_0_6mm_frac: frac(self.pos_within[1]),
            ori_within_0_005rad_frac: frac(self.ori_within[0]),
            ori_within_0_01rad_frac: frac(self.ori_within[1]),
            n_configs,
            n_pairs: self.n,
        };
        // `f64::max` ignores NaN, so a NaN pair shows up only in the sums.
        let finite = per.iter().all(|x| x.is_finite())
            && stats.pos_max_mm.is_finite()
            && stats.ori_rms_rad.is_finite();
        if finite {
            Ok(stats)
        } else {
            Err(MetricsError::NonFiniteResult {
                what: format!("the {what} accuracy"),
            })
        }
    }
}

fn relative_accumulate(g: &[ConfigGeom]) -> Accumulator {
    (0..g.len())
        .into_par_iter()
        .fold(Accumulator::default, |mut acc, i| {
            for b in &g[i + 1..] {
                let (dd, o) = pair_error(&g[i], b);
                acc.add(&dd, o);
            }
            acc
        })
        .reduce(Accumulator::default, Accumulator::merge)
}

fn collaborative_accumulate(left: &[ConfigGeom], right: &[ConfigGeom]) -> Accumulator {
    left.par_iter()
        .fold(Accumulator::default, |mut acc, l| {
            for r in right {
                let (dd, o) = pair_error(l, r);
                acc.add(&dd, o);
            }
            acc
        })
        .reduce(Accumulator::default, Accumulator::merge)
}

/// Both arms' geometry with the model expressed in the left-arm base frame.
fn both_arms(
    dataset: &Dataset,
    model: &DualArmModel,
    split: SplitSelect,
) -> Result<(ArmGeom, ArmGeom), MetricsError> {
    check_base(&model.left_base_from_right_base)?;
    let left = arm_geometry(
        &dataset.left,
        Side::Left,
        &model.left,
        &Isometry3::identity(),
        split,
    )?;
    let right = arm_geometry(
        &dataset.right,
        Side::Right,
        &model.right,
        &model.left_base_from_right_base,
        split,
    )?;
    Ok((left, right))
}

// ------------------------------------------------------------------------------------------------------
// Public entry points

/// All accuracy figures of `model` on the configurations of `split`.
pub fn evaluate(
    dataset: &Dataset,
    model: &DualArmModel,
    split: SplitSelect,
) -> Result<AccuracyReport, MetricsError> {
    let (left, right) = both_arms(dataset, model, split)?;
    // The right arm's model is expressed in the left base; relative figures do not depend on the frame.
    Ok(AccuracyReport {
        relative_left: relative_accumulate(&left.geom).finish(left.geom.len(), "left relative")?,
        relative_right: relative_accumulate(&right.geom)
            .finish(right.geom.len(), "right relative")?,
        collaborative: collaborative_accumulate(&left.geom, &right.geom)
            .finish(left.geom.len() + right.geom.len(), "collaborative")?,
    })
}

/// Relative accuracy of one arm alone (needs no base transform; for single-arm calibration).
pub fn relative_stats(
    dataset: &Dataset,
    arm: &ArmModel,
    side: Side,
    split: SplitSelect,
) -> Result<AccuracyStats, MetricsError> {
    let g = arm_geometry(dataset.arm(side), side, arm, &Isometry3::identity(), split)?;
    relative_accumulate(&g.geom).finish(g.geom.len(), &format!("{side} relative"))
}

/// Collaborative accuracy alone.
pub fn collaborative_stats(
    dataset: &Dataset,
    model: &DualArmModel,
    split: SplitSelect,
) -> Result<AccuracyStats, MetricsError> {
    let (left, right) = both_arms(dataset, model, split)?;
    collaborative_accumulate(&left.geom, &right.geom)
        .finish(left.geom.len() + right.geom.len(), "collaborative")
}

fn make_pair(a: &ArmGeom, i: usize, b: &ArmGeom, j: usize) -> PairError {
    let (pos_error_mm, ori_error_rad) = pair_error(&a.geom[i], &b.geom[j]);
    PairError {
        first: a.indices[i],
        second: b.indices[j],
        pos_error_mm,
        pos_worst_mm: worst(&pos_error_mm),
        ori_error_rad,
    }
}

/// Every pair of `kind`, in order (`i < j` row by row; collaborative: left-major).
pub fn pairs(
    dataset: &Dataset,
    model: &DualArmModel,
    split: SplitSelect,
    kind: PairKind,
) -> Result<Vec<PairError>, MetricsError> {
    match kind {
        PairKind::Relative(side) => {
            let g = arm_geometry(
                dataset.arm(side),
                side,
                model.arm(side),
                &Isometry3::identity(),
                split,
            )?;
            let n = g.geom.len();
            let g = &g;
            Ok((0..n)
                .into_par_iter()
                .flat_map_iter(|i| (i + 1..n).map(move |j| make_pair(g, i, g, j)))
                .collect())
        }
        PairKind::Collaborative => {
            let (left, right) = both_arms(dataset, model, split)?;
            let nr = right.geom.len();
            let (l, r) = (&left, &right);
            Ok((0..left.geom.len())
                .into_par_iter()
                .flat_map_iter(|i| (0..nr).map(move |j| make_pair(l, i, r, j)))
                .collect())
        }
    }
}

/// Every relative pair `i < j` of one arm.
pub fn relative_pairs(
    dataset: &Dataset,
    model: &DualArmModel,
    side: Side,
    split: SplitSelect,
) -> Result<Vec<PairError>, MetricsError> {
    pairs(dataset, model, split, PairKind::Relative(side))
}

/// Every (left, right) pair.
pub fn collaborative_pairs(
    dataset: &Dataset,
    model: &DualArmModel,
    split: SplitSelect,
) -> Result<Vec<PairError>, MetricsError> {
    pairs(dataset, model, split, PairKind::Collaborative)
}

/// Worst `|Δd|`, RMS and max `Δo` of one configuration against a set of others.
fn against(g: &ConfigGeom, others: &[ConfigGeom], skip: Option<usize>) -> (f64, f64, f64) {
    let (mut pos_max, mut ori_sum_sq, mut ori_max, mut n) = (0.0f64, 0.0, 0.0f64, 0usize);
    for (j, o) in others.iter().enumerate() {
        if Some(j) == skip {
            continue;
        }
        let (dd, ori) = pair_error(g, o);
        pos_max = dd.iter().fold(pos_max, |m, d| m.max(d.abs()));
        ori_sum_sq += ori * ori;
        ori_max = ori_max.max(ori);
        n += 1;
    }
    (pos_max, (ori_sum_sq / n.max(1) as f64).sqrt(), ori_max)
}

fn triangle_sides(p: &[Vector3<f64>; 3]) -> [f64; 3] {
    [
        (p[0] - p[1]).norm(),
        (p[1] - p[2]).norm(),
        (p[2] - p[0]).norm(),
    ]
}

/// Per-configuration summary of both arms (left first, each in measurement order).
pub fn per_config(
    dataset: &Dataset,
    model: &DualArmModel,
    split: SplitSelect,
) -> Result<Vec<ConfigError>, MetricsError> {
    let (left, right) = both_arms(dataset, model, split)?;
    let mut out = Vec::with_capacity(left.geom.len() + right.geom.len());
    for (own, other) in [(&left, &right), (&right, &left)] {
        let data = dataset.arm(own.side);
        let model_sides = triangle_sides(&model.arm(own.side).reflectors_mm);
        let rows: Vec<ConfigError> = (0..own.geom.len())
            .into_par_iter()
            .map(|i| {
                let g = &own.geom[i];
                let (rel_pos, rel_ori_rms, rel_ori_max) = against(g, &own.geom, Some(i));
                let (col_pos, col_ori_rms, col_ori_max) = against(g, &other.geom, None);
                let measured_sides = triangle_sides(&g.measured_mm.map(Vector3::from));
                let side_errors: [f64; 3] =
                    std::array::from_fn(|k| measured_sides[k] - model_sides[k]);
                let index = own.indices[i];
                ConfigError {
                    side: own.side,
                    index,
                    id: data.measurements[index].id.clone(),
                    relative_pos_max_mm: rel_pos,
                    relative_ori_rms_rad: rel_ori_rms,
                    relative_ori_max_rad: rel_ori_max,
                    collaborative_pos_max_mm: col_pos,
                    collaborative_ori_rms_rad: col_ori_rms,
                    collaborative_ori_max_rad: col_ori_max,
                    triangle_side_errors_mm: side_errors,
                    rigidity_mm: side_errors.iter().fold(0.0, |m, e| m.max(e.abs())),
                    fit_rms_mm: g.fit_rms_mm,
                }
            })
            .collect();
        out.extend(rows);
    }
    Ok(out)
}

// ------------------------------------------------------------------------------------------------------
// Tables

const COLUMN_TITLES: [&str; 3] = ["relative left", "relative right", "collaborative"];

/// How a row's value is read off the stats and printed.
struct Row {
    label: &'static str,
    value: fn(&AccuracyStats) -> f64,
    kind: RowKind,
}

#[derive(Clone, Copy, PartialEq)]
enum RowKind {
    /// mm, printed with 3 decimals; lower is better.
    Mm,
    /// rad, printed in mrad with 3 decimals; lower is better.
    Mrad,
    /// fraction, printed in percent; higher is better.
    Percent,
    /// a count.
    Count,
}

const ROWS: [Row; 13] = [
    Row {
        label: "configurations",
        value: |s| s.n_configs as f64,
        kind: RowKind::Count,
    },
    Row {
        label: "pairs",
        value: |s| s.n_pairs as f64,
        kind: RowKind::Count,
    },
    Row {
        label: "positioning RMS (mm)",
        value: |s| s.pos_rms_mm,
        kind: RowKind::Mm,
    },
    Row {
        label: "  reflector a RMS (mm)",
        value: |s| s.pos_rms_per_reflector_mm[0],
        kind: RowKind::Mm,
    },
    Row {
        label: "  reflector b RMS (mm)",
        value: |s| s.pos_rms_per_reflector_mm[1],
        kind: RowKind::Mm,
    },
    Row {
        label: "  reflector c RMS (mm)",
        value: |s| s.pos_rms_per_reflector_mm[2],
        kind: RowKind::Mm,
    },
    Row {
        label: "positioning max (mm)",
        value: |s| s.pos_max_mm,
        kind: RowKind::Mm,
    },
    Row {
        label: "|Δd| ≤ 0.3 mm",
        value: |s| s.pos_within_0_3mm_frac,
        kind: RowKind::Percent,
    },
    Row {
        label: "|Δd| ≤ 0.6 mm",
        value: |s| s.pos_within_0_6mm_frac,
        kind: RowKind::Percent,
    },
    Row {
        label: "orientation RMS (mrad)",
        value: |s| s.ori_rms_rad,
        kind: RowKind::Mrad,
    },
    Row {
        label: "orientation max (mrad)",
        value: |s| s.ori_max_rad,
        kind: RowKind::Mrad,
    },
    Row {
        label: "Δo ≤ 0.005 rad",
        value: |s| s.ori_within_0_005rad_frac,
        kind: RowKind::Percent,
    },
    Row {
        label: "Δo ≤ 0.01 rad",
        value: |s| s.ori_within_0_01rad_frac,
        kind: RowKind::Percent,
    },
];

fn format_value(kind: RowKind, v: f64) -> String {
    match kind {
        RowKind::Mm => format!("{v:.3}"),
        RowKind::Mrad => format!("{:.3}", v * 1e3),
        RowKind::Percent => format!("{:.2} %", v * 100.0),
        RowKind::Count => format!("{v:.0}"),
    }
}

fn stats_of(report: &AccuracyReport) -> [&AccuracyStats; 3] {
    [
        &report.relative_left,
        &report.relative_right,
        &report.collaborative,
    ]
}

const LABEL_WIDTH: usize = 24;

/// A table of one report: one column per set of pairs.
pub fn format_table(report: &AccuracyReport) -> String {
    let stats = stats_of(report);
    let mut out = String::new();
    let _ = write!(out, "{:<LABEL_WIDTH$}", "");
    for t in COLUMN_TITLES {
        let _ = write!(out, "{t:>16}");
    }
    out.push('\n');
    for row in &ROWS {
        let _ = write!(out, "{:<LABEL_WIDTH$}", row.label);
        for s in stats {
            let _ = write!(out, "{:>16}", format_value(row.kind, (row.value)(s)));
        }
        out.push('\n');
    }
    out
}

/// The change from `before` to `after`: relative reduction of an error, or percentage points of a
/// frequency.
fn format_change(kind: RowKind, before: f64, after: f64) -> String {
    match kind {
        RowKind::Count => String::new(),
        RowKind::Percent => format!("{:+.2} pp", (after - before) * 100.0),
        RowKind::Mm | RowKind::Mrad => {
            if before > 0.0 {
                format!("{:+.2} %", (after - before) / before * 100.0)
            } else {
                "–".into()
            }
        }
    }
}

/// Two reports side by side (typically nominal vs calibrated), one block per set of pairs, with the
/// change: relative change of errors (negative is better) and percentage points of frequencies.
pub fn format_comparison(
    before: &AccuracyReport,
    after: &AccuracyReport,
    labels: [&str; 2],
) -> String {
    let mut out = String::new();
    for ((title, b), a) in COLUMN_TITLES
        .iter()
        .zip(stats_of(before))
        .zip(stats_of(after))
    {
        if !out.is_empty() {
            out.push('\n');
        }
        let _ = writeln!(
            out,
            "{:<LABEL_WIDTH$}{:>14}{:>14}{:>14}",
            title, labels[0], labels[1], "change"
        );
        for row in &ROWS {
            let (vb, va) = ((row.value)(b), (row.value)(a));
            let _ = writeln!(
                out,
                "{:<LABEL_WIDTH$}{:>14}{:>14}{:>14}",
                row.label,
                format_value(row.kind, vb),
                format_value(row.kind, va),
                format_change(row.kind, vb, va)
            );
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dataset::{Split, TrackerSpec};
    use crate::kinematics::{DhRow, N_JOINTS, N_PARAMS, joint_limits_rad, param_is_angle};
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;
    use std::path::PathBuf;

    fn nominal_reflectors() -> [Vector3<f64>; 3] {
        [
            Vector3::new(45.0, 0.0, 40.0),
            Vector3::new(-25.0, 40.0, 40.0),
            Vector3::new(-25.0, -40.0, 40.0),
        ]
    }

    fn random_unit(rng: &mut ChaCha8Rng) -> Vector3<f64> {
        loop {
            let v = Vector3::new(
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
            );
            if v.norm() > 0.1 && v.norm() < 1.0 {
                return v.normalize();
            }
        }
    }

    fn random_isometry(rng: &mut ChaCha8Rng, scale_mm: f64) -> Isometry3<f64> {
        let axis = random_unit(rng);
        let angle = rng.random_range(-3.0..3.0);
        let t = random_unit(rng) * scale_mm;
        Isometry3::from_parts(
            Translation3::from(t),
            UnitQuaternion::from_scaled_axis(axis * angle),
        )
    }

    fn perturbed_arm(rng: &mut ChaCha8Rng, size: f64) -> ArmModel {
        let mut v = ArmModel::nominal_irb14000(nominal_reflectors()).to_vector();
        for k in 0..N_PARAMS {
            v[k] += size
                * if param_is_angle(k) {
                    rng.random_range(-0.003..0.003)
                } else {
                    rng.random_range(-0.5..0.5)
                };
        }
        ArmModel::from_vector(&v)
    }

    fn random_q(rng: &mut ChaCha8Rng) -> [f64; N_JOINTS] {
        let lim = joint_limits_rad();
        std::array::from_fn(|i| rng.random_range(lim[i].0..lim[i].1))
    }

    /// A dataset measured on `truth` by a tracker at `tracker_from_left_base`, with Gaussian-free uniform
    /// noise of ±`noise_mm` per axis; every third configuration is `ver`.
    fn simulate(
        truth: &DualArmModel,
        tracker_from_left_base: &Isometry3<f64>,
        n: [usize; 2],
        noise_mm: f64,
        seed: u64,
    ) -> Dataset {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let mut arm = |side: Side, count: usize| {
            let tracker_from_base = tracker_from_left_base * truth.left_base_from(side);
            let measurements = (0..count)
                .map(|i| {
                    let q_rad = random_q(&mut rng);
                    let fk = truth.arm(side).reflector_fk(&q_rad);
                    let tracker_points_mm = fk.points_mm.map(|p| {
                        let noise = Vector3::from_fn(|_, _| rng.random_range(-1.0..=1.0));
                        tracker_from_base.transform_point(&p.into()).coords + noise * noise_mm
                    });
                    Measurement {
                        id: format!("{}{i:03}", side.name()),
                        q_rad,
                        tracker_points_mm,
                        split: if i % 3 == 2 { Split::Ver } else { Split::Cal },
                        line: i + 2,
                    }
                })
                .collect();
            ArmData {
                side,
                file: PathBuf::from(format!("{}.csv", side.name())),
                measurements,
            }
        };
        let left = arm(Side::Left, n[0]);
        let right = arm(Side::Right, n[1]);
        Dataset {
            dir: PathBuf::from("mem"),
            robot: None,
            tracker: TrackerSpec::default(),
            nominal_reflectors_mm: nominal_reflectors(),
            left,
            right,
        }
    }

    fn nominal_base() -> Isometry3<f64> {
        #[rustfmt::skip]
        let r = Matrix3::new(
            0.2352, -0.8755, 0.4220,
            0.8746, 0.0012, -0.4849,
            0.4241, 0.4831, 0.7660,
        );
        Isometry3::from_parts(
            Translation3::new(61.61, -70.77, -34.14),
            UnitQuaternion::from_matrix(&r),
        )
    }

    fn true_model(rng: &mut ChaCha8Rng) -> DualArmModel {
        DualArmModel {
            left: perturbed_arm(rng, 1.0),
            right: perturbed_arm(rng, 1.0),
            left_base_from_right_base: nominal_base(),
        }
    }

    fn all_stats(r: &AccuracyReport) -> [AccuracyStats; 3] {
        [r.relative_left, r.relative_right, r.collaborative]
    }

    fn assert_reports_close(a: &AccuracyReport, b: &AccuracyReport, tol: f64) {
        for (x, y) in all_stats(a).iter().zip(all_stats(b).iter()) {
            let vx = serde_json::to_value(x).unwrap();
            let vy = serde_json::to_value(y).unwrap();
            let (ox, oy) = (vx.as_object().unwrap(), vy.as_object().unwrap());
            for (k, v) in ox {
                let flat = |v: &serde_json::Value| -> Vec<f64> {
                    match v {
                        serde_json::Value::Array(a) => {
                            a.iter().map(|e| e.as_f64().unwrap()).collect()
                        }
                        e => vec![e.as_f64().unwrap()],
                    }
                };
                for (p, q) in flat(v).iter().zip(flat(&oy[k])) {
                    assert!((p - q).abs() <= tol, "{k}: {p} vs {q}");
                }
            }
        }
    }

    #[test]
    fn perfect_model_on_noise_free_data_gives_zero() {
        let mut rng = ChaCha8Rng::seed_from_u64(1);
        let truth = true_model(&mut rng);
        let ds = simulate(&truth, &random_isometry(&mut rng, 2000.0), [15, 12], 0.0, 2);
        let r = evaluate(&ds, &truth, SplitSelect::All).unwrap();
        for s in all_stats(&r) {
            assert!(s.pos_max_mm < 1e-9, "{s:?}");
            assert!(s.ori_max_rad < 1e-7, "{s:?}");
            assert_eq!(s.pos_within_0_3mm_frac, 1.0);
            assert_eq!(s.ori_within_0_005rad_frac, 1.0);
        }
        assert_eq!(r.relative_left.n_pairs, 15 * 14 / 2);
        assert_eq!(r.relative_right.n_pairs, 12 * 11 / 2);
        assert_eq!(r.collaborative.n_pairs, 15 * 12);
        assert_eq!(r.collaborative.n_configs, 27);
        // The nominal model on the same data is clearly wrong (mm-level), so the check above can fail.
        let nominal = DualArmModel {
            left: ArmModel::nominal_irb14000(nominal_reflectors()),
            right: ArmModel::nominal_irb14000(nominal_reflectors()),
            left_base_from_right_base: nominal_base(),
        };
        let rn = evaluate(&ds, &nominal, SplitSelect::All).unwrap();
        for s in all_stats(&rn) {
            assert!(s.pos_rms_mm > 0.2, "{s:?}");
            assert!(s.ori_rms_rad > 1e-4, "{s:?}");
        }
    }

    #[test]
    fn split_selects_configurations() {
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let truth = true_model(&mut rng);
        let ds = simulate(&truth, &Isometry3::identity(), [9, 7], 0.01, 4);
        let cal = evaluate(&ds, &truth, SplitSelect::Cal).unwrap();
        let ver = evaluate(&ds, &truth, SplitSelect::Ver).unwrap();
        assert_eq!(cal.relative_left.n_configs, 6);
        assert_eq!(ver.relative_left.n_configs, 3);
        assert_eq!(cal.relative_right.n_configs, 5);
        assert_eq!(ver.relative_right.n_configs, 2);
        assert_eq!(ver.collaborative.n_pairs, 6);
        let p = relative_pairs(&ds, &truth, Side::Left, SplitSelect::Ver).unwrap();
        let ids: Vec<_> = p
            .iter()
            .map(|e| e.ids(&ds, PairKind::Relative(Side::Left)))
            .collect();
        assert_eq!(
            ids,
            vec![
                ("left002", "left005"),
                ("left002", "left008"),
                ("left005", "left008")
            ]
        );
    }

    #[test]
    fn base_translation_error_gives_the_expected_collaborative_error() {
        // Hand-built: all DH parameters zero and q = 0, so the flange is the base; the tracker frame is
        // the left base and the right base sits 300 mm along x. Every measured left-right distance is
        // 300 mm for every reflector.
        let zero_arm = ArmModel {
            dh: [DhRow::new(0.0, 0.0, 0.0, 0.0); N_JOINTS],
            reflectors_mm: nominal_reflectors(),
        };
        let truth = DualArmModel {
            left: zero_arm.clone(),
            right: zero_arm.clone(),
            left_base_from_right_base: Isometry3::translation(300.0, 0.0, 0.0),
        };
        let mut ds = simulate(&truth, &Isometry3::identity(), [3, 4], 0.0, 5);
        for (arm, offset) in [(&mut ds.left, 0.0), (&mut ds.right, 300.0)] {
            for m in &mut arm.measurements {
                m.q_rad = [0.0; N_JOINTS];
                m.tracker_points_mm = nominal_reflectors().map(|t| t + Vector3::x() * offset);
            }
        }
        let mut wrong = truth.clone();
        // 4 mm sideways: model distance sqrt(300² + 4²), so Δd = 300 − sqrt(90016) for every pair.
        wrong.left_base_from_right_base = Isometry3::translation(300.0, 4.0, 0.0);
        let expected = 300.0 - 90016.0f64.sqrt();
        let pairs = collaborative_pairs(&ds, &wrong, SplitSelect::All).unwrap();
        assert_eq!(pairs.len(), 12);
        for p in &pairs {
            for d in p.pos_error_mm {
                assert!((d - expected).abs() < 1e-12, "{d} vs {expected}");
            }
            assert!((p.pos_worst_mm - expected).abs() < 1e-12);
            assert!(p.ori_error_rad < 1e-12);
        }
        // 2 mm further along x: Δd = 300 − 302 = −2 mm.
        wrong.left_base_from_right_base = Isometry3::translation(302.0, 0.0, 0.0);
        let r = evaluate(&ds, &wrong, SplitSelect::All).unwrap();
        assert!((r.collaborative.pos_rms_mm - 2.0).abs() < 1e-12);
        assert!((r.collaborative.pos_max_mm - 2.0).abs() < 1e-12);
        assert_eq!(r.collaborative.pos_within_0_6mm_frac, 0.0);
        assert!(r.relative_left.pos_max_mm < 1e-12 && r.relative_right.pos_max_mm < 1e-12);
    }

    #[test]
    fn base_translation_error_on_a_real_arm() {
        // A base translation error δ leaves the relative figures and all orientations alone and changes
        // each collaborative distance to |v − δ| where v = p_L − B·p_R on the true robot.
        let mut rng = ChaCha8Rng::seed_from_u64(6);
        let truth = true_model(&mut rng);
        let ds = simulate(&truth, &random_isometry(&mut rng, 2500.0), [5, 6], 0.0, 7);
        let delta = Vector3::new(1.5, -0.7, 2.0);
        let mut wrong = truth.clone();
        wrong.left_base_from_right_base =
            Isometry3::from_parts(Translation3::from(delta), Default::default())
                * truth.left_base_from_right_base;
        let pairs = collaborative_pairs(&ds, &wrong, SplitSelect::All).unwrap();
        let mut n = 0;
        for p in &pairs {
            let l = truth
                .left
                .reflector_fk(&ds.left.measurements[p.first].q_rad);
            let r = truth
                .right
                .reflector_fk(&ds.right.measurements[p.second].q_rad);
            for k in 0..3 {
                let v = l.points_mm[k]
                    - truth
                        .left_base_from_right_base
                        .transform_point(&r.points_mm[k].into())
                        .coords;
                let expected = v.norm() - (v - delta).norm();
                assert!((p.pos_error_mm[k] - expected).abs() < 1e-9);
                assert!(expected.abs() > 1e-3);
                n += 1;
            }
            assert!(p.ori_error_rad < 1e-7);
        }
        assert_eq!(n, 5 * 6 * 3);
        let r = evaluate(&ds, &wrong, SplitSelect::All).unwrap();
        assert!(r.relative_left.pos_max_mm < 1e-9 && r.relative_right.ori_max_rad < 1e-7);
    }

    #[test]
    fn rotating_one_measured_triangle_gives_that_orientation_error() {
        let mut rng = ChaCha8Rng::seed_from_u64(8);
        let truth = true_model(&mut rng);
        let mut ds = simulate(&truth, &random_isometry(&mut rng, 2000.0), [6, 5], 0.0, 9);
        let alpha = 0.004;
        let axis = nalgebra::Unit::new_normalize(random_unit(&mut rng));
        let rot = Rotation3::from_axis_angle(&axis, alpha);
        let pts = &mut ds.left.measurements[2].tracker_points_mm;
        let c = (pts[0] + pts[1] + pts[2]) / 3.0;
        for p in pts.iter_mut() {
            *p = c + rot * (*p - c);
        }
        for p in relative_pairs(&ds, &truth, Side::Left, SplitSelect::All).unwrap() {
            let expected = if p.first == 2 || p.second == 2 {
                alpha
            } else {
                0.0
            };
            assert!((p.ori_error_rad - expected).abs() < 1e-9, "{p:?}");
        }
        for p in collaborative_pairs(&ds, &truth, SplitSelect::All).unwrap() {
            let expected = if p.first == 2 { alpha } else { 0.0 };
            assert!((p.ori_error_rad - expected).abs() < 1e-9, "{p:?}");
        }
        let r = evaluate(&ds, &truth, SplitSelect::All).unwrap();
        assert!((r.relative_left.ori_max_rad - alpha).abs() < 1e-9);
        assert!(r.relative_right.ori_max_rad < 1e-7);
        // 5 of 15 left pairs involve configuration 2.
        let expected_rms = (5.0 / 15.0f64).sqrt() * alpha;
        assert!((r.relative_left.ori_rms_rad - expected_rms).abs() < 1e-9);
        assert!((r.relative_left.ori_within_0_005rad_frac - 1.0).abs() < 1e-12);
        let per = per_config(&ds, &truth, SplitSelect::All).unwrap();
        assert_eq!(per.len(), 11);
        assert!((per[2].relative_ori_max_rad - alpha).abs() < 1e-9);
        assert!((per[2].collaborative_ori_max_rad - alpha).abs() < 1e-9);
        assert!(
            per[3].relative_ori_max_rad > alpha - 1e-9 && per[3].collaborative_ori_max_rad < 1e-7
        );
        // A rotation about the centroid keeps the triangle rigid and the fit exact.
        assert!(
            per.iter()
                .all(|c| c.rigidity_mm < 1e-9 && c.fit_rms_mm < 1e-9)
        );
    }

    #[test]
    fn tracker_frame_does_not_matter() {
        let mut rng = ChaCha8Rng::seed_from_u64(10);
        let truth = true_model(&mut rng);
        let ds = simulate(
            &truth,
            &random_isometry(&mut rng, 2000.0),
            [10, 9],
            0.05,
            11,
        );
        let nominal = DualArmModel {
            left: ArmModel::nominal_irb14000(nominal_reflectors()),
            right: ArmModel::nominal_irb14000(nominal_reflectors()),
            left_base_from_right_base: nominal_base(),
        };
        let before = evaluate(&ds, &nominal, SplitSelect::All).unwrap();
        let moved = random_isometry(&mut rng, 3000.0);
        let mut ds2 = ds.clone();
        for arm in [&mut ds2.left, &mut ds2.right] {
            for m in &mut arm.measurements {
                for p in &mut m.tracker_points_mm {
                    *p = moved.transform_point(&(*p).into()).coords;
                }
            }
        }
        let after = evaluate(&ds2, &nominal, SplitSelect::All).unwrap();
        assert_reports_close(&before, &after, 1e-9);
        assert!(before.collaborative.pos_rms_mm > 0.1);
    }

    #[test]
    fn stats_agree_with_the_pair_lists() {
        let mut rng = ChaCha8Rng::seed_from_u64(12);
        let truth = true_model(&mut rng);
        let ds = simulate(
            &truth,
            &random_isometry(&mut rng, 2000.0),
            [12, 10],
            0.3,
            13,
        );
        let mut model = truth.clone();
        model.left = perturbed_arm(&mut rng, 0.2);
        let r = evaluate(&ds, &model, SplitSelect::Cal).unwrap();
        let check = |s: &AccuracyStats, p: &[PairError]| {
            assert_eq!(s.n_pairs, p.len());
            let n = p.len() as f64;
            for k in 0..3 {
                let rms = (p.iter().map(|e| e.pos_error_mm[k].powi(2)).sum::<f64>() / n).sqrt();
                assert!((rms - s.pos_rms_per_reflector_mm[k]).abs() < 1e-9);
            }
            let max = p.iter().map(|e| e.pos_worst_mm.abs()).fold(0.0, f64::max);
            assert!((max - s.pos_max_mm).abs() < 1e-12);
            let frac =
                |f: &dyn Fn(&PairError) -> bool| p.iter().filter(|e| f(e)).count() as f64 / n;
            assert_eq!(
                frac(&|e| e.pos_worst_mm.abs() <= 0.3),
                s.pos_within_0_3mm_frac
            );
            assert_eq!(
                frac(&|e| e.pos_worst_mm.abs() <= 0.6),
                s.pos_within_0_6mm_frac
            );
            assert_eq!(
                frac(&|e| e.ori_error_rad <= 0.005),
                s.ori_within_0_005rad_frac
            );
            assert_eq!(
                frac(&|e| e.ori_error_rad <= 0.01),
                s.ori_within_0_01rad_frac
            );
            let ori = (p.iter().map(|e| e.ori_error_rad.powi(2)).sum::<f64>() / n).sqrt();
            assert!((ori - s.ori_rms_rad).abs() < 1e-12);
        };
        check(
            &r.relative_left,
            &relative_pairs(&ds, &model, Side::Left, SplitSelect::Cal).unwrap(),
        );
        check(
            &r.relative_right,
            &relative_pairs(&ds, &model, Side::Right, SplitSelect::Cal).unwrap(),
        );
        check(
            &r.collaborative,
            &collaborative_pairs(&ds, &model, SplitSelect::Cal).unwrap(),
        );
        // Not all trivially 0 or 1, so the frequency checks mean something.
        assert!(r.relative_left.pos_within_0_3mm_frac < 1.0);
        assert!(r.relative_right.pos_within_0_6mm_frac > 0.0);
        let alone = relative_stats(&ds, &model.left, Side::Left, SplitSelect::Cal).unwrap();
        assert_reports_close(
            &AccuracyReport {
                relative_left: alone,
                ..r
            },
            &r,
            1e-9,
        );
        let col = collaborative_stats(&ds, &model, SplitSelect::Cal).unwrap();
        assert_eq!(col, r.collaborative);
    }

    #[test]
    fn triangle_rigidity_sees_a_displaced_reflector() {
        let mut rng = ChaCha8Rng::seed_from_u64(14);
        let truth = true_model(&mut rng);
        let mut ds = simulate(&truth, &random_isometry(&mut rng, 2000.0), [4, 4], 0.0, 15);
        // Move reflector a 0.25 mm away from b: |ab| grows by 0.25 mm, |ca| by less.
        let m = &mut ds.right.measurements[1];
        let dir = (m.tracker_points_mm[0] - m.tracker_points_mm[1]).normalize();
        m.tracker_points_mm[0] += dir * 0.25;
        let per = per_config(&ds, &truth, SplitSelect::All).unwrap();
        let c = per.iter().find(|c| c.id == "right001").unwrap();
        assert!((c.triangle_side_errors_mm[0] - 0.25).abs() < 1e-9, "{c:?}");
        assert!(c.triangle_side_errors_mm[1].abs() < 1e-9);
        assert!((c.rigidity_mm - 0.25).abs() < 1e-9);
        assert!(c.fit_rms_mm > 0.01);
        assert!(
            per.iter()
                .filter(|c| c.id != "right001")
                .all(|c| c.rigidity_mm < 1e-9)
        );
    }

    #[test]
    fn kabsch_recovers_a_random_rotation() {
        let mut rng = ChaCha8Rng::seed_from_u64(16);
        for _ in 0..200 {
            let model: [Vector3<f64>; 3] =
                std::array::from_fn(|_| random_unit(&mut rng) * rng.random_range(10.0..100.0));
            let truth = random_isometry(&mut rng, 1000.0);
            let measured = model.map(|p| truth.transform_point(&p.into()).coords);
            let fit = kabsch_fit(&model, &measured).unwrap();
            let err = rotation_angle_rad(
                &(fit.rotation.transpose() * truth.rotation.to_rotation_matrix()),
            );
            assert!(err < 1e-9, "{err}");
            assert!((fit.rotation.matrix().determinant() - 1.0).abs() < 1e-12);
            assert!((fit.translation_mm - truth.translation.vector).norm() < 1e-8);
            assert!(fit.rms_mm < 1e-9);
            assert!(
                (fit.isometry().to_homogeneous() - truth.to_homogeneous())
                    .abs()
                    .max()
                    < 1e-8
            );
            let r = kabsch_rotation(&model, &measured);
            assert_eq!(r, fit.rotation);
        }
    }

    #[test]
    fn kabsch_returns_a_proper_rotation_for_mirrored_points() {
        // Mirror images cannot be matched by a rotation; the fit must still be a rotation (det +1).
        let model = nominal_reflectors();
        let measured = model.map(|p| Vector3::new(p.x, p.y, -p.z) + Vector3::new(5.0, 0.0, 0.0));
        let fit = kabsch_fit(&model, &measured).unwrap();
        assert!((fit.rotation.matrix().determinant() - 1.0).abs() < 1e-12);
        // Three points are always coplanar: a proper rotation matches them exactly.
        assert!(fit.rms_mm < 1e-9, "{}", fit.rms_mm);
        let nan = [
            Vector3::new(f64::NAN, 0.0, 0.0),
            Vector3::zeros(),
            Vector3::x(),
        ];
        assert!(kabsch_fit(&model, &nan).is_none());
        assert_eq!(kabsch_rotation(&model, &nan), Rotation3::identity());
    }

    #[test]
    fn bad_input_is_an_error_not_a_panic() {
        let mut rng = ChaCha8Rng::seed_from_u64(17);
        let truth = true_model(&mut rng);
        let ds = simulate(&truth, &Isometry3::identity(), [6, 3], 0.0, 18);
        // Right arm has only one `ver` configuration.
        match evaluate(&ds, &truth, SplitSelect::Ver) {
            Err(MetricsError::TooFewConfigurations {
                side: Side::Right,
                found: 1,
                ..
            }) => {}
            other => panic!("{other:?}"),
        }
        let e = evaluate(&ds, &truth, SplitSelect::Ver)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("right") && e.contains("`ver`") && e.contains('2'),
            "{e}"
        );

        let mut bad = ds.clone();
        bad.left.measurements[1].tracker_points_mm[2].y = f64::NAN;
        let e = evaluate(&bad, &truth, SplitSelect::All).unwrap_err();
        assert!(
            matches!(e, MetricsError::NonFiniteMeasurement { ref field, .. } if field == "cy"),
            "{e}"
        );
        assert!(e.to_string().contains("left001"));

        let mut bad = ds.clone();
        bad.right.measurements[0].q_rad[4] = f64::INFINITY;
        assert!(matches!(
            evaluate(&bad, &truth, SplitSelect::All),
            Err(MetricsError::NonFiniteMeasurement { ref field, .. }) if field == "q5"
        ));

        let mut m = truth.clone();
        m.right.dh[3].alpha_rad = f64::NAN;
        let e = evaluate(&ds, &m, SplitSelect::All).unwrap_err();
        assert!(e.to_string().contains("alpha4"), "{e}");

        let mut m = truth.clone();
        m.left_base_from_right_base.translation.vector.x = f64::NAN;
        assert!(matches!(
            evaluate(&ds, &m, SplitSelect::All),
            Err(MetricsError::NonFiniteModel { .. })
        ));

        let mut m = truth.clone();
        m.left.reflectors_mm[2] = m.left.reflectors_mm[0] * 2.0 - m.left.reflectors_mm[1];
        assert!(matches!(
            evaluate(&ds, &m, SplitSelect::All),
            Err(MetricsError::DegenerateReflectors { side: Side::Left })
        ));

        let mut m = truth.clone();
        m.left.dh[0].d_mm = 1e308;
        m.left.dh[2].d_mm = 1e308;
        assert!(evaluate(&ds, &m, SplitSelect::All).is_err());
    }

    #[test]
    fn report_json_has_the_issue_shape() {
        let mut rng = ChaCha8Rng::seed_from_u64(19);
        let truth = true_model(&mut rng);
        let ds = simulate(&truth, &Isometry3::identity(), [4, 4], 0.02, 20);
        let r = evaluate(&ds, &truth, SplitSelect::All).unwrap();
        let v = serde_json::to_value(r).unwrap();
        let o = v.as_object().unwrap();
        assert_eq!(o.len(), 3);
        for key in ["relative_left", "relative_right", "collaborative"] {
            let s = o[key].as_object().unwrap();
            for f in [
                "pos_rms_mm",
                "pos_max_mm",
                "ori_rms_rad",
                "ori_max_rad",
                "pos_within_0_3mm_frac",
                "pos_within_0_6mm_frac",
                "ori_within_0_005rad_frac",
                "ori_within_0_01rad_frac",
            ] {
                assert!(s[f].is_f64(), "{key}.{f}");
            }
        }
        let back: AccuracyReport = serde_json::from_value(v).unwrap();
        assert_eq!(back, r);
    }

    #[test]
    fn tables_show_the_figures() {
        let stats = |x: f64| AccuracyStats {
            pos_rms_mm: 3.25 * x,
            pos_rms_per_reflector_mm: [3.25 * x, 2.5 * x, 1.0 * x],
            pos_max_mm: 9.5 * x,
            ori_rms_rad: 0.0042 * x,
            ori_max_rad: 0.0123 * x,
            pos_within_0_3mm_frac: 0.0081 / x,
            pos_within_0_6mm_frac: 0.0311 / x,
            ori_within_0_005rad_frac: 0.023 / x,
            ori_within_0_01rad_frac: 0.1248 / x,
            n_configs: 100,
            n_pairs: 4950,
        };
        let before = AccuracyReport {
            relative_left: stats(1.0),
            relative_right: stats(1.0),
            collaborative: stats(1.0),
        };
        let t = format_table(&before);
        for s in [
            "relative left",
            "collaborative",
            "3.250",
            "9.500",
            "4.200",
            "12.300",
            "0.81 %",
            "12.48 %",
            "4950",
        ] {
            assert!(t.contains(s), "{s} missing in\n{t}");
        }
        // Rows are aligned: every line has the same width in characters.
        let widths: Vec<usize> = t.lines().map(|l| l.chars().count()).collect();
        assert!(widths.windows(2).all(|w| w[0] == w[1]), "{t}");
        let after = AccuracyReport {
            relative_left: stats(0.1),
            ..before
        };
        let c = format_comparison(&before, &after, ["nominal", "calibrated"]);
        for s in [
            "nominal",
            "calibrated",
            "0.325",
            "-90.00 %",
            "+7.29 pp",
            "+0.00 %",
        ] {
            assert!(c.contains(s), "{s} missing in\n{c}");
        }
    }
}
