//! The calibrated URDF of the built-in IRB 14000: a copy of its URDF whose joint origins reproduce a
//! calibrated DH [`DualArmModel`] exactly.
//!
//! With the frame conventions of [`crate::robot`], per arm:
//! - the chain-position-2 joint origin in link_1 is `joint1_from_dh_base · DH_1(0)`
//!   (= `Rz(π + θ_1) Tz(d_1 − 66) Tx(a_1) Rx(α_1)`),
//! - the joint at chain position k+1 (k ≥ 2) has origin `DH_k(0)` in link_k,
//! - the fixed flange joint in link_7 is `DH_7(0)`,
//! - the left joint-1 origin is kept (the left DH base stays where it was) and the right joint-1
//!   origin is moved so that the right DH base sits at `left_base_from_right_base` in the left one,
//! - the reflectors become fixed child links `reflector_{a,b,c}_{l,r}` of the flange.
//!
//! The XML is written by urdf-rs's writer (shortest round-trip float formatting, i.e. full
//! precision); everything else in the URDF (geometry, meshes, limits, other links) is kept.

use super::patch::REFLECTOR_RADIUS_M;
use super::{export_err, urdf_pose_from_isometry};
use crate::kinematics::{DualArmModel, N_JOINTS};
use crate::robot::{
    RobotDescription, RobotError, arm_link_name, flange_link_name, joint1_from_dh_base, side_suffix,
};
use crate::side::Side;
use nalgebra::{Isometry3, Vector3};

fn fixed_joint(name: String, parent: &str, child: &str, origin: urdf_rs::Pose) -> urdf_rs::Joint {
    urdf_rs::Joint {
        name,
        joint_type: urdf_rs::JointType::Fixed,
        origin,
        parent: urdf_rs::LinkName {
            link: parent.to_string(),
        },
        child: urdf_rs::LinkName {
            link: child.to_string(),
        },
        axis: urdf_rs::Axis::default(),
        limit: urdf_rs::JointLimit::default(),
        calibration: None,
        dynamics: None,
        mimic: None,
        safety_controller: None,
    }
}

fn reflector_link(name: String) -> urdf_rs::Link {
    urdf_rs::Link {
        name,
        inertial: urdf_rs::Inertial::default(),
        visual: vec![urdf_rs::Visual {
            name: None,
            origin: urdf_rs::Pose::default(),
            geometry: urdf_rs::Geometry::Sphere {
                radius: REFLECTOR_RADIUS_M,
            },
            material: Some(urdf_rs::Material {
                name: "dualcal_reflector".to_string(),
                color: Some(urdf_rs::Color {
                    rgba: urdf_rs::Vec4([0.85, 0.12, 0.1, 1.0]),
                }),
                texture: None,
            }),
        }],
        collision: Vec::new(),
    }
}

fn joint_mut<'a>(
    urdf: &'a mut urdf_rs::Robot,
    name: &str,
) -> Result<&'a mut urdf_rs::Joint, RobotError> {
    urdf.joints
        .iter_mut()
        .find(|j| j.name == name)
        .ok_or_else(|| export_err(format!("joint `{name}` not found")))
}

fn check_finite(model: &DualArmModel) -> Result<(), RobotError> {
    for side in Side::BOTH {
        let arm = model.arm(side);
        if arm.dh().is_none() {
            return Err(export_err(format!(
                "the {side} arm's model is not a DH table; the built-in IRB 14000 exports DH models"
            )));
        }
        if arm.first_non_finite().is_some() {
            return Err(export_err(format!(
                "the {side} arm's parameters are not all finite"
            )));
        }
    }
    let b = &model.left_base_from_right_base;
    if !(b.translation.vector.iter().all(|v| v.is_finite())
        && b.rotation.coords.iter().all(|v| v.is_finite()))
    {
        return Err(export_err(
            "the right-arm base transform is not finite".into(),
        ));
    }
    Ok(())
}

