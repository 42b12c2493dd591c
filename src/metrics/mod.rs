//! Accuracy metrics of the paper (eqs. 5–8): relative positioning and orientation accuracy of each arm and
//! collaborative accuracy of the two arms, with the frequency figures of the paper's Tables 4 and 7.
//!
//! Definitions, over the configurations of one [`Split`] (model points `p_o` from forward kinematics
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
//! precomputed points and rotations (no allocation per pair) and run in parallel with rayon. [`sweep`]
//! computes the figures of both splits, every configuration's residuals and histogram samples in one
//! pass that visits each pair once (what the workbench shows of a model).

mod absolute;
mod geometry;
mod kabsch;
mod sweep;
mod tables;
#[cfg(test)]
mod tests;

use crate::dataset::{ArmData, Dataset, Split};
use crate::kinematics::{ArmModel, DualArmModel, PerReflector, reflector_sides, side_deviations};
use crate::par::prelude::*;
use crate::side::{ConfigId, Side};
pub use absolute::{AbsoluteError, AbsoluteStats, absolute_errors, absolute_stats};
pub use geometry::orientation_measurable;
use geometry::{
    ArmGeom, against, arm_geometry, both_arms, collaborative_accumulate, pair_residual,
    relative_accumulate, worst,
};
pub use kabsch::{KabschFit, kabsch_fit, kabsch_fit_points, kabsch_rotation};
use nalgebra::{Isometry3, Vector3};
use serde::{Deserialize, Serialize};
pub use sweep::{PairSamples, SplitSweep, Sweep, sweep};
pub use tables::{
    ComparisonBlock, ComparisonRow, NOT_MEASURABLE, comparison_blocks, format_comparison,
    format_comparison_named, format_table, format_table_named,
};

/// The metrics need at least two configurations per arm (one pair); a calibration needs more
/// ([`crate::dataset::MIN_CONFIGS`]).
pub const MIN_METRIC_CONFIGS: usize = 2;
/// Positioning thresholds of the paper's Tables 4 and 7, mm.
pub const POS_THRESHOLDS_MM: [f64; 2] = [0.3, 0.6];
/// Orientation thresholds of the paper's Tables 4 and 7, rad.
pub const ORI_THRESHOLDS_RAD: [f64; 2] = [0.005, 0.01];

/// Accuracy figures over one set of pairs (one arm's relative pairs, or the collaborative pairs).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct AccuracyStats {
    /// Largest of the reflectors' RMS of `Δd`, mm.
    pub pos_rms_mm: f64,
    /// RMS of `Δd` of each reflector (a, b, c in the paper's set-up), mm.
    pub pos_rms_per_reflector_mm: PerReflector<f64>,
    /// Largest `|Δd|` over all pairs and reflectors, mm.
    pub pos_max_mm: f64,
    /// RMS of `Δo`, rad; `None`: not measurable (fewer than three reflectors).
    pub ori_rms_rad: Option<f64>,
    /// Largest `Δo`, rad; `None`: not measurable.
    pub ori_max_rad: Option<f64>,
    /// Fraction (0..1) of pairs whose worst-reflector `|Δd|` ≤ 0.3 mm.
    pub pos_within_0_3mm_frac: f64,
    /// Fraction (0..1) of pairs whose worst-reflector `|Δd|` ≤ 0.6 mm.
    pub pos_within_0_6mm_frac: f64,
    /// Fraction (0..1) of pairs with `Δo` ≤ 0.005 rad; `None`: not measurable.
    pub ori_within_0_005rad_frac: Option<f64>,
    /// Fraction (0..1) of pairs with `Δo` ≤ 0.01 rad; `None`: not measurable.
    pub ori_within_0_01rad_frac: Option<f64>,
    /// Configurations involved (left + right for the collaborative figures).
    pub n_configs: usize,
    /// Pairs evaluated: `n(n−1)/2` per arm, `n_left · n_right` collaborative.
    pub n_pairs: usize,
}

/// The three sets of figures; serialises to
/// `{"relative_left": {...}, "relative_right": {...}, "collaborative": {...}}`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct AccuracyReport {
    /// The left arm's relative figures; `None`: the arm was not measured (a dataset of the right
    /// arm alone; serialised as `null`).
    pub relative_left: Option<AccuracyStats>,
    /// The right arm's relative figures; `None`: not measured.
    pub relative_right: Option<AccuracyStats>,
    /// `None`: not measurable from this data — the arms were measured from different tracker
    /// stations, so distances between their reflectors mean nothing, or one arm alone was measured
    /// (serialised as `null`).
    pub collaborative: Option<AccuracyStats>,
    /// The collaborative figures of the pairs taken at one instant (both hands measured together:
    /// the left and right rows of one id), where the dataset says so (`measured_together`); absent
    /// otherwise. The hands' error relative to each other in one pose of the robot.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub collaborative_same_instant: Option<AccuracyStats>,
}

