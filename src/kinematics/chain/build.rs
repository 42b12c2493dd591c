//! Building a [`SerialChain`] from a parsed URDF.

use super::{ChainError, ChainJoint, ChainVariable, JointDrive, MovableKind, SerialChain};
use nalgebra::{Isometry3, Translation3, Unit, UnitQuaternion, Vector3};
use std::collections::HashMap;

/// Convert a URDF pose (m, rpy) to an isometry in mm.
pub fn isometry_from_urdf_pose(pose: &urdf_rs::Pose) -> Isometry3<f64> {
    let [x, y, z] = pose.xyz.0;
    let [r, p, yaw] = pose.rpy.0;
    Isometry3::from_parts(
        Translation3::new(x * 1000.0, y * 1000.0, z * 1000.0),
        UnitQuaternion::from_euler_angles(r, p, yaw),
    )
}

/// Whether every number of a URDF pose is finite.
pub(crate) fn finite_pose(pose: &urdf_rs::Pose) -> bool {
    pose.xyz
        .0
        .iter()
        .chain(pose.rpy.0.iter())
        .all(|v| v.is_finite())
}

/// The rotation taking +z to `axis` (identity for +z, a half turn about x for −z).
fn aligned_rotation(axis: &Unit<Vector3<f64>>) -> UnitQuaternion<f64> {
    UnitQuaternion::rotation_between(&Vector3::z(), axis).unwrap_or_else(|| {
        UnitQuaternion::from_axis_angle(&Vector3::x_axis(), std::f64::consts::PI)
    })
}

fn joint_kind_name(kind: &urdf_rs::JointType) -> &'static str {
    match kind {
        urdf_rs::JointType::Revolute => "revolute",
        urdf_rs::JointType::Continuous => "continuous",
        urdf_rs::JointType::Prismatic => "prismatic",
        urdf_rs::JointType::Fixed => "fixed",
        urdf_rs::JointType::Floating => "floating",
        urdf_rs::JointType::Planar => "planar",
        urdf_rs::JointType::Spherical => "spherical",
    }
}

/// A movable joint's limits in the program's units (rad; mm for a prismatic joint); `None` for a
/// continuous joint, and for a revolute joint without proper limits (urdf-rs reads a missing
/// `<limit>` as [0, 0]: it turns ±π, with a warning). Non-finite or reversed limits are refused.
fn joint_limits(
    j: &urdf_rs::Joint,
    kind: MovableKind,
    warnings: &mut Vec<String>,
) -> Result<Option<(f64, f64)>, ChainError> {
    if kind == MovableKind::Continuous {
        return Ok(None);
    }
    let (lower, upper) = (j.limit.lower, j.limit.upper);
    if !(lower.is_finite() && upper.is_finite() && lower <= upper) {
        return Err(ChainError::BadLimits {
            joint: j.name.clone(),
            lower,
            upper,
        });
    }
    if kind.is_linear() {
        if lower == upper && j.mimic.is_none() {
            warnings.push(format!(
                "joint `{}` is prismatic with the limits [{lower}, {upper}] m (or none): it cannot \
                 move",
                j.name
            ));
        }
        return Ok(Some((lower * 1000.0, upper * 1000.0)));
    }
    if lower == upper {
        warnings.push(format!(
            "joint `{}` is revolute with the limits [{lower}, {upper}] (or none): it is treated as \
             turning ±π",
            j.name
        ));
        return Ok(None);
    }
    Ok(Some((lower, upper)))
}

/// The joints from `base_link` down to `tip_link`, in chain order.
fn path<'a>(
    robot: &'a urdf_rs::Robot,
    base_link: &str,
    tip_link: &str,
) -> Result<Vec<&'a urdf_rs::Joint>, ChainError> {
    for (role, link) in [("base", base_link), ("tip", tip_link)] {
        if !robot.links.iter().any(|l| l.name == link) {
            return Err(ChainError::UnknownLink {
                role,
                link: link.to_string(),
            });
        }
    }
    let parent_joint: HashMap<&str, &urdf_rs::Joint> = robot
        .joints
        .iter()
        .map(|j| (j.child.link.as_str(), j))
        .collect();
    let no_path = || ChainError::NoPath {
        base: base_link.into(),
        tip: tip_link.into(),
    };
    let mut path = Vec::new();
    let mut link = tip_link;
    while link != base_link {
        let joint = parent_joint.get(link).ok_or_else(no_path)?;
        if path.len() > robot.joints.len() {
            // A cycle (a malformed description): no path either.
            return Err(no_path());
        }
        path.push(*joint);
        link = joint.parent.link.as_str();
    }
    path.reverse();
    Ok(path)
}

