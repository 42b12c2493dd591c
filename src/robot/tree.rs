//! The URDF compiled into a kinematic tree: joints in topological order, the arms' joints, links
//! and flanges, and each link's owner.

use super::dh::{arm_joint_name, dh_base_frames, flange_link_name};
use super::geometry::{MeshResolver, compile_shapes};
use super::{Owner, RobotError, ShapeKind, finite_pose, isometry_from_urdf_pose, line_of};
use crate::kinematics::N_JOINTS;
use crate::side::{PerSide, Side};
use nalgebra::{Isometry3, Translation3, Unit, UnitQuaternion, Vector3};
use std::collections::HashMap;

/// A shape in its link's frame (compiled once).
#[derive(Clone, Debug)]
pub(crate) struct LocalShape {
    pub(crate) link: usize,
    pub(crate) kind: ShapeKind,
    pub(crate) link_from_shape: Isometry3<f64>,
    pub(crate) rgba: [f32; 4],
}

#[derive(Clone, Debug)]
pub(crate) enum Motion {
    Fixed,
    Revolute(Unit<Vector3<f64>>),
    Prismatic(Unit<Vector3<f64>>),
}

#[derive(Clone, Debug)]
pub(crate) struct KinJoint {
    pub(crate) parent: usize,
    pub(crate) child: usize,
    /// The joint frame in the parent link's frame (the URDF `<origin>`), mm.
    pub(crate) parent_from_joint: Isometry3<f64>,
    pub(crate) motion: Motion,
    /// (arm, chain position) of the seven arm joints.
    pub(crate) arm: Option<(Side, usize)>,
}

/// The description compiled for fast forward kinematics.
#[derive(Clone, Debug)]
pub(crate) struct Kinematics {
    pub(crate) link_names: Vec<String>,
    /// Joints in topological order (a joint's parent link is placed before it is used).
    pub(crate) joints: Vec<KinJoint>,
    /// Index of the body link (parent of `yumi_joint_1_l`).
    pub(crate) body: usize,
    /// Links connected to the body link's tree.
    pub(crate) reachable: Vec<bool>,
    pub(crate) owner: Vec<Owner>,
    /// For every link, the index in `joints` of its parent joint.
    parent_joint: Vec<Option<usize>>,
    /// Link index of each arm's flange (`yumi_flange_x`, or link_7 as a fallback).
    pub(crate) flange: PerSide<usize>,
    /// Link indices of link_1..link_7 of each arm.
    pub(crate) arm_links: PerSide<[usize; N_JOINTS]>,
    pub(crate) body_from_dh_base: PerSide<Isometry3<f64>>,
    pub(crate) visual: Vec<LocalShape>,
    pub(crate) collision: Vec<LocalShape>,
}

impl Kinematics {
    fn motion(
        &self,
        joint: &KinJoint,
        q_left: &[f64; N_JOINTS],
        q_right: &[f64; N_JOINTS],
    ) -> Isometry3<f64> {
        let q = match joint.arm {
            Some((Side::Left, k)) => q_left[k],
            Some((Side::Right, k)) => q_right[k],
            None => 0.0,
        };
        motion_transform(&joint.motion, q)
    }

    /// Every link's pose in the body frame (indexed like `link_names`; unreachable links get the
    /// pose relative to their own root, and are filtered by callers).
    pub(crate) fn body_from_links(
        &self,
        q_left: &[f64; N_JOINTS],
        q_right: &[f64; N_JOINTS],
    ) -> Vec<Isometry3<f64>> {
        let mut poses = vec![Isometry3::identity(); self.link_names.len()];
        for j in &self.joints {
            poses[j.child] =
                poses[j.parent] * j.parent_from_joint * self.motion(j, q_left, q_right);
        }
        let root_from_body_inv = poses[self.body].inverse();
        for p in &mut poses {
            *p = root_from_body_inv * *p;
        }
        poses
    }

    /// For every link, the index of its rigid group: links joined by fixed joints move as one body.
    pub(crate) fn rigid_groups(&self) -> Vec<usize> {
        let mut group: Vec<usize> = (0..self.link_names.len()).collect();
        // Joints are in topological order, so a child inherits its parent's final group.
        for j in &self.joints {
            if matches!(j.motion, Motion::Fixed) {
                group[j.child] = group[j.parent];
            }
        }
        group
    }

    /// (parent link, child link) of every movable joint.
    pub(crate) fn moving_joint_links(&self) -> Vec<(usize, usize)> {
        self.joints
            .iter()
            .filter(|j| !matches!(j.motion, Motion::Fixed))
            .map(|j| (j.parent, j.child))
            .collect()
    }

