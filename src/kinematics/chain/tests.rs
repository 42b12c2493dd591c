//! Tests of the serial chain: structure, forward kinematics against an independent composition and
//! against the DH model, refusals, and the analytic Jacobian against central differences.

use super::*;
use crate::kinematics::ArmModel;
use crate::test_robots::{
    COLUMN_MIMIC_ARM, DUAL_UR_ARMS, column_mimic_urdf, dual_ur_like_urdf, lift_mimic_urdf,
    yumi_like_urdf,
};
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
        .variable_ranges()
        .into_iter()
        .map(|(lo, hi)| rng.random_range(lo..=hi))
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

/// Independent FK: compose every joint's URDF origin and motion along the path by hand; `q` holds
/// URDF values (rad, m) by joint name, a `<mimic>` joint's computed from its leader's.
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
        let value = match &j.mimic {
            Some(m) => {
                m.multiplier.unwrap_or(1.0) * q.get(&m.joint).copied().unwrap_or(0.0)
                    + m.offset.unwrap_or(0.0)
            }
            None => q.get(&j.name).copied().unwrap_or(0.0),
        };
        let axis = Unit::new_normalize(Vector3::from(j.axis.xyz.0));
        let rot = match j.joint_type {
            urdf_rs::JointType::Fixed => Isometry3::identity(),
            urdf_rs::JointType::Prismatic => Isometry3::from_parts(
                Translation3::from(axis.into_inner() * value * 1000.0),
                UnitQuaternion::identity(),
            ),
            _ => Isometry3::from_parts(
                Translation3::identity(),
                UnitQuaternion::from_axis_angle(&axis, value),
            ),
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
        (lift_mimic_urdf(), "torso", "left_flange"),
        (yumi_like_urdf(), "yumi_body", "gripper_r_finger_r"),
        (yumi_like_urdf(), "yumi_body", "gripper_r_finger_l"),
        (column_mimic_urdf(), COLUMN_MIMIC_ARM.0, COLUMN_MIMIC_ARM.1),
        (
            column_mimic_urdf(),
            COLUMN_MIMIC_ARM.0,
            "gripper_finger_right",
        ),
    ] {
        let robot = parse(&text);
        let chain = SerialChain::from_urdf(&robot, base, tip).unwrap();
        for _ in 0..10 {
            let q = random_q(&chain, &mut rng);
            // The URDF's own values: metres for a prismatic joint.
            let map: HashMap<String, f64> = chain
                .variables()
                .iter()
                .zip(q.iter().copied())
                .map(|(j, v)| {
                    (
                        j.name.clone(),
                        if j.kind.is_linear() { v / 1000.0 } else { v },
                    )
                })
                .collect();
            let a = chain.nominal_base_from_tip(&q).to_homogeneous();
            let b = urdf_fk(&robot, base, tip, &map).to_homogeneous();
            assert!((a - b).abs().max() < 1e-9, "{tip}: {a} vs {b}");
            // The last joint frame is the tip's parent frame turned onto its axis.
            let n = chain.joint_count();
            let frames = chain.joint_frames(&vec![[0.0; 6]; n], &q);
            assert_eq!(frames.len(), n + 1);
            assert!((frames[n].to_homogeneous() - a).abs().max() < 1e-9);
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
    // The gripper's finger: a prismatic joint ends the chain (its travel in mm).
    let finger = SerialChain::from_urdf(&robot, "yumi_body", "gripper_l_finger_r").unwrap();
    assert_eq!(finger.dof(), 8);
    assert!(finger.variable_is_linear(7) && !finger.variable_is_linear(6));
    assert_eq!(finger.joints[7].limits, Some((0.0, 25.0)));
    // The other finger mimics a joint that is not on its chain (the first finger's): that leader is
    // the chain's eighth column, with its limits; the mimicking finger has the correction block.
    let other = SerialChain::from_urdf(&robot, "yumi_body", "gripper_l_finger_l").unwrap();
    assert_eq!((other.dof(), other.joint_count()), (8, 8));
    assert_eq!(other.variable_names()[7], "gripper_l_joint");
    assert!(other.variables()[7].is_off_chain() && other.variable_is_linear(7));
    assert_eq!(other.variable_ranges()[7], (0.0, 25.0));
    assert_eq!(other.joint_names()[7], "gripper_l_joint_m");
    assert_eq!(other.joints[7].drive.leader(), Some(7));
    // A leader the description lacks is refused, naming both.
    let missing = yumi_like_urdf().replace(
        "<mimic joint=\"gripper_l_joint\"",
        "<mimic joint=\"gripper_l_joint_x\"",
    );
    assert_ne!(missing, yumi_like_urdf());
    let e =
        SerialChain::from_urdf(&parse(&missing), "yumi_body", "gripper_l_finger_l").unwrap_err();
    assert!(
        matches!(e, ChainError::MimicOutsideChain { ref joint, ref mimicked }
            if joint == "gripper_l_joint_m" && mimicked == "gripper_l_joint_x"),
        "{e}"
    );
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
    assert_eq!(chain.joints[0].limits, None);
    assert!(chain.warnings[0].contains("left_shoulder_pan_joint"));
}

/// A joint above both arms' chains (a torso) is on both: `SharedJoints` finds it by name, with its
/// parameters and its joint-value column in each arm; chains below it share nothing.
#[test]
fn shared_torso_joints_are_found() {
    let torso = yumi_like_urdf().replace(
        "<joint name=\"yumi_base_link_to_body\" type=\"fixed\">",
        "<joint name=\"yumi_base_link_to_body\" type=\"continuous\">\n    <axis xyz=\"0 0 1\"/>",
    );
    let robot = parse(&torso);
    let arm = |base: &str, tip: &str| {
        let chain = SerialChain::from_urdf(&robot, base, tip).unwrap();
        crate::kinematics::ArmModel::nominal_chain(
            std::sync::Arc::new(chain),
            vec![Vector3::zeros()],
        )
    };
    let (l, r) = (
        arm("yumi_base_link", "yumi_link_7_l"),
        arm("yumi_base_link", "yumi_link_7_r"),
    );
    assert_eq!(l.chain().unwrap().joints[0].limits, None);
    let shared = crate::kinematics::SharedJoints::of(&l, &r);
    assert_eq!(shared.names, ["yumi_base_link_to_body"]);
    assert_eq!(shared.joints, [(0, 0)]);
    assert_eq!(shared.variables, [(0, 0)]);
    assert_eq!(shared.params, (0..6).map(|i| (i, i)).collect::<Vec<_>>());
    assert_eq!(shared.right_param_of(3), Some(3));
    assert_eq!(shared.right_param_of(6), None);
    assert_eq!(
        shared.right_with_left_values(&[0.5, 1.0], &[-0.5, 2.0]),
        [0.5, 2.0]
    );
    let (l, r) = (
        arm("yumi_body", "yumi_link_7_l"),
        arm("yumi_body", "yumi_link_7_r"),
    );
    assert!(crate::kinematics::SharedJoints::of(&l, &r).is_empty());
}

#[test]
fn analytic_jacobian_matches_central_differences() {
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    for (text, base, tip) in [
        (yumi_like_urdf(), "yumi_body", "gripper_l_base"),
        (dual_ur_like_urdf(), "table", DUAL_UR_ARMS[1].1),
        (lift_mimic_urdf(), "torso", "right_flange"),
        (column_mimic_urdf(), COLUMN_MIMIC_ARM.0, COLUMN_MIMIC_ARM.1),
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
    for (text, base, tip) in [
        (dual_ur_like_urdf(), "left_base_link", "left_ee_link"),
        (lift_mimic_urdf(), "left_base_link", "left_flange"),
        (column_mimic_urdf(), COLUMN_MIMIC_ARM.0, COLUMN_MIMIC_ARM.1),
    ] {
        let mut robot = parse(&text);
        let chain = Arc::new(SerialChain::from_urdf(&robot, base, tip).unwrap());
        let arm = random_arm(&chain, &mut rng, 0.5, 0.005);
        let corrections = arm.corrections().unwrap();
        for (name, origin) in chain.corrected_origins(corrections) {
            let j = robot.joints.iter_mut().find(|j| j.name == name).unwrap();
            j.origin = crate::urdf_export::urdf_pose_from_isometry(&origin);
        }
        let again = SerialChain::from_urdf(&robot, base, tip).unwrap();
        for _ in 0..10 {
            let q = random_q(&chain, &mut rng);
            let a = chain.base_from_tip(corrections, &q).to_homogeneous();
            let b = again.nominal_base_from_tip(&q).to_homogeneous();
            assert!((a - b).abs().max() < 1e-9, "{tip}: {a} vs {b}");
        }
    }
}

#[test]
fn prismatic_and_mimic_joints() {
    let robot = parse(&lift_mimic_urdf());
    let chain = SerialChain::from_urdf(&robot, "left_base_link", "left_flange").unwrap();
    // Seven movable joints, six variables: the coupled joint has no column.
    assert_eq!(chain.joint_count(), 7);
    assert_eq!(chain.dof(), 6);
    assert_eq!(chain.param_count(1), 7 * 6 + 3);
    assert_eq!(
        chain.variable_names(),
        ["waist", "lift", "shoulder", "elbow", "wrist", "roll"].map(|n| format!("left_{n}_joint"))
    );
    assert_eq!(chain.joints[1].kind, MovableKind::Prismatic);
    assert_eq!(chain.joints[1].limits, Some((0.0, 300.0)));
    assert_eq!(
        chain.joints[4].drive,
        JointDrive::Mimic {
            leader: 3,
            multiplier: 0.5,
            offset: 0.2
        }
    );
    assert_eq!(chain.variable_ranges()[1], (0.0, 300.0));
    // The lift moves the flange along its axis, mm for mm.
    let q0 = [0.1, 0.0, 0.3, -0.4, 0.2, 0.5];
    let mut q1 = q0;
    q1[1] = 120.0;
    let d = chain.nominal_base_from_tip(&q1).translation.vector
        - chain.nominal_base_from_tip(&q0).translation.vector;
    assert!((d - Vector3::new(0.0, 0.0, 120.0)).norm() < 1e-9, "{d}");
    // A prismatic joint's zero offset (tz) and tilt are preferred over what the next joint holds.
    let order = chain.preference_order(1);
    let lift = 6;
    let pos = |k: usize| order.iter().position(|&o| o == k).unwrap();
    assert!(pos(lift + 2) < pos(lift + 5) && pos(lift + 3) < pos(lift));
    assert!(chain.physical_reason(lift).unwrap().contains("prismatic"));
    assert_eq!(chain.physical_reason(lift + 2), None);
}

#[test]
fn mimic_chains_are_followed_and_loops_refused() {
    // A joint that mimics a mimic joint: the multipliers and offsets compose (URDF units: the lift
    // in metres, so a revolute follower of the lift gets 1/1000 per mm).
    let text = lift_mimic_urdf().replace(
        "<mimic joint=\"left_elbow_joint\" multiplier=\"0.5\" offset=\"0.2\"/>",
        "<mimic joint=\"left_lift_joint\" multiplier=\"2\" offset=\"0.1\"/>",
    );
    let chain = SerialChain::from_urdf(&parse(&text), "left_base_link", "left_flange").unwrap();
    match chain.joints[4].drive {
        JointDrive::Mimic {
            leader,
            multiplier,
            offset,
        } => {
            assert_eq!(leader, 1);
            assert!((multiplier - 2.0 / 1000.0).abs() < 1e-15 && offset == 0.1);
        }
        other => panic!("{other:?}"),
    }
    // elbow mimics coupled, which mimics elbow: a loop.
    let looped = lift_mimic_urdf().replace(
        "<child link=\"left_forearm\"/>",
        "<child link=\"left_forearm\"/>\n    <mimic joint=\"left_coupled_joint\"/>",
    );
    let e = SerialChain::from_urdf(&parse(&looped), "left_base_link", "left_flange").unwrap_err();
    assert!(matches!(e, ChainError::MimicLoop { .. }), "{e}");
    assert!(e.to_string().contains("left_coupled_joint"), "{e}");
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

/// The tip pose's analytic joint Jacobian ([`ArmModel::flange_jacobian`], used by compensation)
/// against central differences of the pose — position and rotation vector — for the DH table, a
/// corrected YuMi-like chain and the lift-and-mimic chain (a prismatic column, a mimic leader).
#[test]
fn flange_jacobian_matches_finite_differences() {
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    let mut models = vec![ArmModel::nominal_irb14000(reflectors())];
    for (text, base, tip) in [
        (yumi_like_urdf(), "yumi_body", "gripper_r_finger_r"),
        (lift_mimic_urdf(), "torso", "left_flange"),
        (column_mimic_urdf(), COLUMN_MIMIC_ARM.0, COLUMN_MIMIC_ARM.1),
    ] {
        let chain = Arc::new(SerialChain::from_urdf(&parse(&text), base, tip).unwrap());
        models.push(random_arm(&chain, &mut rng, 2.0, 0.01));
    }
    for model in &models {
        let n = model.joint_count();
        let limits = model.joint_limits_rad();
        for _ in 0..5 {
            let q: Vec<f64> = limits
                .iter()
                .map(|&(lo, hi)| rng.random_range(lo..hi))
                .collect();
            let (tip, jac) = model.flange_jacobian(&q);
            let fk = model.base_from_flange(&q);
            assert!((tip.to_homogeneous() - fk.to_homogeneous()).amax() < 1e-9);
            for c in 0..n {
                let h = 1e-6;
                let mut qp = q.clone();
                let mut qm = q.clone();
                qp[c] += h;
                qm[c] -= h;
                let (tp, tm) = (model.base_from_flange(&qp), model.base_from_flange(&qm));
                let dp = (tp.translation.vector - tm.translation.vector) / (2.0 * h);
                let dw = (tp.rotation * tm.rotation.inverse()).scaled_axis() / (2.0 * h);
                let col = jac.column(c);
                let (ep, ew) = (
                    (col.fixed_rows::<3>(0) - dp).amax(),
                    (col.fixed_rows::<3>(3) - dw).amax(),
                );
                assert!(
                    ep < 1e-5 * (1.0 + dp.amax()) && ew < 1e-7,
                    "{n} joints, column {c}: position {ep:e}, rotation {ew:e}"
                );
            }
        }
    }
}

/// A lifting column whose measured joint is a virtual leader on a side branch: the leader is the
/// arm's first column (where its first follower stands), with its own limits and no correction; the
/// column's two stages follow it (multiplier and offset in mm) and have theirs.
#[test]
fn a_leader_off_the_chain_is_a_column_of_the_arm() {
    let robot = parse(&column_mimic_urdf());
    let (base, tip) = COLUMN_MIMIC_ARM;
    let chain = SerialChain::from_urdf(&robot, base, tip).unwrap();
    assert_eq!(
        chain.variable_names(),
        [
            "column_prismatic_joint",
            "arm_shoulder_pan_joint",
            "arm_shoulder_lift_joint",
            "arm_elbow_joint",
            "arm_wrist_1_joint",
            "arm_wrist_2_joint",
            "arm_wrist_3_joint"
        ]
    );
    assert_eq!(chain.joint_count(), 8);
    assert_eq!(
        &chain.joint_names()[..2],
        ["column_middle_joint", "column_top_joint"]
    );
    assert!(!chain.joint_names().contains(&"column_prismatic_joint"));
    let leader = &chain.variables()[0];
    assert!(leader.is_off_chain() && leader.kind == MovableKind::Prismatic);
    let (lo, hi) = chain.variable_ranges()[0];
    assert!((lo - 1412.0).abs() < 1e-9 && (hi - 2012.0).abs() < 1e-9);
    assert!(chain.variable_is_linear(0) && !chain.variable_is_linear(1));
    for (k, offset_mm) in [(0, -706.0), (1, -736.0)] {
        match chain.joints[k].drive {
            JointDrive::Mimic {
                leader,
                multiplier,
                offset,
            } => {
                assert_eq!(leader, 0);
                assert!((multiplier - 0.5).abs() < 1e-15 && (offset - offset_mm).abs() < 1e-9);
            }
            other => panic!("{other:?}"),
        }
    }
    // The stages' values: 0.5 · q + offset, e.g. fully down (1412 mm) the middle stage at 0 mm.
    let mut q = vec![0.0; 7];
    q[0] = 1412.0;
    let v = chain.joint_values(&q);
    assert!(v[0].abs() < 1e-9 && (v[1] + 30.0).abs() < 1e-9, "{v:?}");
    // The leader's column moves the flange along z, half a mm per stage per mm.
    let (mut lo, mut hi) = (q.clone(), q);
    hi[0] = 1612.0;
    lo[0] = 1512.0;
    let d = chain.nominal_base_from_tip(&hi).translation.vector
        - chain.nominal_base_from_tip(&lo).translation.vector;
    assert!((d - Vector3::new(0.0, 0.0, 100.0)).norm() < 1e-9, "{d}");
    // Its parameters are the followers' and the arm's: none of the leader's.
    assert_eq!(chain.param_count(1), 8 * 6 + 3);
    assert!((0..chain.param_count(1)).all(|k| !chain.param_name(k).contains("column_prismatic")));
}

/// A leader off the chain that no joint of the chain follows is no column: the gripper's leader
/// beside a chain ending at the flange, the column's leader beside a chain starting above the column.
#[test]
fn a_leader_off_the_chain_followed_by_nothing_on_it_is_no_column() {
    let robot = parse(&column_mimic_urdf());
    let flange = SerialChain::from_urdf(&robot, COLUMN_MIMIC_ARM.0, COLUMN_MIMIC_ARM.1).unwrap();
    assert!(
        !flange
            .variable_names()
            .contains(&"gripper_finger_left_joint")
    );
    let arm = SerialChain::from_urdf(&robot, "arm_base_link", "arm_ee_link").unwrap();
    assert_eq!((arm.dof(), arm.joint_count()), (6, 6));
    assert!(arm.variables().iter().all(|v| !v.is_off_chain()));
    let yumi =
        SerialChain::from_urdf(&parse(&yumi_like_urdf()), "yumi_body", "yumi_link_7_l").unwrap();
    assert_eq!(yumi.dof(), 7);
    assert!(!yumi.variable_names().contains(&"gripper_l_joint"));
    // A chain through the mimicking finger makes the gripper's leader its last column.
    let finger =
        SerialChain::from_urdf(&robot, COLUMN_MIMIC_ARM.0, "gripper_finger_right").unwrap();
    assert_eq!(finger.variable_names()[7], "gripper_finger_left_joint");
    assert_eq!(finger.dof(), 8);
    // Two chains that hold the same column: its leader is one value of both (a shared variable).
    let a = ArmModel::nominal_chain(Arc::new(flange), vec![Vector3::zeros()]);
    let b = ArmModel::nominal_chain(Arc::new(finger), vec![Vector3::zeros()]);
    let shared = crate::kinematics::SharedJoints::of(&a, &b);
    let mut pairs = shared.variables.clone();
    pairs.sort_unstable();
    assert_eq!(pairs, (0..7).map(|i| (i, i)).collect::<Vec<_>>());
    assert_eq!(shared.variable_names.len(), 7);
    assert!(
        shared
            .variable_names
            .contains(&"column_prismatic_joint".to_string())
    );
    // A fixed joint is no leader.
    let fixed = column_mimic_urdf().replace(
        "<joint name=\"column_prismatic_joint\" type=\"prismatic\">",
        "<joint name=\"column_prismatic_joint\" type=\"fixed\">",
    );
    let e =
        SerialChain::from_urdf(&parse(&fixed), COLUMN_MIMIC_ARM.0, COLUMN_MIMIC_ARM.1).unwrap_err();
    assert!(
        matches!(e, ChainError::LeaderNotMovable { ref joint, kind: "fixed", .. }
            if joint == "column_middle_joint"),
        "{e}"
    );
}
