//! Which chains of the description are the arms: given per arm as `base_link` and `tip_link`, or found
//! by the YuMi naming scheme.

use super::dh::{ARM_JOINT_NUMBERS, arm_joint_name, flange_link_name};
use super::{Messages, RobotError};
pub use crate::kinematics::ArmLinks;
use crate::kinematics::{ChainError, SerialChain};
use crate::side::{PerSide, Side};
use std::sync::Arc;

/// One arm of a robot description: its links and its chain.
#[derive(Clone, Debug, PartialEq)]
pub struct ArmSpec {
    pub links: ArmLinks,
    pub chain: Arc<SerialChain>,
}

impl ArmSpec {
    /// The names of the joints with their own value, in chain order (the CSV's `q1 … qN`; a mimic
    /// joint has no column).
    pub fn joint_names(&self) -> Vec<String> {
        self.chain
            .variable_names()
            .into_iter()
            .map(str::to_string)
            .collect()
    }

    /// Which joint values are lengths (prismatic joints, mm), in chain order.
    pub fn linear_joints(&self) -> Vec<bool> {
        self.chain
            .variables()
            .iter()
            .map(|j| j.kind.is_linear())
            .collect()
    }

    /// `(lower, upper)` of every joint value in chain order, rad (±π for a continuous joint; mm for a
    /// prismatic joint).
    pub fn joint_limits_rad(&self) -> Vec<(f64, f64)> {
        self.chain.variable_ranges()
    }
}

/// Is this a description in the YuMi naming scheme (`yumi_joint_{1,2,7,3,4,5,6}_{l,r}`)?
pub(super) fn has_yumi_names(urdf: &urdf_rs::Robot) -> bool {
    urdf.joints
        .iter()
        .any(|j| j.name.starts_with("yumi_joint_"))
}

/// The arms of a YuMi-named description: from the parent of `yumi_joint_1_x` to `yumi_flange_x` when
/// it hangs below link 7, else to the child of `yumi_joint_6_x` (link 7; the public
/// `yumi_description` has no flange link). All fourteen joints must exist.
pub(super) fn yumi_default_arms(
    urdf: &urdf_rs::Robot,
    msg: &Messages,
) -> Result<PerSide<ArmLinks>, RobotError> {
    let missing: Vec<String> = Side::BOTH
        .iter()
        .flat_map(|&s| (0..ARM_JOINT_NUMBERS.len()).map(move |k| arm_joint_name(s, k)))
        .filter(|n| !urdf.joints.iter().any(|j| &j.name == n))
        .collect();
    if !missing.is_empty() {
        return Err(RobotError::MissingJoints {
            file: msg.file.to_string(),
            missing,
        });
    }
    let joint = |name: &str| urdf.joints.iter().find(|j| j.name == name);
    Ok(PerSide::from_fn(|side| {
        let first = joint(&arm_joint_name(side, 0)).map(|j| j.parent.link.clone());
        let last =
            joint(&arm_joint_name(side, ARM_JOINT_NUMBERS.len() - 1)).map(|j| j.child.link.clone());
        let flange = flange_link_name(side);
        let flange_below_last = last.as_ref().is_some_and(|link7| {
            // The flange hangs from link 7 through fixed joints only.
            let mut link = flange.as_str();
            loop {
                let Some(j) = urdf.joints.iter().find(|j| j.child.link == link) else {
                    return false;
                };
                if j.joint_type != urdf_rs::JointType::Fixed {
                    return false;
                }
                if &j.parent.link == link7 {
                    return true;
                }
                link = j.parent.link.as_str();
            }
        });
        ArmLinks::new(
            first.unwrap_or_default(),
            if flange_below_last {
                flange
            } else {
                last.unwrap_or_default()
            },
        )
    }))
}

/// Check that a YuMi-named default chain holds exactly `yumi_joint_{1,2,7,3,4,5,6}_x` in that order.
pub(super) fn check_yumi_chain(
    side: Side,
    chain: &SerialChain,
    msg: &Messages,
) -> Result<(), RobotError> {
    let expected: Vec<String> = (0..ARM_JOINT_NUMBERS.len())
        .map(|k| arm_joint_name(side, k))
        .collect();
    let got = chain.joint_names();
    if got == expected {
        return Ok(());
    }
    // Name the first joint that is out of place (the one the chain holds there, else the missing one).
    let k = expected
        .iter()
        .zip(&got)
        .position(|(e, g)| e != g)
        .unwrap_or(got.len().min(expected.len()));
    let joint = got
        .get(k)
        .map(|s| s.to_string())
        .or_else(|| expected.get(k).cloned())
        .unwrap_or_default();
    Err(msg.bad_joint(
        &joint,
        format!(
            "the {side} arm's chain {} holds the joints {} in this order, expected {}",
            chain.describe(),
            got.join(", "),
            expected.join(", ")
        ),
    ))
}

/// Build both arms' chains (they may share joints: a torso above both, see
/// [`crate::kinematics::SharedJoints`]).
pub(super) fn build_arms(
    urdf: &urdf_rs::Robot,
    links: PerSide<ArmLinks>,
    yumi_defaults: bool,
    msg: &Messages,
) -> Result<PerSide<ArmSpec>, RobotError> {
    let arms = links.try_map(|side, links| {
        let chain = SerialChain::from_urdf(urdf, &links.base_link, &links.tip_link)
            .map_err(|source| chain_error(msg, side, &links, source))?;
        if yumi_defaults {
            check_yumi_chain(side, &chain, msg)?;
        }
        Ok(ArmSpec {
            links,
            chain: Arc::new(chain),
        })
    })?;
    Ok(arms)
}

/// A chain error with the line of the joint or link it names.
fn chain_error(msg: &Messages, side: Side, links: &ArmLinks, source: ChainError) -> RobotError {
    let line = source
        .subject()
        .and_then(|name| super::line_of(msg.text, &format!("name=\"{name}\"")));
    RobotError::Chain {
        file: msg.file.to_string(),
        line,
        side,
        links: Box::new(links.clone()),
        problem: Box::new(source),
    }
}