    /// Pose of one link in the body frame, with `side` at `q` and everything else at zero.
    pub(crate) fn body_from_link(
        &self,
        link: usize,
        side: Side,
        q: &[f64; N_JOINTS],
    ) -> Isometry3<f64> {
        let zero = [0.0; N_JOINTS];
        let mut qs = PerSide::new(&zero, &zero);
        qs[side] = q;
        let (ql, qr) = (qs.left, qs.right);
        // Walk up to the root, then compose downwards.
        let chain_from_root = |mut l: usize| {
            let mut acc = Isometry3::identity();
            while let Some(ji) = self.parent_joint[l] {
                let j = &self.joints[ji];
                acc = j.parent_from_joint * self.motion(j, ql, qr) * acc;
                l = j.parent;
            }
            acc
        };
        chain_from_root(self.body).inverse() * chain_from_root(link)
    }
}

pub(crate) fn motion_transform(motion: &Motion, q: f64) -> Isometry3<f64> {
    match motion {
        Motion::Fixed => Isometry3::identity(),
        Motion::Revolute(axis) => Isometry3::from_parts(
            Translation3::identity(),
            UnitQuaternion::from_axis_angle(axis, q),
        ),
        Motion::Prismatic(axis) => Isometry3::translation(
            axis.x * q * 1000.0,
            axis.y * q * 1000.0,
            axis.z * q * 1000.0,
        ),
    }
}

/// Names and line lookups for the messages of one URDF file.
struct Messages<'a> {
    text: &'a str,
    file: &'a str,
}

impl Messages<'_> {
    fn structure(&self, message: String) -> RobotError {
        RobotError::Structure {
            file: self.file.to_string(),
            message,
        }
    }

    fn bad_joint(&self, joint: &str, problem: String) -> RobotError {
        RobotError::BadJoint {
            file: self.file.to_string(),
            line: line_of(self.text, &format!("name=\"{joint}\"")),
            joint: joint.to_string(),
            problem,
        }
    }
}

/// Compile a parsed URDF into the kinematic tree with its arms, flanges, DH base frames and shapes.
pub(crate) fn compile(
    urdf: &urdf_rs::Robot,
    text: &str,
    file: &str,
    resolver: &MeshResolver<'_>,
    warnings: &mut Vec<String>,
) -> Result<Kinematics, RobotError> {
    let msg = Messages { text, file };
    // The seven joints of each arm must exist.
    let missing: Vec<String> = Side::BOTH
        .iter()
        .flat_map(|&s| (0..N_JOINTS).map(move |k| arm_joint_name(s, k)))
        .filter(|n| !urdf.joints.iter().any(|j| &j.name == n))
        .collect();
    if !missing.is_empty() {
        return Err(RobotError::MissingJoints {
            file: file.to_string(),
            missing,
        });
    }
    let link_names: Vec<String> = urdf.links.iter().map(|l| l.name.clone()).collect();
    let mut link_index: HashMap<&str, usize> = HashMap::new();
    for (i, n) in link_names.iter().enumerate() {
        if link_index.insert(n.as_str(), i).is_some() {
            return Err(msg.structure(format!("link `{n}` is defined twice")));
        }
    }
    let mut raw = parse_joints(urdf, &link_index, &msg, warnings)?;
    let arm_joints_raw = mark_arm_joints(urdf, &mut raw, &link_names, &msg, warnings)?;
    let tree = order_tree(urdf, raw, &link_names, &msg)?;
    let arm_joints = arm_joints_raw.map(|_, idx| idx.map(|k| tree.new_index[k]));
    let joints = tree.joints;
    let body = joints[arm_joints.left[0]].parent;
    let reachable: Vec<bool> = tree
        .root_of
        .iter()
        .map(|&r| r == tree.root_of[body])
        .collect();
    let unreachable: Vec<&str> = (0..link_names.len())
        .filter(|&l| !reachable[l])
        .map(|l| link_names[l].as_str())
        .collect();
    if !unreachable.is_empty() {
        warnings.push(format!(
            "link(s) {} are not connected to `{}` and are ignored",
            unreachable.join(", "),
            link_names[body]
        ));
    }
    let owner = owners(&joints, link_names.len(), body, &arm_joints, &msg)?;
    let arm_links = arm_joints.map(|_, idx| idx.map(|k| joints[k].child));
    let flange = PerSide::from_fn(|side| {
        find_flange(
            side,
            arm_links[side][N_JOINTS - 1],
            &joints,
            &tree.parent_joint,
            &link_index,
            &link_names,
            warnings,
        )
    });
    let mut kin = Kinematics {
        link_names,
        joints,
        body,
        reachable,
        owner,
        parent_joint: tree.parent_joint,
        flange,
        arm_links,
        body_from_dh_base: PerSide::new(Isometry3::identity(), Isometry3::identity()),
        visual: Vec::new(),
        collision: Vec::new(),
    };
    kin.body_from_dh_base = dh_base_frames(&kin, &arm_joints);
    compile_shapes(urdf, resolver, &mut kin, warnings);
    Ok(kin)
}

