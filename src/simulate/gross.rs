//! Gross errors of real measurement files, injected into simulated data for the outlier study
//! (`dualcal reproduce outliers`, docs/reliability.md): a reflector misread, reflector labels swapped
//! in a row, a row of the other arm.

use super::{SimOptions, gauss, gauss3, rng_for};
use crate::dataset::ArmData;
use crate::side::{ConfigId, PerSide, Side};
use nalgebra::Vector3;
use rand::Rng;

/// How many configurations of each arm get which gross error (`round(fraction · configurations)`
/// each; the configurations are chosen at random and distinct).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GrossErrorModel {
    /// Configurations with one reflector (at random) misread by a distance uniform in `misread_mm`,
    /// in a uniformly random direction.
    pub misread_fraction: f64,
    pub misread_mm: (f64, f64),
    /// Configurations with two reflector labels (at random: a↔b, b↔c or a↔c) swapped.
    pub swapped_labels_fraction: f64,
    /// Configurations replaced by a configuration of the other arm (its joint values and a new
    /// measurement of its reflectors: tracker noise again).
    pub other_arm_fraction: f64,
}

impl GrossErrorModel {
    /// The study's mixture: 3% misread by 0.5–5 mm, 1% swapped labels, 1% rows of the other arm.
    pub fn study() -> Self {
        Self {
            misread_fraction: 0.03,
            misread_mm: (0.5, 5.0),
            swapped_labels_fraction: 0.01,
            other_arm_fraction: 0.01,
        }
    }
}

/// What was done to one configuration.
#[derive(Clone, Debug, PartialEq)]
pub enum GrossError {
    /// Reflector `reflector` displaced by `displacement_mm` (tracker frame).
    Misread {
        reflector: usize,
        displacement_mm: Vector3<f64>,
    },
    /// The measured points of reflectors `labels.0` and `labels.1` exchanged.
    SwappedLabels { labels: (usize, usize) },
    /// Replaced by configuration `source` of the other arm.
    OtherArm { source: usize },
}

/// One injected gross error.
#[derive(Clone, Debug, PartialEq)]
pub struct GrossErrorRecord {
    pub config: ConfigId,
    pub id: String,
    pub error: GrossError,
}

/// Inject `model`'s gross errors into both arms (left first). The other-arm rows are taken from the
/// other arm's measurements before any injection.
pub(super) fn inject(
    opts: &SimOptions,
    model: &GrossErrorModel,
    arms: &mut PerSide<ArmData>,
) -> Vec<GrossErrorRecord> {
    let mut rng = rng_for(opts.seed, super::STREAM_GROSS);
    let clean = arms.clone();
    let mut out = Vec::new();
    for side in Side::BOTH {
        let n = arms[side].measurements.len();
        let count = |f: f64| ((f * n as f64).round() as usize).min(n);
        let counts = [
            count(model.misread_fraction),
            count(model.swapped_labels_fraction),
            count(model.other_arm_fraction),
        ];
        let total = counts.iter().sum::<usize>().min(n);
        let picked = rand::seq::index::sample(&mut rng, n, total).into_vec();
        let mut kinds = picked.into_iter();
        for (kind, &c) in counts.iter().enumerate() {
            for index in kinds.by_ref().take(c) {
                let sigma_mm = 0.5 * opts.tracker.mpe_um / 1000.0;
                let m = &mut arms[side].measurements[index];
                let error = match kind {
                    0 => {
                        let reflector = rng.random_range(0..3);
                        let size = rng.random_range(model.misread_mm.0..=model.misread_mm.1);
                        let dir = loop {
                            let v = gauss3(&mut rng);
                            if v.norm() > 1e-6 {
                                break v.normalize();
                            }
                        };
                        m.tracker_points_mm[reflector] += size * dir;
                        GrossError::Misread {
                            reflector,
                            displacement_mm: size * dir,
                        }
                    }
                    1 => {
                        let labels = [(0, 1), (1, 2), (0, 2)][rng.random_range(0..3)];
                        m.tracker_points_mm.swap(labels.0, labels.1);
                        GrossError::SwappedLabels { labels }
                    }
                    _ => {
                        let others = &clean[side.other()].measurements;
                        let source = rng.random_range(0..others.len());
                        m.q_rad = others[source].q_rad.clone();
                        m.tracker_points_mm = others[source]
                            .tracker_points_mm
                            .iter()
                            .map(|p| {
                                p + Vector3::new(gauss(&mut rng), gauss(&mut rng), gauss(&mut rng))
                                    * sigma_mm
                            })
                            .collect();
                        GrossError::OtherArm { source }
                    }
                };
                out.push(GrossErrorRecord {
                    config: ConfigId::new(side, index),
                    id: m.id.clone(),
                    error,
                });
            }
        }
    }
    crate::sort::sort_by_key(&mut out, |r| r.config);
    out
}