impl AccuracyReport {
    /// The relative figures of one arm (`None`: the arm was not measured).
    pub fn relative(&self, side: Side) -> Option<&AccuracyStats> {
        match side {
            Side::Left => self.relative_left.as_ref(),
            Side::Right => self.relative_right.as_ref(),
        }
    }

    /// The collaborative figures, NaN where they are not measurable: for the studies' tables over
    /// simulated one-station data, where they always exist.
    pub fn collaborative_or_nan(&self) -> AccuracyStats {
        self.collaborative.unwrap_or_else(|| self.nan())
    }

    /// One arm's relative figures, NaN where the arm was not measured (the studies' tables).
    pub fn relative_or_nan(&self, side: Side) -> AccuracyStats {
        self.relative(side).copied().unwrap_or_else(|| self.nan())
    }

    /// Figures of nothing: NaN, no orientation, no pairs (as many reflectors as the others have).
    fn nan(&self) -> AccuracyStats {
        let reflectors = [self.relative_left, self.relative_right, self.collaborative]
            .into_iter()
            .flatten()
            .next()
            .map_or_else(PerReflector::default, |r| {
                r.pos_rms_per_reflector_mm.map(|_| f64::NAN)
            });
        AccuracyStats {
            pos_rms_mm: f64::NAN,
            pos_rms_per_reflector_mm: reflectors,
            pos_max_mm: f64::NAN,
            ori_rms_rad: None,
            ori_max_rad: None,
            pos_within_0_3mm_frac: f64::NAN,
            pos_within_0_6mm_frac: f64::NAN,
            ori_within_0_005rad_frac: None,
            ori_within_0_01rad_frac: None,
            n_configs: 0,
            n_pairs: 0,
        }
    }

    /// The figures of one kind of pairs (`None`: not measurable from the data).
    pub fn stats(&self, kind: PairKind) -> Option<&AccuracyStats> {
        match kind {
            PairKind::Relative(side) => self.relative(side),
            PairKind::Collaborative => self.collaborative.as_ref(),
        }
    }
}

/// Which pairs: one arm's configuration pairs `i < j`, or every left configuration with every right one.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum PairKind {
    Relative(Side),
    Collaborative,
}

/// The residuals (measured minus model) of one pair, for histograms and inspection.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct PairResiduals {
    /// Index into `ArmData::measurements` of the first configuration (the left arm's, if collaborative).
    pub first: usize,
    /// Index into `ArmData::measurements` of the second configuration (the right arm's, if collaborative).
    pub second: usize,
    /// Signed `Δd` of each reflector (a, b, c in the paper's set-up), mm.
    pub pos_error_mm: PerReflector<f64>,
    /// The `Δd` of largest magnitude among the reflectors (signed), mm.
    pub pos_worst_mm: f64,
    /// `Δo`, rad; `None`: not measurable (fewer than three reflectors).
    pub ori_error_rad: Option<f64>,
}

impl PairResiduals {
    /// The configuration ids of the pair.
    pub fn ids<'a>(&self, dataset: &'a Dataset, kind: PairKind) -> (&'a str, &'a str) {
        let (a, b) = match kind {
            PairKind::Relative(side) => (dataset.arm(side), dataset.arm(side)),
            PairKind::Collaborative => (&dataset.arms.left, &dataset.arms.right),
        };
        let id =
            |arm: &'a ArmData, i: usize| arm.measurements.get(i).map_or("?", |m| m.id.as_str());
        (id(a, self.first), id(b, self.second))
    }
}

