//! Export of a calibrated URDF: a copy of the robot's URDF whose joint origins reproduce a calibrated
//! [`DualArmModel`] exactly.
//!
//! - For a description loaded from a file (the user's own robot) the copy is the user's text with only
//!   the arm joints' `<origin>` attributes changed, each by the identified correction, and the
//!   reflectors added as fixed links on the tips (`patch`): every link, visual, collision, sensor,
//!   gripper and extra tag stays where it was.
//! - For the built-in IRB 14000 the joint origins are written in its DH frames (`dh`).
//!
//! [`calibrated_overlay`] is the same calibration as a small file robot software can apply to its own
//! description: the corrected origin of every arm joint and the reflector links.

mod dh;
mod overlay;
mod patch;

use crate::kinematics::DualArmModel;
use crate::robot::{ModelForm, RobotDescription, RobotError};
use nalgebra::Isometry3;
pub use overlay::{
    CalibrationOverlay, JointOverlay, OriginOverlay, ReflectorOverlay, calibrated_overlay,
};

fn export_err(message: String) -> RobotError {
    RobotError::Export { message }
}

pub use crate::kinematics::rpy_from_rotation;

/// A URDF `<origin>` (m, rpy) from an isometry in mm.
pub fn urdf_pose_from_isometry(iso: &Isometry3<f64>) -> urdf_rs::Pose {
    let t = iso.translation.vector / 1000.0;
    urdf_rs::Pose {
        xyz: urdf_rs::Vec3([t.x, t.y, t.z]),
        rpy: urdf_rs::Vec3(rpy_from_rotation(&iso.rotation.to_rotation_matrix())),
    }
}

/// The calibrated URDF of `robot` for `model` (see the module documentation). The text is checked
/// by loading it back before it is returned.
pub fn calibrated_urdf(
    robot: &RobotDescription,
    model: &DualArmModel,
) -> Result<String, RobotError> {
    if let Some((side, name)) = crate::side::Side::BOTH
        .iter()
        .find_map(|&s| model.arm(s).first_non_finite().map(|n| (s, n)))
    {
        return Err(export_err(format!(
            "the {side} arm's parameter `{name}` is not finite"
        )));
    }
    // A URDF holds geometry only: the joints' origins and the reflectors. The errors beyond it
    // (compliances, lumped masses, harmonics) stay in the parameter file, and the file says so.
    let terms = model.error_terms();
    let geometric = model.geometric();
    let text = match robot.model_form() {
        ModelForm::Dh => dh::calibrated_dh_urdf(robot, &geometric),
        ModelForm::Chain => patch::calibrated_chain_urdf(robot, &geometric),
    }?;
    if terms.is_geometric() {
        return Ok(text);
    }
    let note = format!(
        "<!-- dualcal: the calibration's `{}` model also has errors beyond geometry (joint compliances, \
         lumped masses, harmonics); a URDF cannot hold them: this file is its geometry only, the \
         parameter file has the whole model. -->\n",
        terms.name()
    );
    Ok(match text.find("<!-- Calibrated by dualcal") {
        Some(at) => format!("{}{note}{}", &text[..at], &text[at..]),
        None => format!("{note}{text}"),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kinematics::rotation_angle_rad;
    use nalgebra::UnitQuaternion;

    #[test]
    fn rpy_roundtrip_including_gimbal_lock() {
        let cases = [
            (0.3, -0.4, 2.0),
            (-2.9, 1.2, -0.7),
            (0.5, std::f64::consts::FRAC_PI_2, 0.2),
            (0.5, -std::f64::consts::FRAC_PI_2 + 1e-9, 0.2),
            (0.0, 0.0, std::f64::consts::PI),
        ];
        for (r, p, y) in cases {
            let q = UnitQuaternion::from_euler_angles(r, p, y).to_rotation_matrix();
            let [r2, p2, y2] = rpy_from_rotation(&q);
            let back = UnitQuaternion::from_euler_angles(r2, p2, y2).to_rotation_matrix();
            assert!(
                rotation_angle_rad(&(q.inverse() * back)) < 1e-14,
                "{r} {p} {y}"
            );
        }
    }
}
