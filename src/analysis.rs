//! The figures of a model on a dataset — one type, [`Analysis`], for every view of them: the
//! accuracy reports of the calibration and verification splits, their histograms and the paper's
//! per-pair samples (for the comparison's histograms and box plots), a row per configuration, and
//! the tracker → robot registration that places the measured points next to the model's for drawing
//! (the calibration itself never needs it: it works on distances).
//!
//! The configurations left out of a calibration are part of what its figures are computed on
//! ([`Analysis::compute_excluding`], [`Analysis::excluded`]): the workbench's calibration view, the
//! comparison of methods and the command line's tables show a model's figures on the same
//! configurations.

use crate::dataset::{Dataset, Split};
use crate::kinematics::DualArmModel;
use crate::metrics::{
    self, AccuracyReport, MetricsError, PairKind, PairSamples, SplitSweep, Sweep,
};
use crate::par::prelude::*;
use crate::side::{ConfigId, PerSide, Side};
use nalgebra::{Isometry3, Point3, Vector3};

/// Why a model's figures cannot be computed.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum AnalysisError {
    /// The accuracy metrics (too few configurations, non-finite values).
    #[error(transparent)]
    Metrics(#[from] MetricsError),
    /// The measured points are too few or (nearly) collinear to place the tracker frame.
    #[error("cannot register the tracker frame to the robot (degenerate points)")]
    Registration,
}

/// Which accuracy indicator: relative (one arm) or collaborative, position or orientation.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Indicator {
    RelativePosition(Side),
    RelativeOrientation(Side),
    CollaborativePosition,
    CollaborativeOrientation,
}

impl Indicator {
    pub const ALL: [Indicator; 6] = [
        Indicator::RelativePosition(Side::Left),
        Indicator::RelativePosition(Side::Right),
        Indicator::CollaborativePosition,
        Indicator::RelativeOrientation(Side::Left),
        Indicator::RelativeOrientation(Side::Right),
        Indicator::CollaborativeOrientation,
    ];

    pub fn label(self) -> String {
        match self {
            Indicator::RelativePosition(s) => format!("relative Δd, {s} arm (mm)"),
            Indicator::RelativeOrientation(s) => format!("relative Δo, {s} arm (rad)"),
            Indicator::CollaborativePosition => "collaborative Δd (mm)".into(),
            Indicator::CollaborativeOrientation => "collaborative Δo (rad)".into(),
        }
    }

    pub fn is_position(self) -> bool {
        matches!(
            self,
            Indicator::RelativePosition(_) | Indicator::CollaborativePosition
        )
    }

    pub fn pair_kind(self) -> PairKind {
        match self {
            Indicator::RelativePosition(s) | Indicator::RelativeOrientation(s) => {
                PairKind::Relative(s)
            }
            Indicator::CollaborativePosition | Indicator::CollaborativeOrientation => {
                PairKind::Collaborative
            }
        }
    }

    /// The matching summary line of a report: (rms, max, [frequency within the two thresholds]);
    /// `None` for an orientation indicator the data cannot measure (fewer than three reflectors).
    pub fn summary(self, report: &AccuracyReport) -> Option<(f64, f64, [f64; 2])> {
        let stats = report.stats(self.pair_kind())?;
        if self.is_position() {
            Some((
                stats.pos_rms_mm,
                stats.pos_max_mm,
                [stats.pos_within_0_3mm_frac, stats.pos_within_0_6mm_frac],
            ))
        } else {
            Some((
                stats.ori_rms_rad?,
                stats.ori_max_rad?,
                [
                    stats.ori_within_0_005rad_frac?,
                    stats.ori_within_0_01rad_frac?,
                ],
            ))
        }
    }
}

/// Bars of the accuracy histograms.
pub const HISTOGRAM_BINS: usize = 41;

