//! What goes back on the robot besides a URDF: the arms' base frames in a controller's configuration
//! ([`abb`]), and joint targets compensated for what a controller cannot take ([`compensate`]).
//!
//! Frames. A calibration gives each arm's kinematics in its model base frame (the built-in robot's DH
//! frame 0, a chain's base link) and the right arm's model base in the left arm's
//! ([`DualArmModel::left_base_from_right_base`]). The **world** of this module is the left arm's model
//! base frame: the left arm is where the controller has it, and the right arm is placed relative to it
//! by the calibration. The body frame of the description (the frame everything is drawn in) is the
//! world moved by the left base's nominal place in the body ([`RobotDescription::body_from_arm_base`]).

pub mod abb;
#[warn(missing_docs)]
pub mod compensate;
pub mod targets;

use crate::kinematics::DualArmModel;
use crate::robot::RobotDescription;
use crate::robot::{arm_joint_name, joint1_from_dh_base};
use crate::side::{PerSide, Side};
use nalgebra::Isometry3;

/// Which frame of each arm the controller calls its base frame, in the body frame of the
/// description, mm: for the IRB 14000 (built in, or a description with the YuMi joint names) joint
/// 1's origin frame — the frame of ABB's `ROB_L`/`ROB_R` base frames, whose values the public
/// `yumi_description` writes as joint 1's origins; for any other description the chain's base link
/// (the arm's model base), which is where ABB puts the base frame of a single arm (its foot).
pub fn body_from_controller_base(robot: &RobotDescription, side: Side) -> Isometry3<f64> {
    let yumi_named = robot.is_builtin()
        || robot
            .urdf
            .joints
            .iter()
            .any(|j| j.name == arm_joint_name(side, 0));
    if yumi_named {
        robot.body_from_dh_base(side) * joint1_from_dh_base().inverse()
    } else {
        robot.body_from_arm_base(side)
    }
}

/// Each arm's controller base frame in the body frame under `model`: the left arm's as the description
/// has it, the right arm's placed by `model`'s `left_base_from_right_base` (with the description's own
/// offset between the right arm's controller base and its model base).
pub fn controller_base_frames(
    robot: &RobotDescription,
    model: &DualArmModel,
) -> PerSide<Isometry3<f64>> {
    let body_from_left_model_base = robot.body_from_arm_base(Side::Left);
    PerSide::from_fn(|side| {
        let model_base_from_controller_base =
            robot.body_from_arm_base(side).inverse() * body_from_controller_base(robot, side);
        body_from_left_model_base * model.left_base_from(side) * model_base_from_controller_base
    })
}