/// One arm's joint origins (chain positions 2..7) from its DH table, its flange and its reflectors.
fn write_arm(
    robot: &RobotDescription,
    model: &DualArmModel,
    side: Side,
    urdf: &mut urdf_rs::Robot,
) -> Result<(), RobotError> {
    let names = robot.arm_joint_names(side);
    let dh = model
        .arm(side)
        .dh()
        .ok_or_else(|| export_err(format!("the {side} arm's model is not a DH table")))?;
    for name in &names {
        let j = joint_mut(urdf, name)?;
        if (Vector3::new(j.axis.xyz[0], j.axis.xyz[1], j.axis.xyz[2]) - Vector3::z()).norm() > 1e-9
        {
            return Err(export_err(format!(
                "joint `{name}` turns about {:?}; a DH chain needs 0 0 1",
                j.axis.xyz.0
            )));
        }
    }
    // Joint origins of chain positions 2..7.
    for k in 1..N_JOINTS {
        let origin = if k == 1 {
            joint1_from_dh_base() * dh[0].transform(0.0)
        } else {
            dh[k - 1].transform(0.0)
        };
        joint_mut(urdf, &names[k])?.origin = urdf_pose_from_isometry(&origin);
    }

    // The flange: a fixed child of link_7 at DH row 7.
    let link7 = arm_link_name(side, N_JOINTS);
    let link7_from_flange = urdf_pose_from_isometry(&dh[N_JOINTS - 1].transform(0.0));
    let flange = flange_link_name(side);
    if robot.flange_link(side) == flange {
        let j = urdf
            .joints
            .iter_mut()
            .find(|j| j.child.link == flange)
            .ok_or_else(|| export_err(format!("no joint carries `{flange}`")))?;
        if j.parent.link != link7 {
            return Err(export_err(format!(
                "`{flange}` hangs from `{}`, not directly from `{link7}`",
                j.parent.link
            )));
        }
        j.origin = link7_from_flange;
    } else {
        if urdf.links.iter().any(|l| l.name == flange) {
            return Err(export_err(format!(
                "link `{flange}` exists but is not fixed to `{link7}`"
            )));
        }
        urdf.links.push(urdf_rs::Link {
            name: flange.clone(),
            inertial: urdf_rs::Inertial::default(),
            visual: Vec::new(),
            collision: Vec::new(),
        });
        urdf.joints.push(fixed_joint(
            format!("yumi_flange_joint_{}", side_suffix(side)),
            &link7,
            &flange,
            link7_from_flange,
        ));
    }

    // Reflectors: fixed links of the flange.
    let arm = model.arm(side);
    for (r, t) in arm.reflector_names.iter().zip(&arm.reflectors_mm) {
        let link = format!("reflector_{r}_{}", side_suffix(side));
        let origin = urdf_rs::Pose {
            xyz: urdf_rs::Vec3([t.x / 1000.0, t.y / 1000.0, t.z / 1000.0]),
            rpy: urdf_rs::Vec3([0.0; 3]),
        };
        if let Some(j) = urdf.joints.iter_mut().find(|j| j.child.link == link) {
            j.parent.link = flange.clone();
            j.joint_type = urdf_rs::JointType::Fixed;
            j.origin = origin;
        } else {
            if !urdf.links.iter().any(|l| l.name == link) {
                urdf.links.push(reflector_link(link.clone()));
            }
            urdf.joints
                .push(fixed_joint(format!("{link}_joint"), &flange, &link, origin));
        }
    }
    Ok(())
}

/// A copy of the built-in `robot`'s URDF whose joint origins reproduce `model` (both arms' DH tables
/// and the right-arm base) exactly, with the reflectors as fixed links of the flanges. The text is
/// checked by loading it back before it is returned.
pub(super) fn calibrated_dh_urdf(
    robot: &RobotDescription,
    model: &DualArmModel,
) -> Result<String, RobotError> {
    check_finite(model)?;
    let mut urdf = robot.urdf.clone();
    let body_from_link: std::collections::HashMap<String, Isometry3<f64>> =
        robot.link_poses(&[], &[]).into_iter().collect();

    for side in Side::BOTH {
        write_arm(robot, model, side, &mut urdf)?;
    }

    // The right joint-1 origin: right DH base = left DH base · left_base_from_right_base.
    let j1r = robot.arm_joint_names(Side::Right)[0].clone();
    let parent = joint_mut(&mut urdf, &j1r)?.parent.link.clone();
    let body_from_parent = body_from_link
        .get(&parent)
        .copied()
        .ok_or_else(|| export_err(format!("link `{parent}` is not connected to the body")))?;
    let body_from_right_base =
        robot.body_from_dh_base(Side::Left) * model.left_base_from_right_base;
    let parent_from_joint1 =
        body_from_parent.inverse() * body_from_right_base * joint1_from_dh_base().inverse();
    joint_mut(&mut urdf, &j1r)?.origin = urdf_pose_from_isometry(&parent_from_joint1);

    let body = urdf_rs::write_to_string(&urdf).map_err(|e| export_err(e.to_string()))?;
    let from = robot.source.as_ref().map_or_else(
        || "the built-in IRB 14000 description".to_string(),
        |p| p.display().to_string(),
    );
    let text = format!(
        "<?xml version=\"1.0\"?>\n<!-- Calibrated by dualcal {} from {}: joint origins reproduce the \
         calibrated DH tables; the right joint-1 origin places the right DH base at the calibrated \
         left_base_from_right_base. Lengths in metres. -->\n{body}\n",
        env!("CARGO_PKG_VERSION"),
        from.replace("--", "- -"),
    );
    // The result must load back as a YuMi description.
    RobotDescription::load(
        crate::robot::RobotSource::Text {
            text: &text,
            path: None,
        },
        &Default::default(),
    )
    .map_err(|e| export_err(format!("the written URDF does not load back: {e}")))?;
    Ok(text)
}