/// A histogram of one indicator's samples over `[lo, hi]` in equal-width bins.
#[derive(Clone, Debug, PartialEq)]
pub struct Histogram {
    pub lo: f64,
    pub hi: f64,
    /// Fraction (0..1) of all samples in each bin; samples outside the range count in the end bins.
    pub fractions: Vec<f64>,
    /// How many samples: one per pair and reflector for `Δd`, one per pair for `Δo` (none when the
    /// orientation is not measurable).
    pub samples: usize,
}

impl Histogram {
    /// Bin `samples` into `bins` bars over `[lo, hi]`. Non-finite samples count in the total only.
    pub fn of(samples: &[f32], lo: f64, hi: f64, bins: usize) -> Self {
        let bins = bins.max(1);
        let per_width = bins as f64 / (hi - lo);
        let counts = samples
            .par_chunks(1 << 15)
            .fold(
                || vec![0usize; bins],
                |mut counts, chunk| {
                    for &s in chunk.iter().filter(|s| s.is_finite()) {
                        // `as` truncates towards zero and saturates: below `lo` is bin 0.
                        let k = ((f64::from(s) - lo) * per_width) as usize;
                        counts[k.min(bins - 1)] += 1;
                    }
                    counts
                },
            )
            .reduce(
                || vec![0usize; bins],
                |mut a, b| {
                    a.iter_mut().zip(b).for_each(|(x, y)| *x += y);
                    a
                },
            );
        let n = samples.len().max(1) as f64;
        Self {
            lo,
            hi,
            fractions: counts.into_iter().map(|c| c as f64 / n).collect(),
            samples: samples.len(),
        }
    }

    pub fn bin_width(&self) -> f64 {
        (self.hi - self.lo) / self.fractions.len().max(1) as f64
    }

    /// (bin centre, fraction) of every bin.
    pub fn bars(&self) -> impl Iterator<Item = (f64, f64)> + '_ {
        let width = self.bin_width();
        self.fractions
            .iter()
            .enumerate()
            .map(move |(k, &f)| (self.lo + (k as f64 + 0.5) * width, f))
    }

    /// The histogram of an indicator on one split: every reflector's signed `Δd` over `±` the largest
    /// `|Δd|`, or `Δo` from zero to the largest.
    fn of_indicator(indicator: Indicator, split: &SplitSweep) -> Self {
        let samples = split.samples(indicator.pair_kind());
        let Some((_, max, _)) = indicator.summary(&split.report) else {
            return Self::of(&[], 0.0, 1.0, HISTOGRAM_BINS);
        };
        let extent = max.max(1e-9);
        if indicator.is_position() {
            Self::of(&samples.pos_mm, -extent, extent, HISTOGRAM_BINS)
        } else {
            Self::of(&samples.ori_rad, 0.0, extent, HISTOGRAM_BINS)
        }
    }
}

/// One configuration as drawn and listed: identity, errors and its reflector points in the body frame.
#[derive(Clone, Debug)]
pub struct ConfigRow {
    pub config: ConfigId,
    pub id: String,
    pub split: Split,
    /// Largest |Δd| over every pair (relative and collaborative) involving it, mm.
    pub worst_pos_mm: f64,
    /// Largest Δo over every pair involving it, rad; `None`: not measurable (fewer than three
    /// reflectors).
    pub worst_ori_rad: Option<f64>,
    /// Largest deviation of the measured distances between its reflectors from the model's, mm.
    pub rigidity_mm: f64,
    /// Measured points of its reflectors (a, b, c) in the body frame (after registration), mm.
    pub measured_body_mm: Vec<Vector3<f64>>,
    /// Model points of its reflectors in the body frame, mm.
    pub model_body_mm: Vec<Vector3<f64>>,
    /// Left out of the calibration and of the accuracy figures (its own errors are still listed).
    pub excluded: bool,
}

impl ConfigRow {
    /// Distance between measured and model point of each reflector after registration, mm.
    pub fn point_errors_mm(&self) -> Vec<f64> {
        self.measured_body_mm
            .iter()
            .zip(&self.model_body_mm)
            .map(|(m, p)| (m - p).norm())
            .collect()
    }
}

