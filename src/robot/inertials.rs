//! The robot's `<inertial>` elements as the lumped masses of the elastic models
//! ([`crate::kinematics::joint_errors`]).

use super::RobotDescription;
use crate::side::{PerSide, Side};
use nalgebra::{Isometry3, Vector3};

impl RobotDescription {
    /// The lumped masses of `side`'s chain from the URDF's `<inertial>` elements, for the elastic
    /// models' torques: per movable joint, the links it carries up to the next movable joint (its
    /// child link and every link fixed to it, side branches such as fingers included) as one mass (kg)
    /// and first moment (kg·mm) in the next joint's frame (the chain's aligned frame; the tip frame
    /// after the last joint). `None` for the built-in robot and for a description without inertials
    /// (the error model then holds 1 kg at each next joint). The other arm of a shared torso is not
    /// part of any link here: its masses come from its own chain at each measured instant.
    pub fn lumped_masses(&self, side: Side) -> Option<crate::kinematics::joint_errors::LinkMasses> {
        if self.is_builtin() {
            return None;
        }
        let chain = &self.arm(side).chain;
        let zeros = PerSide::from_fn(|s| vec![0.0; self.arm(s).chain.dof()]);
        let body: std::collections::HashMap<String, Isometry3<f64>> = self
            .link_poses(&zeros.left, &zeros.right)
            .into_iter()
            .collect();
        let base_from_body = self.body_from_arm_base(side).inverse();
        let corrections = vec![[0.0; crate::kinematics::PARAMS_PER_JOINT]; chain.joint_count()];
        let frames = chain.joint_frames(&corrections, &zeros[side]);
        let mut total = 0.0;
        let out: crate::kinematics::joint_errors::LinkMasses = chain
            .joints
            .iter()
            .enumerate()
            .map(|(k, joint)| {
                // The child link and everything fixed to it.
                let mut group = vec![joint.child_link.clone()];
                let mut i = 0;
                while i < group.len() {
                    for j in &self.urdf.joints {
                        if j.parent.link == group[i]
                            && matches!(j.joint_type, urdf_rs::JointType::Fixed)
                            && !group.contains(&j.child.link)
                        {
                            group.push(j.child.link.clone());
                        }
                    }
                    i += 1;
                }
                let frame_from_base = frames[k + 1].inverse();
                let (mut m, mut s) = (0.0, Vector3::zeros());
                for name in &group {
                    let (Some(link), Some(pose)) = (
                        self.urdf.links.iter().find(|l| &l.name == name),
                        body.get(name),
                    ) else {
                        continue;
                    };
                    let mass = link.inertial.mass.value;
                    if !(mass.is_finite() && mass > 0.0) {
                        continue;
                    }
                    let c = link.inertial.origin.xyz.0;
                    // The inertial origin in the link frame, metres; the poses are in mm.
                    let com_body = nalgebra::Point3::from(
                        pose.translation.vector
                            + pose.rotation * Vector3::new(c[0], c[1], c[2]) * 1000.0,
                    );
                    let com = frame_from_base * (base_from_body * com_body);
                    m += mass;
                    s += com.coords * mass;
                }
                total += m;
                (m, [s.x, s.y, s.z])
            })
            .collect();
        (total > 0.0).then_some(out)
    }
}