/// Per-configuration residuals, for finding the configurations that dominate the errors.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ConfigResiduals {
    pub config: ConfigId,
    pub id: String,
    /// Largest `|Δd|` over the relative pairs involving this configuration, mm.
    pub relative_pos_max_mm: f64,
    /// RMS of `Δo` over the relative pairs involving this configuration, rad (`None`: not measurable).
    pub relative_ori_rms_rad: Option<f64>,
    /// Largest `Δo` over the relative pairs involving this configuration, rad.
    pub relative_ori_max_rad: Option<f64>,
    /// Largest `|Δd|` over the collaborative pairs involving this configuration, mm (`None`: not
    /// measurable, the arms measured from different tracker stations).
    pub collaborative_pos_max_mm: Option<f64>,
    /// RMS of `Δo` over the collaborative pairs involving this configuration, rad.
    pub collaborative_ori_rms_rad: Option<f64>,
    /// Largest `Δo` over the collaborative pairs involving this configuration, rad.
    pub collaborative_ori_max_rad: Option<f64>,
    /// Measured minus model distances between the reflectors (the triangle's sides `|ab|`, `|bc|`,
    /// `|ca|` for three; none for one reflector), mm.
    pub triangle_side_errors_mm: Vec<f64>,
    /// Largest `|triangle_side_errors_mm|` (rigidity of the measured reflector set; 0 for one), mm.
    pub rigidity_mm: f64,
    /// RMS residual of the Kabsch fit of the model reflectors to the measured points, mm (`None`
    /// without orientation: fewer than three reflectors).
    pub fit_rms_mm: Option<f64>,
}

/// Why the metrics cannot be computed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum MetricsError {
    #[error(
        "{side} arm: {found} configuration(s) in split `{}`, the accuracy metrics need at least {min}",
        .split.name()
    )]
    TooFewConfigurations {
        side: Side,
        split: Split,
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
        "{side} arm, configuration `{id}`: {found} joint values, the model's arm has {expected} joints"
    )]
    JointCount {
        side: Side,
        id: String,
        found: usize,
        expected: usize,
    },
    #[error(
        "model: the {side} arm's reflectors t_a, t_b, t_c are (nearly) collinear, no flange rotation can be fitted"
    )]
    DegenerateReflectors { side: Side },
    #[error(
        "{side} arm, configuration `{id}`: {found} reflector positions, the model has {expected} reflectors"
    )]
    ReflectorCount {
        side: Side,
        id: String,
        found: usize,
        expected: usize,
    },
    #[error("{side} arm, configuration `{id}`: the Kabsch fit did not converge")]
    FitFailed { side: Side, id: String },
    #[error("{what} is not finite (the model or the data overflow)")]
    NonFiniteResult { what: String },
}

/// Has every measured arm of `dataset` enough configurations of `split` for the figures
/// ([`MIN_METRIC_CONFIGS`])? (An arm not measured has none and needs none.)
pub fn has_split(dataset: &Dataset, split: Split) -> bool {
    dataset.measured_sides().iter().all(|&s| {
        dataset
            .arm(s)
            .measurements
            .iter()
            .filter(|m| m.split == split)
            .count()
            >= MIN_METRIC_CONFIGS
    })
}

/// All accuracy figures of `model` on the configurations of `split`.
pub fn evaluate(
    dataset: &Dataset,
    model: &DualArmModel,
    split: Split,
) -> Result<AccuracyReport, MetricsError> {
    let (left, right) = both_arms(dataset, model, split)?;
    // The right arm's model is expressed in the left base; relative figures do not depend on the frame.
    let relative = |g: &ArmGeom| {
        let data = dataset.arm(g.side);
        data.is_measured()
            .then(|| {
                relative_accumulate(&g.geom).finish(
                    g.geom.len(),
                    g.orientation,
                    &format!("{} relative", g.side),
                )
            })
            .transpose()
    };
    Ok(AccuracyReport {
        relative_left: relative(&left)?,
        relative_right: relative(&right)?,
        collaborative: if dataset.one_tracker_frame() {
            Some(collaborative_accumulate(&left.geom, &right.geom).finish(
                left.geom.len() + right.geom.len(),
                left.orientation && right.orientation,
                "collaborative",
            )?)
        } else {
            None
        },
        collaborative_same_instant: same_instant(
            dataset,
            (&left.geom, &left.indices),
            (&right.geom, &right.indices),
            left.orientation && right.orientation,
        )?,
    })
}

/// The same-instant collaborative figures ([`AccuracyReport::collaborative_same_instant`]) of two
/// arms' selected geometry, where the dataset measured both hands together in one frame and has
/// pairs of one id.
fn same_instant(
    dataset: &Dataset,
    left: (&[geometry::ConfigGeom], &[usize]),
    right: (&[geometry::ConfigGeom], &[usize]),
    orientation: bool,
) -> Result<Option<AccuracyStats>, MetricsError> {
    if !(dataset.measured_together && dataset.one_tracker_frame()) {
        return Ok(None);
    }
    let (acc, pairs) = geometry::same_instant_accumulate(dataset, left, right);
    if pairs == 0 {
        return Ok(None);
    }
    acc.finish(2 * pairs, orientation, "same-instant collaborative")
        .map(Some)
}

