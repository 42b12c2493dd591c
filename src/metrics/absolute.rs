//! Absolute positioning figures: how far the model puts each measured reflector from where the
//! tracker (or camera) saw it, `|m_ik − T · p_ik|`, with `T` the tracker-from-base transform a method
//! identified (the absolute methods, refs. [18], [19], [28]). Only where that frame is known: the
//! distance methods never see it, and their models have no absolute figures.

use super::MetricsError;
use crate::dataset::{Dataset, Split};
use crate::kinematics::DualArmModel;
use crate::side::{PerSide, Side};
use nalgebra::{Isometry3, Point3};
use serde::{Deserialize, Serialize};

/// Absolute position errors over the measured reflectors of one split (both arms' points that have a
/// tracker frame), mm.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct AbsoluteStats {
    pub mean_mm: f64,
    pub rms_mm: f64,
    pub max_mm: f64,
    /// Measured points in the figures (configurations × reflectors).
    pub n_points: usize,
}

/// One measured point's absolute error.
#[derive(Clone, Debug, PartialEq)]
pub struct AbsoluteError {
    pub side: Side,
    /// The configuration's id.
    pub id: String,
    /// Index of the reflector (the dataset's order).
    pub reflector: usize,
    pub error_mm: f64,
}

/// Every measured point's absolute error under `model` on `split` (left arm first, file order), each
/// arm's points placed by its `tracker_from_base` frame; arms without a frame are left out.
pub fn absolute_errors(
    dataset: &Dataset,
    model: &DualArmModel,
    tracker_from_base: &PerSide<Option<Isometry3<f64>>>,
    split: Split,
) -> Result<Vec<AbsoluteError>, MetricsError> {
    let mut out = Vec::new();
    for side in Side::BOTH {
        let Some(t) = tracker_from_base[side] else {
            continue;
        };
        let arm = model.arm(side);
        for m in dataset.arm(side).select(split) {
            if m.q_rad.len() != arm.joint_count() {
                return Err(MetricsError::JointCount {
                    side,
                    id: m.id.clone(),
                    found: m.q_rad.len(),
                    expected: arm.joint_count(),
                });
            }
            let points = arm.reflector_fk(&m.q_rad).points_mm;
            for (k, (p, measured)) in points.iter().zip(&m.tracker_points_mm).enumerate() {
                out.push(AbsoluteError {
                    side,
                    id: m.id.clone(),
                    reflector: k,
                    error_mm: (measured - (t * Point3::from(*p)).coords).norm(),
                });
            }
        }
    }
    Ok(out)
}

/// The absolute position errors of `model` on `split` summarised ([`absolute_errors`]). `None` when
/// no arm has both a frame and measurements.
pub fn absolute_stats(
    dataset: &Dataset,
    model: &DualArmModel,
    tracker_from_base: &PerSide<Option<Isometry3<f64>>>,
    split: Split,
) -> Result<Option<AbsoluteStats>, MetricsError> {
    let errors_mm: Vec<f64> = absolute_errors(dataset, model, tracker_from_base, split)?
        .iter()
        .map(|e| e.error_mm)
        .collect();
    if errors_mm.is_empty() {
        return Ok(None);
    }
    let n = errors_mm.len() as f64;
    let stats = AbsoluteStats {
        mean_mm: errors_mm.iter().sum::<f64>() / n,
        rms_mm: (errors_mm.iter().map(|e| e * e).sum::<f64>() / n).sqrt(),
        max_mm: errors_mm.iter().copied().fold(0.0, f64::max),
        n_points: errors_mm.len(),
    };
    if ![stats.mean_mm, stats.rms_mm, stats.max_mm]
        .iter()
        .all(|v| v.is_finite())
    {
        return Err(MetricsError::NonFiniteResult {
            what: "the absolute position errors".into(),
        });
    }
    Ok(Some(stats))
}
