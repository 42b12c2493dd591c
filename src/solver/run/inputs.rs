//! What a run checks before any work: settings that fit together, each arm's selected data (enough
//! configurations, joint and reflector counts, finite values) and a method that can fit the robot.

use crate::dataset::Dataset;
use crate::kinematics::{DualArmModel, SharedJoints};
use crate::side::{ConfigId, Side};
use crate::solver::error::CalibrationError;
use crate::solver::methods::set_up::ArmData;
use crate::solver::methods::table::Method;
use crate::solver::settings::CalibrationSettings;
use crate::solver::types::{Stage, identifiable_params};
use nalgebra::Vector3;

/// Settings that cannot work together are refused before any work.
pub(super) fn check_settings(settings: &CalibrationSettings) -> Result<(), CalibrationError> {
    if settings.hold_kinematics && !settings.method.is_absolute() {
        return Err(CalibrationError::InvalidSettings(format!(
            "holding the kinematics (fitting only the tracker frame and the reflectors) needs a \
             method that identifies the tracker frame (`position` or `pose`), not `{}`",
            settings.method.name()
        )));
    }
    if let Some(r) = settings.reflector
        && !settings.method.spec().takes_reflector
    {
        let takers = Method::ALL
            .iter()
            .filter(|m| m.spec().takes_reflector)
            .map(|m| format!("`{}`", m.name()))
            .collect::<Vec<_>>()
            .join(" or ");
        return Err(CalibrationError::InvalidSettings(format!(
            "a reflector ({r}) can only be chosen for method {takers}; `{}` uses all three",
            settings.method.name()
        )));
    }
    Ok(())
}

/// The selected split of one arm, checked.
pub(super) fn arm_input(
    dataset: &Dataset,
    nominal: &DualArmModel,
    side: Side,
    settings: &CalibrationSettings,
) -> Result<ArmData, CalibrationError> {
    let ms: Vec<&crate::dataset::Measurement> = dataset
        .arm(side)
        .measurements
        .iter()
        .enumerate()
        .filter(|(i, m)| {
            settings.split.contains(m.split) && !settings.exclude.contains(&ConfigId::new(side, *i))
        })
        .map(|(_, m)| m)
        .collect();
    let params = identifiable_params(nominal.arm(side));
    let needed = settings.method.min_configurations(nominal.arm(side));
    if ms.len() < needed {
        return Err(CalibrationError::TooFewConfigurations {
            side,
            found: ms.len(),
            needed,
            params,
            method: settings.method.name(),
            count_rule: settings.method.count_rule(),
        });
    }
    let expected = nominal.arm(side).joint_count();
    if let Some(m) = ms.iter().find(|m| m.q_rad.len() != expected) {
        return Err(CalibrationError::JointCount {
            side,
            id: m.id.clone(),
            found: m.q_rad.len(),
            expected,
        });
    }
    let qs: Vec<Vec<f64>> = ms.iter().map(|m| m.q_rad.clone()).collect();
    let reflectors = nominal.arm(side).reflector_count();
    if let Some(m) = ms.iter().find(|m| m.tracker_points_mm.len() != reflectors) {
        return Err(CalibrationError::InvalidSettings(format!(
            "{side} arm: configuration `{}` has {} reflector positions, the model has {reflectors} \
             reflectors",
            m.id,
            m.tracker_points_mm.len()
        )));
    }
    let measured: Vec<Vec<Vector3<f64>>> = ms.iter().map(|m| m.tracker_points_mm.clone()).collect();
    if qs
        .iter()
        .flatten()
        .chain(measured.iter().flatten().flat_map(|v| v.iter()))
        .any(|v| !v.is_finite())
    {
        return Err(CalibrationError::NonFinite {
            stage: Stage::Arm(side),
            detail: "measurement data".into(),
        });
    }
    // ε of constraint (14): the tracker's MPE at the mean measuring distance, squared.
    let mean_dist_m = measured.iter().flatten().map(|p| p.norm()).sum::<f64>()
        / (reflectors as f64 * measured.len() as f64)
        / 1000.0;
    let side_tolerance_mm =
        (dataset.tracker.mpe_um + dataset.tracker.mpe_um_per_m * mean_dist_m) / 1000.0;
    Ok(ArmData {
        side,
        ids: ms.iter().map(|m| m.id.clone()).collect(),
        qs,
        measured,
        side_tolerance_mm,
    })
}

/// The refusal of a method without a fit of both arms on a robot whose arms share `shared`.
pub(super) fn unsupported(shared: &SharedJoints, method: Method) -> CalibrationError {
    CalibrationError::SharedJointsUnsupported {
        joints: shared
            .names
            .iter()
            .map(|n| format!("`{n}`"))
            .collect::<Vec<_>>()
            .join(", "),
        method: method.name(),
        alternatives: tree_methods(),
    }
}

/// The methods that fit both arms at once (robots whose arms share joints), for messages.
fn tree_methods() -> String {
    Method::ALL
        .iter()
        .filter(|m| m.spec().tree_set_up.is_some())
        .map(|m| format!("`{}`", m.name()))
        .collect::<Vec<_>>()
        .join(" or ")
}
