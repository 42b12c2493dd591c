//! The figures of a model on a dataset, as the workbench shows them: accuracy reports and pair
//! residuals of the calibration and verification splits, a row per configuration, and the tracker →
//! robot registration that places the measured points next to the model's for drawing (the
//! calibration itself never needs it: it works on distances).

use crate::dataset::{Dataset, Split};
use crate::kinematics::DualArmModel;
use crate::metrics::{self, AccuracyReport, ConfigResiduals, PairKind, PairResiduals};
use crate::side::{ConfigId, PerSide, Side};
use anyhow::Context as _;
use nalgebra::{Isometry3, Point3, Vector3};

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

    /// The matching summary line of a report: (rms, max, [frequency within the two thresholds]).
    pub fn summary(self, report: &AccuracyReport) -> (f64, f64, [f64; 2]) {
        let stats = match self.pair_kind() {
            PairKind::Relative(side) => report.relative(side),
            PairKind::Collaborative => &report.collaborative,
        };
        if self.is_position() {
            (
                stats.pos_rms_mm,
                stats.pos_max_mm,
                [stats.pos_within_0_3mm_frac, stats.pos_within_0_6mm_frac],
            )
        } else {
            (
                stats.ori_rms_rad,
                stats.ori_max_rad,
                [
                    stats.ori_within_0_005rad_frac,
                    stats.ori_within_0_01rad_frac,
                ],
            )
        }
    }
}

/// The pair residuals of one split for the three pair kinds (left, right, collaborative).
#[derive(Clone, Debug, Default)]
pub struct PairSet {
    pub relative: PerSide<Vec<PairResiduals>>,
    pub collaborative: Vec<PairResiduals>,
}

impl PairSet {
    pub fn of(&self, kind: PairKind) -> &[PairResiduals] {
        match kind {
            PairKind::Relative(side) => &self.relative[side],
            PairKind::Collaborative => &self.collaborative,
        }
    }

    /// Histogram samples of an indicator: every reflector's signed Δd (mm) or Δo (rad).
    pub fn samples(&self, indicator: Indicator) -> Vec<f64> {
        let pairs = self.of(indicator.pair_kind());
        if indicator.is_position() {
            pairs.iter().flat_map(|p| p.pos_error_mm).collect()
        } else {
            pairs.iter().map(|p| p.ori_error_rad).collect()
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
    /// Largest Δo over every pair involving it, rad.
    pub worst_ori_rad: f64,
    /// Largest deviation of the measured triangle's sides from the model's, mm.
    pub rigidity_mm: f64,
    /// Measured points a, b, c in the body frame (after registration), mm.
    pub measured_body_mm: [Vector3<f64>; 3],
    /// Model points a, b, c in the body frame, mm.
    pub model_body_mm: [Vector3<f64>; 3],
}

impl ConfigRow {
    /// Distance between measured and model point of each reflector after registration, mm.
    pub fn point_errors_mm(&self) -> [f64; 3] {
        std::array::from_fn(|k| (self.measured_body_mm[k] - self.model_body_mm[k]).norm())
    }
}

/// The figures of one split: its accuracy report and pair residuals (both empty when the split has
/// too few configurations).
#[derive(Clone, Debug, Default)]
pub struct SplitFigures {
    pub report: Option<AccuracyReport>,
    pub pairs: PairSet,
}

/// Everything derived from one model on one dataset.
#[derive(Clone, Debug)]
pub struct Analysis {
    pub model: DualArmModel,
    /// Figures of the calibration configurations.
    pub cal: SplitFigures,
    /// Figures of the verification configurations.
    pub ver: SplitFigures,
    /// Every configuration of both arms (left first).
    pub configs: Vec<ConfigRow>,
    /// Tracker → left DH base registration used for drawing.
    pub left_base_from_tracker: Isometry3<f64>,
    /// RMS of the registration residuals, mm.
    pub registration_rms_mm: f64,
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

    /// Compute the figures of `model` on `dataset`; `body_from_left_base` places the drawing.
    pub fn compute(
        dataset: &Dataset,
        model: &DualArmModel,
        body_from_left_base: &Isometry3<f64>,
    ) -> anyhow::Result<Self> {
        let figures = |split: Split| -> anyhow::Result<SplitFigures> {
            // A split may be absent (datasets without a `split` column are all `cal`).
            let Ok(report) = metrics::evaluate(dataset, model, split) else {
                return Ok(SplitFigures::default());
            };
            let get = |kind| metrics::pairs(dataset, model, split, kind);
            Ok(SplitFigures {
                report: Some(report),
                pairs: PairSet {
                    relative: PerSide::try_from_fn(|side| get(PairKind::Relative(side)))?,
                    collaborative: get(PairKind::Collaborative)?,
                },
            })
        };
        let (cal, ver) = (figures(Split::Cal)?, figures(Split::Ver)?);
        let per_config: Vec<ConfigResiduals> =
            metrics::per_config(dataset, model, Split::All).context("per-configuration errors")?;

        // Model points in the left base, and the registration of the tracker onto them.
        let mut model_left: Vec<[Vector3<f64>; 3]> = Vec::new();
        let mut from = Vec::new();
        let mut to = Vec::new();
        for side in Side::BOTH {
            let arm = model.arm(side);
            let left_base_from_base = model.left_base_from(side);
            for m in &dataset.arm(side).measurements {
                let fk = arm.reflector_fk(&m.q_rad);
                let pts = fk
                    .points_mm
                    .map(|p| (left_base_from_base * Point3::from(p)).coords);
                from.extend(m.tracker_points_mm);
                to.extend(pts);
                model_left.push(pts);
            }
        }
        let left_base_from_tracker = best_fit_rigid(&from, &to)
            .context("cannot register the tracker frame to the robot (degenerate points)")?;
        let sum_sq: f64 = from
            .iter()
            .zip(&to)
            .map(|(p, q)| ((left_base_from_tracker * Point3::from(*p)).coords - q).norm_squared())
            .sum();
        let registration_rms_mm = (sum_sq / from.len().max(1) as f64).sqrt();

        let body_from_tracker = body_from_left_base * left_base_from_tracker;
        let mut configs = Vec::with_capacity(model_left.len());
        let mut n = 0;
        for side in Side::BOTH {
            for (index, m) in dataset.arm(side).measurements.iter().enumerate() {
                let model_pts = model_left[n];
                n += 1;
                let err = per_config
                    .iter()
                    .find(|c| c.config == ConfigId::new(side, index));
                let (worst_pos_mm, worst_ori_rad, rigidity_mm) =
                    err.map_or((f64::NAN, f64::NAN, f64::NAN), |c| {
                        (
                            c.relative_pos_max_mm.max(c.collaborative_pos_max_mm),
                            c.relative_ori_max_rad.max(c.collaborative_ori_max_rad),
                            c.rigidity_mm,
                        )
                    });
                configs.push(ConfigRow {
                    config: ConfigId::new(side, index),
                    id: m.id.clone(),
                    split: m.split,
                    worst_pos_mm,
                    worst_ori_rad,
                    rigidity_mm,
                    measured_body_mm: m
                        .tracker_points_mm
                        .map(|p| (body_from_tracker * Point3::from(p)).coords),
                    model_body_mm: model_pts
                        .map(|p| (body_from_left_base * Point3::from(p)).coords),
                });
            }
        }
        Ok(Self {
            model: model.clone(),
            cal,
            ver,
            configs,
            left_base_from_tracker,
            registration_rms_mm,
        })
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
