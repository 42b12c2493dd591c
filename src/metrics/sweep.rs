//! Every figure of a model on a whole dataset in one pass over its pairs: what the workbench shows of
//! one model, and recomputes for the live view while a calibration runs.
//!
//! [`evaluate`](super::evaluate) of the calibration and of the verification split and
//! [`per_config`](super::per_config) over all configurations visit the same pairs: a pair of two
//! calibration configurations counts in the calibration figures and in both configurations' rows, a pair
//! with one configuration of each split only in the rows. [`sweep`] computes each pair's residuals once
//! (at 2 × 1100 configurations 2.4 million pairs, against 9 million for the three calls, plus the pair
//! lists) and returns the same figures, and every same-split pair's residuals as `f32` samples for
//! histograms. Each arm's configurations are visited calibration first, so a row's same-split partners
//! are contiguous and its samples go to a slice of their own, written in parallel without locks.

use super::geometry::{Accumulator, ArmGeom, ConfigGeom, SUM_BLOCKS, both_arms, pair_residual};
use super::{AccuracyReport, ConfigResiduals, MIN_METRIC_CONFIGS, MetricsError, PairKind};
use crate::dataset::{Dataset, Split};
use crate::kinematics::DualArmModel;
use crate::kinematics::{reflector_sides, side_deviations};
use crate::par::prelude::*;
use crate::side::{ConfigId, PerSide, Side};
use nalgebra::Vector3;

/// The residuals of one set of pairs as histogram samples.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PairSamples {
    /// Reflectors per pair in `pos_mm`.
    pub reflectors: usize,
    /// Signed `Δd` of each reflector (a, b, c in the paper's set-up) of every pair, mm (`reflectors`
    /// per pair).
    pub pos_mm: Vec<f32>,
    /// `Δo` of every pair, rad; empty when the orientation is not measurable (fewer than three
    /// reflectors).
    pub ori_rad: Vec<f32>,
}

/// The figures of one split.
#[derive(Clone, Debug, PartialEq)]
pub struct SplitSweep {
    /// Exactly [`evaluate`](super::evaluate)'s figures (up to the order of summation).
    pub report: AccuracyReport,
    /// Samples of the left arm's relative pairs, the right arm's, and the collaborative pairs.
    pub samples: [PairSamples; 3],
}

impl SplitSweep {
    /// The samples of one pair kind.
    pub fn samples(&self, kind: PairKind) -> &PairSamples {
        &self.samples[kind_slot(kind)]
    }
}

/// Everything [`sweep`] computes.
#[derive(Clone, Debug, PartialEq)]
pub struct Sweep {
    /// [`per_config`](super::per_config) over [`Split::All`]: both arms, left first, in measurement order.
    pub per_config: Vec<ConfigResiduals>,
    /// The calibration split's figures (`None` with fewer than two of its configurations on an arm).
    pub cal: Option<SplitSweep>,
    /// The verification split's figures (`None` likewise).
    pub ver: Option<SplitSweep>,
}

impl Sweep {
    /// The figures of `split` (`None` for [`Split::All`], which is not computed).
    pub fn split(&self, split: Split) -> Option<&SplitSweep> {
        match split {
            Split::Cal => self.cal.as_ref(),
            Split::Ver => self.ver.as_ref(),
            Split::All => None,
        }
    }
}

const REL_LEFT: usize = 0;
const REL_RIGHT: usize = 1;
const COLLAB: usize = 2;

fn kind_slot(kind: PairKind) -> usize {
    match kind {
        PairKind::Relative(Side::Left) => REL_LEFT,
        PairKind::Relative(Side::Right) => REL_RIGHT,
        PairKind::Collaborative => COLLAB,
    }
}

/// One arm's configurations, calibration ones first.
struct Ordered {
    geom: Vec<ConfigGeom>,
    /// Is the orientation measurable ([`super::geometry::ArmGeom::orientation`])?
    orientation: bool,
    /// Reflectors per configuration.
    reflectors: usize,
    /// Index into `ArmData::measurements` of each.
    indices: Vec<usize>,
    /// How many are calibration configurations (they come first).
    n_cal: usize,
}

