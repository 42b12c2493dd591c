//! Tests of the serial chain: structure, forward kinematics against an independent composition and
//! against the DH model, refusals, and the analytic Jacobian against central differences.

use super::*;
use crate::kinematics::ArmModel;
use crate::test_robots::{DUAL_UR_ARMS, dual_ur_like_urdf, yumi_like_urdf};
use nalgebra::DVector;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::collections::HashMap;
use std::sync::Arc;

pub(crate) fn reflectors() -> [Vector3<f64>; 3] {
    [
        Vector3::new(45.0, 0.0, 40.0),
        Vector3::new(-25.0, 40.0, 40.0),
        Vector3::new(-25.0, -40.0, 40.0),
    ]
}

fn parse(text: &str) -> urdf_rs::Robot {
    urdf_rs::read_from_string(text).expect("test URDF parses")
}

pub(crate) fn random_q(chain: &SerialChain, rng: &mut ChaCha8Rng) -> Vec<f64> {
    chain
        .joints
        .iter()
        .map(|j| {
            let (lo, hi) = j.range_rad();
            rng.random_range(lo..=hi)
        })
        .collect()
}

/// A chain model with random corrections of up to `mm` and `rad` and reflectors moved by up to `mm`.
pub(crate) fn random_arm(
    chain: &Arc<SerialChain>,
    rng: &mut ChaCha8Rng,
    mm: f64,
    rad: f64,
) -> ArmModel {
    let nominal = ArmModel::nominal_chain(chain.clone(), reflectors());
    let v = nominal.to_vector();
    let v = DVector::from_fn(v.len(), |k, _| {
        let s = if nominal.param_is_angle(k) { rad } else { mm };
        v[k] + rng.random_range(-s..s)
    });
    nominal.with_vector(&v)
}

/// Independent FK: compose every joint's URDF origin and rotation along the path by hand.
fn urdf_fk(
    robot: &urdf_rs::Robot,
    base: &str,
    tip: &str,
    q: &HashMap<String, f64>,
) -> Isometry3<f64> {
    let mut t = Isometry3::identity();
    let mut link = tip.to_string();
    while link != base {
        let j = robot.joints.iter().find(|j| j.child.link == link).unwrap();
        let angle = q.get(&j.name).copied().unwrap_or(0.0);
        let axis = Unit::new_normalize(Vector3::from(j.axis.xyz.0));
        let rot = if j.joint_type == urdf_rs::JointType::Fixed {
            Isometry3::identity()
        } else {
            Isometry3::from_parts(
                Translation3::identity(),
                UnitQuaternion::from_axis_angle(&axis, angle),
            )
        };
        t = isometry_from_urdf_pose(&j.origin) * rot * t;
        link = j.parent.link.clone();
    }
    t
}

#[test]
fn yumi_like_chain_has_seven_joints_in_chain_order() {
    let robot = parse(&yumi_like_urdf());
    let chain = SerialChain::from_urdf(&robot, "yumi_body", "yumi_link_7_l").unwrap();
    assert_eq!(
        chain.joint_names(),
        ["1", "2", "7", "3", "4", "5", "6"].map(|n| format!("yumi_joint_{n}_l"))
    );
    assert_eq!(chain.param_count(3), 51);
    assert!(chain.warnings.is_empty(), "{:?}", chain.warnings);
    // From the world link the fixed joints are folded into joint 1's origin, the gripper's into the
    // tip.
    let from_world = SerialChain::from_urdf(&robot, "world", "gripper_l_base").unwrap();
    assert_eq!(
        from_world.joints[0].folded_fixed,
        ["world_joint", "yumi_base_link_to_body"]
    );
    assert!(
        (from_world.last_from_tip.translation.vector - Vector3::new(0.0, 0.0, 7.0)).norm() < 1e-12
    );
    // The flange faces along link 7's z axis.
    assert!((chain.tool_axis().into_inner() - Vector3::z()).norm() < 1e-9);
}