/// One pair kind's residuals as the paper's histograms and box plots show them.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct WorstSamples {
    /// Per pair the signed `Δd` of the reflector with the largest `|Δd|` ("the worst case among the
    /// three errors", Figs. 6 and 8), mm.
    pub pos_mm: Vec<f32>,
    /// Per pair `Δo`, rad.
    pub ori_rad: Vec<f32>,
}

/// The figures of one split: its accuracy report, the histograms of its six indicators and the
/// paper's samples of each (none of them when the split has too few configurations).
#[derive(Clone, Debug, Default)]
pub struct SplitFigures {
    pub report: Option<AccuracyReport>,
    /// In [`Indicator::ALL`] order.
    histograms: Vec<Histogram>,
    /// Left arm's relative pairs, the right arm's, the collaborative pairs.
    worst: [WorstSamples; 3],
}

impl SplitFigures {
    fn of(split: Option<SplitSweep>) -> Self {
        let Some(split) = split else {
            return Self::default();
        };
        let histograms = Indicator::ALL
            .iter()
            .map(|&i| Histogram::of_indicator(i, &split))
            .collect();
        let SplitSweep { report, samples } = split;
        Self {
            report: Some(report),
            histograms,
            worst: samples.map(|s| WorstSamples {
                pos_mm: worst_reflector_mm(&s),
                ori_rad: s.ori_rad,
            }),
        }
    }

    /// The histogram of one indicator (every reflector's signed `Δd`, or `Δo`, over the largest
    /// magnitude).
    pub fn histogram(&self, indicator: Indicator) -> Option<&Histogram> {
        let k = Indicator::ALL.iter().position(|&i| i == indicator)?;
        self.histograms.get(k)
    }

    /// The samples of `indicator` as the paper's histograms and box plots show them
    /// ([`WorstSamples`]); `None` when the split has too few configurations.
    pub fn samples(&self, indicator: Indicator) -> Option<&[f32]> {
        self.report.as_ref()?;
        let s = &self.worst[match indicator.pair_kind() {
            PairKind::Relative(Side::Left) => 0,
            PairKind::Relative(Side::Right) => 1,
            PairKind::Collaborative => 2,
        }];
        Some(if indicator.is_position() {
            &s.pos_mm
        } else {
            &s.ori_rad
        })
    }
}

/// Per pair, the signed `Δd` of largest magnitude among the reflectors.
pub fn worst_reflector_mm(samples: &PairSamples) -> Vec<f32> {
    samples
        .pos_mm
        .par_chunks_exact(samples.reflectors.max(1))
        .map(|d| {
            d.iter()
                .copied()
                .fold(0.0, |w: f32, x| if x.abs() > w.abs() { x } else { w })
        })
        .collect()
}

/// The figures of one model on one dataset, without the configurations it [`excluded`](Self::excluded).
#[derive(Clone, Debug)]
pub struct Analysis {
    pub model: DualArmModel,
    /// Figures of the calibration configurations.
    pub cal: SplitFigures,
    /// Figures of the verification configurations.
    pub ver: SplitFigures,
    /// Every configuration of both arms (left first).
    pub configs: Vec<ConfigRow>,
    /// Tracker → left DH base registration used for drawing (the left arm's station's, where the
    /// arms were measured from two).
    pub left_base_from_tracker: Isometry3<f64>,
    /// Each arm's registration: the same one for both arms measured in one tracker frame, each arm's
    /// own where they were measured from two stations.
    pub left_base_from_station: PerSide<Isometry3<f64>>,
    /// RMS of the registration residuals, mm.
    pub registration_rms_mm: f64,
    /// The configurations left out of the figures (indices into the loaded dataset).
    pub excluded: Vec<ConfigId>,
}

impl Analysis {
    /// The figures of `split` (`None` for `All`, which is not computed).
    pub fn figures(&self, split: Split) -> Option<&SplitFigures> {
        match split {
            Split::Cal => Some(&self.cal),
            Split::Ver => Some(&self.ver),
            Split::All => None,
        }
    }