impl Ordered {
    fn new(dataset: &Dataset, side: Side, arm: ArmGeom) -> Self {
        let ArmGeom {
            geom,
            indices,
            orientation,
            ..
        } = arm;
        let measurements = &dataset.arm(side).measurements;
        let is_cal = |i: usize| measurements[indices[i]].split != Split::Ver;
        let order: Vec<usize> = (0..geom.len())
            .filter(|&i| is_cal(i))
            .chain((0..geom.len()).filter(|&i| !is_cal(i)))
            .collect();
        Self {
            orientation,
            reflectors: dataset.reflector_count(),
            n_cal: (0..geom.len()).filter(|&i| is_cal(i)).count(),
            geom: order.iter().map(|&i| geom[i]).collect(),
            indices: order.iter().map(|&i| indices[i]).collect(),
        }
    }

    fn len(&self) -> usize {
        self.geom.len()
    }

    /// The split group (0 calibration, 1 verification) of position `p`.
    fn group(&self, p: usize) -> usize {
        usize::from(p >= self.n_cal)
    }

    /// The positions of group `g`.
    /// The geometry and measurement indices of split group `g` (0: calibration, 1: verification).
    fn slices(&self, g: usize) -> (&[ConfigGeom], &[usize]) {
        let r = self.range(g);
        (&self.geom[r.clone()], &self.indices[r])
    }

    fn range(&self, g: usize) -> std::ops::Range<usize> {
        if g == 0 {
            0..self.n_cal
        } else {
            self.n_cal..self.len()
        }
    }
}

/// Running figures of one configuration's pairs.
#[derive(Clone, Copy, Debug, Default)]
struct ConfigAcc {
    rel_pos_max: f64,
    rel_ori_sum_sq: f64,
    rel_ori_max: f64,
    col_pos_max: f64,
    col_ori_sum_sq: f64,
    col_ori_max: f64,
}

impl ConfigAcc {
    #[inline]
    fn add_relative(&mut self, pos_abs_max: f64, ori: f64) {
        self.rel_pos_max = self.rel_pos_max.max(pos_abs_max);
        self.rel_ori_sum_sq += ori * ori;
        self.rel_ori_max = self.rel_ori_max.max(ori);
    }

    #[inline]
    fn add_collaborative(&mut self, pos_abs_max: f64, ori: f64) {
        self.col_pos_max = self.col_pos_max.max(pos_abs_max);
        self.col_ori_sum_sq += ori * ori;
        self.col_ori_max = self.col_ori_max.max(ori);
    }

    fn merge(&mut self, o: &Self) {
        self.rel_pos_max = self.rel_pos_max.max(o.rel_pos_max);
        self.rel_ori_sum_sq += o.rel_ori_sum_sq;
        self.rel_ori_max = self.rel_ori_max.max(o.rel_ori_max);
        self.col_pos_max = self.col_pos_max.max(o.col_pos_max);
        self.col_ori_sum_sq += o.col_ori_sum_sq;
        self.col_ori_max = self.col_ori_max.max(o.col_ori_max);
    }
}

/// What one worker has summed: every configuration's running figures (the partner of a pair is
/// updated too, so each pair is visited once) and the figures of the two splits.
struct Partial {
    /// Left arm's configurations, then the right arm's, in visiting order.
    configs: Vec<ConfigAcc>,
    /// Per split group, per pair kind.
    acc: [[Accumulator; 3]; 2],
}

impl Partial {
    fn new(n: usize) -> Self {
        Self {
            configs: vec![ConfigAcc::default(); n],
            acc: Default::default(),
        }
    }

    fn merge(mut self, o: Self) -> Self {
        for (a, b) in self.configs.iter_mut().zip(&o.configs) {
            a.merge(b);
        }
        for g in 0..2 {
            for k in 0..3 {
                self.acc[g][k] = self.acc[g][k].merge(o.acc[g][k]);
            }
        }
        self
    }
}