/// Every joint of the file, in file order, with its links, origin and motion.
fn parse_joints(
    urdf: &urdf_rs::Robot,
    link_index: &HashMap<&str, usize>,
    msg: &Messages,
    warnings: &mut Vec<String>,
) -> Result<Vec<KinJoint>, RobotError> {
    let mut raw: Vec<KinJoint> = Vec::with_capacity(urdf.joints.len());
    let mut seen_joint: HashMap<&str, ()> = HashMap::new();
    for j in &urdf.joints {
        if seen_joint.insert(j.name.as_str(), ()).is_some() {
            return Err(msg.bad_joint(&j.name, "defined twice".into()));
        }
        let find = |l: &str, role: &str| {
            link_index
                .get(l)
                .copied()
                .ok_or_else(|| msg.bad_joint(&j.name, format!("{role} link `{l}` is not defined")))
        };
        let parent = find(&j.parent.link, "parent")?;
        let child = find(&j.child.link, "child")?;
        if !finite_pose(&j.origin) {
            return Err(msg.bad_joint(&j.name, "origin has non-finite values".into()));
        }
        let axis = || {
            let a = Vector3::new(j.axis.xyz[0], j.axis.xyz[1], j.axis.xyz[2]);
            Unit::try_new(a, 1e-12)
                .filter(|u| u.iter().all(|v| v.is_finite()))
                .ok_or_else(|| {
                    msg.bad_joint(
                        &j.name,
                        format!("axis {:?} is not a direction", j.axis.xyz.0),
                    )
                })
        };
        let motion = match j.joint_type {
            urdf_rs::JointType::Revolute | urdf_rs::JointType::Continuous => {
                Motion::Revolute(axis()?)
            }
            urdf_rs::JointType::Prismatic => Motion::Prismatic(axis()?),
            urdf_rs::JointType::Fixed => Motion::Fixed,
            ref other => {
                warnings.push(format!(
                    "joint `{}` of type {other:?} is held fixed",
                    j.name
                ));
                Motion::Fixed
            }
        };
        raw.push(KinJoint {
            parent,
            child,
            parent_from_joint: isometry_from_urdf_pose(&j.origin),
            motion,
            arm: None,
        });
    }
    Ok(raw)
}

/// Mark the seven joints of each arm (revolute, chained, ideally about +z) and return their indices
/// in `raw`, in chain order.
fn mark_arm_joints(
    urdf: &urdf_rs::Robot,
    raw: &mut [KinJoint],
    link_names: &[String],
    msg: &Messages,
    warnings: &mut Vec<String>,
) -> Result<PerSide<[usize; N_JOINTS]>, RobotError> {
    let joint_pos = |name: &str| urdf.joints.iter().position(|j| j.name == name);
    let mut arm_joint_idx = PerSide::new([0usize; N_JOINTS], [0usize; N_JOINTS]);
    for side in Side::BOTH {
        for k in 0..N_JOINTS {
            let name = arm_joint_name(side, k);
            let Some(ji) = joint_pos(&name) else {
                return Err(msg.bad_joint(&name, "missing".into()));
            };
            let j = &urdf.joints[ji];
            if !matches!(
                j.joint_type,
                urdf_rs::JointType::Revolute | urdf_rs::JointType::Continuous
            ) {
                return Err(msg.bad_joint(
                    &name,
                    format!("type is {:?}, expected revolute", j.joint_type),
                ));
            }
            if let Motion::Revolute(axis) = &raw[ji].motion
                && (axis.into_inner() - Vector3::z()).norm() > 1e-9
            {
                warnings.push(format!(
                    "joint `{name}` turns about {:?}, not 0 0 1: the DH correspondence assumes +z",
                    j.axis.xyz.0
                ));
            }
            if k > 0 {
                let prev = &raw[arm_joint_idx[side][k - 1]];
                if raw[ji].parent != prev.child {
                    return Err(msg.bad_joint(
                        &name,
                        format!(
                            "parent link is `{}`, expected `{}` (the child of `{}`)",
                            j.parent.link,
                            link_names[prev.child],
                            arm_joint_name(side, k - 1)
                        ),
                    ));
                }
            }
            raw[ji].arm = Some((side, k));
            arm_joint_idx[side][k] = ji;
        }
    }
    Ok(arm_joint_idx)
}