impl SerialChain {
    /// The chain of `robot` from `base_link` down to `tip_link`.
    pub fn from_urdf(
        robot: &urdf_rs::Robot,
        base_link: &str,
        tip_link: &str,
    ) -> Result<Self, ChainError> {
        let mut joints = Vec::new();
        let mut warnings = Vec::new();
        let mut pending = Isometry3::identity();
        let mut folded = Vec::new();
        for j in path(robot, base_link, tip_link)? {
            if !finite_pose(&j.origin) {
                return Err(ChainError::NonFiniteOrigin {
                    joint: j.name.clone(),
                });
            }
            let origin = isometry_from_urdf_pose(&j.origin);
            let kind = match j.joint_type {
                urdf_rs::JointType::Fixed => {
                    pending *= origin;
                    folded.push(j.name.clone());
                    continue;
                }
                urdf_rs::JointType::Revolute => MovableKind::Revolute,
                urdf_rs::JointType::Continuous => MovableKind::Continuous,
                urdf_rs::JointType::Prismatic => MovableKind::Prismatic,
                ref other => {
                    return Err(ChainError::UnsupportedJoint {
                        joint: j.name.clone(),
                        kind: joint_kind_name(other),
                        base: base_link.into(),
                        tip: tip_link.into(),
                    });
                }
            };
            let a = Vector3::from(j.axis.xyz.0);
            let norm = a.norm();
            if !(norm.is_finite() && norm > 1e-9) {
                return Err(ChainError::BadAxis {
                    joint: j.name.clone(),
                    axis: j.axis.xyz.0,
                });
            }
            let axis = Unit::new_normalize(a);
            let limits = joint_limits(j, kind, &mut warnings)?;
            joints.push(ChainJoint {
                name: j.name.clone(),
                kind,
                parent_from_joint: origin,
                prev_from_parent: pending,
                folded_fixed: std::mem::take(&mut folded),
                axis,
                limits,
                // Resolved below, once every joint of the chain is known.
                drive: JointDrive::Variable(0),
                mimics: j.mimic.as_ref().map(|m| m.joint.clone()),
                joint_from_aligned: aligned_rotation(&axis),
                parent_link: j.parent.link.clone(),
                child_link: j.child.link.clone(),
            });
            pending = Isometry3::identity();
        }
        let variables = resolve_drives(robot, &mut joints, &mut warnings)?;
        if variables.is_empty() {
            return Err(ChainError::NoMovableJoint {
                base: base_link.into(),
                tip: tip_link.into(),
            });
        }
        let mut prev_c = UnitQuaternion::identity();
        let mut prev_aligned_from_aligned = Vec::with_capacity(joints.len());
        for j in &joints {
            let c = j.joint_from_aligned;
            prev_aligned_from_aligned.push(
                Isometry3::from_parts(Translation3::identity(), prev_c.inverse())
                    * j.prev_from_parent
                    * j.parent_from_joint
                    * Isometry3::from_parts(Translation3::identity(), c),
            );
            prev_c = c;
        }
        let last_aligned_from_tip =
            Isometry3::from_parts(Translation3::identity(), prev_c.inverse()) * pending;
        Ok(Self {
            base_link: base_link.into(),
            tip_link: tip_link.into(),
            joints,
            variables,
            last_from_tip: pending,
            warnings,
            prev_aligned_from_aligned,
            last_aligned_from_tip,
        })
    }
}

/// The unit factor from the URDF's value of a joint (m or rad) to the program's (mm or rad).
fn si_to_internal(kind: MovableKind) -> f64 {
    if kind.is_linear() { 1000.0 } else { 1.0 }
}

/// Where a mimic joint's value comes from: the joint that mimics none at the end of its leaders
/// (`root`), and `value = multiplier · root + offset` in URDF units (m, rad).
struct Followed {
    root: String,
    multiplier: f64,
    offset: f64,
}

/// Follow `joint`'s `<mimic>` leader by leader (composing the multipliers and offsets) to a joint
/// that mimics none: a chain joint with its own value, or a leader off the chain. A leader the
/// description lacks, a loop and a non-finite or zero multiplier are refused.
fn follow(
    by_name: &HashMap<&str, &urdf_rs::Joint>,
    joint: &ChainJoint,
    first: &str,
) -> Result<Followed, ChainError> {
    let (mut multiplier, mut offset) = (1.0, 0.0);
    let mut path = vec![joint.name.clone()];
    let mut current = joint.name.clone();
    let mut leader = first.to_string();
    loop {
        let mimic = by_name
            .get(current.as_str())
            .and_then(|u| u.mimic.as_ref())
            .ok_or_else(|| ChainError::MimicOutsideChain {
                joint: joint.name.clone(),
                mimicked: leader.clone(),
            })?;
        let (m, o) = (mimic.multiplier.unwrap_or(1.0), mimic.offset.unwrap_or(0.0));
        if !(m.is_finite() && o.is_finite() && m != 0.0) {
            return Err(ChainError::BadMimic { joint: current });
        }
        // value_current = m · value_leader + o.
        offset += multiplier * o;
        multiplier *= m;
        if path.contains(&leader) {
            path.push(leader);
            return Err(ChainError::MimicLoop {
                joint: joint.name.clone(),
                cycle: path.join(" → "),
            });
        }
        path.push(leader.clone());
        let Some(next) = by_name.get(leader.as_str()) else {
            return Err(ChainError::MimicOutsideChain {
                joint: joint.name.clone(),
                mimicked: leader,
            });
        };
        // A joint that mimics none has its own value: on the chain, or a leader off it.
        match &next.mimic {
            Some(m) => current = std::mem::replace(&mut leader, m.joint.clone()),
            None => break,
        }
    }
    Ok(Followed {
        root: leader,
        multiplier,
        offset,
    })
}

