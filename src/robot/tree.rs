//! The URDF compiled into a kinematic tree: joints in topological order, the arms' joints and tips,
//! the body link, each arm's model base frame and each link's owner.

use super::arms::ArmSpec;
use super::dh::joint1_from_dh_base;
use super::{
    Messages, ModelForm, Owner, RobotError, ShapeKind, finite_pose, isometry_from_urdf_pose,
};
use crate::kinematics::JointDrive;
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
    /// (arm, chain position among the chain's movable joints) of the arms' movable joints.
    pub(crate) arm: Option<(Side, usize)>,
    /// How an arm joint gets its value from the arm's variables (its own, or a mimic's leader).
    pub(crate) drive: Option<JointDrive>,
    /// On both arms' chains (a torso): `arm` is the left arm's position.
    pub(crate) shared: bool,
    /// For a shared joint: how the right arm's variables drive it (used when only the right arm's
    /// values are given).
    pub(crate) right_drive: Option<JointDrive>,
}

/// The description compiled for fast forward kinematics.
#[derive(Clone, Debug)]
pub(crate) struct Kinematics {
    pub(crate) link_names: Vec<String>,
    /// Joints in topological order (a joint's parent link is placed before it is used).
    pub(crate) joints: Vec<KinJoint>,
    /// Index of the body link: the deepest link above both arms' base links.
    pub(crate) body: usize,
    /// Links connected to the body link's tree.
    pub(crate) reachable: Vec<bool>,
    pub(crate) owner: Vec<Owner>,
    /// For every link, the index in `joints` of its parent joint.
    parent_joint: Vec<Option<usize>>,
    /// Link index of each arm's tip link.
    pub(crate) flange: PerSide<usize>,
    /// Each arm's model base frame (DH frame 0, or the base link) in the body frame.
    pub(crate) body_from_arm_base: PerSide<Isometry3<f64>>,
    pub(crate) visual: Vec<LocalShape>,
    pub(crate) collision: Vec<LocalShape>,
}

impl Kinematics {
    fn motion(&self, joint: &KinJoint, q_left: &[f64], q_right: &[f64]) -> Isometry3<f64> {
        let q = match (joint.arm, joint.drive) {
            // A shared joint: the left arm's value, or the right arm's when only those are given.
            (Some((Side::Left, _)), Some(d)) => match joint.right_drive {
                Some(r) if q_left.is_empty() => r.value(q_right),
                _ => d.value(q_left),
            },
            (Some((Side::Right, _)), Some(d)) => d.value(q_right),
            _ => 0.0,
        };
        motion_transform(&joint.motion, q)
    }

