//! Tests of the robot description.

use super::*;
use crate::kinematics::{ArmModel, N_JOINTS, rotation_angle_rad};

#[test]
fn builtin_loads_without_warnings() {
    let robot = RobotDescription::builtin_irb14000();
    assert!(robot.warnings.is_empty(), "{:?}", robot.warnings);
    assert_eq!(robot.flange_link(Side::Left), "yumi_flange_l");
    assert_eq!(robot.arm_joint_names(Side::Right)[2], "yumi_joint_7_r");
    assert_eq!(robot.kin.link_names[robot.kin.body], "yumi_body");
}

#[test]
fn zero_pose_flange_matches_dh() {
    let robot = RobotDescription::builtin_irb14000();
    let arm = ArmModel::nominal_irb14000([Vector3::zeros(); 3]);
    for side in Side::BOTH {
        let q = [0.0; N_JOINTS];
        let urdf = robot.body_from_flange(side, &q);
        let dh = robot.body_from_dh_base(side) * arm.base_from_flange(&q);
        assert!((urdf.translation.vector - dh.translation.vector).norm() < 1e-9);
        assert!(
            rotation_angle_rad(&(urdf.rotation.inverse() * dh.rotation).to_rotation_matrix())
                < 1e-12
        );
    }
}

#[test]
fn line_number_is_read_from_parser_message() {
    assert_eq!(
        line_from_message("Parse error; Line: 12, Column: 3, Reason: x"),
        Some(12)
    );
    assert_eq!(line_from_message("something else"), None);
    assert_eq!(line_of("a\nb\nc", "c"), Some(3));
}

#[test]
fn missing_arm_joints_are_named() {
    let text = r#"<robot name="x"><link name="a"/><link name="b"/>
        <joint name="yumi_joint_1_l" type="revolute"><parent link="a"/><child link="b"/>
        <limit lower="-1" upper="1" effort="1" velocity="1"/></joint></robot>"#;
    let err = RobotDescription::from_str(text, Some(Path::new("x.urdf"))).unwrap_err();
    let msg = err.to_string();
    assert!(
        matches!(err, RobotError::MissingJoints { ref missing, .. } if missing.len() == 13),
        "{msg}"
    );
    assert!(
        msg.contains("x.urdf") && msg.contains("yumi_joint_2_l") && msg.contains("yumi_joint_6_r"),
        "{msg}"
    );
    assert!(!msg.contains("yumi_joint_1_l,"), "{msg}");
}

#[test]
fn broken_chain_is_reported_with_line() {
    // Re-parent joint 4 of the right arm onto link_1: the chain is broken.
    let text = BUILTIN_IRB14000_URDF.replacen(
        "<joint name=\"yumi_joint_4_r\" type=\"revolute\">\n    <parent link=\"yumi_link_4_r\"/>",
        "<joint name=\"yumi_joint_4_r\" type=\"revolute\">\n    <parent link=\"yumi_link_1_r\"/>",
        1,
    );
    assert_ne!(text, BUILTIN_IRB14000_URDF);
    let err = RobotDescription::from_str(&text, None).unwrap_err();
    match &err {
        RobotError::BadJoint { joint, line, .. } => {
            assert_eq!(joint, "yumi_joint_4_r");
            assert!(line.is_some());
        }
        other => panic!("unexpected {other}"),
    }
}

#[test]
fn dataset_links_without_a_robot_must_be_the_builtin_arms() {
    let example = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/datasets/example");
    let mut ds = crate::dataset::load(&example).unwrap();
    assert!(RobotDescription::for_dataset(&ds).unwrap().is_builtin());
    ds.arms.left.links = Some(ArmLinks::new("yumi_body", "yumi_flange_l"));
    assert!(RobotDescription::for_dataset(&ds).is_ok());
    ds.arms.left.links = Some(ArmLinks::new("yumi_body", "yumi_link_7_l"));
    let err = RobotDescription::for_dataset(&ds).unwrap_err().to_string();
    assert!(
        err.contains("yumi_link_7_l") && err.contains("robot"),
        "{err}"
    );
}