#[test]
fn nominal_fk_matches_an_independent_composition() {
    let mut rng = ChaCha8Rng::seed_from_u64(1);
    for (text, base, tip) in [
        (yumi_like_urdf(), "world", "gripper_r_base"),
        (dual_ur_like_urdf(), "world", "left_ee_link"),
        (
            crate::robot::BUILTIN_IRB14000_URDF.to_string(),
            "yumi_body",
            "yumi_flange_l",
        ),
    ] {
        let robot = parse(&text);
        let chain = SerialChain::from_urdf(&robot, base, tip).unwrap();
        for _ in 0..10 {
            let q = random_q(&chain, &mut rng);
            let map: HashMap<String, f64> = chain
                .joints
                .iter()
                .map(|j| j.name.clone())
                .zip(q.iter().copied())
                .collect();
            let a = chain.nominal_base_from_tip(&q).to_homogeneous();
            let b = urdf_fk(&robot, base, tip, &map).to_homogeneous();
            assert!((a - b).abs().max() < 1e-9, "{tip}: {a} vs {b}");
            // The last joint frame is the tip's parent frame turned onto its axis.
            let frames = chain.joint_frames(&vec![[0.0; 6]; chain.dof()], &q);
            assert_eq!(frames.len(), chain.dof() + 1);
            assert!((frames[chain.dof()].to_homogeneous() - a).abs().max() < 1e-9);
        }
    }
}

#[test]
fn builtin_chain_reproduces_the_dh_model() {
    // The built-in URDF reproduces Table 3: the chain's FK equals the engine's DH FK.
    let robot = crate::robot::RobotDescription::builtin_irb14000();
    let chain = SerialChain::from_urdf(&robot.urdf, "yumi_body", "yumi_flange_r").unwrap();
    let dh = ArmModel::nominal_irb14000(reflectors());
    let body_from_base = robot.body_from_arm_base(crate::side::Side::Right);
    let mut rng = ChaCha8Rng::seed_from_u64(2);
    for _ in 0..10 {
        let q = random_q(&chain, &mut rng);
        let a = chain.nominal_base_from_tip(&q).to_homogeneous();
        let b = (body_from_base * dh.base_from_flange(&q)).to_homogeneous();
        assert!((a - b).abs().max() < 1e-9);
    }
}

#[test]
fn refusals_name_the_link_or_joint() {
    let robot = parse(&yumi_like_urdf());
    let err = |b: &str, t: &str| SerialChain::from_urdf(&robot, b, t).unwrap_err();
    assert_eq!(
        err("yumi_body", "yumi_link_9_l"),
        ChainError::UnknownLink {
            role: "tip",
            link: "yumi_link_9_l".into()
        }
    );
    assert!(matches!(
        err("yumi_link_3_l", "yumi_link_7_r"),
        ChainError::NoPath { .. }
    ));
    let e = err("yumi_body", "gripper_l_finger_r");
    assert!(
        e.to_string().contains("`gripper_l_joint`") && e.to_string().contains("prismatic"),
        "{e}"
    );
    let e = err("yumi_body", "gripper_l_finger_l");
    assert!(e.to_string().contains("gripper_l_joint_m"), "{e}");
    assert!(matches!(
        err("yumi_link_7_l", "gripper_l_base"),
        ChainError::NoMovableJoint { .. }
    ));
    let floating = yumi_like_urdf().replace(
        "name=\"yumi_base_link_to_body\" type=\"fixed\"",
        "name=\"yumi_base_link_to_body\" type=\"floating\"",
    );
    let e = SerialChain::from_urdf(&parse(&floating), "world", "yumi_link_2_l").unwrap_err();
    assert!(
        matches!(
            e,
            ChainError::UnsupportedJoint {
                kind: "floating",
                ..
            }
        ),
        "{e}"
    );
    let zero_axis =
        dual_ur_like_urdf().replacen("<axis xyz=\"0 1 0\"/>", "<axis xyz=\"0 0 0\"/>", 1);
    let e =
        SerialChain::from_urdf(&parse(&zero_axis), "left_base_link", "left_ee_link").unwrap_err();
    assert!(
        matches!(e, ChainError::BadAxis { ref joint, .. } if joint == "left_shoulder_lift_joint"),
        "{e}"
    );
    // A revolute joint without limits turns ±π, with a warning naming it.
    let unlimited = dual_ur_like_urdf().replacen(
        "<limit lower=\"-3.14159\" upper=\"3.14159\" effort=\"150\" velocity=\"3.15\"/>",
        "",
        1,
    );
    let chain =
        SerialChain::from_urdf(&parse(&unlimited), "left_base_link", "left_ee_link").unwrap();
    assert_eq!(chain.joints[0].limits_rad, None);
    assert!(chain.warnings[0].contains("left_shoulder_pan_joint"));
}