    /// The accuracy report of `split` (`None` for `All` and for a split with too few configurations).
    pub fn report(&self, split: Split) -> Option<&AccuracyReport> {
        self.figures(split)?.report.as_ref()
    }

    /// The samples of `indicator` on `split` as the paper's histograms and box plots show them
    /// ([`SplitFigures::samples`]).
    pub fn samples(&self, split: Split, indicator: Indicator) -> Option<&[f32]> {
        self.figures(split)?.samples(indicator)
    }

    /// Compute the figures of `model` on `dataset`; `body_from_left_base` places the drawing. Every pair
    /// of configurations is visited once ([`metrics::sweep`]); this is what the workbench recomputes
    /// for the live view while a calibration runs (`cargo bench --bench analysis`).
    pub fn compute(
        dataset: &Dataset,
        model: &DualArmModel,
        body_from_left_base: &Isometry3<f64>,
    ) -> Result<Self, AnalysisError> {
        Self::compute_excluding(dataset, model, body_from_left_base, &[])
    }

    /// [`compute`](Self::compute) with the configurations `exclude` left out of the accuracy figures
    /// and of the registration (as `dualcal calibrate --exclude` leaves them out of its tables). Every
    /// configuration still has its row, marked [`ConfigRow::excluded`], with its errors against the
    /// others: an excluded outlier still shows why it was left out.
    pub fn compute_excluding(
        dataset: &Dataset,
        model: &DualArmModel,
        body_from_left_base: &Isometry3<f64>,
        exclude: &[ConfigId],
    ) -> Result<Self, AnalysisError> {
        let Sweep {
            per_config,
            cal,
            ver,
        } = metrics::sweep(dataset, model)?;
        let (cal, ver) = if exclude.is_empty() {
            (cal, ver)
        } else {
            let kept = metrics::sweep(&dataset.excluding(exclude), model)?;
            (kept.cal, kept.ver)
        };

        // Model points in the left base, and the registration of the tracker onto them.
        let model_left = model_points_in_left_base(dataset, model);
        let (left_base_from_station, registration_rms_mm) =
            register_stations(dataset, &model_left, exclude)?;
        let one_frame = dataset.one_tracker_frame();
        let measured = || {
            Side::BOTH
                .into_iter()
                .flat_map(|side| &dataset.arm(side).measurements)
        };
        let left_base_from_tracker = left_base_from_station.left;

        // The sweep lists every configuration, in the same order (left arm first).
        debug_assert_eq!(per_config.len(), model_left.len());
        let body_from_station = left_base_from_station.map(|_, r| body_from_left_base * r);
        let configs = measured()
            .zip(per_config)
            .zip(model_left)
            .map(|((m, c), model_pts)| {
                let body_from_tracker = body_from_station[c.config.side];
                // Without a common frame the collaborative figures do not exist.
                let worst_pos_mm = c
                    .collaborative_pos_max_mm
                    .map_or(c.relative_pos_max_mm, |o| c.relative_pos_max_mm.max(o));
                let worst_ori_rad = match (c.relative_ori_max_rad, c.collaborative_ori_max_rad) {
                    (Some(r), Some(o)) if one_frame => Some(r.max(o)),
                    (r, _) => r,
                };
                ConfigRow {
                    config: c.config,
                    id: m.id.clone(),
                    split: m.split,
                    worst_pos_mm,
                    worst_ori_rad,
                    rigidity_mm: c.rigidity_mm,
                    measured_body_mm: m
                        .tracker_points_mm
                        .iter()
                        .map(|p| (body_from_tracker * Point3::from(*p)).coords)
                        .collect(),
                    model_body_mm: model_pts
                        .iter()
                        .map(|p| (body_from_left_base * Point3::from(*p)).coords)
                        .collect(),
                    excluded: exclude.contains(&c.config),
                }
            })
            .collect();
        Ok(Self {
            model: model.clone(),
            cal: SplitFigures::of(cal),
            ver: SplitFigures::of(ver),
            configs,
            left_base_from_tracker,
            left_base_from_station,
            registration_rms_mm,
            excluded: exclude.to_vec(),
        })
    }
}

