//! Tests of the robot description.

use super::*;
use crate::kinematics::{ArmModel, N_JOINTS, rotation_angle_rad};
use std::f64::consts::PI;

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
    let err = RobotDescription::load(
        RobotSource::Text {
            text,
            path: Some(Path::new("x.urdf")),
        },
        &Default::default(),
    )
    .unwrap_err();
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
    let err = RobotDescription::load(
        RobotSource::Text {
            text: &text,
            path: None,
        },
        &Default::default(),
    )
    .unwrap_err();
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
    fn load(dataset: &crate::dataset::Dataset) -> Result<RobotDescription, RobotError> {
        RobotDescription::load(
            RobotSource::Dataset {
                dataset,
                robot: None,
            },
            &LoadOptions::default(),
        )
    }
    assert!(load(&ds).unwrap().is_builtin());
    ds.arms.left.links = Some(ArmLinks::new("yumi_body", "yumi_flange_l"));
    assert!(load(&ds).is_ok());
    ds.arms.left.links = Some(ArmLinks::new("yumi_body", "yumi_link_7_l"));
    let err = load(&ds).unwrap_err().to_string();
    assert!(
        err.contains("yumi_link_7_l") && err.contains("robot"),
        "{err}"
    );
}

/// A robot whose arms share a joint (a torso above both base links) loads: the joint is on both
/// chains, its value comes from the left arm's columns when the whole robot is posed, and its link
/// belongs to the body (it carries both arms), each arm owning the links below its own first joint.
#[test]
fn a_shared_torso_joint_loads_once() {
    let torso = crate::test_robots::yumi_like_urdf().replace(
        "<joint name=\"yumi_base_link_to_body\" type=\"fixed\">",
        "<joint name=\"yumi_base_link_to_body\" type=\"continuous\">\n    <axis xyz=\"0 0 1\"/>",
    );
    let options = LoadOptions {
        arms: PerSide::new(
            Some(ArmLinks::new("yumi_base_link", "yumi_link_7_l")),
            Some(ArmLinks::new("yumi_base_link", "yumi_link_7_r")),
        ),
        ..Default::default()
    };
    let source = RobotSource::Text {
        text: &torso,
        path: Some(Path::new("torso.urdf")),
    };
    let robot = RobotDescription::load(source, &options).unwrap();
    let nominal = robot.nominal_model([nalgebra::Vector3::zeros()]);
    let shared = nominal.shared_joints();
    assert_eq!(shared.names, ["yumi_base_link_to_body"]);
    assert_eq!(nominal.arm(Side::Left).joint_count(), 8);
    let kin = &robot.kin;
    let link = |name: &str| kin.link_names.iter().position(|n| n == name).unwrap();
    assert_eq!(kin.owner[link("yumi_body")], Owner::Body);
    assert_eq!(kin.owner[link("yumi_link_1_l")], Owner::Arm(Side::Left));
    assert_eq!(kin.owner[link("yumi_link_1_r")], Owner::Arm(Side::Right));
    // The torso turned by the left values: both arms turn with it.
    let mut q_left = vec![0.0; 8];
    q_left[0] = 0.7;
    let turned = kin.body_from_links(&q_left, &[0.0; 8]);
    let still = kin.body_from_links(&[0.0; 8], &[0.0; 8]);
    let moved = |name: &str| {
        (turned[link(name)].translation.vector - still[link(name)].translation.vector).norm()
    };
    assert!(moved("yumi_link_1_l") > 1.0 && moved("yumi_link_1_r") > 1.0);
    // The continuous torso: drawn from ±π, checked against nothing (any angle is a value it
    // takes); the arm's revolute joints keep their limits.
    assert_eq!(robot.joint_limits_rad(Side::Left)[0], (-PI, PI));
    let checked = robot.joint_limits_checked_rad(Side::Left);
    assert_eq!(checked[0], (f64::NEG_INFINITY, f64::INFINITY));
    assert_eq!(checked[1..], robot.joint_limits_rad(Side::Left)[1..]);
}