#[test]
fn shared_torso_joints_are_refused() {
    let torso = yumi_like_urdf().replace(
        "<joint name=\"yumi_base_link_to_body\" type=\"fixed\">",
        "<joint name=\"yumi_base_link_to_body\" type=\"continuous\">\n    <axis xyz=\"0 0 1\"/>",
    );
    let robot = parse(&torso);
    let l = SerialChain::from_urdf(&robot, "yumi_base_link", "yumi_link_7_l").unwrap();
    let r = SerialChain::from_urdf(&robot, "yumi_base_link", "yumi_link_7_r").unwrap();
    assert_eq!(l.joints[0].limits_rad, None);
    assert_eq!(
        check_disjoint(&l, &r).unwrap_err(),
        ChainError::SharedJoint {
            joint: "yumi_base_link_to_body".into()
        }
    );
    let l = SerialChain::from_urdf(&robot, "yumi_body", "yumi_link_7_l").unwrap();
    let r = SerialChain::from_urdf(&robot, "yumi_body", "yumi_link_7_r").unwrap();
    assert!(check_disjoint(&l, &r).is_ok());
}

#[test]
fn analytic_jacobian_matches_central_differences() {
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    for (text, base, tip) in [
        (yumi_like_urdf(), "yumi_body", "gripper_l_base"),
        (dual_ur_like_urdf(), "table", DUAL_UR_ARMS[1].1),
    ] {
        let chain = Arc::new(SerialChain::from_urdf(&parse(&text), base, tip).unwrap());
        for _ in 0..10 {
            // Large corrections, so that the sequential elementary axes differ from the nominal ones.
            let arm = random_arm(&chain, &mut rng, 2.0, 0.05);
            let q = random_q(&chain, &mut rng);
            let jac = arm.reflector_jacobians(&q);
            let p0 = arm.reflector_fk(&q).points_mm;
            for (a, b) in jac.fk.points_mm.iter().zip(&p0) {
                assert!((a - b).norm() < 1e-9);
            }
            let jac = crate::kinematics::tests::stacked_jacobian(&arm, &q);
            if let Err(e) = crate::kinematics::tests::check_arm_jacobian(&arm, &q, &jac) {
                panic!("{tip}, q {q:?}: {e}");
            }
        }
    }
}

#[test]
fn corrected_origins_reproduce_the_corrected_chain() {
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    let text = dual_ur_like_urdf();
    let mut robot = parse(&text);
    let chain = Arc::new(SerialChain::from_urdf(&robot, "left_base_link", "left_ee_link").unwrap());
    let arm = random_arm(&chain, &mut rng, 0.5, 0.005);
    let corrections = arm.corrections().unwrap();
    for (name, origin) in chain.corrected_origins(corrections) {
        let j = robot.joints.iter_mut().find(|j| j.name == name).unwrap();
        j.origin = crate::urdf_export::urdf_pose_from_isometry(&origin);
    }
    let again = SerialChain::from_urdf(&robot, "left_base_link", "left_ee_link").unwrap();
    for _ in 0..10 {
        let q = random_q(&chain, &mut rng);
        let a = chain.base_from_tip(corrections, &q).to_homogeneous();
        let b = again.nominal_base_from_tip(&q).to_homogeneous();
        assert!((a - b).abs().max() < 1e-9, "{a} vs {b}");
    }
}

#[test]
fn parallel_axes_and_reasons() {
    let chain = SerialChain::from_urdf(
        &parse(&dual_ur_like_urdf()),
        "left_base_link",
        "left_ee_link",
    )
    .unwrap();
    let parallel: Vec<bool> = (0..6).map(|k| chain.parallel_to_previous(k)).collect();
    assert_eq!(parallel, [false, false, true, true, false, false]);
    assert!(chain.physical_reason(0).unwrap().contains("first joint"));
    assert!(chain.physical_reason(2 * 6 + 2).unwrap().contains("Hayati"));
    assert!(
        chain
            .physical_reason(5 * 6 + 5)
            .unwrap()
            .contains("reflector")
    );
    assert_eq!(chain.physical_reason(2 * 6 + 5), None);
    assert_eq!(minimal_parameter_count(chain.dof()), 27);
}
