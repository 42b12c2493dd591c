//! Joints on both arms' chains — a torso, a waist, a lift that carries both arms.
//!
//! Where the two chains start above such a joint, each arm's chain holds it (and its correction
//! parameters, and its joint value as one of the arm's CSV columns). It is one joint of the robot: its
//! corrections are identified once, from both arms' data (the tree fit of step 1, see
//! `solver::tree_problem`), both arms' models carry the same values, and the calibrated URDF changes
//! it once. [`SharedJoints::of`] finds them by name; the built-in IRB 14000 (DH) has none.

use super::{ArmKinematics, ArmModel, DualArmModel, PARAMS_PER_JOINT};
use nalgebra::Isometry3;

/// The joints both arms' chains hold, with the indices of what each arm's model keeps of them.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct SharedJoints {
    /// The joints' names, in the left chain's order.
    pub names: Vec<String>,
    /// (left joint, right joint): indices into each chain's movable joints.
    pub joints: Vec<(usize, usize)>,
    /// (left variable, right variable): the joint-value columns both arms' files carry (0-based `q`
    /// indices); a shared joint driven by a `<mimic>` has none, a leader off both chains that joints
    /// of both follow (a column under both arms) has one.
    pub variables: Vec<(usize, usize)>,
    /// The joints of `variables`, in its order.
    pub variable_names: Vec<String>,
    /// (left parameter, right parameter): the correction parameters identified once.
    pub params: Vec<(usize, usize)>,
}

/// The error parameters of the shared joints (their compliances and harmonics, by name): one joint
/// of the robot gives under the load of both arms once, so both arms' models carry one value.
fn shared_error_params(left: &ArmModel, right: &ArmModel, names: &[String]) -> Vec<(usize, usize)> {
    let range = |arm: &ArmModel| arm.error_offset()..arm.param_count();
    let on_shared = |name: &str| {
        name.rsplit_once('.')
            .is_some_and(|(joint, _)| names.iter().any(|n| n == joint))
    };
    let right_names: Vec<(usize, String)> = range(right)
        .map(|b| (b, right.param_name(b)))
        .filter(|(_, name)| on_shared(name))
        .collect();
    range(left)
        .filter_map(|a| {
            let name = left.param_name(a);
            right_names
                .iter()
                .find(|(_, n)| *n == name)
                .map(|&(b, _)| (a, b))
        })
        .collect()
}

impl SharedJoints {
    /// The movable joints of `left`'s chain that `right`'s chain holds too (same name); none unless
    /// both arms are chains.
    pub fn of(left: &ArmModel, right: &ArmModel) -> Self {
        let (ArmKinematics::Chain { chain: l, .. }, ArmKinematics::Chain { chain: r, .. }) =
            (&left.kinematics, &right.kinematics)
        else {
            return Self::default();
        };
        let mut out = Self::default();
        for (a, joint) in l.joints.iter().enumerate() {
            let Some(b) = r.joints.iter().position(|k| k.name == joint.name) else {
                continue;
            };
            out.names.push(joint.name.clone());
            out.joints.push((a, b));
            if let (Some(va), Some(vb)) = (joint.drive.variable(), r.joints[b].drive.variable()) {
                out.variables.push((va, vb));
                out.variable_names.push(joint.name.clone());
            }
            out.params.extend(
                (0..PARAMS_PER_JOINT).map(|i| (PARAMS_PER_JOINT * a + i, PARAMS_PER_JOINT * b + i)),
            );
        }
        for (va, v) in l.variables().iter().enumerate() {
            let vb = r.variables().iter().position(|w| w.name == v.name);
            if let (true, Some(vb)) = (v.is_off_chain(), vb) {
                out.variables.push((va, vb));
                out.variable_names.push(v.name.clone());
            }
        }
        out.params
            .extend(shared_error_params(left, right, &out.names));
        out
    }

    pub fn is_empty(&self) -> bool {
        self.joints.is_empty()
    }

    /// The right arm's parameter that is left parameter `a`, if `a` is a shared one.
    pub fn right_param_of(&self, a: usize) -> Option<usize> {
        self.params.iter().find(|p| p.0 == a).map(|p| p.1)
    }

    /// The left arm's parameter that is right parameter `b`, if `b` is a shared one.
    pub fn left_param_of(&self, b: usize) -> Option<usize> {
        self.params.iter().find(|p| p.1 == b).map(|p| p.0)
    }

    /// `right` with the shared joints' corrections of `left` (after anything that changed one arm's
    /// copy alone: a perturbation, a fit of one arm).
    pub fn copy_to_right(&self, left: &ArmModel, right: &ArmModel) -> ArmModel {
        let (xl, mut xr) = (left.to_vector(), right.to_vector());
        for &(a, b) in &self.params {
            xr[b] = xl[a];
        }
        right.with_vector(&xr)
    }

    /// Right joint values `q_right` with the shared joints' values of `q_left` (both arms' values of
    /// one robot pose: the shared joints have one value).
    pub fn right_with_left_values(&self, q_left: &[f64], q_right: &[f64]) -> Vec<f64> {
        let mut q = q_right.to_vec();
        for &(a, b) in &self.variables {
            if let (Some(v), Some(slot)) = (q_left.get(a), q.get_mut(b)) {
                *slot = *v;
            }
        }
        q
    }

    /// Left joint values `q_left` with the shared joints' values of `q_right`.
    pub fn left_with_right_values(&self, q_left: &[f64], q_right: &[f64]) -> Vec<f64> {
        let mut q = q_left.to_vec();
        for &(a, b) in &self.variables {
            if let (Some(v), Some(slot)) = (q_right.get(b), q.get_mut(a)) {
                *slot = *v;
            }
        }
        q
    }

    /// `model` with its base correction (step 2's `left_base_from_right_base` against `nominal`'s)
    /// moved into the right arm's first joint of its own, the base back at `nominal`: both arms start
    /// at one link, so the base cannot move on its own — the correction is a correction of how the
    /// right arm sits on the shared joints (see `SerialChain::correction_with_base_correction`: exact
    /// for a turn about and a shift along the shared joints' axes, at their zero otherwise). Unchanged
    /// without shared joints.
    pub fn fold_base(
        &self,
        model: &DualArmModel,
        nominal_left_base_from_right_base: &Isometry3<f64>,
    ) -> DualArmModel {
        let mut out = model.clone();
        let right = &model.arms.right;
        let (Some(chain), Some(corrections)) = (right.chain(), right.corrections()) else {
            return out;
        };
        let Some(own) = (0..chain.joint_count()).find(|&b| !self.joints.iter().any(|j| j.1 == b))
        else {
            return out;
        };
        let mut x = right.to_vector();
        let folded = chain.correction_with_base_correction(
            corrections,
            own,
            nominal_left_base_from_right_base,
            &model.left_base_from_right_base,
        );
        for (i, v) in folded.into_iter().enumerate() {
            x[PARAMS_PER_JOINT * own + i] = v;
        }
        out.arms.right = right.with_vector(&x);
        out.left_base_from_right_base = *nominal_left_base_from_right_base;
        out
    }
}