/// A leader off the chain as a variable: its kind and limits from the URDF (its origin and axis do
/// not matter: it moves nothing on the chain).
fn off_chain_variable(
    leader: &urdf_rs::Joint,
    follower: &str,
    warnings: &mut Vec<String>,
) -> Result<ChainVariable, ChainError> {
    let kind = match leader.joint_type {
        urdf_rs::JointType::Revolute => MovableKind::Revolute,
        urdf_rs::JointType::Continuous => MovableKind::Continuous,
        urdf_rs::JointType::Prismatic => MovableKind::Prismatic,
        ref other => {
            return Err(ChainError::LeaderNotMovable {
                joint: follower.to_string(),
                leader: leader.name.clone(),
                kind: joint_kind_name(other),
            });
        }
    };
    Ok(ChainVariable {
        name: leader.name.clone(),
        kind,
        limits: joint_limits(leader, kind, warnings)?,
        joint: None,
    })
}

/// The variables in chain order and every joint's drive: a joint that mimics none is its own
/// variable; a `<mimic>` is followed to the joint with its own value at the end of its leaders
/// ([`follow`]); a leader off the chain becomes a variable where its first follower stands.
fn resolve_drives(
    robot: &urdf_rs::Robot,
    joints: &mut [ChainJoint],
    warnings: &mut Vec<String>,
) -> Result<Vec<ChainVariable>, ChainError> {
    let by_name: HashMap<&str, &urdf_rs::Joint> =
        robot.joints.iter().map(|j| (j.name.as_str(), j)).collect();
    let own: HashMap<String, usize> = joints
        .iter()
        .enumerate()
        .filter(|(_, j)| j.mimics.is_none())
        .map(|(k, j)| (j.name.clone(), k))
        .collect();
    let followed = joints
        .iter()
        .map(|j| {
            j.mimics
                .as_deref()
                .map(|first| follow(&by_name, j, first))
                .transpose()
        })
        .collect::<Result<Vec<_>, _>>()?;
    let mut variables: Vec<ChainVariable> = Vec::new();
    let mut variable_of: HashMap<String, usize> = HashMap::new();
    for (k, (j, f)) in joints.iter().zip(&followed).enumerate() {
        let variable = match f {
            None => ChainVariable {
                name: j.name.clone(),
                kind: j.kind,
                limits: j.limits,
                joint: Some(k),
            },
            Some(f) if !own.contains_key(&f.root) && !variable_of.contains_key(&f.root) => {
                off_chain_variable(by_name[f.root.as_str()], &j.name, warnings)?
            }
            Some(_) => continue,
        };
        variable_of.insert(variable.name.clone(), variables.len());
        variables.push(variable);
    }
    for (j, f) in joints.iter_mut().zip(followed) {
        let index = variable_of[f.as_ref().map_or(&j.name, |f| &f.root)];
        j.drive = match f {
            None => JointDrive::Variable(index),
            Some(f) => {
                let (to, from) = (
                    si_to_internal(j.kind),
                    si_to_internal(variables[index].kind),
                );
                JointDrive::Mimic {
                    leader: index,
                    multiplier: f.multiplier * to / from,
                    offset: f.offset * to,
                }
            }
        };
    }
    Ok(variables)
}

/// URDF roll, pitch, yaw of a rotation (`R = Rz(yaw) Ry(pitch) Rx(roll)`).
///
/// Yaw and pitch are read from the first column; roll from `(Rz(yaw) Ry(pitch))ᵀ R`, so that the
/// triple reproduces `R` to round-off even near gimbal lock (an error in yaw is absorbed by roll).
pub fn rpy_from_rotation(r: &nalgebra::Rotation3<f64>) -> [f64; 3] {
    let m: &nalgebra::Matrix3<f64> = r.matrix();
    let yaw = if m[(1, 0)].abs() + m[(0, 0)].abs() > 1e-300 {
        m[(1, 0)].atan2(m[(0, 0)])
    } else {
        0.0
    };
    let pitch = (-m[(2, 0)]).atan2(m[(0, 0)].hypot(m[(1, 0)]));
    let rest = (nalgebra::Rotation3::from_axis_angle(&nalgebra::Vector3::z_axis(), yaw)
        * nalgebra::Rotation3::from_axis_angle(&nalgebra::Vector3::y_axis(), pitch))
    .inverse()
        * r;
    let k = rest.matrix();
    let roll = (k[(2, 1)] - k[(1, 2)]).atan2(k[(1, 1)] + k[(2, 2)]);
    [roll, pitch, yaw]
}