/// Relative accuracy of one arm alone (needs no base transform; for single-arm calibration).
pub fn relative_stats(
    dataset: &Dataset,
    arm: &ArmModel,
    side: Side,
    split: Split,
) -> Result<AccuracyStats, MetricsError> {
    let g = arm_geometry(dataset.arm(side), side, arm, &Isometry3::identity(), split)?;
    relative_accumulate(&g.geom).finish(g.geom.len(), g.orientation, &format!("{side} relative"))
}

/// Collaborative accuracy alone (`None`: not measurable, the arms measured from different stations).
pub fn collaborative_stats(
    dataset: &Dataset,
    model: &DualArmModel,
    split: Split,
) -> Result<Option<AccuracyStats>, MetricsError> {
    if !dataset.one_tracker_frame() {
        return Ok(None);
    }
    let (left, right) = both_arms(dataset, model, split)?;
    collaborative_accumulate(&left.geom, &right.geom)
        .finish(
            left.geom.len() + right.geom.len(),
            left.orientation && right.orientation,
            "collaborative",
        )
        .map(Some)
}

fn make_pair(a: &ArmGeom, i: usize, b: &ArmGeom, j: usize) -> PairResiduals {
    let (pos_error_mm, ori_error_rad) = pair_residual(&a.geom[i], &b.geom[j]);
    PairResiduals {
        first: a.indices[i],
        second: b.indices[j],
        pos_error_mm,
        pos_worst_mm: worst(&pos_error_mm),
        ori_error_rad: (a.orientation && b.orientation).then_some(ori_error_rad),
    }
}

/// Every pair of `kind`, in order (`i < j` row by row; collaborative: left-major).
pub fn pairs(
    dataset: &Dataset,
    model: &DualArmModel,
    split: Split,
    kind: PairKind,
) -> Result<Vec<PairResiduals>, MetricsError> {
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
    split: Split,
) -> Result<Vec<PairResiduals>, MetricsError> {
    pairs(dataset, model, split, PairKind::Relative(side))
}

/// Every (left, right) pair.
pub fn collaborative_pairs(
    dataset: &Dataset,
    model: &DualArmModel,
    split: Split,
) -> Result<Vec<PairResiduals>, MetricsError> {
    pairs(dataset, model, split, PairKind::Collaborative)
}

/// Per-configuration summary of both arms (left first, each in measurement order).
pub fn per_config(
    dataset: &Dataset,
    model: &DualArmModel,
    split: Split,
) -> Result<Vec<ConfigResiduals>, MetricsError> {
    let (left, right) = both_arms(dataset, model, split)?;
    let mut out = Vec::with_capacity(left.geom.len() + right.geom.len());
    for (own, other) in [(&left, &right), (&right, &left)] {
        let data = dataset.arm(own.side);
        let model_sides = reflector_sides(&model.arm(own.side).reflectors_mm);
        let rows: Vec<ConfigResiduals> = (0..own.geom.len())
            .into_par_iter()
            .map(|i| {
                let g = &own.geom[i];
                let (rel_pos, rel_ori_rms, rel_ori_max) = against(g, &own.geom, Some(i));
                let (col_pos, col_ori_rms, col_ori_max) = against(g, &other.geom, None);
                let measured: Vec<Vector3<f64>> =
                    g.measured_mm.iter().map(|p| Vector3::from(*p)).collect();
                let (rigidity_mm, side_errors) = side_deviations(&measured, &model_sides);
                let one_frame = dataset.one_tracker_frame();
                let (rel, col) = (
                    own.orientation,
                    own.orientation && other.orientation && one_frame,
                );
                let index = own.indices[i];
                ConfigResiduals {
                    config: ConfigId::new(own.side, index),
                    id: data.measurements[index].id.clone(),
                    relative_pos_max_mm: rel_pos,
                    relative_ori_rms_rad: rel.then_some(rel_ori_rms),
                    relative_ori_max_rad: rel.then_some(rel_ori_max),
                    collaborative_pos_max_mm: one_frame.then_some(col_pos),
                    collaborative_ori_rms_rad: col.then_some(col_ori_rms),
                    collaborative_ori_max_rad: col.then_some(col_ori_max),
                    rigidity_mm,
                    triangle_side_errors_mm: side_errors,
                    fit_rms_mm: own.orientation.then_some(g.fit_rms_mm),
                }
            })
            .collect();
        out.extend(rows);
    }
    Ok(out)
}