    /// Every link's pose in the body frame (indexed like `link_names`; unreachable links get the
    /// pose relative to their own root, and are filtered by callers).
    pub(crate) fn body_from_links(&self, q_left: &[f64], q_right: &[f64]) -> Vec<Isometry3<f64>> {
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
    pub(crate) fn body_from_link(&self, link: usize, side: Side, q: &[f64]) -> Isometry3<f64> {
        let mut qs: PerSide<&[f64]> = PerSide::new(&[], &[]);
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

    /// The link called `name`, if it hangs below `link` through fixed joints only.
    pub(crate) fn fixed_below(&self, link: usize, name: &str) -> Option<usize> {
        let found = self.link_names.iter().position(|n| n == name)?;
        let mut l = found;
        while let Some(ji) = self.parent_joint[l] {
            let j = &self.joints[ji];
            if !matches!(j.motion, Motion::Fixed) {
                return None;
            }
            if j.parent == link {
                return Some(found);
            }
            l = j.parent;
        }
        None
    }

    /// The links from `link` up to its root, `link` first.
    fn ancestors(&self, mut link: usize) -> Vec<usize> {
        let mut out = vec![link];
        while let Some(ji) = self.parent_joint[link] {
            link = self.joints[ji].parent;
            out.push(link);
        }
        out
    }
}

/// A joint's motion at value `q`: rad, or mm for a prismatic joint.
pub(crate) fn motion_transform(motion: &Motion, q: f64) -> Isometry3<f64> {
    match motion {
        Motion::Fixed => Isometry3::identity(),
        Motion::Revolute(axis) => Isometry3::from_parts(
            Translation3::identity(),
            UnitQuaternion::from_axis_angle(axis, q),
        ),
        Motion::Prismatic(axis) => Isometry3::translation(axis.x * q, axis.y * q, axis.z * q),
    }
}

/// The URDF's links and joints, checked (no duplicate, undefined link, non-finite origin, bad axis,
/// second parent or loop) and in topological order, before the arms are known.
pub(crate) struct Tree {
    link_names: Vec<String>,
    link_index: HashMap<String, usize>,
    joints: Vec<KinJoint>,
    /// The joints' names, in `joints` order.
    joint_names: Vec<String>,
    parent_joint: Vec<Option<usize>>,
    root_of: Vec<usize>,
}

/// Check and order the links and joints of a parsed URDF.
pub(crate) fn parse_tree(
    urdf: &urdf_rs::Robot,
    msg: &Messages,
    warnings: &mut Vec<String>,
) -> Result<Tree, RobotError> {
    let link_names: Vec<String> = urdf.links.iter().map(|l| l.name.clone()).collect();
    let mut link_index: HashMap<String, usize> = HashMap::new();
    for (i, n) in link_names.iter().enumerate() {
        if link_index.insert(n.clone(), i).is_some() {
            return Err(msg.structure(format!("link `{n}` is defined twice")));
        }
    }
    let raw = parse_joints(urdf, &link_index, msg, warnings)?;
    let ordered = order_tree(urdf, raw, &link_names, msg)?;
    Ok(Tree {
        link_names,
        link_index,
        joints: ordered.joints,
        joint_names: ordered.names,
        parent_joint: ordered.parent_joint,
        root_of: ordered.root_of,
    })
}

/// Compile the tree with its arms into the kinematics: the arms' joints, tips, the body link and the
/// model base frames (the shapes are `geometry::compile_shapes`' part).
pub(crate) fn compile(
    mut tree: Tree,
    arms: &PerSide<ArmSpec>,
    form: ModelForm,
    msg: &Messages,
    warnings: &mut Vec<String>,
) -> Result<Kinematics, RobotError> {
    // Each arm's movable joints with their chain position. A joint on both chains (a shared torso)
    // keeps the left arm's: posing the whole robot, its value is the left arm's column.
    // A leader off the chain (the virtual joint a column's stages mimic) is driven by its column,
    // at its first follower's position.
    for (side, spec) in arms.iter() {
        let chain = &spec.chain;
        let leaders = chain.variables().iter().enumerate().filter_map(|(i, v)| {
            let first = chain
                .joints
                .iter()
                .position(|j| j.drive.leader() == Some(i))?;
            v.is_off_chain()
                .then_some((first, v.name.as_str(), JointDrive::Variable(i)))
        });
        let on_chain = chain.joints.iter().enumerate();
        for (k, name, drive) in on_chain
            .map(|(k, j)| (k, j.name.as_str(), j.drive))
            .chain(leaders)
        {
            let Some(ji) = tree.joint_names.iter().position(|n| n == name) else {
                continue;
            };
            if tree.joints[ji].arm.is_some() {
                tree.joints[ji].shared = true;
                tree.joints[ji].right_drive = Some(drive);
            } else {
                tree.joints[ji].arm = Some((side, k));
                tree.joints[ji].drive = Some(drive);
            }
        }
    }
    let index = |name: &str| tree.link_index[name];
    let flange = arms.as_ref().map(|_, a| index(&a.links.tip_link));
    let bases = arms.as_ref().map(|_, a| index(&a.links.base_link));
    let mut kin = Kinematics {
        link_names: tree.link_names,
        joints: tree.joints,
        body: 0,
        reachable: Vec::new(),
        owner: Vec::new(),
        parent_joint: tree.parent_joint,
        flange,
        body_from_arm_base: PerSide::new(Isometry3::identity(), Isometry3::identity()),
        visual: Vec::new(),
        collision: Vec::new(),
    };
    // The body: the deepest common ancestor of both base links.
    let right_up = kin.ancestors(bases.right);
    kin.body = kin
        .ancestors(bases.left)
        .into_iter()
        .find(|l| right_up.contains(l))
        .ok_or_else(|| {
            msg.structure(format!(
                "the arms' base links `{}` and `{}` are not connected",
                arms.left.links.base_link, arms.right.links.base_link
            ))
        })?;
    kin.reachable = tree
        .root_of
        .iter()
        .map(|&r| r == tree.root_of[kin.body])
        .collect();
    let unreachable: Vec<&str> = (0..kin.link_names.len())
        .filter(|&l| !kin.reachable[l])
        .map(|l| kin.link_names[l].as_str())
        .collect();
    if !unreachable.is_empty() {
        warnings.push(format!(
            "link(s) {} are not connected to `{}` and are ignored",
            unreachable.join(", "),
            kin.link_names[kin.body]
        ));
    }
    for side in Side::BOTH {
        // Movable joints between the body and a base link are held at zero.
        for &l in kin
            .ancestors(bases[side])
            .iter()
            .take_while(|&&l| l != kin.body)
        {
            if let Some(ji) = kin.parent_joint[l]
                && !matches!(kin.joints[ji].motion, Motion::Fixed)
            {
                warnings.push(format!(
                    "a movable joint above the {side} arm's base link `{}` (to `{}`) is held at zero",
                    arms[side].links.base_link, kin.link_names[l]
                ));
            }
        }
    }
    kin.owner = owners(&kin);
    kin.body_from_arm_base = match form {
        ModelForm::Chain => bases.map(|side, b| kin.body_from_link(b, side, &[])),
        ModelForm::Dh => dh_base_frames(&kin, arms),
    };
    Ok(kin)
}

/// DH base frames: each arm's joint-1 frame (at zero) · Tz(−66) · Rz(π), in the body frame.
fn dh_base_frames(kin: &Kinematics, arms: &PerSide<ArmSpec>) -> PerSide<Isometry3<f64>> {
    let poses = kin.body_from_links(&[], &[]);
    arms.as_ref().map(|side, _| {
        let j1 = kin
            .joints
            .iter()
            .filter(|j| !j.shared && matches!(j.arm, Some((s, _)) if s == side))
            .min_by_key(|j| j.arm.map_or(0, |(_, k)| k))
            .expect("every arm has a first movable joint of its own");
        poses[j1.parent] * j1.parent_from_joint * joint1_from_dh_base()
    })
}

/// Every joint of the file, in file order, with its links, origin and motion.
fn parse_joints(
    urdf: &urdf_rs::Robot,
    link_index: &HashMap<String, usize>,
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
            drive: None,
            shared: false,
            right_drive: None,
        });
    }
    check_mimics(urdf, msg, warnings)?;
    Ok(raw)
}