/// One configuration's row of the pass: its partners after it on its own arm, and (left arm) every
/// right configuration, with the slices its same-split samples go to.
struct Row<'a> {
    side: Side,
    p: usize,
    rel: SampleSlice<'a>,
    col: SampleSlice<'a>,
}

struct SampleSlice<'a> {
    pos: &'a mut [f32],
    /// Empty without orientation.
    ori: &'a mut [f32],
}

impl SampleSlice<'_> {
    #[inline]
    fn write(&mut self, k: usize, dd: &[f64], ori: f64) {
        let r = dd.len();
        for (c, d) in dd.iter().enumerate() {
            self.pos[r * k + c] = *d as f32;
        }
        if let Some(o) = self.ori.get_mut(k) {
            *o = ori as f32;
        }
    }
}

/// Cut `samples` into consecutive rows of `lens` pairs each.
fn rows_of<'a>(samples: &'a mut PairSamples, lens: &[usize]) -> Vec<SampleSlice<'a>> {
    let r = samples.reflectors;
    let ori_stride = usize::from(!samples.ori_rad.is_empty());
    let (mut pos, mut ori) = (&mut samples.pos_mm[..], &mut samples.ori_rad[..]);
    let mut out = Vec::with_capacity(lens.len());
    for &n in lens {
        let (p, rest_p) = std::mem::take(&mut pos).split_at_mut(r * n);
        let (o, rest_o) = std::mem::take(&mut ori).split_at_mut(ori_stride * n);
        (pos, ori) = (rest_p, rest_o);
        out.push(SampleSlice { pos: p, ori: o });
    }
    out
}

/// The relative sample slices of one arm's rows: row `p` of a split group with `n` configurations
/// has `n − p − 1` same-split partners after it.
fn relative_rows<'a>(
    arm: &Ordered,
    cal: &'a mut PairSamples,
    ver: &'a mut PairSamples,
) -> Vec<SampleSlice<'a>> {
    let triangle = |n: usize| -> Vec<usize> { (0..n).map(|p| n - p - 1).collect() };
    let mut rows = rows_of(cal, &triangle(arm.n_cal));
    rows.extend(rows_of(ver, &triangle(arm.len() - arm.n_cal)));
    rows
}

fn zeroed(n_pairs: usize, reflectors: usize, orientation: bool) -> PairSamples {
    PairSamples {
        reflectors,
        pos_mm: vec![0.0; reflectors * n_pairs],
        ori_rad: vec![0.0; if orientation { n_pairs } else { 0 }],
    }
}

#[inline]
fn abs_max(dd: &[f64]) -> f64 {
    dd.iter().fold(0.0f64, |m, d| m.max(d.abs()))
}

/// Zeroed sample buffers per split group (calibration, verification) and pair kind (left relative,
/// right relative, collaborative).
fn sample_buffers(arms: &PerSide<Ordered>) -> [[PairSamples; 3]; 2] {
    std::array::from_fn(|g| {
        let (l, r) = (arms.left.range(g).len(), arms.right.range(g).len());
        let (ol, or) = (arms.left.orientation, arms.right.orientation);
        let n = arms.left.reflectors;
        [
            zeroed(l * l.saturating_sub(1) / 2, n, ol),
            zeroed(r * r.saturating_sub(1) / 2, n, or),
            zeroed(l * r, n, ol && or),
        ]
    })
}