/// Every configuration's model reflector points in the left-arm base frame, the left arm's rows first.
fn model_points_in_left_base(dataset: &Dataset, model: &DualArmModel) -> Vec<Vec<Vector3<f64>>> {
    let mut model_left: Vec<Vec<Vector3<f64>>> = Vec::new();
    for side in Side::BOTH {
        let arm = model.arm(side);
        let left_base_from_base = model.left_base_from(side);
        let points: Vec<Vec<Vector3<f64>>> = dataset
            .arm(side)
            .measurements
            .par_iter()
            .map(|m| {
                arm.reflector_fk(&m.q_rad)
                    .points_mm
                    .iter()
                    .map(|p| (left_base_from_base * Point3::from(*p)).coords)
                    .collect()
            })
            .collect();
        model_left.extend(points);
    }
    model_left
}

/// The registration of the tracker's points onto the model's (`model_left`, the rows of
/// [`model_points_in_left_base`]) over the configurations kept: `left_base_from_station` per arm — one
/// registration of every kept point, or one per arm where the arms were measured from two stations
/// (their coordinates lie in unrelated frames) — and its RMS residual, mm.
fn register_stations(
    dataset: &Dataset,
    model_left: &[Vec<Vector3<f64>>],
    exclude: &[ConfigId],
) -> Result<(PerSide<Isometry3<f64>>, f64), AnalysisError> {
    let measured = || {
        Side::BOTH
            .into_iter()
            .flat_map(|side| &dataset.arm(side).measurements)
    };
    // The registration uses the configurations kept (an outlier would pull every drawn point).
    let kept = |side: Side, i: usize| !exclude.contains(&ConfigId::new(side, i));
    let kept_flags: Vec<bool> = Side::BOTH
        .into_iter()
        .flat_map(|side| (0..dataset.arm(side).measurements.len()).map(move |i| kept(side, i)))
        .collect();
    let n_left = dataset.arms.left.measurements.len();
    let side_of = |row: usize| {
        if row < n_left {
            Side::Left
        } else {
            Side::Right
        }
    };
    let register = |only: Option<Side>| -> Result<(Isometry3<f64>, f64, usize), AnalysisError> {
        let take = |row: usize| kept_flags[row] && only.is_none_or(|s| side_of(row) == s);
        let from: Vec<Vector3<f64>> = measured()
            .enumerate()
            .filter(|(row, _)| take(*row))
            .flat_map(|(_, m)| m.tracker_points_mm.iter().copied())
            .collect();
        let to: Vec<Vector3<f64>> = model_left
            .iter()
            .enumerate()
            .filter(|(row, _)| take(*row))
            .flat_map(|(_, p)| p.iter().copied())
            .collect();
        let fit = best_fit_rigid(&from, &to).ok_or(AnalysisError::Registration)?;
        let sum_sq: f64 = from
            .iter()
            .zip(&to)
            .map(|(p, q)| ((fit * Point3::from(*p)).coords - q).norm_squared())
            .sum();
        Ok((fit, sum_sq, from.len()))
    };
    if dataset.one_tracker_frame() || !dataset.both_measured() {
        // One frame, or one arm alone: one registration of every point.
        let (fit, sum_sq, n) = register(None)?;
        Ok((PerSide::new(fit, fit), (sum_sq / n.max(1) as f64).sqrt()))
    } else {
        let (l, r) = (register(Some(Side::Left))?, register(Some(Side::Right))?);
        Ok((
            PerSide::new(l.0, r.0),
            ((l.1 + r.1) / (l.2 + r.2).max(1) as f64).sqrt(),
        ))
    }
}