/// Every `<mimic>` of the file: a loop (a joint that, leader by leader, follows itself) is refused
/// with the first joint's line; a leader that is not a joint of the file is a warning (the joint is
/// then held at its offset).
fn check_mimics(
    urdf: &urdf_rs::Robot,
    msg: &Messages,
    warnings: &mut Vec<String>,
) -> Result<(), RobotError> {
    let leader_of: HashMap<&str, &str> = urdf
        .joints
        .iter()
        .filter_map(|j| {
            j.mimic
                .as_ref()
                .map(|m| (j.name.as_str(), m.joint.as_str()))
        })
        .collect();
    for j in &urdf.joints {
        let Some(first) = leader_of.get(j.name.as_str()) else {
            continue;
        };
        if !urdf.joints.iter().any(|k| k.name == *first) {
            warnings.push(format!(
                "joint `{}` mimics `{first}`, which is not a joint of the description",
                j.name
            ));
            continue;
        }
        let mut path = vec![j.name.as_str()];
        let mut next = Some(*first);
        while let Some(l) = next {
            if path.contains(&l) {
                path.push(l);
                return Err(msg.bad_joint(
                    &j.name,
                    format!(
                        "<mimic> loop: {} (a joint cannot follow itself)",
                        path.join(" → ")
                    ),
                ));
            }
            path.push(l);
            next = leader_of.get(l).copied();
        }
    }
    Ok(())
}

/// The joints in topological order (from the roots down) and the tree's bookkeeping.
struct OrderedTree {
    joints: Vec<KinJoint>,
    /// The joints' names, in `joints` order.
    names: Vec<String>,
    /// For every link, the index in `joints` of its parent joint.
    parent_joint: Vec<Option<usize>>,
    /// For every link, the root link of its tree.
    root_of: Vec<usize>,
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
    let names: Vec<String> = order.iter().map(|&o| urdf.joints[o].name.clone()).collect();
    let parent_joint: Vec<Option<usize>> = parent_joint_raw
        .iter()
        .map(|p| p.map(|o| new_index[o]))
        .collect();
    Ok(OrderedTree {
        joints,
        names,
        parent_joint,
        root_of,
    })
}

/// Owners: every link below an arm's first movable joint of its own (the first one the other arm's
/// chain does not hold) belongs to that arm, the rest to the body (a shared torso carries both).
fn owners(kin: &Kinematics) -> Vec<Owner> {
    let mut first_own: PerSide<Option<usize>> = PerSide::default();
    for j in kin.joints.iter().filter(|j| !j.shared) {
        if let Some((side, k)) = j.arm {
            first_own[side] = Some(first_own[side].map_or(k, |f: usize| f.min(k)));
        }
    }
    let mut owner = vec![Owner::Body; kin.link_names.len()];
    for j in &kin.joints {
        owner[j.child] = match j.arm {
            Some((side, k)) if !j.shared && first_own[side] == Some(k) => Owner::Arm(side),
            _ => owner[j.parent],
        };
    }
    owner
}