/// The buffers cut into one row per configuration: left rows carry their relative and collaborative
/// slices, right rows their relative slice only (collaborative pairs are visited from the left).
fn sample_rows<'a>(
    arms: &PerSide<Ordered>,
    samples: &'a mut [[PairSamples; 3]; 2],
) -> Vec<Row<'a>> {
    let n_left = arms.left.len();
    let mut rows: Vec<Row> = Vec::with_capacity(n_left + arms.right.len());
    let [cal, ver] = samples;
    let [cal_l, cal_r, cal_c] = cal;
    let [ver_l, ver_r, ver_c] = ver;
    let rel_left = relative_rows(&arms.left, cal_l, ver_l);
    let rel_right = relative_rows(&arms.right, cal_r, ver_r);
    let mut col = rows_of(cal_c, &vec![arms.right.range(0).len(); arms.left.n_cal]);
    col.extend(rows_of(
        ver_c,
        &vec![arms.right.range(1).len(); n_left - arms.left.n_cal],
    ));
    for (p, (rel, col)) in rel_left.into_iter().zip(col).enumerate() {
        rows.push(Row {
            side: Side::Left,
            p,
            rel,
            col,
        });
    }
    for (p, rel) in rel_right.into_iter().enumerate() {
        rows.push(Row {
            side: Side::Right,
            p,
            rel,
            col: SampleSlice {
                pos: &mut [],
                ori: &mut [],
            },
        });
    }
    rows
}

/// Visit every pair once, in parallel over rows: write the same-split samples into the rows' slices
/// and accumulate the split figures and every configuration's worst residuals.
fn accumulate(arms: &PerSide<Ordered>, rows: Vec<Row<'_>>) -> Partial {
    let n_left = arms.left.len();
    let n_configs = n_left + arms.right.len();
    let offset = PerSide::new(0, n_left);
    // Fixed blocks of rows, their partial sums merged in order: the same figures on every run (see
    // `geometry::ordered_sum`).
    let per_block = rows.len().div_ceil(SUM_BLOCKS).max(1);
    let parts: Vec<Partial> = rows
        .into_par_iter()
        .chunks(per_block)
        .map(|block| {
            block
                .into_iter()
                .fold(Partial::new(n_configs), |mut part, mut row| {
                    let side = row.side;
                    let a = &arms[side];
                    let (p, g) = (row.p, a.group(row.p));
                    let own = &a.geom[p];
                    let rel_slot = kind_slot(PairKind::Relative(side));
                    let mut mine = ConfigAcc::default();
                    // Relative pairs (p, q), q after p: same split up to the end of p's group.
                    let same_end = a.range(g).end;
                    for q in p + 1..a.len() {
                        let (dd, ori) = pair_residual(own, &a.geom[q]);
                        let w = abs_max(&dd);
                        mine.add_relative(w, ori);
                        part.configs[offset[side] + q].add_relative(w, ori);
                        if q < same_end {
                            row.rel.write(q - p - 1, &dd, ori);
                            part.acc[g][rel_slot].add(&dd, ori);
                        }
                    }
                    // Collaborative pairs, visited from the left arm.
                    if side == Side::Left {
                        let r_arm = &arms.right;
                        let same = r_arm.range(g);
                        for (r, other) in r_arm.geom.iter().enumerate() {
                            let (dd, ori) = pair_residual(own, other);
                            let w = abs_max(&dd);
                            mine.add_collaborative(w, ori);
                            part.configs[n_left + r].add_collaborative(w, ori);
                            if same.contains(&r) {
                                row.col.write(r - same.start, &dd, ori);
                                part.acc[g][COLLAB].add(&dd, ori);
                            }
                        }
                    }
                    part.configs[offset[side] + p].merge(&mine);
                    part
                })
        })
        .collect();
    parts
        .into_iter()
        .fold(Partial::new(n_configs), Partial::merge)
}