/// Least-squares rigid transform `to_from_from` with `to ≈ T · from` over all point pairs
/// (Kabsch/Umeyama without scale, `det R = +1`, [`crate::metrics::kabsch_fit_points`]). `None` with fewer
/// than 3 pairs, non-finite input or (nearly) collinear points.
pub fn best_fit_rigid(from: &[Vector3<f64>], to: &[Vector3<f64>]) -> Option<Isometry3<f64>> {
    if from.len() != to.len() || from.len() < 3 {
        return None;
    }
    let fit = crate::metrics::kabsch_fit_points(from, to)?;
    (!fit.is_degenerate()).then(|| fit.isometry())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn recovers_a_known_transform_from_noisy_points() {
        let truth = Isometry3::new(
            Vector3::new(1500.0, -300.0, 200.0),
            Vector3::new(0.3, -1.1, 2.0),
        );
        let from: Vec<Vector3<f64>> = (0..50)
            .map(|k| {
                let t = k as f64;
                Vector3::new((t * 0.7).sin() * 400.0, (t * 1.3).cos() * 300.0, t * 10.0)
            })
            .collect();
        let to: Vec<Vector3<f64>> = from
            .iter()
            .enumerate()
            .map(|(k, p)| {
                truth * nalgebra::Point3::from(*p) + Vector3::repeat(0.01 * ((k % 3) as f64 - 1.0))
            })
            .map(|p| p.coords)
            .collect();
        let fit = best_fit_rigid(&from, &to).unwrap();
        let err = (fit.translation.vector - truth.translation.vector).norm();
        assert!(err < 0.05, "translation error {err} mm");
        assert!(fit.rotation.angle_to(&truth.rotation) < 1e-4);
    }

    #[test]
    fn worst_reflector_keeps_the_sign_of_the_largest_magnitude() {
        let s = PairSamples {
            reflectors: 3,
            pos_mm: vec![0.1, -0.3, 0.2, 0.5, 0.0, -0.1, 0.0, 0.0, 0.0],
            ori_rad: vec![0.0; 3],
        };
        assert_eq!(worst_reflector_mm(&s), vec![-0.3, 0.5, 0.0]);
    }

    #[test]
    fn histogram_counts_every_sample_once() {
        let samples = [-1.0, -0.5, 0.0, 0.49, 0.5, 1.0, 7.0, -7.0];
        let h = Histogram::of(&samples, -1.0, 1.0, 4);
        let total: f64 = h.fractions.iter().sum();
        assert!((total - 1.0).abs() < 1e-12);
        // Out-of-range samples land in the end bins.
        assert!((h.fractions[0] - 2.0 / 8.0).abs() < 1e-12, "{h:?}");
        assert!((h.fractions[3] - 3.0 / 8.0).abs() < 1e-12, "{h:?}");
        let bars: Vec<(f64, f64)> = h.bars().collect();
        assert!((bars[0].0 + 0.75).abs() < 1e-12);
        assert_eq!(h.samples, 8);
    }

    #[test]
    fn never_returns_a_reflection() {
        // Mirror image: the best proper rotation still has det +1.
        let from = [
            Vector3::new(0.0, 0.0, 0.0),
            Vector3::new(1.0, 0.0, 0.0),
            Vector3::new(0.0, 1.0, 0.0),
            Vector3::new(0.0, 0.0, 1.0),
        ];
        let to: Vec<_> = from.iter().map(|p| Vector3::new(-p.x, p.y, p.z)).collect();
        let fit = best_fit_rigid(&from, &to).unwrap();
        assert!((fit.rotation.to_rotation_matrix().matrix().determinant() - 1.0).abs() < 1e-9);
    }

    #[test]
    fn refuses_degenerate_input() {
        let line: Vec<_> = (0..5).map(|k| Vector3::new(k as f64, 0.0, 0.0)).collect();
        assert!(best_fit_rigid(&line, &line).is_none());
        assert!(best_fit_rigid(&line[..2], &line[..2]).is_none());
        let nan = vec![Vector3::new(f64::NAN, 0.0, 0.0); 4];
        assert!(best_fit_rigid(&nan, &nan).is_none());
    }
}
