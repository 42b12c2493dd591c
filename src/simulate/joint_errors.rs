//! Unmodelled joint errors of the true robot (periodic gear error and compliance).

use super::JointErrorModel;
use crate::kinematics::ArmModel;
use nalgebra::Vector3;

/// Unmodelled joint error `δq(q)` of [`JointErrorModel`] for the true `arm`.
pub(super) fn joint_error_rad(
    model: &JointErrorModel,
    phases_rad: &[f64],
    arm: &ArmModel,
    q: &[f64],
    gravity_in_base: &Vector3<f64>,
) -> Vec<f64> {
    let frames = arm.joint_frames(q);
    (0..q
        .len()
        .min(frames.len().saturating_sub(1))
        .min(phases_rad.len()))
        .map(|i| {
            let periodic = model.periodic_amplitude_mrad
                * 1e-3
                * (model.periods_per_rev * q[i] + phases_rad[i]).sin();
            let axis = frames[i].rotation * Vector3::z();
            let o = frames[i].translation.vector;
            let lever_mm: Vector3<f64> = frames[i + 1..]
                .iter()
                .map(|f| f.translation.vector - o)
                .sum();
            let torque_m = axis.dot(&lever_mm.cross(gravity_in_base)) / 1000.0;
            periodic + model.compliance_mrad_per_m * 1e-3 * torque_m
        })
        .collect()
}