/// Every configuration's residual summary, in measurement order, left arm first.
fn per_config_residuals(
    dataset: &Dataset,
    model: &DualArmModel,
    arms: &PerSide<Ordered>,
    totals: &Partial,
) -> Vec<ConfigResiduals> {
    let (n_left, n_right) = (arms.left.len(), arms.right.len());
    let offset = PerSide::new(0, n_left);
    let mut per_config = Vec::with_capacity(n_left + n_right);
    for (side, n_other) in [(Side::Left, n_right), (Side::Right, n_left)] {
        let a = &arms[side];
        let data = dataset.arm(side);
        let model_sides = reflector_sides(&model.arm(side).reflectors_mm);
        let mut by_index: Vec<usize> = (0..a.len()).collect();
        crate::sort::sort_by_key(&mut by_index, |&p| a.indices[p]);
        for p in by_index {
            let c = &totals.configs[offset[side] + p];
            let g = &a.geom[p];
            let measured: Vec<Vector3<f64>> =
                g.measured_mm.iter().map(|p| Vector3::from(*p)).collect();
            let (rigidity_mm, side_errors) = side_deviations(&measured, &model_sides);
            let index = a.indices[p];
            let rms = |sum_sq: f64, n: usize| (sum_sq / n.max(1) as f64).sqrt();
            let rel = a.orientation;
            let one_frame = dataset.one_tracker_frame();
            let col = a.orientation && arms[side.other()].orientation && one_frame;
            per_config.push(ConfigResiduals {
                config: ConfigId::new(side, index),
                id: data.measurements[index].id.clone(),
                relative_pos_max_mm: c.rel_pos_max,
                relative_ori_rms_rad: rel.then(|| rms(c.rel_ori_sum_sq, a.len() - 1)),
                relative_ori_max_rad: rel.then_some(c.rel_ori_max),
                collaborative_pos_max_mm: one_frame.then_some(c.col_pos_max),
                collaborative_ori_rms_rad: col.then(|| rms(c.col_ori_sum_sq, n_other)),
                collaborative_ori_max_rad: col.then_some(c.col_ori_max),
                rigidity_mm,
                triangle_side_errors_mm: side_errors,
                fit_rms_mm: a.orientation.then_some(g.fit_rms_mm),
            });
        }
    }
    per_config
}

/// The accuracy figures of both splits, every configuration's residuals, and every same-split pair's
/// residuals as samples, of `model` on every configuration of `dataset`, visiting each pair once.
pub fn sweep(dataset: &Dataset, model: &DualArmModel) -> Result<Sweep, MetricsError> {
    let (left, right) = both_arms(dataset, model, Split::All)?;
    let arms = PerSide::new(
        Ordered::new(dataset, Side::Left, left),
        Ordered::new(dataset, Side::Right, right),
    );
    let mut samples = sample_buffers(&arms);
    let totals = accumulate(&arms, sample_rows(&arms, &mut samples));
    let per_config = per_config_residuals(dataset, model, &arms, &totals);

    let [cal_samples, ver_samples] = samples;
    let split = |g: usize, samples: [PairSamples; 3]| -> Result<Option<SplitSweep>, MetricsError> {
        let (l, r) = (arms.left.range(g).len(), arms.right.range(g).len());
        // Each measured arm needs its figures' minimum (an arm not measured has none).
        let short =
            |side: Side, n: usize| dataset.arm(side).is_measured() && n < MIN_METRIC_CONFIGS;
        if short(Side::Left, l) || short(Side::Right, r) || l + r == 0 {
            return Ok(None);
        }
        let acc = &totals.acc[g];
        let (ol, or) = (arms.left.orientation, arms.right.orientation);
        let one_frame = dataset.one_tracker_frame();
        Ok(Some(SplitSweep {
            report: AccuracyReport {
                relative_left: (l > 0)
                    .then(|| acc[REL_LEFT].finish(l, ol, "left relative"))
                    .transpose()?,
                relative_right: (r > 0)
                    .then(|| acc[REL_RIGHT].finish(r, or, "right relative"))
                    .transpose()?,
                collaborative: if one_frame {
                    Some(acc[COLLAB].finish(l + r, ol && or, "collaborative")?)
                } else {
                    None
                },
                collaborative_same_instant: super::same_instant(
                    dataset,
                    arms.left.slices(g),
                    arms.right.slices(g),
                    ol && or,
                )?,
            },
            samples,
        }))
    };
    Ok(Sweep {
        per_config,
        cal: split(0, cal_samples)?,
        ver: split(1, ver_samples)?,
    })
}