/// The joints in topological order (from the roots down) and the tree's bookkeeping.
struct OrderedTree {
    joints: Vec<KinJoint>,
    /// For every link, the index in `joints` of its parent joint.
    parent_joint: Vec<Option<usize>>,
    /// For every link, the root link of its tree.
    root_of: Vec<usize>,
    /// File-order joint index → topological index.
    new_index: Vec<usize>,
}

/// Check the tree structure (each link has at most one parent joint, no loops) and order the joints.
fn order_tree(
    urdf: &urdf_rs::Robot,
    raw: Vec<KinJoint>,
    link_names: &[String],
    msg: &Messages,
) -> Result<OrderedTree, RobotError> {
    let mut parent_joint_raw: Vec<Option<usize>> = vec![None; link_names.len()];
    for (ji, j) in raw.iter().enumerate() {
        if let Some(other) = parent_joint_raw[j.child] {
            return Err(msg.structure(format!(
                "link `{}` has two parent joints (`{}` and `{}`)",
                link_names[j.child], urdf.joints[other].name, urdf.joints[ji].name
            )));
        }
        parent_joint_raw[j.child] = Some(ji);
    }
    let mut children: Vec<Vec<usize>> = vec![Vec::new(); link_names.len()];
    for (ji, j) in raw.iter().enumerate() {
        children[j.parent].push(ji);
    }
    let roots: Vec<usize> = (0..link_names.len())
        .filter(|&l| parent_joint_raw[l].is_none())
        .collect();
    let mut order: Vec<usize> = Vec::with_capacity(raw.len());
    let mut root_of = vec![usize::MAX; link_names.len()];
    for &r in &roots {
        root_of[r] = r;
        let mut stack = vec![r];
        while let Some(l) = stack.pop() {
            for &ji in &children[l] {
                order.push(ji);
                root_of[raw[ji].child] = r;
                stack.push(raw[ji].child);
            }
        }
    }
    if order.len() != raw.len() {
        let in_loop: Vec<&str> = (0..link_names.len())
            .filter(|&l| root_of[l] == usize::MAX)
            .map(|l| link_names[l].as_str())
            .collect();
        return Err(msg.structure(format!(
            "kinematic loop through link(s) {}",
            in_loop.join(", ")
        )));
    }
    let mut new_index = vec![0usize; raw.len()];
    for (new, &old) in order.iter().enumerate() {
        new_index[old] = new;
    }
    let joints: Vec<KinJoint> = order.iter().map(|&o| raw[o].clone()).collect();
    let parent_joint: Vec<Option<usize>> = parent_joint_raw
        .iter()
        .map(|p| p.map(|o| new_index[o]))
        .collect();
    Ok(OrderedTree {
        joints,
        parent_joint,
        root_of,
        new_index,
    })
}

/// Owners: every link below an arm's joint 1 belongs to that arm, the rest to the body.
fn owners(
    joints: &[KinJoint],
    n_links: usize,
    body: usize,
    arm_joints: &PerSide<[usize; N_JOINTS]>,
    msg: &Messages,
) -> Result<Vec<Owner>, RobotError> {
    let mut owner = vec![Owner::Body; n_links];
    for j in joints {
        owner[j.child] = match j.arm {
            Some((side, 0)) => Owner::Arm(side),
            _ => owner[j.parent],
        };
    }
    for side in Side::BOTH {
        let l1 = joints[arm_joints[side][0]].child;
        if owner[body] != Owner::Body || owner[l1] != Owner::Arm(side) {
            return Err(msg.structure(format!("the {side} arm is not a branch of the body link")));
        }
    }
    Ok(owner)
}

/// The flange link of `side`: `yumi_flange_x` when it is fixed below link 7, else link 7 (with a
/// warning).
fn find_flange(
    side: Side,
    link7: usize,
    joints: &[KinJoint],
    parent_joint: &[Option<usize>],
    link_index: &HashMap<&str, usize>,
    link_names: &[String],
    warnings: &mut Vec<String>,
) -> usize {
    let name = flange_link_name(side);
    let fixed_below_link7 = |mut l: usize| {
        while let Some(ji) = parent_joint[l] {
            let j = &joints[ji];
            if !matches!(j.motion, Motion::Fixed) {
                return false;
            }
            if j.parent == link7 {
                return true;
            }
            l = j.parent;
        }
        false
    };
    match link_index.get(name.as_str()) {
        Some(&l) if fixed_below_link7(l) => l,
        Some(_) => {
            warnings.push(format!(
                "link `{name}` is not fixed to `{}`; the flange is taken to be `{}`",
                link_names[link7], link_names[link7]
            ));
            link7
        }
        None => {
            warnings.push(format!(
                "no link `{name}`; the flange is taken to be `{}`",
                link_names[link7]
            ));
            link7
        }
    }
}
